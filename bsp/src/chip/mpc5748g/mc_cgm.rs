//! The MPC5748G's clocks: the PLL (PLLDIG) and the clock generation module's dividers and
//! selectors (MC_CGM; MPC5748G RM, chapters "Clocking", "PLL Digital Interface", "Clock
//! Generation Module").
//!
//! [`ClockPlan::XTAL40_160_MHZ`] is the set-up for a 40 MHz crystal that NXP's MPC5748G
//! examples and the DEVKIT-MPC5748G's published sources program: the PLL from the crystal
//! (`PREDIV` 2, `MFD` 32: a 640 MHz VCO; NXP's example reaches the same VCO with 1 and
//! 16), PHI0 at 160 MHz (`RFDPHI` 1, `RFDPHI1` 2), the system clock from PHI0 through
//! MC_ME, and the dividers `SC_DC0` /1 (160 MHz), `SC_DC1` /2 (80 MHz, the peripheral
//! bus), `SC_DC2` /4 (40 MHz), `SC_DC5` /2 (FS80, which must equal `SC_DC1`'s clock);
//! FlexCAN_0's protocol clock from the crystal (`AC9` = FXOSC).
//!
//! **The PLL's limits and the formula from VCO to PHI0 are not checked here**: the plan is
//! the sources' values, taken as they are; the reference manual's PLL chapter is what a
//! first run on a board must be checked against.
//!
//! Order ([`Cgm::prepare`]): the dividers first (each in one store that keeps it running:
//! the core is clocked through them), the PLL's input
//! and dividers, then MC_ME's mode transition switches the system clock
//! ([`super::mc_me`]); [`Cgm::pll_locked`] reads the lock afterwards.

use tock_registers::interfaces::{Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::{DC, PLLDV, PLLSR};

/// The registers' bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// A system clock divider (`SC_DC0`, ...).
    pub DC [
        /// The divider's output runs.
        DE OFFSET(31) NUMBITS(1) [],
        /// Divide by `DIV + 1` (3 bits, 4 in `SC_DC2`).
        DIV OFFSET(16) NUMBITS(4) []
    ],
    /// `PLLDV`, the PLL's dividers.
    pub PLLDV [
        /// The loop's multiplication factor.
        MFD OFFSET(0) NUMBITS(8) [],
        /// The input's divider.
        PREDIV OFFSET(12) NUMBITS(3) [],
        /// PHI0's divider.
        RFDPHI OFFSET(16) NUMBITS(6) [],
        /// PHI1's divider.
        RFDPHI1 OFFSET(25) NUMBITS(6) []
    ],
    /// `PLLSR`, the PLL's status.
    pub PLLSR [
        /// Locked.
        LOCK OFFSET(2) NUMBITS(1) []
    ]
    ];
}

/// Register offsets from MC_CGM's base (the PLL's from PLLDIG's).
pub mod offset {
    /// `AC5_SC`: the PLL's input (`SELCTL` 1: FXOSC).
    pub const AC5_SC: usize = 0x1C0;
    /// `AC9_SC`: FlexCAN_0's clock (`SELCTL` 0: FS80, 1: FXOSC).
    pub const AC9_SC: usize = 0x2C0;
    /// `SC_DC0`; `SC_DC1`, `SC_DC2` follow at 4-byte steps.
    pub const SC_DC0: usize = 0x7E8;
    /// `SC_DC5`.
    pub const SC_DC5: usize = 0x7FC;
    /// PLLDIG's `PLLSR`.
    pub const PLLSR: usize = 0x24;
    /// PLLDIG's `PLLDV`.
    pub const PLLDV: usize = 0x28;
    /// PLLDIG's `PLLFD` (fractional divider; 0: integer mode).
    pub const PLLFD: usize = 0x30;
}

/// MC_CGM's base address.
pub const BASE: usize = 0xFFFB_0000;
/// PLLDIG's base address.
pub const PLLDIG_BASE: usize = 0xFFFB_0080;
/// An auxiliary clock selector's `SELCTL` field.
const SELCTL_SHIFT: u32 = 24;

/// How the clocks come from the crystal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ClockPlan {
    /// The crystal, Hz.
    pub fxosc_hz: u32,
    /// `PLLDV[PREDIV]`.
    pub prediv: u8,
    /// `PLLDV[MFD]`.
    pub mfd: u8,
    /// `PLLDV[RFDPHI]`.
    pub rfdphi: u8,
    /// `PLLDV[RFDPHI1]`.
    pub rfdphi1: u8,
    /// PHI0 as the sources give it for these values, Hz.
    pub phi0_hz: u32,
    /// The `DIV` fields of `SC_DC0`, `SC_DC1`, `SC_DC2`, `SC_DC5` (divide by `DIV + 1`).
    pub dividers: [u8; 4],
    /// FlexCAN_0's clock from the crystal (`AC9` = FXOSC), else from FS80.
    pub can_from_fxosc: bool,
}

impl ClockPlan {
    /// From a 40 MHz crystal to 160 MHz (the module's documentation).
    pub const XTAL40_160_MHZ: Self = Self {
        fxosc_hz: 40_000_000,
        prediv: 2,
        mfd: 32,
        rfdphi: 1,
        rfdphi1: 2,
        phi0_hz: 160_000_000,
        dividers: [0, 1, 3, 1],
        can_from_fxosc: true,
    };

    /// The clocks of the dividers `SC_DC0`, `SC_DC1`, `SC_DC2`, `SC_DC5`, Hz.
    pub const fn divided(&self) -> [u32; 4] {
        let d = self.dividers;
        [
            self.phi0_hz / (d[0] as u32 + 1),
            self.phi0_hz / (d[1] as u32 + 1),
            self.phi0_hz / (d[2] as u32 + 1),
            self.phi0_hz / (d[3] as u32 + 1),
        ]
    }

    /// FlexCAN_0's protocol clock, Hz.
    pub const fn can_hz(&self) -> u32 {
        if self.can_from_fxosc {
            self.fxosc_hz
        } else {
            self.divided()[3]
        }
    }
}

/// A plan the module refuses before writing anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CgmError {
    /// `SC_DC5` (FS80) must give the same clock as `SC_DC1`.
    Fs80(u8, u8),
    /// A field that does not fit its width, or a PLL divider of 0 (`PREDIV` 1..=7,
    /// `MFD` 1..=255, `RFDPHI` and `RFDPHI1` 1..=63, the dividers 0..=7, `SC_DC2`
    /// 0..=15).
    Field(&'static str),
}

/// The clock generation module and the PLL.
pub struct Cgm<A> {
    cgm: A,
    pll: A,
}

impl<A: Access> Cgm<A> {
    /// MC_CGM behind `cgm`, PLLDIG behind `pll`.
    pub const fn new(cgm: A, pll: A) -> Self {
        Self { cgm, pll }
    }

    /// The access paths (a test's recorders): MC_CGM's, PLLDIG's.
    pub const fn access(&self) -> (&A, &A) {
        (&self.cgm, &self.pll)
    }

    fn check(plan: &ClockPlan) -> Result<(), CgmError> {
        let d = plan.dividers;
        if d[3] != d[1] {
            return Err(CgmError::Fs80(d[3], d[1]));
        }
        let checks = [
            ("PREDIV", (1..=7).contains(&plan.prediv)),
            ("MFD", plan.mfd != 0),
            ("RFDPHI", (1..=63).contains(&plan.rfdphi)),
            ("RFDPHI1", (1..=63).contains(&plan.rfdphi1)),
            ("SC_DC0", d[0] <= 7),
            ("SC_DC1", d[1] <= 7),
            ("SC_DC2", d[2] <= 15),
            ("SC_DC5", d[3] <= 7),
        ];
        match checks.iter().find(|(_, ok)| !ok) {
            Some((name, _)) => Err(CgmError::Field(name)),
            None => Ok(()),
        }
    }

    /// Writes `plan` up to the switch of the system clock, which MC_ME's mode transition
    /// makes: the dividers (each in one store, kept running), FlexCAN_0's and the PLL's
    /// inputs, the PLL's dividers in integer mode.
    ///
    /// # Errors
    /// [`CgmError`]: the plan breaks a rule; nothing is written.
    pub fn prepare(&self, plan: &ClockPlan) -> Result<(), CgmError> {
        Self::check(plan)?;
        let offsets = [
            offset::SC_DC0,
            offset::SC_DC0 + 4,
            offset::SC_DC0 + 8,
            offset::SC_DC5,
        ];
        for (&at, &div) in offsets.iter().zip(plan.dividers.iter()) {
            // One store, the divider kept running: the core is clocked through them.
            Reg::<A, DC::Register>::new(&self.cgm, at)
                .write(DC::DE::SET + DC::DIV.val(u32::from(div)));
        }
        self.cgm.write(
            offset::AC9_SC,
            u32::from(plan.can_from_fxosc) << SELCTL_SHIFT,
        );
        self.cgm.write(offset::AC5_SC, 1 << SELCTL_SHIFT);
        Reg::<A, PLLDV::Register>::new(&self.pll, offset::PLLDV).write(
            PLLDV::PREDIV.val(u32::from(plan.prediv))
                + PLLDV::MFD.val(u32::from(plan.mfd))
                + PLLDV::RFDPHI.val(u32::from(plan.rfdphi))
                + PLLDV::RFDPHI1.val(u32::from(plan.rfdphi1)),
        );
        self.pll.write(offset::PLLFD, 0);
        Ok(())
    }

    /// Whether the PLL is locked.
    pub fn pll_locked(&self) -> bool {
        Reg::<A, PLLSR::Register>::new(&self.pll, offset::PLLSR).is_set(PLLSR::LOCK)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    type Cgm4 = Cgm<Recorder<{ 0x800 / 4 }, 32>>;

    #[test]
    fn the_devkit_plan_gives_the_documented_clocks() {
        let p = ClockPlan::XTAL40_160_MHZ;
        assert_eq!(
            p.divided(),
            [160_000_000, 80_000_000, 40_000_000, 80_000_000]
        );
        assert_eq!(p.can_hz(), 40_000_000);
        // 500 kbit/s from the 40 MHz crystal: an exact FlexCAN bit timing.
        assert!(crate::chip::flexcan::driver::ctrl1_timing(p.can_hz(), 500_000, 875).is_ok());
    }

    #[test]
    fn prepare_writes_each_divider_in_one_store_then_the_inputs_then_the_pll() {
        let c: Cgm4 = Cgm::new(Recorder::new(), Recorder::new());
        c.prepare(&ClockPlan::XTAL40_160_MHZ).unwrap();
        let cgm: Vec<_> = c.access().0.writes().collect();
        assert_eq!(
            cgm,
            [
                (0x7E8, 1 << 31),
                (0x7EC, 1 << 31 | 1 << 16),
                (0x7F0, 1 << 31 | 3 << 16),
                (0x7FC, 1 << 31 | 1 << 16),
                (0x2C0, 1 << 24),
                (0x1C0, 1 << 24),
            ]
        );
        let pll: Vec<_> = c.access().1.writes().collect();
        assert_eq!(pll, [(0x28, 2 << 25 | 1 << 16 | 2 << 12 | 32), (0x30, 0)]);
        assert!(!c.pll_locked());
        c.access().1.hold_high(offset::PLLSR, 1 << 2);
        assert!(c.pll_locked());
    }

    #[test]
    fn a_plan_that_breaks_a_rule_writes_nothing() {
        let c: Cgm4 = Cgm::new(Recorder::new(), Recorder::new());
        let mut p = ClockPlan::XTAL40_160_MHZ;
        p.dividers[3] = 0;
        assert_eq!(c.prepare(&p), Err(CgmError::Fs80(0, 1)));
        let mut p = ClockPlan::XTAL40_160_MHZ;
        p.mfd = 0;
        assert_eq!(c.prepare(&p), Err(CgmError::Field("MFD")));
        assert_eq!(
            c.access().0.writes().count() + c.access().1.writes().count(),
            0
        );
    }
}
