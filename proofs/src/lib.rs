//! Model checking of the OSEK kernel in `cw-core` (this module), and of the ECU's
//! communication modes ([`modes`]).
//!
//! The book: [verification](../../book/verification.html) (the models and what they cover) and
//! [Kani](../../book/kani.html) (the exhaustive step sequences).
//!
//! [`OsModel`] is a stateright model whose state *is* the real kernel
//! ([`cw_core::os::Os`]) together with a [`VirtualInterrupts`] controller, and whose
//! transitions call the real services: nothing about the scheduler is re-implemented here.
//! Every reachable state of a configuration is explored breadth first, under every
//! interleaving of:
//! - the hardware raising any interrupt at any moment; the controller takes every request
//!   the kernel's interrupt mask admits at once (highest priority first), as the NVIC does,
//!   so an ISR interrupts a task or a lower ISR between any two of their steps;
//! - the innermost ISR's body: its script (the calls of the real ISR, in order, then its
//!   return), or, for the adversarial sets, any of the calls it may make, any number of
//!   times, then its return (an over-approximation of every ISR body);
//! - the running task's calls: terminating, its resources, the activations it makes,
//!   events, interrupt locks, and (adversarial sets) every service and a body that returns
//!   without `TerminateTask`.
//!
//! Checked in every state (the `cw_core::os::spec` predicates):
//! - whenever the processor is at task level, the running task is a highest-priority
//!   ready task, its priority raised exactly to the ceilings it holds;
//! - every active ISR was taken only above the priority it interrupted and never under an
//!   interrupt lock, ISR priorities increase inward, each runs at its ceiling; while an ISR
//!   is active the code running is that ISR;
//! - activations are neither lost nor invented and never exceed the limit;
//! - resource stacks (of tasks and ISRs) are consistent; waiting tasks wait for something
//!   not yet set; the call level follows the state;
//! - the ISR stack's free slots are empty, and what a port reads at the end of a kernel
//!   call in one step (`Os::port_view`) is the kernel's mask and the resources the running
//!   task may lock outside the kernel.
//!
//! Checked on every transition (`cw_core::os::spec::transition_rules`, recorded as a
//! violation in the next state): FIFO within a priority; `E_OS_LIMIT` exactly at the limit;
//! LIFO resources and the priority they restore; events release exactly their waiters; an
//! ISR is entered only when the mask admits it; no task switch while an ISR stays active or
//! an interrupt lock stays in force; a refused service changes nothing.
//!
//! And where the kernel calls the hooks ([`CheckingHooks`]): `PreTaskHook` and
//! `PostTaskHook` see the task entering or leaving the running state as the running task,
//! at task level; `ErrorHook` always has the failed service and is never re-entered, even
//! when a service called inside it fails.

use cw_core::os::{
    spec, Context, CounterId, EventMask, Hooks, InterruptControl, IsrCategory, IsrId, Os, OsConfig,
    OsError, ResourceId, ServiceCall, TaskId, TaskKind, TaskState, VirtualInterrupts,
    OSDEFAULTAPPMODE, RES_SCHEDULER,
};
use stateright::{Model, Property};
use std::fmt::Debug;

pub use cw_core::os::spec::Service;

/// One step of the model: the hardware raises an interrupt, or the code running makes a
/// step (a service call, an ISR's return, a task body's end).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Step {
    /// The hardware raises interrupt request `isr`.
    Raise(IsrId),
    /// The code running now does this.
    Do(Service),
}

/// Hooks that check, where the kernel calls them, what must hold there; the first broken
/// rule is kept and the model reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CheckingHooks {
    in_error_hook: bool,
    broken: Option<&'static str>,
}

impl CheckingHooks {
    fn record(&mut self, rule: &'static str) {
        self.broken.get_or_insert(rule);
    }

    /// The first rule a hook found broken, if any.
    pub const fn broken(&self) -> Option<&'static str> {
        self.broken
    }
}

/// The kernel the models explore.
pub type Kernel<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
> = Os<T, R, C, A, I, Q, &'static OsConfig<T, R, C, A, I>, CheckingHooks>;

/// Whether the task `GetTaskID` names in a pre- or post-task hook is the running one, at
/// task level.
fn hook_sees_running<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Kernel<T, R, C, A, I, Q>,
) -> bool {
    let seen = os.get_task_id();
    matches!(seen, Ok(Some(t)) if os.task_state(t) == Some(TaskState::Running))
        && os.isr_nesting() == 0
}

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
    > Hooks<Kernel<T, R, C, A, I, Q>> for CheckingHooks
{
    fn pre_task_hook(os: &mut Kernel<T, R, C, A, I, Q>) {
        if !hook_sees_running(os) {
            os.hooks_mut()
                .record("PreTaskHook: the task entering the running state is not the running one");
        }
    }

    fn post_task_hook(os: &mut Kernel<T, R, C, A, I, Q>) {
        if !hook_sees_running(os) {
            os.hooks_mut()
                .record("PostTaskHook: the task leaving the running state is not the running one");
        }
    }

    fn error_hook(os: &mut Kernel<T, R, C, A, I, Q>, _error: OsError) {
        if os.hooks().in_error_hook {
            os.hooks_mut().record("ErrorHook was re-entered");
        }
        if os.error_service_id().is_none() {
            os.hooks_mut()
                .record("ErrorHook without OSErrorGetServiceId");
        }
        os.hooks_mut().in_error_hook = true;
        // A call that fails inside ErrorHook must not call it again.
        let _ = os.get_task_state(TaskId(u8::MAX));
        os.hooks_mut().in_error_hook = false;
    }
}

/// What an ISR's body does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IsrBody {
    /// These calls, in order, then the return.
    Script(&'static [ServiceCall]),
    /// Any of these calls, any number of times, in any order, then the return.
    Any(&'static [ServiceCall]),
    /// A whole ISR making one of these calls: entered (when the mask admits it), the call,
    /// returned, in one step from task level. For the sets that stress the task services,
    /// where what happens inside an ISR adds nothing but states.
    Whole(&'static [ServiceCall]),
}

/// A state of the model: the kernel, the interrupt controller, how far each active ISR is
/// in a scripted body, and the first transition rule that failed, if any.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModelState<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
> {
    /// The real kernel.
    pub os: Kernel<T, R, C, A, I, Q>,
    /// Pending interrupt requests and the mask applied.
    pub irq: VirtualInterrupts,
    /// Per ISR: the index of the next call of its scripted body (while it is active).
    pub isr_pc: [u8; I],
    /// A broken transition rule (exploration stops there and the property reports it).
    pub violation: Option<&'static str>,
}

/// States a model must reach, so that the checks above are not vacuous.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reach {
    /// A started task waits in a ready queue (it was preempted).
    Preemption,
    /// Two activations wait at one priority.
    TwoQueued,
    /// A category-2 ISR interrupts another.
    Isr2Nesting,
    /// An interrupt request waits because the mask holds it (a ceiling, a lock or a higher
    /// ISR).
    HeldInterrupt,
    /// An ISR holds a resource.
    IsrResource,
    /// A category-1 ISR runs while `SuspendOSInterrupts` is in force.
    Cat1UnderSuspendOs,
    /// An extended task waits for an event.
    Waiting,
}

/// The model of one configuration.
pub struct OsModel<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
> {
    /// Name for reports.
    pub name: &'static str,
    /// The configuration under test.
    pub cfg: &'static OsConfig<T, R, C, A, I>,
    /// Event masks used in `SetEvent`/`ClearEvent`/`WaitEvent` steps.
    pub event_masks: &'static [EventMask],
    /// `(caller, target)`: tasks that activate another as part of their normal behaviour
    /// (the sonar task activating the Com task on data received).
    pub activations: &'static [(TaskId, TaskId)],
    /// What each ISR's body does.
    pub isr_bodies: &'static [(IsrId, IsrBody)],
    /// Whether tasks take interrupt locks.
    pub task_locks: bool,
    /// Whether tasks may call services beyond terminating and their configured resources:
    /// every activation, chaining, `Schedule`, every resource (including misuse).
    pub adversarial: bool,
    /// Whether a task's body may return without `TerminateTask` (AUTOSAR's missing end).
    pub missing_ends: bool,
    /// The states the model must reach.
    pub reach: &'static [Reach],
}

/// The interrupt services a lock-taking task or ISR may call: each suspend only when not
/// already in force (so nesting stays bounded), each resume always (an unpaired one must be
/// ignored).
fn lock_steps<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &Kernel<T, R, C, A, I, Q>,
    out: &mut Vec<ServiceCall>,
) {
    let locks = os.locks();
    if !locks.all_disabled {
        out.push(ServiceCall::DisableAllInterrupts);
    }
    if locks.suspend_all == 0 {
        out.push(ServiceCall::SuspendAllInterrupts);
    }
    if locks.suspend_os == 0 {
        out.push(ServiceCall::SuspendOsInterrupts);
    }
    out.extend([
        ServiceCall::EnableAllInterrupts,
        ServiceCall::ResumeAllInterrupts,
        ServiceCall::ResumeOsInterrupts,
    ]);
}

/// A call an ISR's body makes, as the port makes it: a lock of a user resource by the
/// kernel's fast paths (the service where they decline), anything else as the service.
fn as_port_calls(call: ServiceCall) -> Service {
    match call {
        ServiceCall::GetResource(r) if r != RES_SCHEDULER => Service::FastGet(r),
        ServiceCall::ReleaseResource(r) if r != RES_SCHEDULER => Service::FastRelease(r),
        c => Service::Call(c),
    }
}

/// A call a task makes, as the port makes it: an activation by the kernel's fast path
/// (the service where it declines), anything else as the service.
fn as_task_port_calls(call: ServiceCall) -> Service {
    match call {
        ServiceCall::ActivateTask(t) => Service::FastActivate(t),
        c => Service::Call(c),
    }
}

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
    > OsModel<T, R, C, A, I, Q>
{
    fn tasks(&self) -> impl Iterator<Item = TaskId> {
        (0..T as u8).map(TaskId)
    }

    fn resources(&self) -> impl Iterator<Item = ResourceId> {
        (0..R as u8)
            .map(ResourceId)
            .chain(std::iter::once(RES_SCHEDULER))
    }

    /// What the running task may do next. The resources it declares it takes as the
    /// port's lock does (the kernel's fast paths, the full service where they decline);
    /// `RES_SCHEDULER`, and (adversarial sets) the resources it does not declare, by the full
    /// services.
    fn task_steps(&self, os: &Kernel<T, R, C, A, I, Q>, running: TaskId) -> Vec<Service> {
        let me = &self.cfg.tasks()[running.0 as usize];
        let mut steps = Vec::new();
        for r in self.resources() {
            if r != RES_SCHEDULER && (me.resources >> r.0) & 1 == 1 {
                steps.push(Service::FastGet(r));
                steps.push(Service::FastRelease(r));
            }
        }
        steps.extend(
            self.task_calls(os, running)
                .into_iter()
                .map(as_task_port_calls),
        );
        steps
    }

    fn task_calls(&self, os: &Kernel<T, R, C, A, I, Q>, running: TaskId) -> Vec<ServiceCall> {
        let me = &self.cfg.tasks()[running.0 as usize];
        let mut calls = vec![ServiceCall::TerminateTask];
        // The services on resources: `RES_SCHEDULER`, and every resource when adversarial.
        for r in self.resources() {
            let declared = r != RES_SCHEDULER && (me.resources >> r.0) & 1 == 1;
            if r == RES_SCHEDULER || (self.adversarial && !declared) {
                calls.push(ServiceCall::GetResource(r));
                calls.push(ServiceCall::ReleaseResource(r));
            }
        }
        for &(caller, target) in self.activations {
            if caller == running {
                calls.push(ServiceCall::ActivateTask(target));
            }
        }
        if me.kind == TaskKind::Extended {
            for &m in self.event_masks {
                calls.push(ServiceCall::WaitEvent(m));
                calls.push(ServiceCall::ClearEvent(m));
            }
        }
        if self.task_locks {
            lock_steps(os, &mut calls);
        }
        if self.adversarial {
            calls.push(ServiceCall::Schedule);
            for t in self.tasks() {
                calls.push(ServiceCall::ActivateTask(t));
                calls.push(ServiceCall::ChainTask(t));
                if self.cfg.tasks()[t.0 as usize].kind == TaskKind::Extended {
                    for &m in self.event_masks {
                        calls.push(ServiceCall::SetEvent(t, m));
                    }
                }
            }
        }
        calls
    }

    fn body(&self, isr: IsrId) -> IsrBody {
        self.isr_bodies
            .iter()
            .find(|(owner, _)| *owner == isr)
            .map_or(IsrBody::Script(&[]), |(_, body)| *body)
    }

    /// The controller takes every request the mask admits: an ISR is entered at once.
    fn deliver(&self, state: &mut ModelState<T, R, C, A, I, Q>) {
        while state.violation.is_none() {
            state.irq.apply_mask(state.os.interrupt_mask());
            let Some(isr) = state.irq.take_next(self.cfg.isrs()) else {
                return;
            };
            let before = state.os;
            let service = Service::EnterIsr(isr);
            let result = spec::call(&mut state.os, service);
            state.violation = match result {
                Err(_) => Some("the kernel refused an interrupt its mask admitted"),
                Ok(_) => spec::transition_rules(&before, &state.os, service, result).err(),
            };
        }
    }

    fn reached(&self, reach: Reach, s: &ModelState<T, R, C, A, I, Q>) -> bool {
        let os = &s.os;
        let cfg = self.cfg;
        let category = |isr: IsrId| cfg.isrs().get(isr.0 as usize).map(|c| c.category);
        match reach {
            Reach::Preemption => {
                (0..=cw_core::os::MAX_PRIORITY).any(|p| os.ready_at(p).any(|t| os.is_started(t)))
            }
            Reach::TwoQueued => {
                (0..=cw_core::os::MAX_PRIORITY).any(|p| os.ready_at(p).nth(1).is_some())
            }
            Reach::Isr2Nesting => {
                os.active_isrs()
                    .filter(|(isr, _)| category(*isr) == Some(IsrCategory::Two))
                    .count()
                    >= 2
            }
            Reach::HeldInterrupt => s.irq.pending() != 0,
            Reach::IsrResource => os
                .active_isrs()
                .any(|(isr, _)| os.isr_held_resources(isr).next().is_some()),
            Reach::Cat1UnderSuspendOs => {
                os.locks().suspend_os != 0
                    && os.active_isr().and_then(category) == Some(IsrCategory::One)
            }
            Reach::Waiting => self.tasks().any(|t| os.is_waiting(t)),
        }
    }
}

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
    > Model for OsModel<T, R, C, A, I, Q>
{
    type State = ModelState<T, R, C, A, I, Q>;
    type Action = Step;

    fn init_states(&self) -> Vec<Self::State> {
        let Ok(mut os) = Kernel::<T, R, C, A, I, Q>::new(self.cfg) else {
            return Vec::new();
        };
        let violation = os
            .start_os(OSDEFAULTAPPMODE)
            .err()
            .map(|_| "StartOS failed");
        vec![ModelState {
            os,
            irq: VirtualInterrupts::new(),
            isr_pc: [0; I],
            violation,
        }]
    }

    fn actions(&self, state: &Self::State, actions: &mut Vec<Self::Action>) {
        if state.violation.is_some() || state.os.is_shut_down() {
            return;
        }
        let os = &state.os;
        for i in (0..I as u8).map(IsrId) {
            match self.body(i) {
                IsrBody::Whole(calls) => {
                    let priority = self.cfg.isrs().get(i.0 as usize).map(|c| c.priority);
                    if os.active_isr().is_none()
                        && priority.is_some_and(|p| os.interrupt_mask().admits(p))
                    {
                        // A tick as a port runs it: the kernel's fast path, else whole.
                        actions.extend(calls.iter().map(|c| {
                            Step::Do(match *c {
                                ServiceCall::IncrementCounter(counter) => {
                                    Service::FastTick(i, counter)
                                }
                                c => Service::Isr(i, c),
                            })
                        }));
                    }
                }
                _ if !state.irq.is_pending(i) => actions.push(Step::Raise(i)),
                _ => {}
            }
        }
        // The processor runs the innermost ISR, if any: only it makes steps.
        if let Some(isr) = os.active_isr() {
            let pc = state.isr_pc.get(isr.0 as usize).copied().unwrap_or(0);
            match self.body(isr) {
                IsrBody::Script(calls) => match calls.get(usize::from(pc)) {
                    Some(call) => actions.push(Step::Do(as_port_calls(*call))),
                    None => actions.push(Step::Do(Service::ExitIsr)),
                },
                IsrBody::Any(calls) => {
                    actions.extend(calls.iter().map(|c| Step::Do(as_port_calls(*c))));
                    actions.push(Step::Do(Service::ExitIsr));
                }
                IsrBody::Whole(_) => actions.push(Step::Do(Service::ExitIsr)),
            }
            return;
        }
        let Some(running) = os.running() else {
            return;
        };
        actions.extend(self.task_steps(os, running).into_iter().map(Step::Do));
        if self.missing_ends {
            actions.push(Step::Do(Service::TaskReturn));
        }
    }

    fn next_state(&self, last: &Self::State, step: Self::Action) -> Option<Self::State> {
        let mut next = *last;
        match step {
            Step::Raise(isr) => {
                next.irq.raise(isr);
            }
            Step::Do(service) => {
                let isr = last.os.active_isr();
                let result = spec::call(&mut next.os, service);
                next.violation = spec::step_contracts(&last.os, service)
                    .and_then(|()| spec::transition_rules(&last.os, &next.os, service, result))
                    .err();
                // The ISR's script moves on (and starts again at its next entry).
                if let Some(pc) = isr.and_then(|i| next.isr_pc.get_mut(i.0 as usize)) {
                    *pc = match service {
                        Service::ExitIsr => 0,
                        _ => pc.saturating_add(1),
                    };
                }
            }
        }
        self.deliver(&mut next);
        if next.violation.is_none() {
            next.violation = next.os.hooks().broken;
        }
        Some(next)
    }

    fn properties(&self) -> Vec<Property<Self>> {
        let mut properties = vec![
            Property::always(
                "transition rules hold (FIFO, limits, LIFO, events, ISR entry, no switch under an ISR or a lock) and the hooks see what they must",
                |_, s: &Self::State| s.violation.is_none(),
            ),
            Property::always(
                "at task level, the running task is a highest-priority ready task at its ceiling",
                |_, s: &Self::State| {
                    spec::running_is_highest_ready(&s.os)
                        && spec::running_priority_is_ceiling(&s.os)
                },
            ),
            Property::always(
                "an ISR runs only above the priority it interrupted, never under a lock, and while it runs no task does",
                |_, s: &Self::State| {
                    spec::isr_nesting_consistent(&s.os)
                        && (s.os.isr_nesting() == 0
                            || matches!(s.os.context(), Context::Isr1 | Context::Isr2))
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
                "waiting tasks are blocked on unset events; the call level follows the state",
                |_, s: &Self::State| {
                    spec::waiting_is_blocked(&s.os) && spec::context_consistent(&s.os)
                },
            ),
            Property::always(
                "free ISR slots are empty; the port's view at a kernel call's end is the kernel's",
                |_, s: &Self::State| {
                    spec::free_isr_slots_empty(&s.os) && spec::port_view_agrees(&s.os)
                },
            ),
        ];
        for &reach in self.reach {
            let name: &'static str = match reach {
                Reach::Preemption => "reached: a task is preempted",
                Reach::TwoQueued => "reached: two activations queued at one priority",
                Reach::Isr2Nesting => "reached: a category-2 ISR interrupts another",
                Reach::HeldInterrupt => "reached: an interrupt request is held by the mask",
                Reach::IsrResource => "reached: an ISR holds a resource",
                Reach::Cat1UnderSuspendOs => {
                    "reached: a category-1 ISR runs under SuspendOSInterrupts"
                }
                Reach::Waiting => "reached: an extended task waits",
            };
            let property = match reach {
                Reach::Preemption => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::Preemption, s)
                }),
                Reach::TwoQueued => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::TwoQueued, s)
                }),
                Reach::Isr2Nesting => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::Isr2Nesting, s)
                }),
                Reach::HeldInterrupt => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::HeldInterrupt, s)
                }),
                Reach::IsrResource => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::IsrResource, s)
                }),
                Reach::Cat1UnderSuspendOs => {
                    Property::sometimes(name, |m: &Self, s: &Self::State| {
                        m.reached(Reach::Cat1UnderSuspendOs, s)
                    })
                }
                Reach::Waiting => Property::sometimes(name, |m: &Self, s: &Self::State| {
                    m.reached(Reach::Waiting, s)
                }),
            };
            properties.push(property);
        }
        properties
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

/// Explores the whole state space of a kernel model and checks its properties.
pub fn check<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    model: OsModel<T, R, C, A, I, Q>,
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

/// The counter every model's timer ISR ticks.
pub const TICK: ServiceCall = ServiceCall::IncrementCounter(CounterId(0));

pub mod configs;
pub mod modes;
pub mod steps;

#[cfg(test)]
mod tests;

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
    > Debug for OsModel<T, R, C, A, I, Q>
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}
