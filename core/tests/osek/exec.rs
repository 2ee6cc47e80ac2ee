//! The test executive: runs a [`Program`] of scripted tasks, ISRs and hooks on the real
//! kernel, as a port runs an application, and judges the order of execution and every
//! status against the script.
//!
//! A script is a list of [`Step`]s, each with a sequence number. Every step of the whole
//! program has its own number, and the numbers say the one order in which the steps must
//! execute: the executive fails a test when a step executes before all lower numbers did
//! (a dispatch or a preemption that should not have happened, or happened early), when a
//! call returns anything but what the step expects, when a task is dispatched, an ISR
//! entered or a hook called with no step left in its script (an unexpected dispatch), and
//! when the program ends with a step not reached.
//!
//! Execution: the kernel decides who runs. The executive runs the innermost active ISR's
//! script, else the running task's; each task script continues across instances (the steps
//! after a `TerminateTask` are the next activation's). Every service call is a rescheduling
//! point, as on a real port. Interrupts: a `Raise` step sets the request in a
//! [`VirtualInterrupts`] controller; after every step the controller takes each request the
//! kernel's mask admits, highest priority first, and the kernel enters its ISR. Hooks run
//! inside the kernel call that causes them: the kernel calls the executive's [`Hooks`]
//! implementation, which runs the hook's script up to its `End` step, the first step of
//! each invocation stating what the kernel passed ([`Act::Hook`]).

#![allow(dead_code)] // each test binary uses the part it needs

use cw_core::os::call::perform;
use cw_core::os::{
    AppMode, Hooks, InterruptControl, IsrId, Os, OsConfig, OsError, Phase, Returned, ServiceCall,
    StatusType, TaskId, VirtualInterrupts,
};

/// What a step does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Act {
    /// Calls a service.
    Call(ServiceCall),
    /// The hardware raises interrupt `isr` here (a request; taken when the mask admits it).
    Raise(IsrId),
    /// The body ends: an ISR returns, a hook returns, a task's body returns without
    /// `TerminateTask` (AUTOSAR's missing end).
    End,
    /// The first step of each hook invocation: the kernel called this hook, with this.
    Hook(HookCall),
}

/// A hook invocation as the kernel made it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HookCall {
    /// `StartupHook`.
    Startup,
    /// `ShutdownHook(Error)`.
    Shutdown(StatusType),
    /// `PreTaskHook`, with the task `GetTaskID` names inside it.
    Pre(Option<TaskId>),
    /// `PostTaskHook`, with the task `GetTaskID` names inside it.
    Post(Option<TaskId>),
    /// `ErrorHook(Error)`, with the failed call (`OSErrorGetServiceId` and parameters).
    Error(OsError, ServiceCall),
    /// The alarm callback with this id.
    Callback(u8),
}

/// What a step must return.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Expect {
    /// Nothing to check (`Raise`, `End`, `Hook`).
    None,
    /// This result.
    Result(Result<Returned, OsError>),
}

/// One step of a script.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Step {
    /// Its place in the one order the program must follow (1, 2, 3, ...).
    pub seq: u16,
    /// What it does.
    pub act: Act,
    /// What it must return.
    pub expect: Expect,
}

/// `call` must succeed and return nothing.
pub const fn ok(seq: u16, call: ServiceCall) -> Step {
    Step {
        seq,
        act: Act::Call(call),
        expect: Expect::Result(Ok(Returned::Nothing)),
    }
}

/// `call` must fail with `error`.
pub const fn err(seq: u16, call: ServiceCall, error: OsError) -> Step {
    Step {
        seq,
        act: Act::Call(call),
        expect: Expect::Result(Err(error)),
    }
}

/// `call` must succeed and return `value`.
pub const fn ret(seq: u16, call: ServiceCall, value: Returned) -> Step {
    Step {
        seq,
        act: Act::Call(call),
        expect: Expect::Result(Ok(value)),
    }
}

/// The hardware raises interrupt `isr`.
pub const fn raise(seq: u16, isr: IsrId) -> Step {
    Step {
        seq,
        act: Act::Raise(isr),
        expect: Expect::None,
    }
}

/// The body ends (see [`Act::End`]).
pub const fn end(seq: u16) -> Step {
    Step {
        seq,
        act: Act::End,
        expect: Expect::None,
    }
}

/// The kernel calls a hook (the first step of each hook invocation).
pub const fn hook(seq: u16, call: HookCall) -> Step {
    Step {
        seq,
        act: Act::Hook(call),
        expect: Expect::None,
    }
}

/// The scripts of one test sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Program {
    /// The application mode `StartOS` is given.
    pub mode: AppMode,
    /// One script per task, by task id.
    pub tasks: &'static [&'static [Step]],
    /// One script per ISR, by ISR id.
    pub isrs: &'static [&'static [Step]],
    /// `StartupHook`'s script.
    pub startup: &'static [Step],
    /// `ShutdownHook`'s script.
    pub shutdown: &'static [Step],
    /// `PreTaskHook`'s script.
    pub pre_task: &'static [Step],
    /// `PostTaskHook`'s script.
    pub post_task: &'static [Step],
    /// `ErrorHook`'s script.
    pub error: &'static [Step],
    /// The alarm callbacks' script (all callbacks, in the order they run).
    pub callback: &'static [Step],
    /// The environment: `Raise` steps the hardware makes while nothing runs (no task, no
    /// ISR), one each time the processor is idle.
    pub idle: &'static [Step],
}

impl Program {
    /// A program of task scripts only, started in `OSDEFAULTAPPMODE`.
    pub const fn tasks(tasks: &'static [&'static [Step]]) -> Self {
        Self {
            mode: cw_core::os::OSDEFAULTAPPMODE,
            tasks,
            isrs: &[],
            startup: &[],
            shutdown: &[],
            pre_task: &[],
            post_task: &[],
            error: &[],
            callback: &[],
            idle: &[],
        }
    }

    /// The same with this environment script.
    pub const fn idle(self, idle: &'static [Step]) -> Self {
        Self { idle, ..self }
    }

    /// The same with these ISR scripts.
    pub const fn isrs(self, isrs: &'static [&'static [Step]]) -> Self {
        Self { isrs, ..self }
    }

    /// The same with this `ErrorHook` script.
    pub const fn error_hook(self, error: &'static [Step]) -> Self {
        Self { error, ..self }
    }

    /// The same with these `PreTaskHook` and `PostTaskHook` scripts.
    pub const fn task_hooks(self, pre_task: &'static [Step], post_task: &'static [Step]) -> Self {
        Self {
            pre_task,
            post_task,
            ..self
        }
    }

    /// The same with these `StartupHook` and `ShutdownHook` scripts.
    pub const fn os_hooks(self, startup: &'static [Step], shutdown: &'static [Step]) -> Self {
        Self {
            startup,
            shutdown,
            ..self
        }
    }

    /// The same with this alarm-callback script.
    pub const fn callbacks(self, callback: &'static [Step]) -> Self {
        Self { callback, ..self }
    }

    /// The same, started in application mode `mode`.
    pub const fn mode(self, mode: AppMode) -> Self {
        Self { mode, ..self }
    }
}

/// Whose script a step belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Who {
    /// A task.
    Task(u8),
    /// An ISR.
    Isr(u8),
    /// `StartupHook`.
    Startup,
    /// `ShutdownHook`.
    Shutdown,
    /// `PreTaskHook`.
    PreTask,
    /// `PostTaskHook`.
    PostTask,
    /// `ErrorHook`.
    Error,
    /// An alarm callback.
    Callback,
    /// The environment while the processor is idle.
    Idle,
}

/// Why a test sequence failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Failure {
    /// A step ran before its turn: the step expected next was another one.
    OutOfOrder {
        /// Who ran it.
        who: Who,
        /// The step that ran.
        step: u16,
        /// The step expected next.
        expected: u16,
    },
    /// A call returned something else.
    WrongResult {
        /// The step.
        step: u16,
        /// What it returned.
        got: Result<Returned, OsError>,
    },
    /// A hook invocation's first step named another call.
    WrongHook {
        /// The step.
        step: u16,
        /// What the kernel did.
        got: HookCall,
    },
    /// A task was dispatched, an ISR entered or a hook called with no step left for it,
    /// or a step of the wrong kind at an invocation's start.
    Unexpected {
        /// Who.
        who: Who,
    },
    /// The program ended with this step not executed.
    NotReached {
        /// Whose step.
        who: Who,
        /// The step.
        step: u16,
    },
    /// The kernel refused an interrupt its own mask admitted.
    IsrRefused {
        /// The ISR.
        isr: IsrId,
        /// Why.
        error: OsError,
    },
}

/// The executive's state. It is the kernel's hooks' data, so that the hooks can run their
/// scripts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Exec {
    program: &'static Program,
    next: u16,
    tasks: [u16; 16],
    isrs: [u16; 8],
    hooks: [u16; 7],
    irq: VirtualInterrupts,
    failure: Option<Failure>,
    /// The last steps executed (a ring), for the failure report.
    trail: [Option<(u16, Who)>; 24],
    executed: usize,
}

impl Exec {
    fn new(program: &'static Program) -> Self {
        Self {
            program,
            next: 1,
            tasks: [0; 16],
            isrs: [0; 8],
            hooks: [0; 7],
            irq: VirtualInterrupts::new(),
            failure: None,
            trail: [None; 24],
            executed: 0,
        }
    }

    fn script(&self, who: Who) -> &'static [Step] {
        let p = self.program;
        match who {
            Who::Task(t) => p.tasks.get(usize::from(t)).copied().unwrap_or(&[]),
            Who::Isr(i) => p.isrs.get(usize::from(i)).copied().unwrap_or(&[]),
            Who::Startup => p.startup,
            Who::Shutdown => p.shutdown,
            Who::PreTask => p.pre_task,
            Who::PostTask => p.post_task,
            Who::Error => p.error,
            Who::Callback => p.callback,
            Who::Idle => p.idle,
        }
    }

    fn cursor(&mut self, who: Who) -> Option<&mut u16> {
        match who {
            Who::Task(t) => self.tasks.get_mut(usize::from(t)),
            Who::Isr(i) => self.isrs.get_mut(usize::from(i)),
            Who::Startup => self.hooks.get_mut(0),
            Who::Shutdown => self.hooks.get_mut(1),
            Who::PreTask => self.hooks.get_mut(2),
            Who::PostTask => self.hooks.get_mut(3),
            Who::Error => self.hooks.get_mut(4),
            Who::Callback => self.hooks.get_mut(5),
            Who::Idle => self.hooks.get_mut(6),
        }
    }

    fn fail(&mut self, failure: Failure) {
        self.failure.get_or_insert(failure);
    }

    /// Takes `who`'s next step, checking its turn; `None` (and a failure) if it has none.
    fn take(&mut self, who: Who) -> Option<Step> {
        if self.failure.is_some() {
            return None;
        }
        let script = self.script(who);
        let cursor = self.cursor(who)?;
        let Some(step) = script.get(usize::from(*cursor)).copied() else {
            self.fail(Failure::Unexpected { who });
            return None;
        };
        *cursor += 1;
        if step.seq != self.next {
            self.fail(Failure::OutOfOrder {
                who,
                step: step.seq,
                expected: self.next,
            });
            return None;
        }
        self.next += 1;
        if let Some(slot) = self.trail.get_mut(self.executed % 24) {
            *slot = Some((step.seq, who));
        }
        self.executed += 1;
        Some(step)
    }

    /// The steps not reached when the program ended.
    fn unfinished(&self) -> Option<Failure> {
        let p = self.program;
        let scripts = p
            .tasks
            .iter()
            .enumerate()
            .map(|(t, s)| (Who::Task(t as u8), *s))
            .chain(
                p.isrs
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (Who::Isr(i as u8), *s)),
            )
            .chain([
                (Who::Startup, p.startup),
                (Who::Shutdown, p.shutdown),
                (Who::PreTask, p.pre_task),
                (Who::PostTask, p.post_task),
                (Who::Error, p.error),
                (Who::Callback, p.callback),
                (Who::Idle, p.idle),
            ]);
        for (who, script) in scripts {
            let mut exec = *self;
            let done = exec.cursor(who).map_or(0, |c| usize::from(*c));
            if let Some(step) = script.get(done) {
                return Some(Failure::NotReached {
                    who,
                    step: step.seq,
                });
            }
        }
        None
    }
}

/// The kernel under test.
pub type Kernel<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
> = Os<T, R, C, A, I, Q, &'static OsConfig<T, R, C, A, I>, Exec>;

/// Runs one step of a call script: the call, checked against the expectation.
fn run_call<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Kernel<T, R, C, A, I, Q>,
    step: Step,
) {
    let Act::Call(call) = step.act else {
        return;
    };
    let got = perform(os, call);
    if step.expect != Expect::Result(got) {
        os.hooks_mut().fail(Failure::WrongResult {
            step: step.seq,
            got,
        });
    }
}

/// Runs one invocation of hook `who`, which the kernel made with `call`.
fn run_hook<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Kernel<T, R, C, A, I, Q>,
    who: Who,
    call: HookCall,
) {
    let Some(first) = os.hooks_mut().take(who) else {
        return;
    };
    match first.act {
        Act::Hook(expected) if expected == call => {}
        Act::Hook(_) => {
            os.hooks_mut().fail(Failure::WrongHook {
                step: first.seq,
                got: call,
            });
            return;
        }
        _ => {
            os.hooks_mut().fail(Failure::Unexpected { who });
            return;
        }
    }
    // A hook that shut the OS down does not go on: `ShutdownOS` does not return (but
    // `ShutdownHook` itself runs while the OS shuts down).
    while os.phase() != Phase::ShutDown {
        let Some(step) = os.hooks_mut().take(who) else {
            return;
        };
        match step.act {
            Act::Call(_) => run_call(os, step),
            Act::Raise(isr) => {
                os.hooks_mut().irq.raise(isr);
            }
            Act::End => return,
            Act::Hook(_) => os.hooks_mut().fail(Failure::Unexpected { who }),
        }
    }
}

fn task_seen<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Kernel<T, R, C, A, I, Q>,
) -> Option<TaskId> {
    os.get_task_id().unwrap_or(None)
}

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
    > Hooks<Kernel<T, R, C, A, I, Q>> for Exec
{
    fn startup_hook(os: &mut Kernel<T, R, C, A, I, Q>) {
        run_hook(os, Who::Startup, HookCall::Startup);
    }

    fn shutdown_hook(os: &mut Kernel<T, R, C, A, I, Q>, error: StatusType) {
        run_hook(os, Who::Shutdown, HookCall::Shutdown(error));
    }

    fn pre_task_hook(os: &mut Kernel<T, R, C, A, I, Q>) {
        let task = task_seen(os);
        run_hook(os, Who::PreTask, HookCall::Pre(task));
    }

    fn post_task_hook(os: &mut Kernel<T, R, C, A, I, Q>) {
        let task = task_seen(os);
        run_hook(os, Who::PostTask, HookCall::Post(task));
    }

    fn error_hook(os: &mut Kernel<T, R, C, A, I, Q>, error: OsError) {
        let call = os.error_call().unwrap_or(ServiceCall::HookMissingEnd);
        run_hook(os, Who::Error, HookCall::Error(error, call));
    }

    fn alarm_callback(os: &mut Kernel<T, R, C, A, I, Q>, callback: u8) {
        run_hook(os, Who::Callback, HookCall::Callback(callback));
    }
}

/// The controller takes every request the kernel's mask admits.
fn take_interrupts<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Kernel<T, R, C, A, I, Q>,
) {
    let isrs = os.config().isrs();
    loop {
        let mask = os.interrupt_mask();
        let exec = os.hooks_mut();
        exec.irq.apply_mask(mask);
        let Some(isr) = exec.irq.take_next(isrs) else {
            return;
        };
        if let Err(error) = os.enter_isr(isr) {
            os.hooks_mut().fail(Failure::IsrRefused { isr, error });
            return;
        }
    }
}

/// Runs `program` on a kernel for `cfg` until nothing is left to run.
///
/// # Errors
/// The first deviation from the scripts, with the last steps executed.
pub fn run<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    cfg: &'static OsConfig<T, R, C, A, I>,
    program: &'static Program,
) -> Result<(), String> {
    let mut os = Kernel::<T, R, C, A, I, Q>::with_hooks(cfg, Exec::new(program))
        .map_err(|e| e.describe().to_string())?;
    if let Err(e) = os.start_os(program.mode) {
        return Err(format!("StartOS failed: {}", e.name()));
    }
    take_interrupts(&mut os);
    // Every iteration executes a step or ends the run, and scripts are finite.
    while os.hooks().failure.is_none() && !os.is_shut_down() {
        let who = if let Some(isr) = os.active_isr() {
            Who::Isr(isr.0)
        } else if let Some(task) = os.running() {
            Who::Task(task.0)
        } else if usize::from(os.hooks().hooks[6]) < program.idle.len() {
            Who::Idle
        } else {
            break;
        };
        let Some(step) = os.hooks_mut().take(who) else {
            break;
        };
        match step.act {
            Act::Call(_) => run_call(&mut os, step),
            Act::Raise(isr) => {
                os.hooks_mut().irq.raise(isr);
            }
            Act::End => {
                let ended = match who {
                    Who::Isr(_) => os.exit_isr(),
                    Who::Task(_) => os.task_returned(),
                    _ => Err(OsError::CallLevel),
                };
                if let Err(e) = ended {
                    return Err(format!(
                        "step {}: the body's end was refused: {e:?}",
                        step.seq
                    ));
                }
            }
            Act::Hook(_) => os.hooks_mut().fail(Failure::Unexpected { who }),
        }
        take_interrupts(&mut os);
    }
    let exec = *os.hooks();
    match exec.failure.or_else(|| exec.unfinished()) {
        None => Ok(()),
        Some(failure) => {
            let trail: Vec<String> = (0..24)
                .map(|k| (exec.executed + k) % 24)
                .filter_map(|k| exec.trail.get(k).copied().flatten())
                .map(|(seq, who)| format!("{seq} {who:?}"))
                .collect();
            Err(format!(
                "{failure:?}\n  last steps executed: {}",
                trail.join(", ")
            ))
        }
    }
}

/// Validates a configuration in a `static` (a broken one stops the build).
#[allow(clippy::panic)]
pub const fn config<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
>(
    description: cw_core::os::OsDescription<T, C, A, I>,
) -> OsConfig<T, R, C, A, I> {
    match OsConfig::new(description) {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    }
}

/// Runs `program` on each configuration (the classes and policies a sequence runs in).
#[track_caller]
pub fn check_each<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    configs: &'static [OsConfig<T, R, C, A, I>],
    program: &'static Program,
) {
    for (k, cfg) in configs.iter().enumerate() {
        if let Err(failure) = run::<T, R, C, A, I, Q>(cfg, program) {
            panic!(
                "sequence failed in configuration {k} ({}, {:?} status): {failure}",
                cfg.class().name(),
                cfg.status()
            );
        }
    }
}
