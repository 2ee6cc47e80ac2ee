//! Resources (OSEK OS 2.2.3 §8, §13.4): `GetResource` and `ReleaseResource` with the
//! immediate priority ceiling protocol, for tasks and category-2 ISRs.
//!
//! A task holding a resource runs at its ceiling; if an ISR shares the resource the ceiling
//! lies at that ISR's level, and the task masks it (see `Os::interrupt_mask`). An ISR
//! holding a resource raises its own level the same way, masking the higher ISRs that share
//! it.

use super::{IsrFrame, Os, ResState, FREE_RES, NONE, NO_RES};
use crate::os::call::ServiceCall;
use crate::os::callevel::Context;
use crate::os::error::ServiceId;
use crate::os::{Hooks, IsrId, OsConfig, OsError, ResourceId, TaskId, RES_SCHEDULER};
use crate::tables::Tables;

/// Who takes or releases a resource.
#[derive(Clone, Copy)]
enum Holder {
    /// A task (its index).
    Task(usize),
    /// The innermost active ISR (its frame index).
    Isr(usize),
}

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
    /// The holder of a resource, or `None` if free or the id is invalid.
    pub fn resource_owner(&self, res: ResourceId) -> Option<TaskId> {
        let state = self.res_state(res).ok()?;
        ((state.owner as usize) < T).then_some(TaskId(state.owner))
    }

    /// The ISR holding a resource, or `None`.
    pub fn resource_isr_owner(&self, res: ResourceId) -> Option<IsrId> {
        let state = self.res_state(res).ok()?;
        let owner = state.owner as usize;
        (owner != NONE as usize && owner >= T).then(|| IsrId((owner - T) as u8))
    }

    /// The resources a task holds, most recently taken first.
    pub fn held_resources(&self, task: TaskId) -> impl Iterator<Item = ResourceId> + '_ {
        let top = self.res_top.get(task.0 as usize).copied().unwrap_or(NO_RES);
        self.resource_stack(top)
    }

    /// The resources the active ISR `isr` holds, most recently taken first (none if it is
    /// not active).
    pub fn isr_held_resources(&self, isr: IsrId) -> impl Iterator<Item = ResourceId> + '_ {
        let top = self.active_frame(isr).map_or(NO_RES, |frame| frame.res_top);
        self.resource_stack(top)
    }

    /// The stack from `top` down. It holds at most the `R` resources and `RES_SCHEDULER`,
    /// and the walk stops there whatever the links say.
    fn resource_stack(&self, mut top: u8) -> impl Iterator<Item = ResourceId> + '_ {
        core::iter::from_fn(move || {
            let id = ResourceId(top);
            let state = self.res_state(id).ok()?;
            top = state.next;
            Some(id)
        })
        .take(R + 1)
    }

    /// The ceiling of a resource (a processor priority).
    pub fn ceiling(&self, res: ResourceId) -> Option<u8> {
        if res == RES_SCHEDULER {
            Some(self.cfg().scheduler_ceiling)
        } else {
            self.cfg().resource_ceiling(res.0 as usize)
        }
    }

    pub(super) fn active_frame(&self, isr: IsrId) -> Option<&IsrFrame> {
        let depth = self.isr_depth as usize;
        // Over the whole stack (`I` frames), not a slice of `depth`: the walk's length is
        // the configuration's, not the state's.
        self.isr_stack
            .iter()
            .enumerate()
            .find(|(i, frame)| *i < depth && frame.isr == isr.0)
            .map(|(_, frame)| frame)
    }

    fn res_state(&self, id: ResourceId) -> Result<&ResState, OsError> {
        if id == RES_SCHEDULER {
            Ok(&self.sched_res)
        } else {
            self.res.get(id.0 as usize).ok_or(OsError::Id)
        }
    }

    fn res_state_mut(&mut self, id: ResourceId) -> Result<&mut ResState, OsError> {
        if id == RES_SCHEDULER {
            Ok(&mut self.sched_res)
        } else {
            self.res.get_mut(id.0 as usize).ok_or(OsError::Id)
        }
    }

    /// The caller of a resource service, with its owner id, static priority and current
    /// priority.
    fn holder(&self) -> Result<(Holder, u8, u8, u8), OsError> {
        match self.context {
            Context::Task => {
                let t = self.calling_task()?;
                Ok((
                    Holder::Task(t),
                    t as u8,
                    self.base_prio(t),
                    self.running_prio,
                ))
            }
            Context::Isr2 => {
                let depth = (self.isr_depth as usize)
                    .checked_sub(1)
                    .ok_or(OsError::CallLevel)?;
                let frame = self.isr_stack.get(depth).ok_or(OsError::CallLevel)?;
                let isr = frame.isr as usize;
                let own = self.cfg().isr_level.get(isr).ok_or(OsError::CallLevel)?;
                Ok((Holder::Isr(depth), (T + isr) as u8, *own, frame.level))
            }
            _ => Err(OsError::CallLevel),
        }
    }

    fn holder_top(&self, holder: Holder) -> u8 {
        match holder {
            Holder::Task(t) => self.res_top.get(t).copied().unwrap_or(NO_RES),
            Holder::Isr(depth) => self.isr_stack.get(depth).map_or(NO_RES, |f| f.res_top),
        }
    }

    fn set_holder_top(&mut self, holder: Holder, top: u8) {
        match holder {
            Holder::Task(t) => {
                if let Some(slot) = self.res_top.get_mut(t) {
                    *slot = top;
                }
            }
            Holder::Isr(depth) => {
                if let Some(frame) = self.isr_stack.get_mut(depth) {
                    frame.res_top = top;
                }
            }
        }
    }

    /// The checks `GetResource` and `ReleaseResource` share: `E_OS_ID` for an unknown
    /// resource, `E_OS_ACCESS` (extended status) when the caller's static priority is above
    /// the ceiling (an ISR's always is for `RES_SCHEDULER`).
    fn resource_caller(&self, res: ResourceId) -> Result<(Holder, u8, u8, u8), OsError> {
        let ceiling = self.ceiling(res).ok_or(OsError::Id)?;
        let (holder, owner, own, current) = self.holder()?;
        if self.extended() && own > ceiling {
            return Err(OsError::Access);
        }
        Ok((holder, owner, current, ceiling))
    }

    /// `GetResource`: takes a resource, raising the caller to its ceiling.
    ///
    /// # Errors
    /// `E_OS_ID` invalid resource; `E_OS_ACCESS` the resource is occupied, or (extended
    /// status) the caller's static priority is above its ceiling; `E_OS_CALLEVEL` not
    /// called by a task or a category-2 ISR; `E_OS_DISABLEDINT`.
    pub fn get_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        self.service(
            ServiceId::GetResource,
            || ServiceCall::GetResource(res),
            |os| {
                let (holder, owner, current, ceiling) = os.resource_caller(res)?;
                let top = os.holder_top(holder);
                let state = os.res_state_mut(res)?;
                if state.owner != NONE {
                    return Err(OsError::Access);
                }
                *state = ResState {
                    owner,
                    prev_prio: current,
                    next: top,
                };
                os.set_holder_top(holder, res.0);
                if ceiling > current {
                    match holder {
                        Holder::Task(_) => {
                            os.running_prio = ceiling;
                            os.sync_threshold();
                        }
                        Holder::Isr(depth) => {
                            if let Some(frame) = os.isr_stack.get_mut(depth) {
                                frame.level = ceiling;
                            }
                        }
                    }
                }
                Ok(())
            },
        )
    }

    /// `ReleaseResource`: releases the most recently taken resource and restores the
    /// priority the caller had before taking it.
    ///
    /// # Errors
    /// `E_OS_ID` invalid resource; `E_OS_NOFUNC` the caller does not hold it, or another
    /// resource must be released first; `E_OS_ACCESS` (extended status) the caller's
    /// static priority is above the ceiling; `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    pub fn release_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        self.service(
            ServiceId::ReleaseResource,
            || ServiceCall::ReleaseResource(res),
            |os| {
                let (holder, _, _, _) = os.resource_caller(res)?;
                if os.holder_top(holder) != res.0 {
                    return Err(OsError::NoFunc);
                }
                os.release_top(holder, res)?;
                if matches!(holder, Holder::Task(_)) {
                    os.reschedule();
                }
                Ok(())
            },
        )
    }

    /// The resources the running task may take now as if nothing else ran, one bit each
    /// ([`crate::os::lock_free_bit`]: the bit says whether the lock masks ISRs):
    /// at task level (not in a hook, an ISR, before start or after shutdown), with no
    /// interrupt lock in force and no resource taken, those of
    /// [`OsConfig::lock_free_resources`] (its own); else none. A port may keep such a lock
    /// outside the kernel until the task's next kernel call, which hands it to
    /// `GetResource` before anything else: the kernel sees the same calls in the same
    /// order, and a lock and release between two kernel calls leave its state as they
    /// found it (`spec::lock_pair_leaves_no_trace`). The port masks what the kernel's
    /// lock would: the interrupts at or below the ceiling ([`Os::ceiling`]) while the lock
    /// is held, none after the release (the task's level masks none).
    #[inline]
    pub fn lock_free_resources(&self) -> u32 {
        self.port_view().1
    }

    /// [`Os::lock_free_resources`] as its definition reads, for `spec::port_view_agrees`
    /// (the kernel computes it with its mask in [`Os::port_view`]).
    pub(crate) fn lock_free_resources_by_definition(&self) -> u32 {
        let t = usize::from(self.running);
        if !matches!(self.context, Context::Task)
            || self.denied & ServiceId::GetResource.bit() != 0
            || self.res_top.get(t).copied() != Some(NO_RES)
        {
            return 0;
        }
        self.cfg().lock_free_resources(t)
    }

    /// What a port carries out at the end of a kernel call, in one: the processor
    /// priority whose mask is the kernel's ([`Os::masked_level`]) and the resources the
    /// running task may lock outside the kernel ([`Os::lock_free_resources`]). At task
    /// level no ISR is active, so the level is the interrupt lock's or the task's
    /// priority, with no ISR frame to look up, and the context is tested once;
    /// `spec::port_view_agrees` states that the pair is the two, in every state the
    /// harnesses and the models reach.
    #[inline]
    pub fn port_view(&self) -> (u8, u32) {
        if !matches!(self.context, Context::Task) {
            return (self.masked_level(), 0);
        }
        let level = self.gate.max(self.running_prio);
        let t = usize::from(self.running);
        if self.denied & ServiceId::GetResource.bit() != 0
            || self.res_top.get(t).copied() != Some(NO_RES)
        {
            return (level, 0);
        }
        (level, self.cfg().lock_free_resources(t))
    }

    /// `GetResource` for the common case, by the stack resource policy: the running task at
    /// task level, or the innermost category-2 ISR, with no interrupt lock in force, a user
    /// resource that is free and (extended status) whose ceiling is at or above the caller's
    /// priority. The resource is pushed on the caller's stack and its priority raised to the
    /// ceiling (a task's preemption threshold with it): the state `GetResource` leaves,
    /// without its call-level table, its holder lookup or its reschedule (taking a resource
    /// never lets a task in).
    ///
    /// Returns the processor priority the caller runs at now, whose
    /// [`InterruptMask::at_level`](crate::os::InterruptMask::at_level) is the kernel's mask;
    /// `None`, with nothing changed, in every other case, where the caller makes the full
    /// service call, which decides, refuses and reports to `ErrorHook`. With a constant
    /// `res` and build-time tables (`static_tables!`) the ceiling is a constant, so the
    /// access check is one load and one compare. `spec::fast_path_agrees` states the
    /// contract (the same state as `GetResource`, the same mask); the harnesses and the
    /// models check it on every step that takes this path.
    #[inline(always)]
    pub fn try_get_resource(&mut self, res: ResourceId) -> Option<u8> {
        if self.denied & ServiceId::GetResource.bit() != 0 {
            return None;
        }
        match self.context {
            Context::Task => self.try_get_for_task(res),
            Context::Isr2 => self.try_get_for_isr(res),
            _ => None,
        }
    }

    #[inline(always)]
    fn try_get_for_task(&mut self, res: ResourceId) -> Option<u8> {
        let t = self.running as usize;
        let ceiling = self.cfg().resource_ceiling(res.0 as usize)?;
        let current = self.running_prio;
        // The task's priority now is at or above its own, so at or below the ceiling it
        // passes extended status's access check (its own priority at or below the
        // ceiling) in either status, and the ceiling is the priority it runs at next.
        // Above it (a task that holds a resource of a higher ceiling) the full service
        // decides: the check needs the task's own priority, a table away.
        if current > ceiling {
            return None;
        }
        let top = self.res_top.get_mut(t)?;
        let state = self.res.get_mut(res.0 as usize)?;
        if state.owner != NONE {
            return None;
        }
        *state = ResState {
            owner: t as u8,
            prev_prio: current,
            next: *top,
        };
        *top = res.0;
        // At task level in the running phase the threshold is the priority + 1.
        self.running_prio = ceiling;
        self.preempt_at = ceiling.saturating_add(1);
        Some(ceiling)
    }

    #[inline(always)]
    fn try_get_for_isr(&mut self, res: ResourceId) -> Option<u8> {
        let depth = (self.isr_depth as usize).checked_sub(1)?;
        let ceiling = self.cfg().resource_ceiling(res.0 as usize)?;
        let frame = self.isr_stack.get_mut(depth)?;
        // As for a task: the ISR's level now is at or above its own, so at or below the
        // ceiling the access check passes in either status; above it, the full service.
        if frame.level > ceiling {
            return None;
        }
        let state = self.res.get_mut(res.0 as usize)?;
        if state.owner != NONE {
            return None;
        }
        *state = ResState {
            owner: (T + frame.isr as usize) as u8,
            prev_prio: frame.level,
            next: frame.res_top,
        };
        frame.res_top = res.0;
        frame.level = ceiling;
        Some(ceiling)
    }

    /// `ReleaseResource` for the common case: the running task at task level, or the
    /// innermost category-2 ISR, with no interrupt lock in force, `res` the user resource
    /// it took last, and (a task) no ready task above the priority it returns to. The
    /// resource is popped and the priority (a task's threshold with it) restored: the state
    /// `ReleaseResource` leaves when it does not switch tasks.
    ///
    /// Returns the processor priority the caller runs at now; `None`, with nothing
    /// changed, in every other case (a task switch among them), where the caller makes the
    /// full service call. The contract is `spec::fast_path_agrees`, as for
    /// [`Os::try_get_resource`].
    #[inline(always)]
    pub fn try_release_resource(&mut self, res: ResourceId) -> Option<u8> {
        if self.denied & ServiceId::ReleaseResource.bit() != 0 {
            return None;
        }
        match self.context {
            Context::Task => self.try_release_for_task(res),
            Context::Isr2 => self.try_release_for_isr(res),
            _ => None,
        }
    }

    #[inline(always)]
    fn try_release_for_task(&mut self, res: ResourceId) -> Option<u8> {
        let t = self.running as usize;
        let top = self.res_top.get_mut(t)?;
        if *top != res.0 {
            return None;
        }
        // (Taken by this task, so in extended status its priority is at or below the
        // ceiling: `GetResource` checked the same constants.)
        let state = self.res.get_mut(res.0 as usize)?;
        let prev = state.prev_prio;
        if self.ready.highest().is_some_and(|ready| ready > prev) {
            return None;
        }
        *top = state.next;
        *state = FREE_RES;
        self.running_prio = prev;
        self.preempt_at = prev.saturating_add(1);
        Some(prev)
    }

    #[inline(always)]
    fn try_release_for_isr(&mut self, res: ResourceId) -> Option<u8> {
        let depth = (self.isr_depth as usize).checked_sub(1)?;
        let frame = self.isr_stack.get_mut(depth)?;
        if frame.res_top != res.0 {
            return None;
        }
        // An ISR's release never switches tasks (that waits for the last ISR's return).
        let state = self.res.get_mut(res.0 as usize)?;
        frame.res_top = state.next;
        frame.level = state.prev_prio;
        *state = FREE_RES;
        Some(frame.level)
    }

    /// Pops `res`, the top of `holder`'s stack, and restores the holder's priority.
    fn release_top(&mut self, holder: Holder, res: ResourceId) -> Result<(), OsError> {
        let state = self.res_state_mut(res)?;
        let released = *state;
        *state = FREE_RES;
        self.set_holder_top(holder, released.next);
        match holder {
            Holder::Task(_) => self.running_prio = released.prev_prio,
            Holder::Isr(depth) => {
                if let Some(frame) = self.isr_stack.get_mut(depth) {
                    frame.level = released.prev_prio;
                }
            }
        }
        Ok(())
    }

    /// Releases everything the innermost ISR holds (it returned holding resources).
    /// Returns whether it held any.
    pub(super) fn release_all_of_isr(&mut self) -> bool {
        let Some(depth) = (self.isr_depth as usize).checked_sub(1) else {
            return false;
        };
        let holder = Holder::Isr(depth);
        let mut any = false;
        // Each round releases one of at most `R + 1` held resources.
        for _ in 0..=R {
            let top = self.holder_top(holder);
            if top == NO_RES || self.release_top(holder, ResourceId(top)).is_err() {
                break;
            }
            any = true;
        }
        any
    }

    /// Releases everything the running task holds (its body returned holding resources).
    pub(super) fn release_all_of_task(&mut self, t: usize) {
        let holder = Holder::Task(t);
        // Each round releases one of at most `R + 1` held resources.
        for _ in 0..=R {
            let top = self.holder_top(holder);
            if top == NO_RES || self.release_top(holder, ResourceId(top)).is_err() {
                return;
            }
        }
    }
}
