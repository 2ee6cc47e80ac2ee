//! OSEK OS conformance, event mechanism (the OSEK/VDX OS test plan's sequences for
//! `SetEvent`, `ClearEvent`, `GetEvent` and `WaitEvent`, from tasks and from category-2
//! ISRs, in the conformance classes ECC1 and ECC2, the preemption policies and the statuses
//! each sequence names). Each test runs one sequence with the executive in `osek/exec.rs`:
//! the steps' numbers are the one order of execution the standard allows.

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    ConformanceClass, EventMask, IsrConfig, IsrId, OsConfig, OsDescription, OsError, ResourceId,
    Returned, ServiceCall::*, Status, TaskConfig, TaskId, TaskState,
};
use exec::{check_each, config, end, err, ok, raise, ret, Program, Step};
use ConformanceClass::{Ecc1, Ecc2};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const T3: TaskId = TaskId(2);
const T4: TaskId = TaskId(3);
const T5: TaskId = TaskId(4);
const INVALID: TaskId = TaskId(60);
const ISR1: IsrId = IsrId(0);
const R1: ResourceId = ResourceId(0);
const E1: EventMask = 0b001;
const E2: EventMask = 0b010;
const E3: EventMask = 0b100;

/// The same task, non-preemptive if `non`.
const fn policy(t: TaskConfig, non: bool) -> TaskConfig {
    if non {
        t.non_preemptive()
    } else {
        t
    }
}

// ---- Sequence 1: error codes (test cases 1, 2, 3, 11, 12, 14, 15, 16, 20, 21, 22),
// ECC1/ECC2, both policies; t1 basic (1) autostart, t2 extended (2) using Resource1, isr1.

const fn s01(class: ConformanceClass, status: Status, non: bool) -> OsConfig<2, 1, 0, 0, 1> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart(), non),
                policy(TaskConfig::extended("t2", 2).uses(0b1), non),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class)
        .status(status),
    )
}

static S01: [OsConfig<2, 1, 0, 0, 1>; 4] = [
    s01(Ecc1, Status::Extended, false),
    s01(Ecc1, Status::Extended, true),
    s01(Ecc2, Status::Extended, false),
    s01(Ecc2, Status::Extended, true),
];
static S01_STANDARD: [OsConfig<2, 1, 0, 0, 1>; 4] = [
    s01(Ecc1, Status::Standard, false),
    s01(Ecc1, Status::Standard, true),
    s01(Ecc2, Status::Standard, false),
    s01(Ecc2, Status::Standard, true),
];

/// isr1 may neither clear nor wait for events (cases 12, 22), in both statuses.
static S01_ISR: [Step; 3] = [
    err(6, ClearEvent(E1), OsError::CallLevel),
    err(7, WaitEvent(E1), OsError::CallLevel),
    end(8),
];

/// t2, chained to by t1: an extended task holding a resource may not wait (case 21).
static S01_T2: [Step; 4] = [
    ok(14, GetResource(R1)),
    err(15, WaitEvent(E1), OsError::Resource),
    ok(16, ReleaseResource(R1)),
    ok(17, TerminateTask),
];

/// Sequence 1 (extended status): `E_OS_ID` for an invalid task, `E_OS_ACCESS` for events of
/// a basic task, `E_OS_STATE` for a suspended one, `E_OS_CALLEVEL` from an ISR,
/// `E_OS_RESOURCE` for a task that waits holding a resource. The same script in the fully
/// and the non-preemptive variant (no step depends on preemption).
#[test]
fn em_seq01_errors() {
    static P: Program = Program::tasks(&[
        &[
            err(1, SetEvent(INVALID, E1), OsError::Id),
            err(2, SetEvent(T1, E1), OsError::Access),
            err(3, SetEvent(T2, E1), OsError::State),
            err(4, ClearEvent(E1), OsError::Access),
            raise(5, ISR1),
            err(9, GetEvent(INVALID), OsError::Id),
            err(10, GetEvent(T1), OsError::Access),
            err(11, GetEvent(T2), OsError::State),
            err(12, WaitEvent(E1), OsError::Access),
            ok(13, ChainTask(T2)),
        ],
        &S01_T2,
    ])
    .isrs(&[&S01_ISR]);
    check_each::<2, 1, 0, 0, 1, 2>(&S01, &P);
}

/// Sequence 1 in standard status (the plan runs it in extended status only): the checks
/// that only extended status makes are left out and the call is carried out (the kernel's
/// documented choice, `Status` in config.rs): `SetEvent`/`ClearEvent`/`GetEvent` on the basic
/// task succeed, and `GetEvent` of a suspended task gives its (empty) events. The checks kept
/// in both statuses stay: `E_OS_ID`, `E_OS_STATE` of `SetEvent`, `E_OS_ACCESS` of
/// `WaitEvent` in a basic task, `E_OS_CALLEVEL`, `E_OS_RESOURCE`.
#[test]
fn em_seq01_errors_standard_status() {
    static P: Program = Program::tasks(&[
        &[
            err(1, SetEvent(INVALID, E1), OsError::Id),
            ok(2, SetEvent(T1, E1)),
            err(3, SetEvent(T2, E1), OsError::State),
            ok(4, ClearEvent(E1)),
            raise(5, ISR1),
            err(9, GetEvent(INVALID), OsError::Id),
            ret(10, GetEvent(T1), Returned::Events(0)),
            ret(11, GetEvent(T2), Returned::Events(0)),
            err(12, WaitEvent(E1), OsError::Access),
            ok(13, ChainTask(T2)),
        ],
        &S01_T2,
    ])
    .isrs(&[&S01_ISR]);
    check_each::<2, 1, 0, 0, 1, 2>(&S01_STANDARD, &P);
}

// ---- Sequence 2: events of ready, running and waiting tasks, WaitEvent blocking and
// returning at once (cases 9/10, 13, 17, 18, 19, 23, 24), ECC1/ECC2, standard and extended
// status; t1 extended (1), t2 extended (2) autostart.

const fn s02(class: ConformanceClass, status: Status, non: bool) -> OsConfig<2, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::extended("t1", 1), non),
                policy(TaskConfig::extended("t2", 2).autostart(), non),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

const fn s02_all(non: bool) -> [OsConfig<2, 0, 0, 0, 0>; 4] {
    [
        s02(Ecc1, Status::Standard, non),
        s02(Ecc1, Status::Extended, non),
        s02(Ecc2, Status::Standard, non),
        s02(Ecc2, Status::Extended, non),
    ]
}

static S02_FULL: [OsConfig<2, 0, 0, 0, 0>; 4] = s02_all(false);
static S02_NON: [OsConfig<2, 0, 0, 0, 0>; 4] = s02_all(true);

/// t2's first steps: events set on a ready task (cases 9/10, 18), then it waits (case 23).
const S02_T2_START: [Step; 4] = [
    ok(1, ActivateTask(T1)),
    ok(2, SetEvent(T1, E1)),
    ret(3, GetEvent(T1), Returned::Events(E1)),
    ok(4, WaitEvent(E2)),
];

/// t1's first steps: `WaitEvent` on an event already set returns at once (case 24),
/// `GetEvent` of a waiting task (19) and of the running one (17), `ClearEvent` (13).
const S02_T1_START: [Step; 8] = [
    ok(5, WaitEvent(E1)),
    ret(6, GetEvent(T2), Returned::Events(0)),
    ok(7, SetEvent(T1, E1)),
    ret(8, GetEvent(T1), Returned::Events(E1)),
    ok(9, WaitEvent(E1)),
    ok(10, ClearEvent(E1)),
    ret(11, GetEvent(T1), Returned::Events(0)),
    ok(12, SetEvent(T2, E2)),
];

/// Sequence 2, full preemption: t2 waits and t1 runs; t1's `SetEvent` for the event t2
/// waits for makes t2 preempt it at once.
#[test]
fn em_seq02_events_and_wait_full() {
    static T1_SCRIPT: [Step; 9] = {
        let s = S02_T1_START;
        [
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5],
            s[6],
            s[7],
            ok(14, TerminateTask),
        ]
    };
    static T2_SCRIPT: [Step; 5] = {
        let s = S02_T2_START;
        [s[0], s[1], s[2], s[3], ok(13, TerminateTask)]
    };
    static P: Program = Program::tasks(&[&T1_SCRIPT, &T2_SCRIPT]);
    check_each::<2, 0, 0, 0, 0, 2>(&S02_FULL, &P);
}

/// Sequence 2, non-preemptive tasks: the released t2 stays ready until t1 calls `Schedule`.
#[test]
fn em_seq02_events_and_wait_non() {
    static T1_SCRIPT: [Step; 11] = {
        let s = S02_T1_START;
        [
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5],
            s[6],
            s[7],
            ret(13, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(14, Schedule),
            ok(16, TerminateTask),
        ]
    };
    static T2_SCRIPT: [Step; 5] = {
        let s = S02_T2_START;
        [s[0], s[1], s[2], s[3], ok(15, TerminateTask)]
    };
    static P: Program = Program::tasks(&[&T1_SCRIPT, &T2_SCRIPT]);
    check_each::<2, 0, 0, 0, 0, 2>(&S02_NON, &P);
}

// ---- Sequence 3: SetEvent from a non-preemptive task (cases 4, 5, 9), ECC1/ECC2,
// standard and extended status; t1 basic (1) autostart, t2 extended (3) autostart, t3
// extended (2), all non-preemptive.

const fn s03(class: ConformanceClass, status: Status) -> OsConfig<3, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).non_preemptive().autostart(),
                TaskConfig::extended("t2", 3).non_preemptive().autostart(),
                TaskConfig::extended("t3", 2).non_preemptive(),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S03: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    s03(Ecc1, Status::Standard),
    s03(Ecc1, Status::Extended),
    s03(Ecc2, Status::Standard),
    s03(Ecc2, Status::Extended),
];

/// Sequence 3: an event t2 does not wait for leaves it waiting (case 5); one it waits for
/// makes it ready without preempting the non-preemptive caller (case 4); events set on a
/// ready task (case 9) and on a task just activated (ready and new: case 9 again) are kept,
/// so t3's `WaitEvent` returns at once.
#[test]
fn em_seq03_set_event_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ret(2, GetTaskState(T2), Returned::State(TaskState::Waiting)),
            ret(3, GetEvent(T2), Returned::Events(0)),
            ok(4, SetEvent(T2, E2)),
            ret(5, GetTaskState(T2), Returned::State(TaskState::Waiting)),
            ret(6, GetEvent(T2), Returned::Events(E2)),
            ok(7, SetEvent(T2, E1)),
            ret(8, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ret(9, GetEvent(T2), Returned::Events(E1 | E2)),
            ok(10, SetEvent(T2, E3)),
            ret(11, GetEvent(T2), Returned::Events(E1 | E2 | E3)),
            ok(12, ActivateTask(T3)),
            ok(13, SetEvent(T3, E3)),
            ret(14, GetEvent(T3), Returned::Events(E3)),
            ok(15, TerminateTask),
        ],
        &[ok(1, WaitEvent(E1)), ok(16, TerminateTask)],
        &[ok(17, WaitEvent(E3)), ok(18, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&S03, &P);
}

// ---- Sequence 4: SetEvent from a preemptive task (cases 6, 7, 8, 10), ECC1/ECC2,
// standard and extended status; t1 extended (2) autostart, t2 extended (3) autostart, t3
// extended (1), t4 basic (4, or 3 like t2 in the ECC2 variant).

const fn s04(class: ConformanceClass, status: Status, p4: u8) -> OsConfig<4, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::extended("t1", 2).autostart(),
                TaskConfig::extended("t2", 3).autostart(),
                TaskConfig::extended("t3", 1),
                TaskConfig::basic("t4", p4),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S04: [OsConfig<4, 0, 0, 0, 0>; 6] = [
    s04(Ecc1, Status::Standard, 4),
    s04(Ecc1, Status::Extended, 4),
    s04(Ecc2, Status::Standard, 4),
    s04(Ecc2, Status::Extended, 4),
    s04(Ecc2, Status::Standard, 3),
    s04(Ecc2, Status::Extended, 3),
];

/// Sequence 4, full preemption: an event t2 does not wait for leaves it waiting (case 8);
/// events set on a ready task (t3 just activated, t1 preempted: case 10) do not preempt;
/// the event t2 waits for makes the higher t2 preempt at once (case 6); set by a task of
/// higher or equal priority (t4; equal in the ECC2 variant) it makes t2 ready without
/// preemption (case 7).
#[test]
fn em_seq04_set_event_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(2, SetEvent(T2, E2)),
            ret(3, GetTaskState(T2), Returned::State(TaskState::Waiting)),
            ret(4, GetEvent(T2), Returned::Events(E2)),
            ok(5, ActivateTask(T3)),
            ret(6, GetTaskState(T3), Returned::State(TaskState::Ready)),
            ok(7, SetEvent(T3, E3)),
            ret(8, GetEvent(T3), Returned::Events(E3)),
            ok(9, SetEvent(T2, E1)),
            ok(14, ActivateTask(T4)),
            ret(19, GetEvent(T1), Returned::Events(E1)),
            ok(20, TerminateTask),
        ],
        &[
            ok(1, WaitEvent(E1)),
            ok(10, ClearEvent(E1)),
            ok(11, SetEvent(T1, E1)),
            ret(12, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(13, WaitEvent(E1)),
            ok(18, TerminateTask),
        ],
        &[ok(21, WaitEvent(E3)), ok(22, TerminateTask)],
        &[
            ok(15, SetEvent(T2, E1)),
            ret(16, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(17, TerminateTask),
        ],
    ]);
    check_each::<4, 0, 0, 0, 0, 4>(&S04, &P);
}

// ---- Sequences 5 and 6: SetEvent and GetEvent from a category-2 ISR (cases 25 to 40),
// extended status, ECC1/ECC2; t1 extended (5) autostart, t2 extended (3, or 4 like t3 in
// the ECC2 variant) autostart, t3 basic (4), t4 extended (1) never activated, t5 extended
// (2), isr1.

const fn s05(class: ConformanceClass, non: bool, p2: u8) -> OsConfig<5, 0, 0, 0, 1> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::extended("t1", 5).autostart(), non),
                policy(TaskConfig::extended("t2", p2).autostart(), non),
                policy(TaskConfig::basic("t3", 4), non),
                policy(TaskConfig::extended("t4", 1), non),
                policy(TaskConfig::extended("t5", 2), non),
            ],
            [],
            [],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class),
    )
}

static S05: [OsConfig<5, 0, 0, 0, 1>; 2] = [s05(Ecc1, true, 3), s05(Ecc2, true, 3)];
static S06: [OsConfig<5, 0, 0, 0, 1>; 3] = [
    s05(Ecc1, false, 3),
    s05(Ecc2, false, 3),
    s05(Ecc2, false, 4),
];

/// isr1, entered while t3 runs, t1 and t2 wait for Event1, t5 is ready and t4 suspended:
/// `GetEvent` (cases 36 to 40) and `SetEvent` (25, 26, 27), an event t1 does not wait for
/// (30/33), the one it waits for (t1 above t3: 28/31), the one t2 waits for (t2 below or
/// equal to t3: 29/32), an event of the ready t5 (34/35). No task switch inside the ISR.
static S05_ISR: [Step; 16] = [
    err(6, GetEvent(INVALID), OsError::Id),
    err(7, GetEvent(T3), OsError::Access),
    err(8, GetEvent(T4), OsError::State),
    ret(9, GetEvent(T5), Returned::Events(0)),
    ret(10, GetEvent(T2), Returned::Events(0)),
    err(11, SetEvent(INVALID, E1), OsError::Id),
    err(12, SetEvent(T3, E1), OsError::Access),
    err(13, SetEvent(T4, E1), OsError::State),
    ok(14, SetEvent(T1, E2)),
    ret(15, GetTaskState(T1), Returned::State(TaskState::Waiting)),
    ok(16, SetEvent(T1, E1)),
    ret(17, GetTaskState(T1), Returned::State(TaskState::Ready)),
    ok(18, SetEvent(T2, E1)),
    ok(19, SetEvent(T5, E1)),
    ret(20, GetEvent(T5), Returned::Events(E1)),
    end(21),
];

/// Sequence 5, non-preemptive tasks: after isr1 the non-preemptive t3 keeps running although
/// the released t1 is above it; then t1, t2 and t5 run by priority, and t5's `WaitEvent`
/// returns at once on the event isr1 set.
#[test]
fn em_seq05_isr_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, WaitEvent(E1)),
            ret(24, GetEvent(T1), Returned::Events(E1 | E2)),
            ok(25, TerminateTask),
        ],
        &[
            ok(2, ActivateTask(T3)),
            ok(3, ActivateTask(T5)),
            ok(4, WaitEvent(E1)),
            ok(26, TerminateTask),
        ],
        &[
            raise(5, ISR1),
            ret(22, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(23, TerminateTask),
        ],
        &[],
        &[ok(27, WaitEvent(E1)), ok(28, TerminateTask)],
    ])
    .isrs(&[&S05_ISR]);
    check_each::<5, 0, 0, 0, 1, 5>(&S05, &P);
}

/// Sequence 6, full preemption: the released t1 preempts t3 when isr1 returns; then the
/// preempted t3 (the oldest of its priority, ahead of t2 released in the ISR in the ECC2
/// variant where they share it), t2 and t5.
#[test]
fn em_seq06_isr_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, WaitEvent(E1)),
            ret(22, GetEvent(T1), Returned::Events(E1 | E2)),
            ok(23, TerminateTask),
        ],
        &[
            ok(2, ActivateTask(T5)),
            ok(3, WaitEvent(E1)),
            ok(25, TerminateTask),
        ],
        &[raise(5, ISR1), ok(24, TerminateTask)],
        &[],
        &[
            ok(4, ActivateTask(T3)),
            ok(26, WaitEvent(E1)),
            ok(27, TerminateTask),
        ],
    ])
    .isrs(&[&S05_ISR]);
    check_each::<5, 0, 0, 0, 1, 5>(&S06, &P);
}
