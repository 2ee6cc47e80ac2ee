//! The S32K144's peripheral clock gating (PCC; S32K1xx RM, chapter "Peripheral Clock
//! Controller"): each peripheral's clock is off out of reset; a driver's board turns it on
//! here first, choosing the functional clock of the peripherals that have one (`PCS`,
//! which may change only while the clock is off).

use tock_registers::interfaces::{Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::PCC;

/// The register's bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// A peripheral's `PCC` word.
    pub PCC [
        /// The peripheral is present on this chip.
        PR OFFSET(31) NUMBITS(1) [],
        /// Its clock is on.
        CGC OFFSET(30) NUMBITS(1) [],
        /// Its functional clock.
        PCS OFFSET(24) NUMBITS(3) [
            Off = 0,
            SoscDiv2 = 1,
            SircDiv2 = 2,
            FircDiv2 = 3,
            SpllDiv2 = 6
        ]
    ]
    ];
}

/// PCC's base address.
pub const BASE: usize = 0x4006_5000;

/// The peripherals this ECU's boards use, by their word's offset in PCC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(usize)]
pub enum Peripheral {
    /// FlexCAN0 (its protocol clock is chosen in `CTRL1[CLKSRC]`, not here).
    FlexCan0 = 0x90,
    /// LPSPI1 (the EVB's system basis chip).
    Lpspi1 = 0xB4,
    /// LPIT0.
    Lpit0 = 0xDC,
    /// FTM0 (input capture of the sensor's echo).
    Ftm0 = 0xE0,
    /// PORTA.
    PortA = 0x124,
    /// PORTB.
    PortB = 0x128,
    /// PORTC.
    PortC = 0x12C,
    /// PORTD.
    PortD = 0x130,
    /// PORTE.
    PortE = 0x134,
    /// LPUART0.
    Lpuart0 = 0x1A8,
    /// LPUART1.
    Lpuart1 = 0x1AC,
    /// LPUART2.
    Lpuart2 = 0x1B0,
}

impl Peripheral {
    /// Whether the peripheral takes a functional clock from `PCS`.
    pub const fn has_functional_clock(self) -> bool {
        matches!(
            self,
            Self::Lpspi1 | Self::Lpit0 | Self::Ftm0 | Self::Lpuart0 | Self::Lpuart1 | Self::Lpuart2
        )
    }
}

/// The functional clock of a peripheral that has one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Source {
    /// `SOSCDIV2_CLK`.
    SoscDiv2,
    /// `SIRCDIV2_CLK`.
    SircDiv2,
    /// `FIRCDIV2_CLK`.
    FircDiv2,
    /// `SPLLDIV2_CLK`.
    SpllDiv2,
}

/// A request PCC cannot carry out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PccError {
    /// The chip does not have the peripheral (`PR` clear).
    Absent(Peripheral),
    /// A functional clock for a peripheral that has none, or none for one that needs it.
    Source(Peripheral),
}

/// The Peripheral Clock Controller.
pub struct Pcc<A> {
    access: A,
}

impl<A: Access> Pcc<A> {
    /// PCC behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Turns `peripheral`'s clock on, with `source` as its functional clock (`None` for a
    /// peripheral without one). The clock goes off first, so that `PCS` may change.
    ///
    /// # Errors
    /// [`PccError`]: the chip lacks the peripheral, or the source does not fit it.
    pub fn enable(&self, peripheral: Peripheral, source: Option<Source>) -> Result<(), PccError> {
        if source.is_some() != peripheral.has_functional_clock() {
            return Err(PccError::Source(peripheral));
        }
        let word: Reg<'_, A, PCC::Register> = Reg::new(&self.access, peripheral as usize);
        if !word.is_set(PCC::PR) {
            return Err(PccError::Absent(peripheral));
        }
        let pcs = match source {
            None => PCC::PCS::Off,
            Some(Source::SoscDiv2) => PCC::PCS::SoscDiv2,
            Some(Source::SircDiv2) => PCC::PCS::SircDiv2,
            Some(Source::FircDiv2) => PCC::PCS::FircDiv2,
            Some(Source::SpllDiv2) => PCC::PCS::SpllDiv2,
        };
        word.write(PCC::CGC::CLEAR);
        word.write(pcs);
        word.write(pcs + PCC::CGC::SET);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    fn pcc() -> Pcc<Recorder<{ 0x1B4 / 4 }, 8>> {
        let r = Recorder::new();
        for p in [Peripheral::FlexCan0, Peripheral::PortD, Peripheral::Lpuart1] {
            r.hold_high(p as usize, 1 << 31);
        }
        Pcc::new(r)
    }

    #[test]
    fn a_clock_goes_off_then_gets_its_source_then_goes_on() {
        let pcc = pcc();
        pcc.enable(Peripheral::Lpuart1, Some(Source::SoscDiv2))
            .unwrap();
        let writes: Vec<_> = pcc.access().writes().collect();
        assert_eq!(
            writes,
            [(0x1AC, 0), (0x1AC, 1 << 24), (0x1AC, 1 << 24 | 1 << 30)]
        );
        pcc.enable(Peripheral::PortD, None).unwrap();
        assert_eq!(pcc.access().word(0x130), 1 << 31 | 1 << 30);
    }

    #[test]
    fn absent_peripherals_and_unfitting_sources_are_refused() {
        let pcc = pcc();
        assert_eq!(
            pcc.enable(Peripheral::Ftm0, Some(Source::SpllDiv2)),
            Err(PccError::Absent(Peripheral::Ftm0))
        );
        assert_eq!(
            pcc.enable(Peripheral::FlexCan0, Some(Source::SoscDiv2)),
            Err(PccError::Source(Peripheral::FlexCan0))
        );
        assert_eq!(
            pcc.enable(Peripheral::Lpuart1, None),
            Err(PccError::Source(Peripheral::Lpuart1))
        );
        assert_eq!(pcc.access().writes().count(), 0);
    }
}
