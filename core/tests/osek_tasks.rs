//! OSEK OS conformance, task management (the OSEK/VDX OS test plan's sequences for
//! `ActivateTask`, `TerminateTask`, `ChainTask`, `Schedule`, `GetTaskID`, `GetTaskState`,
//! multiple activation and FIFO order, in the conformance classes and preemption policies
//! each sequence names). Each test runs one sequence with the executive in `osek/exec.rs`:
//! the steps' numbers are the one order of execution the standard allows.

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    ConformanceClass, EventMask, IsrConfig, IsrId, OsConfig, OsDescription, OsError, Returned,
    ServiceCall::*, Status, TaskConfig, TaskId, TaskState, RES_SCHEDULER,
};
use exec::{check_each, config, end, err, ok, raise, ret, Program, Step};
use ConformanceClass::{Bcc1, Bcc2, Ecc1, Ecc2};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const T3: TaskId = TaskId(2);
const T4: TaskId = TaskId(3);
const INVALID: TaskId = TaskId(60);
const ISR1: IsrId = IsrId(0);
const E1: EventMask = 0b1;

/// A task of priority `p`, non-preemptive if `non`.
const fn task(name: &'static str, p: u8, non: bool) -> TaskConfig {
    let t = TaskConfig::basic(name, p);
    if non {
        t.non_preemptive()
    } else {
        t
    }
}

// ---- Sequence 1: error codes (test cases 1, 10, 15, 20, 21, 23, 24, 25, 28, 33, 34, 35,
// 37), extended status, every class; t1 (1) autostart, t2 (2), isr1.

const fn s01(class: ConformanceClass, non: bool) -> OsConfig<2, 0, 0, 0, 1> {
    config(
        OsDescription::new(
            [task("t1", 1, non).autostart(), task("t2", 2, false)],
            [],
            [],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class),
    )
}

static S01_FULL: [OsConfig<2, 0, 0, 0, 1>; 4] = [
    s01(Bcc1, false),
    s01(Bcc2, false),
    s01(Ecc1, false),
    s01(Ecc2, false),
];
static S01_NON: [OsConfig<2, 0, 0, 0, 1>; 4] = [
    s01(Bcc1, true),
    s01(Bcc2, true),
    s01(Ecc1, true),
    s01(Ecc2, true),
];

/// The steps both policies share after t2 ran, from `base` on: t1 holds `RES_SCHEDULER`
/// and may not end, chain or yield; isr1 may not call task services; `GetTaskID` in the
/// ISR names the interrupted task (AUTOSAR's reading; the test plan of 2.0 said
/// `E_OS_CALLEVEL`, Trampoline `INVALID_TASK`).
const fn s01_tail(base: u16) -> ([Step; 6], [Step; 5]) {
    (
        [
            ok(base, GetResource(RES_SCHEDULER)),
            err(base + 1, TerminateTask, OsError::Resource),
            err(base + 2, ChainTask(T2), OsError::Resource),
            err(base + 3, Schedule, OsError::Resource),
            ok(base + 4, ReleaseResource(RES_SCHEDULER)),
            raise(base + 5, ISR1),
        ],
        [
            err(base + 6, TerminateTask, OsError::CallLevel),
            err(base + 7, ChainTask(T2), OsError::CallLevel),
            err(base + 8, Schedule, OsError::CallLevel),
            ret(base + 9, GetTaskId, Returned::Task(Some(T1))),
            end(base + 10),
        ],
    )
}

const S01_FULL_TAIL: ([Step; 6], [Step; 5]) = s01_tail(9);
static S01_FULL_T1: [Step; 11] = {
    let t = S01_FULL_TAIL.0;
    [
        err(1, ActivateTask(INVALID), OsError::Id),
        err(2, GetTaskState(INVALID), OsError::Id),
        err(3, ChainTask(INVALID), OsError::Id),
        ok(4, ActivateTask(T2)),
        t[0],
        t[1],
        t[2],
        t[3],
        t[4],
        t[5],
        ok(20, TerminateTask),
    ]
};
static S01_FULL_ISR: [Step; 5] = S01_FULL_TAIL.1;
static S01_FULL_PROGRAM: Program = Program::tasks(&[
    &S01_FULL_T1,
    &[
        err(5, ActivateTask(T1), OsError::Limit),
        err(6, ActivateTask(T2), OsError::Limit),
        err(7, ChainTask(T1), OsError::Limit),
        ok(8, TerminateTask),
    ],
])
.isrs(&[&S01_FULL_ISR]);

const S01_NON_TAIL: ([Step; 6], [Step; 5]) = s01_tail(10);
static S01_NON_T1: [Step; 12] = {
    let t = S01_NON_TAIL.0;
    [
        err(1, ActivateTask(INVALID), OsError::Id),
        err(2, GetTaskState(INVALID), OsError::Id),
        err(3, ChainTask(INVALID), OsError::Id),
        ok(4, ActivateTask(T2)),
        ok(5, Schedule),
        t[0],
        t[1],
        t[2],
        t[3],
        t[4],
        t[5],
        ok(21, TerminateTask),
    ]
};
static S01_NON_ISR: [Step; 5] = S01_NON_TAIL.1;
static S01_NON_PROGRAM: Program = Program::tasks(&[
    &S01_NON_T1,
    &[
        err(6, ActivateTask(T1), OsError::Limit),
        err(7, ActivateTask(T2), OsError::Limit),
        err(8, ChainTask(T1), OsError::Limit),
        ok(9, TerminateTask),
    ],
])
.isrs(&[&S01_NON_ISR]);

/// Sequence 1, full preemption: `E_OS_ID`, `E_OS_LIMIT`, `E_OS_RESOURCE`, `E_OS_CALLEVEL`.
#[test]
fn tm_seq01_errors_full() {
    check_each::<2, 0, 0, 0, 1, 2>(&S01_FULL, &S01_FULL_PROGRAM);
}

/// Sequence 1, non-preemptive caller (t2 runs only at `Schedule`).
#[test]
fn tm_seq01_errors_non() {
    check_each::<2, 0, 0, 0, 1, 2>(&S01_NON, &S01_NON_PROGRAM);
}

// ---- Sequences 2 and 3: activation without and with preemption (cases 2, 3, 4, 32),
// standard and extended status, every class.

const fn three(class: ConformanceClass, status: Status, non: bool) -> OsConfig<3, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                task("t1", 1, non).autostart(),
                task("t2", 2, false),
                task("t3", 3, false),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

const fn every_class(non: bool) -> [OsConfig<3, 0, 0, 0, 0>; 8] {
    [
        three(Bcc1, Status::Standard, non),
        three(Bcc1, Status::Extended, non),
        three(Bcc2, Status::Standard, non),
        three(Bcc2, Status::Extended, non),
        three(Ecc1, Status::Standard, non),
        three(Ecc1, Status::Extended, non),
        three(Ecc2, Status::Standard, non),
        three(Ecc2, Status::Extended, non),
    ]
}

static THREE_NON: [OsConfig<3, 0, 0, 0, 0>; 8] = every_class(true);
static THREE_FULL: [OsConfig<3, 0, 0, 0, 0>; 8] = every_class(false);

/// Sequence 2: a non-preemptive task activates two higher tasks; neither runs until
/// `Schedule`, which lets the highest run first.
#[test]
fn tm_seq02_non_preemptive_activation_and_schedule() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, ActivateTask(T3)),
            ok(3, Schedule),
            ok(6, TerminateTask),
        ],
        &[ok(5, TerminateTask)],
        &[ok(4, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&THREE_NON, &P);
}

/// Sequence 3: activating a higher task preempts the caller; a lower one does not.
#[test]
fn tm_seq03_full_preemptive_activation() {
    static P: Program = Program::tasks(&[
        &[ok(1, ActivateTask(T3)), ok(5, TerminateTask)],
        &[ok(4, TerminateTask)],
        &[ok(2, ActivateTask(T2)), ok(3, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&THREE_FULL, &P);
}

// ---- Sequences 4, 5 and 10: activating extended tasks (cases 6, 7, 8, 9), ECC1/ECC2.

const fn extended_set(
    class: ConformanceClass,
    status: Status,
    non: bool,
    p3: u8,
) -> OsConfig<3, 0, 0, 0, 0> {
    let t1 = TaskConfig::extended("t1", 1).autostart();
    config(
        OsDescription::new(
            [
                if non { t1.non_preemptive() } else { t1 },
                TaskConfig::extended("t2", 2),
                TaskConfig::extended("t3", p3),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

static EXT_NON: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    extended_set(Ecc1, Status::Standard, true, 3),
    extended_set(Ecc1, Status::Extended, true, 3),
    extended_set(Ecc2, Status::Standard, true, 3),
    extended_set(Ecc2, Status::Extended, true, 3),
];
static EXT_FULL: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    extended_set(Ecc1, Status::Standard, false, 3),
    extended_set(Ecc1, Status::Extended, false, 3),
    extended_set(Ecc2, Status::Standard, false, 3),
    extended_set(Ecc2, Status::Extended, false, 3),
];
static EXT_EQUAL: [OsConfig<3, 0, 0, 0, 0>; 2] = [
    extended_set(Ecc2, Status::Standard, false, 2),
    extended_set(Ecc2, Status::Extended, false, 2),
];

/// Sequence 4: a non-preemptive task activates a suspended extended task: it becomes
/// ready with no event set, and runs at `Schedule`.
#[test]
fn tm_seq04_activate_extended_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ret(2, GetEvent(T1), Returned::Events(0)),
            ret(3, GetEvent(T2), Returned::Events(0)),
            ok(4, Schedule),
            ok(6, TerminateTask),
        ],
        &[ok(5, TerminateTask)],
        &[],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&EXT_NON, &P);
}

/// Sequence 5: a higher extended task preempts at once with no event set; a lower one
/// waits.
#[test]
fn tm_seq05_activate_extended_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[ok(1, ActivateTask(T3)), ok(7, TerminateTask)],
        &[
            ret(5, GetEvent(T2), Returned::Events(0)),
            ok(6, TerminateTask),
        ],
        &[
            ret(2, GetEvent(T3), Returned::Events(0)),
            ok(3, ActivateTask(T2)),
            ok(4, TerminateTask),
        ],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&EXT_FULL, &P);
}

/// Sequence 10 (ECC2): an extended task of equal priority does not preempt.
#[test]
fn tm_seq10_activate_extended_equal_priority() {
    static P: Program = Program::tasks(&[
        &[ok(1, ActivateTask(T2)), ok(7, TerminateTask)],
        &[
            ret(2, GetEvent(T2), Returned::Events(0)),
            ok(3, ActivateTask(T3)),
            ok(4, TerminateTask),
        ],
        &[
            ret(5, GetEvent(T3), Returned::Events(0)),
            ok(6, TerminateTask),
        ],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&EXT_EQUAL, &P);
}

// ---- Sequence 6: E_OS_LIMIT for extended tasks (cases 11, 16, 19, 29, 31), extended
// status, ECC1/ECC2.

const fn s06(class: ConformanceClass, non: bool) -> OsConfig<2, 0, 0, 0, 0> {
    let t1 = TaskConfig::extended("t1", 1).autostart();
    config(
        OsDescription::new(
            [
                if non { t1.non_preemptive() } else { t1 },
                TaskConfig::extended("t2", 2),
            ],
            [],
            [],
            [],
        )
        .class(class),
    )
}

static S06_FULL: [OsConfig<2, 0, 0, 0, 0>; 2] = [s06(Ecc1, false), s06(Ecc2, false)];
static S06_NON: [OsConfig<2, 0, 0, 0, 0>; 2] = [s06(Ecc1, true), s06(Ecc2, true)];

/// Sequence 6, full preemption: a ready, running or waiting extended task cannot be
/// activated again, nor chained to.
#[test]
fn tm_seq06_extended_limit_full() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ret(5, GetTaskState(T2), Returned::State(TaskState::Waiting)),
            err(6, ActivateTask(T2), OsError::Limit),
            err(7, ChainTask(T2), OsError::Limit),
            ok(8, SetEvent(T2, E1)),
            ok(11, TerminateTask),
        ],
        &[
            err(2, ActivateTask(T1), OsError::Limit),
            err(3, ActivateTask(T2), OsError::Limit),
            ok(4, WaitEvent(E1)),
            err(9, ChainTask(T1), OsError::Limit),
            ok(10, TerminateTask),
        ],
    ]);
    check_each::<2, 0, 0, 0, 0, 2>(&S06_FULL, &P);
}

/// Sequence 6, non-preemptive caller.
#[test]
fn tm_seq06_extended_limit_non() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, Schedule),
            ret(6, GetTaskState(T2), Returned::State(TaskState::Waiting)),
            err(7, ActivateTask(T2), OsError::Limit),
            err(8, ChainTask(T2), OsError::Limit),
            ok(9, SetEvent(T2, E1)),
            ok(10, Schedule),
            ok(13, TerminateTask),
        ],
        &[
            err(3, ActivateTask(T1), OsError::Limit),
            err(4, ActivateTask(T2), OsError::Limit),
            ok(5, WaitEvent(E1)),
            err(11, ChainTask(T1), OsError::Limit),
            ok(12, TerminateTask),
        ],
    ]);
    check_each::<2, 0, 0, 0, 0, 2>(&S06_NON, &P);
}

// ---- Sequences 7 and 8: multiple activation (cases 5, 12, 13, 14, 17, 18, 30),
// BCC2/ECC2.

const fn multi(class: ConformanceClass, status: Status) -> OsConfig<3, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1)
                    .non_preemptive()
                    .activations(2)
                    .autostart(),
                TaskConfig::basic("t2", 2).activations(2),
                TaskConfig::basic("t3", 3).activations(2),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

static MULTI: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    multi(Bcc2, Status::Standard),
    multi(Bcc2, Status::Extended),
    multi(Ecc2, Status::Standard),
    multi(Ecc2, Status::Extended),
];

/// Sequence 7: activations of a ready task, of the running task itself and a `ChainTask`
/// to a ready task are queued, and each runs once, in order.
#[test]
fn tm_seq07_multiple_activation_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, ActivateTask(T2)),
            ok(3, Schedule),
            ok(6, ActivateTask(T1)),
            ok(7, ActivateTask(T3)),
            ok(8, ChainTask(T3)),
            ok(11, ActivateTask(T1)),
            ok(12, TerminateTask),
            ok(13, TerminateTask),
        ],
        &[ok(4, TerminateTask), ok(5, TerminateTask)],
        &[ok(9, TerminateTask), ok(10, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 6>(&MULTI, &P);
}

const fn s08(class: ConformanceClass) -> OsConfig<3, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 2).activations(2).autostart(),
                TaskConfig::basic("t2", 2).activations(2),
                TaskConfig::basic("t3", 1),
            ],
            [],
            [],
            [],
        )
        .class(class),
    )
}

static S08: [OsConfig<3, 0, 0, 0, 0>; 2] = [s08(Bcc2), s08(Ecc2)];

/// Sequence 8, full preemption: an equal or lower task does not preempt; activations of
/// the running task and of a ready one queue up and run first in, first out.
#[test]
fn tm_seq08_multiple_activation_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, ActivateTask(T3)),
            ok(3, ActivateTask(T1)),
            ok(4, TerminateTask),
            ok(7, TerminateTask),
        ],
        &[
            ok(5, ActivateTask(T2)),
            ok(6, TerminateTask),
            ok(8, TerminateTask),
        ],
        &[ok(9, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 5>(&S08, &P);
}

/// Sequence 9: `GetTaskID`, `GetTaskState` (running, suspended, ready), `ChainTask` to a
/// suspended task and to the caller itself.
#[test]
fn tm_seq09_task_id_state_and_chain() {
    static FULL: Program = Program::tasks(&[
        &[
            ret(1, GetTaskId, Returned::Task(Some(T1))),
            ret(2, GetTaskState(T1), Returned::State(TaskState::Running)),
            ret(3, GetTaskState(T2), Returned::State(TaskState::Suspended)),
            ok(4, ActivateTask(T2)),
            ok(7, ChainTask(T3)),
        ],
        &[
            ret(5, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(6, TerminateTask),
        ],
        &[ok(8, ChainTask(T3)), ok(9, TerminateTask)],
    ]);
    static NON: Program = Program::tasks(&[
        &[
            ret(1, GetTaskId, Returned::Task(Some(T1))),
            ret(2, GetTaskState(T1), Returned::State(TaskState::Running)),
            ret(3, GetTaskState(T2), Returned::State(TaskState::Suspended)),
            ok(4, ActivateTask(T2)),
            ok(5, Schedule),
            ok(8, ChainTask(T3)),
        ],
        &[
            ret(6, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(7, TerminateTask),
        ],
        &[ok(9, ChainTask(T3)), ok(10, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&THREE_FULL, &FULL);
    check_each::<3, 0, 0, 0, 0, 3>(&THREE_NON, &NON);
}

// ---- Sequences 11 and 12: FIFO order within a priority (ECC2 / BCC2, ECC2).

const fn s11(non: bool) -> OsConfig<4, 0, 0, 0, 0> {
    config(OsDescription::new(
        [
            TaskConfig::basic("t1", 1).autostart(),
            TaskConfig::extended("t2", 1),
            task("t3", 1, non),
            TaskConfig::basic("t4", 3),
        ],
        [],
        [],
        [],
    ))
}

static S11_FULL: [OsConfig<4, 0, 0, 0, 0>; 1] = [s11(false)];
static S11_NON: [OsConfig<4, 0, 0, 0, 0>; 1] = [s11(true)];

/// Sequence 11: a task released from waiting is the newest of its priority, and the task
/// the release interrupted (preempted) is the oldest: t3 resumes before t2.
#[test]
fn tm_seq11_released_task_is_the_newest() {
    static FULL: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, ActivateTask(T3)),
            ok(3, TerminateTask),
        ],
        &[ok(4, WaitEvent(E1)), ok(9, TerminateTask)],
        &[ok(5, ActivateTask(T4)), ok(8, TerminateTask)],
        &[ok(6, SetEvent(T2, E1)), ok(7, TerminateTask)],
    ]);
    static NON: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, ActivateTask(T3)),
            ok(3, TerminateTask),
        ],
        &[ok(4, WaitEvent(E1)), ok(10, TerminateTask)],
        &[
            ok(5, ActivateTask(T4)),
            ok(6, Schedule),
            ok(9, TerminateTask),
        ],
        &[ok(7, SetEvent(T2, E1)), ok(8, TerminateTask)],
    ]);
    check_each::<4, 0, 0, 0, 0, 4>(&S11_FULL, &FULL);
    check_each::<4, 0, 0, 0, 0, 4>(&S11_NON, &NON);
}

const fn s12(class: ConformanceClass) -> OsConfig<4, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2).activations(3),
                TaskConfig::basic("t3", 2).activations(3),
                TaskConfig::basic("t4", 3),
            ],
            [],
            [],
            [],
        )
        .class(class),
    )
}

static S12: [OsConfig<4, 0, 0, 0, 0>; 2] = [s12(Bcc2), s12(Ecc2)];

/// Sequence 12: a preempted task is the first of the ready queue of its priority, ahead
/// of the activations queued before the preemption.
#[test]
fn tm_seq12_preempted_task_is_the_oldest() {
    static P: Program = Program::tasks(&[
        &[ok(1, ActivateTask(T2)), ok(9, TerminateTask)],
        &[
            ok(2, ActivateTask(T3)),
            ok(3, ActivateTask(T2)),
            ok(4, ActivateTask(T4)),
            ok(6, TerminateTask),
            ok(8, TerminateTask),
        ],
        &[ok(7, TerminateTask)],
        &[ok(5, TerminateTask)],
    ]);
    check_each::<4, 0, 0, 0, 0, 8>(&S12, &P);
}

// ---- Sequences 13 and 14: the class minima (8 active tasks; 16 active tasks with 8
// events each).

const fn ladder<const N: usize>(
    class: ConformanceClass,
    extended: bool,
) -> OsConfig<N, 0, 0, 0, 0> {
    let mut tasks = [TaskConfig::basic("t", 1); N];
    let mut k = 0;
    while k < N {
        let t = if extended {
            TaskConfig::extended("t", k as u8 + 1)
        } else {
            TaskConfig::basic("t", k as u8 + 1)
        };
        tasks[k] = if k == 0 {
            t.non_preemptive().autostart()
        } else {
            t
        };
        k += 1;
    }
    config(OsDescription::new(tasks, [], [], []).class(class))
}

/// t1's script: activates every other task, clears `events` events, terminates; then the
/// others run from the highest down, each clearing its events and terminating.
const fn ladder_scripts<const N: usize, const S: usize>(events: u16) -> [[Step; S]; N] {
    let mut scripts = [[ok(0, TerminateTask); S]; N];
    let mut seq = 1;
    let mut k = 1;
    while k < N {
        scripts[0][k - 1] = ok(seq, ActivateTask(TaskId(k as u8)));
        seq += 1;
        k += 1;
    }
    // Every task (t1 first, then the highest down) clears its events and ends.
    let mut turn = 0;
    while turn < N {
        let t = if turn == 0 { 0 } else { N - turn };
        let first = if t == 0 { N - 1 } else { 0 };
        let mut e = 0;
        while e < events as usize {
            scripts[t][first + e] = ok(seq, ClearEvent(1 << e));
            seq += 1;
            e += 1;
        }
        scripts[t][first + events as usize] = ok(seq, TerminateTask);
        seq += 1;
        turn += 1;
    }
    scripts
}

static S13: [OsConfig<8, 0, 0, 0, 0>; 4] = [
    ladder(Bcc1, false),
    ladder(Bcc2, false),
    ladder(Ecc1, false),
    ladder(Ecc2, false),
];
static S13_SCRIPTS: [[Step; 8]; 8] = ladder_scripts::<8, 8>(0);
static S13_PROGRAM: Program = Program::tasks(&[
    &S13_SCRIPTS[0],
    S13_SCRIPTS[1].split_at(1).0,
    S13_SCRIPTS[2].split_at(1).0,
    S13_SCRIPTS[3].split_at(1).0,
    S13_SCRIPTS[4].split_at(1).0,
    S13_SCRIPTS[5].split_at(1).0,
    S13_SCRIPTS[6].split_at(1).0,
    S13_SCRIPTS[7].split_at(1).0,
]);

/// Sequence 13: eight tasks active at once (every class's minimum), run from the highest
/// down once the non-preemptive first one ends.
#[test]
fn tm_seq13_eight_active_tasks() {
    check_each::<8, 0, 0, 0, 0, 8>(&S13, &S13_PROGRAM);
}

static S14: [OsConfig<16, 0, 0, 0, 0>; 2] = [ladder(Ecc1, true), ladder(Ecc2, true)];
static S14_SCRIPTS: [[Step; 24]; 16] = ladder_scripts::<16, 24>(8);
static S14_PROGRAM: Program = Program::tasks(&[
    &S14_SCRIPTS[0],
    S14_SCRIPTS[1].split_at(9).0,
    S14_SCRIPTS[2].split_at(9).0,
    S14_SCRIPTS[3].split_at(9).0,
    S14_SCRIPTS[4].split_at(9).0,
    S14_SCRIPTS[5].split_at(9).0,
    S14_SCRIPTS[6].split_at(9).0,
    S14_SCRIPTS[7].split_at(9).0,
    S14_SCRIPTS[8].split_at(9).0,
    S14_SCRIPTS[9].split_at(9).0,
    S14_SCRIPTS[10].split_at(9).0,
    S14_SCRIPTS[11].split_at(9).0,
    S14_SCRIPTS[12].split_at(9).0,
    S14_SCRIPTS[13].split_at(9).0,
    S14_SCRIPTS[14].split_at(9).0,
    S14_SCRIPTS[15].split_at(9).0,
]);

/// Sequence 14 (ECC1, ECC2): sixteen extended tasks active at once, each with eight
/// events.
#[test]
fn tm_seq14_sixteen_tasks_eight_events() {
    check_each::<16, 0, 0, 0, 0, 16>(&S14, &S14_PROGRAM);
}

// ---- Sequence 15: ActivateTask and GetTaskState from a category-2 ISR (cases 39-56).

static S15: [OsConfig<2, 0, 0, 0, 1>; 4] = [
    s01(Bcc1, false),
    s01(Bcc2, false),
    s01(Ecc1, false),
    s01(Ecc2, false),
];

/// Sequence 15: in an ISR, `ActivateTask` of a higher task does not switch: the switch
/// happens when the ISR returns; errors as at task level.
#[test]
fn tm_seq15_services_from_an_isr() {
    static P: Program = Program::tasks(&[
        &[raise(1, ISR1), ok(11, TerminateTask)],
        &[ok(10, TerminateTask)],
    ])
    .isrs(&[&[
        err(2, GetTaskState(INVALID), OsError::Id),
        ret(3, GetTaskState(T1), Returned::State(TaskState::Running)),
        err(4, ActivateTask(INVALID), OsError::Id),
        ok(5, ActivateTask(T2)),
        ret(6, GetTaskState(T2), Returned::State(TaskState::Ready)),
        err(7, ActivateTask(T2), OsError::Limit),
        err(8, ActivateTask(T1), OsError::Limit),
        end(9),
    ]]);
    check_each::<2, 0, 0, 0, 1, 2>(&S15, &P);
}
