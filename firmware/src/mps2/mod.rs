//! The ECU on QEMU's mps2-an386 (Cortex-M4): what every image on this board needs (the
//! board's CAN controller and sensor UART named for the ECU's [`Board`], the Port driver,
//! the ISRs' lines and priorities, the end-of-run and WdgM reports, the const check of the
//! configuration against the port), the production image's board and entry points
//! ([`production`]), and the measuring image's ([`measuring`], feature `scenario`).

#[cfg(feature = "scenario")]
pub mod measuring;
pub mod production;

#[cfg(feature = "scenario")]
pub use measuring::{
    load, ImageScenario, ModeLine, Mps2App, Mps2Board, Mps2Ecu, Mps2Sensor, ScenarioEcho,
    ScenarioInput, Start, FIGURE7, IMAGE_CAPACITY, SCENARIO_FILE_MAX,
};
pub use production::{Mps2FlashApp, Mps2FlashBoard, TiedOn};

use cw_bsp::cortex_m::{now_ms, CortexMPort};
use cw_bsp::mps2::{self, SensorUart, SlcanCan, SlcanEvent};
use cw_core::can::Hrh;
use cw_core::os::{status_name, E_OK};

use crate::board::{Board, CanEvents, CanInterrupt, PortDriver, SerialRx};
use crate::config::{self, Kernel};
use crate::ecu::Ecu;

// The ECU's configuration fits the Cortex-M port (task count, ISR priorities the NVIC
// tells apart): checked when the image is built; a refusal names the task or ISR.
const _: () = cw_bsp::port::preempt::assert_fits(
    config::OS.tasks(),
    config::OS.isrs(),
    cw_bsp::cortex_m::ISR_PRIORITIES,
);

impl SerialRx for SensorUart {
    fn read_byte(&mut self) -> Option<u8> {
        SensorUart::read_byte(self)
    }
}

impl CanEvents for SlcanCan {
    fn take_event(&mut self) -> Option<CanInterrupt> {
        SlcanCan::take_event(self).map(|event| match event {
            SlcanEvent::TxConfirmation(pdu) => CanInterrupt::TxConfirmation(pdu),
            // The UART is one receive mailbox; CanIf filters by id.
            SlcanEvent::Received(frame) => CanInterrupt::Received(Hrh(0), frame),
            SlcanEvent::BusOff => CanInterrupt::BusOff,
            SlcanEvent::ModeIndication(mode) => CanInterrupt::ModeIndication(mode),
        })
    }
}

/// The Port driver: the LED outputs low.
pub struct Mps2PortDriver;

impl PortDriver for Mps2PortDriver {
    fn port_init(&mut self) {
        mps2::leds_safe();
    }
}

/// The OSEK priority of ISR `isr` in the configuration.
pub(crate) fn isr_priority(isr: cw_core::os::IsrId) -> u8 {
    config::OS
        .isrs()
        .get(usize::from(isr.0))
        .map_or(1, |c| c.priority)
}

/// The end of `App::start_os` on this board: the CAN controller's interrupts, the sensor
/// UART's (if the sensor is the UART module), then StartOS (interrupts are off until its
/// kernel call ends).
pub(crate) fn start_os_with_devices<B: Board>(
    ecu: &Ecu<CortexMPort<Kernel>, B>,
    uart_sensor: bool,
) {
    mps2::enable_can_interrupts(isr_priority(config::CAN_ISR));
    if uart_sensor {
        SensorUart::enable_interrupt(isr_priority(config::SENSOR_RX_ISR));
    }
    ecu.start_os();
}

/// External interrupt `line`: UART0's RX and TX are the CAN controller (`CanIsr`); the
/// ECU uses no other line through the port.
pub(crate) fn board_irq<B: Board>(ecu: &Ecu<CortexMPort<Kernel>, B>, line: u16) {
    match line {
        0 | 1 => ecu.can_isr(),
        _ => mps2::fatal("an interrupt line the ECU does not use"),
    }
}

/// Logs WdgM's failure once, from the idle loop (no job under way): which task's alive
/// supervision failed, when, and that the watchdog is no longer triggered.
pub(crate) fn report_supervision<B: Board>(name: &str, ecu: &Ecu<CortexMPort<Kernel>, B>) {
    static REPORTED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);
    if REPORTED.load(core::sync::atomic::Ordering::Relaxed) {
        return;
    }
    if let Some((_, Some(f))) = ecu.supervision() {
        REPORTED.store(true, core::sync::atomic::Ordering::Relaxed);
        defmt::println!(
            "{=str}: WdgM: the alive supervision of {=str} failed at {} ms ({} of {} alive indications): LEDs dark, the watchdog no longer triggered",
            name,
            f.name,
            u64::from(f.main_function) * u64::from(config::BSW_PERIOD_MS),
            f.counted,
            f.expected
        );
    }
}

/// `App::shut_down` on this board: the LEDs' safe state (whatever shut the OS down; EcuM's
/// post-run has set it already on a normal shutdown) and the log line `NAME: ShutdownOS at
/// MS ms: ShutdownHook saw STATUS`. Returns whether the status was `E_OK`.
pub(crate) fn shutdown_report<B: Board>(name: &str, ecu: &Ecu<CortexMPort<Kernel>, B>) -> bool {
    mps2::leds_safe();
    let status = ecu.hooks().shutdown.unwrap_or(E_OK);
    defmt::println!(
        "{=str}: ShutdownOS at {} ms: ShutdownHook saw {}; no task or interrupt runs from here on",
        name,
        now_ms(),
        status_name(status).unwrap_or("an application's code")
    );
    status == E_OK
}
