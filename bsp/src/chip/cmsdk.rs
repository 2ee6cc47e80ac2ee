//! Arm CMSDK APB peripherals (Cortex-M System Design Kit, Arm DDI 0479C): the UART (4.4)
//! and the watchdog (3.9), as register blocks and their drivers.

use tock_registers::interfaces::{ReadWriteable, Readable, Writeable};
use tock_registers::register_structs;
use tock_registers::registers::{ReadOnly, ReadWrite, WriteOnly};

pub use bits::{UART_CTRL, UART_INT, UART_STATE, WDOG_CONTROL};

/// The registers' bitfields (the macro's items carry the docs written here, not every
/// helper it generates).
#[allow(missing_docs)]
pub mod bits {
    tock_registers::register_bitfields![u32,
    /// `STATE`.
    pub UART_STATE [
        /// The transmit buffer is full.
        TX_FULL OFFSET(0) NUMBITS(1) [],
        /// The receive buffer holds a byte.
        RX_FULL OFFSET(1) NUMBITS(1) []
    ],
    /// `CTRL`.
    pub UART_CTRL [
        /// Transmitter on.
        TX_EN OFFSET(0) NUMBITS(1) [],
        /// Receiver on.
        RX_EN OFFSET(1) NUMBITS(1) [],
        /// Transmit interrupt on.
        TX_INT OFFSET(2) NUMBITS(1) [],
        /// Receive interrupt on.
        RX_INT OFFSET(3) NUMBITS(1) []
    ],
    /// `INTSTATUS` (write 1 to clear).
    pub UART_INT [
        /// Transmit interrupt.
        TX OFFSET(0) NUMBITS(1) [],
        /// Receive interrupt.
        RX OFFSET(1) NUMBITS(1) []
    ],
    /// `WDOGCONTROL`.
    pub WDOG_CONTROL [
        /// The counter and its interrupt on.
        INTEN OFFSET(0) NUMBITS(1) [],
        /// The reset output on.
        RESEN OFFSET(1) NUMBITS(1) []
    ]
    ];
}

register_structs! {
    /// The CMSDK APB UART.
    pub UartRegisters {
        /// `DATA`: the received byte (read) or the byte to send (write).
        (0x000 => pub data: ReadWrite<u32>),
        /// `STATE`.
        (0x004 => pub state: ReadWrite<u32, UART_STATE::Register>),
        /// `CTRL`.
        (0x008 => pub ctrl: ReadWrite<u32, UART_CTRL::Register>),
        /// `INTSTATUS` / `INTCLEAR`.
        (0x00C => pub intstatus: ReadWrite<u32, UART_INT::Register>),
        /// `BAUDDIV`: the clock divided by the baud rate.
        (0x010 => pub bauddiv: ReadWrite<u32>),
        (0x014 => @END),
    }
}

register_structs! {
    /// The CMSDK APB watchdog.
    pub WatchdogRegisters {
        /// `WDOGLOAD`: writing it restarts the counter from the value.
        (0x000 => pub load: ReadWrite<u32>),
        /// `WDOGVALUE`.
        (0x004 => pub value: ReadOnly<u32>),
        /// `WDOGCONTROL`.
        (0x008 => pub control: ReadWrite<u32, WDOG_CONTROL::Register>),
        /// `WDOGINTCLR`: any write clears the interrupt (and reloads the counter).
        (0x00C => pub intclr: WriteOnly<u32>),
        /// `WDOGRIS`: bit 0, the raw interrupt.
        (0x010 => pub ris: ReadOnly<u32>),
        /// `WDOGMIS`.
        (0x014 => pub mis: ReadOnly<u32>),
        (0x018 => _reserved),
        /// `WDOGLOCK`: the unlock key enables writes to the other registers.
        (0xC00 => pub lock: ReadWrite<u32>),
        (0xC04 => @END),
    }
}

/// The CMSDK APB UART's driver.
pub struct CmsdkUart<'a> {
    regs: &'a UartRegisters,
}

impl<'a> CmsdkUart<'a> {
    /// The driver of the UART `regs`.
    pub const fn new(regs: &'a UartRegisters) -> Self {
        Self { regs }
    }

    /// `baud` baud from a `clock_hz` clock; transmitter and receiver on, with their
    /// interrupts when `interrupts`.
    pub fn init(&self, clock_hz: u32, baud: u32, interrupts: bool) {
        self.regs.bauddiv.set(clock_hz / baud.max(1));
        let on = UART_CTRL::TX_EN::SET + UART_CTRL::RX_EN::SET;
        self.regs.ctrl.write(if interrupts {
            on + UART_CTRL::TX_INT::SET + UART_CTRL::RX_INT::SET
        } else {
            on
        });
    }

    /// The transmitter takes a byte.
    pub fn tx_ready(&self) -> bool {
        !self.regs.state.is_set(UART_STATE::TX_FULL)
    }

    /// Hands `byte` to the transmitter (call when [`CmsdkUart::tx_ready`]).
    pub fn write_byte(&self, byte: u8) {
        self.regs.data.set(u32::from(byte));
    }

    /// The received byte, if one is there.
    pub fn read_byte(&self) -> Option<u8> {
        self.regs
            .state
            .is_set(UART_STATE::RX_FULL)
            .then(|| self.regs.data.get() as u8)
    }

    /// Clears both interrupts.
    pub fn clear_interrupts(&self) {
        self.regs
            .intstatus
            .write(UART_INT::TX::SET + UART_INT::RX::SET);
    }

    /// Clears the transmit interrupt.
    pub fn clear_tx_interrupt(&self) {
        self.regs.intstatus.write(UART_INT::TX::SET);
    }

    /// Turns the receive interrupt on (a UART that only receives).
    pub fn enable_rx_interrupt(&self) {
        self.regs.ctrl.modify(UART_CTRL::RX_INT::SET);
    }
}

/// The CMSDK APB watchdog's driver. The counter counts down at its clock; at zero it
/// raises its interrupt and reloads; at the next zero with the interrupt still raised it
/// resets. A trigger restarts the counter and clears the interrupt, so the reset comes
/// `2 x WDOGLOAD` counts after the last trigger: the load is half the timeout, and the
/// interrupt half-way is the early warning.
pub struct CmsdkWatchdog<'a> {
    regs: &'a WatchdogRegisters,
    clock_hz: u32,
}

impl<'a> CmsdkWatchdog<'a> {
    /// `WDOGLOCK`'s unlock key.
    pub const UNLOCK_KEY: u32 = 0x1ACC_E551;

    /// The driver of the watchdog `regs`, its counter clocked at `clock_hz`.
    pub const fn new(regs: &'a WatchdogRegisters, clock_hz: u32) -> Self {
        Self { regs, clock_hz }
    }

    /// The counts that make half of `timeout_ms`.
    pub const fn half_timeout_counts(&self, timeout_ms: u16) -> u32 {
        (self.clock_hz / 1000).saturating_mul(timeout_ms as u32 / 2)
    }

    /// A trigger with `timeout_ms` (`Wdg_SetTriggerCondition`): unlocked, the counter
    /// restarted from half the timeout, the interrupt cleared, the counter, its
    /// interrupt and the reset on, locked again.
    pub fn trigger(&self, timeout_ms: u16) {
        self.regs.lock.set(Self::UNLOCK_KEY);
        self.regs
            .load
            .set(self.half_timeout_counts(timeout_ms.max(2)));
        self.regs.intclr.set(1);
        self.regs
            .control
            .write(WDOG_CONTROL::INTEN::SET + WDOG_CONTROL::RESEN::SET);
        self.regs.lock.set(0);
    }

    /// `Wdg_SetMode(OFF)`: the counter, its interrupt and the reset off.
    pub fn off(&self) {
        self.regs.lock.set(Self::UNLOCK_KEY);
        self.regs.control.set(0);
        self.regs.intclr.set(1);
        self.regs.lock.set(0);
    }

    /// The watchdog has expired once (its interrupt is raised; the reset follows at the
    /// next expiry).
    pub fn expired(&self) -> bool {
        self.regs.ris.get() & 1 != 0
    }
}

#[cfg(test)]
mod tests;
