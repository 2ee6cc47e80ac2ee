//! What this ECU needs from a board: the CAN controller, the two LED pins, the ultrasonic
//! sensor behind the I/O hardware abstraction, and time. Each board (the host simulation
//! first) implements [`Board`]; the ECU code above it is the same everywhere.

use cw_core::can::CanDriver;
use cw_core::os::TaskId;
use cw_core::sonar::Echo;
use embedded_hal::digital::OutputPin;

use crate::swc::LedColor;

/// A board the ECU runs on.
pub trait Board {
    /// The CAN controller driver.
    type Can: CanDriver;
    /// An LED output pin.
    type Led: OutputPin;

    /// The CAN controller.
    fn can(&mut self) -> &mut Self::Can;

    /// The LED pin of one colour (IoHwAb -> Dio).
    fn led(&mut self, color: LedColor) -> &mut Self::Led;

    /// IoHwAb: trigger the ultrasonic sensor and time its echo (Dio + Gpt).
    fn sonar_echo(&mut self) -> Echo;

    /// Milliseconds since start.
    fn now_ms(&self) -> u64;

    /// Called when a task starts executing (for timing measurements; default: nothing).
    fn task_started(&mut self, _task: TaskId) {}
}
