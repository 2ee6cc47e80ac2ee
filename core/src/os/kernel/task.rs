//! Task management (OSEK OS 2.2.3 §13.2): `ActivateTask`, `TerminateTask`, `ChainTask`,
//! `Schedule`, `GetTaskID`, `GetTaskState`.

use super::{Context, Os, NO_RES};
use crate::os::call::ServiceCall;
use crate::os::error::ServiceId;
use crate::os::{Hooks, OsConfig, OsError, TaskId, TaskState};
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
    /// `ActivateTask`: one more activation of `task`; it preempts the caller if it has a
    /// higher priority (at task level).
    ///
    /// # Errors
    /// `E_OS_LIMIT` the task already has `max_activations`; `E_OS_ID` invalid task;
    /// `E_OS_CALLEVEL` not called by a task or a category-2 ISR; `E_OS_DISABLEDINT`
    /// interrupts disabled.
    #[inline]
    pub fn activate_task(&mut self, task: TaskId) -> Result<(), OsError> {
        self.service(
            ServiceId::ActivateTask,
            || ServiceCall::ActivateTask(task),
            |os| {
                let t = Self::task_index(task)?;
                // The running task was a highest-priority one before the call (the invariant),
                // so the only entry that can outrank it now is the new one: compare with its
                // priority instead of searching the bitmap.
                debug_assert_eq!(os.preempt_at, os.threshold());
                let prio = os.cfg().priority[t];
                let preempts = prio >= os.preempt_at;
                if preempts && !os.cfg().hooks.post_task {
                    // It preempts at once, and nothing runs before the switch: its record
                    // would be queued at an empty priority and taken again at once.
                    let count = os.activation_left(t)?;
                    os.activations[t] = count + 1;
                    os.switch_to(prio, Some(t as u8));
                    return Ok(());
                }
                os.activate(t)?;
                if preempts {
                    os.switch_to(prio, None);
                }
                Ok(())
            },
        )
    }

    /// `ActivateTask` for the common case where it preempts: the running task at task
    /// level, with no interrupt lock in force and no hook around a switch configured,
    /// activates a suspended task whose priority is at or above the caller's preemption
    /// threshold. The caller goes to the head of its priority's queue and the activated
    /// task runs: the state `ActivateTask` leaves, without its call-level table, its
    /// error path or its general switch.
    ///
    /// Returns what a port reads at the end of a kernel call ([`Os::port_view`]: the new
    /// running task's processor priority and the resources it may lock outside the
    /// kernel); `None`, with nothing changed, in every other case, where the caller makes
    /// the full service call, which decides, refuses and reports to `ErrorHook`. With
    /// build-time tables (`static_tables!`) the hook test is a constant.
    /// `spec::fast_path_agrees` states the contract (the same state as `ActivateTask`, the
    /// same view); the harnesses and the models check it on every step that takes this
    /// path.
    #[inline(always)]
    pub fn try_activate_task(&mut self, task: TaskId) -> Option<(u8, u32)> {
        let hooks = self.cfg().hooks;
        // (The hooks' flags in one test: either one sends the switch to the service. The
        // two services in one test too: where `GetResource` is allowed, the view below
        // needs no test of it.)
        if self.denied & (ServiceId::ActivateTask.bit() | ServiceId::GetResource.bit()) != 0
            || !matches!(self.context, Context::Task)
            || (hooks.pre_task | hooks.post_task)
        {
            return None;
        }
        let t = usize::from(task.0);
        let prio = *self.cfg().priority.get(t)?;
        // A suspended task has an activation left (every task has at least one).
        if prio < self.preempt_at || self.activations.get(t).copied() != Some(0) {
            return None;
        }
        self.activations[t] = 1;
        // `switch_to` without its hooks: the caller to the head of its priority's queue,
        // the new task running at its dispatch priority, its threshold; the context stays
        // `Task`.
        self.preempt_running();
        self.run(t);
        self.sync_threshold();
        // `port_view` without its tests: the context is `Task` and `GetResource` allowed
        // (tested above, and the switch changes neither), and the task just started holds
        // no resource (a suspended task holds none: `spec::kernel_invariants`).
        let view = (
            self.gate.max(self.running_prio),
            self.cfg().lock_free_resources(t),
        );
        // As after every switch (`switched`); not in Kani builds, for the same reason.
        #[cfg(not(kani))]
        {
            debug_assert!(crate::os::spec::kernel_invariants(self));
            debug_assert_eq!(view, self.port_view());
        }
        Some(view)
    }

    /// `TerminateTask`: ends the calling task. On success the board must stop executing it.
    ///
    /// # Errors
    /// `E_OS_RESOURCE` the task holds a resource; `E_OS_CALLEVEL` not called by a task;
    /// `E_OS_DISABLEDINT` interrupts disabled.
    pub fn terminate_task(&mut self) -> Result<(), OsError> {
        self.service(
            ServiceId::TerminateTask,
            || ServiceCall::TerminateTask,
            |os| {
                let t = os.calling_task()?;
                if os.res_top[t] != NO_RES {
                    return Err(OsError::Resource);
                }
                if !os.post_task_hook() {
                    return Ok(());
                }
                os.finish(t);
                os.reschedule();
                os.sync_task_context();
                Ok(())
            },
        )
    }

    /// `ChainTask`: ends the calling task and activates `task` (itself included, which
    /// re-queues it as the newest of its priority).
    ///
    /// # Errors
    /// `E_OS_LIMIT` the successor is at its activation limit (the caller keeps running);
    /// `E_OS_ID` invalid task; `E_OS_RESOURCE`, `E_OS_CALLEVEL`, `E_OS_DISABLEDINT` as for
    /// `TerminateTask`.
    pub fn chain_task(&mut self, task: TaskId) -> Result<(), OsError> {
        self.service(
            ServiceId::ChainTask,
            || ServiceCall::ChainTask(task),
            |os| {
                let t = os.calling_task()?;
                let n = Self::task_index(task)?;
                if os.res_top[t] != NO_RES {
                    return Err(OsError::Resource);
                }
                if n != t && os.activations[n] >= os.cfg().max_activations[n] {
                    return Err(OsError::Limit);
                }
                if !os.post_task_hook() {
                    return Ok(());
                }
                os.finish(t);
                os.activate(n)?;
                os.reschedule();
                os.sync_task_context();
                Ok(())
            },
        )
    }

    /// `Schedule`: lets higher-priority ready tasks run; for a non-preemptive task this is
    /// the point where it may be preempted.
    ///
    /// # Errors
    /// `E_OS_RESOURCE` the task holds a resource; `E_OS_CALLEVEL` not called by a task;
    /// `E_OS_DISABLEDINT` interrupts disabled.
    pub fn schedule(&mut self) -> Result<(), OsError> {
        self.service(
            ServiceId::Schedule,
            || ServiceCall::Schedule,
            |os| {
                let t = os.calling_task()?;
                if os.res_top[t] != NO_RES {
                    return Err(OsError::Resource);
                }
                // Release the internal resource (non-preemption) for the decision, then take it
                // back if the task keeps the processor.
                os.running_prio = os.base_prio(t);
                os.reschedule();
                if os.running as usize == t {
                    os.running_prio = os.internal_prio(t);
                    os.sync_threshold();
                }
                Ok(())
            },
        )
    }

    /// `GetTaskID`: the running task; in an ISR or a hook, the task that was running when
    /// it started; `None` (`INVALID_TASK`) when no task runs.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` called where it is not allowed (category-1 ISR, start-up or shutdown
    /// hook, alarm callback); `E_OS_DISABLEDINT` interrupts disabled.
    pub fn get_task_id(&mut self) -> Result<Option<TaskId>, OsError> {
        self.service(
            ServiceId::GetTaskId,
            || ServiceCall::GetTaskId,
            |os| Ok(os.running()),
        )
    }

    /// `GetTaskState`.
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT` as for `GetTaskID`.
    pub fn get_task_state(&mut self, task: TaskId) -> Result<TaskState, OsError> {
        self.service(
            ServiceId::GetTaskState,
            || ServiceCall::GetTaskState(task),
            |os| os.task_state(task).ok_or(OsError::Id),
        )
    }
}
