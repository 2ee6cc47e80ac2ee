//! Operating system execution control (OSEK OS 2.2.3 §13.7): `StartOS`, `ShutdownOS`,
//! `GetActiveApplicationMode`; and the end of a task body that returns without
//! `TerminateTask` (AUTOSAR).

use super::{Locks, Os, Phase, FREE_RES, NONE, NO_FRAME, NO_RES};
use crate::os::call::ServiceCall;
use crate::os::callevel::Context;
use crate::os::error::ServiceId;
use crate::os::queue::ReadyQueue;
use crate::os::{AppMode, Hooks, OsConfig, OsError, StatusType};
use crate::tables::Tables;

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
        K,
        H,
    > Os<T, R, C, A, I, Q, K, H>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Self>,
{
    /// `StartOS(Mode)`: activates the autostart tasks of `mode` (in table order), arms its
    /// autostart alarms, calls `StartupHook` with every interrupt masked, then dispatches
    /// the highest-priority task. On a board, `StartOS` does not return: the board runs
    /// what the kernel dispatched from here on.
    ///
    /// Interrupt locks the start-up code took before (AUTOSAR allows the all-interrupt
    /// services there, SWS_Os_00299) do not stop it, and do not carry into the OS: the code
    /// that took them never runs again.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` the OS has already started; `E_OS_VALUE` `mode` is not a configured
    /// application mode (the OS does not start). `ErrorHook` is not called: the OS is not
    /// running yet.
    pub fn start_os(&mut self, mode: AppMode) -> Result<(), OsError> {
        // Call level only: SWS_Os_00093's E_OS_DISABLEDINT is for tasks, ISRs and hooks.
        if self.cfg().denied[self.context as usize] & ServiceId::StartOs.bit() != 0 {
            return Err(OsError::CallLevel);
        }
        let cfg = self.cfg();
        if mode.0 >= cfg.app_modes {
            return Err(OsError::Value);
        }
        self.set_locks(Locks::default());
        self.mode = mode;
        let bit = 1u32 << mode.0;
        for t in 0..T {
            if cfg.tasks[t].autostart_modes & bit != 0 {
                // Cannot fail: every task has room for at least one activation.
                let _ = self.activate(t);
            }
        }
        self.arm_autostart_alarms(bit);
        self.phase = Phase::Starting;
        if cfg.hooks.startup {
            self.call_hook(Context::StartupHook, |os| H::startup_hook(os));
            if self.is_shut_down() {
                return Ok(());
            }
        }
        self.phase = Phase::Running;
        self.context = Context::Idle;
        self.sync_denied();
        self.reschedule();
        self.sync_task_context();
        Ok(())
    }

    /// `GetActiveApplicationMode`.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here (before `StartOS`, category-1 ISR, alarm
    /// callback); `E_OS_DISABLEDINT`.
    pub fn get_active_application_mode(&mut self) -> Result<AppMode, OsError> {
        self.service(
            ServiceId::GetActiveApplicationMode,
            || ServiceCall::GetActiveApplicationMode,
            |os| Ok(os.mode),
        )
    }

    /// `ShutdownOS(Error)`: calls `ShutdownHook(Error)`, then stops the OS for good: no
    /// task, ISR or alarm runs any more and every interrupt is masked. `PostTaskHook` is not
    /// called (AUTOSAR SWS_Os_00071). On a board, `ShutdownOS` does not return: the board
    /// stops (AUTOSAR: interrupts disabled, an endless loop).
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here (allowed: task, category-2 ISR, `ErrorHook`,
    /// `StartupHook`); `E_OS_DISABLEDINT`. The service has no status in OSEK: it never
    /// calls `ErrorHook`.
    pub fn shutdown_os(&mut self, error: StatusType) -> Result<(), OsError> {
        self.check(ServiceId::ShutdownOs)?;
        self.shut_down(error);
        Ok(())
    }

    /// The OS's own `ShutdownOS(error)`, from wherever the board detected a fault it cannot
    /// recover from (AUTOSAR SWS_Os_00068: a stack overflow is `E_OS_STACKFAULT`). No
    /// call-level check: the OS calls it, not the application.
    pub fn shutdown_on_fault(&mut self, error: OsError) {
        self.shut_down(error.status());
    }

    fn shut_down(&mut self, error: StatusType) {
        if self.is_shut_down() {
            return;
        }
        self.phase = Phase::ShuttingDown;
        // No task preempts from here (`spec::threshold_synced`, inside ShutdownHook too).
        self.sync_threshold();
        if self.cfg().hooks.shutdown {
            self.call_hook(Context::ShutdownHook, |os| H::shutdown_hook(os, error));
        }
        self.phase = Phase::ShutDown;
        self.context = Context::ShutDown;
        self.running = NONE;
        self.running_prio = 0;
        self.ready = ReadyQueue::new();
        self.activations = [0; T];
        self.started = [false; T];
        self.waiting = [false; T];
        self.events = [0; T];
        self.wait_mask = [0; T];
        self.res_top = [NO_RES; T];
        self.res = [FREE_RES; R];
        self.sched_res = FREE_RES;
        self.isr_stack = [NO_FRAME; I];
        self.isr_depth = 0;
        self.error_call = None;
        self.disarm_all();
        self.sync_threshold();
        self.set_locks(Locks::default());
    }

    /// The port reports that the running task's body returned without `TerminateTask` or
    /// `ChainTask` (AUTOSAR SWS_Os_00052, 00069, 00070, 00239; OSEK calls this undefined).
    /// Interrupt locks the task left are undone, its resources released, `ErrorHook` is
    /// called with `E_OS_MISSINGEND` while it is still running, and the task is terminated.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` no task is running at task level.
    pub fn task_returned(&mut self) -> Result<(), OsError> {
        let t = self.calling_task()?;
        if self.locks.any() {
            self.set_locks(Locks::default());
        }
        self.release_all_of_task(t);
        // The task's priority is its own again, and so is its threshold, inside the hooks
        // below too (`spec::threshold_synced`).
        self.sync_threshold();
        self.report(
            ServiceCall::TaskMissingEnd(crate::os::TaskId(t as u8)),
            OsError::MissingEnd,
        );
        if self.is_shut_down() || !self.post_task_hook() {
            return Ok(());
        }
        self.finish(t);
        self.reschedule();
        self.sync_task_context();
        Ok(())
    }
}
