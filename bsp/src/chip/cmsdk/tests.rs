//! The CMSDK drivers' register sequences, on register blocks in ordinary memory.

use super::*;

/// A register block in RAM, all registers zero.
fn block<T>() -> T {
    // SAFETY: the register blocks are `repr(C)` structs of `u32` cells (and padding
    // arrays of bytes); all zeroes is a valid value of each.
    unsafe { core::mem::zeroed() }
}

#[test]
fn the_uart_is_set_to_its_baud_rate_with_both_directions_and_interrupts() {
    let regs: UartRegisters = block();
    let uart = CmsdkUart::new(&regs);
    uart.init(25_000_000, 115_200, true);
    assert_eq!(regs.bauddiv.get(), 217);
    assert_eq!(regs.ctrl.get(), 0b1111);
    let regs: UartRegisters = block();
    CmsdkUart::new(&regs).init(25_000_000, 9_600, false);
    assert_eq!((regs.bauddiv.get(), regs.ctrl.get()), (2604, 0b0011));
}

#[test]
fn the_uart_sends_only_when_its_buffer_has_room_and_reads_only_a_byte_there() {
    let regs: UartRegisters = block();
    let uart = CmsdkUart::new(&regs);
    assert!(uart.tx_ready());
    regs.state.set(1);
    assert!(!uart.tx_ready(), "TX_FULL");
    assert_eq!(uart.read_byte(), None, "RX_FULL clear");
    regs.data.set(0x1_42);
    regs.state.set(2);
    assert_eq!(uart.read_byte(), Some(0x42), "the low byte");
    uart.write_byte(b'Z');
    assert_eq!(regs.data.get(), u32::from(b'Z'));
    uart.clear_interrupts();
    assert_eq!(regs.intstatus.get(), 0b11);
    uart.clear_tx_interrupt();
    assert_eq!(regs.intstatus.get(), 0b01);
}

#[test]
fn a_uart_enabled_for_receiving_keeps_its_other_bits() {
    let regs: UartRegisters = block();
    let uart = CmsdkUart::new(&regs);
    uart.init(25_000_000, 9_600, false);
    uart.enable_rx_interrupt();
    assert_eq!(regs.ctrl.get(), 0b1011);
}

#[test]
fn a_trigger_loads_half_the_timeout_and_leaves_the_watchdog_running_and_locked() {
    let regs: WatchdogRegisters = block();
    let wdg = CmsdkWatchdog::new(&regs, 50_000_000);
    wdg.trigger(50);
    assert_eq!(regs.load.get(), 50_000 * 25, "25 ms of a 50 MHz clock");
    assert_eq!(regs.control.get(), 0b11, "INTEN and RESEN");
    assert_eq!(regs.lock.get(), 0, "locked again");
    assert!(!wdg.expired());
    wdg.off();
    assert_eq!((regs.control.get(), regs.lock.get()), (0, 0));
}

#[test]
fn the_watchdog_block_has_its_lock_at_0xc00() {
    let regs: WatchdogRegisters = block();
    let base = core::ptr::addr_of!(regs) as usize;
    assert_eq!(core::ptr::addr_of!(regs.lock) as usize - base, 0xC00);
    assert_eq!(core::mem::size_of::<WatchdogRegisters>(), 0xC04);
    assert_eq!(core::mem::size_of::<UartRegisters>(), 0x14);
}
