//! The MPC5748G's pins (SIUL2; MPC5748G RM, chapter "System Integration Unit Lite2").
//!
//! Each pad `n` (port letter `P` and pin `p`: `n = 16 x (P - 'A') + p`) has a pad
//! configuration register `MSCRn` at `0x240 + 4n`: its function (`SSS`; 0 is GPIO), its
//! output and input buffers (`OBE`, `IBE`), its slew rate. An input function whose signal
//! can come from several pads takes it from the pad its `IMCRk` (`0xA40 + 4k`) names.
//! A GPIO pad's output is the byte `GPDOn` at `0x1300 + n` (bit 0) and its input the byte
//! `GPDIn` at `0x1500 + n`.
//!
//! Those byte registers are reached as 32-bit words, big-endian (the byte at the lowest
//! address is the word's most significant): a pad's output is a read-modify-write of the
//! word holding it and three neighbours, so pads that share a word must be driven from
//! one context (the ECU drives its LEDs under one OS resource).

use crate::chip::access::Access;

/// Register offsets from SIUL2's base.
pub mod offset {
    /// `MSCR0`.
    pub const MSCR0: usize = 0x240;
    /// `IMCR0` (the reference manual's IMCR512).
    pub const IMCR0: usize = 0xA40;
    /// `GPDO0`, a byte per pad.
    pub const GPDO0: usize = 0x1300;
    /// `GPDI0`, a byte per pad.
    pub const GPDI0: usize = 0x1500;
}

/// SIUL2's base address.
pub const BASE: usize = 0xFFFC_0000;

/// `MSCR[OBE]`: the output buffer on.
pub const OBE: u32 = 1 << 25;
/// `MSCR[IBE]`: the input buffer on.
pub const IBE: u32 = 1 << 19;
/// `MSCR[SRC]`: the fastest slew rate (3).
pub const SRC_FULL: u32 = 3 << 28;

/// A pad: its port letter and pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pad {
    /// The port's letter (`b'A'` to `b'K'`).
    pub port: u8,
    /// The pin in the port (0..=15).
    pub pin: u8,
}

impl Pad {
    /// Pin `pin` of port `port`.
    pub const fn new(port: u8, pin: u8) -> Self {
        Self { port, pin }
    }

    /// The pad's number: `16 x (port - 'A') + pin`.
    pub const fn number(&self) -> usize {
        16 * (self.port.saturating_sub(b'A') as usize) + (self.pin as usize & 15)
    }
}

/// The pad multiplexing and GPIO of SIUL2.
pub struct Siul2<A> {
    access: A,
}

/// The word holding byte register `at` and the byte's shift in it (big-endian).
const fn byte_lane(at: usize) -> (usize, u32) {
    (at & !3, 8 * (3 - (at & 3) as u32))
}

impl<A: Access> Siul2<A> {
    /// SIUL2 behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Pad `pad`'s configuration: `MSCR` written whole.
    pub fn configure(&self, pad: Pad, mscr: u32) {
        self.access.write(offset::MSCR0 + 4 * pad.number(), mscr);
    }

    /// Pad `pad` as a GPIO output at level `high`: the level first, then the buffer, so
    /// that the pad never shows the other one.
    pub fn output(&self, pad: Pad, high: bool) {
        self.drive(pad, high);
        self.configure(pad, OBE);
    }

    /// Pad `pad` as a GPIO input.
    pub fn input(&self, pad: Pad) {
        self.configure(pad, IBE);
    }

    /// Input function `imcr` (its index from `IMCR0`) takes its signal from source `sss`.
    pub fn route_input(&self, imcr: usize, sss: u32) {
        self.access.write(offset::IMCR0 + 4 * imcr, sss & 0xF);
    }

    /// Drives GPIO pad `pad` high or low (`GPDO`, a read-modify-write of its word).
    pub fn drive(&self, pad: Pad, high: bool) {
        let (word, shift) = byte_lane(offset::GPDO0 + pad.number());
        let old = self.access.read(word);
        let new = (old & !(0xFF << shift)) | (u32::from(high) << shift);
        self.access.write(word, new);
    }

    /// Whether pad `pad`'s input is high (`GPDI`).
    pub fn is_high(&self, pad: Pad) -> bool {
        let (word, shift) = byte_lane(offset::GPDI0 + pad.number());
        (self.access.read(word) >> shift) & 1 == 1
    }

    /// Whether pad `pad`'s output is driven high (`GPDO`).
    pub fn is_driven_high(&self, pad: Pad) -> bool {
        let (word, shift) = byte_lane(offset::GPDO0 + pad.number());
        (self.access.read(word) >> shift) & 1 == 1
    }
}

/// One GPIO output pad as an embedded-hal pin; `active_low`: its logical high is a low
/// level (LEDs wired from the pad to the supply, as on NXP's MPC5748G boards).
pub struct Output<A> {
    siul2: Siul2<A>,
    pad: Pad,
    active_low: bool,
}

impl<A: Access> Output<A> {
    /// Pad `pad` of `siul2`, made an output at its logical low.
    pub fn new(siul2: Siul2<A>, pad: Pad, active_low: bool) -> Self {
        siul2.output(pad, active_low);
        Self {
            siul2,
            pad,
            active_low,
        }
    }

    /// Drives the pad to its logical `high` or low.
    pub fn set(&self, high: bool) {
        self.siul2.drive(self.pad, high != self.active_low);
    }

    /// The SIUL2 behind the pin (a test's recorder).
    pub const fn siul2(&self) -> &Siul2<A> {
        &self.siul2
    }
}

impl<A> embedded_hal::digital::ErrorType for Output<A> {
    type Error = core::convert::Infallible;
}

impl<A: Access> embedded_hal::digital::OutputPin for Output<A> {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.set(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.set(true);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use embedded_hal::digital::OutputPin;

    use super::*;
    use crate::chip::access::Recorder;

    type Words = Recorder<{ 0x1600 / 4 }, 16>;

    #[test]
    fn pads_are_numbered_sixteen_per_port() {
        assert_eq!(Pad::new(b'A', 0).number(), 0);
        assert_eq!(Pad::new(b'A', 10).number(), 10);
        assert_eq!(Pad::new(b'B', 1).number(), 17);
        assert_eq!(Pad::new(b'H', 13).number(), 125);
        assert_eq!(Pad::new(b'J', 4).number(), 148);
    }

    #[test]
    fn an_output_gets_its_level_before_its_buffer() {
        let s: Siul2<Words> = Siul2::new(Recorder::new());
        // PA10: GPDO10 is the byte at 0x130A, bits 15:8 of the word at 0x1308.
        s.output(Pad::new(b'A', 10), true);
        let writes: Vec<_> = s.access().writes().collect();
        assert_eq!(writes, [(0x1308, 1 << 8), (0x240 + 4 * 10, OBE)]);
        assert!(s.is_driven_high(Pad::new(b'A', 10)));
        assert!(
            !s.is_driven_high(Pad::new(b'A', 11)),
            "its neighbour untouched"
        );
    }

    #[test]
    fn driving_one_pad_keeps_its_neighbours() {
        let s: Siul2<Words> = Siul2::new(Recorder::new());
        s.access().preset(0x1304, 0x0101_0101);
        s.drive(Pad::new(b'A', 6), false);
        assert_eq!(s.access().word(0x1304), 0x0101_0001);
        s.access().preset(0x1500 + 16, 0x0001_0000);
        assert!(
            s.is_high(Pad::new(b'B', 1)),
            "GPDI17: the second byte of 0x1510"
        );
    }

    #[test]
    fn an_active_low_led_is_lit_by_a_low_level() {
        let s: Siul2<Words> = Siul2::new(Recorder::new());
        let mut led = Output::new(s, Pad::new(b'A', 10), true);
        assert!(led.siul2().is_driven_high(Pad::new(b'A', 10)), "dark: high");
        led.set_high().unwrap();
        assert!(!led.siul2().is_driven_high(Pad::new(b'A', 10)), "lit: low");
    }

    #[test]
    fn an_input_function_is_routed_through_its_imcr() {
        let s: Siul2<Words> = Siul2::new(Recorder::new());
        // FlexCAN_0's RX from PB1: IMCR188 (the manual's IMCR700), source 2.
        s.route_input(188, 2);
        assert_eq!(s.access().writes().last(), Some((0xD30, 2)));
    }
}
