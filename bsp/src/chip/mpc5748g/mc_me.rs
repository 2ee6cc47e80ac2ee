//! The MPC5748G's mode entry module (MC_ME; MPC5748G RM, chapter "Mode Entry Module").
//!
//! The chip runs in one of its modes (DRUN out of reset, RUN0 to RUN3, ...); each mode's
//! configuration register (`DRUN_MC`, `RUN0_MC`, ...) says which clock sources run and
//! which one is the system clock. A change of configuration, even of the mode the chip is
//! in, takes effect only through a mode transition: the target mode and the key 0x5AF0
//! into `MCTL`, then the same with the inverted key 0xA50F; the transition is over when
//! `GS[S_MTRANS]` clears, and `GS[S_CURRENT_MODE]` then names the mode.
//!
//! A peripheral's clock runs in a mode when its `PCTLn` names a run configuration
//! (`RUN_PC0` to `RUN_PC7`) that enables that mode. `PCTLn` are byte registers at
//! `0xC0 + n`; this driver reaches them as 32-bit words, big-endian (the byte at the
//! lowest address is the word's most significant), with a read-modify-write at start-up
//! only.

use tock_registers::interfaces::Readable;

use crate::chip::access::{Access, Reg};

pub use bits::{GS, MC};

/// The registers' bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `GS`, global status.
    pub GS [
        /// The system clock's source.
        S_SYSCLK OFFSET(0) NUMBITS(4) [],
        /// The PLL runs.
        S_PLLON OFFSET(6) NUMBITS(1) [],
        /// The crystal oscillator runs.
        S_FXOSC OFFSET(5) NUMBITS(1) [],
        /// A mode transition is under way.
        S_MTRANS OFFSET(27) NUMBITS(1) [],
        /// The mode the chip is in.
        S_CURRENT_MODE OFFSET(28) NUMBITS(4) []
    ],
    /// A mode's configuration (`DRUN_MC`, `RUN0_MC`, ...).
    pub MC [
        /// The system clock's source.
        SYSCLK OFFSET(0) NUMBITS(4) [
            Firc = 0,
            Fxosc = 1,
            PllPhi0 = 2
        ],
        /// The 16 MHz internal oscillator runs.
        FIRCON OFFSET(4) NUMBITS(1) [],
        /// The crystal oscillator runs.
        FXOSCON OFFSET(5) NUMBITS(1) [],
        /// The PLL runs.
        PLLON OFFSET(6) NUMBITS(1) [],
        /// The 128 kHz internal oscillator runs.
        SIRCON OFFSET(7) NUMBITS(1) [],
        /// The flash's power mode (3: normal).
        FLAON OFFSET(16) NUMBITS(2) [],
        /// The main voltage regulator runs.
        MVRON OFFSET(20) NUMBITS(1) []
    ]
    ];
}

/// Register offsets from MC_ME's base.
pub mod offset {
    /// `GS`, global status.
    pub const GS: usize = 0x00;
    /// `MCTL`, mode control.
    pub const MCTL: usize = 0x04;
    /// `ME`, the modes enabled.
    pub const ME: usize = 0x08;
    /// `DRUN_MC`; `RUNn_MC` follow at 4-byte steps from 0x30.
    pub const DRUN_MC: usize = 0x2C;
    /// `RUN_PC0`; `RUN_PCn` at 4-byte steps.
    pub const RUN_PC0: usize = 0x80;
    /// `PCTL0`; `PCTLn` is the byte at `PCTL0 + n`.
    pub const PCTL0: usize = 0xC0;
}

/// MC_ME's base address.
pub const BASE: usize = 0xFFFB_8000;
/// The mode transition's key, and its inverse.
pub const KEY: u32 = 0x5AF0;
/// The inverted key.
pub const INVERTED_KEY: u32 = 0xA50F;
/// Reads of `GS` before a transition that has not ended is reported.
pub const POLLS: u32 = 100_000;

/// A mode of the chip (its `MCTL[TARGET_MODE]` code).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Mode {
    /// DRUN, the mode out of reset.
    Drun = 3,
    /// RUN0.
    Run0 = 4,
}

impl Mode {
    const fn config_offset(self) -> usize {
        match self {
            Self::Drun => offset::DRUN_MC,
            Self::Run0 => 0x30,
        }
    }

    /// This mode's bit in `ME` and in the `RUN_PCn` registers.
    pub const fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// A mode's clock sources and system clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModeConfig {
    /// The crystal oscillator runs.
    pub fxosc: bool,
    /// The PLL runs (it needs the crystal: its input is FXOSC, `AC5`).
    pub pll: bool,
    /// The system clock: `MC::SYSCLK`'s codes (0 FIRC, 1 FXOSC, 2 PLL PHI0).
    pub sysclk: u8,
}

impl ModeConfig {
    /// The boards' run configuration: FIRC, the 40 MHz crystal and the PLL on, the
    /// system clock from PLL PHI0, the flash and main regulator on.
    pub const PLL: Self = Self {
        fxosc: true,
        pll: true,
        sysclk: 2,
    };

    /// The word of `MC` this configuration writes.
    pub fn word(&self) -> u32 {
        let v = MC::FIRCON::SET
            + MC::FXOSCON.val(u32::from(self.fxosc || self.pll))
            + MC::PLLON.val(u32::from(self.pll))
            + MC::FLAON.val(3)
            + MC::MVRON::SET
            + MC::SYSCLK.val(u32::from(self.sysclk & 0xF));
        v.into()
    }
}

/// What a mode change ended in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MeError {
    /// `GS[S_MTRANS]` did not clear within [`POLLS`] reads.
    TransitionStuck(Mode),
    /// The transition ended in another mode (`GS[S_CURRENT_MODE]`, the code).
    WrongMode(Mode, u8),
    /// The configuration asks for a system clock whose source it leaves off.
    ClockOff(ModeConfig),
}

/// The mode entry module.
pub struct McMe<A> {
    access: A,
}

impl<A: Access> McMe<A> {
    /// The module behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn gs(&self) -> Reg<'_, A, GS::Register> {
        Reg::new(&self.access, offset::GS)
    }

    /// Writes `mode`'s configuration (taking effect at the next transition into it).
    ///
    /// # Errors
    /// [`MeError::ClockOff`]: the system clock's source would be off.
    pub fn configure(&self, mode: Mode, config: &ModeConfig) -> Result<(), MeError> {
        let source_on = match config.sysclk {
            0 => true,
            1 => config.fxosc || config.pll,
            2 => config.pll,
            _ => false,
        };
        if !source_on {
            return Err(MeError::ClockOff(*config));
        }
        self.access.write(mode.config_offset(), config.word());
        Ok(())
    }

    /// Lets the peripherals of run configuration `pc` (0..=7) run in `modes` (an OR of
    /// [`Mode::bit`]s).
    pub fn run_configuration(&self, pc: u8, modes: u32) {
        self.access
            .write(offset::RUN_PC0 + 4 * usize::from(pc % 8), modes & 0xFF);
    }

    /// Gives peripheral `n` (its `PCTLn` index) run configuration `pc` (0..=7).
    pub fn peripheral(&self, n: u8, pc: u8) {
        let at = offset::PCTL0 + usize::from(n);
        let word = at & !3;
        // Big-endian: the byte at the word's lowest address is its top byte.
        let shift = 8 * (3 - (at & 3));
        let old = self.access.read(word);
        let new = (old & !(0xFF << shift)) | (u32::from(pc % 8) << shift);
        self.access.write(word, new);
    }

    /// Changes to `mode` (or applies its new configuration when the chip is in it): the
    /// key, the inverted key, then a bounded wait for the transition's end.
    ///
    /// # Errors
    /// [`MeError`]: the transition did not end, or ended in another mode.
    pub fn enter(&self, mode: Mode) -> Result<(), MeError> {
        let target = u32::from(mode as u8) << 28;
        self.access.write(offset::MCTL, target | KEY);
        self.access.write(offset::MCTL, target | INVERTED_KEY);
        if !(0..POLLS).any(|_| !self.gs().is_set(GS::S_MTRANS)) {
            return Err(MeError::TransitionStuck(mode));
        }
        let now = self.gs().read(GS::S_CURRENT_MODE) as u8;
        if now == mode as u8 {
            Ok(())
        } else {
            Err(MeError::WrongMode(mode, now))
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    fn me() -> McMe<Recorder<{ 0x200 / 4 }, 16>> {
        let r = Recorder::new();
        // Out of reset: DRUN, FIRC as the system clock.
        r.preset(offset::GS, 3 << 28 | 1 << 4);
        McMe::new(r)
    }

    #[test]
    fn the_devkit_configuration_is_nxps_word() {
        // NXP's example writes DRUN_MC = 0x00130072: MVRON, FLAON normal, PLLON, FXOSCON,
        // FIRCON, SYSCLK = PLL PHI0.
        assert_eq!(ModeConfig::PLL.word(), 0x0013_0072);
        let m = me();
        m.configure(Mode::Drun, &ModeConfig::PLL).unwrap();
        assert_eq!(
            m.access().writes().last(),
            Some((offset::DRUN_MC, 0x0013_0072))
        );
        let off = ModeConfig {
            fxosc: true,
            pll: false,
            sysclk: 2,
        };
        assert_eq!(m.configure(Mode::Drun, &off), Err(MeError::ClockOff(off)));
    }

    #[test]
    fn enter_writes_the_key_then_the_inverted_key_and_waits() {
        let m = me();
        // Under way for two reads, then over in DRUN.
        m.access()
            .script(offset::GS, &[1 << 27 | 3 << 28, 1 << 27 | 3 << 28]);
        m.enter(Mode::Drun).unwrap();
        let writes: Vec<_> = m.access().writes().collect();
        assert_eq!(
            writes,
            [(offset::MCTL, 0x3000_5AF0), (offset::MCTL, 0x3000_A50F)]
        );
    }

    #[test]
    fn a_stuck_or_wrong_transition_is_reported() {
        let m = me();
        m.access().hold_high(offset::GS, 1 << 27);
        assert_eq!(
            m.enter(Mode::Run0),
            Err(MeError::TransitionStuck(Mode::Run0))
        );
        let m = me();
        assert_eq!(m.enter(Mode::Run0), Err(MeError::WrongMode(Mode::Run0, 3)));
    }

    #[test]
    fn peripheral_control_bytes_are_big_endian_in_their_word() {
        let m = me();
        // PCTL70 (FlexCAN_0) at 0x106: the word at 0x104, its third byte (bits 15:8).
        m.access().preset(0x104, 0x1122_3344);
        m.peripheral(70, 1);
        assert_eq!(m.access().writes().last(), Some((0x104, 0x1122_0144)));
        // PCTL91 (PIT) at 0x11B: the word at 0x118, its last byte.
        m.peripheral(91, 1);
        assert_eq!(m.access().writes().last(), Some((0x118, 0x0000_0001)));
        m.run_configuration(1, Mode::Drun.bit() | Mode::Run0.bit());
        assert_eq!(m.access().writes().last(), Some((0x84, 0x18)));
    }
}
