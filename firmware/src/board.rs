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
//! | Dio (`Dio_WriteChannel`, `Dio_ReadChannel`) | [`Leds`], [`EchoSensor::trigger`] (`OutputPin`), [`EchoSensor::echo`], [`ModeInputs`] (`InputPin`) |
//! | Gpt (delays, the echo's duration) | [`EchoSensor::delay`] (`DelayNs`), [`EchoSensor::capture`] ([`PulseCapture`]) |
//! | Can | [`BoardParts::can`] ([`CanDriver`] and [`CanEvents`]) |
//! | a UART receiver (no AUTOSAR driver names it) | [`SerialSensor::rx`] ([`SerialRx`]) |
//!
//! The OS port (time base, interrupt controller, task switching) is the board's too:
//! `cw_bsp::port::Port`.

use cw_core::can::CanDriver;
use cw_core::os::TaskId;
use cw_core::sonar::uart::Ranger;
use cw_core::sonar::SonarConfig;
use cw_core::warning::Measurement;
use cw_core::wdgm::WdgDriver;
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
    /// The controller reached a mode it could not reach when asked
    /// (`CanIf_ControllerModeIndication`).
    ModeIndication(cw_core::can::ControllerMode),
}

impl From<cw_bsp::chip::flexcan::FlexcanEvent> for CanInterrupt {
    fn from(event: cw_bsp::chip::flexcan::FlexcanEvent) -> Self {
        use cw_bsp::chip::flexcan::FlexcanEvent;
        match event {
            FlexcanEvent::TxConfirmation(pdu) => Self::TxConfirmation(pdu),
            FlexcanEvent::Received(hrh, frame) => Self::Received(hrh, frame),
            FlexcanEvent::BusOff => Self::BusOff,
            FlexcanEvent::ModeIndication(mode) => Self::ModeIndication(mode),
        }
    }
}

/// The CAN controller's interrupt sources, as `CanIsr` reads them.
pub trait CanEvents {
    /// The oldest event not yet taken (transmit confirmation, reception, bus-off, mode
    /// indication).
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

/// A UART's receiver: the bytes that arrived since the last call, oldest first (the
/// board's interrupt takes them off the UART into a buffer).
pub trait SerialRx {
    /// The oldest byte not yet read, if any.
    fn read_byte(&mut self) -> Option<u8>;
}

/// The distance sensor as IoHwAb samples it: once per `OsSonarTask` job.
pub trait DistanceSensor {
    /// One sample with the ECU's sensor parameters: a distance, nothing in range, or
    /// invalid. Never an error: a sensor that cannot be read is an invalid sample, which
    /// UltraSonic holds over or reports.
    fn sample(&mut self, config: &SonarConfig) -> Measurement;
}

/// A board the ECU runs on: the types of its MCAL drivers.
pub trait Board {
    /// The CAN controller driver.
    type Can: CanDriver + CanEvents;
    /// A warning LED's Dio channel (high = lit).
    type Led: OutputPin;
    /// The ultrasonic sensor.
    type Sensor: DistanceSensor;
    /// A mode input's Dio channel (high = on).
    type ModeInput: InputPin;
    /// The Port driver.
    type Port: PortDriver;
    /// The watchdog driver (AUTOSAR Wdg) that WdgM triggers.
    type Watchdog: WdgDriver;
    /// Faults a test board injects into the tasks (a scenario's `stall`); [`NoFaults`]
    /// on a vehicle's board.
    type Faults: TaskFaults;
}

/// Faults a test board injects into the tasks.
pub trait TaskFaults {
    /// Whether this board injects faults at all (`false`: the ECU does not even ask
    /// [`TaskFaults::hangs`] at each job's start).
    const INJECTS: bool = true;
    /// Whether the job of `task` that starts now hangs at its first line; `now_ms` reads
    /// the time, which a board asks for only where a fault names `task` (a job start
    /// pays for the clock only when it may hang).
    fn hangs(&self, task: TaskId, now_ms: impl FnOnce() -> u64) -> bool;
}

/// A board that injects no fault.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoFaults;

impl TaskFaults for NoFaults {
    const INJECTS: bool = false;
    #[inline(always)]
    fn hangs(&self, _task: TaskId, _now_ms: impl FnOnce() -> u64) -> bool {
        false
    }
}

/// A scenario's `stall` lines, their tasks found by name in the OS configuration:
/// from each time on, that task's jobs hang.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stalls<const N: usize> {
    stalls: [(u64, TaskId); N],
    len: usize,
}

impl<const N: usize> Stalls<N> {
    /// The stalls of `scenario`, its task names found in `tasks` (the OS configuration's).
    ///
    /// # Errors
    /// The first name that is no task of `tasks`.
    pub fn of<const M: usize>(
        scenario: &cw_core::scenario::Scenario<M>,
        tasks: &[cw_core::os::TaskConfig],
    ) -> Result<Self, cw_core::scenario::TaskName> {
        let mut stalls = Self {
            stalls: [(0, TaskId(0)); N],
            len: 0,
        };
        for (at, name) in &scenario.stalls {
            let task = tasks
                .iter()
                .position(|t| t.name == name.as_str())
                .ok_or(*name)?;
            if let Some(slot) = stalls.stalls.get_mut(stalls.len) {
                *slot = (u64::from(*at), TaskId(task as u8));
                stalls.len += 1;
            }
        }
        Ok(stalls)
    }
}

impl<const N: usize> TaskFaults for Stalls<N> {
    #[inline(always)]
    fn hangs(&self, task: TaskId, now_ms: impl FnOnce() -> u64) -> bool {
        // A scenario without stalls (the common case) pays one test at a job's start.
        if self.len == 0 {
            return false;
        }
        self.first_stall(task).is_some_and(|from| now_ms() >= from)
    }
}

impl<const N: usize> Stalls<N> {
    /// When the first stall of `task` begins, if a stall names it.
    #[inline(never)]
    fn first_stall(&self, task: TaskId) -> Option<u64> {
        self.stalls
            .iter()
            .take(self.len)
            .filter(|&&(_, t)| t == task)
            .map(|&(at, _)| at)
            .min()
    }
}

/// A mode input the board ties on (a board without an ignition or bus-enable line:
/// ignition on, communication enabled; a vehicle's ECU reads pins).
pub struct TiedOn;

impl embedded_hal::digital::ErrorType for TiedOn {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::InputPin for TiedOn {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        Ok(true)
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        Ok(false)
    }
}

/// The two warning LEDs.
pub struct Leds<B: Board> {
    /// The red LED.
    pub red: B::Led,
    /// The yellow LED.
    pub yellow: B::Led,
}

/// The mode inputs the ModeManager SWC reads every 10 ms (Dio input channels, high =
/// on).
pub struct ModeInputs<B: Board> {
    /// Ignition (terminal 15): low asks the ECU to run down and shut off.
    pub ignition: B::ModeInput,
    /// Communication enable: low asks the ECU to stop transmitting while it keeps working
    /// (a diagnostic communication control, or the network released).
    pub com_enable: B::ModeInput,
}

/// An HC-SR04-class sensor (the paper's): a trigger line, an echo line, a Gpt delay and
/// the Gpt capture of the echo's width (sampled by [`crate::iohwab::measure_echo`]).
pub struct EchoSensor<T, E, D, C> {
    /// The trigger line (a high pulse of at least 10 µs starts a measurement).
    pub trigger: T,
    /// The echo line (high while the echo is timed; idle low).
    pub echo: E,
    /// The Gpt busy-wait delay (the trigger pulse's length).
    pub delay: D,
    /// The Gpt capture of the echo's width.
    pub capture: C,
}

/// A UART ranging module (A02YYUW, JSN-SR04T in UART mode: `cw_core::sonar::uart`) on a
/// UART receiver: each sample takes the bytes received since the last one.
pub struct SerialSensor<R> {
    /// The UART receiver the module sends to.
    pub rx: R,
    /// The frame decoder and the sample rules.
    pub ranger: Ranger,
}

impl<R: SerialRx> SerialSensor<R> {
    /// The module on `rx`, silent after `silent_after_samples` samples without a good
    /// frame.
    pub const fn new(rx: R, silent_after_samples: u8) -> Self {
        Self {
            rx,
            ranger: Ranger::new(silent_after_samples),
        }
    }
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
    pub sonar: B::Sensor,
    /// The mode inputs.
    pub modes: ModeInputs<B>,
    /// The watchdog (started by `Ecu::init`).
    pub watchdog: B::Watchdog,
    /// The faults the board injects.
    pub faults: B::Faults,
}

#[cfg(test)]
mod tests {
    use core::cell::Cell;

    use super::{Stalls, TaskFaults};
    use cw_core::os::TaskId;

    #[test]
    fn a_stall_hangs_its_task_from_its_time_on_and_reads_the_clock_only_for_it() {
        let stalls = Stalls::<4> {
            stalls: [
                (100, TaskId(2)),
                (50, TaskId(2)),
                (0, TaskId(0)),
                (0, TaskId(0)),
            ],
            len: 2,
        };
        let reads = Cell::new(0);
        let reads = &reads;
        let at = |now: u64| {
            move || {
                reads.set(reads.get() + 1);
                now
            }
        };
        // A task no stall names: no hang, and no clock read (the slots past `len` are not
        // stalls, task 0's among them).
        assert!(!stalls.hangs(TaskId(0), at(1_000)));
        assert!(!stalls.hangs(TaskId(1), at(1_000)));
        assert_eq!(reads.get(), 0);
        // Task 2: from the earlier of its two stalls on.
        assert!(!stalls.hangs(TaskId(2), at(49)));
        assert!(stalls.hangs(TaskId(2), at(50)));
        assert!(stalls.hangs(TaskId(2), at(100)));
        assert_eq!(reads.get(), 3, "one read per start of a task a stall names");
    }
}
