//! An OSEK/VDX OS 2.2.3 kernel (with the AUTOSAR OS scalability-class-1 additions) as a
//! state machine.
//!
//! This module decides *who runs*; making a task or an ISR run (stacks, context switches,
//! calling its body, masking interrupts) is the board's job. Every service below changes
//! the state and, at a rescheduling point, updates [`Os::running`]; the board compares that
//! with the task it was executing and switches, and applies [`Os::interrupt_mask`] to its
//! interrupt hardware ([`InterruptControl`]).
//!
//! # What is implemented
//! - Tasks ([`TaskConfig`]): priority 0 (lowest) ..= 63, basic or extended, fully or
//!   non-preemptive, multiple activation of basic tasks, autostart per application mode.
//!   `ActivateTask`, `TerminateTask`, `ChainTask`, `Schedule`, `GetTaskID`, `GetTaskState`.
//! - Events (extended tasks): `SetEvent`, `ClearEvent`, `GetEvent`, `WaitEvent`.
//! - Resources with the immediate priority ceiling protocol: `GetResource`,
//!   `ReleaseResource`, strictly LIFO, plus [`RES_SCHEDULER`]. Ceilings are derived from
//!   the configuration (the highest priority of the tasks and ISRs that declare the
//!   resource); a resource shared with an ISR has its ceiling at that ISR's level, so a task
//!   holding it masks the ISR.
//! - Counters and alarms: `SetRelAlarm`, `SetAbsAlarm`, `CancelAlarm`, `GetAlarm`,
//!   `GetAlarmBase`, cyclic and autostart alarms, the three actions (activate a task, set an
//!   event, an alarm callback), and the AUTOSAR `IncrementCounter`, `GetCounterValue`,
//!   `GetElapsedValue`.
//! - Interrupts as OS objects ([`IsrConfig`]): category 1 and 2, each above every task;
//!   ISRs nest by priority (a higher one interrupts a lower one, an equal or lower one
//!   stays pending: [`Os::enter_isr`] refuses it); rescheduling happens when the last ISR
//!   returns ([`Os::exit_isr`]). `GetISRID` (AUTOSAR), and `GetTaskID` in an ISR gives the
//!   interrupted task.
//! - Interrupt services: `DisableAllInterrupts`/`EnableAllInterrupts`,
//!   `SuspendAllInterrupts`/`ResumeAllInterrupts`, `SuspendOSInterrupts`/
//!   `ResumeOSInterrupts`, nestable as the standard says; while any is in force every other
//!   service returns `E_OS_DISABLEDINT`, and inside a `DisableAllInterrupts` section no
//!   suspend, inside a suspend section no `DisableAllInterrupts` is carried out (OSEK allows
//!   no service there).
//! - Hook routines ([`Hooks`]): StartupHook, ShutdownHook, PreTaskHook, PostTaskHook,
//!   ErrorHook (with `OSErrorGetServiceId` and the parameters), alarm callbacks.
//! - `StartOS(AppMode)` with application modes, `GetActiveApplicationMode`,
//!   `ShutdownOS(Error)`.
//! - Call levels ([`Context`], [`callevel::allowed`]): every service checks where it is
//!   called from.
//! - Standard and extended status ([`Status`]), conformance classes BCC1..ECC2
//!   ([`ConformanceClass`]), both checked at build time.
//!
//! # Scheduling rules (OSEK OS 2.2.3 §4.6)
//! - At task level, the running task is always a highest-priority ready task; a running
//!   task's priority is raised to the ceiling of the resources it holds (and, for a
//!   non-preemptive task, to the ceiling of [`RES_SCHEDULER`], which is how OSEK defines
//!   non-preemption).
//! - Within one priority, ready tasks are served first in, first out; every activation of
//!   a basic task is a separate entry in that order; a preempted task is the *oldest* of
//!   its priority (it goes to the head); a task released from waiting is the newest.
//! - A task of equal priority never preempts the running one.
//! - While an ISR, a hook or an interrupt lock is active, no task switch happens; the
//!   decision is taken when the last ISR returns, the lock is released or the hook ends.
//!
//! # Where OSEK and AUTOSAR differ ([`Dialect`], default OSEK)
//! - The interrupt services in hooks and alarm callbacks, and before `StartOS` and after
//!   `ShutdownOS`: OSEK allows only `Suspend/ResumeAllInterrupts` in alarm callbacks and in
//!   the error, pre- and post-task hooks and none in the start-up and shutdown hooks or
//!   outside the OS; AUTOSAR allows all six in every hook and callback, and the four
//!   all-interrupt services outside the OS (SWS_Os_00299).
//! - `SetRelAlarm` with increment 0: OSEK leaves it to the implementation, and here the
//!   alarm then expires after one full counter revolution (`maxallowedvalue + 1` ticks,
//!   as `SetAbsAlarm` at the current value does); AUTOSAR returns `E_OS_VALUE` in both
//!   statuses (SWS_Os_00304).
//!
//! # Where OSEK is silent or undefined (AUTOSAR's rule, in both dialects)
//! - A call from a context the call-level table does not allow returns `E_OS_CALLEVEL`
//!   (OSEK defines it for five services, the rest is "implementation specific").
//! - A call while interrupts are disabled or suspended returns `E_OS_DISABLEDINT`
//!   (SWS_Os_00093); an unpaired `Enable`/`Resume` is ignored (SWS_Os_00092).
//! - A task whose body returns without `TerminateTask`/`ChainTask` ([`Os::task_returned`]):
//!   interrupt locks undone, resources released, `ErrorHook(E_OS_MISSINGEND)`, then
//!   terminated (SWS_Os_00052, 00069, 00070, 00239).
//! - A category-2 ISR that returns with a lock or a resource: undone or released, and
//!   `ErrorHook(E_OS_DISABLEDINT)` / `ErrorHook(E_OS_RESOURCE)` (SWS_Os_00368, 00369).
//! - An alarm action that fails calls `ErrorHook` with the action's service
//!   (`ActivateTask`/`SetEvent`) and parameters; `IncrementCounter` itself returns `E_OK`
//!   (SWS_Os_00321).
//! - `ShutdownOS` does not call `PostTaskHook` (SWS_Os_00071).
//! - `SetAbsAlarm` with `start` equal to the current counter value expires after one full
//!   counter revolution, never immediately.
//! - Check order within a service where several errors apply: call level, then interrupt
//!   lock, then identifier, then access, then state/limit/resource.

pub mod call;
pub mod callevel;
mod config;
mod error;
mod hooks;
mod irq;
mod kernel;
mod queue;
pub mod rta;
pub mod spec;
pub mod steps;
pub mod timeline;

pub use call::{Returned, ServiceCall};
pub use callevel::Context;
pub use config::lock_free_bit;
pub use config::{
    AlarmAction, AlarmAutostart, AlarmConfig, ConfigError, ConformanceClass, CounterConfig,
    Dialect, HookSet, IsrCategory, IsrConfig, OsConfig, OsDescription, Preemption, Status,
    TaskConfig, TaskKind, ISR_LEVEL_BASE, LOCK_FREE_RESOURCES, MAX_APP_MODES, MAX_ISRS,
    MAX_ISR_PRIORITY, MAX_PRIORITY, MAX_RESOURCES, MAX_TASKS,
};
pub use error::{status_name, OsError, ServiceId, StatusType, E_OK};
pub use hooks::{Hooks, NoHooks};
pub use irq::{InterruptControl, InterruptMask, VirtualInterrupts};
pub use kernel::{AlarmBase, Locks, Os, Phase};

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

/// Identifies an ISR (AUTOSAR `ISRType`): its index in the configuration's ISR table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct IsrId(pub u8);

/// An application mode (`AppModeType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AppMode(pub u8);

/// The application mode every configuration has (mode 0).
pub const OSDEFAULTAPPMODE: AppMode = AppMode(0);

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
