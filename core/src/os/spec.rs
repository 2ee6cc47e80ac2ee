//! Named predicates: the scheduler's contract, stated over the kernel's public inspection
//! methods. The harnesses in this crate, the fuzz targets, the stateright model in
//! `proofs/` and `debug_assert!`s inside the kernel all execute these same functions.

use super::OsConfig;
use super::{
    AlarmId, CounterId, EventMask, Os, OsError, ResourceId, TaskId, TaskKind, TickType,
    RES_SCHEDULER,
};
use crate::tables::Tables;

/// OSEK §4.6: at task level, the running task has the highest priority among ready
/// activations (ties go to the running task); with nothing running, nothing is ready.
pub fn running_is_highest_ready<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    if os.isr_depth() != 0 {
        return true;
    }
    match (os.running_priority(), os.highest_ready()) {
        (_, None) => true,
        (None, Some(_)) => false,
        (Some(running), Some(ready)) => ready <= running,
    }
}

/// Immediate priority ceiling: the running task's priority is exactly the highest of its
/// dispatch priority and the ceilings of the resources it holds.
pub fn running_priority_is_ceiling<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    let Some(task) = os.running() else {
        return true;
    };
    let mut expected = os.dispatch_priority(task).unwrap_or(0);
    for res in os.held_resources(task) {
        let ceiling = os.ceiling(res).unwrap_or(0);
        if ceiling > expected {
            expected = ceiling;
        }
    }
    os.running_priority() == Some(expected)
}

/// No activation is lost or invented: for every task, ready records plus the running or
/// waiting instance equal its activation count, which never exceeds the configured limit.
pub fn activations_accounted<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    (0..T).all(|t| {
        let id = TaskId(t as u8);
        let on_cpu = usize::from(os.running() == Some(id)) + usize::from(os.is_waiting(id));
        let count = os.activation_count(id);
        count <= os.config().tasks()[t].max_activations
            && os.queued_records(id) + on_cpu == usize::from(count)
            && on_cpu <= 1
    })
}

/// Resources: each held resource has exactly one owner, it appears exactly once on that
/// owner's stack, its ceiling is at least the owner's priority, and only tasks that have
/// started hold resources. Waiting tasks hold none.
pub fn resources_consistent<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    let ids = (0..R as u8)
        .map(ResourceId)
        .chain(core::iter::once(RES_SCHEDULER));
    for res in ids {
        if let Some(owner) = os.resource_owner(res) {
            if !os.is_started(owner) || os.is_waiting(owner) {
                return false;
            }
            if os.held_resources(owner).filter(|r| *r == res).count() != 1 {
                return false;
            }
            let base = os.config().tasks()[owner.0 as usize].priority;
            if os.ceiling(res).unwrap_or(0) < base {
                return false;
            }
        }
    }
    (0..T as u8).map(TaskId).all(|t| {
        os.held_resources(t)
            .all(|r| os.resource_owner(r) == Some(t))
    })
}

/// Waiting tasks are extended and wait for something not yet set. (`WaitEvent(0)` is legal
/// in OSEK and waits forever, so an empty mask is allowed.)
pub fn waiting_is_blocked<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    (0..T).all(|t| {
        let id = TaskId(t as u8);
        !os.is_waiting(id)
            || (os.config().tasks()[t].kind == TaskKind::Extended
                && os.events(id) & os.wait_mask(id) == 0)
    })
}

/// All of the above.
pub fn kernel_invariants<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &Os<T, R, C, A, Q, K>,
) -> bool {
    running_is_highest_ready(os)
        && running_priority_is_ceiling(os)
        && activations_accounted(os)
        && resources_consistent(os)
        && waiting_is_blocked(os)
}

/// One call into the kernel: a service at the current call level, or a whole category-2
/// ISR that calls one service (entered, run, left: rescheduling happens at its exit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Service {
    /// `ActivateTask`.
    ActivateTask(TaskId),
    /// `TerminateTask`.
    TerminateTask,
    /// `ChainTask`.
    ChainTask(TaskId),
    /// `Schedule`.
    Schedule,
    /// `SetEvent`.
    SetEvent(TaskId, EventMask),
    /// `ClearEvent`.
    ClearEvent(EventMask),
    /// `WaitEvent`.
    WaitEvent(EventMask),
    /// `GetResource`.
    GetResource(ResourceId),
    /// `ReleaseResource`.
    ReleaseResource(ResourceId),
    /// `SetRelAlarm`.
    SetRelAlarm(AlarmId, TickType, TickType),
    /// `SetAbsAlarm`.
    SetAbsAlarm(AlarmId, TickType, TickType),
    /// `CancelAlarm`.
    CancelAlarm(AlarmId),
    /// `IncrementCounter` at the current level.
    IncrementCounter(CounterId),
    /// Enter interrupt level.
    EnterIsr,
    /// Leave interrupt level.
    ExitIsr,
    /// A timer ISR: `IncrementCounter` inside an ISR.
    IsrTick(CounterId),
    /// An ISR that calls `ActivateTask`.
    IsrActivateTask(TaskId),
    /// An ISR that calls `SetEvent`.
    IsrSetEvent(TaskId, EventMask),
}

impl Service {
    /// Whether this is a whole ISR (whose inner service may fail without undoing the
    /// ISR's own entry and exit).
    pub const fn is_isr(self) -> bool {
        matches!(
            self,
            Self::IsrTick(_) | Self::IsrActivateTask(_) | Self::IsrSetEvent(..)
        )
    }
}

fn in_isr<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize, K>(
    os: &mut Os<T, R, C, A, Q, K>,
    service: impl FnOnce(&mut Os<T, R, C, A, Q, K>) -> Result<(), OsError>,
) -> Result<(), OsError>
where
    K: Tables<OsConfig<T, R, C, A>>,
{
    os.enter_isr()?;
    let result = service(os);
    os.exit_isr()?;
    result
}

/// Performs one [`Service`] on the kernel.
pub fn call<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize, K>(
    os: &mut Os<T, R, C, A, Q, K>,
    service: Service,
) -> Result<(), OsError>
where
    K: Tables<OsConfig<T, R, C, A>>,
{
    match service {
        Service::ActivateTask(t) => os.activate_task(t),
        Service::TerminateTask => os.terminate_task(),
        Service::ChainTask(t) => os.chain_task(t),
        Service::Schedule => os.schedule(),
        Service::SetEvent(t, m) => os.set_event(t, m),
        Service::ClearEvent(m) => os.clear_event(m),
        Service::WaitEvent(m) => os.wait_event(m),
        Service::GetResource(r) => os.get_resource(r),
        Service::ReleaseResource(r) => os.release_resource(r),
        Service::SetRelAlarm(a, inc, cyc) => os.set_rel_alarm(a, inc, cyc),
        Service::SetAbsAlarm(a, start, cyc) => os.set_abs_alarm(a, start, cyc),
        Service::CancelAlarm(a) => os.cancel_alarm(a),
        Service::IncrementCounter(c) => os.increment_counter(c).map(|_| ()),
        Service::EnterIsr => os.enter_isr(),
        Service::ExitIsr => os.exit_isr(),
        Service::IsrTick(c) => in_isr(os, |os| os.increment_counter(c).map(|_| ())),
        Service::IsrActivateTask(t) => in_isr(os, |os| os.activate_task(t)),
        Service::IsrSetEvent(t, m) => in_isr(os, |os| os.set_event(t, m)),
    }
}

/// Whether the sequence `prefix` is a prefix of `seq`.
fn starts_with<I: PartialEq>(
    mut seq: impl Iterator<Item = I>,
    prefix: impl Iterator<Item = I>,
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
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    before: &Os<T, R, C, A, Q, K>,
    after: &Os<T, R, C, A, Q, K>,
) -> Result<(), &'static str> {
    let preempted = before.running().filter(|r| {
        after.running() != Some(*r)
            && !after.is_waiting(*r)
            && before.is_started(*r)
            && after.is_started(*r)
    });
    let mut dispatched = 0;
    let mut levels = before.ready_bitmap() | after.ready_bitmap();
    while levels != 0 {
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

/// The rules of one call, judged from the states before and after it and its result:
/// a refused service changes nothing; `ActivateTask` fails with `E_OS_LIMIT` exactly at the
/// limit and otherwise adds one activation; `ReleaseResource` succeeds only for the most
/// recently taken resource and restores the caller's priority to the ceiling of what it
/// still holds; `GetResource` raises it to the ceiling; a waiting task becomes ready exactly
/// when an event it waits for is set; FIFO discipline ([`fifo_discipline`]).
pub fn transition_rules<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    before: &Os<T, R, C, A, Q, K>,
    after: &Os<T, R, C, A, Q, K>,
    service: Service,
    result: Result<(), OsError>,
) -> Result<(), &'static str> {
    let caller = if before.isr_depth() == 0 {
        before.running()
    } else {
        None
    };
    if result.is_err()
        && !service.is_isr()
        && !matches!(service, Service::IncrementCounter(_))
        && after != before
    {
        return Err("a refused service changed the state");
    }
    if let Service::ActivateTask(t) | Service::IsrActivateTask(t) = service {
        if let Some(task) = before.config().tasks().get(t.0 as usize) {
            let had = before.activation_count(t);
            match result {
                Err(OsError::Limit) if had != task.max_activations => {
                    return Err("E_OS_LIMIT below the limit")
                }
                Ok(()) if after.activation_count(t) != had + 1 => {
                    return Err("an activation was lost")
                }
                Err(e) if e != OsError::Limit => {
                    return Err("ActivateTask of a valid task failed otherwise")
                }
                _ => {}
            }
        } else if result != Err(OsError::Id) {
            return Err("ActivateTask of an invalid task did not return E_OS_ID");
        }
    }
    if let (Service::ReleaseResource(r), Ok(()), Some(t)) = (service, result, caller) {
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
    if let (Service::GetResource(r), Ok(()), Some(_)) = (service, result, caller) {
        let ceiling = after.ceiling(r).unwrap_or(0);
        if after.running_priority() != before.running_priority().map(|p| p.max(ceiling)) {
            return Err("GetResource did not raise the priority to the ceiling");
        }
    }
    for t in (0..T as u8).map(TaskId) {
        let was = before.is_waiting(t);
        let released = was && !after.is_waiting(t);
        let event_arrived = after.events(t) & before.wait_mask(t) != 0;
        if released && !event_arrived {
            return Err("a waiting task was released without its event");
        }
        if was && event_arrived && !released {
            return Err("a waited event was set but the task still waits");
        }
    }
    fifo_discipline(before, after)
}

/// Performs `service` and checks [`transition_rules`] and [`kernel_invariants`].
pub fn call_and_check<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, R, C, A>>,
>(
    os: &mut Os<T, R, C, A, Q, K>,
    service: Service,
) -> Result<Result<(), OsError>, &'static str> {
    let before = *os;
    let result = call(os, service);
    transition_rules(&before, os, service, result)?;
    if !kernel_invariants(os) {
        return Err("a kernel invariant is broken");
    }
    Ok(result)
}
