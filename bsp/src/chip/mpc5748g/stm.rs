//! The MPC5748G's system timer module (STM; MPC5748G RM, chapter "System Timer Module"):
//! a free-running 32-bit up-counter on the system clock divided by `CR[CPS] + 1`, with
//! four compare channels. The time base of the board (its `now_us`, its delays), as the
//! DWT's cycle counter is on a Cortex-M.

use crate::chip::access::Access;

/// Register offsets from STM's base.
pub mod offset {
    /// `CR`: `TEN` (bit 0), `FRZ` (bit 1), `CPS` (bits 15:8, divide by `CPS + 1`).
    pub const CR: usize = 0x00;
    /// `CNT`, the count.
    pub const CNT: usize = 0x04;
    /// Channel 0's `CCR` (`CEN`, bit 0); a channel's registers are 0x10 apart.
    pub const CCR0: usize = 0x10;
    /// Channel 0's `CIR` (`CIF`, bit 0, write 1 to clear).
    pub const CIR0: usize = 0x14;
    /// Channel 0's `CMP`.
    pub const CMP0: usize = 0x18;
}

/// STM_0's base address.
pub const BASE: usize = 0xFC06_8000;

/// The system timer.
pub struct Stm<A> {
    access: A,
}

impl<A: Access> Stm<A> {
    /// The timer behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Starts the counter at 0, counting the system clock divided by `divider` (1..=256;
    /// clamped), frozen under the debugger.
    pub fn start(&self, divider: u16) {
        let cps = u32::from(divider.clamp(1, 256) - 1);
        self.access.write(offset::CR, 0);
        self.access.write(offset::CNT, 0);
        self.access.write(offset::CR, cps << 8 | 1 << 1 | 1);
    }

    /// The count.
    pub fn now(&self) -> u32 {
        self.access.read(offset::CNT)
    }

    /// Channel `ch` (0..=3) raises its flag when the count reaches `at`.
    pub fn compare(&self, ch: u8, at: u32) {
        let base = 0x10 * usize::from(ch % 4);
        self.access.write(offset::CCR0 + base, 0);
        self.access.write(offset::CIR0 + base, 1);
        self.access.write(offset::CMP0 + base, at);
        self.access.write(offset::CCR0 + base, 1);
    }

    /// Whether channel `ch`'s compare matched since the last call (the flag read set, then
    /// cleared by writing 1).
    pub fn take_match(&self, ch: u8) -> bool {
        let at = offset::CIR0 + 0x10 * usize::from(ch % 4);
        if self.access.read(at) & 1 == 0 {
            return false;
        }
        self.access.write(at, 1);
        true
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    type Words = Recorder<{ 0x60 / 4 }, 16>;

    #[test]
    fn start_stops_zeroes_then_runs_with_the_prescaler() {
        let s: Stm<Words> = Stm::new(Recorder::new());
        // 160 MHz / 160: one count per microsecond.
        s.start(160);
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(writes, [(0x00, 0), (0x04, 0), (0x00, 159 << 8 | 0b11)]);
        s.start(0);
        assert_eq!(
            s.access().writes().last(),
            Some((0x00, 0b11)),
            "clamped to 1"
        );
    }

    #[test]
    fn a_compare_is_armed_with_its_flag_cleared_and_taken_once() {
        let s: Stm<Words> = Stm::new(Recorder::new());
        s.compare(2, 1000);
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(writes, [(0x30, 0), (0x34, 1), (0x38, 1000), (0x30, 1)]);
        // The write of 1 cleared the flag (the recorder keeps words, not flags).
        s.access().preset(0x34, 0);
        assert!(!s.take_match(2));
        s.access().script(0x34, &[1]);
        assert!(s.take_match(2));
        assert_eq!(
            s.access().writes().last(),
            Some((0x34, 1)),
            "cleared by a 1"
        );
    }
}
