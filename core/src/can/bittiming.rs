//! CAN bit timing (ISO 11898-1, 11.3.1): how a controller divides its clock into a bit.
//!
//! A bit is `1 + tseg1 + tseg2` time quanta (the synchronisation segment, the propagation
//! and first phase segments, the second phase segment), each quantum `prescaler` clocks
//! of the controller. The bus samples the bit after `1 + tseg1` quanta (the sample
//! point); resynchronisation moves an edge by at most `sjw` quanta. [`find`] chooses the
//! timing a controller's limits allow for a bitrate and a sample point: an exact bitrate
//! (a CAN bus tolerates little clock error), then the sample point nearest the one asked
//! for, then the most quanta per bit (the finest resynchronisation).

/// What a controller's timing registers can express.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BitTimingLimits {
    /// The clock prescaler's range.
    pub prescaler: (u16, u16),
    /// `tseg1` (propagation plus first phase segment), quanta.
    pub tseg1: (u8, u8),
    /// `tseg2` (second phase segment), quanta.
    pub tseg2: (u8, u8),
    /// The largest resynchronisation jump width.
    pub sjw_max: u8,
    /// Quanta per bit (the CAN standard asks for 8 to 25).
    pub quanta: (u8, u8),
}

/// NXP FlexCAN's classic bit timing (S32K1xx `CAN_CTRL1`): PRESDIV + 1 in 1..=256,
/// PROPSEG + 1 and PSEG1 + 1 each 1..=8 (so `tseg1` 2..=16), PSEG2 + 1 in 2..=8, RJW + 1
/// in 1..=4.
pub const FLEXCAN: BitTimingLimits = BitTimingLimits {
    prescaler: (1, 256),
    tseg1: (2, 16),
    tseg2: (2, 8),
    sjw_max: 4,
    quanta: (8, 25),
};

/// The sample point CiA 301 recommends for `bitrate`, per mille of the bit: 87.5 % up to
/// 500 kbit/s, 80 % up to 800 kbit/s, 75 % above.
pub const fn cia_sample_permille(bitrate: u32) -> u16 {
    if bitrate <= 500_000 {
        875
    } else if bitrate <= 800_000 {
        800
    } else {
        750
    }
}

/// One bit timing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BitTiming {
    /// Clocks per quantum.
    pub prescaler: u16,
    /// Propagation plus first phase segment, quanta.
    pub tseg1: u8,
    /// Second phase segment, quanta.
    pub tseg2: u8,
    /// Resynchronisation jump width, quanta.
    pub sjw: u8,
}

impl BitTiming {
    /// Quanta per bit.
    pub const fn quanta(&self) -> u32 {
        1 + self.tseg1 as u32 + self.tseg2 as u32
    }

    /// The bitrate with a `clock_hz` clock, if it is a whole number of bits per second.
    pub const fn bitrate(&self, clock_hz: u32) -> Option<u32> {
        let clocks_per_bit = self.prescaler as u32 * self.quanta();
        if clocks_per_bit == 0 || clock_hz % clocks_per_bit != 0 {
            return None;
        }
        Some(clock_hz / clocks_per_bit)
    }

    /// The sample point, per mille of the bit.
    pub const fn sample_permille(&self) -> u32 {
        (1 + self.tseg1 as u32) * 1000 / self.quanta()
    }

    /// Whether every field lies within `limits`.
    pub const fn fits(&self, limits: &BitTimingLimits) -> bool {
        let q = self.quanta();
        self.prescaler >= limits.prescaler.0
            && self.prescaler <= limits.prescaler.1
            && self.tseg1 >= limits.tseg1.0
            && self.tseg1 <= limits.tseg1.1
            && self.tseg2 >= limits.tseg2.0
            && self.tseg2 <= limits.tseg2.1
            && self.sjw >= 1
            && self.sjw <= limits.sjw_max
            && self.sjw <= self.tseg2
            && q >= limits.quanta.0 as u32
            && q <= limits.quanta.1 as u32
    }
}

/// No timing of the controller gives the bitrate exactly from its clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unreachable {
    /// The controller's clock, Hz.
    pub clock_hz: u32,
    /// The bitrate asked for.
    pub bitrate: u32,
}

impl core::fmt::Display for Unreachable {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "no bit timing gives {} bit/s exactly from a {} Hz clock",
            self.bitrate, self.clock_hz
        )
    }
}

/// The timing for `bitrate` from a `clock_hz` clock within `limits`: an exact bitrate,
/// the sample point nearest `sample_permille`, then the most quanta; `sjw` as large as the
/// limits and `tseg2` allow.
///
/// # Errors
/// [`Unreachable`] when no timing within the limits gives the bitrate exactly.
pub fn find(
    clock_hz: u32,
    bitrate: u32,
    sample_permille: u16,
    limits: &BitTimingLimits,
) -> Result<BitTiming, Unreachable> {
    let unreachable = Unreachable { clock_hz, bitrate };
    if bitrate == 0 {
        return Err(unreachable);
    }
    let mut best: Option<(u32, u32, BitTiming)> = None;
    for quanta in limits.quanta.0..=limits.quanta.1 {
        let q = u32::from(quanta);
        let Some(clocks_per_bit) = bitrate.checked_mul(q) else {
            continue;
        };
        if clock_hz % clocks_per_bit != 0 {
            continue;
        }
        let Ok(prescaler) = u16::try_from(clock_hz / clocks_per_bit) else {
            continue;
        };
        for tseg1 in limits.tseg1.0..=limits.tseg1.1 {
            let Some(tseg2) = quanta.checked_sub(1).and_then(|q| q.checked_sub(tseg1)) else {
                continue;
            };
            let timing = BitTiming {
                prescaler,
                tseg1,
                tseg2,
                sjw: limits.sjw_max.min(tseg2).max(1),
            };
            if !timing.fits(limits) {
                continue;
            }
            let error = timing
                .sample_permille()
                .abs_diff(u32::from(sample_permille));
            // Nearer the sample point first, then more quanta (later in the loop: `>=`
            // on the quanta keeps the last, the most).
            let better = best.is_none_or(|(e, bq, _)| error < e || (error == e && q >= bq));
            if better {
                best = Some((error, q, timing));
            }
        }
    }
    best.map(|(_, _, t)| t).ok_or(unreachable)
}

/// The rules [`find`] keeps, for the tests, the fuzz target and Kani.
pub mod spec {
    use super::{find, BitTiming, BitTimingLimits};

    /// `find`'s answer is within the limits, gives the bitrate exactly, and no timing of
    /// the limits gives it with a sample point nearer `sample_permille` (checked against
    /// every timing the limits hold with `max_prescaler` at most, by exhaustion); a
    /// refusal means no timing gives the bitrate.
    pub fn find_is_exact_and_nearest(
        clock_hz: u32,
        bitrate: u32,
        sample_permille: u16,
        limits: &BitTimingLimits,
    ) -> bool {
        let found = find(clock_hz, bitrate, sample_permille, limits);
        let mut nearest: Option<u32> = None;
        for prescaler in limits.prescaler.0..=limits.prescaler.1 {
            for tseg1 in limits.tseg1.0..=limits.tseg1.1 {
                for tseg2 in limits.tseg2.0..=limits.tseg2.1 {
                    let t = BitTiming {
                        prescaler,
                        tseg1,
                        tseg2,
                        sjw: 1,
                    };
                    if t.fits(limits) && t.bitrate(clock_hz) == Some(bitrate) {
                        let e = t.sample_permille().abs_diff(u32::from(sample_permille));
                        nearest = Some(nearest.map_or(e, |n| n.min(e)));
                    }
                }
            }
        }
        match (found, nearest) {
            (Ok(t), Some(n)) => {
                t.fits(limits)
                    && t.bitrate(clock_hz) == Some(bitrate)
                    && t.sample_permille().abs_diff(u32::from(sample_permille)) == n
            }
            (Err(_), None) => true,
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests;
