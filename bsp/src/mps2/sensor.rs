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
//! The ring is single-producer (the ISR), single-consumer (the sensor task): the ISR
//! writes a slot and then publishes it with a release store of `TAIL`; the task reads
//! slots up to the `TAIL` it acquired and hands them back with a release store of
//! `HEAD`. Atomics alone, no lock: the ISR never waits for a task.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

use super::{map, Irq, SYSCLK_HZ};
use crate::chip::cmsdk::CmsdkUart;

/// CMSDK APB UART1.
/// UART1's receive interrupt line.
pub const SENSOR_RX_IRQ: u16 = 2;
/// The ring's size, bytes (a power of two: the indices wrap with it).
const RING: usize = 64;

static RING_BYTES: [AtomicU8; RING] = [const { AtomicU8::new(0) }; RING];
/// Bytes written since start (the ISR's).
static TAIL: AtomicU32 = AtomicU32::new(0);
/// Bytes read since start (the sensor task's).
static HEAD: AtomicU32 = AtomicU32::new(0);
/// Bytes dropped on a full ring.
static OVERRUNS: AtomicU32 = AtomicU32::new(0);
/// Bytes received.
static RECEIVED: AtomicU32 = AtomicU32::new(0);

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
        let head = HEAD.load(Ordering::Relaxed);
        if head == TAIL.load(Ordering::Acquire) {
            return None;
        }
        let byte = RING_BYTES
            .get(head as usize % RING)
            .map(|slot| slot.load(Ordering::Relaxed));
        HEAD.store(head.wrapping_add(1), Ordering::Release);
        byte
    }
}

/// What the sensor's UART counted since start-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SensorUartStats {
    /// Bytes received.
    pub received: u32,
    /// Bytes dropped because the ring was full.
    pub overruns: u32,
}

/// What the sensor's UART counted since start-up.
pub fn sensor_uart_stats() -> SensorUartStats {
    SensorUartStats {
        received: RECEIVED.load(Ordering::Relaxed),
        overruns: OVERRUNS.load(Ordering::Relaxed),
    }
}

/// `SensorRxIsr`: every byte the UART holds into the ring.
pub(super) extern "C" fn uart1_rx() {
    let uart = CmsdkUart::new(map::uart(map::UART1));
    uart.clear_interrupts();
    while let Some(byte) = uart.read_byte() {
        RECEIVED.fetch_add(1, Ordering::Relaxed);
        let tail = TAIL.load(Ordering::Relaxed);
        if tail.wrapping_sub(HEAD.load(Ordering::Acquire)) as usize >= RING {
            OVERRUNS.fetch_add(1, Ordering::Relaxed);
            continue;
        }
        if let Some(slot) = RING_BYTES.get(tail as usize % RING) {
            slot.store(byte, Ordering::Relaxed);
        }
        TAIL.store(tail.wrapping_add(1), Ordering::Release);
    }
}
