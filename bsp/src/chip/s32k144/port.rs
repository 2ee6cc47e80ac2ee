//! The S32K144's pins: the multiplexer of each pin (PORT; S32K1xx RM, chapter "Port
//! Control and Interrupts") and the general-purpose outputs and inputs (GPIO; chapter
//! "General-Purpose Input/Output").
//!
//! A GPIO pin is driven through its port's set and clear registers (`PSOR`, `PCOR`): a
//! write of the pin's bit changes that pin alone, with no read-modify-write, so pins of
//! one port can be driven from anywhere without a lock. Only the direction (`PDDR`) is
//! read, modified and written, once, when the pin is made an output ([`Gpio::output`]),
//! before anything else drives it.

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};

use crate::chip::access::{Access, Reg};

pub use bits::PCR;

/// The register's bitfields.
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// A pin's control register.
    pub PCR [
        /// The pin's function: 0 off (analog), 1 GPIO, 2 to 7 the alternatives.
        MUX OFFSET(8) NUMBITS(3) [],
        /// Passive filter.
        PFE OFFSET(4) NUMBITS(1) [],
        /// Pull enable.
        PE OFFSET(1) NUMBITS(1) [],
        /// Pull-up (1) or pull-down (0).
        PS OFFSET(0) NUMBITS(1) []
    ]
    ];
}

/// The ports' PORT bases (pin multiplexing).
pub mod port_base {
    /// PORTA.
    pub const A: usize = 0x4004_9000;
    /// PORTB.
    pub const B: usize = 0x4004_A000;
    /// PORTC.
    pub const C: usize = 0x4004_B000;
    /// PORTD.
    pub const D: usize = 0x4004_C000;
    /// PORTE.
    pub const E: usize = 0x4004_D000;
}

/// The ports' GPIO bases.
pub mod gpio_base {
    /// PTA.
    pub const A: usize = 0x400F_F000;
    /// PTB.
    pub const B: usize = 0x400F_F040;
    /// PTC.
    pub const C: usize = 0x400F_F080;
    /// PTD.
    pub const D: usize = 0x400F_F0C0;
    /// PTE.
    pub const E: usize = 0x400F_F100;
}

/// GPIO register offsets.
pub mod offset {
    /// `PDOR`, the output levels.
    pub const PDOR: usize = 0x00;
    /// `PSOR`: a 1 sets that output.
    pub const PSOR: usize = 0x04;
    /// `PCOR`: a 1 clears that output.
    pub const PCOR: usize = 0x08;
    /// `PDIR`, the input levels.
    pub const PDIR: usize = 0x10;
    /// `PDDR`, the directions (1: output).
    pub const PDDR: usize = 0x14;
}

/// A pin's function in `PCR[MUX]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mux {
    /// A general-purpose input or output.
    Gpio,
    /// Alternative `n` (2..=7) of the pin's table in the data sheet (FlexCAN0 on PTE4 and
    /// PTE5: 5).
    Alt(u8),
}

/// One port's pin multiplexing.
pub struct Port<A> {
    access: A,
}

impl<A: Access> Port<A> {
    /// The port behind `access`.
    pub const fn new(access: A) -> Self {
        Self { access }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Gives pin `pin` (0..=31) the function `mux`, its other settings kept; `false` for a
    /// pin or an alternative that does not exist (nothing written).
    pub fn set_mux(&self, pin: u8, mux: Mux) -> bool {
        let value = match mux {
            Mux::Gpio => 1,
            Mux::Alt(n) if (2..=7).contains(&n) => u32::from(n),
            Mux::Alt(_) => return false,
        };
        if pin > 31 {
            return false;
        }
        let pcr: Reg<'_, A, PCR::Register> = Reg::new(&self.access, 4 * usize::from(pin));
        pcr.modify(PCR::MUX.val(value));
        true
    }
}

/// One GPIO pin of a port.
pub struct Gpio<A> {
    access: A,
    mask: u32,
    active_low: bool,
}

impl<A: Access> Gpio<A> {
    /// Pin `pin` (taken modulo 32) of the port behind `access`; `active_low`: the pin's
    /// logical high is a low level (an LED that lights on a low level, as the S32K144EVB's
    /// RGB LED does).
    pub const fn new(access: A, pin: u8, active_low: bool) -> Self {
        Self {
            access,
            mask: 1 << (pin % 32),
            active_low,
        }
    }

    /// The access path (a test's recorder).
    pub const fn access(&self) -> &A {
        &self.access
    }

    /// Makes the pin an output at its logical low (an LED off), the level set before the
    /// direction so that the pin never shows the other one.
    pub fn output(&self) {
        self.drive(false);
        let pddr: Reg<'_, A, ()> = Reg::new(&self.access, offset::PDDR);
        pddr.set(pddr.get() | self.mask);
    }

    /// Drives the pin to its logical `high` or low.
    pub fn drive(&self, high: bool) {
        let at = if high != self.active_low {
            offset::PSOR
        } else {
            offset::PCOR
        };
        self.access.write(at, self.mask);
    }

    /// Whether the pin's output is at its logical high.
    pub fn is_driven_high(&self) -> bool {
        (self.access.read(offset::PDOR) & self.mask != 0) != self.active_low
    }

    /// Whether the pin's input is at its logical high.
    pub fn is_high(&self) -> bool {
        (self.access.read(offset::PDIR) & self.mask != 0) != self.active_low
    }
}

impl<A> embedded_hal::digital::ErrorType for Gpio<A> {
    type Error = core::convert::Infallible;
}

impl<A: Access> embedded_hal::digital::OutputPin for Gpio<A> {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.drive(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.drive(true);
        Ok(())
    }
}

impl<A: Access> embedded_hal::digital::StatefulOutputPin for Gpio<A> {
    fn is_set_high(&mut self) -> Result<bool, Self::Error> {
        Ok(self.is_driven_high())
    }

    fn is_set_low(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.is_driven_high())
    }
}

impl<A: Access> embedded_hal::digital::InputPin for Gpio<A> {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        Ok(Gpio::is_high(self))
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        Ok(!Gpio::is_high(self))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use embedded_hal::digital::{OutputPin, StatefulOutputPin};

    use super::*;
    use crate::chip::access::Recorder;

    #[test]
    fn a_pin_gets_its_function_and_keeps_its_other_settings() {
        let port = Port::new(Recorder::<32, 8>::new());
        port.access().preset(4 * 5, 0b11); // pull-up on
        assert!(port.set_mux(5, Mux::Alt(5)));
        assert_eq!(port.access().word(4 * 5), 5 << 8 | 0b11);
        assert!(port.set_mux(15, Mux::Gpio));
        assert_eq!(port.access().word(4 * 15), 1 << 8);
        assert!(!port.set_mux(32, Mux::Gpio));
        assert!(!port.set_mux(3, Mux::Alt(1)));
        assert!(!port.set_mux(3, Mux::Alt(8)));
    }

    #[test]
    fn an_active_low_led_is_off_before_it_becomes_an_output_and_lit_by_a_clear() {
        // PTD15, the EVB's red LED: lit by a low level.
        let mut red = Gpio::new(Recorder::<8, 8>::new(), 15, true);
        red.access().preset(offset::PDDR, 1); // PTD0 already an output
        red.output();
        let writes: Vec<_> = red.access().writes().collect();
        assert_eq!(
            writes,
            [(offset::PSOR, 1 << 15), (offset::PDDR, 1 << 15 | 1)],
            "the level (high: off) first, then the direction"
        );
        red.set_high().unwrap();
        assert_eq!(red.access().writes().last(), Some((offset::PCOR, 1 << 15)));
        red.access().preset(offset::PDOR, 0);
        assert!(red.is_set_high().unwrap(), "a low level is the LED lit");
    }

    #[test]
    fn an_active_high_pin_is_set_by_psor_and_read_from_pdir() {
        let mut trigger = Gpio::new(Recorder::<8, 8>::new(), 3, false);
        trigger.set_high().unwrap();
        trigger.set_low().unwrap();
        let writes: Vec<_> = trigger.access().writes().collect();
        assert_eq!(writes, [(offset::PSOR, 1 << 3), (offset::PCOR, 1 << 3)]);
        trigger.access().preset(offset::PDIR, 1 << 3);
        assert!(trigger.is_high());
    }
}
