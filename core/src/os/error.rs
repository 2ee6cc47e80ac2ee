//! OSEK `StatusType` error codes (OSEK OS 2.2.3 §13.1; AUTOSAR keeps the same values).

/// An OSEK error. `E_OK` is `Ok(())`.
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
        }
    }
}
