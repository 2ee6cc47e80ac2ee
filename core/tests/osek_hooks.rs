//! OSEK OS conformance, error handling, hook routines and OS execution control (the test
//! plan's sequences for `StartupHook`, `ShutdownHook`, `PreTaskHook`, `PostTaskHook`,
//! `ErrorHook`, `GetActiveApplicationMode`, `StartOS` with application modes and
//! `ShutdownOS`), plus AUTOSAR's missing end of a task.
//!
//! Hooks are called where OSEK says: `PreTaskHook` each time a task enters the running
//! state, `PostTaskHook` each time it is about to leave it (neither around an ISR, which
//! changes no task's state), `ErrorHook` at the end of every service that returns an error,
//! never from inside itself. A hook script's first step of each invocation states what the
//! kernel passed (the task `GetTaskID` names in it, the error and the failed call).

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    AlarmAction, AlarmBase, AlarmConfig, AlarmId, AppMode, ConformanceClass, CounterConfig,
    CounterId, Dialect, EventMask, HookSet, IsrConfig, IsrId, OsConfig, OsDescription, OsError,
    ResourceId, Returned,
    ServiceCall::{self, *},
    TaskConfig, TaskId, TaskState, E_OK, OSDEFAULTAPPMODE,
};
use exec::{check_each, config, end, err, hook, ok, raise, ret, HookCall, Program, Step};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const INVALID: TaskId = TaskId(50);
const TICK: IsrId = IsrId(0);
const A0: AlarmId = AlarmId(0);
const C0: CounterId = CounterId(0);
const E1: EventMask = 0b1;

const fn counter(max: u32) -> CounterConfig {
    CounterConfig {
        max_allowed_value: max,
        ticks_per_base: 10,
        min_cycle: 1,
    }
}

// ---- Sequence 1: StartupHook, ShutdownOS from it, ShutdownHook (cases 1, 3, 6, 7).

const fn s01(dialect: Dialect) -> OsConfig<1, 0, 0, 0, 0> {
    config(
        OsDescription::new([TaskConfig::basic("t1", 1).autostart()], [], [], [])
            .dialect(dialect)
            .hooks(HookSet::ALL)
            .app_modes(2),
    )
}

static S01: [OsConfig<1, 0, 0, 0, 0>; 2] = [s01(Dialect::Osek), s01(Dialect::Autosar)];

/// Sequence 1: `StartupHook` knows the application mode, may call neither `GetTaskID` nor
/// `ActivateTask` (both reach `ErrorHook`), and may shut the OS down; then `ShutdownHook`
/// runs with the error (it may not call `ShutdownOS`, which reports to no `ErrorHook`), and
/// the autostart task never runs.
#[test]
fn eh_seq01_startup_hook_shuts_down() {
    static P: Program = Program::tasks(&[&[]])
        .mode(AppMode(1))
        .os_hooks(
            &[
                hook(1, HookCall::Startup),
                ret(2, GetActiveApplicationMode, Returned::Mode(AppMode(1))),
                err(3, GetTaskId, OsError::CallLevel),
                err(6, ActivateTask(T1), OsError::CallLevel),
                ok(9, ShutdownOs(E_OK)),
            ],
            &[
                hook(10, HookCall::Shutdown(E_OK)),
                ret(11, GetActiveApplicationMode, Returned::Mode(AppMode(1))),
                err(12, ShutdownOs(E_OK), OsError::CallLevel),
                end(13),
            ],
        )
        .error_hook(&[
            hook(4, HookCall::Error(OsError::CallLevel, GetTaskId)),
            end(5),
            hook(7, HookCall::Error(OsError::CallLevel, ActivateTask(T1))),
            end(8),
        ]);
    check_each::<1, 0, 0, 0, 0, 1>(&S01, &P);
}

// ---- Sequence 2: Pre/PostTaskHook calling points and the services inside them (cases 1,
// 4, 5, 8, 9, 12, 13, 14). t1 (1, extended) autostart, t2 (2); an alarm sets t1's event; a
// tick ISR drives its counter.

const fn s02(class: ConformanceClass) -> OsConfig<2, 0, 1, 1, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::extended("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [counter(3)],
            [AlarmConfig::new("a0", C0, AlarmAction::SetEvent(T1, E1))],
            [IsrConfig::cat2("tick", 1)],
        )
        .class(class)
        .hooks(HookSet::ALL),
    )
}

static S02: [OsConfig<2, 0, 1, 1, 1>; 2] =
    [s02(ConformanceClass::Ecc1), s02(ConformanceClass::Ecc2)];

const BASE: Returned = Returned::Base(AlarmBase {
    max_allowed_value: 3,
    ticks_per_base: 10,
    min_cycle: 1,
});

/// Sequence 2: `PreTaskHook` at each dispatch and `PostTaskHook` before each exit from the
/// running state (waiting, chaining), both seeing that task as running, and what they may
/// ask; an error inside them reaches `ErrorHook`; an ISR in between calls neither;
/// `ShutdownOS` calls no `PostTaskHook` (AUTOSAR SWS_Os_00071).
#[test]
fn eh_seq02_pre_and_post_task_hooks() {
    static P: Program = Program::tasks(&[
        &[
            ok(
                12,
                SetAbsAlarm {
                    alarm: A0,
                    start: 3,
                    cycle: 0,
                },
            ),
            ok(13, WaitEvent(E1)),
            ok(34, ChainTask(T2)),
        ],
        &[ok(43, ShutdownOs(E_OK))],
    ])
    .isrs(&[&[
        ok(20, IncrementCounter(C0)),
        end(21),
        ok(23, IncrementCounter(C0)),
        end(24),
        ok(26, IncrementCounter(C0)),
        end(27),
    ]])
    .idle(&[raise(19, TICK), raise(22, TICK), raise(25, TICK)])
    .os_hooks(
        &[hook(1, HookCall::Startup), end(2)],
        &[hook(44, HookCall::Shutdown(E_OK)), end(45)],
    )
    .task_hooks(
        &[
            hook(3, HookCall::Pre(Some(T1))),
            ret(
                4,
                GetActiveApplicationMode,
                Returned::Mode(OSDEFAULTAPPMODE),
            ),
            ret(5, GetTaskState(T1), Returned::State(TaskState::Running)),
            ret(6, GetEvent(T1), Returned::Events(0)),
            ret(7, GetAlarmBase(A0), BASE),
            err(8, GetAlarm(A0), OsError::NoFunc),
            end(11),
            hook(28, HookCall::Pre(Some(T1))),
            ret(29, GetEvent(T1), Returned::Events(E1)),
            err(30, GetAlarm(A0), OsError::NoFunc),
            end(33),
            hook(38, HookCall::Pre(Some(T2))),
            err(39, GetEvent(T2), OsError::Access),
            end(42),
        ],
        &[
            hook(14, HookCall::Post(Some(T1))),
            ret(15, GetTaskState(T1), Returned::State(TaskState::Running)),
            ret(16, GetEvent(T1), Returned::Events(0)),
            ret(17, GetAlarm(A0), Returned::Ticks(3)),
            end(18),
            hook(35, HookCall::Post(Some(T1))),
            ret(36, GetEvent(T1), Returned::Events(E1)),
            end(37),
        ],
    )
    .error_hook(&[
        hook(9, HookCall::Error(OsError::NoFunc, GetAlarm(A0))),
        end(10),
        hook(31, HookCall::Error(OsError::NoFunc, GetAlarm(A0))),
        end(32),
        hook(40, HookCall::Error(OsError::Access, GetEvent(T2))),
        end(41),
    ]);
    check_each::<2, 0, 1, 1, 1, 2>(&S02, &P);
}

// ---- Sequence 3: the services inside ErrorHook (cases 1, 5, 8, 9, 12, 13, 14).

const fn s03(dialect: Dialect) -> OsConfig<1, 0, 1, 1, 1> {
    config(
        OsDescription::new(
            [TaskConfig::extended("t1", 1).autostart()],
            [counter(3)],
            [AlarmConfig::new("a0", C0, AlarmAction::SetEvent(T1, E1))],
            [IsrConfig::cat2("tick", 1)],
        )
        .dialect(dialect)
        .hooks(HookSet {
            error: true,
            ..HookSet::NONE
        }),
    )
}

static S03: [OsConfig<1, 0, 1, 1, 1>; 2] = [s03(Dialect::Osek), s03(Dialect::Autosar)];

/// Sequence 3: inside `ErrorHook`, the failed service and its parameters
/// (`OSErrorGetServiceId`, `OSError_SetAbsAlarm_AlarmID`, `_start`, `_cycle`), and what it
/// may ask; a service it may not call fails without calling `ErrorHook` again.
#[test]
fn eh_seq03_services_inside_error_hook() {
    static P: Program = Program::tasks(&[&[
        ok(
            1,
            SetAbsAlarm {
                alarm: A0,
                start: 3,
                cycle: 3,
            },
        ),
        ok(2, WaitEvent(E1)),
        err(
            12,
            SetAbsAlarm {
                alarm: A0,
                start: 2,
                cycle: 2,
            },
            OsError::State,
        ),
        ok(24, TerminateTask),
    ]])
    .isrs(&[&[
        ok(4, IncrementCounter(C0)),
        end(5),
        ok(7, IncrementCounter(C0)),
        end(8),
        ok(10, IncrementCounter(C0)),
        end(11),
    ]])
    .idle(&[raise(3, TICK), raise(6, TICK), raise(9, TICK)])
    .error_hook(&[
        hook(
            13,
            HookCall::Error(
                OsError::State,
                SetAbsAlarm {
                    alarm: A0,
                    start: 2,
                    cycle: 2,
                },
            ),
        ),
        ret(
            14,
            GetActiveApplicationMode,
            Returned::Mode(OSDEFAULTAPPMODE),
        ),
        ret(15, GetTaskId, Returned::Task(Some(T1))),
        ret(16, GetTaskState(T1), Returned::State(TaskState::Running)),
        ret(17, GetEvent(T1), Returned::Events(E1)),
        ret(18, GetAlarmBase(A0), BASE),
        ret(19, GetAlarm(A0), Returned::Ticks(3)),
        ret(20, GetIsrId, Returned::Isr(None)),
        err(21, ActivateTask(T1), OsError::CallLevel),
        err(22, GetAlarm(AlarmId(9)), OsError::Id),
        end(23),
    ]);
    check_each::<1, 0, 1, 1, 1, 1>(&S03, &P);
}

// ---- Sequence 4: interrupts raised inside hooks run after the hook (cases 10, 11, 17, 18,
// 20, 23, 24, 28, 30, 33, 34).

const fn s04() -> OsConfig<2, 0, 0, 0, 2> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1), IsrConfig::cat2("isr2", 2)],
        )
        .hooks(HookSet {
            pre_task: true,
            post_task: true,
            ..HookSet::NONE
        }),
    )
}

static S04: [OsConfig<2, 0, 0, 0, 2>; 1] = [s04()];

/// Sequence 4: an interrupt raised in a pre- or post-task hook is held (hooks run with
/// category-2 ISRs masked), also inside the hook's own `SuspendAllInterrupts` section; each
/// is taken once, highest first, when the hook is over; no task hook runs around an ISR.
#[test]
fn eh_seq04_interrupts_raised_in_hooks() {
    static P: Program = Program::tasks(&[&[ok(3, ChainTask(T2))], &[ok(19, TerminateTask)]])
        .isrs(&[
            &[end(18)],
            &[
                ret(
                    16,
                    GetActiveApplicationMode,
                    Returned::Mode(OSDEFAULTAPPMODE),
                ),
                end(17),
            ],
        ])
        .task_hooks(
            &[
                hook(1, HookCall::Pre(Some(T1))),
                end(2),
                hook(10, HookCall::Pre(Some(T2))),
                raise(11, IsrId(1)),
                ok(12, SuspendAllInterrupts),
                raise(13, IsrId(1)),
                ok(14, ResumeAllInterrupts),
                end(15),
            ],
            &[
                hook(4, HookCall::Post(Some(T1))),
                raise(5, IsrId(0)),
                ok(6, SuspendAllInterrupts),
                raise(7, IsrId(0)),
                ok(8, ResumeAllInterrupts),
                end(9),
                hook(20, HookCall::Post(Some(T2))),
                end(21),
            ],
        );
    check_each::<2, 0, 0, 0, 2, 2>(&S04, &P);
}

// ---- Sequence 5: ErrorHook for every service that returns an error, with the service and
// its parameters, the failing action of an alarm, never recursively; ShutdownOS from
// ErrorHook.

const fn s05(dialect: Dialect) -> OsConfig<2, 1, 1, 1, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::extended("t1", 1).uses(0b1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [counter(9)],
            [AlarmConfig::new("a0", C0, AlarmAction::ActivateTask(T1))],
            [IsrConfig::cat2("tick", 1)],
        )
        .dialect(dialect)
        .hooks(HookSet {
            error: true,
            shutdown: true,
            ..HookSet::NONE
        }),
    )
}

static S05: [OsConfig<2, 1, 1, 1, 1>; 2] = [s05(Dialect::Osek), s05(Dialect::Autosar)];

/// Every failing call t1 makes, with the error it must return (and `ErrorHook` must see).
const FAILING: [(ServiceCall, OsError); 20] = [
    (ActivateTask(INVALID), OsError::Id),
    (ActivateTask(T1), OsError::Limit),
    (ChainTask(INVALID), OsError::Id),
    (
        SetRelAlarm {
            alarm: AlarmId(9),
            increment: 1,
            cycle: 0,
        },
        OsError::Id,
    ),
    (GetTaskState(INVALID), OsError::Id),
    (GetResource(ResourceId(7)), OsError::Id),
    (ReleaseResource(ResourceId(0)), OsError::NoFunc),
    (SetEvent(T2, E1), OsError::Access),
    (SetEvent(INVALID, E1), OsError::Id),
    (GetEvent(T2), OsError::Access),
    (GetAlarm(A0), OsError::NoFunc),
    (GetAlarmBase(AlarmId(5)), OsError::Id),
    (
        SetRelAlarm {
            alarm: A0,
            increment: 100,
            cycle: 0,
        },
        OsError::Value,
    ),
    (
        SetAbsAlarm {
            alarm: A0,
            start: 1,
            cycle: 100,
        },
        OsError::Value,
    ),
    (CancelAlarm(A0), OsError::NoFunc),
    (IncrementCounter(CounterId(3)), OsError::Id),
    (GetCounterValue(CounterId(3)), OsError::Id),
    (GetElapsedValue(C0, 50), OsError::Value),
    (WaitEvent(0), OsError::Resource),
    (TerminateTask, OsError::Resource),
];

/// t1's script and `ErrorHook`'s: each failing call, then its `ErrorHook` invocation
/// (which also tries a call it may not make: no second `ErrorHook`); the last two are made
/// holding the resource. Then an alarm whose action fails (t1 is running), and finally
/// `ShutdownOS` from `ErrorHook`.
const fn s05_scripts() -> ([Step; 25], [Step; 65]) {
    let mut task = [ok(0, TerminateTask); 25];
    let mut error = [end(0); 65];
    let mut seq = 1;
    let mut t = 0;
    let mut e = 0;
    let mut k = 0;
    while k < FAILING.len() {
        if k == 18 {
            task[t] = ok(seq, GetResource(ResourceId(0)));
            t += 1;
            seq += 1;
        }
        let (call, error_code) = FAILING[k];
        task[t] = err(seq, call, error_code);
        error[e] = hook(seq + 1, HookCall::Error(error_code, call));
        error[e + 1] = err(seq + 2, ActivateTask(T2), OsError::CallLevel);
        error[e + 2] = end(seq + 3);
        t += 1;
        e += 3;
        seq += 4;
        k += 1;
    }
    task[t] = ok(seq, ReleaseResource(ResourceId(0)));
    task[t + 1] = ok(
        seq + 1,
        SetRelAlarm {
            alarm: A0,
            increment: 1,
            cycle: 0,
        },
    );
    task[t + 2] = raise(seq + 2, TICK);
    // The tick ISR (its script below) ticks; the alarm's ActivateTask(t1) fails.
    error[e] = hook(seq + 4, HookCall::Error(OsError::Limit, ActivateTask(T1)));
    error[e + 1] = ret(seq + 5, GetIsrId, Returned::Isr(Some(TICK)));
    error[e + 2] = end(seq + 6);
    // Back in t1: a last error, and ShutdownOS from ErrorHook.
    task[t + 3] = err(seq + 8, ActivateTask(INVALID), OsError::Id);
    error[e + 3] = hook(seq + 9, HookCall::Error(OsError::Id, ActivateTask(INVALID)));
    error[e + 4] = ok(seq + 10, ShutdownOs(OsError::Id.status()));
    (task, error)
}

const S05_SCRIPTS: ([Step; 25], [Step; 65]) = s05_scripts();
static S05_TASK: [Step; 25] = S05_SCRIPTS.0;
static S05_ERROR: [Step; 65] = S05_SCRIPTS.1;

/// Sequence 5: `ErrorHook` is called for every service that returns an error, with
/// `OSErrorGetServiceId` and the parameters, never from inside itself; for an alarm action
/// that fails, with that action's service (AUTOSAR SWS_Os_00321: `IncrementCounter` itself
/// returns `E_OK`); `ShutdownOS` from `ErrorHook` ends everything.
#[test]
fn eh_seq05_error_hook_for_every_service() {
    static P: Program = Program::tasks(&[&S05_TASK, &[]])
        .isrs(&[&[ok(85, IncrementCounter(C0)), end(89)]])
        .error_hook(&S05_ERROR)
        .os_hooks(
            &[],
            &[hook(93, HookCall::Shutdown(OsError::Id.status())), end(94)],
        );
    check_each::<2, 1, 1, 1, 1, 2>(&S05, &P);
}

// ---- Sequence 6: application modes (StartOS, GetActiveApplicationMode).

const fn s06() -> OsConfig<2, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2).autostart_in(0b10),
            ],
            [counter(9)],
            [AlarmConfig::new("a0", C0, AlarmAction::ActivateTask(T1))
                .relative(4, 0)
                .in_modes(0b10)],
            [],
        )
        .app_modes(2),
    )
}

static S06: [OsConfig<2, 0, 1, 1, 0>; 1] = [s06()];

/// Sequence 6: `StartOS(mode)` activates the tasks and arms the alarms of that mode only.
#[test]
fn eh_seq06_application_modes() {
    static DEFAULT: Program = Program::tasks(&[
        &[
            ret(
                1,
                GetActiveApplicationMode,
                Returned::Mode(OSDEFAULTAPPMODE),
            ),
            err(2, GetAlarm(A0), OsError::NoFunc),
            ok(3, TerminateTask),
        ],
        &[],
    ]);
    static SECOND: Program = Program::tasks(&[
        &[],
        &[
            ret(1, GetActiveApplicationMode, Returned::Mode(AppMode(1))),
            ret(2, GetAlarm(A0), Returned::Ticks(4)),
            ret(3, GetTaskState(T1), Returned::State(TaskState::Suspended)),
            ok(4, TerminateTask),
        ],
    ])
    .mode(AppMode(1));
    check_each::<2, 0, 1, 1, 0, 2>(&S06, &DEFAULT);
    check_each::<2, 0, 1, 1, 0, 2>(&S06, &SECOND);
}

// ---- Sequence 7: a task body that returns without TerminateTask (AUTOSAR SWS_Os_00052,
// 00069, 00070, 00239; OSEK calls it undefined).

const fn s07() -> OsConfig<2, 1, 0, 0, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).uses(0b1).autostart(),
                TaskConfig::basic("t2", 2).uses(0b1),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 3)],
        )
        .hooks(HookSet {
            error: true,
            post_task: true,
            ..HookSet::NONE
        }),
    )
}

static S07: [OsConfig<2, 1, 0, 0, 1>; 1] = [s07()];

/// Sequence 7: t1 returns holding a resource under `SuspendOSInterrupts`: `ErrorHook`
/// sees `E_OS_MISSINGEND` while t1 still runs (with its lock already undone and its
/// resource released), then `PostTaskHook`, then the next task; the interrupt held by the
/// lock runs.
#[test]
fn eh_seq07_missing_end_of_a_task() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(ResourceId(0))),
            ok(2, ActivateTask(T2)),
            ok(3, SuspendOsInterrupts),
            raise(4, IsrId(0)),
            end(5),
        ],
        &[ok(12, TerminateTask)],
    ])
    .isrs(&[&[end(11)]])
    .error_hook(&[
        hook(6, HookCall::Error(OsError::MissingEnd, TaskMissingEnd(T1))),
        ret(7, GetTaskState(T1), Returned::State(TaskState::Running)),
        end(8),
    ])
    .task_hooks(
        &[],
        &[
            hook(9, HookCall::Post(Some(T1))),
            end(10),
            hook(13, HookCall::Post(Some(T2))),
            end(14),
        ],
    );
    check_each::<2, 1, 0, 0, 1, 2>(&S07, &P);
}

// ---- Sequence 8: ShutdownOS from a category-2 ISR, and where it is refused.

const fn s08() -> OsConfig<2, 0, 0, 0, 2> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1), IsrConfig::cat1("fast", 9)],
        )
        .hooks(HookSet::ALL),
    )
}

static S08: [OsConfig<2, 0, 0, 0, 2>; 1] = [s08()];

/// Sequence 8: `ShutdownOS` is refused in a pre- or post-task hook and in a category-1
/// ISR; from a category-2 ISR it calls `ShutdownHook` with its error, and then nothing
/// runs: not the task the ISR activated, not the interrupt raised before.
#[test]
fn eh_seq08_shutdown_from_an_isr() {
    static P: Program = Program::tasks(&[&[raise(6, IsrId(1)), raise(9, IsrId(0))], &[]])
        .isrs(&[
            &[
                ok(10, ActivateTask(T2)),
                raise(11, IsrId(0)),
                ok(12, ShutdownOs(42)),
            ],
            &[err(7, ShutdownOs(1), OsError::CallLevel), end(8)],
        ])
        .os_hooks(
            &[hook(1, HookCall::Startup), end(2)],
            &[hook(13, HookCall::Shutdown(42)), end(14)],
        )
        .task_hooks(
            &[
                hook(3, HookCall::Pre(Some(T1))),
                err(4, ShutdownOs(1), OsError::CallLevel),
                end(5),
            ],
            &[],
        );
    check_each::<2, 0, 0, 0, 2, 2>(&S08, &P);
}
