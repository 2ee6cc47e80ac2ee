//! The S32K144's clocks (System Clock Generator, SCG; S32K1xx RM, chapter "System Clock
//! Generator", and the data sheet's clock limits for RUN mode).
//!
//! [`ClockPlan`] says how the clocks are derived from the crystal (the system oscillator,
//! SOSC) through the system PLL (SPLL), and [`ClockPlan::clocks`] checks it against the
//! chip's limits before anything is written, naming the limit a plan breaks. [`Scg::start`]
//! then carries it out in the order the manual asks: SOSC's dividers, its configuration,
//! enable and wait for valid; the SPLL disabled, its dividers and configuration, enabled
//! and wait for valid; then the RUN mode's source and dividers, and wait until the
//! status register reports the SPLL as the system clock. Every wait is bounded.
//!
//! The flash needs no wait-state register on this chip: its clock is the slow clock
//! (`DIVSLOW`), which the plan keeps at or below 26.67 MHz.

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::{CCR, SOSCCFG, SOSCCSR, SPLLCFG, SPLLCSR, XDIV};

/// The registers' bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `CSR` (status) and `RCCR` (RUN mode's configuration).
    pub CCR [
        /// System clock source.
        SCS OFFSET(24) NUMBITS(4) [
            Sosc = 1,
            Sirc = 2,
            Firc = 3,
            Spll = 6
        ],
        /// Core clock divider minus one.
        DIVCORE OFFSET(16) NUMBITS(4) [],
        /// Bus clock divider minus one.
        DIVBUS OFFSET(4) NUMBITS(4) [],
        /// Slow (flash) clock divider minus one.
        DIVSLOW OFFSET(0) NUMBITS(4) []
    ],
    /// `SOSCCSR`.
    pub SOSCCSR [
        /// The oscillator is valid.
        SOSCVLD OFFSET(24) NUMBITS(1) [],
        /// The register is locked.
        LK OFFSET(23) NUMBITS(1) [],
        /// Enabled.
        SOSCEN OFFSET(0) NUMBITS(1) []
    ],
    /// `SOSCDIV` and `SPLLDIV`: the asynchronous dividers (0 off, n: divide by 2^(n-1)).
    pub XDIV [
        /// Divider 2.
        DIV2 OFFSET(8) NUMBITS(3) [],
        /// Divider 1.
        DIV1 OFFSET(0) NUMBITS(3) []
    ],
    /// `SOSCCFG`.
    pub SOSCCFG [
        /// Frequency range.
        RANGE OFFSET(4) NUMBITS(2) [
            Medium = 2,
            High = 3
        ],
        /// High-gain operation.
        HGO OFFSET(3) NUMBITS(1) [],
        /// A crystal (1) rather than an external clock (0).
        EREFS OFFSET(2) NUMBITS(1) []
    ],
    /// `SPLLCSR`.
    pub SPLLCSR [
        /// The PLL is locked and valid.
        SPLLVLD OFFSET(24) NUMBITS(1) [],
        /// The register is locked.
        LK OFFSET(23) NUMBITS(1) [],
        /// Enabled.
        SPLLEN OFFSET(0) NUMBITS(1) []
    ],
    /// `SPLLCFG`.
    pub SPLLCFG [
        /// The multiplier minus 16.
        MULT OFFSET(16) NUMBITS(5) [],
        /// The reference divider minus one.
        PREDIV OFFSET(8) NUMBITS(3) []
    ]
    ];
}

/// Register offsets from SCG's base.
pub mod offset {
    /// `CSR`, the clocks in use.
    pub const CSR: usize = 0x010;
    /// `RCCR`, RUN mode's clocks.
    pub const RCCR: usize = 0x014;
    /// `SOSCCSR`.
    pub const SOSCCSR: usize = 0x100;
    /// `SOSCDIV`.
    pub const SOSCDIV: usize = 0x104;
    /// `SOSCCFG`.
    pub const SOSCCFG: usize = 0x108;
    /// `SPLLCSR`.
    pub const SPLLCSR: usize = 0x600;
    /// `SPLLDIV`.
    pub const SPLLDIV: usize = 0x604;
    /// `SPLLCFG`.
    pub const SPLLCFG: usize = 0x608;
}

/// SCG's base address.
pub const BASE: usize = 0x4006_4000;

/// Polls of a status bit before a step is declared failed (an 8 MHz crystal starts in a
/// few ms; a poll takes a few cycles of the 48 MHz FIRC the chip starts on).
pub const POLLS: u32 = 1_000_000;

/// An asynchronous divider's setting (`SOSCDIV2`, `SPLLDIV2`: the peripherals' clocks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AsyncDiv {
    /// The output is off.
    Off,
    /// Divide by `2^n` (`n` in 0..=6: by 1 to 64).
    By(u8),
}

impl AsyncDiv {
    const fn field(self) -> u32 {
        match self {
            Self::Off => 0,
            Self::By(n) => (if n > 6 { 6 } else { n }) as u32 + 1,
        }
    }

    const fn divide(self, hz: u32) -> u32 {
        match self {
            Self::Off => 0,
            Self::By(n) => hz >> (if n > 6 { 6 } else { n }),
        }
    }
}

/// How the clocks come from the crystal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ClockPlan {
    /// The crystal on EXTAL/XTAL, Hz.
    pub sosc_hz: u32,
    /// The SPLL's reference divider (1..=8).
    pub prediv: u8,
    /// The SPLL's multiplier (16..=47).
    pub mult: u8,
    /// The core clock's divider of the SPLL's output (1..=16).
    pub divcore: u8,
    /// The bus clock's divider of the core clock (1..=16).
    pub divbus: u8,
    /// The slow (flash) clock's divider of the core clock (1..=8).
    pub divslow: u8,
    /// `SOSCDIV2` (FlexCAN's oscillator clock, LPUART, ...).
    pub sosc_div2: AsyncDiv,
    /// `SPLLDIV2` (the asynchronous peripherals' fast clock).
    pub spll_div2: AsyncDiv,
}

/// The clocks a plan gives, Hz.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Clocks {
    /// The core and system clock.
    pub core_hz: u32,
    /// The bus clock (the peripheral clock of FlexCAN's `CLKSRC` = 1).
    pub bus_hz: u32,
    /// The slow clock, which the flash runs on.
    pub slow_hz: u32,
    /// `SOSCDIV2_CLK`.
    pub sosc_div2_hz: u32,
    /// `SPLLDIV2_CLK`.
    pub spll_div2_hz: u32,
}

/// A limit a plan breaks (the data sheet's, RUN mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClockError {
    /// A divider or multiplier outside its field.
    Field(&'static str),
    /// The SPLL's reference (SOSC / PREDIV) outside 8 to 16 MHz.
    Reference(u32),
    /// The SPLL's VCO outside 180 to 320 MHz.
    Vco(u32),
    /// The core clock above 80 MHz.
    Core(u32),
    /// The bus clock above 48 MHz, or not a whole divider of the core clock.
    Bus(u32),
    /// The slow clock above 26.67 MHz.
    Slow(u32),
}

impl core::fmt::Display for ClockError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Field(name) => write!(f, "{name} is outside its register field"),
            Self::Reference(hz) => write!(f, "the SPLL reference {hz} Hz is outside 8-16 MHz"),
            Self::Vco(hz) => write!(f, "the SPLL VCO {hz} Hz is outside 180-320 MHz"),
            Self::Core(hz) => write!(f, "the core clock {hz} Hz is above 80 MHz"),
            Self::Bus(hz) => write!(f, "the bus clock {hz} Hz is above 48 MHz"),
            Self::Slow(hz) => write!(f, "the slow (flash) clock {hz} Hz is above 26.67 MHz"),
        }
    }
}

impl ClockPlan {
    /// The S32K144EVB's: its 8 MHz crystal, the SPLL at 160 MHz (8 MHz x 40 / 2), the core
    /// at 80 MHz, the bus at 40 MHz, the flash at 26.67 MHz; `SOSCDIV2` 8 MHz (FlexCAN's
    /// oscillator clock), `SPLLDIV2` 40 MHz.
    pub const EVB_80_MHZ: Self = Self {
        sosc_hz: 8_000_000,
        prediv: 1,
        mult: 40,
        divcore: 2,
        divbus: 2,
        divslow: 3,
        sosc_div2: AsyncDiv::By(0),
        spll_div2: AsyncDiv::By(2),
    };

    /// The clocks this plan gives, checked against the chip's limits.
    ///
    /// # Errors
    /// [`ClockError`] names the first limit broken.
    pub const fn clocks(&self) -> Result<Clocks, ClockError> {
        if self.prediv < 1 || self.prediv > 8 {
            return Err(ClockError::Field("PREDIV"));
        }
        if self.mult < 16 || self.mult > 47 {
            return Err(ClockError::Field("MULT"));
        }
        if self.divcore < 1 || self.divcore > 16 || self.divbus < 1 || self.divbus > 16 {
            return Err(ClockError::Field("DIVCORE/DIVBUS"));
        }
        if self.divslow < 1 || self.divslow > 8 {
            return Err(ClockError::Field("DIVSLOW"));
        }
        let reference = self.sosc_hz / self.prediv as u32;
        if reference < 8_000_000 || reference > 16_000_000 {
            return Err(ClockError::Reference(reference));
        }
        let vco = reference as u64 * self.mult as u64;
        if vco < 180_000_000 || vco > 320_000_000 {
            return Err(ClockError::Vco(vco as u32));
        }
        let spll = (vco / 2) as u32;
        let core = spll / self.divcore as u32;
        if core > 80_000_000 {
            return Err(ClockError::Core(core));
        }
        let bus = core / self.divbus as u32;
        if bus > 48_000_000 {
            return Err(ClockError::Bus(bus));
        }
        let slow = core / self.divslow as u32;
        if slow > 26_670_000 {
            return Err(ClockError::Slow(slow));
        }
        Ok(Clocks {
            core_hz: core,
            bus_hz: bus,
            slow_hz: slow,
            sosc_div2_hz: self.sosc_div2.divide(self.sosc_hz),
            spll_div2_hz: self.spll_div2.divide(spll),
        })
    }
}

/// A clock that did not become valid within [`POLLS`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ScgError {
    /// The plan breaks a limit.
    Plan(ClockError),
    /// A register stayed locked (`LK`).
    Locked(&'static str),
    /// The oscillator did not become valid (no crystal, or a broken one).
    SoscNotValid,
    /// The PLL did not lock.
    SpllNotValid,
    /// The system clock did not switch to the SPLL.
    NotSwitched,
}

/// The System Clock Generator.
pub struct Scg<A> {
    access: A,
}

impl<A: Access> Scg<A> {
    /// The SCG behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn poll(&self, ready: impl Fn() -> bool) -> bool {
        (0..POLLS).any(|_| ready())
    }

    /// Carries out `plan`: the SOSC, then the SPLL, then RUN mode on the SPLL.
    ///
    /// # Errors
    /// [`ScgError`] names the step that failed; the chip then still runs on the clock it
    /// had (the FIRC out of reset), since the system clock switches last.
    pub fn start(&self, plan: &ClockPlan) -> Result<Clocks, ScgError> {
        let clocks = plan.clocks().map_err(ScgError::Plan)?;
        let a = &self.access;
        let sosccsr: Reg<'_, A, SOSCCSR::Register> = Reg::new(a, offset::SOSCCSR);
        if !self.poll(|| !sosccsr.is_set(SOSCCSR::LK)) {
            return Err(ScgError::Locked("SOSCCSR"));
        }
        sosccsr.set(0);
        Reg::<A, XDIV::Register>::new(a, offset::SOSCDIV)
            .write(XDIV::DIV1.val(1) + XDIV::DIV2.val(plan.sosc_div2.field()));
        let range = if plan.sosc_hz > 8_000_000 {
            SOSCCFG::RANGE::High
        } else {
            SOSCCFG::RANGE::Medium
        };
        Reg::<A, SOSCCFG::Register>::new(a, offset::SOSCCFG).write(range + SOSCCFG::EREFS::SET);
        sosccsr.write(SOSCCSR::SOSCEN::SET);
        if !self.poll(|| sosccsr.is_set(SOSCCSR::SOSCVLD)) {
            return Err(ScgError::SoscNotValid);
        }
        let spllcsr: Reg<'_, A, SPLLCSR::Register> = Reg::new(a, offset::SPLLCSR);
        if !self.poll(|| !spllcsr.is_set(SPLLCSR::LK)) {
            return Err(ScgError::Locked("SPLLCSR"));
        }
        spllcsr.modify(SPLLCSR::SPLLEN::CLEAR);
        Reg::<A, XDIV::Register>::new(a, offset::SPLLDIV)
            .write(XDIV::DIV1.val(2) + XDIV::DIV2.val(plan.spll_div2.field()));
        Reg::<A, SPLLCFG::Register>::new(a, offset::SPLLCFG).write(
            SPLLCFG::PREDIV.val(u32::from(plan.prediv) - 1)
                + SPLLCFG::MULT.val(u32::from(plan.mult) - 16),
        );
        spllcsr.write(SPLLCSR::SPLLEN::SET);
        if !self.poll(|| spllcsr.is_set(SPLLCSR::SPLLVLD)) {
            return Err(ScgError::SpllNotValid);
        }
        Reg::<A, CCR::Register>::new(a, offset::RCCR).write(
            CCR::SCS::Spll
                + CCR::DIVCORE.val(u32::from(plan.divcore) - 1)
                + CCR::DIVBUS.val(u32::from(plan.divbus) - 1)
                + CCR::DIVSLOW.val(u32::from(plan.divslow) - 1),
        );
        let csr: Reg<'_, A, CCR::Register> = Reg::new(a, offset::CSR);
        if !self.poll(|| csr.read(CCR::SCS) == 6) {
            return Err(ScgError::NotSwitched);
        }
        Ok(clocks)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    /// SCG as words up to `SPLLCFG`.
    type Words = Recorder<{ 0x60C / 4 }, 32>;

    #[test]
    fn the_evbs_plan_is_80_40_26_67_mhz() {
        let c = ClockPlan::EVB_80_MHZ.clocks().unwrap();
        assert_eq!(
            c,
            Clocks {
                core_hz: 80_000_000,
                bus_hz: 40_000_000,
                slow_hz: 26_666_666,
                sosc_div2_hz: 8_000_000,
                spll_div2_hz: 40_000_000,
            }
        );
    }

    #[test]
    fn plans_beyond_a_limit_are_refused_by_name() {
        let evb = ClockPlan::EVB_80_MHZ;
        let refused = |p: ClockPlan| p.clocks().err();
        assert_eq!(
            refused(ClockPlan { mult: 48, ..evb }),
            Some(ClockError::Field("MULT"))
        );
        assert_eq!(
            refused(ClockPlan { prediv: 2, ..evb }),
            Some(ClockError::Reference(4_000_000))
        );
        assert_eq!(
            refused(ClockPlan { mult: 20, ..evb }),
            Some(ClockError::Vco(160_000_000))
        );
        assert_eq!(
            refused(ClockPlan { divcore: 1, ..evb }),
            Some(ClockError::Core(160_000_000))
        );
        assert_eq!(
            refused(ClockPlan { divbus: 1, ..evb }),
            Some(ClockError::Bus(80_000_000))
        );
        assert_eq!(
            refused(ClockPlan { divslow: 2, ..evb }),
            Some(ClockError::Slow(40_000_000))
        );
        assert_eq!(
            ClockError::Slow(40_000_000).to_string(),
            "the slow (flash) clock 40000000 Hz is above 26.67 MHz"
        );
    }

    #[test]
    fn start_writes_sosc_then_spll_then_run_mode_in_the_manuals_order() {
        let scg = Scg::new(Words::new());
        let r = scg.access();
        r.hold_high(offset::SOSCCSR, 1 << 24);
        r.hold_high(offset::SPLLCSR, 1 << 24);
        r.hold_high(offset::CSR, 6 << 24);
        scg.start(&ClockPlan::EVB_80_MHZ).unwrap();
        let writes: Vec<_> = r.writes().collect();
        assert_eq!(
            writes,
            [
                (offset::SOSCCSR, 0),
                (offset::SOSCDIV, 0x101),
                // RANGE medium (an 8 MHz crystal), EREFS: a crystal.
                (offset::SOSCCFG, 2 << 4 | 1 << 2),
                (offset::SOSCCSR, 1),
                (offset::SPLLCSR, 1 << 24),
                (offset::SPLLDIV, 3 << 8 | 2),
                // PREDIV 0 (by 1), MULT 24 (by 40).
                (offset::SPLLCFG, 24 << 16),
                (offset::SPLLCSR, 1),
                // SPLL, core by 2, bus by 2, slow by 3.
                (offset::RCCR, 6 << 24 | 1 << 16 | 1 << 4 | 2),
            ]
        );
    }

    #[test]
    fn a_missing_crystal_is_reported_and_the_system_clock_left_alone() {
        let scg = Scg::new(Words::new());
        assert_eq!(
            scg.start(&ClockPlan::EVB_80_MHZ),
            Err(ScgError::SoscNotValid)
        );
        assert!(scg.access().writes().all(|(o, _)| o != offset::RCCR));
        let locked = Scg::new(Words::new());
        locked.access().hold_high(offset::SOSCCSR, 1 << 23);
        assert_eq!(
            locked.start(&ClockPlan::EVB_80_MHZ),
            Err(ScgError::Locked("SOSCCSR"))
        );
    }
}
