//! Model checking of the OSEK scheduler in `cw-core` (this module), and of the ECU's
//! communication modes ([`modes`]).
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
//! Checked on every transition (`cw_core::os::spec::transition_rules`, recorded as a
//! violation in the next state):
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
    spec, CounterId, EventMask, Os, OsConfig, ResourceId, TaskId, TaskKind, RES_SCHEDULER,
};
use stateright::{Model, Property};
use std::fmt::Debug;

/// One step: a service called by the running task, or a whole ISR (timer tick,
/// activation or event from an interrupt).
pub use cw_core::os::spec::Service as Step;

/// A state of the model: the kernel, plus the first transition check that failed, if any.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ModelState<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
> {
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

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>
    OsModel<T, R, C, A, Q>
{
    fn tasks(&self) -> impl Iterator<Item = TaskId> {
        (0..T as u8).map(TaskId)
    }

    fn resources(&self) -> impl Iterator<Item = ResourceId> {
        (0..R as u8)
            .map(ResourceId)
            .chain(std::iter::once(RES_SCHEDULER))
    }
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> Model
    for OsModel<T, R, C, A, Q>
{
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
            actions.push(Step::IsrTick(CounterId(c)));
        }
        if self.isr_services {
            for t in self.tasks() {
                actions.push(Step::IsrActivateTask(t));
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
        actions.push(Step::TerminateTask);
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
                actions.push(Step::ActivateTask(target));
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
                actions.push(Step::ActivateTask(t));
                actions.push(Step::ChainTask(t));
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
        let result = spec::call(&mut os, step);
        let violation = spec::transition_rules(&last.os, &os, step, result).err();
        Some(ModelState { os, violation })
    }

    fn properties(&self) -> Vec<Property<Self>> {
        vec![
            Property::always(
                "transition rules hold (FIFO, limits, LIFO, events)",
                |_, s: &Self::State| s.violation.is_none(),
            ),
            Property::always(
                "running task is a highest-priority ready task",
                |_, s: &Self::State| {
                    spec::running_is_highest_ready(&s.os)
                        && spec::running_priority_is_ceiling(&s.os)
                },
            ),
            Property::always(
                "activations accounted, never above the limit",
                |_, s: &Self::State| spec::activations_accounted(&s.os),
            ),
            Property::always("resource stacks consistent", |_, s: &Self::State| {
                spec::resources_consistent(&s.os)
            }),
            Property::always(
                "waiting tasks are blocked on unset events",
                |_, s: &Self::State| spec::waiting_is_blocked(&s.os),
            ),
            // Reachability: the checks above are not vacuous.
            Property::sometimes("a task is preempted", |_, s: &Self::State| {
                (0..=cw_core::os::MAX_PRIORITY)
                    .any(|p| s.os.ready_at(p).any(|t| s.os.is_started(t)))
            }),
            Property::sometimes(
                "two activations are queued at one priority",
                |_, s: &Self::State| {
                    (0..=cw_core::os::MAX_PRIORITY).any(|p| s.os.ready_at(p).nth(1).is_some())
                },
            ),
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

/// Explores the whole state space of a scheduler model and checks its properties.
pub fn check<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize>(
    model: OsModel<T, R, C, A, Q>,
    threads: usize,
) -> Outcome {
    let name = model.name;
    explore(name, model, threads)
}

/// Explores the whole state space of the communication-mode model and checks it.
pub fn check_modes(threads: usize) -> Outcome {
    explore(
        "EcuM/BswM/ComM/CanSM/CanIf modes, bus-off and controller faults",
        modes::ModeModel,
        threads,
    )
}

fn explore<M>(name: &'static str, model: M, threads: usize) -> Outcome
where
    M: Model + Send + Sync + 'static,
    M::State: Debug + std::hash::Hash + Eq + Send + Sync + Clone,
    M::Action: Debug + Eq + Send + Sync + Clone,
{
    use stateright::Checker;
    let properties = model.properties();
    let checker = model.checker().threads(threads).spawn_bfs().join();
    let discoveries = checker.discoveries();
    let mut failures = Vec::new();
    for p in properties {
        let found = discoveries.get(p.name);
        let failed = match p.expectation {
            stateright::Expectation::Always | stateright::Expectation::Eventually => {
                found.is_some()
            }
            stateright::Expectation::Sometimes => found.is_none(),
        };
        if failed {
            let path = found
                .map(|path| format!("{:?}", path.clone().into_actions()))
                .unwrap_or_default();
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
pub mod modes;

#[cfg(test)]
mod tests;

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize> Debug
    for OsModel<T, R, C, A, Q>
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}
