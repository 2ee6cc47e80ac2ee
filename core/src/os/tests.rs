//! Kernel harnesses: the configuration rules, each service's error codes and effects,
//! interrupts, locks, hooks and shutdown, and a bolero harness that drives random step
//! sequences (task services, ISRs, locks) and checks the [`spec`] invariants and transition
//! rules after every step. The OSEK test plan's sequences are in `core/tests/osek/`.
extern crate std;

use super::steps::{SmallOs, Step, SMALL};
use super::*;
use std::vec::Vec;

const COUNTER: CounterConfig = CounterConfig {
    max_allowed_value: 99,
    ticks_per_base: 1,
    min_cycle: 1,
};

// Tasks: 0 Low(1, basic, 3 activations, uses R0), 1 Mid(3, extended, uses R0 and R1),
// 2 High(5, basic), 3 Np(2, non-preemptive basic), 4 Low2(1, basic, 2 activations).
// Alarms on counter 0: activate High, set event 1 of Mid, callback 7.
// ISRs: 0 Tick (cat. 2, priority 1), 1 Can (cat. 2, priority 3, uses R1), 2 Fast (cat. 1, 6).
const CONFIG: OsConfig<5, 2, 1, 3, 3> = match OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("Low", 1).activations(3).uses(0b01),
            TaskConfig::extended("Mid", 3).uses(0b11),
            TaskConfig::basic("High", 5),
            TaskConfig::basic("Np", 2).non_preemptive(),
            TaskConfig::basic("Low2", 1).activations(2),
        ],
        [COUNTER],
        [
            AlarmConfig::new(
                "ActHigh",
                CounterId(0),
                AlarmAction::ActivateTask(TaskId(2)),
            ),
            AlarmConfig::new("EvMid", CounterId(0), AlarmAction::SetEvent(TaskId(1), 1)),
            AlarmConfig::new("Cb", CounterId(0), AlarmAction::Callback(7)),
        ],
        [
            IsrConfig::cat2("Tick", 1),
            IsrConfig::cat2("Can", 3).uses(0b10),
            IsrConfig::cat1("Fast", 6),
        ],
    )
    .hooks(HookSet::ALL)
    .app_modes(2),
) {
    Ok(c) => c,
    Err(e) => panic!("{}", e.describe()),
};
static CFG: OsConfig<5, 2, 1, 3, 3> = CONFIG;

/// What the hooks saw, in order (a fixed ring, so the kernel stays `Copy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Seen {
    Startup(AppMode),
    Shutdown(StatusType),
    Pre(Option<TaskId>),
    Post(Option<TaskId>),
    Error(OsError, ServiceCall, Option<IsrId>),
    Callback(u8, Result<(), OsError>),
    /// What `exit_isr` returned when a hook called it.
    ExitIsr(Result<(), OsError>),
    /// The call level a hook found itself at.
    At(Context),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
struct Recorder {
    seen: [Option<Seen>; 24],
    len: usize,
    /// Make ErrorHook call a service that fails (to show it is not re-entered).
    fail_inside_error_hook: bool,
    /// Make ErrorHook shut the OS down.
    shutdown_in_error_hook: bool,
    /// Make PostTaskHook call a service it may not (so ErrorHook runs from it).
    fail_inside_post_task_hook: bool,
    /// Make ErrorHook shut the OS down on this error only.
    shutdown_on_error: Option<OsError>,
    /// Make ErrorHook try to return from the ISR it interrupted (as a broken port would).
    exit_isr_in_error_hook: bool,
    /// Make PreTaskHook and ErrorHook return with `SuspendAllInterrupts` in force.
    leave_lock_in_hooks: bool,
    /// Make PreTaskHook take the category-1 ISR `Fast` (which a hook does not mask).
    fast_isr_in_pre_task_hook: bool,
    /// Make ErrorHook take the category-1 ISR `Fast`.
    fast_isr_in_error_hook: bool,
}

impl Recorder {
    fn push(&mut self, seen: Seen) {
        if let Some(slot) = self.seen.get_mut(self.len) {
            *slot = Some(seen);
        }
        self.len += 1;
    }

    fn take(&mut self) -> Vec<Seen> {
        let out = self.seen.iter().take(self.len).flatten().copied().collect();
        *self = Self {
            fail_inside_error_hook: self.fail_inside_error_hook,
            shutdown_in_error_hook: self.shutdown_in_error_hook,
            fail_inside_post_task_hook: self.fail_inside_post_task_hook,
            shutdown_on_error: self.shutdown_on_error,
            exit_isr_in_error_hook: self.exit_isr_in_error_hook,
            leave_lock_in_hooks: self.leave_lock_in_hooks,
            fast_isr_in_pre_task_hook: self.fast_isr_in_pre_task_hook,
            fast_isr_in_error_hook: self.fast_isr_in_error_hook,
            ..Self::default()
        };
        out
    }
}

type TestOs = Os<5, 2, 1, 3, 3, 8, &'static OsConfig<5, 2, 1, 3, 3>, Recorder>;

impl Hooks<TestOs> for Recorder {
    fn startup_hook(os: &mut TestOs) {
        let mode = os.get_active_application_mode().unwrap_or(AppMode(99));
        os.hooks_mut().push(Seen::Startup(mode));
    }
    fn shutdown_hook(os: &mut TestOs, error: StatusType) {
        os.hooks_mut().push(Seen::Shutdown(error));
        // The threshold is in sync inside the hook too: no task preempts any more.
        assert!(spec::threshold_synced(os), "{os:?}");
    }
    fn pre_task_hook(os: &mut TestOs) {
        let id = os.get_task_id().unwrap_or(None);
        os.hooks_mut().push(Seen::Pre(id));
        if os.hooks().fast_isr_in_pre_task_hook {
            let taken = os.enter_isr(FAST);
            let exit = os.exit_isr();
            os.hooks_mut().push(Seen::ExitIsr(taken.and(exit)));
            let at = os.context();
            os.hooks_mut().push(Seen::At(at));
        }
        if os.hooks().leave_lock_in_hooks {
            let _ = os.suspend_all_interrupts();
        }
    }
    fn post_task_hook(os: &mut TestOs) {
        // Every activation is a queued record or the running task, also while the running
        // task is about to leave the processor (a task activated at task level is queued
        // before this hook runs).
        assert!(spec::activations_accounted(os), "{os:?}");
        let id = os.get_task_id().unwrap_or(None);
        os.hooks_mut().push(Seen::Post(id));
        if os.hooks().fail_inside_post_task_hook {
            let _ = os.activate_task(TaskId(0));
        }
    }
    fn error_hook(os: &mut TestOs, error: OsError) {
        // OSErrorGetServiceId names the service of the failed call.
        assert_eq!(os.error_service_id(), os.error_call().map(|c| c.id()));
        let call = os.error_call().unwrap_or(ServiceCall::HookMissingEnd);
        let isr = os.get_isr_id().unwrap_or(None);
        os.hooks_mut().push(Seen::Error(error, call, isr));
        assert!(spec::threshold_synced(os), "{os:?}");
        if os.hooks().fast_isr_in_error_hook {
            let taken = os.enter_isr(FAST);
            let exit = os.exit_isr();
            os.hooks_mut().push(Seen::ExitIsr(taken.and(exit)));
        }
        if os.hooks().fail_inside_error_hook {
            let _ = os.activate_task(TaskId(0));
        }
        if os.hooks().exit_isr_in_error_hook {
            let exit = os.exit_isr();
            os.hooks_mut().push(Seen::ExitIsr(exit));
        }
        if os.hooks().leave_lock_in_hooks {
            let _ = os.suspend_all_interrupts();
        }
        if os.hooks().shutdown_in_error_hook || os.hooks().shutdown_on_error == Some(error) {
            let _ = os.shutdown_os(error.status());
        }
    }
    fn alarm_callback(os: &mut TestOs, callback: u8) {
        // Only the SuspendAll pair is allowed here (OSEK); ActivateTask is not.
        let refused = os.activate_task(TaskId(0));
        let _ = os.suspend_all_interrupts();
        let _ = os.resume_all_interrupts();
        os.hooks_mut().push(Seen::Callback(callback, refused));
    }
}

const LOW: TaskId = TaskId(0);
const MID: TaskId = TaskId(1);
const HIGH: TaskId = TaskId(2);
const NP: TaskId = TaskId(3);
const LOW2: TaskId = TaskId(4);
const R0: ResourceId = ResourceId(0);
const R1: ResourceId = ResourceId(1);
const TICK: IsrId = IsrId(0);
const CAN: IsrId = IsrId(1);
const FAST: IsrId = IsrId(2);

fn os() -> TestOs {
    match TestOs::new(&CFG) {
        Ok(mut os) => {
            assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
            os.hooks_mut().take();
            os
        }
        Err(e) => panic!("{e:?}"),
    }
}

/// Runs `body` inside ISR `isr` (entered and left around it).
fn in_isr<V>(
    os: &mut TestOs,
    isr: IsrId,
    body: impl FnOnce(&mut TestOs) -> Result<V, OsError>,
) -> Result<V, OsError> {
    assert_eq!(os.enter_isr(isr), Ok(()));
    let result = body(os);
    assert_eq!(os.exit_isr(), Ok(()));
    result
}

/// `ActivateTask` from the tick ISR: how a task starts when nothing runs.
fn activate_from_isr(os: &mut TestOs, task: TaskId) -> Result<(), OsError> {
    in_isr(os, TICK, |os| os.activate_task(task))
}

fn check(os: &TestOs) {
    assert!(spec::kernel_invariants(os), "invariants: {os:?}");
}

/// The kernel of a test's own configuration `cfg`, started in the default mode.
fn started<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    cfg: &'static OsConfig<T, R, C, A, I>,
) -> Os<T, R, C, A, I, Q> {
    let Ok(mut os) = Os::<T, R, C, A, I, Q>::new(cfg) else {
        panic!("test configuration refused");
    };
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    os
}

#[test]
fn derived_configuration() {
    assert_eq!(CFG.resource_ceiling(0), Some(3));
    // R1 is shared with the Can ISR (priority 3): its ceiling lies at interrupt level.
    assert_eq!(CFG.resource_ceiling(1), Some(ISR_LEVEL_BASE + 3));
    assert_eq!(CFG.scheduler_ceiling(), 5);
    assert_eq!(CFG.total_activations(), 8);
    assert_eq!(CFG.isr_level(2), Some(ISR_LEVEL_BASE + 6));
    // SuspendOSInterrupts masks up to the highest category-2 ISR (Can), not Fast.
    assert_eq!(CFG.os_interrupt_level(), ISR_LEVEL_BASE + 3);
    assert_eq!(
        Os::<5, 2, 1, 3, 3, 7>::new(&CFG).err(),
        Some(ConfigError::QueueCapacity { needed: 8 })
    );
}

#[test]
fn impossible_configurations_are_refused_with_the_item() {
    let t = |p| TaskConfig::basic("t", p);
    let tasks = |tasks| OsConfig::<1, 1, 0, 0, 0>::new(OsDescription::new(tasks, [], [], [])).err();
    assert_eq!(tasks([t(64)]), Some(ConfigError::TaskPriority { task: 0 }));
    assert_eq!(
        tasks([t(1).activations(0)]),
        Some(ConfigError::TaskActivations { task: 0 })
    );
    assert_eq!(
        tasks([TaskConfig::extended("e", 1).activations(2)]),
        Some(ConfigError::ExtendedActivations { task: 0 })
    );
    assert_eq!(
        tasks([t(1).uses(0b10)]),
        Some(ConfigError::TaskResource { task: 0 })
    );
    assert_eq!(
        tasks([t(1).autostart_in(0b10)]),
        Some(ConfigError::TaskAppMode { task: 0 })
    );
    assert_eq!(
        OsConfig::<1, 0, 0, 0, 0>::new(OsDescription::new([t(1)], [], [], []).app_modes(0)).err(),
        Some(ConfigError::AppModes)
    );
    let bad_counter = CounterConfig {
        min_cycle: 0,
        ..COUNTER
    };
    assert_eq!(
        OsConfig::<1, 0, 1, 0, 0>::new(OsDescription::new([t(1)], [bad_counter], [], [])).err(),
        Some(ConfigError::CounterLimits { counter: 0 })
    );
    // One task, one counter and one alarm: the error the alarm alone causes.
    let one_alarm = |alarm: AlarmConfig| {
        OsConfig::<1, 0, 1, 1, 0>::new(OsDescription::new([t(1)], [COUNTER], [alarm], [])).err()
    };
    let cb = AlarmConfig::new("a", CounterId(0), AlarmAction::Callback(0));
    assert_eq!(
        one_alarm(AlarmConfig {
            counter: CounterId(1),
            ..cb
        }),
        Some(ConfigError::AlarmCounter { alarm: 0 })
    );
    assert_eq!(
        one_alarm(AlarmConfig::new(
            "a",
            CounterId(0),
            AlarmAction::SetEvent(TaskId(0), 1)
        )),
        Some(ConfigError::AlarmAction { alarm: 0 })
    );
    assert_eq!(
        one_alarm(cb.relative(0, 10)),
        Some(ConfigError::AlarmAutostart { alarm: 0 })
    );
    assert_eq!(
        one_alarm(cb.relative(1, 10).in_modes(0b10)),
        Some(ConfigError::AlarmAppMode { alarm: 0 })
    );
}

#[test]
fn conformance_classes_refuse_what_they_do_not_allow() {
    let two = |class, a: TaskConfig, b: TaskConfig| {
        OsConfig::<2, 0, 0, 0, 0>::new(OsDescription::new([a, b], [], [], []).class(class)).err()
    };
    let basic = |p| TaskConfig::basic("b", p);
    let ext = |p| TaskConfig::extended("e", p);
    use ConformanceClass::*;
    for class in [Bcc1, Bcc2] {
        assert_eq!(
            two(class, basic(1), ext(2)),
            Some(ConfigError::ClassExtendedTask { task: 1 })
        );
    }
    for class in [Bcc1, Ecc1] {
        assert_eq!(
            two(class, basic(1), basic(2).activations(2)),
            Some(ConfigError::ClassMultipleActivations { task: 1 })
        );
        assert_eq!(
            two(class, basic(3), basic(3)),
            Some(ConfigError::ClassSharedPriority { task: 1, other: 0 })
        );
    }
    assert_eq!(two(Bcc1, basic(1), basic(2)), None);
    assert_eq!(two(Bcc2, basic(3), basic(3).activations(4)), None);
    assert_eq!(two(Ecc1, basic(1), ext(2)), None);
    assert_eq!(two(Ecc2, ext(2), basic(2).activations(3)), None);
}

#[test]
fn isr_configuration_rules() {
    let one_task = [TaskConfig::basic("t", 1)];
    let isrs =
        |isrs| OsConfig::<1, 1, 0, 0, 2>::new(OsDescription::new(one_task, [], [], isrs)).err();
    let cat2 = IsrConfig::cat2;
    assert_eq!(
        isrs([cat2("a", 64), cat2("b", 1)]),
        Some(ConfigError::IsrPriority { isr: 0 })
    );
    assert_eq!(
        isrs([cat2("a", 1), cat2("b", 2).uses(0b10)]),
        Some(ConfigError::IsrResource { isr: 1 })
    );
    assert_eq!(
        isrs([cat2("a", 1), IsrConfig::cat1("b", 9).uses(0b1)]),
        Some(ConfigError::Cat1Resource { isr: 1 })
    );
    assert_eq!(
        isrs([IsrConfig::cat1("a", 4), cat2("b", 4)]),
        Some(ConfigError::Cat1BelowCat2 { cat1: 0, cat2: 1 })
    );
    assert_eq!(isrs([IsrConfig::cat1("a", 5), cat2("b", 4)]), None);
}

#[test]
fn start_os_activates_the_mode_autostart_and_calls_startup_hook() {
    static MODES: OsConfig<2, 0, 1, 2, 0> = match OsConfig::new(
        OsDescription::new(
            [
                TaskConfig::basic("A", 1).autostart(),
                TaskConfig::basic("B", 2).autostart_in(0b10),
            ],
            [COUNTER],
            [
                AlarmConfig::new("a0", CounterId(0), AlarmAction::ActivateTask(TaskId(0)))
                    .relative(5, 0),
                AlarmConfig::new("a1", CounterId(0), AlarmAction::ActivateTask(TaskId(1)))
                    .relative(7, 0)
                    .in_modes(0b11),
            ],
            [],
        )
        .app_modes(2),
    ) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut os = match Os::<2, 0, 1, 2, 0, 2>::new(&MODES) {
        Ok(os) => os,
        Err(e) => panic!("{e:?}"),
    };
    assert_eq!(os.context(), Context::BeforeStart);
    assert_eq!(os.activate_task(TaskId(0)), Err(OsError::CallLevel));
    assert_eq!(os.start_os(AppMode(2)), Err(OsError::Value));
    assert_eq!(os.phase(), Phase::BeforeStart);
    assert_eq!(os.start_os(AppMode(1)), Ok(()));
    assert_eq!(os.running(), Some(TaskId(1)));
    assert_eq!(os.get_active_application_mode(), Ok(AppMode(1)));
    assert!(!os.alarm_armed(AlarmId(0)));
    assert!(os.alarm_armed(AlarmId(1)));
    assert_eq!(os.start_os(AppMode(1)), Err(OsError::CallLevel));

    // The recording kernel: StartupHook sees the mode, then the first task is dispatched.
    let mut os = match TestOs::new(&CFG) {
        Ok(os) => os,
        Err(e) => panic!("{e:?}"),
    };
    assert_eq!(os.start_os(AppMode(1)), Ok(()));
    assert_eq!(os.hooks_mut().take(), [Seen::Startup(AppMode(1))]);
}

#[test]
fn activate_task_errors_and_limit() {
    let mut os = os();
    assert_eq!(os.running(), None);
    assert_eq!(os.context(), Context::Idle);
    assert_eq!(
        os.activate_task(LOW),
        Err(OsError::CallLevel),
        "the idle loop calls nothing"
    );
    assert_eq!(activate_from_isr(&mut os, TaskId(5)), Err(OsError::Id));
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.context(), Context::Task);
    // Two more activations queue up; the fourth is beyond the limit and changes nothing.
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.activate_task(LOW), Ok(()));
    let before = os;
    assert_eq!(os.activate_task(LOW), Err(OsError::Limit));
    assert!(spec::same_kernel_state(&os, &before));
    assert_eq!(os.activation_count(LOW), 3);
    // None is lost: the task runs three times.
    for remaining in (0..3).rev() {
        assert_eq!(os.running(), Some(LOW));
        assert_eq!(os.terminate_task(), Ok(()));
        assert_eq!(os.activation_count(LOW), remaining);
        check(&os);
    }
    assert_eq!(os.running(), None);
    assert_eq!(os.task_state(LOW), Some(TaskState::Suspended));
}

#[test]
fn preemption_and_fifo_within_a_priority() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    // Equal priority does not preempt, and queues behind in activation order.
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.ready_at(1).collect::<Vec<_>>(), [LOW2, LOW, LOW2]);
    // A higher priority preempts; the preempted task becomes the oldest of its priority.
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.get_task_state(LOW), Ok(TaskState::Ready));
    assert_eq!(os.ready_at(1).collect::<Vec<_>>(), [LOW, LOW2, LOW, LOW2]);
    check(&os);
    assert_eq!(os.terminate_task(), Ok(()));
    // The preempted instance resumes (it was started), then the queue in FIFO order.
    assert_eq!(os.running(), Some(LOW));
    assert!(os.is_started(LOW));
    let mut order = Vec::new();
    while let Some(t) = os.running() {
        order.push(t);
        assert_eq!(os.terminate_task(), Ok(()));
        check(&os);
    }
    assert_eq!(order, [LOW, LOW2, LOW, LOW2]);
}

#[test]
fn terminate_and_chain_errors() {
    let mut os = os();
    assert_eq!(os.terminate_task(), Err(OsError::CallLevel));
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.terminate_task(), Err(OsError::Resource));
    assert_eq!(os.chain_task(HIGH), Err(OsError::Resource));
    assert_eq!(os.schedule(), Err(OsError::Resource));
    assert_eq!(os.release_resource(R0), Ok(()));
    assert_eq!(os.chain_task(TaskId(9)), Err(OsError::Id));
    // At interrupt level.
    assert_eq!(
        in_isr(&mut os, TICK, |os| os.terminate_task()),
        Err(OsError::CallLevel)
    );
    assert_eq!(
        in_isr(&mut os, TICK, |os| os.schedule()),
        Err(OsError::CallLevel)
    );
    assert_eq!(os.exit_isr(), Err(OsError::CallLevel));
    // Chain to a task at its limit: E_OS_LIMIT and the caller keeps running.
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.chain_task(LOW2), Err(OsError::Limit));
    assert_eq!(os.running(), Some(LOW));
    // Chain to itself: the task is re-queued as the newest of its priority.
    assert_eq!(os.chain_task(LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW2));
    assert_eq!(os.ready_at(1).collect::<Vec<_>>(), [LOW2, LOW]);
    assert_eq!(os.activation_count(LOW), 1);
    check(&os);
    // Chain to a higher task.
    assert_eq!(os.chain_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.get_task_state(LOW2), Ok(TaskState::Ready));
    check(&os);
}

#[test]
fn non_preemptive_task_yields_only_at_schedule() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, NP), Ok(()));
    assert_eq!(os.running_priority(), Some(5));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(
        os.running(),
        Some(NP),
        "a non-preemptive task is not preempted"
    );
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.schedule(), Ok(()));
    assert_eq!(
        os.running(),
        Some(HIGH),
        "Schedule lets the higher task run"
    );
    assert_eq!(os.ready_at(2).next(), Some(NP));
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.running(), Some(NP));
    assert_eq!(
        os.running_priority(),
        Some(5),
        "internal resource taken again"
    );
    // Schedule with nothing higher keeps the task and its priority.
    assert_eq!(os.schedule(), Ok(()));
    assert_eq!(os.running(), Some(NP));
    assert_eq!(os.running_priority(), Some(5));
    check(&os);
}

/// A task holding every resource it may and `RES_SCHEDULER` (the most a stack can hold:
/// `R + 1`) sees them all, most recent first, and gives them back in that order.
#[test]
fn the_fullest_resource_stack_is_walked_whole() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, MID), Ok(()));
    assert_eq!(os.running(), Some(MID));
    for res in [R0, R1, RES_SCHEDULER] {
        assert_eq!(os.get_resource(res), Ok(()));
    }
    assert_eq!(
        os.held_resources(MID).collect::<Vec<_>>(),
        [RES_SCHEDULER, R1, R0]
    );
    check(&os);
    for res in [RES_SCHEDULER, R1, R0] {
        assert_eq!(os.release_resource(res), Ok(()));
    }
    assert_eq!(os.held_resources(MID).count(), 0);
    check(&os);
}

#[test]
fn resources_ceiling_and_lifo() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.get_resource(ResourceId(2)), Err(OsError::Id));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.running_priority(), Some(3));
    assert_eq!(os.get_resource(R0), Err(OsError::Access), "occupied");
    // Mid (priority 3) is not above the ceiling: no preemption; High is.
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    // High's priority is above R0's ceiling: E_OS_ACCESS both ways.
    assert_eq!(os.get_resource(R0), Err(OsError::Access));
    assert_eq!(os.release_resource(R0), Err(OsError::Access));
    assert_eq!(os.get_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.release_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.terminate_task(), Ok(()));
    // Low resumes at its ceiling, ahead of Mid.
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.running_priority(), Some(3));
    assert_eq!(os.get_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.running_priority(), Some(5));
    assert_eq!(os.release_resource(R0), Err(OsError::NoFunc), "not LIFO");
    assert_eq!(os.release_resource(R1), Err(OsError::NoFunc), "not held");
    assert_eq!(
        os.held_resources(LOW).collect::<Vec<_>>(),
        [RES_SCHEDULER, R0]
    );
    assert_eq!(os.release_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.running_priority(), Some(3));
    check(&os);
    // Releasing the last resource lowers the priority and lets Mid preempt.
    assert_eq!(os.release_resource(R0), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.ready_at(1).next(), Some(LOW));
    check(&os);
    // An ISR may not take RES_SCHEDULER nor a resource whose ceiling lies below it.
    assert_eq!(
        in_isr(&mut os, CAN, |os| os.get_resource(RES_SCHEDULER)),
        Err(OsError::Access)
    );
    assert_eq!(
        in_isr(&mut os, CAN, |os| os.get_resource(R0)),
        Err(OsError::Access)
    );
}

#[test]
fn a_resource_shared_with_an_isr_masks_it() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, MID), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::None);
    assert_eq!(os.get_resource(R1), Ok(()));
    // Mid now runs at the Can ISR's level: Can (3) and Tick (1) are held, Fast (6) is not.
    assert_eq!(os.running_priority(), Some(ISR_LEVEL_BASE + 3));
    assert_eq!(os.interrupt_mask(), InterruptMask::UpTo(3));
    assert_eq!(os.enter_isr(CAN), Err(OsError::Access));
    assert_eq!(os.enter_isr(TICK), Err(OsError::Access));
    assert_eq!(in_isr(&mut os, FAST, |_| Ok(())), Ok(()));
    assert_eq!(os.release_resource(R1), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::None);
    // The ISR takes it too, raising its own level (nothing above 3 shares it, so the mask
    // stays at 3) and releases it.
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.get_resource(R1), Ok(()));
    assert_eq!(os.isr_held_resources(CAN).collect::<Vec<_>>(), [R1]);
    assert_eq!(os.resource_isr_owner(R1), Some(CAN));
    assert_eq!(os.interrupt_mask(), InterruptMask::UpTo(3));
    check(&os);
    assert_eq!(os.release_resource(R1), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    check(&os);
}

#[test]
fn isrs_nest_by_priority_and_reschedule_when_the_last_returns() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.enter_isr(TICK), Ok(()));
    assert_eq!(os.context(), Context::Isr2);
    // Equal or lower priority stays pending; higher nests.
    assert_eq!(os.enter_isr(TICK), Err(OsError::Access));
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.enter_isr(TICK), Err(OsError::Access));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.get_task_id(), Ok(Some(LOW)), "GetTaskID in an ISR");
    assert_eq!(os.get_isr_id(), Ok(Some(CAN)));
    assert_eq!(os.enter_isr(FAST), Ok(()));
    assert_eq!(os.context(), Context::Isr1);
    assert_eq!(os.get_isr_id(), Err(OsError::CallLevel));
    assert_eq!(os.activate_task(HIGH), Err(OsError::CallLevel));
    assert_eq!(os.exit_isr(), Ok(()));
    check(&os);
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.running(), Some(LOW), "an ISR is still active");
    check(&os);
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.get_isr_id(), Ok(None));
    check(&os);
    // Bad port calls.
    assert_eq!(os.enter_isr(IsrId(3)), Err(OsError::Id));
}

#[test]
fn interrupt_locks_nest_mask_and_refuse_other_services() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    // Unpaired enable/resume: ignored.
    assert_eq!(os.enable_all_interrupts(), Err(OsError::NoFunc));
    assert_eq!(os.resume_all_interrupts(), Err(OsError::NoFunc));
    assert_eq!(os.resume_os_interrupts(), Err(OsError::NoFunc));
    check(&os);
    // SuspendOS holds the category-2 ISRs, not the category-1 one.
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::UpTo(3));
    assert_eq!(os.enter_isr(TICK), Err(OsError::Access));
    assert_eq!(in_isr(&mut os, FAST, |_| Ok(())), Ok(()));
    // Every other service is refused with E_OS_DISABLEDINT and changes nothing.
    let before = os;
    assert_eq!(os.activate_task(HIGH), Err(OsError::DisabledInt));
    assert_eq!(os.terminate_task(), Err(OsError::DisabledInt));
    assert_eq!(os.get_task_id(), Err(OsError::DisabledInt));
    assert!(spec::same_kernel_state(&os, &before));
    // Nesting across kinds; all interrupts held while SuspendAll is in force.
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::All);
    assert_eq!(os.enter_isr(FAST), Err(OsError::Access));
    assert_eq!(os.resume_all_interrupts(), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::All, "one level left");
    assert_eq!(os.resume_all_interrupts(), Ok(()));
    assert_eq!(os.resume_os_interrupts(), Ok(()));
    assert_eq!(os.interrupt_mask(), InterruptMask::None);
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    // DisableAll inside this context's SuspendAll section: refused and not carried out.
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.disable_all_interrupts(), Err(OsError::DisabledInt));
    assert!(!os.locks().all_disabled);
    assert_eq!(os.resume_all_interrupts(), Ok(()));
    // DisableAll does not nest.
    assert_eq!(os.disable_all_interrupts(), Ok(()));
    assert_eq!(os.disable_all_interrupts(), Err(OsError::NoFunc));
    assert_eq!(os.enable_all_interrupts(), Ok(()));
    assert_eq!(os.locks(), Locks::default());
    check(&os);
}

#[test]
fn events_wait_and_release() {
    let mut os = os();
    assert_eq!(
        activate_from_isr(&mut os, HIGH),
        Ok(()),
        "a task to call from"
    );
    assert_eq!(os.set_event(MID, 1), Err(OsError::State), "suspended");
    assert_eq!(os.set_event(LOW, 1), Err(OsError::Access), "basic task");
    assert_eq!(os.get_event(LOW), Err(OsError::Access));
    assert_eq!(os.get_event(MID), Err(OsError::State));
    assert_eq!(os.set_event(TaskId(7), 1), Err(OsError::Id));
    assert_eq!(os.wait_event(1), Err(OsError::Access));
    assert_eq!(os.clear_event(1), Err(OsError::Access));
    assert_eq!(
        in_isr(&mut os, TICK, |os| os.clear_event(1)),
        Err(OsError::CallLevel)
    );
    assert_eq!(
        in_isr(&mut os, TICK, |os| os.wait_event(1)),
        Err(OsError::CallLevel)
    );
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.wait_event(0b10), Err(OsError::Resource));
    assert_eq!(os.release_resource(R0), Ok(()));
    // An event already set: WaitEvent returns at once.
    assert_eq!(os.set_event(MID, 0b100), Ok(()));
    assert_eq!(os.wait_event(0b110), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.clear_event(0b100), Ok(()));
    assert_eq!(os.get_event(MID), Ok(0));
    // Wait: Low runs; an unrelated event does not release; a waited one does, at once.
    assert_eq!(os.wait_event(0b10), Ok(()));
    assert_eq!(os.get_task_state(MID), Ok(TaskState::Waiting));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.activate_task(MID), Err(OsError::Limit));
    assert_eq!(os.set_event(MID, 0b1), Ok(()));
    assert_eq!(os.get_task_state(MID), Ok(TaskState::Waiting));
    check(&os);
    assert_eq!(in_isr(&mut os, TICK, |os| os.set_event(MID, 0b10)), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.get_event(MID), Ok(0b11));
    check(&os);
    // Re-activation of an extended task clears its events.
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.get_event(MID), Ok(0));
}

#[test]
fn hooks_are_called_where_the_standard_says() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.hooks_mut().take(), [Seen::Pre(Some(LOW))]);
    // Preemption: PostTaskHook sees the old task, PreTaskHook the new one.
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Post(Some(LOW)),
            Seen::Pre(Some(HIGH)),
            Seen::Post(Some(HIGH)),
            Seen::Pre(Some(LOW)),
        ]
    );
    // An ISR that changes nothing switches nothing: no hooks.
    assert_eq!(in_isr(&mut os, TICK, |_| Ok(())), Ok(()));
    assert_eq!(os.hooks_mut().take(), []);
    // ErrorHook: the service and its parameters, and GetISRID inside an ISR.
    assert_eq!(os.activate_task(TaskId(9)), Err(OsError::Id));
    assert_eq!(
        in_isr(&mut os, CAN, |os| os.get_resource(R0)),
        Err(OsError::Access)
    );
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(OsError::Id, ServiceCall::ActivateTask(TaskId(9)), None),
            Seen::Error(OsError::Access, ServiceCall::GetResource(R0), Some(CAN)),
        ]
    );
    assert_eq!(os.error_service_id(), None, "only inside ErrorHook");
    // Never recursively: the failing call inside ErrorHook is not reported again.
    os.hooks_mut().fail_inside_error_hook = true;
    assert_eq!(os.set_rel_alarm(AlarmId(7), 1, 0), Err(OsError::Id));
    let seen = os.hooks_mut().take();
    assert_eq!(seen.len(), 1, "{seen:?}");
    os.hooks_mut().fail_inside_error_hook = false;
    // Alarm actions: a failing one goes to ErrorHook with its own service; a callback runs
    // at its own call level, where ActivateTask is refused.
    assert_eq!(os.set_rel_alarm(AlarmId(1), 1, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(2), 1, 0), Ok(()));
    assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(OsError::State, ServiceCall::SetEvent(MID, 1), None),
            // The refused ActivateTask inside the callback is reported too.
            Seen::Error(OsError::CallLevel, ServiceCall::ActivateTask(LOW), None),
            Seen::Callback(7, Err(OsError::CallLevel)),
        ]
    );
    check(&os);
}

#[test]
fn shutdown_calls_the_hook_and_stops_everything() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    os.hooks_mut().take();
    assert_eq!(os.set_rel_alarm(AlarmId(0), 5, 5), Ok(()));
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.shutdown_os(E_OK), Err(OsError::DisabledInt));
    assert_eq!(os.resume_all_interrupts(), Ok(()));
    assert_eq!(
        in_isr(&mut os, FAST, |os| os.shutdown_os(E_OK)),
        Err(OsError::CallLevel)
    );
    assert_eq!(os.shutdown_os(42), Ok(()));
    // No PostTaskHook at ShutdownOS (AUTOSAR SWS_Os_00071).
    assert_eq!(os.hooks_mut().take(), [Seen::Shutdown(42)]);
    assert!(os.is_shut_down());
    assert_eq!(os.running(), None);
    assert_eq!(os.interrupt_mask(), InterruptMask::All);
    assert_eq!(os.enter_isr(TICK), Err(OsError::State));
    assert_eq!(os.activate_task(LOW), Err(OsError::CallLevel));
    assert!(!os.alarm_armed(AlarmId(0)));
    check(&os);

    // From ErrorHook, inside an ISR: the ISR's return finds nothing left to do.
    let mut os = os_after(|os| os.hooks_mut().shutdown_in_error_hook = true);
    assert_eq!(os.enter_isr(TICK), Ok(()));
    assert_eq!(os.activate_task(TaskId(9)), Err(OsError::Id));
    assert!(os.is_shut_down());
    assert_eq!(os.exit_isr(), Err(OsError::State));
    assert_eq!(
        os.hooks_mut().take().last(),
        Some(&Seen::Shutdown(OsError::Id.status()))
    );
    check(&os);
}

/// The OS shut down inside PostTaskHook (a service refused there, and ErrorHook shutting
/// down): every way out of the running state stops at once, nothing else is dispatched.
#[test]
fn shutdown_inside_post_task_hook_ends_every_way_out_of_a_task() {
    type Leave = fn(&mut TestOs) -> Result<(), OsError>;
    let ways: [(&str, TaskId, Leave); 6] = [
        ("TerminateTask", LOW, |os| os.terminate_task()),
        ("preempted", LOW, |os| os.activate_task(HIGH)),
        // Preempted at an ISR's return: the switch is the return's.
        ("preempted at an ISR's return", LOW, |os| {
            in_isr(os, CAN, |os| os.activate_task(HIGH))
        }),
        ("ChainTask", LOW, |os| os.chain_task(HIGH)),
        ("WaitEvent", MID, |os| os.wait_event(1)),
        ("return", LOW, |os| os.task_returned()),
    ];
    for (name, task, leave) in ways {
        let mut os = os();
        assert_eq!(activate_from_isr(&mut os, task), Ok(()));
        assert_eq!(os.running(), Some(task), "{name}");
        os.hooks_mut().fail_inside_post_task_hook = true;
        os.hooks_mut().shutdown_on_error = Some(OsError::CallLevel);
        os.hooks_mut().take();
        let _ = leave(&mut os);
        assert!(os.is_shut_down(), "{name}");
        assert_eq!(os.running(), None, "{name}");
        let seen = os.hooks_mut().take();
        let post = seen.iter().position(|s| *s == Seen::Post(Some(task)));
        assert!(post.is_some(), "{name}: {seen:?}");
        assert_eq!(
            seen.last(),
            Some(&Seen::Shutdown(OsError::CallLevel.status())),
            "{name}: {seen:?}"
        );
        assert!(
            !seen.iter().any(|s| matches!(s, Seen::Pre(_))),
            "{name}: nothing is dispatched after the shutdown: {seen:?}"
        );
        check(&os);
    }
}

/// `ShutdownOS` called by `ErrorHook` ends the service that reported: the alarms that
/// expire on the same tick, the ISR's return, the task's missing end go no further.
#[test]
fn shutdown_inside_error_hook_ends_the_reporting_path() {
    {
        // An alarm's activation over the limit, with a callback alarm due on the same tick.
        let mut os = os();
        assert_eq!(os.enter_isr(TICK), Ok(()));
        assert_eq!(os.activate_task(HIGH), Ok(()));
        assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
        assert_eq!(os.set_rel_alarm(AlarmId(2), 1, 0), Ok(()));
        os.hooks_mut().shutdown_on_error = Some(OsError::Limit);
        os.hooks_mut().take();
        assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
        assert!(os.is_shut_down());
        let seen = os.hooks_mut().take();
        assert_eq!(
            seen.last(),
            Some(&Seen::Shutdown(OsError::Limit.status())),
            "{seen:?}"
        );
        assert!(
            !seen.iter().any(|s| matches!(s, Seen::Callback(..))),
            "no alarm runs after the shutdown: {seen:?}"
        );
        assert_eq!(os.exit_isr(), Err(OsError::State));
        check(&os);
    }
    {
        // A category-2 ISR returns under a lock it took.
        let mut os = os();
        assert_eq!(os.enter_isr(TICK), Ok(()));
        assert_eq!(os.suspend_os_interrupts(), Ok(()));
        os.hooks_mut().shutdown_on_error = Some(OsError::DisabledInt);
        os.hooks_mut().take();
        assert_eq!(os.exit_isr(), Ok(()));
        assert!(os.is_shut_down());
        assert_eq!(os.isr_nesting(), 0);
        assert_eq!(os.locks(), Locks::default());
        check(&os);
    }
    {
        // A task's body returns without TerminateTask: no PostTaskHook after the shutdown.
        let mut os = os();
        assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
        os.hooks_mut().shutdown_on_error = Some(OsError::MissingEnd);
        os.hooks_mut().take();
        assert_eq!(os.task_returned(), Ok(()));
        assert!(os.is_shut_down());
        assert_eq!(
            os.hooks_mut().take(),
            [
                Seen::Error(OsError::MissingEnd, ServiceCall::TaskMissingEnd(LOW), None),
                Seen::Shutdown(OsError::MissingEnd.status()),
            ]
        );
        check(&os);
    }
}

/// A second shutdown (the board reporting a fault after `ShutdownOS`) changes nothing and
/// does not call `ShutdownHook` again.
#[test]
fn a_second_shutdown_changes_nothing() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.shutdown_os(OsError::Value.status()), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Pre(Some(LOW)),
            Seen::Shutdown(OsError::Value.status())
        ]
    );
    let before = os;
    os.shutdown_on_fault(OsError::StackFault);
    assert_eq!(os, before);
    assert_eq!(os.hooks_mut().take(), []);
}

/// Without a `ShutdownHook` configured, `ShutdownOS` stops the OS all the same.
#[test]
fn shutdown_without_a_shutdown_hook() {
    let mut os = small_started();
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    assert_eq!(os.activate_task(TaskId(0)), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.running(), Some(TaskId(0)));
    assert_eq!(os.shutdown_os(OsError::Value.status()), Ok(()));
    assert_eq!(os.phase(), Phase::ShutDown);
    assert_eq!(os.running(), None);
    assert_eq!(os.activation_count(TaskId(0)), 0);
    assert!(spec::kernel_invariants(&os));
}

/// Only the port returns from an ISR: a hook running inside one (here `ErrorHook`) that
/// tries is refused with `E_OS_CALLEVEL`, and the ISR stays active.
#[test]
fn exit_isr_from_a_hook_inside_an_isr_is_refused() {
    let mut os = os();
    assert_eq!(os.enter_isr(TICK), Ok(()));
    os.hooks_mut().exit_isr_in_error_hook = true;
    os.hooks_mut().take();
    assert_eq!(os.activate_task(TaskId(9)), Err(OsError::Id));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(
                OsError::Id,
                ServiceCall::ActivateTask(TaskId(9)),
                Some(TICK)
            ),
            Seen::ExitIsr(Err(OsError::CallLevel)),
        ]
    );
    assert_eq!(os.isr_nesting(), 1);
    assert_eq!(os.exit_isr(), Ok(()));
    check(&os);
}

/// A hook that returns with an interrupt lock in force has it undone; `PreTaskHook`'s is
/// reported to `ErrorHook` (`E_OS_DISABLEDINT`), `ErrorHook`'s own is not (it would call
/// itself).
#[test]
fn locks_left_by_hooks_are_undone() {
    let mut os = os();
    os.hooks_mut().leave_lock_in_hooks = true;
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Pre(Some(LOW)),
            Seen::Error(OsError::DisabledInt, ServiceCall::HookMissingEnd, None),
        ]
    );
    assert_eq!(os.locks(), Locks::default());
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    check(&os);
}

#[test]
fn after_an_isr_inside_error_hook_a_higher_activation_preempts_at_once() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    os.hooks_mut().fast_isr_in_error_hook = true;
    // A refused call of the task's: ErrorHook, which the category-1 ISR interrupts.
    assert_eq!(os.activate_task(TaskId(9)), Err(OsError::Id));
    os.hooks_mut().fast_isr_in_error_hook = false;
    assert!(os.hooks_mut().take().contains(&Seen::ExitIsr(Ok(()))));
    check(&os);
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    check(&os);
}

/// The resources each task may lock outside the kernel, as the configuration derives
/// them (built at run time here, so that the derivation is measured): a task's own
/// resources, those an ISR shares too among them (the port masks the ISRs itself); none
/// for a non-preemptive task, or an unknown index.
#[test]
fn lock_free_resources_are_a_preemptive_tasks_own() {
    let description = OsDescription::new(
        [
            TaskConfig::basic("A", 1).uses(0b011),
            TaskConfig::basic("B", 2).uses(0b110),
            TaskConfig::basic("N", 3).uses(0b010).non_preemptive(),
        ],
        [],
        [],
        // Resource 2 is the ISRs' too (the first one's level is its ceiling).
        [
            IsrConfig::cat2("J", 2).uses(0b100),
            IsrConfig::cat2("I", 1).uses(0b100),
        ],
    );
    let Ok(cfg) = std::hint::black_box(OsConfig::<3, 3, 0, 0, 2>::new(description)) else {
        panic!("the configuration is valid")
    };
    // Resource 2, which the ISRs share, in the second twelve bits: its lock masks them.
    assert_eq!(cfg.lock_free_resources(0), 0b011);
    assert_eq!(cfg.lock_free_resources(1), 0b010 | 1 << (12 + 2));
    assert_eq!(cfg.lock_free_resources(2), 0);
    assert_eq!(cfg.lock_free_resources(3), 0);
    assert_eq!(cfg.resource_ceiling(2), Some(ISR_LEVEL_BASE + 2));
    // The kind a resource's type carries, from the same ceilings.
    let kinds = [0, 1, 2, 3].map(|r| cfg.isr_shared(ResourceId(r)));
    assert_eq!(kinds, [false, false, true, false]);
}

/// The answer's bit of a resource says which kind of lock it is: bit `r` for one that
/// masks nothing, bit `12 + r` for one that masks ISRs; none from resource 12 on, where a
/// task's lock always goes through the kernel. The answer fits in its low 24 bits.
#[test]
fn the_lock_free_bit_says_the_kind_of_lock() {
    for r in 0..=u8::MAX {
        let (unmasked, masked) = (
            crate::os::lock_free_bit(ResourceId(r), false),
            crate::os::lock_free_bit(ResourceId(r), true),
        );
        if r < crate::os::LOCK_FREE_RESOURCES {
            assert_eq!((unmasked, masked), (1 << r, 1 << (12 + r)), "{r}");
            assert!(masked < 1 << 24, "{r}");
        } else {
            assert_eq!((unmasked, masked), (0, 0), "{r}");
        }
    }
    // A task's resources from 12 on are never named, of either kind.
    let description = OsDescription::new(
        [TaskConfig::basic("A", 1).uses(1 << 12 | 1 << 13 | 1)],
        [],
        [],
        [IsrConfig::cat2("I", 0).uses(1 << 13)],
    );
    let Ok(cfg) = std::hint::black_box(OsConfig::<1, 14, 0, 0, 1>::new(description)) else {
        panic!("the configuration is valid")
    };
    assert_eq!(cfg.lock_free_resources(0), 0b1);
    // An ISR of priority 0 makes the lowest interrupt-level ceiling: shared all the same.
    assert_eq!(cfg.resource_ceiling(13), Some(ISR_LEVEL_BASE));
    assert!(cfg.isr_shared(ResourceId(13)));
    assert!(!cfg.isr_shared(ResourceId(12)));
}

/// A ready queue of more than 255 records cannot be indexed by the kernel's `u8` links;
/// one of exactly 255 can, and holds every record the configuration allows.
#[test]
fn ready_queue_of_255_records_is_the_largest() {
    const fn two_tasks(a: u8, b: u8) -> OsConfig<2, 0, 0, 0, 1> {
        match OsConfig::new(OsDescription::new(
            [
                TaskConfig::basic("A", 1).activations(a),
                TaskConfig::basic("B", 2).activations(b),
            ],
            [],
            [],
            [IsrConfig::cat2("I", 1)],
        )) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        }
    }
    static BIG: OsConfig<2, 0, 0, 0, 1> = two_tasks(200, 100);
    static FULL: OsConfig<2, 0, 0, 0, 1> = two_tasks(200, 55);
    assert_eq!(BIG.total_activations(), 300);
    assert_eq!(
        Os::<2, 0, 0, 0, 1, 300>::new(&BIG).err(),
        Some(ConfigError::QueueCapacity { needed: 300 })
    );
    assert_eq!(FULL.total_activations(), 255);
    let Ok(mut os) = Os::<2, 0, 0, 0, 1, 255>::new(&FULL) else {
        panic!("255 records refused");
    };
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    for (task, n) in [(TaskId(0), 200), (TaskId(1), 55)] {
        for _ in 0..n {
            assert_eq!(os.activate_task(task), Ok(()));
        }
        assert_eq!(os.activate_task(task), Err(OsError::Limit));
    }
    assert_eq!(os.exit_isr(), Ok(()));
    // Every record comes out: B's 55, then A's 200.
    let mut order = Vec::new();
    while let Some(task) = os.running() {
        order.push(task);
        assert_eq!(os.terminate_task(), Ok(()));
    }
    assert_eq!(order.len(), 255);
    assert!(order[..55].iter().all(|t| *t == TaskId(1)));
    assert!(order[55..].iter().all(|t| *t == TaskId(0)));
}

/// Before its first start a task's saved priority is its configured one (what
/// `saved_priority` promises for a task not yet started), before and after `StartOS`.
#[test]
fn a_task_not_yet_started_has_its_configured_priority() {
    let Ok(mut os) = TestOs::new(&CFG) else {
        panic!("test configuration refused");
    };
    let configured = [1, 3, 5, 2, 1];
    for (t, prio) in configured.iter().enumerate() {
        assert_eq!(os.saved_priority(TaskId(t as u8)), Some(*prio));
    }
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    for (t, prio) in configured.iter().enumerate() {
        assert_eq!(os.saved_priority(TaskId(t as u8)), Some(*prio));
    }
    assert_eq!(os.saved_priority(TaskId(5)), None);
}

/// The inspection functions (what the oracles read) report the kernel's state: the
/// highest ready priority beside the running task, and a waiting task's mask and events.
#[test]
fn inspection_reports_ready_priorities_masks_and_events() {
    let mut os = os();
    assert_eq!(os.highest_ready(), None);
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.highest_ready(), None, "the running task is not ready");
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.highest_ready(), Some(1));
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.highest_ready(), Some(1));
    assert_eq!(os.activate_task(NP), Ok(()));
    assert_eq!(os.highest_ready(), Some(2));
    assert_eq!((os.wait_mask(MID), os.events(MID)), (0, 0));
    assert_eq!(os.wait_event(0b10), Ok(()));
    // Mid waits; Np (priority 2) runs.
    assert_eq!(os.running(), Some(NP));
    assert_eq!((os.wait_mask(MID), os.events(MID)), (0b10, 0));
    assert_eq!(os.set_event(MID, 0b01), Ok(()));
    assert_eq!((os.wait_mask(MID), os.events(MID)), (0b10, 0b01));
    assert!(os.is_waiting(MID));
    assert_eq!(os.set_event(MID, 0b10), Ok(()));
    // Np is non-preemptive: Mid is ready, with both events and no mask.
    assert_eq!(os.running(), Some(NP));
    assert_eq!(os.highest_ready(), Some(3));
    assert_eq!((os.wait_mask(MID), os.events(MID)), (0, 0b11));
    // Np runs at the scheduler's ceiling (its internal resource); no priority beyond the
    // last task.
    assert_eq!(os.dispatch_priority(NP), Some(5));
    assert_eq!(os.dispatch_priority(MID), Some(3));
    assert_eq!(os.dispatch_priority(TaskId(5)), None);
    check(&os);
}

/// Kernels compare equal only over the same configuration (a model checker merging states
/// by equality must not merge two systems), and their `Debug` names the configuration
/// rather than printing its tables.
#[test]
fn kernels_over_different_configurations_differ() {
    // The same tables at another address: another configuration.
    static OTHER: OsConfig<5, 2, 1, 3, 3> = CONFIG;
    let other = &OTHER;
    let (Ok(a), Ok(b), Ok(c)) = (TestOs::new(&CFG), TestOs::new(&CFG), TestOs::new(other)) else {
        panic!("test configuration refused");
    };
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert!(std::format!("{a:?}").contains("cfg: OsConfig,"));
}

fn os_after(setup: impl FnOnce(&mut TestOs)) -> TestOs {
    let mut os = os();
    setup(&mut os);
    os
}

#[test]
fn missing_ends_are_cleaned_up_and_reported() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    os.hooks_mut().take();
    // The task's body returns holding a resource and a lock.
    assert_eq!(os.task_returned(), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(OsError::MissingEnd, ServiceCall::TaskMissingEnd(LOW), None),
            Seen::Post(Some(LOW)),
            Seen::Pre(Some(LOW)),
        ]
    );
    assert_eq!(os.locks(), Locks::default());
    assert_eq!(os.resource_owner(R0), None);
    assert_eq!(os.activation_count(LOW), 1);
    check(&os);
    // A category-2 ISR returns holding a resource and a lock.
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.get_resource(R1), Ok(()));
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(
                OsError::DisabledInt,
                ServiceCall::IsrMissingEnd(CAN),
                Some(CAN)
            ),
            Seen::Error(
                OsError::Resource,
                ServiceCall::IsrMissingEnd(CAN),
                Some(CAN)
            ),
        ]
    );
    assert_eq!(os.resource_isr_owner(R1), None);
    assert_eq!(
        os.isr_held_resources(CAN).count(),
        0,
        "CAN is no longer active"
    );
    assert_eq!(os.interrupt_mask(), InterruptMask::None);
    check(&os);
    // Each kind of missing end alone is reported alone.
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.get_resource(R1), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [Seen::Error(
            OsError::Resource,
            ServiceCall::IsrMissingEnd(CAN),
            Some(CAN)
        )]
    );
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [Seen::Error(
            OsError::DisabledInt,
            ServiceCall::IsrMissingEnd(CAN),
            Some(CAN)
        )]
    );
    // A category-1 ISR's lock is undone without ErrorHook (it is outside the OS).
    assert_eq!(os.enter_isr(FAST), Ok(()));
    assert_eq!(os.suspend_all_interrupts(), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.hooks_mut().take(), []);
    assert_eq!(os.locks(), Locks::default());
    check(&os);
}

/// A category-1 ISR taken inside PreTaskHook returns to the hook: no rescheduling, and the
/// hook goes on at its own call level.
#[test]
fn an_isr_inside_a_hook_returns_to_the_hook() {
    let mut os = os();
    os.hooks_mut().fast_isr_in_pre_task_hook = true;
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Pre(Some(LOW)),
            Seen::ExitIsr(Ok(())),
            Seen::At(Context::PreTaskHook)
        ]
    );
    assert_eq!((os.running(), os.context()), (Some(LOW), Context::Task));
    check(&os);
}

/// A category-1 ISR inside `PreTaskHook` raised the preemption threshold at its entry; its
/// return to the hook puts back the task's, so the task that then runs is preempted by a
/// higher-priority activation at once (it kept the raised threshold, and ran on past the
/// higher task it activated, before). The same inside `ErrorHook`, below.
#[test]
fn after_an_isr_inside_a_hook_a_higher_activation_preempts_at_once() {
    let mut os = os();
    os.hooks_mut().fast_isr_in_pre_task_hook = true;
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    os.hooks_mut().fast_isr_in_pre_task_hook = false;
    check(&os);
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    check(&os);
}

/// The board's fault path: `ShutdownOS` with the fault's status, `ShutdownHook` told it.
#[test]
fn a_fault_shuts_the_os_down_with_its_status() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    os.hooks_mut().take();
    os.shutdown_on_fault(OsError::StackFault);
    assert_eq!(
        os.hooks_mut().take(),
        [Seen::Shutdown(OsError::StackFault.status())]
    );
    assert_eq!((os.phase(), os.running()), (Phase::ShutDown, None));
    check(&os);
}

#[test]
fn dialects_differ_where_the_standards_do() {
    fn config(dialect: Dialect) -> OsConfig<1, 0, 1, 1, 0> {
        match OsConfig::new(
            OsDescription::new(
                [TaskConfig::basic("T", 1).autostart()],
                [COUNTER],
                [AlarmConfig::new(
                    "a",
                    CounterId(0),
                    AlarmAction::ActivateTask(TaskId(0)),
                )],
                [],
            )
            .dialect(dialect),
        ) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        }
    }
    static OSEK: std::sync::LazyLock<OsConfig<1, 0, 1, 1, 0>> =
        std::sync::LazyLock::new(|| config(Dialect::Osek));
    static AUTOSAR: std::sync::LazyLock<OsConfig<1, 0, 1, 1, 0>> =
        std::sync::LazyLock::new(|| config(Dialect::Autosar));
    let start = |cfg: &'static OsConfig<1, 0, 1, 1, 0>| {
        let Ok(os) = Os::<1, 0, 1, 1, 0, 1>::new(cfg) else {
            panic!("refused");
        };
        os
    };
    // Interrupt services before StartOS: AUTOSAR only (SWS_Os_00299).
    let mut osek = start(&OSEK);
    let mut autosar = start(&AUTOSAR);
    assert_eq!(osek.suspend_all_interrupts(), Err(OsError::CallLevel));
    assert_eq!(autosar.suspend_all_interrupts(), Ok(()));
    assert_eq!(autosar.resume_all_interrupts(), Ok(()));
    assert_eq!(autosar.suspend_os_interrupts(), Err(OsError::CallLevel));
    // Start-up code may disable interrupts before StartOS; the OS starts anyway, unlocked.
    assert_eq!(autosar.disable_all_interrupts(), Ok(()));
    assert_eq!(osek.start_os(OSDEFAULTAPPMODE), Ok(()));
    assert_eq!(autosar.start_os(OSDEFAULTAPPMODE), Ok(()));
    assert_eq!(autosar.locks(), Locks::default());
    assert_eq!(autosar.running(), Some(TaskId(0)));
    // SetRelAlarm with increment 0.
    assert_eq!(autosar.set_rel_alarm(AlarmId(0), 0, 0), Err(OsError::Value));
    assert_eq!(osek.set_rel_alarm(AlarmId(0), 0, 0), Ok(()));
    assert_eq!(
        osek.alarm_remaining(AlarmId(0)),
        Some(100),
        "a full revolution"
    );
    // The call-level tables differ only in the interrupt services.
    for context in Context::ALL {
        let diff = callevel::allowed(Dialect::Osek, context)
            ^ callevel::allowed(Dialect::Autosar, context);
        assert_eq!(diff & !callevel::INTERRUPT_SERVICES, 0, "{context:?}");
    }
}

/// An alarm's ticks are kept in 32 bits: no delay exceeds `u32::MAX` (the largest counter
/// stops one below it, and standard status, which does not check an increment against the
/// counter, arms at most `u32::MAX` ahead). At the top of that range the deltas add up to
/// each alarm's remaining ticks, an alarm inserted before another or cancelled leaves the
/// other's as it was, and the fast ticks count them down exactly.
#[test]
fn alarms_at_the_top_of_the_32_bit_range_keep_their_ticks() {
    const TOP: CounterConfig = CounterConfig {
        max_allowed_value: TickType::MAX - 1,
        ticks_per_base: 1,
        min_cycle: 1,
    };
    static TOP_CFG: std::sync::LazyLock<OsConfig<1, 1, 1, 3, 1>> = std::sync::LazyLock::new(|| {
        match OsConfig::new(
            OsDescription::new(
                [TaskConfig::basic("T", 1).activations(3).autostart()],
                [TOP],
                [
                    AlarmConfig::new("a", CounterId(0), AlarmAction::ActivateTask(TaskId(0))),
                    AlarmConfig::new("b", CounterId(0), AlarmAction::ActivateTask(TaskId(0))),
                    AlarmConfig::new("c", CounterId(0), AlarmAction::ActivateTask(TaskId(0))),
                ],
                [IsrConfig::cat2("Tick", 1)],
            )
            .status(Status::Standard)
            .dialect(Dialect::Osek),
        ) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        }
    });
    let Ok(mut os) = Os::<1, 1, 1, 3, 1, 3>::new(&*TOP_CFG) else {
        panic!("refused");
    };
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    let (a, b, c) = (AlarmId(0), AlarmId(1), AlarmId(2));
    // Standard status arms beyond the counter's range; the OSEK dialect's increment 0 is a
    // full revolution, `maxallowedvalue + 1`.
    assert_eq!(os.set_rel_alarm(a, TickType::MAX, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(b, 0, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(c, 5, 0), Ok(()));
    assert_eq!(os.alarm_remaining(a), Some(u64::from(TickType::MAX)));
    assert_eq!(os.alarm_remaining(b), Some(u64::from(TickType::MAX)));
    assert_eq!(os.alarm_remaining(c), Some(5));
    assert_eq!(os.get_alarm(a), Ok(TickType::MAX));
    assert_eq!(os.ticks_to_expiry(CounterId(0)), Some(5));
    // Four ticks at once by the fast path, then one: c is due.
    assert!(os.try_ticks(IsrId(0), CounterId(0), 4).is_some());
    assert_eq!(os.alarm_remaining(a), Some(u64::from(TickType::MAX) - 4));
    assert_eq!(os.try_ticks(IsrId(0), CounterId(0), 1), None);
    // Cancelling b, the one just before a in the list, leaves a's ticks as they were.
    assert_eq!(os.cancel_alarm(b), Ok(()));
    assert_eq!(os.alarm_remaining(a), Some(u64::from(TickType::MAX) - 4));
    assert_eq!(os.ticks_to_expiry(CounterId(0)), Some(1));
    assert!(spec::kernel_invariants(&os));
}

#[test]
fn standard_status_leaves_out_only_harmless_checks() {
    fn config(status: Status) -> OsConfig<2, 1, 1, 1, 1> {
        match OsConfig::new(
            OsDescription::new(
                [
                    TaskConfig::basic("B", 1).uses(0b1),
                    TaskConfig::basic("H", 4).autostart(),
                ],
                [COUNTER],
                [AlarmConfig::new(
                    "a",
                    CounterId(0),
                    AlarmAction::ActivateTask(TaskId(0)),
                )],
                [IsrConfig::cat2("I", 1)],
            )
            .status(status),
        ) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        }
    }
    static STANDARD: std::sync::LazyLock<OsConfig<2, 1, 1, 1, 1>> =
        std::sync::LazyLock::new(|| config(Status::Standard));
    static EXTENDED: std::sync::LazyLock<OsConfig<2, 1, 1, 1, 1>> =
        std::sync::LazyLock::new(|| config(Status::Extended));
    let start = |cfg: &'static OsConfig<2, 1, 1, 1, 1>| {
        let Ok(mut os) = Os::<2, 1, 1, 1, 1, 2>::new(cfg) else {
            panic!("refused");
        };
        assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
        os
    };
    let (mut std_os, mut ext_os) = (start(&STANDARD), start(&EXTENDED));
    // H (4) above R0's ceiling (1); an increment above the counter's range; events of a
    // basic task: refused in extended status only.
    assert_eq!(ext_os.get_resource(ResourceId(0)), Err(OsError::Access));
    assert_eq!(std_os.get_resource(ResourceId(0)), Ok(()));
    assert_eq!(std_os.release_resource(ResourceId(0)), Ok(()));
    assert_eq!(
        ext_os.set_rel_alarm(AlarmId(0), 500, 0),
        Err(OsError::Value)
    );
    assert_eq!(std_os.set_rel_alarm(AlarmId(0), 500, 0), Ok(()));
    assert_eq!(ext_os.get_event(TaskId(1)), Err(OsError::Access));
    assert_eq!(std_os.get_event(TaskId(1)), Ok(0));
    // Checks that keep the kernel consistent stay (extended status finds the caller above
    // the ceiling first).
    assert_eq!(std_os.release_resource(ResourceId(0)), Err(OsError::NoFunc));
    assert_eq!(ext_os.release_resource(ResourceId(0)), Err(OsError::Access));
    // The lock's fast paths take a lock only at or below the ceiling, where the access
    // check passes in either status: above it they decline, from a task and from an ISR,
    // in both statuses, and the service decides (above: standard status takes the lock,
    // extended status refuses it).
    for os in [&mut std_os, &mut ext_os] {
        assert_eq!(os.try_get_resource(ResourceId(0)), None);
        assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
        assert_eq!(os.try_get_resource(ResourceId(0)), None);
        assert_eq!(os.exit_isr(), Ok(()));
    }
    for os in [&mut std_os, &mut ext_os] {
        assert_eq!(os.activate_task(TaskId(2)), Err(OsError::Id));
        assert_eq!(os.wait_event(1), Err(OsError::Access));
        assert!(spec::kernel_invariants(os));
    }
}

#[test]
fn alarms_relative_absolute_cyclic() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    os.hooks_mut().take();
    let (act_high, cb) = (AlarmId(0), AlarmId(2));
    assert_eq!(os.set_rel_alarm(AlarmId(3), 1, 0), Err(OsError::Id));
    assert_eq!(os.set_rel_alarm(act_high, 100, 0), Err(OsError::Value));
    assert_eq!(os.set_rel_alarm(act_high, 5, 100), Err(OsError::Value));
    assert_eq!(os.get_alarm(act_high), Err(OsError::NoFunc));
    assert_eq!(os.cancel_alarm(act_high), Err(OsError::NoFunc));
    assert_eq!(os.set_rel_alarm(act_high, 5, 10), Ok(()));
    assert_eq!(os.set_rel_alarm(act_high, 5, 10), Err(OsError::State));
    assert_eq!(os.get_alarm(act_high), Ok(5));
    assert_eq!(
        os.get_alarm_base(act_high),
        Ok(AlarmBase {
            max_allowed_value: 99,
            ticks_per_base: 1,
            min_cycle: 1
        })
    );
    // Absolute at value 3 (now 0): 3 ticks away; the callback alarm at the current value
    // waits a full revolution.
    assert_eq!(os.set_abs_alarm(cb, 100, 0), Err(OsError::Value));
    assert_eq!(os.set_abs_alarm(cb, 0, 0), Ok(()));
    assert_eq!(os.get_alarm(cb), Ok(100));
    assert_eq!(os.cancel_alarm(cb), Ok(()));
    assert_eq!(os.set_abs_alarm(cb, 3, 0), Ok(()));
    assert_eq!(os.get_alarm(cb), Ok(3));
    os.hooks_mut().take();
    let mut high_runs = Vec::new();
    for tick in 1..=30u32 {
        assert_eq!(
            in_isr(&mut os, TICK, |os| os.increment_counter(CounterId(0))),
            Ok(())
        );
        if os.running() == Some(HIGH) {
            high_runs.push(tick);
            assert_eq!(os.terminate_task(), Ok(()));
        }
        check(&os);
    }
    assert_eq!(high_runs, [5, 15, 25]);
    let callbacks: Vec<_> = os
        .hooks_mut()
        .take()
        .into_iter()
        .filter(|s| matches!(s, Seen::Callback(..)))
        .collect();
    assert_eq!(callbacks, [Seen::Callback(7, Err(OsError::CallLevel))]);
    assert_eq!(os.counter_value(CounterId(0)), Some(30));
    assert_eq!(os.get_counter_value(CounterId(0)), Ok(30));
    assert_eq!(os.get_elapsed_value(CounterId(0), 95), Ok((30, 35)));
    assert_eq!(os.get_elapsed_value(CounterId(0), 100), Err(OsError::Value));
    assert_eq!(os.get_alarm(act_high), Ok(5));
    assert_eq!(os.increment_counter(CounterId(1)), Err(OsError::Id));
    assert_eq!(os.cancel_alarm(act_high), Ok(()));
    assert!(!os.alarm_armed(act_high));
}

#[test]
fn counter_wraps_and_simultaneous_alarms_fire_in_arming_order() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    for _ in 0..98 {
        assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    }
    assert_eq!(os.counter_value(CounterId(0)), Some(98));
    assert_eq!(os.set_abs_alarm(AlarmId(2), 1, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 3, 0), Ok(()));
    assert_eq!(os.get_alarm(AlarmId(2)), Ok(3));
    assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    assert_eq!(os.counter_value(CounterId(0)), Some(0));
    assert_eq!(os.running(), Some(LOW));
    os.hooks_mut().take();
    assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    // The callback (armed first) runs before High is activated and dispatched.
    assert_eq!(
        os.hooks_mut().take(),
        [
            Seen::Error(OsError::CallLevel, ServiceCall::ActivateTask(LOW), None),
            Seen::Callback(7, Err(OsError::CallLevel)),
            Seen::Post(Some(LOW)),
            Seen::Pre(Some(HIGH)),
        ]
    );
    assert_eq!(os.running(), Some(HIGH));
}

#[test]
fn cancelling_an_alarm_deep_in_its_counters_list_keeps_the_others() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    // One counter, three alarms 2, 4 and 7 ticks away: the delta list is Cb -> ActHigh -> EvMid.
    assert_eq!(os.set_rel_alarm(AlarmId(2), 2, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 4, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(1), 7, 0), Ok(()));
    // Cancelling the last walks past the head (whose successor is another alarm).
    assert_eq!(os.cancel_alarm(AlarmId(1)), Ok(()));
    check(&os);
    assert!(!os.alarm_armed(AlarmId(1)));
    assert_eq!(os.get_alarm(AlarmId(2)), Ok(2));
    assert_eq!(os.get_alarm(AlarmId(0)), Ok(4));
    // Cancelling the middle one links the head to the last; both keep their times.
    assert_eq!(os.set_rel_alarm(AlarmId(1), 7, 0), Ok(()));
    assert_eq!(os.cancel_alarm(AlarmId(0)), Ok(()));
    check(&os);
    assert_eq!(os.get_alarm(AlarmId(2)), Ok(2));
    assert_eq!(os.get_alarm(AlarmId(1)), Ok(7));
}

/// Alarms on two counters: each alarm follows its own counter (its limits, its base, its
/// ticks), and cancelling one leaves the other counter's list alone.
#[test]
fn alarms_follow_their_own_counter() {
    static TWO: OsConfig<2, 0, 2, 2, 1> = match OsConfig::new(OsDescription::new(
        [TaskConfig::basic("A", 1), TaskConfig::basic("B", 2)],
        [
            COUNTER,
            CounterConfig {
                max_allowed_value: 9,
                ticks_per_base: 2,
                min_cycle: 2,
            },
        ],
        [
            AlarmConfig::new(
                "OnFirst",
                CounterId(0),
                AlarmAction::ActivateTask(TaskId(0)),
            ),
            AlarmConfig::new(
                "OnSecond",
                CounterId(1),
                AlarmAction::ActivateTask(TaskId(1)),
            ),
        ],
        [IsrConfig::cat2("Tick", 1)],
    )) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut os: Os<2, 0, 2, 2, 1, 2> = started(&TWO);
    let (first, second) = (AlarmId(0), AlarmId(1));
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    assert_eq!(
        os.get_alarm_base(second),
        Ok(AlarmBase {
            max_allowed_value: 9,
            ticks_per_base: 2,
            min_cycle: 2
        })
    );
    // The second counter's limits: at most 9 ticks, cycles of at least 2.
    assert_eq!(os.set_rel_alarm(second, 10, 0), Err(OsError::Value));
    assert_eq!(os.set_rel_alarm(second, 3, 1), Err(OsError::Value));
    assert_eq!(os.set_rel_alarm(first, 50, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(second, 3, 0), Ok(()));
    // Ticks of the first counter do not bring the second alarm nearer.
    for _ in 0..3 {
        assert_eq!(os.increment_counter(CounterId(0)), Ok(()));
    }
    assert_eq!(os.get_alarm(first), Ok(47));
    assert_eq!(os.get_alarm(second), Ok(3));
    // Cancelling the first leaves the second armed, and the second expires on its own
    // counter's third tick.
    assert_eq!(os.cancel_alarm(first), Ok(()));
    assert!(os.alarm_armed(second));
    for _ in 0..2 {
        assert_eq!(os.increment_counter(CounterId(1)), Ok(()));
    }
    assert_eq!(os.task_state(TaskId(1)), Some(TaskState::Suspended));
    assert_eq!(os.increment_counter(CounterId(1)), Ok(()));
    assert_eq!(os.task_state(TaskId(1)), Some(TaskState::Ready));
    assert!(!os.alarm_armed(second));
    // An absolute alarm on the second counter wraps at its own modulus (10): value 1 is
    // 8 ticks from 3.
    assert_eq!(os.set_abs_alarm(second, 1, 0), Ok(()));
    assert_eq!(os.get_alarm(second), Ok(8));
    // The limits are inclusive: an increment, a start and a cycle of the maximum are
    // accepted.
    assert_eq!(os.cancel_alarm(second), Ok(()));
    assert_eq!(os.set_rel_alarm(second, 9, 9), Ok(()));
    assert_eq!(os.get_alarm(second), Ok(9));
    assert_eq!(os.cancel_alarm(second), Ok(()));
    assert_eq!(os.set_abs_alarm(second, 9, 2), Ok(()));
    assert_eq!(os.get_alarm(second), Ok(6));
    // Elapsed ticks on the second counter (now 3): none since 3, two since 1, four since
    // 9 (wrapped at 10).
    assert_eq!(os.get_elapsed_value(CounterId(1), 3), Ok((3, 0)));
    assert_eq!(os.get_elapsed_value(CounterId(1), 1), Ok((3, 2)));
    assert_eq!(os.get_elapsed_value(CounterId(1), 9), Ok((3, 4)));
    assert_eq!(os.get_elapsed_value(CounterId(1), 10), Err(OsError::Value));
    assert_eq!(os.exit_isr(), Ok(()));
}

#[test]
fn virtual_interrupt_controller_takes_the_highest_admitted_request() {
    let mut os = os();
    let mut irq = VirtualInterrupts::new();
    assert!(irq.raise(TICK));
    assert!(!irq.raise(TICK), "one flag per request");
    assert!(irq.raise(CAN));
    assert!(irq.raise(FAST));
    assert!(!irq.raise(IsrId(64)));
    irq.apply_mask(InterruptMask::All);
    assert_eq!(irq.take_next(CFG.isrs()), None);
    irq.apply_mask(os.interrupt_mask());
    assert_eq!(irq.take_next(CFG.isrs()), Some(FAST));
    irq.apply_mask(InterruptMask::UpTo(1));
    assert_eq!(irq.take_next(CFG.isrs()), Some(CAN));
    assert_eq!(irq.take_next(CFG.isrs()), None, "Tick is masked");
    assert!(irq.is_pending(TICK));
    assert_eq!(os.enter_isr(TICK), Ok(()));
    irq.apply_mask(os.interrupt_mask());
    assert_eq!(irq.mask(), InterruptMask::UpTo(1));
}

/// The step vocabulary reaches every service kind, ids beyond the configuration, and
/// `RES_SCHEDULER`: each one-argument step stands for the number of distinct services its
/// mapping allows. The mapping reduces bytes modulo 2 to 8, so the bytes 0..120 (a
/// multiple of every modulus) reach every service a byte can; `SetAbsAlarm`'s start is
/// the byte itself.
#[test]
fn every_step_stands_for_the_services_it_names() {
    let distinct = |f: &dyn Fn(u8) -> Step| {
        let mut seen: Vec<spec::Service> = Vec::new();
        for b in 0..120 {
            let s = f(b).service();
            if !seen.contains(&s) {
                seen.push(s);
            }
        }
        seen
    };
    assert_eq!(distinct(&Step::Activate).len(), 6);
    assert_eq!(distinct(&Step::Chain).len(), 6);
    assert_eq!(distinct(&|m| Step::SetEvent(m, m)).len(), 12);
    assert_eq!(distinct(&Step::ClearEvent).len(), 4);
    assert_eq!(distinct(&Step::WaitEvent).len(), 4);
    let gets = distinct(&Step::GetResource);
    assert_eq!(gets.len(), 5);
    assert!(gets.contains(&spec::Service::Call(ServiceCall::GetResource(
        RES_SCHEDULER
    ))));
    assert_eq!(distinct(&Step::ReleaseResource).len(), 5);
    assert_eq!(distinct(&Step::FastGet).len(), 5);
    assert_eq!(distinct(&Step::FastRelease).len(), 5);
    assert_eq!(
        Step::FastGet(1).service().as_osek(),
        spec::Service::Call(ServiceCall::GetResource(ResourceId(1)))
    );
    assert_eq!(distinct(&|a| Step::SetRel(a, a, a)).len(), 8);
    for start in 0..=u8::MAX {
        assert_eq!(
            Step::SetAbs(5, start, 6).service(),
            spec::Service::Call(ServiceCall::SetAbsAlarm {
                alarm: AlarmId(1),
                start: TickType::from(start),
                cycle: 2
            })
        );
    }
    assert_eq!(distinct(&Step::Cancel).len(), 4);
    assert_eq!(distinct(&Step::Lock).len(), 6);
    assert_eq!(distinct(&Step::EnterIsr).len(), 4);
    assert_eq!(distinct(&Step::IsrTick).len(), 4);
    assert_eq!(distinct(&Step::FastTick).len(), 4);
    assert_eq!(distinct(&Step::FastActivate).len(), 6);
    assert_eq!(
        Step::FastActivate(1).service().as_osek(),
        spec::Service::Call(ServiceCall::ActivateTask(TaskId(1)))
    );
    assert_eq!(
        Step::FastTick(0).service().as_osek(),
        spec::Service::Isr(IsrId(0), ServiceCall::IncrementCounter(CounterId(0)))
    );
    assert_eq!(distinct(&|i| Step::IsrActivate(i, i)).len(), 12);
    // GetTaskId, GetIsrId, GetActiveApplicationMode, GetTaskState of 6 ids, GetAlarm of 4.
    assert_eq!(distinct(&Step::Query).len(), 13);
    for (step, service) in [
        (Step::Terminate, ServiceCall::TerminateTask),
        (Step::Schedule, ServiceCall::Schedule),
        (Step::Tick, ServiceCall::IncrementCounter(CounterId(0))),
    ] {
        assert_eq!(step.service(), spec::Service::Call(service));
    }
    assert_eq!(Step::ExitIsr.service(), spec::Service::ExitIsr);
    assert_eq!(Step::TaskReturn.service(), spec::Service::TaskReturn);
}

/// Random sequences of up to 64 steps keep the invariants and transition rules (a bolero
/// test and fuzz target). Not a Kani proof: one symbolic step of any kind does not finish
/// under Kani in 300 s (the book: `docs/src/kani.md`). Every sequence of up to 5 of these steps (each of
/// the 4,358 services they stand for) on the small configuration is explored exhaustively
/// by `cw-proofs steps` instead, and the model checker's configurations to the end.
#[test]
fn random_step_sequences_keep_the_invariants() {
    bolero::check!().with_type::<Vec<Step>>().for_each(|steps| {
        let mut os = os();
        for s in steps.iter().take(64) {
            if let Err(rule) = spec::call_and_check(&mut os, s.service()) {
                panic!("{s:?}: {rule}\n{os:?}");
            }
        }
    });
}

#[test]
fn transition_rules_can_fail() {
    let before = os();
    let activate = spec::Service::Isr(TICK, ServiceCall::ActivateTask(LOW));
    // A successful ActivateTask that changed nothing would be a lost activation.
    assert_eq!(
        spec::transition_rules(&before, &before, activate, Ok(Returned::Nothing)),
        Err("an activation was lost")
    );
    let mut queued_ab = before;
    let mut queued_ba = before;
    for (os, order) in [
        (&mut queued_ab, [HIGH, LOW, LOW2]),
        (&mut queued_ba, [HIGH, LOW2, LOW]),
    ] {
        assert_eq!(os.enter_isr(TICK), Ok(()));
        for t in order {
            assert_eq!(os.activate_task(t), Ok(()));
        }
        assert_eq!(os.exit_isr(), Ok(()));
    }
    assert!(spec::fifo_discipline(&queued_ab, &queued_ba).is_err());
    assert_eq!(spec::fifo_discipline(&queued_ab, &queued_ab), Ok(()));
    // A task switch while an ISR is active.
    let mut in_isr_a = queued_ab;
    assert_eq!(in_isr_a.enter_isr(TICK), Ok(()));
    let mut switched = in_isr_a;
    assert_eq!(switched.exit_isr(), Ok(()));
    assert_eq!(switched.terminate_task(), Ok(()));
    assert_eq!(switched.enter_isr(TICK), Ok(()));
    assert_eq!(
        spec::transition_rules(
            &in_isr_a,
            &switched,
            spec::Service::Call(ServiceCall::GetTaskId),
            Ok(Returned::Nothing)
        ),
        Err("a task switch happened while an ISR was active")
    );
    // An ISR entered under a mask that held it.
    let mut locked = queued_ab;
    assert_eq!(locked.suspend_os_interrupts(), Ok(()));
    let mut forced = queued_ab;
    assert_eq!(forced.enter_isr(TICK), Ok(()));
    assert_eq!(
        spec::transition_rules(
            &locked,
            &forced,
            spec::Service::EnterIsr(TICK),
            Ok(Returned::Nothing)
        ),
        Err("an ISR was entered although the interrupt mask held it")
    );
    // The invariants themselves catch a broken nesting.
    assert!(spec::isr_nesting_consistent(&forced));
}

/// The small configuration right after `StartOS`: nothing runs yet (the idle loop).
fn small_started() -> SmallOs {
    let Ok(mut os) = SmallOs::new(&SMALL) else {
        panic!("the small configuration is valid")
    };
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    os
}

/// The small configuration started, then one ISR (either id, or an invalid one) that
/// activates any task (either one, or an invalid id) and returns, checked against the
/// rules and invariants like every step.
fn small_after_an_isr(isr: u8, task: u8) -> SmallOs {
    let mut os = small_started();
    let first = spec::Service::Isr(IsrId(isr % 2), ServiceCall::ActivateTask(TaskId(task % 3)));
    let verdict = spec::call_and_check(&mut os, first);
    assert!(verdict.is_ok(), "{first:?}: {verdict:?}");
    os
}

/// After any first ISR of [`small_after_an_isr`], step `s` keeps the transition rules and
/// every kernel invariant.
fn second_step_keeps_the_invariants(isr: u8, task: u8, s: Step) {
    let mut os = small_after_an_isr(isr, task);
    let verdict = spec::call_and_check(&mut os, s.service());
    assert!(verdict.is_ok(), "{s:?}: {verdict:?}");
}

/// The small configuration right after `StartOS` (no task runs yet), then step `s`, checked
/// against the transition rules and every kernel invariant.
fn first_step_keeps_the_invariants(s: Step) {
    let mut os = small_started();
    let verdict = spec::call_and_check(&mut os, s.service());
    assert!(verdict.is_ok(), "{s:?}: {verdict:?}");
}

// Kani proofs of one step from the state after `StartOS`, each for one kind of step with
// every argument symbolic (ids beyond the configuration included, so refusals are proved
// too). These are the steps that start the system: the kernel dispatches a task, enters or
// leaves an ISR, and advances a counter. Bounds and verification times: the book, `docs/src/kani.md`.

/// `ActivateTask` of any task id: a valid one is dispatched, an invalid one refused with
/// `E_OS_ID` and nothing changed.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn from_start_any_activation_keeps_the_invariants() {
    bolero::check!()
        .with_type::<u8>()
        .cloned()
        .for_each(|t| first_step_keeps_the_invariants(Step::Activate(t)));
}

/// Any ISR id (the configured one or not) entering: admitted, or refused and nothing
/// changed.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn from_start_any_isr_entry_keeps_the_invariants() {
    bolero::check!()
        .with_type::<u8>()
        .cloned()
        .for_each(|i| first_step_keeps_the_invariants(Step::EnterIsr(i)));
}

/// A whole ISR (any id) that activates any task and returns, where the kernel reschedules.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn from_start_any_isr_activating_any_task_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8)>()
        .cloned()
        .for_each(|(i, t)| first_step_keeps_the_invariants(Step::IsrActivate(i, t)));
}

/// A whole ISR (any id) that increments the counter and returns.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn from_start_any_isr_ticking_the_counter_keeps_the_invariants() {
    bolero::check!()
        .with_type::<u8>()
        .cloned()
        .for_each(|i| first_step_keeps_the_invariants(Step::IsrTick(i)));
}

/// A Kani proof (and a bolero test) of two steps from the state after `StartOS`: ISR 0
/// activates task `$task` (A is 0, B is 1, so that task runs), then one kind of step with
/// every argument symbolic; the rules and every invariant are checked after each.
macro_rules! two_step_proof {
    ($(#[doc = $doc:expr])* $name:ident: task $task:expr, any $ty:ty => |$v:pat_param| $step:expr) => {
        $(#[doc = $doc])*
        #[test]
        #[cfg_attr(kani, kani::proof, kani::unwind(10))]
        fn $name() {
            bolero::check!()
                .with_type::<$ty>()
                .cloned()
                .for_each(|$v| second_step_keeps_the_invariants(0, $task, $step));
        }
    };
}

two_step_proof! {
    /// Task A runs, then `ChainTask` of any task id.
    after_an_isr_started_a_any_chain_keeps_the_invariants: task 0, any u8 => |t| Step::Chain(t)
}
two_step_proof! {
    /// Task A runs, then `ActivateTask` of any task id.
    after_an_isr_started_a_any_activation_keeps_the_invariants: task 0, any u8 => |t| Step::Activate(t)
}
two_step_proof! {
    /// Task A runs, then `GetResource` of any resource id (its own, `RES_SCHEDULER`, or an
    /// invalid one).
    after_an_isr_started_a_any_get_resource_keeps_the_invariants: task 0, any u8 => |r| Step::GetResource(r)
}
two_step_proof! {
    /// Task A runs, then `SetEvent` of any task id and any mask (B waits for nothing yet;
    /// A is basic and refuses events).
    after_an_isr_started_a_any_set_event_keeps_the_invariants: task 0, any (u8, u8) => |(t, m)| Step::SetEvent(t, m)
}
two_step_proof! {
    /// Task A runs, then `SetRelAlarm` of any alarm id, increment and cycle.
    after_an_isr_started_a_any_rel_alarm_keeps_the_invariants: task 0, any (u8, u8, u8) => |(a, i, c)| Step::SetRel(a, i, c)
}
two_step_proof! {
    /// Task A runs, then `CancelAlarm` of any alarm id.
    after_an_isr_started_a_any_cancel_keeps_the_invariants: task 0, any u8 => |a| Step::Cancel(a)
}
two_step_proof! {
    /// Task B (extended) runs, then `ChainTask` of any task id.
    after_an_isr_started_b_any_chain_keeps_the_invariants: task 1, any u8 => |t| Step::Chain(t)
}
two_step_proof! {
    /// Task B runs, then `ActivateTask` of any task id (A is of lower priority and waits).
    after_an_isr_started_b_any_activation_keeps_the_invariants: task 1, any u8 => |t| Step::Activate(t)
}
two_step_proof! {
    /// Task B runs, then `WaitEvent` of any mask (B waits, or an event already set lets it
    /// go on).
    after_an_isr_started_b_any_wait_event_keeps_the_invariants: task 1, any u8 => |m| Step::WaitEvent(m)
}

// One harness per group of step kinds: any first ISR, then any step of the group with any
// arguments. Bolero tests and fuzz inputs; not Kani proofs: one kind of second step after
// one concrete first step verifies (the two proofs above), but any second step after any
// first one does not finish under Kani in 300 s (the book: `docs/src/kani.md`), and a marked harness that
// does not finish proves nothing.

/// Task management: ActivateTask (the service, and the port's by the fast path),
/// TerminateTask, ChainTask, Schedule, a body's return.
#[test]
fn after_an_isr_any_task_service_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(isr, task, kind, a)| {
            let s = match kind % 6 {
                0 => Step::Activate(a),
                1 => Step::Terminate,
                2 => Step::Chain(a),
                3 => Step::Schedule,
                4 => Step::FastActivate(a),
                _ => Step::TaskReturn,
            };
            second_step_keeps_the_invariants(isr, task, s);
        });
}

/// Events: SetEvent, ClearEvent, WaitEvent.
#[test]
fn after_an_isr_any_event_service_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(isr, task, kind, a, b)| {
            let s = match kind % 3 {
                0 => Step::SetEvent(a, b),
                1 => Step::ClearEvent(b),
                _ => Step::WaitEvent(b),
            };
            second_step_keeps_the_invariants(isr, task, s);
        });
}

/// Resources: GetResource, ReleaseResource, and the port's lock by the fast paths
/// (`RES_SCHEDULER` and invalid ids too).
#[test]
fn after_an_isr_any_resource_service_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(isr, task, kind, r)| {
            let s = match kind % 4 {
                0 => Step::GetResource(r),
                1 => Step::ReleaseResource(r),
                2 => Step::FastGet(r),
                _ => Step::FastRelease(r),
            };
            second_step_keeps_the_invariants(isr, task, s);
        });
}

/// The port's lock by the fast paths: after an ISR started A or B, a lock of any resource
/// id, then the release of any: each step checked against the full service
/// (`spec::fast_path_agrees`: the same state, the same result, the kernel's mask), the
/// transition rules and every invariant. (A bolero test and fuzz target; the two Kani
/// proofs below take one fast step each, with the contract alone.)
#[test]
fn after_an_isr_any_fast_lock_pair_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(bool, u8, u8)>()
        .cloned()
        .for_each(|(b, get, release)| {
            let mut os = small_after_an_isr(0, u8::from(b));
            for s in [Step::FastGet(get), Step::FastRelease(release)] {
                let verdict = spec::call_and_check(&mut os, s.service());
                assert!(verdict.is_ok(), "{s:?}: {verdict:?}");
            }
        });
}

/// `GetResource`'s fast path agrees with the service (`spec::fast_path_agrees`) for any
/// resource id (the task's own, `RES_SCHEDULER`, invalid ones), taken by A or by B: so
/// every rule and invariant the harnesses above prove of `GetResource` holds of it.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn any_fast_get_agrees_with_get_resource() {
    bolero::check!()
        .with_type::<(bool, u8)>()
        .cloned()
        .for_each(|(b, r)| {
            let os = small_after_an_isr(0, u8::from(b));
            let verdict = spec::fast_path_agrees(&os, Step::FastGet(r).service());
            assert!(verdict.is_ok(), "{r}: {verdict:?}");
        });
}

/// `ActivateTask`'s fast path agrees with the service (`spec::fast_path_agrees`) for any
/// task id (A's second activation, B's first, invalid ones), from A or B running, holding
/// resource 0 or not: the same state, the same result, the kernel's view; where it
/// declines (B activating A below it, a limit, a lock held above the activated task) it
/// changed nothing.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn any_fast_activation_agrees_with_activate_task() {
    bolero::check!()
        .with_type::<(bool, bool, u8)>()
        .cloned()
        .for_each(|(b, locked, t)| {
            let mut os = small_after_an_isr(0, u8::from(b));
            if locked {
                assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
            }
            let verdict = spec::fast_path_agrees(&os, Step::FastActivate(t).service());
            assert!(verdict.is_ok(), "{t}: {verdict:?}");
        });
}

/// `ReleaseResource`'s fast path agrees with the service for any resource id, after A took
/// resource 0, with B (above the priority A returns to) activated meanwhile or not: the
/// fast path must decline the release that switches to B.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn any_fast_release_agrees_with_release_resource() {
    bolero::check!()
        .with_type::<(bool, u8)>()
        .cloned()
        .for_each(|(b_ready, r)| {
            let mut os = small_after_an_isr(0, 0);
            assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
            if b_ready {
                assert_eq!(os.activate_task(TaskId(1)), Ok(()));
            }
            let verdict = spec::fast_path_agrees(&os, Step::FastRelease(r).service());
            assert!(verdict.is_ok(), "{r}: {verdict:?}");
        });
}

/// A lock and its release that a port keeps outside the kernel ([`Os::lock_free_resources`])
/// leave no trace (`spec::lock_pair_leaves_no_trace`): from A or B running after an ISR,
/// holding resource 0 through the kernel or not, for any resource id. (The step
/// harnesses, the step sequences and the models check it too, at every `GetResource`.)
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn a_lock_pair_outside_the_kernel_leaves_no_trace() {
    bolero::check!()
        .with_type::<(bool, bool, u8)>()
        .cloned()
        .for_each(|(b, held, r)| {
            let mut os = small_after_an_isr(0, u8::from(b));
            if held {
                assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
            }
            // A task that holds a resource taken through the kernel locks through it.
            assert_eq!(os.lock_free_resources() != 0, !held);
            let verdict = spec::lock_pair_leaves_no_trace(&os, ResourceId(r % 4));
            assert!(verdict.is_ok(), "{r}: {verdict:?}");
        });
}

/// A task's own resource that an ISR shares is one it may lock outside the kernel too:
/// the port then masks the ISR itself, at the ceiling the kernel's lock would mask
/// (`spec::lock_pair_leaves_no_trace` checks the level), and nothing after the release.
#[test]
fn a_resource_an_isr_shares_may_be_locked_outside_the_kernel_at_its_ceiling() {
    static SHARED: OsConfig<1, 1, 0, 0, 1> = match OsConfig::new(OsDescription::new(
        [TaskConfig::basic("Sender", 1).uses(0b1).autostart()],
        [],
        [],
        [IsrConfig::cat2("Can", 2).uses(0b1)],
    )) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut os: Os<1, 1, 0, 0, 1, 1> = started(&SHARED);
    assert_eq!(os.lock_free_resources(), 1 << 12);
    assert_eq!(os.interrupt_mask(), InterruptMask::None);
    let verdict = spec::lock_pair_leaves_no_trace(&os, R0);
    assert!(verdict.is_ok(), "{verdict:?}");
    assert_eq!(os.try_get_resource(R0), SHARED.isr_level(0));
    assert_eq!(os.interrupt_mask(), InterruptMask::UpTo(2));
    assert_eq!(os.lock_free_resources(), 0);
}

/// Only the running task at task level, with no interrupt lock and nothing held, may lock
/// outside the kernel: not before `StartOS`, not the idle loop, not an ISR, not under
/// `SuspendOSInterrupts`, not while holding a resource.
#[test]
fn only_a_task_at_task_level_that_holds_nothing_may_lock_outside_the_kernel() {
    let Ok(before_start) = SmallOs::new(&SMALL) else {
        panic!("the small configuration is valid")
    };
    assert_eq!(before_start.lock_free_resources(), 0);
    let idle = small_started();
    assert_eq!(idle.lock_free_resources(), 0);
    let mut os = small_after_an_isr(0, 1);
    assert_eq!(os.lock_free_resources(), 0b1);
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    assert_eq!(os.lock_free_resources(), 0);
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.lock_free_resources(), 0b1);
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    assert_eq!(os.lock_free_resources(), 0);
    assert_eq!(os.resume_os_interrupts(), Ok(()));
    assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
    assert_eq!(os.lock_free_resources(), 0);
    assert_eq!(os.release_resource(ResourceId(0)), Ok(()));
    assert_eq!(os.lock_free_resources(), 0b1);
}

/// The OS tick's fast path agrees with the whole ISR (entry, `IncrementCounter`, return)
/// for any ISR id (the configured one, invalid ones), from the idle loop after `StartOS`
/// or from task A or B running: so every rule and invariant proved of the whole ISR holds
/// of it.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn any_fast_tick_agrees_with_the_whole_isr() {
    bolero::check!()
        .with_type::<(u8, u8)>()
        .cloned()
        .for_each(|(from, i)| {
            let os = match from % 3 {
                0 => small_started(),
                task => small_after_an_isr(0, task - 1),
            };
            let verdict = spec::fast_path_agrees(&os, Step::FastTick(i).service());
            assert!(verdict.is_ok(), "{i}: {verdict:?}");
        });
}

/// The tick's fast path takes the ticks where nothing is due, from a task or the idle
/// loop, and declines the rest, which the whole ISR then runs: a tick an alarm is due at,
/// a tick nested in another ISR, a tick the mask holds, an unknown ISR or counter.
#[test]
fn the_fast_tick_takes_the_ticks_where_nothing_is_due() {
    let (tick, counter) = (IsrId(0), CounterId(0));
    let mut idle = small_started();
    assert_eq!(idle.try_tick(tick, counter), Some(0));
    assert_eq!(idle.counter_value(counter), Some(1));
    assert_eq!(idle.try_tick(IsrId(1), counter), None);
    assert_eq!(idle.try_tick(tick, CounterId(1)), None);
    // B runs and arms its alarm two ticks away: the first tick is fast, the second, where
    // the alarm expires and sets B's event, is the whole ISR's.
    let mut os = small_after_an_isr(0, 1);
    assert_eq!(os.set_rel_alarm(AlarmId(0), 2, 0), Ok(()));
    assert_eq!(os.try_tick(tick, counter), Some(2));
    assert_eq!(os.get_alarm(AlarmId(0)), Ok(1));
    let due = os;
    assert_eq!(os.try_tick(tick, counter), None);
    assert_eq!(os, due);
    assert_eq!(
        spec::call(&mut os, Step::FastTick(0).service()),
        Ok(Returned::Nothing)
    );
    assert_eq!(os.events(TaskId(1)), 1);
    // Under SuspendOSInterrupts the tick is held: declined.
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    assert_eq!(os.try_tick(tick, counter), None);
    assert_eq!(os.resume_os_interrupts(), Ok(()));
    // Nested in another ISR: declined.
    assert_eq!(os.enter_isr(tick), Ok(()));
    assert_eq!(os.try_tick(tick, counter), None);
}

/// The tick where alarms are due has a fast path of its own where each due alarm
/// activates a task of its own that may be activated once more: it leaves the state the
/// whole ISR leaves (the task an alarm activated running where it preempts, the hooks
/// around the switch called as at the ISR's return), and declines an alarm due with
/// another action, a task at its limit (whose `E_OS_LIMIT` the whole ISR reports), and a
/// tick nested in another ISR.
#[test]
fn the_due_tick_fast_path_activates_and_declines_what_it_cannot_run() {
    let counter = CounterId(0);
    let agrees = |os: &TestOs| {
        let verdict = spec::fast_path_agrees(os, spec::Service::FastTick(TICK, counter));
        assert!(verdict.is_ok(), "{verdict:?}");
    };
    // Low runs and arms ActHigh one tick away: the tick activates High, which preempts.
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    os.hooks_mut().take();
    agrees(&os);
    let before = os;
    assert_eq!(os.try_tick(TICK, counter), None);
    assert_eq!(os, before);
    assert_eq!(os.try_tick_due(TICK, counter), Some(5));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.counter_value(counter), Some(1));
    assert_eq!(
        os.hooks_mut().take(),
        [Seen::Post(Some(LOW)), Seen::Pre(Some(HIGH))]
    );
    check(&os);
    // Armed again while High runs (its one activation taken): the tick declines, and the
    // whole ISR reports the activation refused.
    assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    agrees(&os);
    let before = os;
    assert_eq!(os.try_tick_due(TICK, counter), None);
    assert_eq!(os, before);
    assert_eq!(
        spec::call(&mut os, spec::Service::FastTick(TICK, counter)),
        Ok(Returned::Nothing)
    );
    assert!(os.hooks_mut().take().contains(&Seen::Error(
        OsError::Limit,
        ServiceCall::ActivateTask(HIGH),
        Some(TICK)
    )));
    // An alarm that sets an event due at the same tick as ActHigh: declined.
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(1), 1, 0), Ok(()));
    agrees(&os);
    let before = os;
    assert_eq!(os.try_tick_due(TICK, counter), None);
    assert_eq!(os, before);
    // An unknown counter or ISR: declined.
    assert_eq!(os.try_tick_due(TICK, CounterId(1)), None);
    assert_eq!(os.try_tick_due(IsrId(9), counter), None);
    assert_eq!(os, before);
    // Nested in another ISR: declined.
    assert_eq!(os.cancel_alarm(AlarmId(1)), Ok(()));
    assert_eq!(os.enter_isr(CAN), Ok(()));
    assert_eq!(os.try_tick_due(TICK, counter), None);
    assert_eq!(os.exit_isr(), Ok(()));
    agrees(&os);
    // From the idle loop: the task runs, and the context is a task's again.
    let mut idle = self::os();
    assert_eq!(activate_from_isr(&mut idle, LOW), Ok(()));
    assert_eq!(idle.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    assert_eq!(idle.terminate_task(), Ok(()));
    assert_eq!(idle.running(), None);
    agrees(&idle);
    assert_eq!(idle.try_tick_due(TICK, counter), Some(5));
    assert_eq!(
        (idle.running(), idle.context()),
        (Some(HIGH), Context::Task)
    );
    check(&idle);
}

/// Any tick from a task of the test configuration (hooks around every switch, which may
/// fail a call and shut the OS down) with any of its three alarms (an activation, an
/// event, a callback) armed one or two ticks away, the activated task already active or
/// not: the tick's fast paths agree with the whole ISR, the one for due alarms where only
/// the activation is due.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(10))]
fn any_due_tick_agrees_with_the_whole_isr() {
    bolero::check!()
        .with_type::<(u8, [u8; 3])>()
        .cloned()
        .for_each(|(from, delays)| {
            let mut os = self::os();
            let start = [LOW, MID, HIGH, NP][usize::from(from % 4)];
            assert_eq!(activate_from_isr(&mut os, start), Ok(()));
            if from & 4 != 0 {
                let _ = os.activate_task(HIGH);
            }
            // The hooks around the switch at the tick's return may fail a call, and
            // `ErrorHook` may shut the OS down there.
            os.hooks_mut().fail_inside_post_task_hook = from & 8 != 0;
            if from & 16 != 0 {
                os.hooks_mut().shutdown_on_error = Some(OsError::CallLevel);
            }
            for (alarm, delay) in delays.iter().enumerate() {
                if delay % 3 != 0 {
                    let _ = os.set_rel_alarm(AlarmId(alarm as u8), TickType::from(delay % 3), 0);
                }
            }
            let verdict = spec::fast_path_agrees(&os, spec::Service::FastTick(TICK, CounterId(0)));
            assert!(verdict.is_ok(), "{verdict:?}");
        });
}

/// The tick's fast path where alarms are due declines at `os` and changes nothing, and
/// the tick as a port runs it (`FastTick`: the whole ISR) succeeds.
fn declined_then_whole<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
>(
    os: &mut Os<T, R, C, A, I, Q>,
    tick: IsrId,
    counter: CounterId,
) {
    let before = *os;
    assert_eq!(os.try_tick_due(tick, counter), None);
    assert_eq!(*os, before);
    assert_eq!(
        spec::call(os, spec::Service::FastTick(tick, counter)),
        Ok(Returned::Nothing)
    );
}

/// Two alarms due at one tick that activate the same task: declined (the second
/// activation depends on the first), and the whole ISR runs them.
#[test]
fn the_due_tick_fast_path_declines_one_task_activated_twice() {
    static TWICE: OsConfig<2, 0, 1, 2, 1> = match OsConfig::new(OsDescription::new(
        [
            TaskConfig::basic("Idle", 1).autostart(),
            TaskConfig::basic("T", 2).activations(2),
        ],
        [COUNTER],
        [
            AlarmConfig::new("a", CounterId(0), AlarmAction::ActivateTask(TaskId(1))),
            AlarmConfig::new("b", CounterId(0), AlarmAction::ActivateTask(TaskId(1))),
        ],
        [IsrConfig::cat2("Tick", 1)],
    )) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut os: Os<2, 0, 1, 2, 1, 3> = started(&TWICE);
    let (tick, counter) = (IsrId(0), CounterId(0));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(1), 1, 0), Ok(()));
    let before = os;
    declined_then_whole(&mut os, tick, counter);
    assert_eq!(os.running(), Some(TaskId(1)));
    assert_eq!(os.activation_count(TaskId(1)), 2);
    let verdict = spec::fast_path_agrees(&before, spec::Service::FastTick(tick, counter));
    assert!(verdict.is_ok(), "{verdict:?}");
    // One of them alone: taken.
    let mut one = before;
    assert_eq!(one.cancel_alarm(AlarmId(1)), Ok(()));
    assert_eq!(one.try_tick_due(tick, counter), Some(2));
    assert_eq!(one.running(), Some(TaskId(1)));
}

/// A due alarm of a task numbered 32 or above sends the tick to the whole ISR (the fast
/// path tells the due alarms' tasks apart in 32 bits), which activates it.
#[test]
fn the_due_tick_fast_path_declines_a_task_above_31() {
    static MANY: std::sync::LazyLock<OsConfig<33, 0, 1, 1, 1>> = std::sync::LazyLock::new(|| {
        let mut tasks = [TaskConfig::basic("T", 1); 33];
        tasks[0] = TaskConfig::basic("Idle", 1).autostart();
        match OsConfig::new(OsDescription::new(
            tasks,
            [COUNTER],
            [AlarmConfig::new(
                "a",
                CounterId(0),
                AlarmAction::ActivateTask(TaskId(32)),
            )],
            [IsrConfig::cat2("Tick", 1)],
        )) {
            Ok(c) => c,
            Err(e) => panic!("{}", e.describe()),
        }
    });
    let mut os: Os<33, 0, 1, 1, 1, 33> = started(&MANY);
    let (tick, counter) = (IsrId(0), CounterId(0));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 1, 0), Ok(()));
    declined_then_whole(&mut os, tick, counter);
    assert_eq!(os.activation_count(TaskId(32)), 1);
}

/// The tick's fast path is taken while a task holds a resource it shares with an ISR
/// below the tick (the ECU's send under `RES_COM`, interrupted by `SysTickIsr`): the mask
/// is then that ISR's level, below the tick's, so the tick is admitted, and the state is
/// the whole ISR's.
#[test]
fn the_fast_tick_is_taken_under_a_lower_isrs_ceiling() {
    static SHARED: OsConfig<1, 1, 1, 1, 2> = match OsConfig::new(OsDescription::new(
        [TaskConfig::basic("Sender", 1).uses(0b1).autostart()],
        [COUNTER],
        [AlarmConfig::new(
            "Unarmed",
            CounterId(0),
            AlarmAction::ActivateTask(TaskId(0)),
        )],
        [
            IsrConfig::cat2("Can", 1).uses(0b1),
            IsrConfig::cat2("Tick", 2),
        ],
    )) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let mut os: Os<1, 1, 1, 1, 2, 1> = started(&SHARED);
    let (tick, counter) = (IsrId(1), CounterId(0));
    assert_eq!(os.running(), Some(TaskId(0)));
    assert_eq!(os.get_resource(R0), Ok(()));
    let can_level = SHARED.isr_level(0);
    assert_eq!(Some(os.masked_level()), can_level);
    let before = os;
    assert_eq!(os.try_tick(tick, counter), can_level);
    assert_eq!(os.counter_value(counter), Some(1));
    let verdict = spec::fast_path_agrees(&before, spec::Service::FastTick(tick, counter));
    assert!(verdict.is_ok(), "{verdict:?}");
}

/// A category-2 ISR takes and releases the resource it declares by the fast paths: its
/// level rises to the ceiling and back, the same state as the services leave; a nested
/// lock and a release out of order are declined, and the services refuse them.
#[test]
fn an_isr_locks_its_resource_by_the_fast_paths() {
    let mut os = os();
    let res = ResourceId(1);
    assert_eq!(os.enter_isr(CAN), Ok(()));
    let before = os;
    let level = os.config().isr_level(usize::from(CAN.0));
    // Mid (3) and Can use R1: its ceiling is Can's own level, so the level stays.
    assert_eq!(os.try_get_resource(res), level);
    assert_eq!(os.isr_held_resources(CAN).next(), Some(res));
    let mut full = before;
    assert_eq!(full.get_resource(res), Ok(()));
    assert_eq!(os, full);
    assert_eq!(os.try_get_resource(res), None);
    assert_eq!(os.try_release_resource(ResourceId(0)), None);
    assert_eq!(os.try_release_resource(res), level);
    assert_eq!(os, before);
    assert_eq!(os.try_release_resource(res), None);
    // A resource the ISR does not declare, whose ceiling is below its level: in extended
    // status the fast path declines and the service refuses (E_OS_ACCESS).
    assert_eq!(os.try_get_resource(ResourceId(0)), None);
    assert_eq!(os.get_resource(ResourceId(0)), Err(OsError::Access));
}

/// Any number of ticks at once (`try_ticks`, the tickless simulation's step) agrees with
/// as many fast ticks one by one (`spec::ticks_agree`), from the idle loop or with A or B
/// running, with B's alarm armed any number of ticks away or not.
#[test]
fn any_ticks_at_once_agree_with_the_ticks_one_by_one() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(from, alarm, i, n)| {
            let mut os = match from % 3 {
                0 => small_started(),
                task => small_after_an_isr(0, task - 1),
            };
            if from % 3 != 0 && alarm % 4 != 0 {
                let _ = os.set_rel_alarm(AlarmId(0), TickType::from(alarm % 4), 0);
            }
            let verdict = spec::ticks_agree(&os, IsrId(i % 3), CounterId(0), u64::from(n % 9));
            assert!(verdict.is_ok(), "{i} x{n}: {verdict:?}");
        });
}

#[test]
fn ticks_at_once_stop_before_the_alarm_and_wrap_the_counter() {
    let (tick, counter) = (IsrId(0), CounterId(0));
    let mut os = small_after_an_isr(0, 1);
    assert_eq!(os.ticks_to_expiry(counter), Some(u64::MAX));
    // The counter counts 0..=3: five ticks from 0 wrap it to 1.
    assert_eq!(os.try_ticks(tick, counter, 5), Some(2));
    assert_eq!(os.counter_value(counter), Some(1));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 3, 0), Ok(()));
    assert_eq!(os.ticks_to_expiry(counter), Some(3));
    assert_eq!(os.try_ticks(tick, counter, 3), None);
    assert_eq!(os.try_ticks(tick, counter, 0), None);
    assert_eq!(os.try_ticks(tick, counter, 2), Some(2));
    assert_eq!(os.ticks_to_expiry(counter), Some(1));
    assert_eq!(os.ticks_to_expiry(CounterId(1)), None);
}

/// `ActivateTask`'s fast path takes the activation that preempts (A running activates B
/// above it) and declines the rest, changing nothing: one that queues (A activating
/// itself, B activating A), one at or below a held resource's ceiling, one of a task
/// already active (running, or waiting), an invalid id, one from an ISR.
#[test]
fn the_fast_activation_takes_the_preempting_case_and_declines_the_rest() {
    let mut os = small_after_an_isr(0, 0);
    assert_eq!(os.running(), Some(TaskId(0)));
    let before = os;
    assert_eq!(os.try_activate_task(TaskId(0)), None, "A itself: it queues");
    assert_eq!(os.try_activate_task(TaskId(7)), None, "an invalid id");
    assert_eq!(os, before);
    assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
    let held = os;
    assert_eq!(
        os.try_activate_task(TaskId(1)),
        None,
        "B at the ceiling A holds"
    );
    assert_eq!(os, held);
    assert_eq!(os.release_resource(ResourceId(0)), Ok(()));
    let mut full = os;
    assert_eq!(full.activate_task(TaskId(1)), Ok(()));
    let view = os.try_activate_task(TaskId(1));
    assert_eq!(os, full, "the state the service leaves");
    assert_eq!(view, Some(full.port_view()));
    assert_eq!(os.running(), Some(TaskId(1)));
    let running_b = os;
    assert_eq!(os.try_activate_task(TaskId(1)), None, "B is active");
    assert_eq!(os.try_activate_task(TaskId(0)), None, "A is below B");
    assert_eq!(os, running_b);
    // B (extended) waits and A runs again: B, above A, is active still.
    assert_eq!(os.wait_event(1), Ok(()));
    assert_eq!(os.running(), Some(TaskId(0)));
    let waiting_b = os;
    assert_eq!(os.try_activate_task(TaskId(1)), None, "B waits: its limit");
    assert_eq!(os, waiting_b);
    assert_eq!(os.activate_task(TaskId(1)), Err(OsError::Limit));
    // From an ISR: the switch waits for its return, the service's.
    let mut os = small_started();
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    let in_isr = os;
    assert_eq!(os.try_activate_task(TaskId(1)), None);
    assert_eq!(os, in_isr);
}

/// The activation's fast path where the small configuration cannot take it: a caller
/// preempted while it holds a resource (its saved priority the ceiling), a
/// non-preemptive task activated (it runs at its dispatch priority, above every task),
/// and the same from a task that holds the scheduler. Each step is taken by the fast
/// path and checked against the service (`spec::fast_path_agrees`), the transition rules
/// and every invariant (`spec::call_and_check`).
#[test]
fn the_fast_activation_agrees_where_a_resource_is_held_and_for_a_non_preemptive_task() {
    static PLAIN: OsConfig<4, 1, 0, 0, 1> = match OsConfig::new(OsDescription::new(
        [
            TaskConfig::basic("Low", 1).uses(0b1),
            TaskConfig::basic("Mid", 2).uses(0b1),
            TaskConfig::basic("Np", 3).non_preemptive(),
            TaskConfig::basic("High", 4),
        ],
        [],
        [],
        [IsrConfig::cat2("Tick", 1)],
    )) {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    };
    let start = || {
        let mut os = match Os::<4, 1, 0, 0, 1, 4>::new(&PLAIN) {
            Ok(os) => os,
            Err(e) => panic!("{e:?}"),
        };
        assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
        assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
        assert_eq!(os.activate_task(TaskId(0)), Ok(()));
        assert_eq!(os.exit_isr(), Ok(()));
        assert_eq!(os.running(), Some(TaskId(0)));
        os
    };
    let fast = |os: &mut Os<4, 1, 0, 0, 1, 4>, task: u8| {
        let service = spec::Service::FastActivate(TaskId(task));
        let mut probe = *os;
        assert!(
            probe.try_activate_task(TaskId(task)).is_some(),
            "taken: {task}"
        );
        let verdict = spec::call_and_check(os, service);
        assert!(matches!(verdict, Ok(Ok(_))), "{task}: {verdict:?}");
        assert_eq!(os.running(), Some(TaskId(task)));
    };
    // Low holds resource 0 (ceiling 2, Mid's): High preempts it; Low keeps the ceiling.
    let mut os = start();
    assert_eq!(os.get_resource(ResourceId(0)), Ok(()));
    fast(&mut os, 3);
    assert_eq!(os.saved_priority(TaskId(0)), Some(2));
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.running(), Some(TaskId(0)));
    // Np, non-preemptive: it runs at its dispatch priority, above High.
    let mut os = start();
    fast(&mut os, 2);
    assert_eq!(os.running_priority(), os.ceiling(RES_SCHEDULER));
    let np = os;
    assert_eq!(os.try_activate_task(TaskId(3)), None, "nothing preempts Np");
    assert_eq!(os, np);
    // Low holding the scheduler: nothing preempts it either.
    let mut os = start();
    assert_eq!(os.get_resource(RES_SCHEDULER), Ok(()));
    let scheduler = os;
    assert_eq!(os.try_activate_task(TaskId(3)), None);
    assert_eq!(os, scheduler);
}

/// With `PreTaskHook` or `PostTaskHook` configured, the activation's fast path declines
/// even where the activation preempts: the hooks run around the switch, which the service
/// makes.
#[test]
fn the_fast_activation_leaves_the_switch_to_the_service_where_task_hooks_run() {
    let mut os = os();
    assert_eq!(activate_from_isr(&mut os, TaskId(0)), Ok(()));
    assert_eq!(os.running(), Some(TaskId(0)));
    let before = os;
    assert_eq!(os.try_activate_task(TaskId(2)), None);
    assert_eq!(os, before);
    assert_eq!(os.activate_task(TaskId(2)), Ok(()));
    assert_eq!(os.running(), Some(TaskId(2)), "it preempts");
}

/// The fast paths take the common case and decline the rest, which the full services
/// then refuse or carry out: a nested lock of the same resource (E_OS_ACCESS), a release
/// of a resource not held (E_OS_NOFUNC), a release that lets a higher task in (the
/// switch), a lock with an interrupt lock in force (E_OS_DISABLEDINT), a lock from an ISR.
#[test]
fn fast_lock_paths_take_the_common_case_and_decline_the_rest() {
    let mut os = small_after_an_isr(0, 0);
    let res = ResourceId(0);
    assert_eq!(os.running(), Some(TaskId(0)));
    // A second activation of A waits, at the priority A returns to: no reason to switch.
    assert_eq!(os.activate_task(TaskId(0)), Ok(()));
    // A (priority 1) and B (2) use resource 0: its ceiling is 2.
    assert_eq!(os.try_get_resource(res), Some(2));
    assert_eq!(os.running_priority(), Some(2));
    assert_eq!(os.held_resources(TaskId(0)).next(), Some(res));
    let held = os;
    assert_eq!(os.try_get_resource(res), None);
    assert_eq!(os, held);
    assert_eq!(os.get_resource(res), Err(OsError::Access));
    assert_eq!(os.try_release_resource(ResourceId(1)), None);
    assert_eq!(os.try_release_resource(RES_SCHEDULER), None);
    assert_eq!(os.try_release_resource(res), Some(1));
    assert_eq!(os.running_priority(), Some(1));
    assert_eq!(os.try_release_resource(res), None);
    assert_eq!(os.release_resource(res), Err(OsError::NoFunc));
    // B becomes ready while A holds the resource: the release must switch to B.
    assert_eq!(os.try_get_resource(res), Some(2));
    assert_eq!(os.activate_task(TaskId(1)), Ok(()));
    assert_eq!(os.running(), Some(TaskId(0)));
    let before = os;
    assert_eq!(os.try_release_resource(res), None);
    assert_eq!(os, before);
    assert_eq!(os.release_resource(res), Ok(()));
    assert_eq!(os.running(), Some(TaskId(1)));
    // B under SuspendOSInterrupts: declined, and the service refuses.
    assert_eq!(os.suspend_os_interrupts(), Ok(()));
    assert_eq!(os.try_get_resource(res), None);
    assert_eq!(os.get_resource(res), Err(OsError::DisabledInt));
    assert_eq!(os.resume_os_interrupts(), Ok(()));
    // B, whose priority is the ceiling itself, takes and releases it by the fast paths,
    // and its priority stays.
    assert_eq!(os.try_get_resource(res), Some(2));
    assert_eq!(os.held_resources(TaskId(1)).next(), Some(res));
    assert_eq!(os.try_release_resource(res), Some(2));
    assert_eq!(os.held_resources(TaskId(1)).next(), None);
    // From an ISR: the full service's holder is the ISR's frame.
    assert_eq!(os.enter_isr(IsrId(0)), Ok(()));
    assert_eq!(os.try_get_resource(res), None);
}

/// Alarms and counters: SetRelAlarm, SetAbsAlarm, CancelAlarm, IncrementCounter from a
/// task or from an ISR.
#[test]
fn after_an_isr_any_alarm_service_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(isr, task, kind, a, b, c)| {
            let s = match kind % 5 {
                0 => Step::SetRel(a, b, c),
                1 => Step::SetAbs(a, b, c),
                2 => Step::Cancel(a),
                3 => Step::Tick,
                _ => Step::IsrTick(a),
            };
            second_step_keeps_the_invariants(isr, task, s);
        });
}

/// Interrupts: the six lock services, an ISR's entry and return, an ISR activating a task,
/// and the queries.
#[test]
fn after_an_isr_any_interrupt_step_keeps_the_invariants() {
    bolero::check!()
        .with_type::<(u8, u8, u8, u8, u8)>()
        .cloned()
        .for_each(|(isr, task, kind, a, b)| {
            let s = match kind % 5 {
                0 => Step::Lock(a),
                1 => Step::EnterIsr(a),
                2 => Step::ExitIsr,
                3 => Step::IsrActivate(a, b),
                _ => Step::Query(a),
            };
            second_step_keeps_the_invariants(isr, task, s);
        });
}
