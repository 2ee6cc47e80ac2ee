//! OSEK/VDX OS 2.2.3 scheduler state machine.
//!
//! This module decides *who runs*; making a task run (stacks, context switches, calling
//! its body) is the board's job. Every service below changes the state and, at a
//! rescheduling point, updates [`Os::running`]; the board compares that with the task it
//! was executing and switches.
//!
//! # What is implemented
//! - Static tasks ([`TaskConfig`]): priority 0 (lowest) ..= 63, basic or extended,
//!   fully or non-preemptive, multiple activation of basic tasks (BCC2/ECC2), autostart.
//! - Task services: `ActivateTask`, `TerminateTask`, `ChainTask`, `Schedule`, `GetTaskID`,
//!   `GetTaskState`.
//! - Events (extended tasks): `SetEvent`, `ClearEvent`, `GetEvent`, `WaitEvent`.
//! - Resources with the immediate priority ceiling protocol: `GetResource`,
//!   `ReleaseResource`, strictly LIFO, plus [`RES_SCHEDULER`]. Ceilings are derived from the
//!   configuration (the highest priority of the tasks that declare the resource), never
//!   written by hand.
//! - Counters and alarms: `SetRelAlarm`, `SetAbsAlarm`, `CancelAlarm`, `GetAlarm`,
//!   `GetAlarmBase`, cyclic alarms, autostart alarms, the three alarm actions (activate a
//!   task, set an event, a callback), and `IncrementCounter` to drive a counter.
//! - Category-2 interrupt level ([`Os::enter_isr`] / [`Os::exit_isr`]): services called
//!   there defer rescheduling to the exit of the outermost ISR.
//! - The extended-status error codes ([`OsError`]) on exactly the conditions the standard
//!   lists for each service.
//!
//! # Scheduling rules (OSEK OS 2.2.3 §4.6)
//! - The running task is always a highest-priority ready task; a running task's priority
//!   is raised to the ceiling of the resources it holds (and, for a non-preemptive task,
//!   to the ceiling of [`RES_SCHEDULER`], which is how OSEK defines non-preemption).
//! - Within one priority, ready tasks are served first in, first out; every activation of
//!   a basic task is a separate entry in that order; a preempted task is the *oldest* of
//!   its priority (it goes to the head); a task released from waiting is the newest.
//! - A task of equal priority never preempts the running one.
//!
//! # Choices where OSEK and AUTOSAR OS differ, or OSEK is silent
//! - `SetRelAlarm` with increment 0 returns `E_OS_VALUE` (AUTOSAR SWS_Os_00304); OSEK
//!   leaves it open.
//! - `SetAbsAlarm` with `start` equal to the current counter value expires after one full
//!   counter revolution (`maxallowedvalue + 1` ticks), never immediately.
//! - Services called with no task running and outside any ISR (start-up code, idle) are
//!   treated as interrupt level: `TerminateTask`, `ChainTask`, `Schedule`, `WaitEvent` and
//!   `ClearEvent` return `E_OS_CALLEVEL` there.
//! - Interrupt service routines do not take task resources: their priority lies above every
//!   task-derived ceiling, so `GetResource`/`ReleaseResource` at interrupt level return
//!   `E_OS_ACCESS`, as the standard's ceiling rule requires.
//! - Check order within a service where several errors apply: call level, then identifier,
//!   then access, then state/limit/resource (AUTOSAR's order).
//! - Errors raised by alarm actions (e.g. activating a task at its limit) cannot be returned
//!   to anyone; they are counted in the [`TickReport`] of the tick that caused them.

mod config;
mod error;
mod kernel;
mod queue;
pub mod spec;

pub use config::{
    AlarmAction, AlarmAutostart, AlarmConfig, ConfigError, CounterConfig, OsConfig, Preemption,
    TaskConfig, TaskKind, MAX_PRIORITY, MAX_RESOURCES, MAX_TASKS,
};
pub use error::OsError;
pub use kernel::{AlarmBase, Os, TickReport};

/// Identifies a task: its index in the configuration's task table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TaskId(pub u8);

/// Identifies a resource: its index in the configuration's resource table, or
/// [`RES_SCHEDULER`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ResourceId(pub u8);

/// Identifies a counter: its index in the configuration's counter table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CounterId(pub u8);

/// Identifies an alarm: its index in the configuration's alarm table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AlarmId(pub u8);

/// The resource every task may take to lock out all other tasks (OSEK `RES_SCHEDULER`).
pub const RES_SCHEDULER: ResourceId = ResourceId(0xFF);

/// A set of events of an extended task, one bit each.
pub type EventMask = u32;

/// Counter ticks (OSEK `TickType`).
pub type TickType = u32;

/// OSEK task states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TaskState {
    /// Not activated.
    Suspended,
    /// Activated (or preempted, or released from waiting) and waiting for the processor.
    Ready,
    /// Executing.
    Running,
    /// An extended task blocked in `WaitEvent`.
    Waiting,
}

#[cfg(test)]
mod tests;
