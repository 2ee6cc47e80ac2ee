//! Call levels: the contexts code can run in, and which services each may call (OSEK OS
//! 2.2.3 Figure 12-1; AUTOSAR SWS OS "allowed calling context for OS service calls").
//!
//! Every service checks its caller against [`allowed`] and refuses a call from anywhere
//! else with `E_OS_CALLEVEL` (AUTOSAR SWS_Os_00088; OSEK defines the code for five task
//! services and leaves the others to the implementation, which here uses the same code).
//! The two tables differ only in the interrupt services: OSEK allows none of them in the
//! start-up and shutdown hooks and only the `Suspend/ResumeAllInterrupts` pair in the other
//! hooks and in alarm callbacks, where AUTOSAR allows all six everywhere, and before
//! `StartOS` and after `ShutdownOS` too (SWS_Os_00299). The AUTOSAR services (`GetISRID`,
//! `IncrementCounter`, `GetCounterValue`, `GetElapsedValue`) are available in both
//! dialects with AUTOSAR's rows.
//!
//! While interrupts are disabled or suspended, every service but the six interrupt services
//! returns `E_OS_DISABLEDINT` instead (SWS_Os_00093; OSEK only says such calls are not
//! allowed).

use super::config::Dialect;
use super::error::ServiceId;

/// Where code runs, as far as the OS is concerned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Context {
    /// Before `StartOS`: only `StartOS` (and, in AUTOSAR, the all-interrupt services).
    BeforeStart = 0,
    /// The OS runs but neither a task, an ISR nor a hook: the board's idle loop, which
    /// calls no service.
    Idle,
    /// A task.
    Task,
    /// A category-1 ISR.
    Isr1,
    /// A category-2 ISR.
    Isr2,
    /// `ErrorHook`.
    ErrorHook,
    /// `PreTaskHook`.
    PreTaskHook,
    /// `PostTaskHook`.
    PostTaskHook,
    /// `StartupHook`.
    StartupHook,
    /// `ShutdownHook`.
    ShutdownHook,
    /// An alarm callback.
    AlarmCallback,
    /// After `ShutdownOS`: the OS no longer runs.
    ShutDown,
}

impl Context {
    /// Number of contexts.
    pub const COUNT: usize = 12;

    /// Every context, in order.
    pub const ALL: [Context; Self::COUNT] = [
        Self::BeforeStart,
        Self::Idle,
        Self::Task,
        Self::Isr1,
        Self::Isr2,
        Self::ErrorHook,
        Self::PreTaskHook,
        Self::PostTaskHook,
        Self::StartupHook,
        Self::ShutdownHook,
        Self::AlarmCallback,
        Self::ShutDown,
    ];

    /// A short name, for tables and messages.
    pub const fn name(self) -> &'static str {
        match self {
            Self::BeforeStart => "before StartOS",
            Self::Idle => "idle",
            Self::Task => "task",
            Self::Isr1 => "ISR cat. 1",
            Self::Isr2 => "ISR cat. 2",
            Self::ErrorHook => "ErrorHook",
            Self::PreTaskHook => "PreTaskHook",
            Self::PostTaskHook => "PostTaskHook",
            Self::StartupHook => "StartupHook",
            Self::ShutdownHook => "ShutdownHook",
            Self::AlarmCallback => "alarm callback",
            Self::ShutDown => "after ShutdownOS",
        }
    }

    /// Whether this is one of the hook routines (or an alarm callback), which run inside
    /// the kernel with category-2 interrupts held.
    pub const fn is_hook(self) -> bool {
        matches!(
            self,
            Self::ErrorHook
                | Self::PreTaskHook
                | Self::PostTaskHook
                | Self::StartupHook
                | Self::ShutdownHook
                | Self::AlarmCallback
        )
    }
}

const fn mask(services: &[ServiceId]) -> u64 {
    let mut m = 0;
    let mut i = 0;
    while i < services.len() {
        m |= services[i].bit();
        i += 1;
    }
    m
}

use ServiceId as S;

/// The six interrupt services.
pub const INTERRUPT_SERVICES: u64 = mask(&[
    S::DisableAllInterrupts,
    S::EnableAllInterrupts,
    S::SuspendAllInterrupts,
    S::ResumeAllInterrupts,
    S::SuspendOsInterrupts,
    S::ResumeOsInterrupts,
]);

/// The four services on all interrupts (AUTOSAR allows them before `StartOS` and after
/// `ShutdownOS`).
const ALL_INTERRUPT_SERVICES: u64 = mask(&[
    S::DisableAllInterrupts,
    S::EnableAllInterrupts,
    S::SuspendAllInterrupts,
    S::ResumeAllInterrupts,
]);

/// The pair OSEK allows in alarm callbacks and in the error, pre-task and post-task hooks.
const SUSPEND_ALL_PAIR: u64 = mask(&[S::SuspendAllInterrupts, S::ResumeAllInterrupts]);

/// What the error, pre-task and post-task hooks may ask.
const HOOK_QUERIES: u64 = mask(&[
    S::GetTaskId,
    S::GetTaskState,
    S::GetEvent,
    S::GetAlarmBase,
    S::GetAlarm,
    S::GetActiveApplicationMode,
]);

/// Every service a task may call: all but `StartOS` and the pseudo-services.
const TASK: u64 = mask(&[
    S::ActivateTask,
    S::TerminateTask,
    S::ChainTask,
    S::Schedule,
    S::GetTaskId,
    S::GetTaskState,
    S::GetResource,
    S::ReleaseResource,
    S::SetEvent,
    S::ClearEvent,
    S::GetEvent,
    S::WaitEvent,
    S::GetAlarmBase,
    S::GetAlarm,
    S::SetRelAlarm,
    S::SetAbsAlarm,
    S::CancelAlarm,
    S::GetActiveApplicationMode,
    S::ShutdownOs,
    S::GetIsrId,
    S::IncrementCounter,
    S::GetCounterValue,
    S::GetElapsedValue,
]) | INTERRUPT_SERVICES;

/// What a category-2 ISR may call: everything but the services that end, chain, yield or
/// block a task, and `ClearEvent`.
const ISR2: u64 = TASK
    & !mask(&[
        S::TerminateTask,
        S::ChainTask,
        S::Schedule,
        S::ClearEvent,
        S::WaitEvent,
    ]);

// The OS tick's fast path (`Os::try_ticks`) takes a category-2 ISR's `IncrementCounter`
// without the call-level table: it must stay allowed there.
const _: () = assert!(ISR2 & S::IncrementCounter.bit() != 0);

/// The services `context` may call in `dialect`, one bit per [`ServiceId`].
pub const fn allowed(dialect: Dialect, context: Context) -> u64 {
    let autosar = matches!(dialect, Dialect::Autosar);
    let hook_interrupts = if autosar {
        INTERRUPT_SERVICES
    } else {
        SUSPEND_ALL_PAIR
    };
    let outside = if autosar { ALL_INTERRUPT_SERVICES } else { 0 };
    match context {
        Context::BeforeStart => S::StartOs.bit() | outside,
        Context::Idle => 0,
        Context::Task => TASK,
        Context::Isr1 => INTERRUPT_SERVICES,
        Context::Isr2 => ISR2,
        Context::ErrorHook => HOOK_QUERIES | mask(&[S::ShutdownOs, S::GetIsrId]) | hook_interrupts,
        Context::PreTaskHook | Context::PostTaskHook => HOOK_QUERIES | hook_interrupts,
        Context::StartupHook => {
            mask(&[S::GetActiveApplicationMode, S::ShutdownOs])
                | if autosar { INTERRUPT_SERVICES } else { 0 }
        }
        Context::ShutdownHook => {
            S::GetActiveApplicationMode.bit() | if autosar { INTERRUPT_SERVICES } else { 0 }
        }
        Context::AlarmCallback => hook_interrupts,
        Context::ShutDown => outside,
    }
}

/// The services refused in `context` (the complement of [`allowed`]), per context, as the
/// kernel caches them.
pub(crate) const fn denied_table(dialect: Dialect) -> [u64; Context::COUNT] {
    let mut table = [0u64; Context::COUNT];
    let mut i = 0;
    while i < Context::COUNT {
        table[i] = !allowed(dialect, Context::ALL[i]);
        i += 1;
    }
    table
}
