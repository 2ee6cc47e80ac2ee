//! The S32K144's LPUART (S32K1xx RM, chapter "Low Power Universal Asynchronous
//! Receiver/Transmitter"): 8N1 at a baud rate computed from its functional clock, as a
//! [`ByteUart`] (the SLCAN controller's, or the UART distance sensor's line).
//!
//! The baud rate is `clock / ((OSR + 1) x SBR)`: [`Divisors::for_baud`] searches every
//! oversampling ratio the register allows (4x to 32x) for the one whose divisor comes
//! nearest the rate asked for, and refuses a rate it cannot reach within 3 % (a UART
//! frame of 10 bits tolerates about 4.5 % between both ends).

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use crate::chip::access::{Access, Reg};
use crate::slcan::ByteUart;

pub use bits::{BAUD, CTRL, STAT};

/// The registers' bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `BAUD`.
    pub BAUD [
        /// The oversampling ratio minus one (3..=31).
        OSR OFFSET(24) NUMBITS(5) [],
        /// Sampling on both edges (needed for ratios 4x to 7x).
        BOTHEDGE OFFSET(17) NUMBITS(1) [],
        /// Two stop bits.
        SBNS OFFSET(13) NUMBITS(1) [],
        /// The baud rate modulo divisor.
        SBR OFFSET(0) NUMBITS(13) []
    ],
    /// `STAT` (flags write-1-to-clear).
    pub STAT [
        /// The transmit data register is empty.
        TDRE OFFSET(23) NUMBITS(1) [],
        /// Transmission complete.
        TC OFFSET(22) NUMBITS(1) [],
        /// The receive data register is full.
        RDRF OFFSET(21) NUMBITS(1) [],
        /// Receiver overrun (write 1 to clear).
        OR OFFSET(19) NUMBITS(1) [],
        /// Noise (write 1 to clear).
        NF OFFSET(18) NUMBITS(1) [],
        /// Framing error (write 1 to clear).
        FE OFFSET(17) NUMBITS(1) []
    ],
    /// `CTRL`.
    pub CTRL [
        /// Transmit interrupt (on `TDRE`).
        TIE OFFSET(23) NUMBITS(1) [],
        /// Receive interrupt (on `RDRF`).
        RIE OFFSET(21) NUMBITS(1) [],
        /// Transmitter on.
        TE OFFSET(19) NUMBITS(1) [],
        /// Receiver on.
        RE OFFSET(18) NUMBITS(1) [],
        /// Nine data bits.
        M OFFSET(4) NUMBITS(1) [],
        /// Parity on.
        PE OFFSET(1) NUMBITS(1) []
    ]
    ];
}

/// Register offsets.
pub mod offset {
    /// `BAUD`.
    pub const BAUD: usize = 0x10;
    /// `STAT`.
    pub const STAT: usize = 0x14;
    /// `CTRL`.
    pub const CTRL: usize = 0x18;
    /// `DATA`.
    pub const DATA: usize = 0x1C;
}

/// The LPUARTs' base addresses.
pub mod base {
    /// LPUART0.
    pub const LPUART0: usize = 0x4006_A000;
    /// LPUART1 (the S32K144EVB's OpenSDA virtual serial port).
    pub const LPUART1: usize = 0x4006_B000;
    /// LPUART2.
    pub const LPUART2: usize = 0x4006_C000;
}

/// `BAUD`'s divisors for one rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Divisors {
    /// The oversampling ratio (4..=32).
    pub oversampling: u8,
    /// The modulo divisor (1..=8191).
    pub sbr: u16,
}

/// No divisors give the rate within 3 %.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BaudUnreachable {
    /// The functional clock, Hz.
    pub clock_hz: u32,
    /// The rate asked for.
    pub baud: u32,
}

impl Divisors {
    /// The divisors nearest `baud` from a `clock_hz` functional clock (the highest
    /// oversampling among equals: the most samples per bit).
    ///
    /// # Errors
    /// [`BaudUnreachable`] when the nearest is more than 3 % off (or `baud` is 0).
    pub fn for_baud(clock_hz: u32, baud: u32) -> Result<Self, BaudUnreachable> {
        let refused = BaudUnreachable { clock_hz, baud };
        if baud == 0 {
            return Err(refused);
        }
        let mut best: Option<(u64, Self)> = None;
        for oversampling in 4..=32u32 {
            let per_bit = u64::from(oversampling) * u64::from(baud);
            // The divisor rounded to nearest, within its field.
            let sbr = ((u64::from(clock_hz) + per_bit / 2) / per_bit).clamp(1, 8191);
            let actual = u64::from(clock_hz) / (u64::from(oversampling) * sbr);
            let error = actual.abs_diff(u64::from(baud));
            if best.is_none_or(|(e, _)| error <= e) {
                best = Some((
                    error,
                    Self {
                        oversampling: oversampling as u8,
                        sbr: sbr as u16,
                    },
                ));
            }
        }
        match best {
            Some((error, d)) if error * 100 <= u64::from(baud) * 3 => Ok(d),
            _ => Err(refused),
        }
    }

    /// The rate these divisors give from `clock_hz`.
    pub const fn baud(&self, clock_hz: u32) -> u32 {
        clock_hz / (self.oversampling as u32 * self.sbr as u32)
    }
}

/// One LPUART.
pub struct Lpuart<A> {
    access: A,
    overruns: u32,
}

impl<A: Access> Lpuart<A> {
    /// The LPUART behind `access` (its clock gate on, its pins muxed).
    pub const fn new(access: A) -> Self {
        Self {
            access,
            overruns: 0,
        }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    fn baud_reg(&self) -> Reg<'_, A, BAUD::Register> {
        Reg::new(&self.access, offset::BAUD)
    }
    fn stat(&self) -> Reg<'_, A, STAT::Register> {
        Reg::new(&self.access, offset::STAT)
    }
    fn ctrl(&self) -> Reg<'_, A, CTRL::Register> {
        Reg::new(&self.access, offset::CTRL)
    }

    /// 8N1 at `baud` from a `clock_hz` functional clock, receiver and transmitter on, the
    /// receive interrupt on. The transmitter and receiver are off while `BAUD` changes,
    /// as the manual asks.
    ///
    /// # Errors
    /// [`BaudUnreachable`]: nothing was written.
    pub fn configure(&self, clock_hz: u32, baud: u32) -> Result<Divisors, BaudUnreachable> {
        let d = Divisors::for_baud(clock_hz, baud)?;
        self.ctrl().write(CTRL::TE::CLEAR + CTRL::RE::CLEAR);
        self.baud_reg().write(
            BAUD::OSR.val(u32::from(d.oversampling) - 1)
                + BAUD::BOTHEDGE.val(u32::from(d.oversampling < 8))
                + BAUD::SBR.val(u32::from(d.sbr)),
        );
        self.ctrl()
            .write(CTRL::TE::SET + CTRL::RE::SET + CTRL::RIE::SET);
        Ok(d)
    }

    /// Receiver overruns seen (a byte lost because the last one was not read in time).
    pub const fn overruns(&self) -> u32 {
        self.overruns
    }
}

impl<A: Access> ByteUart for Lpuart<A> {
    fn tx_ready(&self) -> bool {
        self.stat().is_set(STAT::TDRE)
    }

    fn write_byte(&mut self, byte: u8) {
        self.access.write(offset::DATA, u32::from(byte));
    }

    fn read_byte(&mut self) -> Option<u8> {
        let stat = self.stat().extract();
        if stat.is_set(STAT::OR) {
            self.overruns = self.overruns.saturating_add(1);
            self.stat().write(STAT::OR::SET);
        }
        if !stat.is_set(STAT::RDRF) {
            return None;
        }
        u8::try_from(self.access.read(offset::DATA) & 0xFF).ok()
    }

    /// Clears the error flags (noise, framing); `RDRF` and `TDRE` follow the data.
    fn clear_interrupts(&mut self) {
        self.stat().write(STAT::NF::SET + STAT::FE::SET);
    }

    fn tx_idle(&mut self) {
        self.ctrl().modify(CTRL::TIE::CLEAR);
    }

    fn request_service(&mut self) {
        self.ctrl().modify(CTRL::TIE::SET);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::chip::access::Recorder;

    #[test]
    fn the_usual_rates_from_the_evbs_clocks_are_within_3_percent() {
        for clock in [8_000_000, 40_000_000, 48_000_000] {
            for baud in [9_600, 19_200, 38_400, 57_600, 115_200] {
                let d = Divisors::for_baud(clock, baud).unwrap();
                let actual = d.baud(clock);
                assert!(
                    actual.abs_diff(baud) * 100 <= baud * 3,
                    "{clock} Hz {baud}: {d:?} gives {actual}"
                );
                assert!((4..=32).contains(&d.oversampling) && (1..=8191).contains(&d.sbr));
            }
        }
        // 9600 from the 8 MHz SOSCDIV2: 8e6 / (17 x 49) = 9603.8, 0.04 % off (16x
        // oversampling with SBR 52 would be 0.16 % off).
        assert_eq!(
            Divisors::for_baud(8_000_000, 9_600),
            Ok(Divisors {
                oversampling: 17,
                sbr: 49
            })
        );
        assert!(Divisors::for_baud(8_000_000, 3_000_000).is_err());
        assert!(Divisors::for_baud(8_000_000, 0).is_err());
        assert!(
            Divisors::for_baud(48_000_000, 100).is_err(),
            "SBR at most 8191"
        );
    }

    #[test]
    fn configure_stops_both_sides_then_sets_the_rate_then_starts_them() {
        let uart = Lpuart::new(Recorder::<8, 8>::new());
        let d = uart.configure(8_000_000, 9_600).unwrap();
        let writes: Vec<_> = uart.access().writes().collect();
        assert_eq!(
            writes,
            [
                (offset::CTRL, 0),
                (
                    offset::BAUD,
                    (u32::from(d.oversampling) - 1) << 24 | u32::from(d.sbr)
                ),
                (offset::CTRL, 1 << 19 | 1 << 18 | 1 << 21),
            ]
        );
        assert!(uart.configure(8_000_000, 0).is_err());
        assert_eq!(
            uart.access().writes().count(),
            3,
            "a refused rate writes nothing"
        );
    }

    #[test]
    fn bytes_move_when_the_flags_say_so_and_overruns_are_counted() {
        let mut uart = Lpuart::new(Recorder::<8, 16>::new());
        assert!(!uart.tx_ready());
        uart.access().hold_high(offset::STAT, 1 << 23);
        assert!(uart.tx_ready());
        uart.write_byte(b'A');
        assert_eq!(uart.read_byte(), None);
        uart.access().preset(offset::DATA, u32::from(b'Z'));
        uart.access().preset(offset::STAT, 1 << 21 | 1 << 19);
        assert_eq!(uart.read_byte(), Some(b'Z'));
        assert_eq!(uart.overruns(), 1);
        uart.request_service();
        assert_eq!(uart.access().word(offset::CTRL) & 1 << 23, 1 << 23);
        uart.tx_idle();
        assert_eq!(uart.access().word(offset::CTRL) & 1 << 23, 0);
        let writes: Vec<_> = uart.access().writes().collect();
        assert_eq!(
            writes[..2],
            [(offset::DATA, u32::from(b'A')), (offset::STAT, 1 << 19)]
        );
    }
}
