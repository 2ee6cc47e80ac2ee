//! Hook routines (OSEK OS 2.2.3 §11) and alarm callbacks.
//!
//! The application implements [`Hooks`] for a type of its own; the kernel stores one value
//! of it (the hooks' data, reachable with [`Os::hooks`](super::Os::hooks) and
//! [`Os::hooks_mut`](super::Os::hooks_mut)) and calls the routines the configuration
//! enables ([`HookSet`](super::HookSet)), each with the kernel itself, at the call level of
//! that hook: a hook may call exactly the services the standard allows there, and any other
//! returns `E_OS_CALLEVEL`.
//!
//! | routine | called |
//! |---|---|
//! | `StartupHook` | by `StartOS`, after the kernel is initialised and before the first task is dispatched, all interrupts masked |
//! | `ShutdownHook` | by `ShutdownOS`, with its error code, before the OS stops for good |
//! | `PreTaskHook` | each time a task enters the running state (dispatched or resumed), before it executes |
//! | `PostTaskHook` | each time the running task is about to leave the running state (terminate, chain, wait, preempted), while it is still the running task |
//! | `ErrorHook` | at the end of every service that returns an error, and when an alarm action fails or a task or ISR ends badly (AUTOSAR); never while `ErrorHook` runs |
//! | alarm callback | when an alarm whose action is `Callback(id)` expires |
//!
//! Inside `ErrorHook`, [`Os::error_service_id`](super::Os::error_service_id)
//! (`OSErrorGetServiceId`) and [`Os::error_call`](super::Os::error_call) (the service's
//! parameters, the `OSError_<Service>_<Param>` macros) tell what failed.

use super::OsError;
use super::StatusType;

/// The application's hook routines and alarm callbacks. `O` is the kernel type; every
/// method has an empty default, so an application writes only the hooks it enables.
///
/// The implementing type is the hooks' data: it lives inside the kernel, so the kernel
/// stays a plain value (`Copy`, comparable, hashable: the model checker explores it).
pub trait Hooks<O>: Copy + Eq + core::hash::Hash + core::fmt::Debug {
    /// `StartupHook`.
    fn startup_hook(os: &mut O) {
        let _ = os;
    }

    /// `ShutdownHook(Error)`.
    fn shutdown_hook(os: &mut O, error: StatusType) {
        let _ = (os, error);
    }

    /// `PreTaskHook`.
    fn pre_task_hook(os: &mut O) {
        let _ = os;
    }

    /// `PostTaskHook`.
    fn post_task_hook(os: &mut O) {
        let _ = os;
    }

    /// `ErrorHook(Error)`.
    fn error_hook(os: &mut O, error: OsError) {
        let _ = (os, error);
    }

    /// The alarm callback `callback` (`ALARMCALLBACK`).
    fn alarm_callback(os: &mut O, callback: u8) {
        let _ = (os, callback);
    }
}

/// No hook routines and no alarm callbacks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct NoHooks;

impl<O> Hooks<O> for NoHooks {}
