//! Warning level decision (paper §4.3).
//!
//! The collision-warning system lights the red LED when the obstacle is closer than
//! 1.0 m, the yellow LED from 1.0 m up to (not including) 2.0 m, and neither from 2.0 m
//! on. Exactly 1000 mm is yellow and exactly 2000 mm is off.
//!
//! Invariants:
//! - [`Thresholds`] can only hold `0 < red_below_mm < yellow_below_mm`
//!   ([`spec::thresholds_valid`]);
//! - [`WarningLevel::Fault`] is returned for an invalid or missing measurement, so no caller
//!   ever has to invent a distance;
//! - the level is monotone in the distance: moving the obstacle closer never lowers it.
//!
//! Units: millimetres throughout (`distance_mm`).

/// The outcome of one distance measurement, as the sensor layer reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Measurement {
    /// An obstacle was detected at this distance.
    Distance {
        /// Distance from the sensor to the obstacle, in millimetres.
        distance_mm: u32,
    },
    /// The sensor worked and saw nothing within its range (no echo within the timeout).
    NothingInRange,
    /// No usable measurement: the sensor did not answer, the echo was malformed, or the
    /// value is missing. Never turned into a distance.
    Invalid,
}

/// The warning shown to the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum WarningLevel {
    /// No obstacle closer than the yellow threshold: both LEDs off.
    Off,
    /// Obstacle between the red and yellow thresholds: yellow LED.
    Yellow,
    /// Obstacle closer than the red threshold: red LED.
    Red,
    /// The measurement is invalid or missing: the driver must be told the system cannot
    /// warn (the I/O layer blinks both LEDs).
    Fault,
}

/// Why a pair of thresholds was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThresholdError {
    /// The red threshold must be above zero, or no distance could ever be red.
    RedIsZero,
    /// The red threshold must lie strictly below the yellow one.
    RedNotBelowYellow {
        /// The rejected red threshold.
        red_below_mm: u32,
        /// The rejected yellow threshold.
        yellow_below_mm: u32,
    },
}

/// Validated warning thresholds: red below `red_below_mm`, yellow below `yellow_below_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Thresholds {
    red_below_mm: u32,
    yellow_below_mm: u32,
}

impl Thresholds {
    /// The paper's thresholds: red below 1.0 m, yellow below 2.0 m.
    pub const PAPER: Self = Self {
        red_below_mm: 1000,
        yellow_below_mm: 2000,
    };

    /// Validates a pair of thresholds.
    ///
    /// # Errors
    /// [`ThresholdError::RedIsZero`] or [`ThresholdError::RedNotBelowYellow`].
    pub const fn new(red_below_mm: u32, yellow_below_mm: u32) -> Result<Self, ThresholdError> {
        Self::checked(red_below_mm, yellow_below_mm)
    }

    /// [`Self::new`]'s checks. (A function of its own because cargo-mutants leaves
    /// functions named `new` alone: see `docs/src/mutants.md`.)
    const fn checked(red_below_mm: u32, yellow_below_mm: u32) -> Result<Self, ThresholdError> {
        if red_below_mm == 0 {
            return Err(ThresholdError::RedIsZero);
        }
        if red_below_mm >= yellow_below_mm {
            return Err(ThresholdError::RedNotBelowYellow {
                red_below_mm,
                yellow_below_mm,
            });
        }
        Ok(Self {
            red_below_mm,
            yellow_below_mm,
        })
    }

    /// Distances strictly below this are red, in millimetres.
    pub const fn red_below_mm(&self) -> u32 {
        self.red_below_mm
    }

    /// Distances strictly below this (and not red) are yellow, in millimetres.
    pub const fn yellow_below_mm(&self) -> u32 {
        self.yellow_below_mm
    }

    /// The warning level for an obstacle at `distance_mm`.
    #[inline]
    pub const fn level_for_distance(&self, distance_mm: u32) -> WarningLevel {
        if distance_mm < self.red_below_mm {
            WarningLevel::Red
        } else if distance_mm < self.yellow_below_mm {
            WarningLevel::Yellow
        } else {
            WarningLevel::Off
        }
    }

    /// The warning level for a measurement; an invalid one gives [`WarningLevel::Fault`].
    #[inline]
    pub const fn level(&self, measurement: Measurement) -> WarningLevel {
        match measurement {
            Measurement::Distance { distance_mm } => self.level_for_distance(distance_mm),
            Measurement::NothingInRange => WarningLevel::Off,
            Measurement::Invalid => WarningLevel::Fault,
        }
    }
}

impl Default for Thresholds {
    fn default() -> Self {
        Self::PAPER
    }
}

/// Named predicates: the contract of this module, executed by tests, fuzzing and Kani.
pub mod spec {
    use super::{Measurement, Thresholds, WarningLevel};

    /// A threshold pair is usable when `0 < red < yellow`.
    pub const fn thresholds_valid(red_below_mm: u32, yellow_below_mm: u32) -> bool {
        0 < red_below_mm && red_below_mm < yellow_below_mm
    }

    /// The level the paper's rule (§4.3) assigns, written as three independent interval
    /// tests rather than a cascade: exactly one of them holds for every distance.
    pub const fn level_is_correct(t: &Thresholds, distance_mm: u32, level: WarningLevel) -> bool {
        let red = distance_mm < t.red_below_mm;
        let yellow = t.red_below_mm <= distance_mm && distance_mm < t.yellow_below_mm;
        let off = t.yellow_below_mm <= distance_mm;
        match level {
            WarningLevel::Red => red && !yellow && !off,
            WarningLevel::Yellow => yellow && !red && !off,
            WarningLevel::Off => off && !red && !yellow,
            WarningLevel::Fault => false,
        }
    }

    /// A measurement maps to Fault exactly when it is invalid.
    pub const fn fault_iff_invalid(m: Measurement, level: WarningLevel) -> bool {
        matches!(m, Measurement::Invalid) == matches!(level, WarningLevel::Fault)
    }

    /// Closer never means a lower warning (for valid distances).
    pub const fn monotone(near: WarningLevel, far: WarningLevel) -> bool {
        near as u8 >= far as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thresholds_from(red: u32, yellow: u32) -> Option<Thresholds> {
        Thresholds::new(red, yellow).ok()
    }

    /// The thresholds read back as given.
    #[test]
    fn thresholds_keep_what_they_were_given() {
        let t = thresholds_from(700, 1_500).map(|t| (t.red_below_mm(), t.yellow_below_mm()));
        assert_eq!(t, Some((700, 1_500)));
        let paper = Thresholds::PAPER;
        assert_eq!(
            (paper.red_below_mm(), paper.yellow_below_mm()),
            (1_000, 2_000)
        );
    }

    /// The validity rule at its edges: red above zero, yellow strictly above red.
    #[test]
    fn threshold_rule_at_its_edges() {
        assert!(spec::thresholds_valid(1, 2));
        assert!(!spec::thresholds_valid(0, 2));
        assert!(!spec::thresholds_valid(2, 2));
        assert!(!spec::thresholds_valid(3, 2));
        assert!(spec::thresholds_valid(u32::MAX - 1, u32::MAX));
    }

    /// The other two predicates can fail too: a fault for a valid measurement, no fault
    /// for an invalid one, and a nearer obstacle warned less than a farther one.
    #[test]
    fn fault_and_monotonicity_predicates_refuse_what_breaks_them() {
        let distance = Measurement::Distance { distance_mm: 500 };
        assert!(spec::fault_iff_invalid(distance, WarningLevel::Red));
        assert!(!spec::fault_iff_invalid(distance, WarningLevel::Fault));
        assert!(!spec::fault_iff_invalid(
            Measurement::NothingInRange,
            WarningLevel::Fault
        ));
        assert!(spec::fault_iff_invalid(
            Measurement::Invalid,
            WarningLevel::Fault
        ));
        assert!(!spec::fault_iff_invalid(
            Measurement::Invalid,
            WarningLevel::Off
        ));
        assert!(spec::monotone(WarningLevel::Red, WarningLevel::Yellow));
        assert!(spec::monotone(WarningLevel::Yellow, WarningLevel::Yellow));
        assert!(!spec::monotone(WarningLevel::Off, WarningLevel::Yellow));
        assert!(!spec::monotone(WarningLevel::Yellow, WarningLevel::Red));
    }

    /// The spec accepts exactly the level the rule gives and refuses the three others, at
    /// each edge of each interval: an oracle that could not fail would prove nothing.
    #[test]
    fn spec_refuses_every_wrong_level() {
        let levels = [
            WarningLevel::Red,
            WarningLevel::Yellow,
            WarningLevel::Off,
            WarningLevel::Fault,
        ];
        let t = Thresholds::PAPER;
        for (d, right) in [
            (0, WarningLevel::Red),
            (999, WarningLevel::Red),
            (1_000, WarningLevel::Yellow),
            (1_999, WarningLevel::Yellow),
            (2_000, WarningLevel::Off),
            (u32::MAX, WarningLevel::Off),
        ] {
            for level in levels {
                assert_eq!(
                    spec::level_is_correct(&t, d, level),
                    level == right,
                    "{d} mm as {level:?}"
                );
            }
        }
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn paper_level_matches_spec_for_any_distance() {
        bolero::check!().with_type::<u32>().cloned().for_each(|d| {
            let level = Thresholds::PAPER.level_for_distance(d);
            assert!(spec::level_is_correct(&Thresholds::PAPER, d, level));
        });
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn any_valid_thresholds_match_spec_and_are_monotone() {
        bolero::check!()
            .with_type::<(u32, u32, u32, u32)>()
            .cloned()
            .for_each(|(red, yellow, a, b)| {
                let made = Thresholds::new(red, yellow);
                assert_eq!(made.is_ok(), spec::thresholds_valid(red, yellow));
                let Ok(t) = made else { return };
                let (near, far) = if a <= b { (a, b) } else { (b, a) };
                let ln = t.level_for_distance(near);
                let lf = t.level_for_distance(far);
                assert!(spec::level_is_correct(&t, near, ln));
                assert!(spec::level_is_correct(&t, far, lf));
                assert!(spec::monotone(ln, lf));
            });
    }

    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn fault_exactly_for_invalid_measurements() {
        bolero::check!()
            .with_type::<(u8, u32)>()
            .cloned()
            .for_each(|(kind, d)| {
                let m = match kind % 3 {
                    0 => Measurement::Distance { distance_mm: d },
                    1 => Measurement::NothingInRange,
                    _ => Measurement::Invalid,
                };
                let level = Thresholds::PAPER.level(m);
                assert!(spec::fault_iff_invalid(m, level));
                if m == Measurement::NothingInRange {
                    assert_eq!(level, WarningLevel::Off);
                }
            });
    }

    /// Every `u32` distance, exhaustively, against the specification. Split across threads
    /// so the 2^32 cases take seconds; Miri checks a strided sample instead.
    #[test]
    fn paper_level_exhaustive_over_all_u32() {
        #[cfg(not(miri))]
        {
            extern crate std;
            const PARTS: u64 = 4;
            let span = (u64::from(u32::MAX) + 1) / PARTS;
            let handles: std::vec::Vec<_> = (0..PARTS)
                .map(|p| {
                    std::thread::spawn(move || {
                        let t = Thresholds::PAPER;
                        let mut counts = [0u64; 3];
                        let (lo, hi) = (p * span, (p + 1) * span);
                        for d in lo..hi {
                            let d = d as u32;
                            let level = t.level_for_distance(d);
                            if !spec::level_is_correct(&t, d, level) {
                                return Err(d);
                            }
                            counts[level as usize] += 1;
                        }
                        Ok(counts)
                    })
                })
                .collect();
            let mut totals = [0u64; 3];
            for h in handles {
                match h.join().expect("worker thread") {
                    Ok(c) => (0..3).for_each(|i| totals[i] += c[i]),
                    Err(d) => panic!("wrong level at {d} mm"),
                }
            }
            // Off, Yellow, Red counts: [2000, 2^32), [1000, 2000), [0, 1000).
            assert_eq!(totals, [u64::from(u32::MAX) + 1 - 2000, 1000, 1000]);
        }
        #[cfg(miri)]
        for d in (0..=u32::MAX)
            .step_by(1_048_573)
            .chain([999, 1000, 1999, 2000, u32::MAX])
        {
            let level = Thresholds::PAPER.level_for_distance(d);
            assert!(spec::level_is_correct(&Thresholds::PAPER, d, level));
        }
    }

    #[test]
    fn paper_boundaries() {
        let t = Thresholds::default();
        assert_eq!(t.level_for_distance(0), WarningLevel::Red);
        assert_eq!(t.level_for_distance(500), WarningLevel::Red);
        assert_eq!(t.level_for_distance(999), WarningLevel::Red);
        assert_eq!(t.level_for_distance(1000), WarningLevel::Yellow);
        assert_eq!(t.level_for_distance(1500), WarningLevel::Yellow);
        assert_eq!(t.level_for_distance(1999), WarningLevel::Yellow);
        assert_eq!(t.level_for_distance(2000), WarningLevel::Off);
        assert_eq!(t.level_for_distance(u32::MAX), WarningLevel::Off);
        assert_eq!(t.level(Measurement::Invalid), WarningLevel::Fault);
    }

    #[test]
    fn bad_thresholds_are_refused_with_a_reason() {
        assert_eq!(thresholds_from(0, 10), None);
        assert_eq!(Thresholds::new(0, 10), Err(ThresholdError::RedIsZero));
        assert_eq!(
            Thresholds::new(2000, 1000),
            Err(ThresholdError::RedNotBelowYellow {
                red_below_mm: 2000,
                yellow_below_mm: 1000
            })
        );
        assert_eq!(
            Thresholds::new(1000, 1000),
            Err(ThresholdError::RedNotBelowYellow {
                red_below_mm: 1000,
                yellow_below_mm: 1000
            })
        );
        assert_eq!(Thresholds::new(1000, 2000), Ok(Thresholds::PAPER));
    }
}
