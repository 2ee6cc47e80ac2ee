//! Ultrasonic echo to distance conversion (HC-SR04-class sensor, paper §3.2 and §4.1).
//!
//! The sensor answers a trigger pulse with an echo pulse whose width is the round-trip
//! time of the sound: `distance = width * c / 2`. With nothing in range the echo stays
//! high for about 38 ms and then drops.
//!
//! Invariants:
//! - no input overflows: the product `width_us * c_mm_per_s` is formed in `u64`, where the
//!   largest `u32 * u32` fits, and the quotient is below 2^32 for every admissible speed;
//! - a missing or zero-width echo is [`Measurement::Invalid`], never a distance;
//! - an echo at or past the timeout, or beyond the rated range, is
//!   [`Measurement::NothingInRange`];
//! - the distance is rounded to the nearest millimetre ([`spec::distance_is_rounded`]).
//!
//! Units: `width_us` microseconds, `c_mm_per_s` millimetres per second, `distance_mm`
//! millimetres, temperatures in tenths of a degree Celsius (`temp_decicelsius`).

use crate::warning::Measurement;

pub mod model;
pub mod uart;

/// What the board observed on the echo line for one trigger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Echo {
    /// An echo pulse of this width was measured.
    Pulse {
        /// Width of the echo pulse, in microseconds.
        width_us: u32,
    },
    /// No echo pulse started at all: the sensor is absent, unpowered or miswired.
    Missing,
}

/// Speed of sound, validated to a physically plausible range for air.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SpeedOfSound {
    mm_per_s: u32,
}

/// Why a sensor parameter was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SonarConfigError {
    /// The speed of sound lies outside [`SpeedOfSound::MIN_MM_PER_S`]..=[`SpeedOfSound::MAX_MM_PER_S`].
    SpeedOutOfRange {
        /// The rejected speed, in mm/s.
        mm_per_s: u32,
    },
    /// The temperature lies outside -50.0..=+85.0 °C.
    TemperatureOutOfRange {
        /// The rejected temperature, in tenths of a degree Celsius.
        temp_decicelsius: i16,
    },
    /// The echo timeout is zero or the range limits are inconsistent.
    BadLimits,
}

impl SpeedOfSound {
    /// 343 m/s, dry air at 20 °C (the design value of the paper's sensor).
    pub const AT_20_C: Self = Self { mm_per_s: 343_000 };
    /// Lowest accepted speed (air at about -50 °C).
    pub const MIN_MM_PER_S: u32 = 300_000;
    /// Highest accepted speed (air at about +85 °C).
    pub const MAX_MM_PER_S: u32 = 390_000;

    /// Validates a speed of sound in millimetres per second.
    ///
    /// # Errors
    /// [`SonarConfigError::SpeedOutOfRange`] outside 300..=390 m/s.
    pub const fn new(mm_per_s: u32) -> Result<Self, SonarConfigError> {
        if mm_per_s < Self::MIN_MM_PER_S || mm_per_s > Self::MAX_MM_PER_S {
            return Err(SonarConfigError::SpeedOutOfRange { mm_per_s });
        }
        Ok(Self { mm_per_s })
    }

    /// Temperature-compensated speed of sound in dry air, `c = 331.3 + 0.606 * T` m/s.
    ///
    /// # Errors
    /// [`SonarConfigError::TemperatureOutOfRange`] outside -50.0..=+85.0 °C.
    pub const fn at_temperature(temp_decicelsius: i16) -> Result<Self, SonarConfigError> {
        if temp_decicelsius < -500 || temp_decicelsius > 850 {
            return Err(SonarConfigError::TemperatureOutOfRange { temp_decicelsius });
        }
        // 0.606 m/s per °C = 60.6 mm/s per 0.1 °C; keep it exact with a /10 at the end.
        let mm_per_s = 331_300 + (606 * temp_decicelsius as i32) / 10;
        Self::new(mm_per_s as u32)
    }

    /// The speed in millimetres per second.
    pub const fn mm_per_s(&self) -> u32 {
        self.mm_per_s
    }
}

/// Sensor parameters: speed of sound, echo timeout and rated range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SonarConfig {
    speed: SpeedOfSound,
    echo_timeout_us: u32,
    max_range_mm: u32,
}

impl SonarConfig {
    /// HC-SR04 defaults: 343 m/s, 38 ms echo timeout, 4 m rated range.
    pub const HC_SR04: Self = Self {
        speed: SpeedOfSound::AT_20_C,
        echo_timeout_us: 38_000,
        max_range_mm: 4_000,
    };

    /// Validates a sensor configuration.
    ///
    /// # Errors
    /// [`SonarConfigError::BadLimits`] when the timeout or the range is zero.
    pub const fn new(
        speed: SpeedOfSound,
        echo_timeout_us: u32,
        max_range_mm: u32,
    ) -> Result<Self, SonarConfigError> {
        if echo_timeout_us == 0 || max_range_mm == 0 {
            return Err(SonarConfigError::BadLimits);
        }
        Ok(Self {
            speed,
            echo_timeout_us,
            max_range_mm,
        })
    }

    /// The configured speed of sound.
    pub const fn speed(&self) -> SpeedOfSound {
        self.speed
    }

    /// Echo pulses this long or longer mean nothing in range, in microseconds.
    pub const fn echo_timeout_us(&self) -> u32 {
        self.echo_timeout_us
    }

    /// Distances beyond this are reported as nothing in range, in millimetres.
    pub const fn max_range_mm(&self) -> u32 {
        self.max_range_mm
    }

    /// Round-trip echo width to one-way distance, rounded to the nearest millimetre.
    /// Total over `u32`: never overflows, never panics.
    #[inline]
    pub const fn echo_to_distance_mm(&self, width_us: u32) -> u32 {
        // width_us * c / 2 / 1e6 (µs to s), with half-up rounding. The product is at most
        // (2^32 - 1) * 390_000 < 2^61, and the quotient below 2^32 - 1 since c < 2e6 / 2.
        let product = width_us as u64 * self.speed.mm_per_s as u64;
        ((product + 1_000_000) / 2_000_000) as u32
    }

    /// Turns an echo observation into a measurement.
    #[inline]
    pub const fn measure(&self, echo: Echo) -> Measurement {
        match echo {
            Echo::Missing | Echo::Pulse { width_us: 0 } => Measurement::Invalid,
            Echo::Pulse { width_us } => {
                if width_us >= self.echo_timeout_us {
                    return Measurement::NothingInRange;
                }
                self.classify_distance(self.echo_to_distance_mm(width_us))
            }
        }
    }

    /// A distance the sensor measured, as a measurement: beyond the rated range it is
    /// nothing in range.
    #[inline]
    pub const fn classify_distance(&self, distance_mm: u32) -> Measurement {
        if distance_mm > self.max_range_mm {
            Measurement::NothingInRange
        } else {
            Measurement::Distance { distance_mm }
        }
    }

    /// The echo width an obstacle at `distance_mm` produces, rounded to the nearest
    /// microsecond; the inverse of [`Self::echo_to_distance_mm`], used by simulated sensors.
    /// Saturates at `u32::MAX` microseconds.
    pub const fn distance_to_echo_us(&self, distance_mm: u32) -> u32 {
        let c = self.speed.mm_per_s as u64;
        let width = (distance_mm as u64 * 2_000_000 + c / 2) / c;
        if width > u32::MAX as u64 {
            u32::MAX
        } else {
            width as u32
        }
    }
}

impl Default for SonarConfig {
    fn default() -> Self {
        Self::HC_SR04
    }
}

/// Named predicates: the contract of this module.
pub mod spec {
    /// `distance_mm` is `width_us * c / 2e6` rounded half-up: the exact rational lies in
    /// `[distance - 0.5, distance + 0.5)`. Stated in `u128` so the check itself cannot overflow.
    pub const fn distance_is_rounded(width_us: u32, c_mm_per_s: u32, distance_mm: u32) -> bool {
        let exact_x2e6 = width_us as u128 * c_mm_per_s as u128;
        let d = distance_mm as u128 * 2_000_000;
        // d - 1e6 <= exact < d + 1e6
        d <= exact_x2e6 + 1_000_000 && exact_x2e6 < d + 1_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn speed_from(raw: u32) -> SpeedOfSound {
        let span = SpeedOfSound::MAX_MM_PER_S - SpeedOfSound::MIN_MM_PER_S + 1;
        match SpeedOfSound::new(SpeedOfSound::MIN_MM_PER_S + raw % span) {
            Ok(s) => s,
            Err(e) => panic!("speed in range was refused: {e:?}"),
        }
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn conversion_is_total_and_rounded() {
        bolero::check!()
            .with_type::<(u32, u32)>()
            .cloned()
            .for_each(|(width_us, raw_speed)| {
                let speed = speed_from(raw_speed);
                let cfg = SonarConfig {
                    speed,
                    ..SonarConfig::HC_SR04
                };
                let d = cfg.echo_to_distance_mm(width_us);
                assert!(spec::distance_is_rounded(width_us, speed.mm_per_s(), d));
            });
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn measurement_classification() {
        bolero::check!()
            .with_type::<Option<u32>>()
            .cloned()
            .for_each(|echo| {
                let cfg = SonarConfig::HC_SR04;
                let echo = match echo {
                    Some(width_us) => Echo::Pulse { width_us },
                    None => Echo::Missing,
                };
                let m = cfg.measure(echo);
                match (echo, m) {
                    (Echo::Missing, m) => assert_eq!(m, Measurement::Invalid),
                    (Echo::Pulse { width_us: 0 }, m) => assert_eq!(m, Measurement::Invalid),
                    (Echo::Pulse { width_us }, Measurement::NothingInRange) => assert!(
                        width_us >= cfg.echo_timeout_us()
                            || cfg.echo_to_distance_mm(width_us) > cfg.max_range_mm()
                    ),
                    (Echo::Pulse { width_us }, Measurement::Distance { distance_mm }) => {
                        assert!(width_us < cfg.echo_timeout_us());
                        assert!(distance_mm <= cfg.max_range_mm());
                        assert_eq!(distance_mm, cfg.echo_to_distance_mm(width_us));
                    }
                    (Echo::Pulse { width_us }, Measurement::Invalid) => {
                        panic!("a {width_us} us pulse was called invalid")
                    }
                }
            });
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn round_trip_through_echo_width_is_within_a_millimetre() {
        bolero::check!()
            .with_type::<(u16, u32)>()
            .cloned()
            .for_each(|(distance_mm, raw_speed)| {
                let cfg = SonarConfig {
                    speed: speed_from(raw_speed),
                    ..SonarConfig::HC_SR04
                };
                let d = u32::from(distance_mm);
                let back = cfg.echo_to_distance_mm(cfg.distance_to_echo_us(d));
                assert!(back.abs_diff(d) <= 1, "{d} mm came back as {back} mm");
            });
    }

    #[test]
    fn paper_distances_and_limits() {
        let cfg = SonarConfig::HC_SR04;
        // 1 m at 343 m/s is a 5831 us round trip.
        assert_eq!(cfg.echo_to_distance_mm(5831), 1000);
        assert_eq!(
            cfg.measure(Echo::Pulse { width_us: 5831 }),
            Measurement::Distance { distance_mm: 1000 }
        );
        assert_eq!(
            cfg.measure(Echo::Pulse { width_us: 38_000 }),
            Measurement::NothingInRange
        );
        assert_eq!(
            cfg.measure(Echo::Pulse { width_us: 30_000 }),
            Measurement::NothingInRange
        );
        assert_eq!(
            cfg.measure(Echo::Pulse { width_us: u32::MAX }),
            Measurement::NothingInRange
        );
        assert_eq!(cfg.measure(Echo::Missing), Measurement::Invalid);
        assert_eq!(
            cfg.measure(Echo::Pulse { width_us: 0 }),
            Measurement::Invalid
        );
        assert_eq!(cfg.echo_to_distance_mm(u32::MAX), 736_586_891);
    }

    #[test]
    fn temperature_compensation() {
        assert_eq!(
            SpeedOfSound::at_temperature(0).map(|s| s.mm_per_s()),
            Ok(331_300)
        );
        assert_eq!(
            SpeedOfSound::at_temperature(200).map(|s| s.mm_per_s()),
            Ok(343_420)
        );
        assert_eq!(
            SpeedOfSound::at_temperature(-500).map(|s| s.mm_per_s()),
            Ok(301_000)
        );
        assert_eq!(
            SpeedOfSound::at_temperature(851),
            Err(SonarConfigError::TemperatureOutOfRange {
                temp_decicelsius: 851
            })
        );
        assert_eq!(
            SpeedOfSound::new(1),
            Err(SonarConfigError::SpeedOutOfRange { mm_per_s: 1 })
        );
        assert_eq!(
            SonarConfig::new(SpeedOfSound::AT_20_C, 0, 4000),
            Err(SonarConfigError::BadLimits)
        );
    }
}
