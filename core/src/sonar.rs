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
        let distance_mm = (product + 1_000_000) / 2_000_000;
        // Exact, so the narrowing below loses nothing (proved for every input by the
        // Kani harness `conversion_is_exact`).
        debug_assert!(distance_mm <= u32::MAX as u64);
        distance_mm as u32
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

    /// Any width at any admissible speed: the distance is `width_us * c / 2e6` rounded
    /// half up (`spec::distance_is_rounded`).
    ///
    /// A bolero test, not a Kani proof (it timed out): the check relates a division of up
    /// to 51 bits to multiplications, which CBMC's bit-level encoding cannot decide in the
    /// time a proof may take (measured with Kani 0.60 and CBMC 6.4.1:
    /// `q * 2e6 <= x < q * 2e6 + 2e6` for `q = x / 2e6` takes 0.6 s for a 32-bit `x`, 9 s
    /// for 36 bits and over 100 s for 40; even the product `w * 343_000`, formed in `u64`
    /// and in `u128`, is not shown to agree within a minute). The property is proved in
    /// two parts instead:
    /// - for every width and speed, [`conversion_is_exact`] (Kani) proves that nothing
    ///   overflows and nothing is lost in the narrowing, so the result is the quotient
    ///   `q = (w * c + 1e6) / 2e6` of exact unsigned division, and
    ///   `spec::distance_is_rounded` is that division's definition
    ///   (`2e6 * q <= w * c + 1e6 < 2e6 * (q + 1)`);
    /// - [`conversion_is_rounded_for_every_echo_below_the_timeout`] checks the spec itself,
    ///   by exhaustion, on every width the HC-SR04 configuration converts, at every speed.
    #[test]
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

    /// Any width at any admissible speed: the product and the rounding offset never
    /// overflow `u64`, and the rounded quotient fits the `u32` it is narrowed to (the
    /// `debug_assert!` in `echo_to_distance_mm`), so the conversion is exact.
    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn conversion_is_exact() {
        bolero::check!()
            .with_type::<(u32, u32)>()
            .cloned()
            .for_each(|(width_us, raw_speed)| {
                let cfg = SonarConfig {
                    speed: speed_from(raw_speed),
                    ..SonarConfig::HC_SR04
                };
                let _ = cfg.echo_to_distance_mm(width_us);
            });
    }

    /// Proof by exhaustion of `spec::distance_is_rounded` on every width the HC-SR04
    /// configuration converts (below its 38 ms echo timeout), at every admissible speed:
    /// 38,000 x 90,001 = 3.42e9 cases, split across threads by speed. Miri checks a
    /// strided sample instead.
    #[test]
    fn conversion_is_rounded_for_every_echo_below_the_timeout() {
        fn first_unrounded(
            cfg: SonarConfig,
            mut widths_us: impl Iterator<Item = u32>,
        ) -> Option<u32> {
            let c = cfg.speed().mm_per_s();
            widths_us.find(|&w| !spec::distance_is_rounded(w, c, cfg.echo_to_distance_mm(w)))
        }
        let timeout_us = SonarConfig::HC_SR04.echo_timeout_us();
        #[cfg(not(miri))]
        let failure = first_failure_at_every_speed(move |cfg| first_unrounded(cfg, 0..timeout_us));
        #[cfg(miri)]
        let failure = sampled_speeds().find_map(|cfg| {
            first_unrounded(cfg, (0..timeout_us).step_by(997)).map(|w| (cfg.speed().mm_per_s(), w))
        });
        assert_eq!(failure, None, "(speed mm/s, width us) not rounded");
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

    /// Any `u16` distance at any admissible speed comes back within a millimetre through
    /// its echo width.
    ///
    /// A bolero test, not a Kani proof (it timed out): both conversions divide, one of
    /// them by the symbolic speed, and the check relates the quotients to products, the
    /// arithmetic CBMC decides worst (see [`conversion_is_total_and_rounded`]). Proved by
    /// exhaustion instead, over the whole domain:
    /// [`round_trip_for_every_u16_distance_and_speed`].
    #[test]
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

    /// Proof by exhaustion of the round trip: every `u16` distance at every admissible
    /// speed, 65,536 x 90,001 = 5.9e9 cases (1.4 x 2^32; each is a hardware division by
    /// the speed and one by a constant), split across threads by speed. Miri checks a
    /// strided sample instead.
    #[test]
    fn round_trip_for_every_u16_distance_and_speed() {
        fn first_astray(
            cfg: SonarConfig,
            mut distances_mm: impl Iterator<Item = u32>,
        ) -> Option<u32> {
            distances_mm.find(|&d| {
                cfg.echo_to_distance_mm(cfg.distance_to_echo_us(d))
                    .abs_diff(d)
                    > 1
            })
        }
        let distances_mm = 0..=u32::from(u16::MAX);
        #[cfg(not(miri))]
        let failure =
            first_failure_at_every_speed(move |cfg| first_astray(cfg, distances_mm.clone()));
        #[cfg(miri)]
        let failure = sampled_speeds().find_map(|cfg| {
            first_astray(cfg, distances_mm.clone().step_by(997))
                .map(|d| (cfg.speed().mm_per_s(), d))
        });
        assert_eq!(
            failure, None,
            "(speed mm/s, distance mm) came back more than 1 mm off"
        );
    }

    /// Runs `first_failure` on the HC-SR04 configuration at every admissible speed, split
    /// across threads; the first failure found, as (speed in mm/s, its input).
    #[cfg(not(miri))]
    fn first_failure_at_every_speed(
        first_failure: impl Fn(SonarConfig) -> Option<u32> + Clone + Send + 'static,
    ) -> Option<(u32, u32)> {
        extern crate std;
        const PARTS: u32 = 4;
        let span = (SpeedOfSound::MAX_MM_PER_S - SpeedOfSound::MIN_MM_PER_S) / PARTS + 1;
        let handles: std::vec::Vec<_> = (0..PARTS)
            .map(|p| {
                let first_failure = first_failure.clone();
                std::thread::spawn(move || {
                    let from = SpeedOfSound::MIN_MM_PER_S + p * span;
                    let to = (from + span).min(SpeedOfSound::MAX_MM_PER_S + 1);
                    (from..to).find_map(|c| first_failure(config_at(c)).map(|x| (c, x)))
                })
            })
            .collect();
        let failures: std::vec::Vec<_> = handles
            .into_iter()
            .map(|h| h.join().expect("worker thread"))
            .collect();
        failures.into_iter().flatten().next()
    }

    /// The lowest, the design and the highest speed, and a stride through the rest.
    #[cfg(miri)]
    fn sampled_speeds() -> impl Iterator<Item = SonarConfig> {
        (SpeedOfSound::MIN_MM_PER_S..=SpeedOfSound::MAX_MM_PER_S)
            .step_by(9_001)
            .chain([SpeedOfSound::AT_20_C.mm_per_s(), SpeedOfSound::MAX_MM_PER_S])
            .map(config_at)
    }

    /// The HC-SR04 configuration at `mm_per_s`, which must be admissible.
    fn config_at(mm_per_s: u32) -> SonarConfig {
        match SpeedOfSound::new(mm_per_s) {
            Ok(speed) => SonarConfig {
                speed,
                ..SonarConfig::HC_SR04
            },
            Err(e) => panic!("speed in range was refused: {e:?}"),
        }
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
        // The range's ends are accepted: +85.0 °C and -50.0 °C, and the speeds' limits.
        assert_eq!(
            SpeedOfSound::at_temperature(850).map(|s| s.mm_per_s()),
            Ok(382_810)
        );
        assert_eq!(
            SpeedOfSound::at_temperature(-501),
            Err(SonarConfigError::TemperatureOutOfRange {
                temp_decicelsius: -501
            })
        );
        for limit in [SpeedOfSound::MIN_MM_PER_S, SpeedOfSound::MAX_MM_PER_S] {
            assert_eq!(SpeedOfSound::new(limit).map(|s| s.mm_per_s()), Ok(limit));
        }
        assert_eq!(
            SpeedOfSound::new(SpeedOfSound::MAX_MM_PER_S + 1),
            Err(SonarConfigError::SpeedOutOfRange {
                mm_per_s: SpeedOfSound::MAX_MM_PER_S + 1
            })
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
        assert_eq!(
            SonarConfig::new(SpeedOfSound::AT_20_C, 38_000, 0),
            Err(SonarConfigError::BadLimits)
        );
    }

    /// A valid custom configuration is accepted and keeps what it was given (a module
    /// with a 1 ms timeout and a 150 mm range at 0 °C).
    #[test]
    fn a_valid_custom_configuration_is_kept() {
        let speed = match SpeedOfSound::at_temperature(0) {
            Ok(speed) => speed,
            Err(e) => panic!("0 °C refused: {e:?}"),
        };
        let cfg = match SonarConfig::new(speed, 1_000, 150) {
            Ok(cfg) => cfg,
            Err(e) => panic!("a valid configuration refused: {e:?}"),
        };
        assert_eq!(cfg.speed(), speed);
        assert_eq!((cfg.echo_timeout_us(), cfg.max_range_mm()), (1_000, 150));
        assert_eq!(cfg.echo_to_distance_mm(1_000), 166);
        assert_eq!(
            SonarConfig::new(speed, 1, 1).map(|c| (c.echo_timeout_us(), c.max_range_mm())),
            Ok((1, 1))
        );
    }

    /// The simulated sensor's echo width is the distance's round trip rounded to the
    /// nearest microsecond, at every admissible speed, and saturates beyond `u32`. (The
    /// exhaustive round trip below covers every `u16` distance; this one is quick enough
    /// to run for each mutant of the mutation tests.)
    #[test]
    fn echo_width_is_the_nearest_microsecond_and_saturates() {
        for mm_per_s in [
            SpeedOfSound::MIN_MM_PER_S,
            SpeedOfSound::AT_20_C.mm_per_s(),
            SpeedOfSound::MAX_MM_PER_S,
        ] {
            let cfg = config_at(mm_per_s);
            let c = u64::from(mm_per_s);
            // Under Miri (the big-endian run) every seventh distance: the arithmetic is
            // the same on either byte order, and the native run takes them all.
            let stride = if cfg!(miri) { 7 } else { 1 };
            for d in (0..=20_000)
                .step_by(stride)
                .chain([1_000_000, 2_000_000, 600_000_000])
            {
                let w = u64::from(cfg.distance_to_echo_us(d));
                let exact = u64::from(d) * 2_000_000;
                assert!(
                    2 * (w * c).abs_diff(exact) <= c,
                    "{d} mm at {c} mm/s: {w} us"
                );
            }
            assert_eq!(cfg.distance_to_echo_us(u32::MAX), u32::MAX);
        }
    }
}
