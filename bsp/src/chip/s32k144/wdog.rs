//! The S32K144's watchdog (WDOG; S32K1xx RM, chapter "Watchdog timer").
//!
//! Out of reset the watchdog runs from the 128 kHz LPO with a timeout of 0x400 counts
//! (8 ms), so the start-up code reconfigures it at once ([`Wdog::configure`]): the
//! unlock key written to `CNT`, then, while `CS[ULK]` says it is unlocked (the window is
//! 128 bus clocks), the timeout in `TOVAL` and the control word with `CS[UPDATE]` set so
//! that it can be reconfigured again, and 32-bit refresh commands (`CS[CMD32EN]`). The
//! new configuration takes effect once `CS[RCS]` says so. WdgM then triggers it
//! ([`Wdog::refresh`]: the 32-bit refresh key into `CNT`).

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::CS;

/// The register's bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `CS`, control and status.
    pub CS [
        /// Enabled in stop mode.
        STOP OFFSET(0) NUMBITS(1) [],
        /// Enabled in wait mode.
        WAIT OFFSET(1) NUMBITS(1) [],
        /// Enabled in debug mode.
        DBG OFFSET(2) NUMBITS(1) [],
        /// Test mode.
        TST OFFSET(3) NUMBITS(2) [],
        /// Updates allowed (another reconfiguration after unlocking).
        UPDATE OFFSET(5) NUMBITS(1) [],
        /// Interrupt before the reset.
        INT OFFSET(6) NUMBITS(1) [],
        /// The watchdog counts.
        EN OFFSET(7) NUMBITS(1) [],
        /// Clock source.
        CLK OFFSET(8) NUMBITS(2) [
            Bus = 0,
            Lpo = 1,
            Sosc = 2,
            Sirc = 3
        ],
        /// Reconfiguration complete.
        RCS OFFSET(10) NUMBITS(1) [],
        /// Unlocked.
        ULK OFFSET(11) NUMBITS(1) [],
        /// A fixed 256 prescaler.
        PRES OFFSET(12) NUMBITS(1) [],
        /// 32-bit unlock and refresh commands.
        CMD32EN OFFSET(13) NUMBITS(1) [],
        /// The interrupt flag (write 1 to clear).
        FLG OFFSET(14) NUMBITS(1) [],
        /// Window mode.
        WIN OFFSET(15) NUMBITS(1) []
    ]
    ];
}

/// Register offsets from WDOG's base.
pub mod offset {
    /// `CS`.
    pub const CS: usize = 0x0;
    /// `CNT`: the counter, and where the keys are written.
    pub const CNT: usize = 0x4;
    /// `TOVAL`: the timeout value.
    pub const TOVAL: usize = 0x8;
    /// `WIN`: the window's start.
    pub const WIN: usize = 0xC;
}

/// WDOG's base address.
pub const BASE: usize = 0x4005_2000;

/// The 32-bit unlock key (written to `CNT`).
pub const UNLOCK_KEY: u32 = 0xD928_C520;

/// The 32-bit refresh key (written to `CNT`).
pub const REFRESH_KEY: u32 = 0xB480_A602;

/// The LPO clock the watchdog counts, Hz.
pub const LPO_HZ: u32 = 128_000;

/// Polls of `CS` for the unlock and for the reconfiguration to complete.
pub const POLLS: u32 = 1_000;

/// A timeout `TOVAL` can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Timeout {
    /// `TOVAL`, in (prescaled) LPO counts.
    pub toval: u16,
    /// The fixed 256 prescaler on (`CS[PRES]`).
    pub prescaled: bool,
}

impl Timeout {
    /// The timeout nearest below `ms` milliseconds of the 128 kHz LPO: without the
    /// prescaler up to 511 ms (65,535 counts), with it up to about 131 s; `None` for 0
    /// or beyond.
    pub const fn from_ms(ms: u32) -> Option<Self> {
        let counts = ms as u64 * LPO_HZ as u64 / 1000;
        if counts == 0 {
            None
        } else if counts <= u16::MAX as u64 {
            Some(Self {
                toval: counts as u16,
                prescaled: false,
            })
        } else if counts / 256 <= u16::MAX as u64 {
            Some(Self {
                toval: (counts / 256) as u16,
                prescaled: true,
            })
        } else {
            None
        }
    }

    /// The timeout in microseconds.
    pub const fn us(&self) -> u64 {
        let counts = self.toval as u64 * if self.prescaled { 256 } else { 1 };
        counts * 1_000_000 / LPO_HZ as u64
    }
}

/// The watchdog did not acknowledge a step within [`POLLS`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WdogError {
    /// `CS[ULK]` did not come after the unlock key.
    NotUnlocked,
    /// `CS[RCS]` did not come after the new configuration.
    NotReconfigured,
}

/// The watchdog.
pub struct Wdog<A> {
    access: A,
}

impl<A: Access> Wdog<A> {
    /// The watchdog behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn cs(&self) -> Reg<'_, A, CS::Register> {
        Reg::new(&self.access, offset::CS)
    }

    fn unlock(&self) -> Result<(), WdogError> {
        self.access.write(offset::CNT, UNLOCK_KEY);
        if (0..POLLS).any(|_| self.cs().is_set(CS::ULK)) {
            Ok(())
        } else {
            Err(WdogError::NotUnlocked)
        }
    }

    fn reconfigured(&self) -> Result<(), WdogError> {
        if (0..POLLS).any(|_| self.cs().is_set(CS::RCS)) {
            Ok(())
        } else {
            Err(WdogError::NotReconfigured)
        }
    }

    /// Runs the watchdog from the LPO with `timeout`, reconfigurable and refreshed by
    /// 32-bit commands, counting in wait and debug mode too (a debugger halting the core
    /// stops the counter only if `DBG` is clear: it is, so a halted core is not reset).
    ///
    /// # Errors
    /// [`WdogError`]: the watchdog did not unlock or did not take the configuration.
    pub fn configure(&self, timeout: Timeout) -> Result<(), WdogError> {
        self.unlock()?;
        self.access.write(offset::TOVAL, u32::from(timeout.toval));
        self.cs().write(
            CS::EN::SET
                + CS::UPDATE::SET
                + CS::CMD32EN::SET
                + CS::CLK::Lpo
                + CS::WAIT::SET
                + CS::PRES.val(u32::from(timeout.prescaled)),
        );
        self.reconfigured()
    }

    /// Stops the watchdog (reconfigurable later): for a board without supervision, and
    /// for the start-up code before the watchdog's configuration is known.
    ///
    /// # Errors
    /// [`WdogError`]: the watchdog did not unlock or did not take the configuration.
    pub fn disable(&self) -> Result<(), WdogError> {
        self.unlock()?;
        self.access.write(offset::TOVAL, 0xFFFF);
        self.cs()
            .write(CS::UPDATE::SET + CS::CMD32EN::SET + CS::CLK::Lpo);
        self.reconfigured()
    }

    /// Triggers the watchdog: the counter starts again.
    pub fn refresh(&self) {
        self.access.write(offset::CNT, REFRESH_KEY);
    }

    /// Whether the watchdog counts.
    pub fn is_enabled(&self) -> bool {
        self.cs().is_set(CS::EN)
    }

    /// Clears the interrupt flag.
    pub fn clear_flag(&self) {
        self.cs().modify(CS::FLG::SET);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    fn wdog() -> Wdog<Recorder<4, 16>> {
        let r = Recorder::new();
        // Out of reset: enabled, LPO, 32-bit commands, unlocked (ULK); 0x400 counts.
        r.preset(offset::CS, 0x2980);
        r.preset(offset::TOVAL, 0x400);
        Wdog::new(r)
    }

    #[test]
    fn out_of_reset_values_are_an_8_ms_lpo_watchdog() {
        let w = wdog();
        assert!(w.is_enabled());
        let reset = Timeout {
            toval: 0x400,
            prescaled: false,
        };
        assert_eq!(reset.us(), 8_000);
    }

    #[test]
    fn configure_unlocks_then_writes_the_timeout_and_the_control_word() {
        let w = wdog();
        w.access().hold_high(offset::CS, 1 << 11 | 1 << 10); // ULK, RCS
        let t = Timeout::from_ms(100).unwrap();
        assert_eq!(
            t,
            Timeout {
                toval: 12_800,
                prescaled: false
            }
        );
        w.configure(t).unwrap();
        let writes: Vec<_> = w.access().writes().collect();
        assert_eq!(
            writes,
            [
                (offset::CNT, UNLOCK_KEY),
                (offset::TOVAL, 12_800),
                // EN, UPDATE, CMD32EN, CLK = LPO, WAIT.
                (offset::CS, 1 << 7 | 1 << 5 | 1 << 13 | 1 << 8 | 1 << 1),
            ]
        );
    }

    #[test]
    fn a_watchdog_that_does_not_unlock_is_reported() {
        let w = wdog();
        // Locked (ULK clear), as after a configuration has completed.
        w.access().preset(offset::CS, 0x2180);
        assert_eq!(
            w.configure(Timeout::from_ms(10).unwrap()),
            Err(WdogError::NotUnlocked)
        );
        assert_eq!(w.access().writes().count(), 1, "only the unlock key");
        w.access().hold_high(offset::CS, 1 << 11);
        assert_eq!(w.disable(), Err(WdogError::NotReconfigured));
    }

    #[test]
    fn refresh_writes_the_32_bit_key() {
        let w = wdog();
        w.refresh();
        assert_eq!(w.access().writes().last(), Some((offset::CNT, REFRESH_KEY)));
    }

    #[test]
    fn timeouts_take_the_prescaler_beyond_511_ms() {
        assert_eq!(Timeout::from_ms(0), None);
        assert_eq!(Timeout::from_ms(511).map(|t| t.prescaled), Some(false));
        let t = Timeout::from_ms(512).unwrap();
        assert!(t.prescaled);
        assert_eq!(t.toval, 256);
        assert_eq!(t.us(), 512_000);
        assert!(Timeout::from_ms(131_000).is_some());
        assert_eq!(Timeout::from_ms(132_000), None);
    }
}
