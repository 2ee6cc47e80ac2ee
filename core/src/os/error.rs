//! OSEK `StatusType` error codes (OSEK OS 2.2.3 §13.1) and the AUTOSAR OS additions this
//! kernel raises, plus the service identifiers that `ErrorHook` reads
//! (`OSErrorGetServiceId`, OSEK §13.8.2.1).

/// `StatusType`: `E_OK` (0) or an error code. Applications may pass their own codes to
/// `ShutdownOS`, so the hook that receives it takes the raw value.
pub type StatusType = u8;

/// `E_OK`: the service succeeded.
pub const E_OK: StatusType = 0;

/// An OSEK or AUTOSAR OS error. `E_OK` is `Ok(..)`.
///
/// Codes 1..=8 are fixed by OSEK. AUTOSAR names its additional codes without fixing their
/// values; this kernel numbers them as ATK2, ERIKA3 and most AUTOSAR OS implementations do
/// (9 `E_OS_SERVICEID`, 10 `E_OS_ILLEGAL_ADDRESS`, 11, 12, 13; Arctic Core shifts them by
/// one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum OsError {
    /// `E_OS_ACCESS` (1): the object is not accessible from the caller (wrong task kind,
    /// resource occupied or its ceiling below the caller's priority).
    Access = 1,
    /// `E_OS_CALLEVEL` (2): the service is not allowed at this call level.
    CallLevel = 2,
    /// `E_OS_ID` (3): the object identifier is invalid.
    Id = 3,
    /// `E_OS_LIMIT` (4): too many task activations.
    Limit = 4,
    /// `E_OS_NOFUNC` (5): the object is not in use (alarm), or a resource is released out
    /// of LIFO order or by a task that does not hold it.
    NoFunc = 5,
    /// `E_OS_RESOURCE` (6): the caller still holds a resource.
    Resource = 6,
    /// `E_OS_STATE` (7): the object is in the wrong state (events of a suspended task,
    /// alarm already in use).
    State = 7,
    /// `E_OS_VALUE` (8): a value is outside the admitted range.
    Value = 8,
    /// `E_OS_MISSINGEND` (11, AUTOSAR): a task's body returned without `TerminateTask` or
    /// `ChainTask` (SWS_Os_00069).
    MissingEnd = 11,
    /// `E_OS_DISABLEDINT` (12, AUTOSAR): a service was called while interrupts were
    /// disabled or suspended (SWS_Os_00093), or an ISR returned with them so
    /// (SWS_Os_00368).
    DisabledInt = 12,
    /// `E_OS_STACKFAULT` (13, AUTOSAR): a stack overflow was detected (SWS_Os_00068); the
    /// port shuts the OS down with it.
    StackFault = 13,
}

impl OsError {
    /// The standard's name of the code.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Access => "E_OS_ACCESS",
            Self::CallLevel => "E_OS_CALLEVEL",
            Self::Id => "E_OS_ID",
            Self::Limit => "E_OS_LIMIT",
            Self::NoFunc => "E_OS_NOFUNC",
            Self::Resource => "E_OS_RESOURCE",
            Self::State => "E_OS_STATE",
            Self::Value => "E_OS_VALUE",
            Self::MissingEnd => "E_OS_MISSINGEND",
            Self::DisabledInt => "E_OS_DISABLEDINT",
            Self::StackFault => "E_OS_STACKFAULT",
        }
    }

    /// The numeric `StatusType` value.
    pub const fn status(self) -> StatusType {
        self as StatusType
    }

    /// Every error, in the order of their codes.
    pub const ALL: [Self; 11] = [
        Self::Access,
        Self::CallLevel,
        Self::Id,
        Self::Limit,
        Self::NoFunc,
        Self::Resource,
        Self::State,
        Self::Value,
        Self::MissingEnd,
        Self::DisabledInt,
        Self::StackFault,
    ];

    /// The error a `StatusType` value names (`None`: `E_OK`, or a code no service of
    /// this kernel returns, such as an application's own `ShutdownOS` code).
    pub fn from_status(status: StatusType) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.status() == status)
    }
}

/// The standard's name of a `StatusType` value: `E_OK`, an error's name, or `None` for a
/// code the standard does not name here (an application's own).
pub fn status_name(status: StatusType) -> Option<&'static str> {
    if status == E_OK {
        Some("E_OK")
    } else {
        OsError::from_status(status).map(OsError::name)
    }
}

/// `OSServiceIdType`: which service an error came from (`OSErrorGetServiceId`). The
/// numbering is this kernel's (OSEK leaves it to the implementation); it also indexes
/// the call-level table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum ServiceId {
    /// `OSServiceId_ActivateTask`.
    ActivateTask = 0,
    /// `OSServiceId_TerminateTask`.
    TerminateTask,
    /// `OSServiceId_ChainTask`.
    ChainTask,
    /// `OSServiceId_Schedule`.
    Schedule,
    /// `OSServiceId_GetTaskID`.
    GetTaskId,
    /// `OSServiceId_GetTaskState`.
    GetTaskState,
    /// `DisableAllInterrupts`.
    DisableAllInterrupts,
    /// `EnableAllInterrupts`.
    EnableAllInterrupts,
    /// `SuspendAllInterrupts`.
    SuspendAllInterrupts,
    /// `ResumeAllInterrupts`.
    ResumeAllInterrupts,
    /// `SuspendOSInterrupts`.
    SuspendOsInterrupts,
    /// `ResumeOSInterrupts`.
    ResumeOsInterrupts,
    /// `OSServiceId_GetResource`.
    GetResource,
    /// `OSServiceId_ReleaseResource`.
    ReleaseResource,
    /// `OSServiceId_SetEvent`.
    SetEvent,
    /// `OSServiceId_ClearEvent`.
    ClearEvent,
    /// `OSServiceId_GetEvent`.
    GetEvent,
    /// `OSServiceId_WaitEvent`.
    WaitEvent,
    /// `OSServiceId_GetAlarmBase`.
    GetAlarmBase,
    /// `OSServiceId_GetAlarm`.
    GetAlarm,
    /// `OSServiceId_SetRelAlarm`.
    SetRelAlarm,
    /// `OSServiceId_SetAbsAlarm`.
    SetAbsAlarm,
    /// `OSServiceId_CancelAlarm`.
    CancelAlarm,
    /// `OSServiceId_GetActiveApplicationMode`.
    GetActiveApplicationMode,
    /// `OSServiceId_StartOS`.
    StartOs,
    /// `OSServiceId_ShutdownOS`.
    ShutdownOs,
    /// `OSServiceId_GetISRID` (AUTOSAR).
    GetIsrId,
    /// `OSServiceId_IncrementCounter` (AUTOSAR).
    IncrementCounter,
    /// `OSServiceId_GetCounterValue` (AUTOSAR).
    GetCounterValue,
    /// `OSServiceId_GetElapsedValue` (AUTOSAR).
    GetElapsedValue,
    /// Not a call: a task's body returned without `TerminateTask`/`ChainTask` (reported
    /// with `E_OS_MISSINGEND`).
    TaskMissingEnd,
    /// Not a call: a category-2 ISR returned holding a resource or with interrupts
    /// disabled or suspended (reported with `E_OS_RESOURCE` or `E_OS_DISABLEDINT`).
    IsrMissingEnd,
    /// Not a call: a hook or alarm callback returned with interrupts suspended (reported
    /// with `E_OS_DISABLEDINT`).
    HookMissingEnd,
}

impl ServiceId {
    /// Every service id, in numbering order.
    pub const ALL: [ServiceId; 33] = [
        Self::ActivateTask,
        Self::TerminateTask,
        Self::ChainTask,
        Self::Schedule,
        Self::GetTaskId,
        Self::GetTaskState,
        Self::DisableAllInterrupts,
        Self::EnableAllInterrupts,
        Self::SuspendAllInterrupts,
        Self::ResumeAllInterrupts,
        Self::SuspendOsInterrupts,
        Self::ResumeOsInterrupts,
        Self::GetResource,
        Self::ReleaseResource,
        Self::SetEvent,
        Self::ClearEvent,
        Self::GetEvent,
        Self::WaitEvent,
        Self::GetAlarmBase,
        Self::GetAlarm,
        Self::SetRelAlarm,
        Self::SetAbsAlarm,
        Self::CancelAlarm,
        Self::GetActiveApplicationMode,
        Self::StartOs,
        Self::ShutdownOs,
        Self::GetIsrId,
        Self::IncrementCounter,
        Self::GetCounterValue,
        Self::GetElapsedValue,
        Self::TaskMissingEnd,
        Self::IsrMissingEnd,
        Self::HookMissingEnd,
    ];

    /// The bit of this service in a call-level mask.
    #[inline(always)]
    pub const fn bit(self) -> u64 {
        1 << (self as u8)
    }

    /// The standard's name of the service.
    pub const fn name(self) -> &'static str {
        match self {
            Self::ActivateTask => "ActivateTask",
            Self::TerminateTask => "TerminateTask",
            Self::ChainTask => "ChainTask",
            Self::Schedule => "Schedule",
            Self::GetTaskId => "GetTaskID",
            Self::GetTaskState => "GetTaskState",
            Self::DisableAllInterrupts => "DisableAllInterrupts",
            Self::EnableAllInterrupts => "EnableAllInterrupts",
            Self::SuspendAllInterrupts => "SuspendAllInterrupts",
            Self::ResumeAllInterrupts => "ResumeAllInterrupts",
            Self::SuspendOsInterrupts => "SuspendOSInterrupts",
            Self::ResumeOsInterrupts => "ResumeOSInterrupts",
            Self::GetResource => "GetResource",
            Self::ReleaseResource => "ReleaseResource",
            Self::SetEvent => "SetEvent",
            Self::ClearEvent => "ClearEvent",
            Self::GetEvent => "GetEvent",
            Self::WaitEvent => "WaitEvent",
            Self::GetAlarmBase => "GetAlarmBase",
            Self::GetAlarm => "GetAlarm",
            Self::SetRelAlarm => "SetRelAlarm",
            Self::SetAbsAlarm => "SetAbsAlarm",
            Self::CancelAlarm => "CancelAlarm",
            Self::GetActiveApplicationMode => "GetActiveApplicationMode",
            Self::StartOs => "StartOS",
            Self::ShutdownOs => "ShutdownOS",
            Self::GetIsrId => "GetISRID",
            Self::IncrementCounter => "IncrementCounter",
            Self::GetCounterValue => "GetCounterValue",
            Self::GetElapsedValue => "GetElapsedValue",
            Self::TaskMissingEnd => "(task returned without TerminateTask)",
            Self::IsrMissingEnd => "(ISR returned holding a resource or a lock)",
            Self::HookMissingEnd => "(hook returned with interrupts suspended)",
        }
    }

    /// Whether this is one of the six interrupt services, which return no status, never
    /// call `ErrorHook` and stay callable while interrupts are disabled.
    pub const fn is_interrupt_service(self) -> bool {
        matches!(
            self,
            Self::DisableAllInterrupts
                | Self::EnableAllInterrupts
                | Self::SuspendAllInterrupts
                | Self::ResumeAllInterrupts
                | Self::SuspendOsInterrupts
                | Self::ResumeOsInterrupts
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_status_names_itself_and_codes_round_trip() {
        for e in OsError::ALL {
            assert_eq!(OsError::from_status(e.status()), Some(e));
            assert_eq!(status_name(e.status()), Some(e.name()));
        }
        assert_eq!(status_name(E_OK), Some("E_OK"));
        assert_eq!(OsError::from_status(E_OK), None);
        // 9 and 10 are AUTOSAR codes this kernel never returns; 200 an application's.
        for code in [9, 10, 14, 200] {
            assert_eq!(status_name(code), None, "{code}");
        }
    }
}
