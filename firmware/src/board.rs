//! What this ECU needs from a board: the MCAL drivers the paper configures (§3.2.2:
//! Port, Dio, Gpt, Can) as embedded-hal 1.0 and `cw_core::can` traits. Each board (the host
//! simulation first) implements [`Board`]; everything above it, [`crate::iohwab`], the
//! SWCs, the RTE and the BSW, is the same on every board.
//!
//! | AUTOSAR module | here |
//! |---|---|
//! | Port (`Port_Init`) | [`Board::port_init`]: every pin to its direction and initial level |
//! | Dio (`Dio_WriteChannel`, `Dio_ReadChannel`) | [`Board::dio_out`] (`OutputPin`), [`Board::dio_in`] (`InputPin`) |
//! | Gpt (time base, delays, the echo's duration) | [`Board::now_ms`], [`Board::gpt_delay`] (`DelayNs`), [`Board::gpt_capture`] ([`PulseCapture`]) |
//! | Can | [`Board::can`] ([`CanDriver`]) |
//! | interrupt controller (OS port) | [`Board::irq`] ([`InterruptControl`]): the kernel's interrupt mask, applied after every kernel call |

use cw_core::can::CanDriver;
use cw_core::os::{InterruptControl, TaskId};
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};

/// The Dio output channels of this ECU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DioOut {
    /// The red warning LED (high = lit).
    RedLed,
    /// The yellow warning LED (high = lit).
    YellowLed,
    /// The ultrasonic sensor's trigger line (a high pulse of at least 10 µs starts a
    /// measurement).
    SonarTrigger,
}

/// The Dio input channels of this ECU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DioIn {
    /// The ultrasonic sensor's echo line (high while the echo is timed; idle low).
    SonarEcho,
}

/// Gpt input capture: the duration of a pulse on the echo line, timed by the hardware
/// timer (AUTOSAR Icu signal measurement, `Icu_GetTimeElapsed`, on the Gpt time base).
pub trait PulseCapture {
    /// The high time, µs, of the first complete pulse on the echo line after the last
    /// trigger pulse, or `None` when no complete pulse came within `timeout_us` (or the
    /// sensor was not triggered).
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32>;
}

/// A board the ECU runs on: its MCAL.
pub trait Board {
    /// The CAN controller driver.
    type Can: CanDriver;
    /// A Dio output channel.
    type Out: OutputPin;
    /// A Dio input channel.
    type In: InputPin;
    /// The Gpt busy-wait delay.
    type Delay: DelayNs;
    /// The Gpt input capture on the echo line.
    type Capture: PulseCapture;
    /// The interrupt controller, as the OS drives it.
    type Irq: InterruptControl;

    /// `Port_Init`: every pin to its configured direction and initial level (outputs low).
    /// Runs once, in EcuM start-up one, before any Dio access.
    fn port_init(&mut self);

    /// The CAN controller.
    fn can(&mut self) -> &mut Self::Can;

    /// A Dio output channel.
    fn dio_out(&mut self, channel: DioOut) -> &mut Self::Out;

    /// A Dio input channel.
    fn dio_in(&mut self, channel: DioIn) -> &mut Self::In;

    /// The Gpt delay.
    fn gpt_delay(&mut self) -> &mut Self::Delay;

    /// The Gpt input capture.
    fn gpt_capture(&mut self) -> &mut Self::Capture;

    /// The interrupt controller: the ECU applies the kernel's interrupt mask to it after
    /// every kernel call that can change it.
    fn irq(&mut self) -> &mut Self::Irq;

    /// Milliseconds since start (the Gpt time base).
    fn now_ms(&self) -> u64;

    /// Called when a task starts executing (for timing measurements; default: nothing).
    fn task_started(&mut self, _task: TaskId) {}
}
