//! Interrupt processing (OSEK OS 2.2.3 §6, §13.3): ISR entry and return as the port
//! reports them, the six interrupt services, `GetISRID` (AUTOSAR), and the interrupt mask
//! the board must apply.

use super::{IsrFrame, Os, Phase, NONE, NO_FRAME, NO_RES};
use crate::os::call::ServiceCall;
use crate::os::callevel::Context;
use crate::os::config::{IsrCategory, ISR_LEVEL_BASE};
use crate::os::error::ServiceId;
use crate::os::{CounterId, Hooks, InterruptMask, IsrId, OsConfig, OsError, TickType};
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
    /// The interrupts the board must hold pending now (apply it after every kernel call):
    /// all of them before `StartOS` has finished its start-up hook, after `ShutdownOS`,
    /// and under `DisableAllInterrupts`/`SuspendAllInterrupts`; otherwise every ISR at or
    /// below the processor priority (the innermost ISR's, or a task's raised to a ceiling at
    /// interrupt level), and at least every category-2 ISR under `SuspendOSInterrupts` and
    /// while a hook or an alarm callback runs.
    #[inline]
    pub fn interrupt_mask(&self) -> InterruptMask {
        InterruptMask::at_level(self.masked_level())
    }

    /// The processor priority at or below which interrupts are held (`u8::MAX`: all):
    /// [`Os::interrupt_mask`] is its [`InterruptMask::at_level`]. A port whose controller
    /// masks by level applies it without the conversion.
    #[inline(always)]
    pub fn masked_level(&self) -> u8 {
        self.gate.max(self.current_level())
    }

    /// The innermost active ISR (any category), if any.
    pub fn active_isr(&self) -> Option<IsrId> {
        self.top_frame().map(|frame| IsrId(frame.isr))
    }

    /// How many ISRs are active (nested).
    pub const fn isr_nesting(&self) -> u8 {
        self.isr_depth
    }

    /// The ISR stack's slots, the active ISRs' frames below the free ones: for
    /// `spec::free_isr_slots_empty`.
    pub(crate) const fn isr_slots(&self) -> &[IsrFrame; I] {
        &self.isr_stack
    }

    /// The active ISRs, outermost first, each with the processor priority it runs at now.
    pub fn active_isrs(&self) -> impl Iterator<Item = (IsrId, u8)> + '_ {
        let depth = self.isr_depth as usize;
        // Over the whole stack (`I` frames) and stopping at `depth`: the walk's length is
        // the configuration's, not the state's.
        self.isr_stack
            .iter()
            .enumerate()
            .map_while(move |(i, frame)| (i < depth).then_some((IsrId(frame.isr), frame.level)))
    }

    /// The processor priority and context the active ISR at nesting depth `depth`
    /// (0: outermost) interrupted.
    pub fn interrupted_by(&self, depth: usize) -> Option<(u8, Context, super::Locks)> {
        let frame = self.isr_stack.get(..self.isr_depth as usize)?.get(depth)?;
        let below = match depth.checked_sub(1) {
            Some(d) => self.isr_stack.get(d).map_or(0, |f| f.level),
            None => self.running_priority().unwrap_or(0),
        };
        Some((below, frame.interrupted, frame.locks))
    }

    /// The port enters ISR `isr`: the hardware took its interrupt. A category-2 ISR runs
    /// at interrupt level, where task switches wait until the last ISR returns.
    ///
    /// This is how the kernel learns of an interrupt, not an OSEK service: it has no call
    /// level and never calls `ErrorHook`.
    ///
    /// # Errors
    /// `E_OS_ID` unknown ISR; `E_OS_STATE` the OS is not running (before `StartOS` has
    /// dispatched, or after `ShutdownOS`); `E_OS_ACCESS` the interrupt mask holds it (its
    /// priority is not above the processor priority, or a lock is in force): the hardware
    /// must keep it pending.
    pub fn enter_isr(&mut self, isr: IsrId) -> Result<(), OsError> {
        let i = isr.0 as usize;
        let Some(config) = self.cfg().isrs.get(i) else {
            return Err(OsError::Id);
        };
        let level = ISR_LEVEL_BASE + config.priority;
        if level <= self.masked_level() {
            return Err(if matches!(self.phase, Phase::Running) {
                OsError::Access
            } else {
                OsError::State
            });
        }
        let frame = self.frame_of(isr, level);
        let depth = self.isr_depth as usize;
        let Some(slot) = self.isr_stack.get_mut(depth) else {
            return Err(OsError::Access);
        };
        *slot = frame;
        self.isr_depth += 1;
        self.context = match config.category {
            IsrCategory::One => Context::Isr1,
            IsrCategory::Two => Context::Isr2,
        };
        // At interrupt level nothing preempts (`threshold`).
        self.preempt_at = u8::MAX;
        self.sync_denied();
        Ok(())
    }

    /// The OS tick for the common case: category-2 ISR `isr`, whose whole body is
    /// `IncrementCounter(counter)`, interrupts a task or the idle loop at task level, its
    /// priority is above the processor priority, and no alarm of the counter is due at this
    /// tick. Then the ISR's entry, the service and its return together only advance the
    /// counter and the delta of the alarm at the head of its list (the ISR's slot, which the
    /// entry fills and the return empties, is empty before and after): this does that, in
    /// one step.
    ///
    /// Returns the processor priority at or below which the kernel's mask holds interrupts
    /// now (its [`InterruptMask::at_level`] is `interrupt_mask()`); `None`, with nothing
    /// changed, in every other case, where the port runs the ISR whole (`enter_isr`, the
    /// service, `exit_isr`). The contract is `spec::fast_path_agrees`, as for the lock's
    /// fast paths.
    #[inline(always)]
    pub fn try_tick(&mut self, isr: IsrId, counter: CounterId) -> Option<u8> {
        self.try_ticks(isr, counter, 1)
    }

    /// `ticks` (at least 1) OS ticks of [`Os::try_tick`] at once, all or none: the state
    /// `ticks` successive fast ticks leave, where each of them would be taken (no alarm
    /// due at any of them: `ticks` is below [`Os::ticks_to_expiry`]); `None`, with nothing
    /// changed, otherwise. For a simulation in virtual time, which need not run the ticks
    /// where nothing happens one by one (`spec::ticks_agree` is the contract).
    #[inline(always)]
    pub fn try_ticks(&mut self, isr: IsrId, counter: CounterId, ticks: u64) -> Option<u8> {
        if ticks == 0 {
            return None;
        }
        let masked = self.admits_tick(isr)?;
        let cfg = self.cfg();
        let c = counter.0 as usize;
        let max = cfg.counters.get(c)?.max_allowed_value;
        let head = usize::from(*self.counter_head.get(c)?);
        // The head's delta is at least 1 between ticks; the tick that brings it to 0 is
        // the one its alarm is due at.
        if self
            .alarm_delta
            .get(head)
            .is_some_and(|delta| u64::from(*delta) <= ticks)
        {
            return None;
        }
        // (The ISR's slot is left as the return leaves it: empty, as it is now.)
        let value = self.counter_value.get_mut(c)?;
        *value = if ticks == 1 {
            if *value >= max {
                0
            } else {
                *value + 1
            }
        } else {
            // (`value <= max`, so the sum does not overflow and the remainder fits.)
            ((u64::from(*value) + ticks) % (u64::from(max) + 1)) as TickType
        };
        if let Some(delta) = self.alarm_delta.get_mut(head) {
            // (`ticks` is below the delta, so it fits.)
            *delta -= ticks as TickType;
        }
        Some(masked)
    }

    /// The OS tick where alarms are due, for the common case: as [`Os::try_tick`] (the
    /// category-2 ISR `isr`, whose whole body is `IncrementCounter(counter)`, interrupts a
    /// task or the idle loop at task level, above the processor priority), where every
    /// alarm due at this tick activates a task that may be activated once more, each a
    /// task of its own. Then the ISR runs no `ErrorHook`, callback or `SetEvent`, and its
    /// entry, the service and its return together advance the counter, run the due
    /// alarms (each re-armed where cyclic, its task activated) and reschedule at the
    /// ISR's return: this does that, in one step, without the ISR's frame, its context's
    /// call-level and mask bookkeeping, and the service's.
    ///
    /// Returns the processor priority whose mask is the kernel's now, as
    /// [`Os::try_tick`] does; the running task may have changed (a port carries that out as
    /// after any kernel call). `None`, with nothing changed, in every other case, where the
    /// port runs the ISR whole. The contract is `spec::fast_path_agrees`.
    #[inline]
    pub fn try_tick_due(&mut self, isr: IsrId, counter: CounterId) -> Option<u8> {
        self.admits_tick(isr)?;
        let c = counter.0 as usize;
        if c >= C || !self.due_alarms_only_activate(c) {
            return None;
        }
        // The ISR's entry and return leave the context, the locks and the ISR's (empty)
        // slot as they found them; what is left is the service's tick and the return's
        // rescheduling point, from the interrupted context (a task's or the idle loop's).
        // The tick changes only the ready queue: the threshold of that context is in sync
        // (`spec::threshold_synced`), and a switch syncs the context.
        self.advance(c);
        debug_assert_eq!(self.preempt_at, self.threshold());
        self.reschedule_in_sync();
        Some(self.masked_level())
    }

    /// Whether the tick's fast paths may stand for the whole ISR `isr`: a category-2 ISR
    /// (which may call `IncrementCounter` in both dialects: `callevel` asserts it when it
    /// builds its table) at task level (nested in another ISR, its frame would go above
    /// it; of the contexts at task level only a task and the idle loop admit a category-2
    /// ISR: the mask test declines the hooks, and before and after the run), above the
    /// processor priority. The kernel's masked level where it may, `None` otherwise.
    #[inline(always)]
    fn admits_tick(&self, isr: IsrId) -> Option<u8> {
        if self.isr_depth != 0 {
            return None;
        }
        let config = self.cfg().isrs.get(isr.0 as usize)?;
        let masked = self.masked_level();
        (matches!(config.category, IsrCategory::Two) && ISR_LEVEL_BASE + config.priority > masked)
            .then_some(masked)
    }

    /// The frame of ISR `isr` entered now at processor priority `level`: no resources
    /// held, the locks in force and the context it interrupts.
    #[inline(always)]
    fn frame_of(&self, isr: IsrId, level: u8) -> IsrFrame {
        IsrFrame {
            isr: isr.0,
            level,
            res_top: NO_RES,
            locks: self.locks,
            interrupted: self.context,
        }
    }

    /// The innermost ISR returns. An ISR that leaves interrupt locks or resources behind
    /// has them undone and released; for a category-2 ISR that is reported to `ErrorHook`
    /// (`E_OS_DISABLEDINT`, `E_OS_RESOURCE`; AUTOSAR SWS_Os_00368, 00369). When the last
    /// ISR returns to task level, this is a rescheduling point.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` no ISR is active, or code other than the ISR itself (a hook) is
    /// running; `E_OS_STATE` the OS was shut down.
    pub fn exit_isr(&mut self) -> Result<(), OsError> {
        let Some(frame) = self.top_frame().copied() else {
            return Err(if self.is_shut_down() {
                OsError::State
            } else {
                OsError::CallLevel
            });
        };
        if !matches!(self.context, Context::Isr1 | Context::Isr2) {
            return Err(OsError::CallLevel);
        }
        if self.locks != frame.locks || frame.res_top != NO_RES {
            self.isr_missing_end(frame);
            if self.is_shut_down() {
                return Ok(());
            }
        }
        self.isr_depth -= 1;
        // The slot it leaves is empty again (`spec::free_isr_slots_empty`), so the tick's
        // fast path, which stands for an entry and a return, need not write it.
        self.isr_stack
            .iter_mut()
            .skip(usize::from(self.isr_depth))
            .take(1)
            .for_each(|slot| *slot = NO_FRAME);
        self.context = frame.interrupted;
        if self.isr_depth == 0 && matches!(self.context, Context::Task | Context::Idle) {
            self.reschedule();
            // A hook around the switch may have shut the OS down (`ErrorHook` after a
            // refused call in `PostTaskHook`): its context and masks stand.
            if self.is_shut_down() {
                return Ok(());
            }
            self.context = if self.running == NONE {
                Context::Idle
            } else {
                Context::Task
            };
        } else if self.isr_depth == 0 {
            // Back in a hook (which a category-1 ISR may interrupt): no rescheduling point,
            // but the threshold the entry raised is the one the state defines again, as it
            // was before the ISR (`spec::threshold_synced`); the task level after the hook
            // relies on it.
            self.sync_threshold();
        }
        self.sync_denied();
        Ok(())
    }

    /// An ISR returns with interrupt locks or resources it took: undo and release them, and
    /// for a category-2 ISR report each to `ErrorHook` (AUTOSAR SWS_Os_00368, 00369).
    #[cold]
    #[inline(never)]
    fn isr_missing_end(&mut self, frame: IsrFrame) {
        let isr = IsrId(frame.isr);
        let cat2 = self
            .cfg()
            .isrs
            .get(frame.isr as usize)
            .is_some_and(|c| matches!(c.category, IsrCategory::Two));
        let unlocked = self.locks != frame.locks;
        if unlocked {
            self.set_locks(frame.locks);
        }
        let released = self.release_all_of_isr();
        if cat2 && unlocked {
            self.report(ServiceCall::IsrMissingEnd(isr), OsError::DisabledInt);
        }
        if cat2 && released {
            self.report(ServiceCall::IsrMissingEnd(isr), OsError::Resource);
        }
    }

    /// Runs an interrupt service: call-level check only (they never raise `ErrorHook`,
    /// AUTOSAR SWS_Os_00367), then `body` on the locks, which then come into force. `body`
    /// also sees the locks the current context found when it started (an ISR's entry), so
    /// that it can tell this context's own critical sections from those it interrupted.
    fn interrupt_service(
        &mut self,
        call: ServiceCall,
        body: impl FnOnce(&mut super::Locks, super::Locks) -> Result<(), OsError>,
    ) -> Result<(), OsError> {
        self.check(call.id())?;
        let base = self
            .top_frame()
            .map_or(super::Locks::default(), |f| f.locks);
        let mut locks = self.locks;
        body(&mut locks, base)?;
        self.set_locks(locks);
        Ok(())
    }

    /// `DisableAllInterrupts`: every interrupt held until `EnableAllInterrupts`. Not
    /// nestable, and not allowed inside this context's `Suspend...` section (OSEK §13.3.2:
    /// only suspend/resume pairs are allowed there), where it is not carried out, and then
    /// neither is the `EnableAllInterrupts` that would pair with it.
    ///
    /// OSEK declares the interrupt services without a status; the result here only says
    /// whether the call was carried out.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_NOFUNC` already disabled (ignored);
    /// `E_OS_DISABLEDINT` inside a `Suspend...` section (ignored).
    pub fn disable_all_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::DisableAllInterrupts, |locks, base| {
            if locks.all_disabled {
                return Err(OsError::NoFunc);
            }
            if locks.suspend_all > base.suspend_all || locks.suspend_os > base.suspend_os {
                return Err(OsError::DisabledInt);
            }
            locks.all_disabled = true;
            Ok(())
        })
    }

    /// `EnableAllInterrupts`: ends `DisableAllInterrupts`.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_NOFUNC` no `DisableAllInterrupts` in force:
    /// ignored (AUTOSAR SWS_Os_00092).
    pub fn enable_all_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::EnableAllInterrupts, |locks, _| {
            if !locks.all_disabled {
                return Err(OsError::NoFunc);
            }
            locks.all_disabled = false;
            Ok(())
        })
    }

    /// `SuspendAllInterrupts`: every interrupt held until the matching
    /// `ResumeAllInterrupts`; nestable. Not allowed inside a `DisableAllInterrupts` section
    /// (OSEK: no service there), where it is not carried out.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_DISABLEDINT` inside `DisableAllInterrupts`
    /// (ignored); `E_OS_LIMIT` nested 255 deep (ignored).
    pub fn suspend_all_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::SuspendAllInterrupts, |locks, _| {
            if locks.all_disabled {
                return Err(OsError::DisabledInt);
            }
            locks.suspend_all = locks.suspend_all.checked_add(1).ok_or(OsError::Limit)?;
            Ok(())
        })
    }

    /// `ResumeAllInterrupts`: ends one `SuspendAllInterrupts`; the last one restores the
    /// interrupts.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_NOFUNC` none in force: ignored
    /// (SWS_Os_00092).
    pub fn resume_all_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::ResumeAllInterrupts, |locks, _| {
            locks.suspend_all = locks.suspend_all.checked_sub(1).ok_or(OsError::NoFunc)?;
            Ok(())
        })
    }

    /// `SuspendOSInterrupts`: every category-2 interrupt held until the matching
    /// `ResumeOSInterrupts`; category-1 ISRs still run. Nestable. Not allowed inside a
    /// `DisableAllInterrupts` section, where it is not carried out.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_DISABLEDINT` inside `DisableAllInterrupts`
    /// (ignored); `E_OS_LIMIT` nested 255 deep (ignored).
    pub fn suspend_os_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::SuspendOsInterrupts, |locks, _| {
            if locks.all_disabled {
                return Err(OsError::DisabledInt);
            }
            locks.suspend_os = locks.suspend_os.checked_add(1).ok_or(OsError::Limit)?;
            Ok(())
        })
    }

    /// `ResumeOSInterrupts`: ends one `SuspendOSInterrupts`.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_NOFUNC` none in force: ignored
    /// (SWS_Os_00092).
    pub fn resume_os_interrupts(&mut self) -> Result<(), OsError> {
        self.interrupt_service(ServiceCall::ResumeOsInterrupts, |locks, _| {
            locks.suspend_os = locks.suspend_os.checked_sub(1).ok_or(OsError::NoFunc)?;
            Ok(())
        })
    }

    /// `GetISRID` (AUTOSAR): the category-2 ISR running now (in `ErrorHook`: the one in
    /// which the error occurred), or `None` (`INVALID_ISR`).
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not allowed here; `E_OS_DISABLEDINT`.
    pub fn get_isr_id(&mut self) -> Result<Option<IsrId>, OsError> {
        self.service(
            ServiceId::GetIsrId,
            || ServiceCall::GetIsrId,
            |os| {
                let isr = os.top_frame().and_then(|frame| {
                    let cat2 = os
                        .cfg()
                        .isrs
                        .get(frame.isr as usize)
                        .is_some_and(|c| matches!(c.category, IsrCategory::Two));
                    cat2.then_some(IsrId(frame.isr))
                });
                Ok(isr)
            },
        )
    }
}
