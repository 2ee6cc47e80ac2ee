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

use cw_bsp::cortex_m::CortexMPort;
use cw_bsp::mps2::{self, SensorUart, SlcanCan, SlcanEvent};
use cw_core::can::Hrh;

pub(crate) use crate::cortex_m::{isr_priority, report_supervision};

use crate::board::{Board, CanEvents, CanInterrupt, PortDriver, SerialRx};
use crate::config::{self, Kernel};
use crate::ecu::Ecu;

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

/// The end of `App::start_os` on this board: the CAN controller's interrupts, the sensor
/// UART's (if the sensor is the UART module), then StartOS (interrupts are off until its
/// kernel call ends).
pub(crate) fn start_os_with_devices<B: Board>(
    ecu: &Ecu<CortexMPort<Kernel>, B>,
    uart_sensor: bool,
) {
    mps2::enable_can_interrupts(isr_priority(config::os::CAN_ISR));
    if uart_sensor {
        SensorUart::enable_interrupt(isr_priority(config::os::SENSOR_RX_ISR));
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

/// `App::shut_down` on this board: [`crate::cortex_m::shutdown_report`] with the LEDs'
/// safe state.
pub(crate) fn shutdown_report<B: Board>(name: &str, ecu: &Ecu<CortexMPort<Kernel>, B>) -> bool {
    crate::cortex_m::shutdown_report(name, ecu, mps2::leds_safe)
}
