//! The MPC5748G's periodic interrupt timer (PIT; MPC5748G RM, chapter "Periodic Interrupt
//! Timer"): 16 down-counting channels on the 40 MHz peripheral clock (F40), each
//! reloading from `LDVAL` and raising `TFLG[TIF]` (write 1 to clear) at zero. The OS
//! tick's timer on this chip (the role SysTick has on a Cortex-M).

use crate::chip::access::Access;

/// Register offsets from PIT's base.
pub mod offset {
    /// `MCR`: `MDIS` (bit 1) stops the timers' clock, `FRZ` (bit 0) stops them under the
    /// debugger.
    pub const MCR: usize = 0x00;
    /// Channel 0's `LDVAL`; a channel's registers are 0x10 apart.
    pub const LDVAL0: usize = 0x100;
    /// Channel 0's `CVAL`, the count.
    pub const CVAL0: usize = 0x104;
    /// Channel 0's `TCTRL`: `TEN` (bit 0), `TIE` (bit 1), `CHN` (bit 2).
    pub const TCTRL0: usize = 0x108;
    /// Channel 0's `TFLG`: `TIF` (bit 0, write 1 to clear).
    pub const TFLG0: usize = 0x10C;
}

/// PIT's base address.
pub const BASE: usize = 0xFFF8_4000;
/// The timers' clock, Hz (F40).
pub const CLOCK_HZ: u32 = 40_000_000;
/// `MCR[MDIS]`.
const MDIS: u32 = 1 << 1;
/// `MCR[FRZ]`.
const FRZ: u32 = 1 << 0;
/// `TCTRL[TEN]`.
const TEN: u32 = 1 << 0;
/// `TCTRL[TIE]`.
const TIE: u32 = 1 << 1;

/// The periodic interrupt timer.
pub struct Pit<A> {
    access: A,
}

impl<A: Access> Pit<A> {
    /// The timer behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Channel `ch` (0..=15) raises its flag, and its interrupt, every `period_us`
    /// microseconds: the module's clock stopped while the period is loaded, then on
    /// (frozen under the debugger), the flag cleared, the channel started. `false` for a
    /// period of 0 or beyond the counter (nothing written).
    pub fn start_periodic(&self, ch: u8, period_us: u32) -> bool {
        let counts = u64::from(period_us) * u64::from(CLOCK_HZ / 1_000_000);
        let Some(load) = counts.checked_sub(1).and_then(|c| u32::try_from(c).ok()) else {
            return false;
        };
        let base = 0x10 * usize::from(ch % 16);
        self.access.write(offset::MCR, MDIS | FRZ);
        self.access.write(offset::LDVAL0 + base, load);
        self.access.write(offset::MCR, FRZ);
        self.access.write(offset::TFLG0 + base, 1);
        self.access.write(offset::TCTRL0 + base, TIE | TEN);
        true
    }

    /// Whether channel `ch` reached zero since the last call (its flag read set, then
    /// cleared by writing 1).
    pub fn take_flag(&self, ch: u8) -> bool {
        let at = offset::TFLG0 + 0x10 * usize::from(ch % 16);
        if self.access.read(at) & 1 == 0 {
            return false;
        }
        self.access.write(at, 1);
        true
    }

    /// Channel `ch`'s count.
    pub fn count(&self, ch: u8) -> u32 {
        self.access
            .read(offset::CVAL0 + 0x10 * usize::from(ch % 16))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    type Words = Recorder<{ 0x200 / 4 }, 16>;

    #[test]
    fn a_one_ms_tick_loads_39_999_with_the_clock_stopped() {
        let p: Pit<Words> = Pit::new(Recorder::new());
        assert!(p.start_periodic(1, 1000));
        let writes: Vec<_> = p.access().writes().collect();
        assert_eq!(
            writes,
            [
                (0x00, 0b11),
                (0x110, 39_999),
                (0x00, 0b01),
                (0x11C, 1),
                (0x118, 0b11),
            ]
        );
        assert!(!p.start_periodic(0, 0), "no period");
        assert!(!p.start_periodic(0, 200_000_000), "beyond 32 bits");
    }

    #[test]
    fn the_flag_is_cleared_by_writing_one_after_reading_it_set() {
        let p: Pit<Words> = Pit::new(Recorder::new());
        assert!(!p.take_flag(0));
        assert_eq!(p.access().writes().count(), 0);
        p.access().script(0x10C, &[1]);
        assert!(p.take_flag(0));
        assert_eq!(p.access().writes().last(), Some((0x10C, 1)));
    }
}
