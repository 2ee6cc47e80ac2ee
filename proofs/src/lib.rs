//! Model checking of the OSEK scheduler in `cw-core`.
//!
//! [`OsModel`] is a stateright model whose state *is* the real kernel
//! ([`cw_core::os::Os`]) and whose transitions call the real services: nothing about the
//! scheduler is re-implemented here. Every reachable state of a configuration, under every
//! interleaving of task-level service calls and interrupts (timer ticks, activations from
//! an ISR), is explored breadth first.
//!
//! Checked in every state (the `cw_core::os::spec` predicates):
//! - the running task is a highest-priority ready task, its priority raised exactly to the
//!   ceilings it holds (so no task excluded by a ceiling runs);
//! - activations are neither lost nor invented and never exceed the limit;
//! - resource stacks are consistent; waiting tasks wait for something not yet set.
//!
//! Checked on every transition (recorded as a violation in the next state):
//! - FIFO within a priority: each ready queue keeps its old entries in order, loses at most
//!   its head (to the dispatcher), gains new entries only at its tail, and only a preempted
//!   task goes to its head;
//! - `ActivateTask` fails with `E_OS_LIMIT` exactly at the limit, and succeeds otherwise,
//!   adding one activation;
//! - `ReleaseResource` succeeds only for the most recently taken resource and restores the
//!   caller's priority to the ceiling of what it still holds; `GetResource` raises it;
//! - a waiting task becomes ready exactly when an event it waits for is set;
//! - a refused service leaves the state unchanged.

use cw_core::os::{
    spec, CounterId, EventMask, Os, OsConfig, OsError, ResourceId, TaskId, TaskKind, RES_SCHEDULER,
};
use stateright::{Model, Property};
use std::fmt::Debug;

/// One step: a service called by the running task, or an interrupt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Step {
    /// The running task calls `ActivateTask`.
    Activate(TaskId),
    /// The running task calls `TerminateTask`.
    Terminate,
    /// The running task calls `ChainTask`.
    Chain(TaskId),
    /// The running task calls `Schedule`.
    Schedule,
    /// The running task calls `GetResource`.
    GetResource(ResourceId),
    /// The running task calls `ReleaseResource`.
    ReleaseResource(ResourceId),
    /// The running task calls `SetEvent`.
    SetEvent(TaskId, EventMask),
    /// The running task calls `ClearEvent`.
    ClearEvent(EventMask),
    /// The running task calls `WaitEvent`.
    WaitEvent(EventMask),
    /// A timer ISR calls `IncrementCounter`.
    Tick(CounterId),
    /// An ISR calls `ActivateTask`.
    IsrActivate(TaskId),
    /// An ISR calls `SetEvent`.
    IsrSetEvent(TaskId, EventMask),
}

/// A state of the model: the kernel, plus the first transition check that failed, if any.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ModelState<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> {
    /// The real kernel.
    pub os: Os<T, R, C, A, Q>,
    /// A broken transition rule (exploration stops there and the property reports it).
    pub violation: Option<&'static str>,
}

/// The model of one configuration.
pub struct OsModel<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> {
    /// Name for reports.
    pub name: &'static str,
    /// The configuration under test.
    pub cfg: &'static OsConfig<T, R, C, A>,
    /// Event masks used in `SetEvent`/`ClearEvent`/`WaitEvent` steps.
    pub event_masks: &'static [EventMask],
    /// Whether ISRs may activate tasks and set events (besides the alarms' own actions).
    pub isr_services: bool,
    /// `(caller, target)`: tasks that activate another as part of their normal behaviour
    /// (the sonar task activating the Com task on data received).
    pub activations: &'static [(TaskId, TaskId)],
    /// Whether tasks may call services beyond terminating and their configured resources:
    /// every activation, chaining, `Schedule`, every resource (including misuse).
    pub adversarial: bool,
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> OsModel<T, R, C, A, Q> {
    fn tasks(&self) -> impl Iterator<Item = TaskId> {
        (0..T as u8).map(TaskId)
    }

    fn resources(&self) -> impl Iterator<Item = ResourceId> {
        (0..R as u8).map(ResourceId).chain(std::iter::once(RES_SCHEDULER))
    }

    fn run(os: &mut Os<T, R, C, A, Q>, step: Step) -> Result<(), OsError> {
        match step {
            Step::Activate(t) => os.activate_task(t),
            Step::Terminate => os.terminate_task(),
            Step::Chain(t) => os.chain_task(t),
            Step::Schedule => os.schedule(),
            Step::GetResource(r) => os.get_resource(r),
            Step::ReleaseResource(r) => os.release_resource(r),
            Step::SetEvent(t, m) => os.set_event(t, m),
            Step::ClearEvent(m) => os.clear_event(m),
            Step::WaitEvent(m) => os.wait_event(m),
            Step::Tick(c) => Self::in_isr(os, |os| os.increment_counter(c).map(|_| ())),
            Step::IsrActivate(t) => Self::in_isr(os, |os| os.activate_task(t)),
            Step::IsrSetEvent(t, m) => Self::in_isr(os, |os| os.set_event(t, m)),
        }
    }

    /// Runs `service` inside a category-2 ISR: rescheduling happens at the ISR's exit.
    fn in_isr(
        os: &mut Os<T, R, C, A, Q>,
        service: impl FnOnce(&mut Os<T, R, C, A, Q>) -> Result<(), OsError>,
    ) -> Result<(), OsError> {
        os.enter_isr()?;
        let result = service(os);
        os.exit_isr()?;
        result
    }

    /// The transition rules; returns the first one broken.
    pub(crate) fn check_transition(
        &self,
        before: &Os<T, R, C, A, Q>,
        after: &Os<T, R, C, A, Q>,
        step: Step,
        result: Result<(), OsError>,
    ) -> Option<&'static str> {
        let caller = before.running();
        let is_isr_step = matches!(step, Step::Tick(_) | Step::IsrActivate(_) | Step::IsrSetEvent(..));
        if result.is_err() && !is_isr_step && after != before {
            return Some("a refused service changed the state");
        }
        // Activation limit.
        if let Step::Activate(t) | Step::IsrActivate(t) = step {
            let max = self.cfg.tasks()[t.0 as usize].max_activations;
            let had = before.activation_count(t);
            match result {
                Err(OsError::Limit) if had != max => return Some("E_OS_LIMIT below the limit"),
                Err(OsError::Limit) => {}
                Ok(()) if after.activation_count(t) != had + 1 => return Some("an activation was lost"),
                Ok(()) => {}
                Err(_) => return Some("ActivateTask failed for another reason"),
            }
        }
        // Resources: LIFO release, priority restored; take raises to the ceiling.
        if let (Step::ReleaseResource(r), Ok(()), Some(t)) = (step, result, caller) {
            if before.held_resources(t).next() != Some(r) {
                return Some("a resource was released out of LIFO order");
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
                return Some("ReleaseResource did not restore the priority");
            }
        }
        if let (Step::GetResource(r), Ok(()), Some(_)) = (step, result, caller) {
            let ceiling = after.ceiling(r).unwrap_or(0);
            if after.running_priority() != before.running_priority().map(|p| p.max(ceiling)) {
                return Some("GetResource did not raise the priority to the ceiling");
            }
        }
        // Waiting -> ready exactly when a waited event is set.
        for t in self.tasks() {
            let was = before.is_waiting(t);
            let waited = before.wait_mask(t);
            let released = was && !after.is_waiting(t);
            let event_arrived = after.events(t) & waited != 0;
            if released && !event_arrived {
                return Some("a waiting task was released without its event");
            }
            if was && event_arrived && !released {
                return Some("a waited event was set but the task still waits");
            }
        }
        if let Some(rule) = self.check_fifo(before, after) {
            return Some(rule);
        }
        None
    }

    /// Queue discipline per priority: after = [preempted]? ++ (before minus at most its head)
    /// ++ new entries; at most one entry leaves all queues, and it is the task now running.
    pub(crate) fn check_fifo(&self, before: &Os<T, R, C, A, Q>, after: &Os<T, R, C, A, Q>) -> Option<&'static str> {
        let preempted = before.running().filter(|r| {
            after.running() != Some(*r) && !after.is_waiting(*r) && before.is_started(*r) && after.is_started(*r)
        });
        let mut removed = 0;
        for p in 0..=cw_core::os::MAX_PRIORITY {
            let old: Vec<TaskId> = before.ready_at(p).collect();
            let mut new: Vec<TaskId> = after.ready_at(p).collect();
            if old.is_empty() && new.is_empty() {
                continue;
            }
            if let Some(r) = preempted {
                if after.saved_priority(r) == Some(p) {
                    if new.first() != Some(&r) {
                        return Some("a preempted task is not the oldest of its priority");
                    }
                    new.remove(0);
                }
            }
            // Old entries keep their order at the front; anything after them is new (tail).
            if new.len() >= old.len() && new[..old.len()] == old[..] {
                continue;
            }
            if !old.is_empty() && new.len() >= old.len() - 1 && new[..old.len() - 1] == old[1..] {
                removed += 1;
                if after.running() != Some(old[0]) {
                    return Some("an entry left a ready queue without being dispatched");
                }
            } else {
                return Some("a ready queue lost its order (not FIFO)");
            }
        }
        if removed > 1 {
            return Some("more than one task was dispatched in one step");
        }
        None
    }
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> Model for OsModel<T, R, C, A, Q> {
    type State = ModelState<T, R, C, A, Q>;
    type Action = Step;

    fn init_states(&self) -> Vec<Self::State> {
        let Ok(mut os) = Os::<T, R, C, A, Q>::new(self.cfg) else {
            return Vec::new();
        };
        let violation = os.start().err().map(|_| "StartOS failed");
        vec![ModelState { os, violation }]
    }

    fn actions(&self, state: &Self::State, actions: &mut Vec<Self::Action>) {
        if state.violation.is_some() {
            return;
        }
        let os = &state.os;
        for c in 0..C as u8 {
            actions.push(Step::Tick(CounterId(c)));
        }
        if self.isr_services {
            for t in self.tasks() {
                actions.push(Step::IsrActivate(t));
                if self.cfg.tasks()[t.0 as usize].kind == TaskKind::Extended {
                    for &m in self.event_masks {
                        actions.push(Step::IsrSetEvent(t, m));
                    }
                }
            }
        }
        let Some(running) = os.running() else {
            return;
        };
        let me = &self.cfg.tasks()[running.0 as usize];
        actions.push(Step::Terminate);
        // The resources the task declares, taken and released; all of them when adversarial.
        for r in self.resources() {
            let declared = r == RES_SCHEDULER || (me.resources >> r.0) & 1 == 1;
            if declared || self.adversarial {
                actions.push(Step::GetResource(r));
                actions.push(Step::ReleaseResource(r));
            }
        }
        for &(caller, target) in self.activations {
            if caller == running {
                actions.push(Step::Activate(target));
            }
        }
        if me.kind == TaskKind::Extended {
            for &m in self.event_masks {
                actions.push(Step::WaitEvent(m));
                actions.push(Step::ClearEvent(m));
            }
        }
        if self.adversarial {
            actions.push(Step::Schedule);
            for t in self.tasks() {
                actions.push(Step::Activate(t));
                actions.push(Step::Chain(t));
                if self.cfg.tasks()[t.0 as usize].kind == TaskKind::Extended {
                    for &m in self.event_masks {
                        actions.push(Step::SetEvent(t, m));
                    }
                }
            }
        }
    }

    fn next_state(&self, last: &Self::State, step: Self::Action) -> Option<Self::State> {
        let mut os = last.os;
        let result = Self::run(&mut os, step);
        let violation = self.check_transition(&last.os, &os, step, result);
        Some(ModelState { os, violation })
    }

    fn properties(&self) -> Vec<Property<Self>> {
        vec![
            Property::always("transition rules hold (FIFO, limits, LIFO, events)", |_, s: &Self::State| {
                s.violation.is_none()
            }),
            Property::always("running task is a highest-priority ready task", |_, s: &Self::State| {
                spec::running_is_highest_ready(&s.os) && spec::running_priority_is_ceiling(&s.os)
            }),
            Property::always("activations accounted, never above the limit", |_, s: &Self::State| {
                spec::activations_accounted(&s.os)
            }),
            Property::always("resource stacks consistent", |_, s: &Self::State| {
                spec::resources_consistent(&s.os)
            }),
            Property::always("waiting tasks are blocked on unset events", |_, s: &Self::State| {
                spec::waiting_is_blocked(&s.os)
            }),
            // Reachability: the checks above are not vacuous.
            Property::sometimes("a task is preempted", |_, s: &Self::State| {
                (0..=cw_core::os::MAX_PRIORITY).any(|p| s.os.ready_at(p).any(|t| s.os.is_started(t)))
            }),
            Property::sometimes("two activations are queued at one priority", |_, s: &Self::State| {
                (0..=cw_core::os::MAX_PRIORITY).any(|p| s.os.ready_at(p).nth(1).is_some())
            }),
        ]
    }
}

/// Outcome of checking one model.
#[derive(Debug)]
pub struct Outcome {
    /// Model name.
    pub name: &'static str,
    /// Distinct states explored.
    pub unique_states: usize,
    /// States generated (with repeats).
    pub states: usize,
    /// Properties that failed or whose example was not found, with the path to it.
    pub failures: Vec<String>,
}

/// Explores the whole state space of `model` and checks its properties.
pub fn check<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    model: OsModel<T, R, C, A, Q>,
    threads: usize,
) -> Outcome {
    use stateright::Checker;
    let name = model.name;
    let properties = model.properties();
    let checker = model.checker().threads(threads).spawn_bfs().join();
    let discoveries = checker.discoveries();
    let mut failures = Vec::new();
    for p in properties {
        let found = discoveries.get(p.name);
        let failed = match p.expectation {
            stateright::Expectation::Always | stateright::Expectation::Eventually => found.is_some(),
            stateright::Expectation::Sometimes => found.is_none(),
        };
        if failed {
            let path = found.map(|path| format!("{:?}", path.clone().into_actions())).unwrap_or_default();
            failures.push(format!("{}: {:?} {}", p.name, p.expectation, path));
        }
    }
    Outcome {
        name,
        unique_states: checker.unique_state_count(),
        states: checker.state_count(),
        failures,
    }
}

pub mod configs;

#[cfg(test)]
mod tests;

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> Debug for OsModel<T, R, C, A, Q> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}
