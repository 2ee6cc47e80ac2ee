//! Events (OSEK OS 2.2.3 §13.5): `SetEvent`, `ClearEvent`, `GetEvent`, `WaitEvent`.

use super::{Os, NONE, NO_RES};
use crate::os::call::ServiceCall;
use crate::os::error::ServiceId;
use crate::os::{EventMask, Hooks, OsConfig, OsError, TaskId};
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
    /// Sets events of task `t`: the work of `SetEvent` and of an alarm's event action.
    pub(super) fn set_event_inner(&mut self, t: usize, mask: EventMask) -> Result<(), OsError> {
        if self.extended() && !self.is_extended_task(t) {
            return Err(OsError::Access);
        }
        // Kept in standard status too: events set on a suspended task would survive into
        // its next activation, which OSEK says starts with none.
        if self.activations[t] == 0 {
            return Err(OsError::State);
        }
        self.events[t] |= mask;
        if self.waiting[t] && self.events[t] & self.wait_mask[t] != 0 {
            self.waiting[t] = false;
            self.wait_mask[t] = 0;
            self.saved_prio[t] = self.base_prio(t);
            self.ready
                .push_back(self.base_prio(t), t as u8)
                .map_err(|_| OsError::Limit)?;
        }
        Ok(())
    }

    /// `SetEvent`: sets events of an extended task; a task waiting for any of them becomes
    /// ready (the newest of its priority).
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_ACCESS` not an extended task (extended status);
    /// `E_OS_STATE` the task is suspended; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn set_event(&mut self, task: TaskId, mask: EventMask) -> Result<(), OsError> {
        self.service(
            ServiceId::SetEvent,
            || ServiceCall::SetEvent(task, mask),
            |os| {
                let t = Self::task_index(task)?;
                os.set_event_inner(t, mask)?;
                os.reschedule();
                Ok(())
            },
        )
    }

    /// `ClearEvent`: clears events of the calling extended task.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_ACCESS` the caller is a basic task
    /// (extended status); `E_OS_DISABLEDINT`.
    pub fn clear_event(&mut self, mask: EventMask) -> Result<(), OsError> {
        self.service(
            ServiceId::ClearEvent,
            || ServiceCall::ClearEvent(mask),
            |os| {
                let t = os.calling_task()?;
                if os.extended() && !os.is_extended_task(t) {
                    return Err(OsError::Access);
                }
                os.events[t] &= !mask;
                Ok(())
            },
        )
    }

    /// `GetEvent`: the events set for an extended task.
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_ACCESS` not an extended task and `E_OS_STATE`
    /// suspended (both extended status); `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn get_event(&mut self, task: TaskId) -> Result<EventMask, OsError> {
        self.service(
            ServiceId::GetEvent,
            || ServiceCall::GetEvent(task),
            |os| {
                let t = Self::task_index(task)?;
                if os.extended() {
                    if !os.is_extended_task(t) {
                        return Err(OsError::Access);
                    }
                    if os.activations[t] == 0 {
                        return Err(OsError::State);
                    }
                }
                Ok(os.events[t])
            },
        )
    }

    /// `WaitEvent`: the calling extended task waits until one of `mask` is set; returns at
    /// once if one already is.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_ACCESS` basic task; `E_OS_RESOURCE` the
    /// task holds a resource; `E_OS_DISABLEDINT`.
    pub fn wait_event(&mut self, mask: EventMask) -> Result<(), OsError> {
        self.service(
            ServiceId::WaitEvent,
            || ServiceCall::WaitEvent(mask),
            |os| {
                let t = os.calling_task()?;
                // Kept in standard status: a basic task that waits would let its next queued
                // activation run while this one is blocked.
                if !os.is_extended_task(t) {
                    return Err(OsError::Access);
                }
                if os.res_top[t] != NO_RES {
                    return Err(OsError::Resource);
                }
                if os.events[t] & mask != 0 {
                    return Ok(());
                }
                if !os.post_task_hook() {
                    return Ok(());
                }
                os.waiting[t] = true;
                os.wait_mask[t] = mask;
                os.saved_prio[t] = os.base_prio(t);
                os.running = NONE;
                os.running_prio = 0;
                os.reschedule();
                os.sync_task_context();
                Ok(())
            },
        )
    }
}
