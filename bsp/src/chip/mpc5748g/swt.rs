//! The MPC5748G's software watchdog (SWT; MPC5748G RM, chapter "Software Watchdog Timer").
//!
//! SWT_0 can run out of reset with its soft lock set (NXP's start-up code disables it
//! first thing). Its control register is locked until the unlock sequence is written to
//! the service register (`SR`: 0xC520, then 0xD928), which clears `CR[SLK]`; a hard lock
//! (`CR[HLK]`) lasts until reset. In its fixed service mode the watchdog is serviced by
//! 0xA602 then 0xB480 in `SR`. Its counter runs from the 16 MHz internal oscillator
//! (FIRC).

use tock_registers::interfaces::{Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::CR;

/// The register's bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `CR`, control.
    pub CR [
        /// The watchdog counts.
        WEN OFFSET(0) NUMBITS(1) [],
        /// Stopped while the core is halted by a debugger.
        FRZ OFFSET(1) NUMBITS(1) [],
        /// Stopped in stop mode.
        STP OFFSET(2) NUMBITS(1) [],
        /// Soft lock: `CR` and `TO` read-only until the unlock sequence.
        SLK OFFSET(4) NUMBITS(1) [],
        /// Hard lock: read-only until reset.
        HLK OFFSET(5) NUMBITS(1) [],
        /// Interrupt then reset (0: reset at the first time-out).
        ITR OFFSET(6) NUMBITS(1) [],
        /// Window mode.
        WND OFFSET(7) NUMBITS(1) [],
        /// Reset on an invalid access.
        RIA OFFSET(8) NUMBITS(1) [],
        /// Service mode (0: fixed keys).
        SMD OFFSET(9) NUMBITS(2) [],
        /// The bus masters allowed to access the watchdog (one bit each, MAP7 at bit 24 to
        /// MAP0 at bit 31).
        MAP OFFSET(24) NUMBITS(8) []
    ]
    ];
}

/// Register offsets from SWT's base.
pub mod offset {
    /// `CR`, control.
    pub const CR: usize = 0x00;
    /// `IR`, interrupt flag.
    pub const IR: usize = 0x04;
    /// `TO`, time-out, in counter clocks.
    pub const TO: usize = 0x08;
    /// `SR`, service (and unlock) keys.
    pub const SR: usize = 0x10;
}

/// SWT_0's base address.
pub const BASE: usize = 0xFC05_0000;

/// The unlock sequence, in order.
pub const UNLOCK: [u32; 2] = [0xC520, 0xD928];
/// The fixed service sequence, in order.
pub const SERVICE: [u32; 2] = [0xA602, 0xB480];
/// The counter's clock, Hz (FIRC).
pub const CLOCK_HZ: u32 = 16_000_000;
/// Reads of `CR` before an unlock that has not taken effect is reported.
pub const POLLS: u32 = 1_000;
/// The smallest time-out the watchdog takes, in counter clocks.
pub const MIN_TIMEOUT: u32 = 0x100;

/// What the watchdog refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SwtError {
    /// `CR[HLK]`: locked until reset.
    HardLocked,
    /// `CR[SLK]` stayed set after the unlock sequence.
    NotUnlocked,
    /// A time-out shorter than [`MIN_TIMEOUT`] counter clocks, or beyond 32 bits.
    Timeout(u32),
}

/// The software watchdog.
pub struct Swt<A> {
    access: A,
}

impl<A: Access> Swt<A> {
    /// The watchdog behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn cr(&self) -> Reg<'_, A, CR::Register> {
        Reg::new(&self.access, offset::CR)
    }

    fn unlock(&self) -> Result<(), SwtError> {
        if self.cr().is_set(CR::HLK) {
            return Err(SwtError::HardLocked);
        }
        for key in UNLOCK {
            self.access.write(offset::SR, key);
        }
        if (0..POLLS).any(|_| !self.cr().is_set(CR::SLK)) {
            Ok(())
        } else {
            Err(SwtError::NotUnlocked)
        }
    }

    /// Stops the watchdog (left unlocked, so that it can be configured again): the unlock
    /// sequence, then `CR` with every master allowed, reset on an invalid access, frozen
    /// under the debugger, and `WEN` clear.
    ///
    /// # Errors
    /// [`SwtError`]: hard-locked, or the unlock did not take.
    pub fn disable(&self) -> Result<(), SwtError> {
        self.unlock()?;
        self.cr()
            .write(CR::MAP.val(0xFF) + CR::RIA::SET + CR::FRZ::SET + CR::WEN::CLEAR);
        Ok(())
    }

    /// Runs the watchdog with a time-out of `timeout_us` microseconds, in fixed service
    /// mode, resetting the chip at the first time-out, soft-locked afterwards.
    ///
    /// # Errors
    /// [`SwtError`]: hard-locked, the unlock did not take, or a time-out out of range.
    pub fn start(&self, timeout_us: u32) -> Result<(), SwtError> {
        let clocks = u64::from(timeout_us) * u64::from(CLOCK_HZ) / 1_000_000;
        let clocks = u32::try_from(clocks)
            .ok()
            .filter(|&c| c >= MIN_TIMEOUT)
            .ok_or(SwtError::Timeout(timeout_us))?;
        self.unlock()?;
        self.access.write(offset::TO, clocks);
        self.cr()
            .write(CR::MAP.val(0xFF) + CR::RIA::SET + CR::FRZ::SET + CR::SLK::SET + CR::WEN::SET);
        Ok(())
    }

    /// Services the watchdog: its counter starts again.
    pub fn service(&self) {
        for key in SERVICE {
            self.access.write(offset::SR, key);
        }
    }

    /// Whether the watchdog counts.
    pub fn is_enabled(&self) -> bool {
        self.cr().is_set(CR::WEN)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    /// Out of reset as NXP's start-up code finds SWT_0: every master allowed, reset on an
    /// invalid access, frozen under the debugger, soft-locked, counting.
    const CR_RUNNING: u32 = 0xFF00_0113;

    fn swt() -> Swt<Recorder<8, 16>> {
        let r = Recorder::new();
        r.preset(offset::CR, CR_RUNNING);
        Swt::new(r)
    }

    #[test]
    fn disable_unlocks_then_clears_wen() {
        let s = swt();
        assert!(s.is_enabled());
        // The unlock clears SLK (the recorder's stored word stands for the silicon).
        s.access()
            .script(offset::CR, &[CR_RUNNING, CR_RUNNING & !(1 << 4)]);
        s.disable().unwrap();
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(
            writes,
            [
                (offset::SR, 0xC520),
                (offset::SR, 0xD928),
                (offset::CR, 0xFF00_0102),
            ]
        );
        assert!(!s.is_enabled());
    }

    #[test]
    fn a_locked_watchdog_is_reported_and_left_alone() {
        let s = swt();
        s.access().hold_high(offset::CR, 1 << 4);
        assert_eq!(s.disable(), Err(SwtError::NotUnlocked));
        assert_eq!(s.access().writes().count(), 2, "the two unlock keys only");
        let hard = swt();
        hard.access().hold_high(offset::CR, 1 << 5);
        assert_eq!(hard.start(10_000), Err(SwtError::HardLocked));
        assert_eq!(hard.access().writes().count(), 0);
    }

    #[test]
    fn start_writes_the_timeout_in_firc_clocks_then_locks() {
        let s = swt();
        s.access().preset(offset::CR, 0xFF00_0102);
        s.start(20_000).unwrap();
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(
            writes,
            [
                (offset::SR, 0xC520),
                (offset::SR, 0xD928),
                (offset::TO, 320_000),
                (offset::CR, 0xFF00_0113),
            ]
        );
        assert_eq!(s.start(10), Err(SwtError::Timeout(10)), "160 clocks");
    }

    #[test]
    fn service_writes_the_two_keys() {
        let s = swt();
        s.service();
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(writes, [(offset::SR, 0xA602), (offset::SR, 0xB480)]);
    }
}
