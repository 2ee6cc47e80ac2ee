//! A simulated HC-SR04 ultrasonic sensor (paper §3.2; architecture guide §1).
//!
//! The scenario knows the true distance to the obstacle; at each measurement the caller
//! passes it and [`HcSr04::measure`] returns what the board would observe on the echo line,
//! a [`cw_core::sonar::Echo`]:
//!
//! - the echo width is [`SonarConfig::distance_to_echo_us`] of the (noisy) distance, with
//!   the sensor's [`SonarConfig`] (default [`SonarConfig::HC_SR04`], 343 m/s);
//! - a true distance beyond the rated range ([`SonarConfig::max_range_mm`], 4 m) gives
//!   what the real part gives when no echo returns: the echo line held high for the
//!   timeout, [`SonarConfig::echo_timeout_us`] (38 ms);
//! - noise ([`Noise`]): uniform or approximately Gaussian (Irwin–Hall: the sum of 12
//!   uniforms), in millimetres, from a seeded [`XorShift64`], so a run repeats exactly;
//!   noisy widths are capped at the timeout;
//! - dropouts: with a probability in parts per million, or forced on, a measurement
//!   returns [`Echo::Missing`] (no echo pulse started: sensor unplugged or miswired).
//!
//! A measurement takes time: the 10 µs trigger pulse, then the echo pulse
//! ([`HcSr04::measurement_time_us`]); the firmware's Gpt/ICU sees the echo end then.
//!
//! Units: distances in millimetres, times in microseconds, probabilities in parts per
//! million (`_ppm`).
//!
//! Simplified: the 8-cycle 40 kHz burst between trigger and echo start (about 200 µs) is
//! not modelled, nor the blind zone below 2 cm, multipath echoes, the beam angle or the
//! temperature dependence of the speed of sound (choose it through the [`SonarConfig`]).

use cw_core::sonar::{Echo, SonarConfig};

use cw_core::sonar::model::EchoModel;
pub use cw_core::sonar::model::{Noise, XorShift64};

/// The simulated HC-SR04: the shared sensor model ([`EchoModel`], which the image's
/// scenario sensor uses too) and a forced dropout.
#[derive(Debug, Clone)]
pub struct HcSr04 {
    model: EchoModel,
    forced_dropout: bool,
}

impl Default for HcSr04 {
    fn default() -> Self {
        Self::new(SonarConfig::HC_SR04)
    }
}

impl HcSr04 {
    /// Length of the trigger pulse the firmware sends, µs.
    pub const TRIGGER_US: u32 = 10;

    /// One part per million, the unit of [`Self::with_dropout_ppm`].
    pub const PPM: u32 = EchoModel::PPM;

    /// An exact sensor (no noise, no dropouts) with the given parameters, PRNG seed 1.
    pub fn new(config: SonarConfig) -> Self {
        Self {
            model: EchoModel::new(config, 1),
            forced_dropout: false,
        }
    }

    /// Sets the noise model.
    pub fn with_noise(mut self, noise: Noise) -> Self {
        self.model = self.model.with_noise(noise);
        self
    }

    /// Sets the probability of a missing echo, parts per million (clamped to 1 000 000).
    pub fn with_dropout_ppm(mut self, dropout_ppm: u32) -> Self {
        self.model = self.model.with_dropout_ppm(dropout_ppm);
        self
    }

    /// Reseeds the PRNG: the same seed gives the same sequence of measurements.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.model = self.model.with_seed(seed);
        self
    }

    /// Forces every measurement to be [`Echo::Missing`] (sensor unplugged) or lifts that.
    pub fn set_forced_dropout(&mut self, on: bool) {
        self.forced_dropout = on;
    }

    /// Whether dropouts are forced.
    pub fn forced_dropout(&self) -> bool {
        self.forced_dropout
    }

    /// The sensor parameters.
    pub fn config(&self) -> &SonarConfig {
        &self.model.config
    }

    /// One measurement of an obstacle truly `true_distance_mm` away.
    pub fn measure(&mut self, true_distance_mm: u32) -> Echo {
        if self.forced_dropout {
            return Echo::Missing;
        }
        self.model.echo(true_distance_mm)
    }

    /// Virtual time one measurement takes, µs: the trigger pulse plus the echo pulse. With
    /// a missing echo the firmware waits for the echo timeout before it gives up.
    pub fn measurement_time_us(&self, echo: Echo) -> u32 {
        let echo_us = match echo {
            Echo::Pulse { width_us } => width_us,
            Echo::Missing => self.model.config.echo_timeout_us(),
        };
        Self::TRIGGER_US.saturating_add(echo_us)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cw_core::warning::Measurement;

    #[test]
    fn exact_sensor_reads_back_the_true_distance() {
        let mut sonar = HcSr04::default();
        let cfg = SonarConfig::HC_SR04;
        for d in [20, 999, 1_000, 1_999, 2_000, 4_000] {
            let echo = sonar.measure(d);
            assert_eq!(
                echo,
                Echo::Pulse {
                    width_us: cfg.distance_to_echo_us(d)
                }
            );
            assert_eq!(cfg.measure(echo), Measurement::Distance { distance_mm: d });
        }
        // 1 m at 343 m/s: a 5831 us round trip, plus the 10 us trigger.
        let echo = sonar.measure(1_000);
        assert_eq!(echo, Echo::Pulse { width_us: 5_831 });
        assert_eq!(sonar.measurement_time_us(echo), 5_841);
    }

    #[test]
    fn beyond_four_metres_the_echo_is_held_for_38_ms() {
        let mut sonar = HcSr04::default();
        for d in [4_001, 10_000, u32::MAX] {
            let echo = sonar.measure(d);
            assert_eq!(echo, Echo::Pulse { width_us: 38_000 });
            assert_eq!(
                SonarConfig::HC_SR04.measure(echo),
                Measurement::NothingInRange
            );
            assert_eq!(sonar.measurement_time_us(echo), 38_010);
        }
    }

    #[test]
    fn forced_dropout_loses_every_echo_until_lifted() {
        let mut sonar = HcSr04::default();
        sonar.set_forced_dropout(true);
        assert!(sonar.forced_dropout());
        assert_eq!(sonar.measure(1_500), Echo::Missing);
        assert_eq!(sonar.measurement_time_us(Echo::Missing), 38_010);
        sonar.set_forced_dropout(false);
        assert_eq!(
            sonar.measure(1_500),
            Echo::Pulse {
                width_us: SonarConfig::HC_SR04.distance_to_echo_us(1_500)
            }
        );
    }

    #[test]
    fn dropout_probability_is_honoured_and_repeatable() {
        let run = |seed| {
            let mut sonar = HcSr04::default().with_dropout_ppm(100_000).with_seed(seed);
            (0..10_000)
                .map(|_| sonar.measure(1_500))
                .collect::<std::vec::Vec<_>>()
        };
        let a = run(42);
        let missing = a.iter().filter(|e| **e == Echo::Missing).count();
        assert!(
            (800..=1_200).contains(&missing),
            "{missing} of 10000 at 10%"
        );
        assert_eq!(a, run(42), "same seed, same measurements");
        assert_ne!(a, run(43));
        let mut always = HcSr04::default().with_dropout_ppm(u32::MAX);
        assert_eq!(always.measure(1_000), Echo::Missing);
    }

    #[test]
    fn uniform_noise_stays_within_its_amplitude() {
        let cfg = SonarConfig::HC_SR04;
        let mut sonar = HcSr04::default()
            .with_noise(Noise::Uniform { amplitude_mm: 30 })
            .with_seed(7);
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..5_000 {
            let Echo::Pulse { width_us } = sonar.measure(1_500) else {
                panic!("no dropouts configured")
            };
            let d = cfg.echo_to_distance_mm(width_us);
            // +-30 mm of noise, +-1 mm of rounding through the echo width.
            assert!((1_469..=1_531).contains(&d), "{d} mm");
            seen.insert(d);
        }
        assert!(
            seen.len() > 50,
            "noise spreads the readings: {}",
            seen.len()
        );
    }

    #[test]
    fn gaussian_noise_has_the_configured_spread() {
        let cfg = SonarConfig::HC_SR04;
        let mut sonar = HcSr04::default()
            .with_noise(Noise::Gaussian { sigma_mm: 20 })
            .with_seed(99);
        let n = 20_000;
        let readings: std::vec::Vec<f64> = (0..n)
            .map(|_| match sonar.measure(2_000) {
                Echo::Pulse { width_us } => f64::from(cfg.echo_to_distance_mm(width_us)),
                Echo::Missing => panic!("no dropouts configured"),
            })
            .collect();
        let mean = readings.iter().sum::<f64>() / f64::from(n);
        let var = readings
            .iter()
            .map(|d| (d - mean) * (d - mean))
            .sum::<f64>()
            / f64::from(n);
        assert!((mean - 2_000.0).abs() < 1.0, "mean {mean}");
        assert!((var.sqrt() - 20.0).abs() < 1.0, "sigma {}", var.sqrt());
        assert!(readings.iter().all(|d| (1_879.0..=2_121.0).contains(d)));
    }

    #[test]
    fn noise_never_underflows_near_zero() {
        let mut sonar = HcSr04::default()
            .with_noise(Noise::Uniform { amplitude_mm: 100 })
            .with_seed(3);
        for _ in 0..1_000 {
            assert!(matches!(sonar.measure(5), Echo::Pulse { .. }));
        }
    }

    #[test]
    fn xorshift_is_deterministic_and_survives_a_zero_seed() {
        let mut a = XorShift64::new(0);
        let mut b = XorShift64::new(0);
        let first = a.next_u64();
        assert_ne!(first, 0);
        assert_eq!(first, b.next_u64());
        assert_eq!(a.next_below(0), 0);
        assert!((0.0..1.0).contains(&a.next_unit()));
    }
}
