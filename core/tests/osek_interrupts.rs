//! OSEK OS conformance, interrupt processing (the test plan's interrupt sequences, as
//! rewritten for OS 2.2.3): the six interrupt services from a task and from an ISR, their
//! nesting and pairing, requests held while masked and taken once when unmasked, ISR
//! nesting by priority, the return to a non-preemptive or a preemptive task, interrupt
//! services in alarm callbacks, `E_OS_DISABLEDINT` for every service under a lock, category
//! 1 ISRs, and AUTOSAR's cleanup of an ISR that returns with a lock or a resource.
//!
//! Requests are one flag each: raising an interrupt that is already pending is lost, as on
//! real hardware. A step numbered `n` in an ISR's script executes when the executive's
//! interrupt controller takes the request, which is the one order the standard allows.

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    AlarmAction, AlarmConfig, AlarmId, ConformanceClass, CounterConfig, CounterId, Dialect,
    HookSet, IsrConfig, IsrId, OsConfig, OsDescription, OsError, ResourceId, Returned,
    ServiceCall::{self, *},
    Status, TaskConfig, TaskId, TaskState,
};
use exec::{check_each, config, end, err, hook, ok, raise, ret, HookCall, Program};
use ConformanceClass::{Bcc1, Bcc2, Ecc1, Ecc2};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const T3: TaskId = TaskId(2);
const ISR1: IsrId = IsrId(0);
const ISR2: IsrId = IsrId(1);
const ISR3: IsrId = IsrId(2);

// ---- Sequence 1: the interrupt services from a task and from an ISR (cases 1, 2, 4-7,
// 9-12, 14-16, 20-31, 34), every class, both statuses, both policies. t1 (1) autostart;
// isr1 (1) < isr2 (2) < isr3 (3).

const fn s01(class: ConformanceClass, status: Status, non: bool) -> OsConfig<2, 0, 0, 0, 3> {
    let t1 = TaskConfig::basic("t1", 1).autostart();
    config(
        OsDescription::new(
            [
                if non { t1.non_preemptive() } else { t1 },
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [
                IsrConfig::cat2("isr1", 1),
                IsrConfig::cat2("isr2", 2),
                IsrConfig::cat2("isr3", 3),
            ],
        )
        .class(class)
        .status(status),
    )
}

const fn s01_all() -> [OsConfig<2, 0, 0, 0, 3>; 16] {
    let classes = [Bcc1, Bcc2, Ecc1, Ecc2];
    let mut out = [s01(Bcc1, Status::Standard, false); 16];
    let mut k = 0;
    while k < 16 {
        let status = if k % 2 == 0 {
            Status::Standard
        } else {
            Status::Extended
        };
        out[k] = s01(classes[k / 4], status, (k / 2) % 2 == 1);
        k += 1;
    }
    out
}

static S01: [OsConfig<2, 0, 0, 0, 3>; 16] = s01_all();

/// Sequence 1: `DisableAll`/`EnableAll`, `SuspendAll`/`ResumeAll` and `SuspendOS`/
/// `ResumeOS`, nested three deep, from t1 and then from isr1: a request raised three
/// times while masked runs once, when the last lock goes; unmasked, it runs at once; a
/// higher ISR interrupts isr1; a lower one raised by isr3 waits for isr3 and runs before
/// isr1 resumes.
#[test]
fn ip_seq01_interrupt_services_and_nesting() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, DisableAllInterrupts),
            ok(2, EnableAllInterrupts),
            ok(3, DisableAllInterrupts),
            raise(4, ISR2),
            raise(5, ISR2),
            raise(6, ISR2),
            ok(7, EnableAllInterrupts),
            raise(9, ISR2),
            ok(11, SuspendAllInterrupts),
            ok(12, ResumeAllInterrupts),
            ok(13, SuspendAllInterrupts),
            ok(14, SuspendAllInterrupts),
            ok(15, SuspendAllInterrupts),
            raise(16, ISR2),
            ok(17, ResumeAllInterrupts),
            ok(18, ResumeAllInterrupts),
            ok(19, ResumeAllInterrupts),
            raise(21, ISR2),
            ok(23, SuspendOsInterrupts),
            ok(24, ResumeOsInterrupts),
            ok(25, SuspendOsInterrupts),
            ok(26, SuspendOsInterrupts),
            ok(27, SuspendOsInterrupts),
            raise(28, ISR2),
            ok(29, ResumeOsInterrupts),
            ok(30, ResumeOsInterrupts),
            ok(31, ResumeOsInterrupts),
            raise(33, ISR1),
            ok(71, TerminateTask),
        ],
        &[],
    ])
    .isrs(&[
        &[
            ok(34, DisableAllInterrupts),
            ok(35, EnableAllInterrupts),
            ok(36, DisableAllInterrupts),
            raise(37, ISR2),
            raise(38, ISR2),
            raise(39, ISR2),
            ok(40, EnableAllInterrupts),
            raise(42, ISR2),
            ok(44, SuspendAllInterrupts),
            ok(45, ResumeAllInterrupts),
            ok(46, SuspendAllInterrupts),
            ok(47, SuspendAllInterrupts),
            ok(48, SuspendAllInterrupts),
            raise(49, ISR2),
            ok(50, ResumeAllInterrupts),
            ok(51, ResumeAllInterrupts),
            ok(52, ResumeAllInterrupts),
            raise(54, ISR2),
            ok(56, SuspendOsInterrupts),
            ok(57, ResumeOsInterrupts),
            ok(58, SuspendOsInterrupts),
            ok(59, SuspendOsInterrupts),
            ok(60, SuspendOsInterrupts),
            raise(61, ISR2),
            ok(62, ResumeOsInterrupts),
            ok(63, ResumeOsInterrupts),
            ok(64, ResumeOsInterrupts),
            raise(66, ISR3),
            end(70),
        ],
        &[
            end(8),
            end(10),
            end(20),
            end(22),
            end(32),
            end(41),
            end(43),
            end(53),
            end(55),
            end(65),
            end(69),
        ],
        &[raise(67, ISR2), end(68)],
    ]);
    check_each::<2, 0, 0, 0, 3, 2>(&S01, &P);
}

// ---- Sequences 2 and 3: the return from an ISR to a non-preemptive and to a preemptive
// task (cases 17, 18, 32, 33). t1 (1) autostart, t2 (2); isr1 (1) < isr2 (2).

const fn s02(class: ConformanceClass, non: bool) -> OsConfig<2, 0, 0, 0, 2> {
    let t1 = TaskConfig::basic("t1", 1).autostart();
    config(
        OsDescription::new(
            [
                if non { t1.non_preemptive() } else { t1 },
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1), IsrConfig::cat2("isr2", 2)],
        )
        .class(class),
    )
}

static S02_NON: [OsConfig<2, 0, 0, 0, 2>; 4] = [
    s02(Bcc1, true),
    s02(Bcc2, true),
    s02(Ecc1, true),
    s02(Ecc2, true),
];
static S02_FULL: [OsConfig<2, 0, 0, 0, 2>; 4] = [
    s02(Bcc1, false),
    s02(Bcc2, false),
    s02(Ecc1, false),
    s02(Ecc2, false),
];

/// Sequence 2: isr1 is interrupted by the higher isr2, which raises isr1 again (equal to
/// the running level: pending) and activates t2; when the ISRs are done, the
/// non-preemptive t1 continues.
#[test]
fn ip_seq02_return_to_a_non_preemptive_task() {
    static P: Program = Program::tasks(&[
        &[raise(1, ISR1), ok(8, TerminateTask)],
        &[ok(9, TerminateTask)],
    ])
    .isrs(&[
        &[raise(2, ISR2), end(6), end(7)],
        &[raise(3, ISR1), ok(4, ActivateTask(T2)), end(5)],
    ]);
    check_each::<2, 0, 0, 0, 2, 2>(&S02_NON, &P);
}

/// Sequence 3: the same under full preemption: t2 runs when the last ISR returns.
#[test]
fn ip_seq03_return_to_a_preemptive_task() {
    static P: Program = Program::tasks(&[
        &[raise(1, ISR1), ok(9, TerminateTask)],
        &[ok(8, TerminateTask)],
    ])
    .isrs(&[
        &[raise(2, ISR2), end(6), end(7)],
        &[raise(3, ISR1), ok(4, ActivateTask(T2)), end(5)],
    ]);
    check_each::<2, 0, 0, 0, 2, 2>(&S02_FULL, &P);
}

// ---- Sequence 4: interrupt services in alarm callbacks (cases 35-39). t1 autostart; two
// callback alarms on a counter the tick ISR (isr1, priority 1) drives; isr2 (2).

const fn s04(dialect: Dialect) -> OsConfig<1, 0, 1, 2, 2> {
    config(
        OsDescription::new(
            [TaskConfig::basic("t1", 1).autostart()],
            [CounterConfig {
                max_allowed_value: 99,
                ticks_per_base: 1,
                min_cycle: 1,
            }],
            [
                AlarmConfig::new("cb1", CounterId(0), AlarmAction::Callback(1)),
                AlarmConfig::new("cb2", CounterId(0), AlarmAction::Callback(2)),
            ],
            [IsrConfig::cat2("tick", 1), IsrConfig::cat2("isr2", 2)],
        )
        .dialect(dialect),
    )
}

static S04: [OsConfig<1, 0, 1, 2, 2>; 2] = [s04(Dialect::Osek), s04(Dialect::Autosar)];

/// Sequence 4: a callback may suspend and resume all interrupts, nested; an interrupt it
/// raises waits until the callback is over (callbacks run with category-2 ISRs held), and
/// is taken then, inside the tick ISR it is higher than. `ActivateTask` there is refused.
#[test]
fn ip_seq04_interrupt_services_in_alarm_callbacks() {
    static P: Program = Program::tasks(&[&[
        ok(
            1,
            SetRelAlarm {
                alarm: AlarmId(0),
                increment: 1,
                cycle: 0,
            },
        ),
        raise(2, ISR1),
        ok(
            12,
            SetRelAlarm {
                alarm: AlarmId(1),
                increment: 1,
                cycle: 0,
            },
        ),
        raise(13, ISR1),
        ok(27, TerminateTask),
    ]])
    .isrs(&[
        &[
            ok(3, IncrementCounter(CounterId(0))),
            end(11),
            ok(14, IncrementCounter(CounterId(0))),
            end(26),
        ],
        &[end(10), end(25)],
    ])
    .callbacks(&[
        hook(4, HookCall::Callback(1)),
        ok(5, SuspendAllInterrupts),
        ok(6, ResumeAllInterrupts),
        err(7, ActivateTask(T1), OsError::CallLevel),
        raise(8, ISR2),
        end(9),
        hook(15, HookCall::Callback(2)),
        ok(16, SuspendAllInterrupts),
        ok(17, SuspendAllInterrupts),
        ok(18, SuspendAllInterrupts),
        raise(19, ISR2),
        ok(20, ResumeAllInterrupts),
        ok(21, ResumeAllInterrupts),
        ok(22, ResumeAllInterrupts),
        raise(23, ISR2),
        end(24),
    ]);
    check_each::<1, 0, 1, 2, 2, 1>(&S04, &P);
}

// ---- Sequence 5: mismatched pairs and E_OS_DISABLEDINT (cases 3, 8, 13, 19), extended
// status, full preemption.

const fn s05(class: ConformanceClass) -> OsConfig<2, 0, 0, 0, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class),
    )
}

static S05: [OsConfig<2, 0, 0, 0, 1>; 4] = [s05(Bcc1), s05(Bcc2), s05(Ecc1), s05(Ecc2)];

/// Sequence 5: a resume or enable without its own suspend or disable is not carried out
/// (AUTOSAR SWS_Os_00092), nor is a `DisableAllInterrupts` inside a `Suspend` section or a
/// `Suspend` inside a `DisableAllInterrupts` section (OSEK allows no service there); any
/// other service returns `E_OS_DISABLEDINT`; the held request runs when the right lock
/// goes.
#[test]
fn ip_seq05_mismatched_pairs_and_disabledint() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, SuspendAllInterrupts),
            err(2, ActivateTask(T2), OsError::DisabledInt),
            raise(3, ISR1),
            err(4, ResumeOsInterrupts, OsError::NoFunc),
            err(5, EnableAllInterrupts, OsError::NoFunc),
            ok(6, ResumeAllInterrupts),
            ok(8, SuspendOsInterrupts),
            err(9, ActivateTask(T2), OsError::DisabledInt),
            raise(10, ISR1),
            err(11, ResumeAllInterrupts, OsError::NoFunc),
            err(12, EnableAllInterrupts, OsError::NoFunc),
            err(13, DisableAllInterrupts, OsError::DisabledInt),
            err(14, EnableAllInterrupts, OsError::NoFunc),
            ok(15, ResumeOsInterrupts),
            ok(17, DisableAllInterrupts),
            err(18, ActivateTask(T2), OsError::DisabledInt),
            raise(19, ISR1),
            err(20, ResumeAllInterrupts, OsError::NoFunc),
            err(21, ResumeOsInterrupts, OsError::NoFunc),
            err(22, SuspendAllInterrupts, OsError::DisabledInt),
            ok(23, EnableAllInterrupts),
            ret(25, GetTaskState(T2), Returned::State(TaskState::Suspended)),
            ok(26, TerminateTask),
        ],
        &[],
    ])
    .isrs(&[&[end(7), end(16), end(24)]]);
    check_each::<2, 0, 0, 0, 1, 2>(&S05, &P);
}

// ---- Sequence 6: every service under SuspendAllInterrupts (case 19).

const fn s06(dialect: Dialect) -> OsConfig<3, 1, 1, 1, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::extended("t1", 2).uses(0b1).autostart(),
                TaskConfig::basic("t2", 3),
                TaskConfig::extended("t3", 1),
            ],
            [CounterConfig {
                max_allowed_value: 99,
                ticks_per_base: 1,
                min_cycle: 1,
            }],
            [AlarmConfig::new(
                "a1",
                CounterId(0),
                AlarmAction::ActivateTask(TaskId(1)),
            )],
            [IsrConfig::cat2("isr1", 1)],
        )
        .dialect(dialect),
    )
}

static S06: [OsConfig<3, 1, 1, 1, 1>; 2] = [s06(Dialect::Osek), s06(Dialect::Autosar)];

/// The services sequence 6 calls under the lock, each of which must be refused.
const UNDER_LOCK: [ServiceCall; 25] = [
    ActivateTask(T2),
    TerminateTask,
    ChainTask(T2),
    Schedule,
    GetTaskId,
    GetTaskState(T2),
    GetResource(ResourceId(0)),
    ReleaseResource(ResourceId(0)),
    SetEvent(T3, 1),
    ClearEvent(1),
    GetEvent(T3),
    WaitEvent(1),
    GetAlarmBase(AlarmId(0)),
    GetAlarm(AlarmId(0)),
    SetRelAlarm {
        alarm: AlarmId(0),
        increment: 1,
        cycle: 0,
    },
    SetAbsAlarm {
        alarm: AlarmId(0),
        start: 1,
        cycle: 0,
    },
    CancelAlarm(AlarmId(0)),
    GetActiveApplicationMode,
    GetIsrId,
    IncrementCounter(CounterId(0)),
    GetCounterValue(CounterId(0)),
    GetElapsedValue(CounterId(0), 0),
    ShutdownOs(0),
    ChainTask(T1),
    ActivateTask(T3),
];

const fn s06_t1() -> [exec::Step; 32] {
    let mut steps = [ok(0, TerminateTask); 32];
    steps[0] = ok(1, ActivateTask(T3));
    steps[1] = ret(2, GetTaskState(T3), Returned::State(TaskState::Ready));
    steps[2] = ok(3, SuspendAllInterrupts);
    let mut k = 0;
    while k < UNDER_LOCK.len() {
        steps[3 + k] = err(4 + k as u16, UNDER_LOCK[k], OsError::DisabledInt);
        k += 1;
    }
    // 29: resume; nothing above changed anything.
    steps[28] = ok(29, ResumeAllInterrupts);
    steps[29] = ret(30, GetTaskState(T2), Returned::State(TaskState::Suspended));
    steps[30] = err(31, GetAlarm(AlarmId(0)), OsError::NoFunc);
    steps[31] = ok(32, TerminateTask);
    steps
}

static S06_T1: [exec::Step; 32] = s06_t1();

/// Sequence 6: while `SuspendAllInterrupts` is in force every other service returns
/// `E_OS_DISABLEDINT` and does nothing (AUTOSAR SWS_Os_00093; OSEK only forbids such
/// calls); after the resume, nothing has changed.
#[test]
fn ip_seq06_every_service_refused_under_a_lock() {
    static P: Program = Program::tasks(&[
        &S06_T1,
        &[],
        &[
            ret(33, GetEvent(T3), Returned::Events(0)),
            ok(34, TerminateTask),
        ],
    ]);
    check_each::<3, 1, 1, 1, 1, 3>(&S06, &P);
}

// ---- Sequence 7: category-1 ISRs (not in the OSEK 2.0 plan: it could not observe them).

const fn s07() -> OsConfig<1, 0, 0, 0, 2> {
    config(OsDescription::new(
        [TaskConfig::basic("t1", 1).autostart()],
        [],
        [],
        [IsrConfig::cat2("isr2", 2), IsrConfig::cat1("fast", 7)],
    ))
}

static S07: [OsConfig<1, 0, 0, 0, 2>; 1] = [s07()];

/// Sequence 7: a category-1 ISR runs under `SuspendOSInterrupts` (which holds the
/// category-2 one) but not under `SuspendAllInterrupts`; it may open its own suspend
/// section but call no other service (`E_OS_CALLEVEL`).
#[test]
fn ip_seq07_category_1_isrs() {
    const CAT2: IsrId = IsrId(0);
    const FAST: IsrId = IsrId(1);
    static P: Program = Program::tasks(&[&[
        ok(1, SuspendOsInterrupts),
        raise(2, CAT2),
        raise(3, FAST),
        ok(9, SuspendAllInterrupts),
        raise(10, FAST),
        ok(11, ResumeAllInterrupts),
        ok(13, ResumeOsInterrupts),
        ok(15, TerminateTask),
    ]])
    .isrs(&[
        &[end(14)],
        &[
            err(4, ActivateTask(T1), OsError::CallLevel),
            err(5, GetTaskId, OsError::CallLevel),
            ok(6, SuspendAllInterrupts),
            ok(7, ResumeAllInterrupts),
            end(8),
            end(12),
        ],
    ]);
    check_each::<1, 0, 0, 0, 2, 1>(&S07, &P);
}

// ---- Sequence 8: an ISR that returns with a lock or a resource (AUTOSAR SWS_Os_00368,
// 00369; OSEK calls it undefined).

const fn s08(dialect: Dialect) -> OsConfig<2, 1, 0, 0, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1).uses(0b1)],
        )
        .dialect(dialect)
        .hooks(HookSet {
            error: true,
            ..HookSet::NONE
        }),
    )
}

static S08: [OsConfig<2, 1, 0, 0, 1>; 2] = [s08(Dialect::Osek), s08(Dialect::Autosar)];

/// Sequence 8: isr1 returns under `SuspendOSInterrupts` and holding a resource: the OS
/// resumes and releases for it and reports both to `ErrorHook` (inside which `GetISRID`
/// names isr1); the activation it made takes effect at its return.
#[test]
fn ip_seq08_isr_returning_with_a_lock_and_a_resource() {
    static P: Program = Program::tasks(&[
        &[raise(1, ISR1), ok(14, TerminateTask)],
        &[
            ret(12, GetIsrId, Returned::Isr(None)),
            ok(13, TerminateTask),
        ],
    ])
    .isrs(&[&[
        ok(2, GetResource(ResourceId(0))),
        ok(3, ActivateTask(T2)),
        ok(4, SuspendOsInterrupts),
        end(5),
    ]])
    .error_hook(&[
        hook(
            6,
            HookCall::Error(OsError::DisabledInt, ServiceCall::IsrMissingEnd(ISR1)),
        ),
        ret(7, GetIsrId, Returned::Isr(Some(ISR1))),
        end(8),
        hook(
            9,
            HookCall::Error(OsError::Resource, ServiceCall::IsrMissingEnd(ISR1)),
        ),
        ret(10, GetTaskId, Returned::Task(Some(T1))),
        end(11),
    ]);
    check_each::<2, 1, 0, 0, 1, 2>(&S08, &P);
}
