//! Service calls as values: what `ErrorHook` reads about the failed call
//! (`OSErrorGetServiceId` and the `OSError_<Service>_<Param>` parameters), and one entry
//! point, [`perform`], that carries out any call on a kernel. The model checker, the fuzz
//! targets and the conformance tests drive the kernel through it.

use super::error::{ServiceId, StatusType};
use super::{
    AlarmBase, AlarmId, AppMode, CounterId, EventMask, Hooks, IsrId, Os, OsConfig, OsError,
    ResourceId, TaskId, TaskState, TickType,
};
use crate::tables::Tables;

/// One OS service call with its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ServiceCall {
    /// `ActivateTask(TaskID)`.
    ActivateTask(TaskId),
    /// `TerminateTask()`.
    TerminateTask,
    /// `ChainTask(TaskID)`.
    ChainTask(TaskId),
    /// `Schedule()`.
    Schedule,
    /// `GetTaskID(&TaskID)`.
    GetTaskId,
    /// `GetTaskState(TaskID, &State)`.
    GetTaskState(TaskId),
    /// `DisableAllInterrupts()`.
    DisableAllInterrupts,
    /// `EnableAllInterrupts()`.
    EnableAllInterrupts,
    /// `SuspendAllInterrupts()`.
    SuspendAllInterrupts,
    /// `ResumeAllInterrupts()`.
    ResumeAllInterrupts,
    /// `SuspendOSInterrupts()`.
    SuspendOsInterrupts,
    /// `ResumeOSInterrupts()`.
    ResumeOsInterrupts,
    /// `GetResource(ResID)`.
    GetResource(ResourceId),
    /// `ReleaseResource(ResID)`.
    ReleaseResource(ResourceId),
    /// `SetEvent(TaskID, Mask)`.
    SetEvent(TaskId, EventMask),
    /// `ClearEvent(Mask)`.
    ClearEvent(EventMask),
    /// `GetEvent(TaskID, &Event)`.
    GetEvent(TaskId),
    /// `WaitEvent(Mask)`.
    WaitEvent(EventMask),
    /// `GetAlarmBase(AlarmID, &Info)`.
    GetAlarmBase(AlarmId),
    /// `GetAlarm(AlarmID, &Tick)`.
    GetAlarm(AlarmId),
    /// `SetRelAlarm(AlarmID, increment, cycle)`.
    SetRelAlarm {
        /// `AlarmID`.
        alarm: AlarmId,
        /// `increment`.
        increment: TickType,
        /// `cycle`.
        cycle: TickType,
    },
    /// `SetAbsAlarm(AlarmID, start, cycle)`.
    SetAbsAlarm {
        /// `AlarmID`.
        alarm: AlarmId,
        /// `start`.
        start: TickType,
        /// `cycle`.
        cycle: TickType,
    },
    /// `CancelAlarm(AlarmID)`.
    CancelAlarm(AlarmId),
    /// `GetActiveApplicationMode()`.
    GetActiveApplicationMode,
    /// `StartOS(Mode)`.
    StartOs(AppMode),
    /// `ShutdownOS(Error)`.
    ShutdownOs(StatusType),
    /// `GetISRID()`.
    GetIsrId,
    /// `IncrementCounter(CounterID)`.
    IncrementCounter(CounterId),
    /// `GetCounterValue(CounterID, &Value)`.
    GetCounterValue(CounterId),
    /// `GetElapsedValue(CounterID, &Value, &ElapsedValue)` with the previous `Value`.
    GetElapsedValue(CounterId, TickType),
    /// Not a call: the task's body returned without ending itself.
    TaskMissingEnd(TaskId),
    /// Not a call: the category-2 ISR returned holding a resource or a lock.
    IsrMissingEnd(IsrId),
    /// Not a call: a hook or alarm callback returned with interrupts suspended.
    HookMissingEnd,
}

impl ServiceCall {
    /// The service's identifier (`OSErrorGetServiceId`).
    pub const fn id(self) -> ServiceId {
        match self {
            Self::ActivateTask(_) => ServiceId::ActivateTask,
            Self::TerminateTask => ServiceId::TerminateTask,
            Self::ChainTask(_) => ServiceId::ChainTask,
            Self::Schedule => ServiceId::Schedule,
            Self::GetTaskId => ServiceId::GetTaskId,
            Self::GetTaskState(_) => ServiceId::GetTaskState,
            Self::DisableAllInterrupts => ServiceId::DisableAllInterrupts,
            Self::EnableAllInterrupts => ServiceId::EnableAllInterrupts,
            Self::SuspendAllInterrupts => ServiceId::SuspendAllInterrupts,
            Self::ResumeAllInterrupts => ServiceId::ResumeAllInterrupts,
            Self::SuspendOsInterrupts => ServiceId::SuspendOsInterrupts,
            Self::ResumeOsInterrupts => ServiceId::ResumeOsInterrupts,
            Self::GetResource(_) => ServiceId::GetResource,
            Self::ReleaseResource(_) => ServiceId::ReleaseResource,
            Self::SetEvent(..) => ServiceId::SetEvent,
            Self::ClearEvent(_) => ServiceId::ClearEvent,
            Self::GetEvent(_) => ServiceId::GetEvent,
            Self::WaitEvent(_) => ServiceId::WaitEvent,
            Self::GetAlarmBase(_) => ServiceId::GetAlarmBase,
            Self::GetAlarm(_) => ServiceId::GetAlarm,
            Self::SetRelAlarm { .. } => ServiceId::SetRelAlarm,
            Self::SetAbsAlarm { .. } => ServiceId::SetAbsAlarm,
            Self::CancelAlarm(_) => ServiceId::CancelAlarm,
            Self::GetActiveApplicationMode => ServiceId::GetActiveApplicationMode,
            Self::StartOs(_) => ServiceId::StartOs,
            Self::ShutdownOs(_) => ServiceId::ShutdownOs,
            Self::GetIsrId => ServiceId::GetIsrId,
            Self::IncrementCounter(_) => ServiceId::IncrementCounter,
            Self::GetCounterValue(_) => ServiceId::GetCounterValue,
            Self::GetElapsedValue(..) => ServiceId::GetElapsedValue,
            Self::TaskMissingEnd(_) => ServiceId::TaskMissingEnd,
            Self::IsrMissingEnd(_) => ServiceId::IsrMissingEnd,
            Self::HookMissingEnd => ServiceId::HookMissingEnd,
        }
    }

    /// The task parameter (`OSError_ActivateTask_TaskID`, `OSError_ChainTask_TaskID`,
    /// `OSError_GetTaskState_TaskID`, `OSError_SetEvent_TaskID`, `OSError_GetEvent_TaskID`).
    pub const fn task(self) -> Option<TaskId> {
        match self {
            Self::ActivateTask(t)
            | Self::ChainTask(t)
            | Self::GetTaskState(t)
            | Self::SetEvent(t, _)
            | Self::GetEvent(t)
            | Self::TaskMissingEnd(t) => Some(t),
            _ => None,
        }
    }

    /// The resource parameter (`OSError_GetResource_ResID`, `OSError_ReleaseResource_ResID`).
    pub const fn resource(self) -> Option<ResourceId> {
        match self {
            Self::GetResource(r) | Self::ReleaseResource(r) => Some(r),
            _ => None,
        }
    }

    /// The alarm parameter (`OSError_<Service>_AlarmID`).
    pub const fn alarm(self) -> Option<AlarmId> {
        match self {
            Self::GetAlarmBase(a)
            | Self::GetAlarm(a)
            | Self::CancelAlarm(a)
            | Self::SetRelAlarm { alarm: a, .. }
            | Self::SetAbsAlarm { alarm: a, .. } => Some(a),
            _ => None,
        }
    }

    /// The event mask parameter (`OSError_SetEvent_Mask`, `OSError_ClearEvent_Mask`,
    /// `OSError_WaitEvent_Mask`).
    pub const fn mask(self) -> Option<EventMask> {
        match self {
            Self::SetEvent(_, m) | Self::ClearEvent(m) | Self::WaitEvent(m) => Some(m),
            _ => None,
        }
    }

    /// The counter parameter (`OSError_IncrementCounter_CounterID`, ...).
    pub const fn counter(self) -> Option<CounterId> {
        match self {
            Self::IncrementCounter(c) | Self::GetCounterValue(c) | Self::GetElapsedValue(c, _) => {
                Some(c)
            }
            _ => None,
        }
    }
}

/// What a call returned besides its status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Returned {
    /// Nothing (the service has only a status).
    Nothing,
    /// `GetTaskID`: the task, or `INVALID_TASK`.
    Task(Option<TaskId>),
    /// `GetTaskState`.
    State(TaskState),
    /// `GetEvent`.
    Events(EventMask),
    /// `GetAlarmBase`.
    Base(AlarmBase),
    /// `GetAlarm` (ticks left), `GetCounterValue` (the value).
    Ticks(TickType),
    /// `GetActiveApplicationMode`.
    Mode(AppMode),
    /// `GetISRID`: the ISR, or `INVALID_ISR`.
    Isr(Option<IsrId>),
    /// `GetElapsedValue`: the new value and the ticks elapsed since the previous one.
    Elapsed {
        /// The counter's value now.
        value: TickType,
        /// Ticks since the value passed in.
        elapsed: TickType,
    },
}

/// Carries out `call` on `os` as the code running now would call it.
///
/// # Errors
/// The service's status.
pub fn perform<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    os: &mut Os<T, R, C, A, I, Q, K, H>,
    call: ServiceCall,
) -> Result<Returned, OsError>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let none = |r: Result<(), OsError>| r.map(|()| Returned::Nothing);
    match call {
        ServiceCall::ActivateTask(t) => none(os.activate_task(t)),
        ServiceCall::TerminateTask => none(os.terminate_task()),
        ServiceCall::ChainTask(t) => none(os.chain_task(t)),
        ServiceCall::Schedule => none(os.schedule()),
        ServiceCall::GetTaskId => os.get_task_id().map(Returned::Task),
        ServiceCall::GetTaskState(t) => os.get_task_state(t).map(Returned::State),
        ServiceCall::DisableAllInterrupts => none(os.disable_all_interrupts()),
        ServiceCall::EnableAllInterrupts => none(os.enable_all_interrupts()),
        ServiceCall::SuspendAllInterrupts => none(os.suspend_all_interrupts()),
        ServiceCall::ResumeAllInterrupts => none(os.resume_all_interrupts()),
        ServiceCall::SuspendOsInterrupts => none(os.suspend_os_interrupts()),
        ServiceCall::ResumeOsInterrupts => none(os.resume_os_interrupts()),
        ServiceCall::GetResource(r) => none(os.get_resource(r)),
        ServiceCall::ReleaseResource(r) => none(os.release_resource(r)),
        ServiceCall::SetEvent(t, m) => none(os.set_event(t, m)),
        ServiceCall::ClearEvent(m) => none(os.clear_event(m)),
        ServiceCall::GetEvent(t) => os.get_event(t).map(Returned::Events),
        ServiceCall::WaitEvent(m) => none(os.wait_event(m)),
        ServiceCall::GetAlarmBase(a) => os.get_alarm_base(a).map(Returned::Base),
        ServiceCall::GetAlarm(a) => os.get_alarm(a).map(Returned::Ticks),
        ServiceCall::SetRelAlarm {
            alarm,
            increment,
            cycle,
        } => none(os.set_rel_alarm(alarm, increment, cycle)),
        ServiceCall::SetAbsAlarm {
            alarm,
            start,
            cycle,
        } => none(os.set_abs_alarm(alarm, start, cycle)),
        ServiceCall::CancelAlarm(a) => none(os.cancel_alarm(a)),
        ServiceCall::GetActiveApplicationMode => {
            os.get_active_application_mode().map(Returned::Mode)
        }
        ServiceCall::StartOs(mode) => none(os.start_os(mode)),
        ServiceCall::ShutdownOs(error) => none(os.shutdown_os(error)),
        ServiceCall::GetIsrId => os.get_isr_id().map(Returned::Isr),
        ServiceCall::IncrementCounter(c) => none(os.increment_counter(c)),
        ServiceCall::GetCounterValue(c) => os.get_counter_value(c).map(Returned::Ticks),
        ServiceCall::GetElapsedValue(c, previous) => os
            .get_elapsed_value(c, previous)
            .map(|(value, elapsed)| Returned::Elapsed { value, elapsed }),
        ServiceCall::TaskMissingEnd(_) => none(os.task_returned()),
        ServiceCall::IsrMissingEnd(_) | ServiceCall::HookMissingEnd => Err(OsError::CallLevel),
    }
}
