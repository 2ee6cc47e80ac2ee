//! The echo an ideal or imperfect HC-SR04 gives for a true distance: the sensor model the
//! host simulation's sensor and the image's scenario sensor share, so that one seed gives
//! the same measurements on both (and the image's frames can be compared with the host's
//! on noisy scenarios).
//!
//! One measurement ([`EchoModel::echo`]) draws from a seeded [`XorShift64`], in this order:
//!
//! 1. the dropout roll, always (so changing the probability does not shift the noise of
//!    the other measurements): below `dropout_ppm` parts per million, no echo;
//! 2. beyond the rated range ([`SonarConfig::max_range_mm`]), no draw: the echo is held
//!    for the timeout, as the real part does when nothing returns;
//! 3. the noise ([`Noise`]): uniform, or approximately Gaussian (Irwin–Hall: the sum of
//!    12 uniforms, in `f64`, whose IEEE arithmetic gives the same bits on every target);
//!    the noisy width is capped at the timeout.
//!
//! A forced dropout (a scenario's `dropout` window, an unplugged sensor) is the caller's:
//! it returns no echo before drawing anything.

use super::{Echo, SonarConfig};

/// A tiny deterministic PRNG (Marsaglia xorshift64). Not for cryptography.
#[derive(Debug, Clone)]
pub struct XorShift64 {
    state: u64,
}

impl XorShift64 {
    /// Used in place of a zero seed, which would make xorshift emit zeros forever.
    const NONZERO_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

    /// A generator from `seed`; seed 0 is replaced by a fixed non-zero constant.
    pub const fn new(seed: u64) -> Self {
        Self {
            state: if seed == 0 { Self::NONZERO_SEED } else { seed },
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.state = x;
        x
    }

    /// A number in `0..bound` (`0` when `bound` is 0). The modulo bias is below 2^-32 for
    /// the bounds used here.
    pub fn next_below(&mut self, bound: u64) -> u64 {
        if bound == 0 {
            return 0;
        }
        self.next_u64() % bound
    }

    /// A number in `[0, 1)` with 53 random bits.
    pub fn next_unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Measurement noise added to the true distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Noise {
    /// Exact measurements.
    #[default]
    None,
    /// Uniform in `-amplitude_mm..=amplitude_mm`.
    Uniform {
        /// Largest deviation, mm.
        amplitude_mm: u32,
    },
    /// Approximately normal with standard deviation `sigma_mm` (sum of 12 uniforms,
    /// so never beyond ±6 sigma).
    Gaussian {
        /// Standard deviation, mm.
        sigma_mm: u32,
    },
}

impl From<crate::scenario::NoiseSpec> for Noise {
    fn from(spec: crate::scenario::NoiseSpec) -> Self {
        match spec {
            crate::scenario::NoiseSpec::Off => Self::None,
            crate::scenario::NoiseSpec::Uniform(amplitude_mm) => Self::Uniform { amplitude_mm },
            crate::scenario::NoiseSpec::Gaussian(sigma_mm) => Self::Gaussian { sigma_mm },
        }
    }
}

/// `v` rounded to the nearest integer, halves away from zero (as `f64::round`, which
/// `core` lacks), saturating at the `i64` range.
fn round_half_away(v: f64) -> i64 {
    let whole = v as i64;
    let frac = v - whole as f64;
    if frac >= 0.5 {
        whole.saturating_add(1)
    } else if frac <= -0.5 {
        whole.saturating_sub(1)
    } else {
        whole
    }
}

/// A sensor's imperfections and the generator they draw from.
#[derive(Debug, Clone)]
pub struct EchoModel {
    /// The sensor's parameters.
    pub config: SonarConfig,
    /// The noise on each distance.
    pub noise: Noise,
    /// The probability of a missing echo, parts per million (at most [`EchoModel::PPM`]).
    pub dropout_ppm: u32,
    rng: XorShift64,
}

impl EchoModel {
    /// One part per million, the unit of `dropout_ppm`.
    pub const PPM: u32 = 1_000_000;

    /// An exact sensor (no noise, no dropouts) with `config`, generator seed `seed`.
    pub const fn new(config: SonarConfig, seed: u64) -> Self {
        Self {
            config,
            noise: Noise::None,
            dropout_ppm: 0,
            rng: XorShift64::new(seed),
        }
    }

    /// Sets the noise model.
    pub const fn with_noise(mut self, noise: Noise) -> Self {
        self.noise = noise;
        self
    }

    /// Sets the probability of a missing echo, parts per million (clamped to [`Self::PPM`]).
    pub const fn with_dropout_ppm(mut self, dropout_ppm: u32) -> Self {
        self.dropout_ppm = if dropout_ppm > Self::PPM {
            Self::PPM
        } else {
            dropout_ppm
        };
        self
    }

    /// Restarts the generator from `seed`.
    pub const fn with_seed(mut self, seed: u64) -> Self {
        self.rng = XorShift64::new(seed);
        self
    }

    /// The echo of one measurement of an obstacle truly `true_distance_mm` away.
    pub fn echo(&mut self, true_distance_mm: u32) -> Echo {
        let roll = self.rng.next_below(u64::from(Self::PPM));
        if roll < u64::from(self.dropout_ppm) {
            return Echo::Missing;
        }
        let timeout_us = self.config.echo_timeout_us();
        if true_distance_mm > self.config.max_range_mm() {
            return Echo::Pulse {
                width_us: timeout_us,
            };
        }
        let noisy_mm = self.add_noise(true_distance_mm);
        let width_us = self.config.distance_to_echo_us(noisy_mm).min(timeout_us);
        Echo::Pulse { width_us }
    }

    fn add_noise(&mut self, distance_mm: u32) -> u32 {
        let offset_mm: i64 = match self.noise {
            Noise::None => 0,
            Noise::Uniform { amplitude_mm } => {
                let span = 2 * u64::from(amplitude_mm) + 1;
                self.rng.next_below(span) as i64 - i64::from(amplitude_mm)
            }
            Noise::Gaussian { sigma_mm } => {
                let mut sum = 0.0;
                for _ in 0..12 {
                    sum += self.rng.next_unit();
                }
                round_half_away((sum - 6.0) * f64::from(sigma_mm))
            }
        };
        let noisy = i64::from(distance_mm).saturating_add(offset_mm);
        noisy.clamp(0, i64::from(u32::MAX)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_is_half_away_from_zero() {
        for (v, r) in [
            (0.0, 0),
            (0.49, 0),
            (0.5, 1),
            (1.5, 2),
            (2.4999, 2),
            (-0.5, -1),
            (-0.49, 0),
            (-2.5, -3),
            (-7.2, -7),
        ] {
            assert_eq!(round_half_away(v), r, "{v}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_echoes_and_another_seed_others() {
        let model = |seed| {
            EchoModel::new(SonarConfig::HC_SR04, seed)
                .with_noise(Noise::Gaussian { sigma_mm: 15 })
                .with_dropout_ppm(20_000)
        };
        let run = |mut m: EchoModel| -> [Echo; 64] { core::array::from_fn(|_| m.echo(1_500)) };
        assert_eq!(run(model(7)), run(model(7)));
        assert_ne!(run(model(7)), run(model(8)));
    }

    #[test]
    fn beyond_the_range_draws_no_noise() {
        let mut far =
            EchoModel::new(SonarConfig::HC_SR04, 3).with_noise(Noise::Uniform { amplitude_mm: 50 });
        let mut rng = XorShift64::new(3);
        assert_eq!(far.echo(5_000), Echo::Pulse { width_us: 38_000 });
        // Only the dropout roll was drawn.
        let _ = rng.next_u64();
        assert_eq!(far.rng.next_u64(), rng.next_u64());
    }
}
