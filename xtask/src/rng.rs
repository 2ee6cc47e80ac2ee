//! The seeded generator of the differential and log-format runs: `rand`'s xoshiro256**
//! (`rand_xoshiro`, seeded through SplitMix64), so a run can be replayed exactly from its
//! printed seed, with the few draws the generators need.

use rand::{Rng as _, RngCore as _, SeedableRng as _};
use rand_xoshiro::Xoshiro256StarStar;

/// The `--seed` option of every randomized run.
#[derive(Clone, Copy, Default, clap::Args)]
pub struct Seed {
    /// Generator seed (decimal or 0x hex); a fresh one when not given
    #[arg(long = "seed", value_name = "SEED", value_parser = parse_seed)]
    pub given: Option<u64>,
}

impl Seed {
    /// The seed given, or a fresh one from the operating system.
    pub fn or_fresh(self) -> u64 {
        self.given.unwrap_or_else(rand::random)
    }
}

/// A generator seed: decimal, or hexadecimal after `0x`.
fn parse_seed(text: &str) -> crate::Result<u64> {
    match text.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => text.parse(),
    }
    .map_err(|e| format!("`{text}`: {e}"))
}

/// A seeded generator.
pub struct Rng(Xoshiro256StarStar);

impl Rng {
    /// A generator whose whole sequence is determined by `seed`.
    pub fn new(seed: u64) -> Self {
        Self(Xoshiro256StarStar::seed_from_u64(seed))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// A number in `0..n`, uniformly (`0` when `n` is 0).
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            0
        } else {
            self.0.random_range(0..n)
        }
    }

    /// True with probability `1 / n`.
    pub fn one_in(&mut self, n: u64) -> bool {
        self.below(n) == 0
    }

    /// A uniformly chosen element of a slice, or `fallback` when it is empty.
    pub fn pick<T: Copy>(&mut self, items: &[T], fallback: T) -> T {
        let i = self.below(items.len() as u64) as usize;
        items.get(i).copied().unwrap_or(fallback)
    }

    /// Fills `bytes` with random bytes.
    pub fn fill(&mut self, bytes: &mut [u8]) {
        self.0.fill_bytes(bytes);
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    #[test]
    fn a_seed_replays_its_sequence() {
        let (mut a, mut b) = (Rng::new(7), Rng::new(7));
        let draws = |r: &mut Rng| (r.next_u64(), r.below(10), r.pick(&[1, 2, 3], 0));
        assert_eq!(draws(&mut a), draws(&mut b));
        assert_ne!(Rng::new(7).next_u64(), Rng::new(8).next_u64());
        assert_eq!(Rng::new(1).below(0), 0);
        assert_eq!(Rng::new(1).pick::<u8>(&[], 9), 9);
    }
}
