//! What this ECU needs from a board: the MCAL drivers the paper configures (§3.2.2:
//! Port, Dio, Gpt, Can) as embedded-hal 1.0 and `cw_core::can` traits. A board (the host
//! simulation, QEMU's mps2-an386) names their types in [`Board`] and hands the ECU one
//! [`BoardParts`]; everything above it, [`crate::iohwab`], the SWCs, the RTE and the BSW,
//! is the same on every board.
//!
//! The parts are split by who uses them, because tasks and ISRs preempt each other: the
//! CAN controller belongs to the Com stack (OSEK resource `RES_COM`), the LEDs to the LED
//! resource (`RES_LEDS`), the sensor's pins and timer to `OsSonarTask` alone.
//!
//! | AUTOSAR module | here |
//! |---|---|
//! | Port (`Port_Init`) | [`PortDriver::port_init`]: every pin to its direction and initial level |
//! | Dio (`Dio_WriteChannel`, `Dio_ReadChannel`) | [`Leds`], [`SonarIo::trigger`] (`OutputPin`), [`SonarIo::echo`] (`InputPin`) |
//! | Gpt (delays, the echo's duration) | [`SonarIo::delay`] (`DelayNs`), [`SonarIo::capture`] ([`PulseCapture`]) |
//! | Can | [`BoardParts::can`] ([`CanDriver`] and [`CanEvents`]) |
//!
//! The OS port (time base, interrupt controller, task switching) is the board's too:
//! `cw_bsp::port::Port`.

use cw_core::can::CanDriver;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};

/// A CAN controller event, taken by the ECU's CAN interrupt (`CanIsr`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CanInterrupt {
    /// The frame of this CanIf PDU handle was sent.
    TxConfirmation(u16),
    /// A frame arrived in this receive mailbox.
    Received(cw_core::can::Hrh, cw_core::can::CanFrame),
    /// The controller went bus-off.
    BusOff,
}

/// The CAN controller's interrupt sources, as `CanIsr` reads them.
pub trait CanEvents {
    /// The oldest event not yet taken (transmit confirmation, reception, bus-off).
    fn take_event(&mut self) -> Option<CanInterrupt>;
}

/// Gpt input capture: the duration of a pulse on the echo line, timed by the hardware
/// timer (AUTOSAR Icu signal measurement, `Icu_GetTimeElapsed`, on the Gpt time base).
pub trait PulseCapture {
    /// The high time, µs, of the first complete pulse on the echo line after the last
    /// trigger pulse, or `None` when no complete pulse came within `timeout_us` (or the
    /// sensor was not triggered).
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32>;
}

/// The AUTOSAR Port driver.
pub trait PortDriver {
    /// `Port_Init`: every pin to its configured direction and initial level (outputs
    /// low). Runs once, in EcuM start-up one, before any Dio access.
    fn port_init(&mut self);
}

/// A board the ECU runs on: the types of its MCAL drivers.
pub trait Board {
    /// The CAN controller driver.
    type Can: CanDriver + CanEvents;
    /// A warning LED's Dio channel (high = lit).
    type Led: OutputPin;
    /// The sensor's trigger line (a high pulse of at least 10 µs starts a measurement).
    type Trigger: OutputPin;
    /// The sensor's echo line (high while the echo is timed; idle low).
    type Echo: InputPin;
    /// The Gpt busy-wait delay.
    type Delay: DelayNs;
    /// The Gpt input capture on the echo line.
    type Capture: PulseCapture;
    /// The Port driver.
    type Port: PortDriver;
}

/// The two warning LEDs.
pub struct Leds<B: Board> {
    /// The red LED.
    pub red: B::Led,
    /// The yellow LED.
    pub yellow: B::Led,
}

/// The ultrasonic sensor's lines and timer.
pub struct SonarIo<B: Board> {
    /// The trigger line.
    pub trigger: B::Trigger,
    /// The echo line.
    pub echo: B::Echo,
    /// The Gpt delay (the trigger pulse's length).
    pub delay: B::Delay,
    /// The Gpt capture of the echo's width.
    pub capture: B::Capture,
}

/// Everything the ECU takes from a board.
pub struct BoardParts<B: Board> {
    /// The Port driver (used once, at start-up).
    pub port: B::Port,
    /// The CAN controller.
    pub can: B::Can,
    /// The LEDs.
    pub leds: Leds<B>,
    /// The sensor.
    pub sonar: SonarIo<B>,
}
