//! QEMU's `mps2-an386` board (Arm MPS2 with the AN386 FPGA image: a Cortex-M4 at 25 MHz),
//! as QEMU 7.2 models it.
//!
//! | part | here | registers |
//! |---|---|---|
//! | warning LEDs | [`Led`]: FPGAIO LED bits 0 (red) and 1 (yellow) | FPGAIO `LED0` at `0x4002_8000` |
//! | CAN | [`SlcanCan`]: frames as SLCAN (Lawicel) text on UART0 | CMSDK APB UART0 at `0x4000_4000`, IRQ 0 (RX), 1 (TX) |
//! | distance sensor (live runs) | [`SensorUart`]: a UART ranging module's bytes ([`sensor`]) | CMSDK APB UART1 at `0x4000_5000`, IRQ 2 (RX) |
//! | OS tick | SysTick, 25 000 core clocks per ms | SCS |
//! | watchdog | [`CmsdkWatchdog`]: WdgM's trigger; its first expiry is an NMI, its second resets the board | CMSDK APB watchdog at `0x4000_8000` |
//! | log, exit | semihosting (`-semihosting-config enable=on,target=native`) | |
//!
//! QEMU models no FlexCAN, so the CAN controller here is a UART speaking SLCAN: what the
//! ECU sends is visible outside the emulator (QEMU's `-serial tcp:...` and python-can's
//! `slcan` interface). One transmit mailbox: a frame occupies it until its last character
//! has left the UART, then the driver reports the transmit confirmation.

pub mod semihosting;
pub mod sensor;

pub use sensor::{sensor_uart_stats, SensorUart, SensorUartStats};

use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

#[cfg(feature = "bus-faults")]
use cw_core::can::CanFrame;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};

use crate::chip::cmsdk::CmsdkUart;
use crate::chip::fpgaio::FpgaLeds;
use crate::cortex_m::{app, now_ms, now_us};
use crate::port::preempt::{Mark, PortFault};
use crate::slcan::{ByteUart, SlcanBoard, SlcanBus};
pub use crate::slcan::{SlcanEvent, SlcanStats};

/// The core clock, Hz (SysTick counts it).
pub const SYSCLK_HZ: u32 = 25_000_000;

/// The AN386 image's peripherals this board uses, at their addresses (its memory map).
mod map {
    use crate::chip::cmsdk::{UartRegisters, WatchdogRegisters};
    use crate::chip::fpgaio::FpgaIoRegisters;

    /// CMSDK APB UART0 (the CAN controller's SLCAN link).
    pub const UART0: usize = 0x4000_4000;
    /// CMSDK APB UART1 (the sensor).
    pub const UART1: usize = 0x4000_5000;
    /// The CMSDK APB watchdog.
    pub const WATCHDOG: usize = 0x4000_8000;
    /// FPGAIO.
    pub const FPGAIO: usize = 0x4002_8000;

    /// The UART at `base` (UART0 or UART1).
    pub fn uart(base: usize) -> &'static UartRegisters {
        // SAFETY: UART0 and UART1 are CMSDK APB UARTs at these addresses on this board,
        // mapped for its whole life; the block is accessed through volatile cells only.
        unsafe { &*(base as *const UartRegisters) }
    }

    /// The watchdog.
    pub fn watchdog() -> &'static WatchdogRegisters {
        // SAFETY: as `uart`: the CMSDK APB watchdog of this board.
        unsafe { &*(WATCHDOG as *const WatchdogRegisters) }
    }

    /// FPGAIO.
    pub fn fpgaio() -> &'static FpgaIoRegisters {
        // SAFETY: as `uart`: the FPGAIO block of this board.
        unsafe { &*(FPGAIO as *const FpgaIoRegisters) }
    }
}

/// A warning LED: one bit of the FPGAIO LED register. The LED pins are the ECU's
/// `RES_LEDS`, so the register's read-modify-write never races another writer.
pub struct Led {
    bit: u32,
}

impl Led {
    /// The red LED (LED0 bit 0).
    pub const RED: Self = Self { bit: 0 };
    /// The yellow LED (LED0 bit 1).
    pub const YELLOW: Self = Self { bit: 1 };

    fn write(&self, lit: bool) {
        let (now, new) = FpgaLeds::new(map::fpgaio()).set(self.bit, lit);
        if new != now {
            led_changed(new);
        }
    }
}

/// LED register values logged with their time, from the start of the run.
pub const LED_LOG: usize = 48;

struct LedLog {
    entries: [(u32, u8); LED_LOG],
    len: usize,
    dropped: u32,
}

struct LedLogCell(core::cell::UnsafeCell<LedLog>);

// SAFETY: reached only inside `cortex_m::interrupt::free`, on a single core.
unsafe impl Sync for LedLogCell {}

static LEDS_LOGGED: LedLogCell = LedLogCell(core::cell::UnsafeCell::new(LedLog {
    entries: [(0, 0); LED_LOG],
    len: 0,
    dropped: 0,
}));

fn led_changed(value: u32) {
    let at_ms = u32::try_from(now_ms()).unwrap_or(u32::MAX);
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are off; the only reference to the log.
        let log = unsafe { &mut *LEDS_LOGGED.0.get() };
        match log.entries.get_mut(log.len) {
            Some(slot) => {
                *slot = (at_ms, value as u8);
                log.len += 1;
            }
            None => log.dropped = log.dropped.saturating_add(1),
        }
    });
}

/// Calls `f` with each logged change of the LED register in order (ms since the OS
/// started, the register's bits: 0 red, 1 yellow); returns how many changes came after
/// the log was full.
pub fn led_changes(mut f: impl FnMut(u32, u8)) -> u32 {
    cortex_m::interrupt::free(|_| {
        // SAFETY: as in `led_changed`; `f` does not write LEDs.
        let log = unsafe { &*LEDS_LOGGED.0.get() };
        for &(at, value) in log.entries.iter().take(log.len) {
            f(at, value);
        }
        log.dropped
    })
}

/// Both LEDs dark: the outputs' safe state, for fatal errors.
pub fn leds_safe() {
    FpgaLeds::new(map::fpgaio()).all_dark();
}

impl ErrorType for Led {
    type Error = Infallible;
}

impl OutputPin for Led {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.write(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.write(true);
        Ok(())
    }
}

/// A line the board does not have (the HC-SR04's trigger and echo: the emulated sensor
/// needs no pulse): writes go nowhere, reads are low.
pub struct Unconnected;

impl ErrorType for Unconnected {
    type Error = Infallible;
}

impl OutputPin for Unconnected {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl InputPin for Unconnected {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(false)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(true)
    }
}

/// Busy-wait delays on the core clock.
pub struct CoreDelay;

impl DelayNs for CoreDelay {
    fn delay_ns(&mut self, ns: u32) {
        // 25 cycles per µs; at least one.
        cortex_m::asm::delay((ns / 40).max(1));
    }
}

/// Starts SysTick free-running, without its interrupt: the clock of the measurements made
/// before the OS starts ([`crate::cortex_m::start_free_systick`]).
pub fn start_measuring_clock() {
    crate::cortex_m::start_free_systick();
}

/// Starts SysTick: one interrupt per millisecond, at OSEK ISR priority `osek_priority`.
pub fn start_tick(osek_priority: u8) {
    crate::cortex_m::start_systick(SYSCLK_HZ / 1000 - 1, osek_priority);
}

/// UART0, the SLCAN controller's byte UART: its interrupt work is its transmit line's
/// (line 1), which `Can_Write` pends.
pub struct Uart0;

impl Uart0 {
    fn chip() -> CmsdkUart<'static> {
        CmsdkUart::new(map::uart(map::UART0))
    }
}

impl ByteUart for Uart0 {
    fn tx_ready(&self) -> bool {
        Self::chip().tx_ready()
    }
    fn write_byte(&mut self, byte: u8) {
        Self::chip().write_byte(byte);
    }
    fn read_byte(&mut self) -> Option<u8> {
        Self::chip().read_byte()
    }
    fn clear_interrupts(&mut self) {
        Self::chip().clear_interrupts();
    }
    fn tx_idle(&mut self) {
        Self::chip().clear_tx_interrupt();
        cortex_m::peripheral::NVIC::unpend(Irq(1));
    }
    fn request_service(&mut self) {
        cortex_m::peripheral::NVIC::pend(Irq(1));
    }
}

/// This board's time and trace marks for the SLCAN controller.
pub struct Mps2Slcan;

impl SlcanBoard for Mps2Slcan {
    fn now_ms() -> u64 {
        now_ms()
    }
    fn now_us() -> u64 {
        now_us()
    }
    fn mark_write(start: bool) {
        if crate::cortex_m::trace::ENABLED {
            crate::cortex_m::trace::mark(if start {
                Mark::SpanStart(DRIVER_WRITE_SPAN)
            } else {
                Mark::SpanEnd(DRIVER_WRITE_SPAN)
            });
        }
    }
}

/// The trace span (`cortex_m::trace`) the driver's `Can_Write` is measured in: the
/// bus-fault check, the frame into the mailbox and the transmit interrupt requested (the
/// ECU names it `span::DRIVER_WRITE`).
pub const DRIVER_WRITE_SPAN: usize = 5;

/// This board's CAN controller: SLCAN on UART0 ([`crate::slcan`]).
pub type SlcanCan = crate::slcan::SlcanCan<Uart0, Mps2Slcan>;

/// The bus around UART0's controller: its counters and the faults a scenario plays.
pub static SLCAN_BUS: SlcanBus = SlcanBus::new();

/// The CAN controller on UART0 (QEMU's first `-serial`), 115 200 baud, its interrupts on.
pub fn slcan_uart0() -> SlcanCan {
    CmsdkUart::new(map::uart(map::UART0)).init(SYSCLK_HZ, 115_200, true);
    SlcanCan::new(Uart0, &SLCAN_BUS)
}

/// Enables UART0's interrupts (the CAN controller's) in the NVIC at OSEK ISR priority
/// `osek_priority`.
pub fn enable_can_interrupts(osek_priority: u8) {
    crate::cortex_m::enable_irq(Irq(0), osek_priority);
    crate::cortex_m::enable_irq(Irq(1), osek_priority);
}

/// What UART0's SLCAN link has counted since start-up.
pub fn slcan_stats() -> SlcanStats {
    SLCAN_BUS.stats()
}

/// The board's work in every OS tick (the application's tick calls it first): the CAN
/// controller's delayed transmission or bus-off, when due, raises its interrupt.
pub fn on_tick() {
    if SLCAN_BUS.deferred_due(now_ms()) {
        cortex_m::peripheral::NVIC::pend(Irq(1));
    }
}

/// Fault injection (a scenario's `can-errors`): [`SlcanBus::inject_tx_errors`].
#[cfg(feature = "bus-faults")]
pub fn inject_tx_errors(count: u32) {
    SLCAN_BUS.inject_tx_errors(count);
}

/// A tester's frame on the bus (a scenario's `frame`): the controller receives it in the
/// interrupt this raises.
#[cfg(feature = "bus-faults")]
pub fn put_frame_on_bus(frame: CanFrame) {
    SLCAN_BUS.put_frame(&frame);
    cortex_m::peripheral::NVIC::pend(Irq(0));
}

/// An external interrupt line of this board (QEMU's mps2 wiring).
pub use crate::cortex_m::Line as Irq;

// The log: `defmt` frames, written to the host's standard output over semihosting by
// defmt-semihosting's global logger (its critical section is cortex-m's single-core one:
// PRIMASK, restored after the frame). The format strings stay in the ELF's `.defmt`
// section, not in flash; the host decodes the frames with the ELF (`defmt-print -e ELF`,
// which `cargo xtask qemu` and the emulator tests run on QEMU's output).
use defmt_semihosting as _;

/// Ends the QEMU run (semihosting `SYS_EXIT`), successfully or not: the measuring and
/// test images' end (QEMU runs them with semihosting; a board without a debugger would
/// fault on the call, so a production image never makes it: [`halt`] resets).
pub fn exit(success: bool) -> ! {
    let code = if success {
        cortex_m_semihosting::debug::EXIT_SUCCESS
    } else {
        cortex_m_semihosting::debug::EXIT_FAILURE
    };
    cortex_m_semihosting::debug::exit(code);
    loop {
        cortex_m::asm::wfi();
    }
}

/// The board's watchdog for WdgM (`cw_core::wdgm::WdgDriver`): the CMSDK APB watchdog
/// ([`crate::chip::cmsdk::CmsdkWatchdog`]), its first expiry an NMI (the early warning,
/// which logs the reason), its second a reset of the board.
pub struct CmsdkWatchdog {
    _private: (),
}

impl CmsdkWatchdog {
    /// The board's watchdog (started by the first trigger).
    pub const fn new() -> Self {
        Self { _private: () }
    }

    fn chip() -> crate::chip::cmsdk::CmsdkWatchdog<'static> {
        crate::chip::cmsdk::CmsdkWatchdog::new(map::watchdog(), WATCHDOG_CLOCK_HZ)
    }
}

impl Default for CmsdkWatchdog {
    fn default() -> Self {
        Self::new()
    }
}

/// The watchdog's counter clock, Hz. On the AN386 FPGA image it is the 25 MHz system
/// clock; QEMU 7.2's model counts twice as fast (measured: with `WDOGLOAD` at 625,000,
/// the first expiry came 12.5 ms after the trigger, by the OS's SysTick time), so the
/// timeout is set for the model QEMU runs. A port to the physical board halves this.
const WATCHDOG_CLOCK_HZ: u32 = 2 * SYSCLK_HZ;

/// The last trigger of the watchdog, OS ms (for the report of its expiry).
static WATCHDOG_TRIGGERED_MS: AtomicU32 = AtomicU32::new(0);

impl cw_core::wdgm::WdgDriver for CmsdkWatchdog {
    fn set_trigger_condition(&mut self, timeout_ms: u16) {
        Self::chip().trigger(timeout_ms);
        WATCHDOG_TRIGGERED_MS.store(
            u32::try_from(now_ms()).unwrap_or(u32::MAX),
            Ordering::Relaxed,
        );
    }

    fn off(&mut self) {
        Self::chip().off();
    }
}

/// Whether the watchdog has expired once (its interrupt raised: the reset follows at the
/// next expiry).
pub fn watchdog_expired() -> bool {
    CmsdkWatchdog::chip().expired()
}

/// How a fatal fault ends the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FatalEnd {
    /// A system reset (`SCB::sys_reset`): the production image, as on silicon (QEMU,
    /// run with `-no-reboot`, exits).
    Reset,
    /// QEMU's exit with a failure status (semihosting): the measuring and test images,
    /// whose runs a test reads to its end.
    Exit,
}

/// The image ends fatal faults by QEMU's exit instead of a reset.
static END_BY_EXIT: AtomicBool = AtomicBool::new(false);

/// Chooses how this image ends fatal faults (a reset unless told; before start).
pub fn set_fatal_end(end: FatalEnd) {
    END_BY_EXIT.store(end == FatalEnd::Exit, Ordering::Relaxed);
}

/// A fault the OS cannot go on from, already reported: the outputs' safe state (LEDs
/// dark), then the image's end ([`FatalEnd`]): a reset, or QEMU's exit with a failure.
pub fn halt() -> ! {
    cortex_m::interrupt::disable();
    leds_safe();
    if watchdog_expired() {
        // The watchdog's reset comes at its next expiry: it, not the software, ends the run.
        loop {
            cortex_m::asm::wfi();
        }
    }
    if END_BY_EXIT.load(Ordering::Relaxed) {
        exit(false)
    }
    crate::cortex_m::last_words(|| defmt::println!("RESET"));
    cortex_m::peripheral::SCB::sys_reset()
}

/// Logs a port fault with the outputs in their safe state: `FATAL: WHAT ITEM` (a stack
/// overflow then shuts the OS down, whose report follows).
pub fn report(fault: &PortFault) {
    leds_safe();
    if *fault == PortFault::Nmi && watchdog_expired() {
        defmt::println!(
            "watchdog: not triggered since {} ms; expired at {} ms (NMI), its reset follows",
            WATCHDOG_TRIGGERED_MS.load(Ordering::Relaxed),
            now_ms()
        );
        return;
    }
    crate::cortex_m::log_fault(fault);
}

/// A fatal error of the board or the application: LEDs to their safe state, the reason on
/// the log, then [`halt`].
pub fn fatal(what: &str) -> ! {
    leds_safe();
    crate::cortex_m::last_words(|| defmt::println!("FATAL: {=str}", what));
    halt()
}

extern "C" fn uart0_rx() {
    if let Some(app) = app() {
        app.irq(0);
    }
}

extern "C" fn uart0_tx() {
    if let Some(app) = app() {
        app.irq(1);
    }
}

/// The external interrupt line no device of the board drives: software pends it
/// ([`pend_software_irq`]), as a test's or a demo's interrupt source.
pub const SOFTWARE_IRQ: u16 = 31;

extern "C" fn software_irq() {
    if let Some(app) = app() {
        app.irq(SOFTWARE_IRQ);
    }
}

/// Enables [`SOFTWARE_IRQ`] at OSEK ISR priority `osek_priority`.
pub fn enable_software_irq(osek_priority: u8) {
    crate::cortex_m::enable_irq(Irq(SOFTWARE_IRQ), osek_priority);
}

/// Requests [`SOFTWARE_IRQ`].
pub fn pend_software_irq() {
    cortex_m::peripheral::NVIC::pend(Irq(SOFTWARE_IRQ));
}

extern "C" fn unused_irq() {
    fatal("an interrupt without a handler");
}

/// The external interrupt vector: UART0's receive and transmit lines are the CAN
/// controller's, UART1's receive line the distance sensor's, line 31 is
/// [`SOFTWARE_IRQ`]; no other line is enabled.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [extern "C" fn(); 32] = {
    let mut v: [extern "C" fn(); 32] = [unused_irq; 32];
    v[0] = uart0_rx;
    v[1] = uart0_tx;
    v[sensor::SENSOR_RX_IRQ as usize] = sensor::uart1_rx;
    v[SOFTWARE_IRQ as usize] = software_irq;
    v
};

/// FlexCAN's register map in ordinary RAM, for the measuring images: QEMU's mps2-an386
/// has no FlexCAN, so the FlexCAN driver's own paths are counted against a block of RAM
/// laid out as the module (the same loads and stores at the same offsets as on an
/// S32K144: the instructions are the silicon's; what the module would do in reply, a
/// caller does by hand).
#[cfg(feature = "trace")]
pub mod flexcan_ram {
    use core::cell::UnsafeCell;
    use core::sync::atomic::{AtomicBool, Ordering};

    use crate::chip::flexcan::regs::{offset, Mmio, MAX_MAILBOXES};

    /// Words of the block: through the individual masks of every buffer.
    const WORDS: usize = (offset::RXIMR0 + 4 * MAX_MAILBOXES) / 4;

    struct Block(UnsafeCell<[u32; WORDS]>);

    // SAFETY: the block is reached only through the one `Mmio` that `take` hands out.
    unsafe impl Sync for Block {}

    static BLOCK: Block = Block(UnsafeCell::new([0; WORDS]));
    static TAKEN: AtomicBool = AtomicBool::new(false);

    /// The block as a FlexCAN's registers, all zero: once; `None` afterwards.
    pub fn take() -> Option<Mmio> {
        if TAKEN.swap(true, Ordering::AcqRel) {
            return None;
        }
        // SAFETY: `TAKEN` hands the block out once, so the returned `Mmio` is its only
        // user, and the block spans every offset the FlexCAN register view produces.
        Some(unsafe { Mmio::new(BLOCK.0.get().cast()) })
    }
}
