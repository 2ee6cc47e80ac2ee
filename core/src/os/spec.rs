//! Named predicates: the kernel's contract, stated over its public inspection methods.
//! The harnesses in this crate, the fuzz targets, the stateright model in `proofs/`, the
//! conformance tests and `debug_assert!`s inside the kernel all execute these same
//! functions.

use super::call::{perform, Returned, ServiceCall};
use super::callevel::Context;
use super::config::{IsrCategory, Status};
use super::kernel::NO_FRAME;
use super::{
    CounterId, Hooks, InterruptMask, IsrId, Os, OsConfig, OsError, Phase, ResourceId, TaskId,
    TaskKind, RES_SCHEDULER,
};
use crate::tables::Tables;

/// Declares a predicate over any kernel: the generic parameters are the same for all.
macro_rules! predicate {
    ($(#[$meta:meta])* pub fn $name:ident($os:ident) -> bool $body:block) => {
        $(#[$meta])*
        pub fn $name<
            const T: usize,
            const R: usize,
            const C: usize,
            const A: usize,
            const I: usize,
            const Q: usize,
            K,
            H,
        >(
            $os: &Os<T, R, C, A, I, Q, K, H>,
        ) -> bool
        where
            K: Tables<OsConfig<T, R, C, A, I>>,
            H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
        $body
    };
}

/// Whether the processor is at task level: the OS runs, no ISR is active and no hook runs.
fn at_task_level<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    os: &Os<T, R, C, A, I, Q, K, H>,
) -> bool
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    os.phase() == Phase::Running
        && os.isr_nesting() == 0
        && matches!(os.context(), Context::Task | Context::Idle)
}

predicate! {
    /// OSEK §4.6: whenever the processor is at task level, the running task has the highest
    /// priority among ready activations (ties go to the running task); with nothing
    /// running, nothing is ready.
    pub fn running_is_highest_ready(os) -> bool {
        if !at_task_level(os) {
            return true;
        }
        match (os.running_priority(), os.highest_ready()) {
            (_, None) => true,
            (None, Some(_)) => false,
            (Some(running), Some(ready)) => ready <= running,
        }
    }
}

predicate! {
    /// Immediate priority ceiling: the running task's priority is exactly the highest of
    /// its dispatch priority and the ceilings of the resources it holds.
    pub fn running_priority_is_ceiling(os) -> bool {
        let Some(task) = os.running() else {
            return true;
        };
        let mut expected = os.dispatch_priority(task).unwrap_or(0);
        for res in os.held_resources(task) {
            expected = expected.max(os.ceiling(res).unwrap_or(0));
        }
        os.running_priority() == Some(expected)
    }
}

predicate! {
    /// No activation is lost or invented: for every task, ready records plus the running or
    /// waiting instance equal its activation count, which never exceeds the configured
    /// limit.
    pub fn activations_accounted(os) -> bool {
        (0..T).all(|t| {
            let id = TaskId(t as u8);
            let on_cpu = usize::from(os.running() == Some(id)) + usize::from(os.is_waiting(id));
            let count = os.activation_count(id);
            count <= os.config().tasks()[t].max_activations
                && os.queued_records(id) + on_cpu == usize::from(count)
                && on_cpu <= 1
        })
    }
}

predicate! {
    /// Resources: each held resource has exactly one owner (a started, not waiting task, or
    /// an active ISR), it appears exactly once on that owner's stack, and (in extended
    /// status) its ceiling is at least the owner's priority, so `RES_SCHEDULER` is never an
    /// ISR's. Waiting tasks hold none.
    pub fn resources_consistent(os) -> bool {
        let extended = os.config().status() == Status::Extended;
        let ids = (0..R as u8)
            .map(ResourceId)
            .chain(core::iter::once(RES_SCHEDULER));
        for res in ids {
            let ceiling = os.ceiling(res).unwrap_or(0);
            if let Some(owner) = os.resource_owner(res) {
                if !os.is_started(owner) || os.is_waiting(owner) {
                    return false;
                }
                if os.held_resources(owner).filter(|r| *r == res).count() != 1 {
                    return false;
                }
                let base = os.config().tasks()[owner.0 as usize].priority;
                if extended && ceiling < base {
                    return false;
                }
            }
            if let Some(isr) = os.resource_isr_owner(res) {
                if os.active_isrs().all(|(active, _)| active != isr) {
                    return false;
                }
                if os.isr_held_resources(isr).filter(|r| *r == res).count() != 1 {
                    return false;
                }
                let level = os.config().isr_level(isr.0 as usize).unwrap_or(u8::MAX);
                if extended && ceiling < level {
                    return false;
                }
            }
        }
        (0..T as u8).map(TaskId).all(|t| {
            os.held_resources(t)
                .all(|r| os.resource_owner(r) == Some(t))
        }) && os.active_isrs().all(|(isr, _)| {
            os.isr_held_resources(isr)
                .all(|r| os.resource_isr_owner(r) == Some(isr))
        })
    }
}

predicate! {
    /// Waiting tasks are extended and wait for something not yet set. (`WaitEvent(0)` is
    /// legal in OSEK and waits forever, so an empty mask is allowed.)
    pub fn waiting_is_blocked(os) -> bool {
        (0..T).all(|t| {
            let id = TaskId(t as u8);
            !os.is_waiting(id)
                || (os.config().tasks()[t].kind == TaskKind::Extended
                    && os.events(id) & os.wait_mask(id) == 0)
        })
    }
}

predicate! {
    /// ISRs: every active ISR was taken only above the priority it interrupted and only when
    /// the locks then in force let it through (so an ISR never runs below its priority, and
    /// none runs while interrupts are disabled); ISR priorities strictly increase inward;
    /// each runs at exactly the highest of its own level and the ceilings it holds; and
    /// while one is active, the code running is that ISR (or a hook it caused).
    pub fn isr_nesting_consistent(os) -> bool {
        let cfg = os.config();
        for (depth, (isr, level)) in os.active_isrs().enumerate() {
            let Some(config) = cfg.isrs().get(isr.0 as usize) else {
                return false;
            };
            let Some(own) = cfg.isr_level(isr.0 as usize) else {
                return false;
            };
            let Some((below, _, locks)) = os.interrupted_by(depth) else {
                return false;
            };
            if own <= below || locks.masks_all() {
                return false;
            }
            if config.category == IsrCategory::Two && locks.suspend_os != 0 {
                return false;
            }
            let mut expected = own;
            for res in os.isr_held_resources(isr) {
                expected = expected.max(os.ceiling(res).unwrap_or(0));
            }
            if level != expected {
                return false;
            }
        }
        if let Some(innermost) = os.active_isr() {
            let category = cfg
                .isrs()
                .get(innermost.0 as usize)
                .map(|c| c.category);
            let context_ok = match os.context() {
                Context::Isr1 => category == Some(IsrCategory::One),
                Context::Isr2 => category == Some(IsrCategory::Two),
                other => other.is_hook(),
            };
            if !context_ok {
                return false;
            }
        }
        true
    }
}

predicate! {
    /// The ISR stack's slots above the active ISRs are empty: an ISR's return empties the
    /// slot its entry filled, so a step that stands for an entry and a return (the tick's
    /// fast path) leaves the slot as it found it, without writing it.
    pub fn free_isr_slots_empty(os) -> bool {
        let free = usize::from(os.isr_nesting());
        os.isr_slots().iter().skip(free).all(|frame| *frame == NO_FRAME)
    }
}

predicate! {
    /// The call level follows the state: at task level the context is `Task` exactly when
    /// a task runs; after `ShutdownOS` nothing runs, nothing is ready and nothing is active.
    pub fn context_consistent(os) -> bool {
        match os.phase() {
            Phase::ShutDown => {
                os.running().is_none()
                    && os.ready_bitmap() == 0
                    && os.isr_nesting() == 0
                    && os.context() == Context::ShutDown
            }
            Phase::Running if os.isr_nesting() == 0 && !os.context().is_hook() => {
                (os.context() == Context::Task) == os.running().is_some()
                    && matches!(os.context(), Context::Task | Context::Idle)
            }
            _ => true,
        }
    }
}

predicate! {
    /// What a port reads at the end of every kernel call in one step
    /// ([`Os::port_view`](crate::os::Os::port_view)) is the kernel's mask and the
    /// resources the running task may lock outside the kernel, as each is defined.
    pub fn port_view_agrees(os) -> bool {
        let (level, lock_free) = os.port_view();
        level == os.masked_level() && lock_free == os.lock_free_resources_by_definition()
    }
}

predicate! {
    /// The preemption threshold the kernel keeps is the one its state defines: no task
    /// preempts in an ISR, before `StartOS` or after `ShutdownOS`; any ready task
    /// preempts the idle loop; one above the running task's priority preempts it. The
    /// fast paths test it without computing it (`ActivateTask`'s, and the tick's where
    /// alarms are due at its rescheduling point).
    pub fn threshold_synced(os) -> bool {
        os.preemption_threshold() == os.threshold()
    }
}

predicate! {
    /// All of the above.
    pub fn kernel_invariants(os) -> bool {
        running_is_highest_ready(os)
            && running_priority_is_ceiling(os)
            && activations_accounted(os)
            && resources_consistent(os)
            && waiting_is_blocked(os)
            && isr_nesting_consistent(os)
            && free_isr_slots_empty(os)
            && context_consistent(os)
            && port_view_agrees(os)
            && threshold_synced(os)
    }
}

/// One step of the code running on the processor: a service call, the entry or return of
/// an ISR as the hardware and the port report them, a whole ISR that calls one service, or
/// a task body that returns without ending itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Service {
    /// A service called by the code running now.
    Call(ServiceCall),
    /// The hardware takes interrupt `isr` (refused when masked).
    EnterIsr(IsrId),
    /// The running ISR returns.
    ExitIsr,
    /// A whole ISR that calls one service: entered, the call, returned. Rescheduling
    /// happens at its return.
    Isr(IsrId, ServiceCall),
    /// The running task's body returns without `TerminateTask` (AUTOSAR: missing end).
    TaskReturn,
    /// `GetResource` as a port takes a lock: the kernel's fast path
    /// ([`Os::try_get_resource`]), and the full service where that declines.
    FastGet(ResourceId),
    /// `ReleaseResource` as a port ends a lock: [`Os::try_release_resource`], and the full
    /// service where that declines.
    FastRelease(ResourceId),
    /// A whole ISR whose body is `IncrementCounter` (the OS tick), as a port runs it: the
    /// kernel's fast paths ([`Os::try_tick`], then [`Os::try_tick_due`]), and the whole
    /// ISR where both decline.
    FastTick(IsrId, CounterId),
    /// `ActivateTask` as a port makes it: the kernel's fast path
    /// ([`Os::try_activate_task`]), and the full service where that declines.
    FastActivate(TaskId),
}

impl Service {
    /// The OSEK service this step carries out (the fast lock steps are `GetResource` and
    /// `ReleaseResource`).
    pub const fn as_osek(self) -> Self {
        match self {
            Self::FastGet(r) => Self::Call(ServiceCall::GetResource(r)),
            Self::FastRelease(r) => Self::Call(ServiceCall::ReleaseResource(r)),
            Self::FastTick(isr, c) => Self::Isr(isr, ServiceCall::IncrementCounter(c)),
            Self::FastActivate(t) => Self::Call(ServiceCall::ActivateTask(t)),
            s => s,
        }
    }
}

/// Performs one [`Service`] on the kernel.
///
/// # Errors
/// The status of the step (for a whole ISR: of its entry, else of its call).
pub fn call<
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
    service: Service,
) -> Result<Returned, OsError>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    match service {
        Service::Call(c) => perform(os, c),
        Service::EnterIsr(isr) => os.enter_isr(isr).map(|()| Returned::Nothing),
        Service::ExitIsr => os.exit_isr().map(|()| Returned::Nothing),
        Service::Isr(isr, c) => {
            os.enter_isr(isr)?;
            let result = perform(os, c);
            // The ISR returns whatever its call did (after a ShutdownOS nothing is left).
            let _ = os.exit_isr();
            result
        }
        Service::TaskReturn => os.task_returned().map(|()| Returned::Nothing),
        Service::FastGet(r) => match os.try_get_resource(r) {
            Some(_) => Ok(Returned::Nothing),
            None => os.get_resource(r).map(|()| Returned::Nothing),
        },
        Service::FastRelease(r) => match os.try_release_resource(r) {
            Some(_) => Ok(Returned::Nothing),
            None => os.release_resource(r).map(|()| Returned::Nothing),
        },
        Service::FastTick(isr, c) => match os.try_tick(isr, c) {
            Some(_) => Ok(Returned::Nothing),
            None => match os.try_tick_due(isr, c) {
                Some(_) => Ok(Returned::Nothing),
                None => call(os, service.as_osek()),
            },
        },
        Service::FastActivate(t) => match os.try_activate_task(t) {
            Some(_) => Ok(Returned::Nothing),
            None => os.activate_task(t).map(|()| Returned::Nothing),
        },
    }
}

/// The contract of the kernel's fast paths ([`Os::try_get_resource`],
/// [`Os::try_release_resource`], [`Os::try_tick`] and [`Os::try_tick_due`],
/// [`Os::try_activate_task`]), for a
/// [`Service::FastGet`], [`Service::FastRelease`], [`Service::FastTick`] or
/// [`Service::FastActivate`] step from `before` (any other step agrees trivially): where
/// the fast path takes the step, it leaves exactly the state the full service (or whole
/// ISR) leaves, that succeeds, and the level the fast path returns gives the kernel's
/// interrupt mask (the activation's: the kernel's whole view, [`Os::port_view`]), and
/// after a lock nothing may be locked outside the kernel ([`Os::lock_free_resources`] is
/// empty: a port need not ask); where it declines, it changed nothing. (So every rule and invariant proved of the services holds of the
/// fast paths.)
///
/// # Errors
/// Which part of the contract is broken.
pub fn fast_path_agrees<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    service: Service,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let (mut fast, mut full) = (*before, *before);
    let (taken, served) = match service {
        Service::FastGet(r) => (fast.try_get_resource(r), full.get_resource(r)),
        Service::FastRelease(r) => (fast.try_release_resource(r), full.release_resource(r)),
        // The tick's two fast paths in the order a port tries them: where nothing is due,
        // then where alarms are.
        Service::FastTick(isr, c) => (
            fast.try_tick(isr, c).or_else(|| fast.try_tick_due(isr, c)),
            call(&mut full, service.as_osek()).map(|_| ()),
        ),
        Service::FastActivate(t) => {
            let view = fast.try_activate_task(t);
            let served = full.activate_task(t);
            return match view {
                None if fast != *before => Err("a declined fast path changed the state"),
                None => Ok(()),
                Some(_) if served.is_err() => Err("the fast path took a step the service refuses"),
                Some(_) if fast != full => Err("the fast path left another state than the service"),
                Some(view) if view != full.port_view() => {
                    Err("the fast path's view is not the kernel's (its mask, the locks outside it)")
                }
                Some(_) => Ok(()),
            };
        }
        _ => return Ok(()),
    };
    match taken {
        None if fast != *before => Err("a declined fast path changed the state"),
        None => Ok(()),
        Some(_) if served.is_err() => Err("the fast path took a step the service refuses"),
        Some(_) if fast != full => Err("the fast path left another state than the service"),
        Some(level) if InterruptMask::at_level(level) != full.interrupt_mask() => {
            Err("the fast path's level is not the kernel's interrupt mask")
        }
        // A port that took a lock by the fast path knows, without asking, that nothing
        // may now be locked outside the kernel (the caller holds a resource).
        Some(_) if matches!(service, Service::FastGet(_)) && fast.lock_free_resources() != 0 => {
            Err("after the lock's fast path a resource may be locked outside the kernel")
        }
        Some(_) => Ok(()),
    }
}

/// The contract a port relies on when it keeps a task's lock outside the kernel until
/// the task's next kernel call ([`Os::lock_free_resources`]): where that names `res`, by
/// the bit of the kind of lock its ceiling makes ([`crate::os::lock_free_bit`]: masking
/// nothing below interrupt level, else masking the ISRs up to the ceiling), it is a user
/// resource the running task declares, the running task is at task level with
/// nothing held and no interrupt lock, so that the kernel masks no interrupt; the lock's
/// fast path takes it and masks what the resource's ceiling ([`Os::ceiling`]) masks (the
/// ISRs that share it and those below: the mask the port applies itself), the
/// release's fast path right after takes that too and masks nothing again, and the two
/// leave the state they found. So a pair the kernel never sees (no kernel call between
/// the two) is one it would have left no trace of, with the masks the port applied, and
/// a kernel call in between, which hands the lock to the kernel first, sees the state the
/// lock would have made.
///
/// # Errors
/// Which part of the contract is broken.
pub fn lock_pair_leaves_no_trace<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    res: ResourceId,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let answer = before.lock_free_resources();
    let unmasked_bit = answer & crate::os::lock_free_bit(res, false) != 0;
    let masked_bit = answer & crate::os::lock_free_bit(res, true) != 0;
    if !unmasked_bit && !masked_bit {
        return Ok(());
    }
    // The bit says which kind of lock: one that masks nothing exactly where the ceiling
    // is a task's level (a port takes that one with no table of ceilings).
    let isr_ceiling = before
        .ceiling(res)
        .is_some_and(|c| c >= crate::os::ISR_LEVEL_BASE);
    if unmasked_bit == masked_bit || masked_bit != isr_ceiling {
        return Err("the answer names the resource as the other kind of lock than its ceiling");
    }
    // What the mask names, by the definitions: the running task at task level, holding
    // nothing, no interrupt lock, masking nothing; `res` one of its own resources.
    let running = before.running().map(|t| usize::from(t.0));
    let task = running.and_then(|t| before.config().tasks().get(t));
    let declared = task.is_some_and(|t| t.resources & (1u32 << res.0) != 0);
    let alone = at_task_level(before)
        && !before.locks().any()
        && running.is_some_and(|t| before.held_resources(TaskId(t as u8)).next().is_none());
    let unmasked = before.interrupt_mask() == InterruptMask::None;
    if res == RES_SCHEDULER || !declared || !alone || !unmasked {
        return Err("the mask names a resource the task may not lock outside the kernel");
    }
    let mut os = *before;
    let Some(level) = os.try_get_resource(res) else {
        return Err("the lock's fast path declined a lock the port may take outside the kernel");
    };
    if Some(level) != before.ceiling(res) || os.masked_level() != level {
        return Err("the lock's fast path masks another level than the resource's ceiling");
    }
    let Some(level) = os.try_release_resource(res) else {
        return Err("the release's fast path declined the release right after the lock");
    };
    if InterruptMask::at_level(level) != InterruptMask::None {
        return Err("the release's fast path left an interrupt masked");
    }
    if os != *before {
        return Err("a lock and its release left another state than they found");
    }
    Ok(())
}

/// The contract of [`Os::try_ticks`]: `ticks` ticks at once are taken exactly when each
/// of `ticks` successive [`Os::try_tick`] calls would be, and leave the state those leave,
/// with the same level; declined, they change nothing.
///
/// # Errors
/// Which part of the contract is broken.
pub fn ticks_agree<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    isr: IsrId,
    counter: CounterId,
    ticks: u64,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let mut at_once = *before;
    let taken = at_once.try_ticks(isr, counter, ticks);
    let mut one_by_one = *before;
    let mut level = None;
    let mut each = ticks > 0;
    for _ in 0..ticks {
        level = one_by_one.try_tick(isr, counter);
        if level.is_none() {
            each = false;
            break;
        }
    }
    match taken {
        None if at_once != *before => Err("declined ticks changed the state"),
        None if each => Err("ticks the fast path takes one by one were declined at once"),
        None => Ok(()),
        Some(_) if !each => Err("ticks were taken at once that one by one are not"),
        Some(_) if at_once != one_by_one => Err("ticks at once left another state"),
        Some(l) if Some(l) != level => Err("ticks at once gave another level"),
        Some(_) => Ok(()),
    }
}

/// Whether two kernels are in the same state apart from the hooks' data.
pub fn same_kernel_state<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    a: &Os<T, R, C, A, I, Q, K, H>,
    b: &Os<T, R, C, A, I, Q, K, H>,
) -> bool
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let mut a = *a;
    *a.hooks_mut() = *b.hooks();
    a == *b
}

/// Whether the sequence `prefix` is a prefix of `seq`.
fn starts_with<It: PartialEq>(
    mut seq: impl Iterator<Item = It>,
    prefix: impl Iterator<Item = It>,
) -> bool {
    prefix.into_iter().all(|p| seq.next() == Some(p))
}

/// FIFO within a priority, per queue: after = [preempted task]? ++ (before, less at most
/// its head) ++ new entries at the tail. At most one entry leaves all queues per call, and
/// it is the task now running; only a preempted task goes to a head.
pub fn fifo_discipline<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    after: &Os<T, R, C, A, I, Q, K, H>,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    if after.phase() == Phase::ShutDown {
        return Ok(());
    }
    let preempted = before.running().filter(|r| {
        after.running() != Some(*r)
            && !after.is_waiting(*r)
            && before.is_started(*r)
            && after.is_started(*r)
    });
    let mut dispatched = 0;
    let mut levels = before.ready_bitmap() | after.ready_bitmap();
    // Each queue has at most `Q` non-empty priorities (one record each at least).
    for _ in 0..2 * Q {
        if levels == 0 {
            break;
        }
        let p = levels.trailing_zeros() as u8;
        levels &= levels - 1;
        let mut new = after.ready_at(p).peekable();
        if let Some(r) = preempted.filter(|r| after.saved_priority(*r) == Some(p)) {
            if new.next() != Some(r) {
                return Err("a preempted task is not the oldest of its priority");
            }
        }
        // Either every old entry is still there, in order, at the front ...
        if starts_with(new.clone(), before.ready_at(p)) {
            continue;
        }
        // ... or the old head was dispatched and the rest kept their order.
        let head = before.ready_at(p).next();
        if head.is_some() && starts_with(new, before.ready_at(p).skip(1)) {
            if after.running() != head {
                return Err("an entry left a ready queue without being dispatched");
            }
            dispatched += 1;
            continue;
        }
        return Err("a ready queue lost its order (not FIFO)");
    }
    if dispatched > 1 {
        return Err("more than one task was dispatched by one call");
    }
    Ok(())
}

/// The `ActivateTask` carried out by a step, if any.
fn activation(service: Service) -> Option<TaskId> {
    match service {
        Service::Call(ServiceCall::ActivateTask(t))
        | Service::Isr(_, ServiceCall::ActivateTask(t)) => Some(t),
        _ => None,
    }
}

/// The rules of one step, judged from the states before and after it and its result:
/// - a refused step changes nothing but the hooks' data;
/// - `ActivateTask` fails with `E_OS_LIMIT` exactly at the limit and otherwise adds one
///   activation;
/// - `ReleaseResource` succeeds only for the most recently taken resource and restores the
///   caller's priority to the ceiling of what it still holds; `GetResource` raises it to
///   the ceiling;
/// - a waiting task becomes ready exactly when an event it waits for is set;
/// - an ISR is entered only when the interrupt mask admits it;
/// - no task switch happens while an ISR stays active or an interrupt lock stays in force;
/// - FIFO discipline ([`fifo_discipline`]).
pub fn transition_rules<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    after: &Os<T, R, C, A, I, Q, K, H>,
    service: Service,
    result: Result<Returned, OsError>,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let service = service.as_osek();
    let caller = (before.context() == Context::Task)
        .then(|| before.running())
        .flatten();
    let composite = matches!(service, Service::Isr(..));
    if result.is_err() && !composite && !same_kernel_state(before, after) {
        return Err("a refused service changed the state");
    }
    if let Some(t) = activation(service) {
        if let Some(task) = before.config().tasks().get(t.0 as usize) {
            let had = before.activation_count(t);
            match result {
                Ok(_) if after.activation_count(t) != had + 1 => {
                    return Err("an activation was lost")
                }
                Err(OsError::Limit) if had != task.max_activations => {
                    return Err("E_OS_LIMIT below the limit")
                }
                // Any other refusal came before the activation (call level, a lock, the
                // interrupt mask), and changed nothing (checked above).
                _ => {}
            }
        } else if result.is_ok() {
            return Err("ActivateTask of an invalid task succeeded");
        }
    }
    if let (Service::Call(ServiceCall::ReleaseResource(r)), Ok(_), Some(t)) =
        (service, result, caller)
    {
        if before.held_resources(t).next() != Some(r) {
            return Err("a resource was released out of LIFO order");
        }
        let mut expected = after.dispatch_priority(t).unwrap_or(0);
        for held in after.held_resources(t) {
            expected = expected.max(after.ceiling(held).unwrap_or(0));
        }
        let now = if after.running() == Some(t) {
            after.running_priority()
        } else {
            after.saved_priority(t)
        };
        if now != Some(expected) {
            return Err("ReleaseResource did not restore the priority");
        }
    }
    if let (Service::Call(ServiceCall::GetResource(r)), Ok(_), Some(_)) = (service, result, caller)
    {
        let ceiling = after.ceiling(r).unwrap_or(0);
        if after.running_priority() != before.running_priority().map(|p| p.max(ceiling)) {
            return Err("GetResource did not raise the priority to the ceiling");
        }
    }
    for t in (0..T as u8).map(TaskId) {
        let was = before.is_waiting(t);
        let released = was && !after.is_waiting(t);
        let event_arrived = after.events(t) & before.wait_mask(t) != 0;
        if after.phase() != Phase::ShutDown && released && !event_arrived {
            return Err("a waiting task was released without its event");
        }
        if was && event_arrived && !released {
            return Err("a waited event was set but the task still waits");
        }
    }
    if let Service::EnterIsr(isr) | Service::Isr(isr, _) = service {
        let admitted = before
            .config()
            .isrs()
            .get(isr.0 as usize)
            .is_some_and(|c| before.interrupt_mask().admits(c.priority));
        let entered = match service {
            Service::EnterIsr(_) => result.is_ok(),
            _ => !same_kernel_state(before, after),
        };
        if entered && !admitted {
            return Err("an ISR was entered although the interrupt mask held it");
        }
    }
    if after.phase() != Phase::ShutDown && after.running() != before.running() {
        if before.isr_nesting() > 0 && after.isr_nesting() > 0 {
            return Err("a task switch happened while an ISR was active");
        }
        if before.locks().any() && after.locks().any() {
            return Err("a task switch happened while interrupts were disabled");
        }
    }
    fifo_discipline(before, after)
}

/// The contracts of the paths a port takes instead of `service` from `before`: the fast
/// paths' ([`fast_path_agrees`]) and, for a lock, that of a lock kept outside the kernel
/// ([`lock_pair_leaves_no_trace`]). The harnesses, the step sequences and the models
/// check them on every step.
///
/// # Errors
/// The first contract broken.
pub fn step_contracts<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K,
    H,
>(
    before: &Os<T, R, C, A, I, Q, K, H>,
    service: Service,
) -> Result<(), &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    fast_path_agrees(before, service)?;
    if let Service::FastGet(res) | Service::Call(ServiceCall::GetResource(res)) = service {
        lock_pair_leaves_no_trace(before, res)?;
    }
    Ok(())
}

/// Performs `service` and checks [`step_contracts`], [`transition_rules`] and
/// [`kernel_invariants`].
///
/// # Errors
/// The first rule or invariant broken.
pub fn call_and_check<
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
    service: Service,
) -> Result<Result<Returned, OsError>, &'static str>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Os<T, R, C, A, I, Q, K, H>>,
{
    let before = *os;
    step_contracts(&before, service)?;
    let result = call(os, service);
    transition_rules(&before, os, service, result)?;
    if !kernel_invariants(os) {
        return Err("a kernel invariant is broken");
    }
    Ok(result)
}
