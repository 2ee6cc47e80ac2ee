//! The distance sensor's UART: a UART ranging module (A02YYUW, `cw_core::sonar::uart`)
//! on CMSDK APB UART1 at `0x4000_5000` (QEMU's second `-serial`), 9600 baud, receive
//! only (the module's RX pin selects its output mode and needs no data).
//!
//! The UART holds one received byte. Its receive interrupt (`SensorRxIsr`, OSEK
//! category 1, above every category-2 ISR) moves each byte into a 64-byte ring the
//! sensor task empties once per sample, 40 ms apart: at 9600 baud at most 39 bytes
//! arrive in that time, 4 of them per frame from a module sending every 100 ms. A byte
//! that finds the ring full is dropped and counted as an overrun, as a UART's own
//! overrun would drop it.
//!
//! The ring is [`crate::ring::ByteRing`]: the ISR pushes, the sensor task pops, with
//! atomics alone.

use super::{map, Irq, SYSCLK_HZ};
use crate::chip::cmsdk::CmsdkUart;
use crate::ring::ByteRing;

/// CMSDK APB UART1.
/// UART1's receive interrupt line.
pub const SENSOR_RX_IRQ: u16 = 2;
/// The ring between the interrupt and the sensor task: 64 bytes.
static RING: ByteRing<64> = ByteRing::new();

/// The sensor's UART receiver, for the sensor task.
pub struct SensorUart {
    _private: (),
}

impl SensorUart {
    /// UART1 at the module's 9600 baud, receiver and its interrupt on. The interrupt
    /// stays masked in the NVIC until [`Self::enable_interrupt`].
    pub fn uart1() -> Self {
        let uart = CmsdkUart::new(map::uart(map::UART1));
        uart.init(SYSCLK_HZ, cw_core::sonar::uart::BAUD, false);
        uart.enable_rx_interrupt();
        Self { _private: () }
    }

    /// Enables the receive interrupt in the NVIC at OSEK ISR priority `osek_priority`.
    pub fn enable_interrupt(osek_priority: u8) {
        crate::cortex_m::enable_irq(Irq(SENSOR_RX_IRQ), osek_priority);
    }

    /// The oldest byte received and not yet read.
    pub fn read_byte(&mut self) -> Option<u8> {
        RING.pop()
    }
}

/// What the sensor's UART counted since start-up.
pub type SensorUartStats = crate::ring::RingStats;

/// What the sensor's UART counted since start-up.
pub fn sensor_uart_stats() -> SensorUartStats {
    RING.stats()
}

/// `SensorRxIsr`: every byte the UART holds into the ring.
pub(super) extern "C" fn uart1_rx() {
    let uart = CmsdkUart::new(map::uart(map::UART1));
    uart.clear_interrupts();
    while let Some(byte) = uart.read_byte() {
        RING.push(byte);
    }
}
