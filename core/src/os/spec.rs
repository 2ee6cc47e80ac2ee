//! Named predicates: the scheduler's contract, stated over the kernel's public inspection
//! methods. The harnesses in this crate, the fuzz targets, the stateright model in
//! `proofs/` and `debug_assert!`s inside the kernel all execute these same functions.

use super::{Os, ResourceId, TaskId, TaskKind, RES_SCHEDULER};

/// OSEK §4.6: at task level, the running task has the highest priority among ready
/// activations (ties go to the running task); with nothing running, nothing is ready.
pub fn running_is_highest_ready<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
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
pub fn running_priority_is_ceiling<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
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
pub fn activations_accounted<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
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
pub fn resources_consistent<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
) -> bool {
    let ids = (0..R as u8).map(ResourceId).chain(core::iter::once(RES_SCHEDULER));
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
    (0..T as u8).map(TaskId).all(|t| os.held_resources(t).all(|r| os.resource_owner(r) == Some(t)))
}

/// Waiting tasks are extended and wait for something not yet set. (`WaitEvent(0)` is legal
/// in OSEK and waits forever, so an empty mask is allowed.)
pub fn waiting_is_blocked<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
) -> bool {
    (0..T).all(|t| {
        let id = TaskId(t as u8);
        !os.is_waiting(id)
            || (os.config().tasks()[t].kind == TaskKind::Extended
                && os.events(id) & os.wait_mask(id) == 0)
    })
}

/// All of the above.
pub fn kernel_invariants<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    os: &Os<T, R, C, A, Q>,
) -> bool {
    running_is_highest_ready(os)
        && running_priority_is_ceiling(os)
        && activations_accounted(os)
        && resources_consistent(os)
        && waiting_is_blocked(os)
}
