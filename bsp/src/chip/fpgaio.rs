//! The MPS2 FPGA images' FPGAIO block (AN386: at `0x4002_8000`): the user LEDs.

use tock_registers::interfaces::{Readable, Writeable};
use tock_registers::register_structs;
use tock_registers::registers::ReadWrite;

register_structs! {
    /// FPGAIO's registers this project uses.
    pub FpgaIoRegisters {
        /// `LED0`: one bit per user LED (1: lit).
        (0x000 => pub led0: ReadWrite<u32>),
        (0x004 => @END),
    }
}

/// The LED bits through FPGAIO's `LED0`.
pub struct FpgaLeds<'a> {
    regs: &'a FpgaIoRegisters,
}

impl<'a> FpgaLeds<'a> {
    /// The LEDs of the block `regs`.
    pub const fn new(regs: &'a FpgaIoRegisters) -> Self {
        Self { regs }
    }

    /// Sets LED `bit` lit or dark; returns the register's value before and after.
    pub fn set(&self, bit: u32, lit: bool) -> (u32, u32) {
        let now = self.regs.led0.get();
        let new = if lit {
            now | (1 << bit)
        } else {
            now & !(1 << bit)
        };
        self.regs.led0.set(new);
        (now, new)
    }

    /// Every LED dark.
    pub fn all_dark(&self) {
        self.regs.led0.set(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> FpgaIoRegisters {
        // SAFETY: the block is plain `u32` cells; all zeroes is a valid value.
        unsafe { core::mem::zeroed() }
    }

    #[test]
    fn each_led_is_its_own_bit_and_dark_clears_them_all() {
        let regs = block();
        let leds = FpgaLeds::new(&regs);
        assert_eq!(leds.set(0, true), (0, 0b01));
        assert_eq!(leds.set(1, true), (0b01, 0b11));
        assert_eq!(leds.set(0, false), (0b11, 0b10));
        leds.all_dark();
        assert_eq!(regs.led0.get(), 0);
    }
}
