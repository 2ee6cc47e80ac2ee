//! The S32K144EVB's parts as the ECU takes them (built for `thumbv7em-none-eabihf` with
//! feature `s32k144evb`): start-up, LEDs, the HC-SR04, FlexCAN0, the watchdog, the OS
//! tick, the interrupt vector, the log and the board's ends.
//!
//! Every peripheral is reached through [`Mmio`] at the address the S32K1xx reference
//! manual's memory map gives it; the drivers are `crate::chip`'s, tested on the host.

use core::convert::Infallible;
use core::sync::atomic::{AtomicU8, Ordering};

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};

use super::{
    rgb, CAN_IRQS, CAN_RX, CAN_TX, CORE_HZ, ECHO_CHANNEL, ECHO_PRESCALE_LOG2, ECHO_TICK_HZ,
    FLASH_CONFIG, IRQ_LINES, LED_BLUE, LED_GREEN, LED_RED, SONAR_ECHO, SONAR_TRIGGER,
    START_TIMEOUT,
};
use crate::chip::access::Mmio;
use crate::chip::flexcan::{Flexcan, FlexcanConfig, LayoutError};
use crate::chip::s32k144::ftm::{self, Ftm};
use crate::chip::s32k144::pcc::{Pcc, Peripheral, Source};
use crate::chip::s32k144::port::{gpio_base, port_base, Gpio, Mux, Port};
use crate::chip::s32k144::scg::{self, Scg};
use crate::chip::s32k144::wdog::{self, Timeout, Wdog};
use crate::cortex_m::{app, Line};
use crate::port::preempt::PortFault;

/// The S32K144's peripherals this board uses, at their addresses.
mod map {
    use crate::chip::access::Mmio;

    /// FlexCAN0.
    pub const FLEXCAN0: usize = 0x4002_4000;

    /// The peripheral at `base`, for volatile accesses.
    pub fn at(base: usize) -> Mmio {
        // SAFETY: every `base` passed here is a peripheral of the S32K144's memory map
        // (the board's constants and the chip modules' `BASE`s), mapped for the chip's
        // whole life. Two values for one block exist only for GPIO ports, whose pins
        // are driven through the set and clear registers (a write changes its own pin
        // alone) and whose direction register is written once, at start-up, before any
        // interrupt is enabled.
        unsafe { Mmio::new(base as *mut u8) }
    }
}

const fn port_of(port: u8) -> usize {
    match port {
        b'A' => port_base::A,
        b'B' => port_base::B,
        b'C' => port_base::C,
        b'D' => port_base::D,
        _ => port_base::E,
    }
}

const fn gpio_of(port: u8) -> usize {
    match port {
        b'A' => gpio_base::A,
        b'B' => gpio_base::B,
        b'C' => gpio_base::C,
        b'D' => gpio_base::D,
        _ => gpio_base::E,
    }
}

fn gpio(pin: super::Pin, active_low: bool) -> Gpio<Mmio> {
    Gpio::new(map::at(gpio_of(pin.port)), pin.pin, active_low)
}

fn mux(pin: super::Pin, function: Mux) -> bool {
    Port::new(map::at(port_of(pin.port))).set_mux(pin.pin, function)
}

// ---- start-up -----------------------------------------------------------------------

/// The flash configuration field, which the linker script places at 0x400.
#[link_section = ".flash_config"]
#[used]
#[no_mangle]
static FLASH_CONFIG_FIELD: [u8; 16] = FLASH_CONFIG.bytes();

/// Brings the board up, first thing in `main` (the watchdog resets the chip 8 ms after
/// reset otherwise): the watchdog reconfigured to [`START_TIMEOUT`], the clocks to
/// [`super::CLOCK_PLAN`], the clock gates, the pins' functions, the LEDs dark, the
/// trigger low, and FTM0 counting with its channel capturing the echo. A step that fails
/// is fatal: the chip resets (the watchdog, or [`fatal`]).
pub fn start_up() {
    let wdog = Wdog::new(map::at(wdog::BASE));
    if wdog.configure(START_TIMEOUT).is_err() {
        // The watchdog would not take the configuration; its reset comes anyway.
        halt();
    }
    if Scg::new(map::at(scg::BASE))
        .start(&super::CLOCK_PLAN)
        .is_err()
    {
        fatal("the clocks did not start (SCG)");
    }
    let pcc = Pcc::new(map::at(crate::chip::s32k144::pcc::BASE));
    let gates = [
        (Peripheral::PortB, None),
        (Peripheral::PortC, None),
        (Peripheral::PortD, None),
        (Peripheral::PortE, None),
        (Peripheral::FlexCan0, None),
        (Peripheral::Ftm0, Some(Source::SpllDiv2)),
    ];
    if gates
        .into_iter()
        .any(|(p, source)| pcc.enable(p, source).is_err())
    {
        fatal("a clock gate was refused (PCC)");
    }
    leds_safe();
    for led in [LED_RED, LED_GREEN, LED_BLUE] {
        gpio(led, true).output();
    }
    gpio(SONAR_TRIGGER, false).output();
    let muxed = [
        mux(LED_RED, Mux::Gpio),
        mux(LED_GREEN, Mux::Gpio),
        mux(LED_BLUE, Mux::Gpio),
        mux(SONAR_TRIGGER, Mux::Gpio),
        mux(SONAR_ECHO, Mux::Alt(super::ECHO_ALT)),
        mux(CAN_RX, Mux::Alt(super::CAN_ALT)),
        mux(CAN_TX, Mux::Alt(super::CAN_ALT)),
    ];
    if muxed.contains(&false) {
        fatal("a pin function does not exist (PORT)");
    }
    let ftm = Ftm::new(map::at(ftm::base::FTM0));
    ftm.start(ECHO_PRESCALE_LOG2);
    ftm.capture_both_edges(ECHO_CHANNEL);
}

// ---- LEDs ---------------------------------------------------------------------------

/// The warning LEDs asked for: bit 0 red, bit 1 yellow. Written under the ECU's LED
/// resource only (`RES_LEDS`), so the read-modify-write never races another writer.
static WARNINGS: AtomicU8 = AtomicU8::new(0);

/// One of the ECU's two warning LEDs, shown on the board's RGB LED ([`rgb`]).
pub struct Led {
    bit: u8,
}

impl Led {
    /// The red warning LED.
    pub const RED: Self = Self { bit: 1 };
    /// The yellow warning LED.
    pub const YELLOW: Self = Self { bit: 2 };

    fn write(&self, lit: bool) {
        let now = WARNINGS.load(Ordering::Relaxed);
        let new = if lit { now | self.bit } else { now & !self.bit };
        WARNINGS.store(new, Ordering::Relaxed);
        let (red, green) = rgb(new & Led::RED.bit != 0, new & Led::YELLOW.bit != 0);
        gpio(LED_RED, true).drive(red);
        gpio(LED_GREEN, true).drive(green);
    }
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

/// Every LED channel dark: the outputs' safe state, for fatal errors.
pub fn leds_safe() {
    WARNINGS.store(0, Ordering::Relaxed);
    for led in [LED_RED, LED_GREEN, LED_BLUE] {
        gpio(led, true).drive(false);
    }
}

// ---- the HC-SR04 ----------------------------------------------------------------------

/// The HC-SR04's trigger line (PTC1).
pub fn sonar_trigger() -> Gpio<Mmio> {
    gpio(SONAR_TRIGGER, false)
}

/// The HC-SR04's echo line read as a GPIO input (PTC0; its function is FTM0's channel).
pub fn sonar_echo() -> Gpio<Mmio> {
    gpio(SONAR_ECHO, false)
}

/// FTM0 channel 0's capture of the echo's width.
pub struct EchoCapture {
    ftm: Ftm<Mmio>,
}

impl EchoCapture {
    /// The capture (FTM0 started by [`start_up`]).
    pub fn ftm0() -> Self {
        Self {
            ftm: Ftm::new(map::at(ftm::base::FTM0)),
        }
    }

    /// The high time of the next echo pulse, µs, or `None` when either edge does not
    /// come within `timeout_us`. An edge captured before the call (a late echo of the
    /// last measurement) is discarded first.
    pub fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        self.ftm.discard_capture(ECHO_CHANNEL);
        self.ftm
            .high_time_ticks(ECHO_CHANNEL, timeout_us)
            .map(|ticks| ftm::ticks_to_us(ticks, ECHO_TICK_HZ))
    }
}

/// Busy-wait delays on the core clock.
pub struct CoreDelay;

impl DelayNs for CoreDelay {
    fn delay_ns(&mut self, ns: u32) {
        let cycles = u64::from(ns) * u64::from(CORE_HZ / 1_000_000) / 1000;
        cortex_m::asm::delay(u32::try_from(cycles).unwrap_or(u32::MAX).max(1));
    }
}

// ---- the UART ranging module (the alternative sensor) ----------------------------------

#[cfg(feature = "s32k144evb-uart")]
pub use uart_sensor::{sensor_uart_stats, SensorUart};

/// The UART ranging module on LPUART0 (feature `s32k144evb-uart`).
#[cfg(feature = "s32k144evb-uart")]
mod uart_sensor {
    use core::sync::atomic::{AtomicU32, Ordering};

    use super::super::{SENSOR_UART_ALT, SENSOR_UART_CLOCK_HZ, SENSOR_UART_IRQ, SENSOR_UART_RX};
    use super::{fatal, map, mux};
    use crate::chip::s32k144::lpuart::{self, Lpuart};
    use crate::chip::s32k144::pcc::{Pcc, Peripheral, Source};
    use crate::chip::s32k144::port::Mux;
    use crate::cortex_m::Line;
    use crate::ring::{ByteRing, RingStats};
    use crate::slcan::ByteUart;

    /// The ring between LPUART0's receive interrupt and the sensor task: at 9600 baud at most
    /// 39 bytes arrive between two samples, 40 ms apart.
    static SENSOR_RING: ByteRing<64> = ByteRing::new();
    /// Bytes LPUART0 itself lost (its receiver overran before the interrupt read it).
    static SENSOR_UART_OVERRUNS: AtomicU32 = AtomicU32::new(0);

    /// The UART ranging module on LPUART0: receive only (the module's own RX pin selects its
    /// output mode and needs no data).
    pub struct SensorUart {
        _private: (),
    }

    impl SensorUart {
        /// LPUART0 on the oscillator clock at the module's 9600 baud, its receiver and receive
        /// interrupt on, PTB0 its RX; the interrupt stays masked in the NVIC until
        /// [`Self::enable_interrupt`]. A refused clock gate or baud rate is fatal.
        pub fn lpuart0() -> Self {
            let gated = Pcc::new(map::at(crate::chip::s32k144::pcc::BASE))
                .enable(Peripheral::Lpuart0, Some(Source::SoscDiv2));
            if gated.is_err() || !mux(SENSOR_UART_RX, Mux::Alt(SENSOR_UART_ALT)) {
                fatal("LPUART0 cannot be set up (PCC, PORT)");
            }
            let uart = Lpuart::new(map::at(lpuart::base::LPUART0));
            if uart
                .configure(SENSOR_UART_CLOCK_HZ, cw_core::sonar::uart::BAUD)
                .is_err()
            {
                fatal("LPUART0 cannot reach the sensor's baud rate");
            }
            Self { _private: () }
        }

        /// Enables the receive interrupt in the NVIC at OSEK ISR priority `osek_priority`.
        pub fn enable_interrupt(osek_priority: u8) {
            crate::cortex_m::enable_irq(Line(SENSOR_UART_IRQ), osek_priority);
        }

        /// The oldest byte received and not yet read.
        pub fn read_byte(&mut self) -> Option<u8> {
            SENSOR_RING.pop()
        }
    }

    /// What the sensor's UART counted since start-up: bytes received and dropped by the ring,
    /// and bytes LPUART0 lost before its interrupt read them.
    pub fn sensor_uart_stats() -> (RingStats, u32) {
        (
            SENSOR_RING.stats(),
            SENSOR_UART_OVERRUNS.load(Ordering::Relaxed),
        )
    }

    /// `SensorRxIsr` (OSEK category 1): every byte LPUART0 holds into the ring.
    pub(super) extern "C" fn lpuart0_rx() {
        let mut uart = Lpuart::new(map::at(lpuart::base::LPUART0));
        uart.clear_interrupts();
        while let Some(byte) = uart.read_byte() {
            SENSOR_RING.push(byte);
        }
        SENSOR_UART_OVERRUNS.fetch_add(uart.overruns(), Ordering::Relaxed);
    }
}

// ---- CAN ----------------------------------------------------------------------------

/// FlexCAN0 and its driver.
pub type EvbCan = Flexcan<Mmio>;

/// FlexCAN0 with `config`'s buffers (no register touched before `Can_Init`).
///
/// # Errors
/// [`LayoutError`] when the buffers cannot hold the configuration.
pub fn flexcan0(config: &FlexcanConfig<'_>) -> Result<EvbCan, LayoutError> {
    Flexcan::new(map::at(map::FLEXCAN0), config)
}

/// Enables FlexCAN0's interrupt lines ([`CAN_IRQS`]) at OSEK ISR priority
/// `osek_priority`.
pub fn enable_can_interrupts(osek_priority: u8) {
    for line in CAN_IRQS {
        crate::cortex_m::enable_irq(Line(line), osek_priority);
    }
}

// ---- the OS tick and the watchdog ---------------------------------------------------

/// Starts SysTick: one interrupt per millisecond, at OSEK ISR priority `osek_priority`.
pub fn start_tick(osek_priority: u8) {
    crate::cortex_m::start_systick(CORE_HZ / 1000 - 1, osek_priority);
}

/// The board's watchdog for WdgM (`cw_core::wdgm::WdgDriver`): WDOG, on the LPO. A new
/// timeout reconfigures it (allowed: start-up leaves `CS[UPDATE]` set), with every
/// interrupt masked for the unlock window's 128 bus clocks; a trigger is a refresh.
pub struct EvbWatchdog {
    timeout_ms: u16,
}

impl EvbWatchdog {
    /// The watchdog as start-up left it (at [`START_TIMEOUT`]).
    pub const fn new() -> Self {
        Self { timeout_ms: 0 }
    }

    fn chip() -> Wdog<Mmio> {
        Wdog::new(map::at(wdog::BASE))
    }
}

impl Default for EvbWatchdog {
    fn default() -> Self {
        Self::new()
    }
}

impl cw_core::wdgm::WdgDriver for EvbWatchdog {
    fn set_trigger_condition(&mut self, timeout_ms: u16) {
        let wdog = Self::chip();
        if timeout_ms != self.timeout_ms {
            let Some(timeout) = Timeout::from_ms(u32::from(timeout_ms)) else {
                fatal("a watchdog timeout WDOG cannot count");
            };
            if cortex_m::interrupt::free(|_| wdog.configure(timeout)).is_err() {
                fatal("the watchdog refused its new timeout");
            }
            self.timeout_ms = timeout_ms;
        }
        wdog.refresh();
    }

    fn off(&mut self) {
        if cortex_m::interrupt::free(|_| Self::chip().disable()).is_err() {
            fatal("the watchdog would not stop");
        }
        self.timeout_ms = 0;
    }
}

// ---- the log and the board's ends ---------------------------------------------------

// The log: defmt frames into an RTT buffer in RAM, which the debug probe reads while the
// core runs (`probe-rs run` decodes them with the ELF). With no probe attached the buffer
// fills and further frames are dropped: the ECU never waits for the log.
use defmt_rtt as _;

/// A fault the OS cannot go on from, already reported: the outputs' safe state (LEDs
/// dark), then a system reset (the ECU starts again, as its watchdog would make it).
pub fn halt() -> ! {
    cortex_m::interrupt::disable();
    leds_safe();
    crate::cortex_m::last_words(|| defmt::println!("RESET"));
    cortex_m::peripheral::SCB::sys_reset()
}

/// Logs a port fault with the outputs in their safe state: `FATAL: WHAT ITEM`.
pub fn report(fault: &PortFault) {
    leds_safe();
    crate::cortex_m::log_fault(fault);
}

/// A fatal error of the board or the application: LEDs to their safe state, the reason on
/// the log, then [`halt`].
pub fn fatal(what: &str) -> ! {
    leds_safe();
    crate::cortex_m::last_words(|| defmt::println!("FATAL: {=str}", what));
    halt()
}

// ---- the interrupt vector -----------------------------------------------------------

/// FlexCAN0's interrupt line `LINE`: the ECU's `CanIsr` (through the application).
extern "C" fn can0<const LINE: u16>() {
    if let Some(app) = app() {
        app.irq(LINE);
    }
}

extern "C" fn unused_irq() {
    fatal("an interrupt without a handler");
}

/// The external interrupt vector: FlexCAN0's lines ([`CAN_IRQS`]) are the ECU's
/// `CanIsr`, LPUART0's the UART sensor's `SensorRxIsr` (enabled only when that sensor is
/// used); no other line is enabled.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [extern "C" fn(); IRQ_LINES] = {
    let mut v: [extern "C" fn(); IRQ_LINES] = [unused_irq; IRQ_LINES];
    v[CAN_IRQS[0] as usize] = can0::<{ CAN_IRQS[0] }>;
    v[CAN_IRQS[1] as usize] = can0::<{ CAN_IRQS[1] }>;
    v[CAN_IRQS[2] as usize] = can0::<{ CAN_IRQS[2] }>;
    #[cfg(feature = "s32k144evb-uart")]
    {
        v[super::SENSOR_UART_IRQ as usize] = uart_sensor::lpuart0_rx;
    }
    v
};
