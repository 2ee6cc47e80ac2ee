//! OSEK OS conformance, resource management (the OSEK/VDX OS test plan's sequences for
//! `GetResource` and `ReleaseResource` with the immediate priority ceiling protocol, nested
//! resources, `RES_SCHEDULER`, and resources in category-2 ISRs, in the conformance classes
//! and preemption policies each sequence names). Each test runs one sequence with the
//! executive in `osek/exec.rs`: the steps' numbers are the one order of execution the
//! standard allows.

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    ConformanceClass, IsrConfig, IsrId, OsConfig, OsDescription, OsError, ResourceId, Returned,
    ServiceCall::*, Status, TaskConfig, TaskId, TaskState, RES_SCHEDULER,
};
use exec::{check_each, config, end, err, ok, raise, ret, Program};
use ConformanceClass::{Bcc1, Bcc2, Ecc1, Ecc2};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const T3: TaskId = TaskId(2);
const ISR1: IsrId = IsrId(0);
const ISR2: IsrId = IsrId(1);
const ISR3: IsrId = IsrId(2);
const INVALID: ResourceId = ResourceId(40);

/// The same task, non-preemptive if `non`.
const fn policy(t: TaskConfig, non: bool) -> TaskConfig {
    if non {
        t.non_preemptive()
    } else {
        t
    }
}

// ---- Sequence 1: error codes and nesting (test cases 1, 2, 3, 4, 5, 7, 8, 9, 10, 11, 12),
// extended status, every class; t1 (1) autostart using ResourceA and Resource1..6 (indices
// 0..6, so every ceiling is 1), t2 (2) using none.

const RES: [ResourceId; 7] = [
    ResourceId(0),
    ResourceId(1),
    ResourceId(2),
    ResourceId(3),
    ResourceId(4),
    ResourceId(5),
    ResourceId(6),
];

const fn s01(class: ConformanceClass, non: bool) -> OsConfig<2, 7, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart().uses(0x7F), non),
                policy(TaskConfig::basic("t2", 2), non),
            ],
            [],
            [],
            [],
        )
        .class(class),
    )
}

static S01_FULL: [OsConfig<2, 7, 0, 0, 0>; 4] = [
    s01(Bcc1, false),
    s01(Bcc2, false),
    s01(Ecc1, false),
    s01(Ecc2, false),
];
static S01_NON: [OsConfig<2, 7, 0, 0, 0>; 4] = [
    s01(Bcc1, true),
    s01(Bcc2, true),
    s01(Ecc1, true),
    s01(Ecc2, true),
];

/// Sequence 1, full preemption: `E_OS_ID` (cases 1, 7); six nested resources released in
/// LIFO order, `E_OS_NOFUNC` out of order (9); `E_OS_ACCESS` for an occupied resource (3)
/// and for a caller above the ceiling (2, 10); `E_OS_NOFUNC` for a resource not held,
/// `RES_SCHEDULER` included (8). t2 preempts at its activation.
#[test]
fn rm_seq01_errors_full() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(RES[0])),
            ok(2, ReleaseResource(RES[0])),
            err(3, GetResource(INVALID), OsError::Id),
            ok(4, GetResource(RES[1])),
            ok(5, GetResource(RES[2])),
            ok(6, GetResource(RES[3])),
            ok(7, GetResource(RES[4])),
            ok(8, GetResource(RES[5])),
            ok(9, GetResource(RES[6])),
            ok(10, ReleaseResource(RES[6])),
            ok(11, ReleaseResource(RES[5])),
            ok(12, ReleaseResource(RES[4])),
            ok(13, ReleaseResource(RES[3])),
            err(14, ReleaseResource(RES[1]), OsError::NoFunc),
            ok(15, ReleaseResource(RES[2])),
            err(16, GetResource(RES[1]), OsError::Access),
            ok(17, ReleaseResource(RES[1])),
            ok(18, ActivateTask(T2)),
            err(22, ReleaseResource(INVALID), OsError::Id),
            err(23, ReleaseResource(RES[1]), OsError::NoFunc),
            err(24, ReleaseResource(RES_SCHEDULER), OsError::NoFunc),
            ok(25, TerminateTask),
        ],
        &[
            err(19, GetResource(RES[2]), OsError::Access),
            err(20, ReleaseResource(RES[1]), OsError::Access),
            ok(21, TerminateTask),
        ],
    ]);
    check_each::<2, 7, 0, 0, 0, 2>(&S01_FULL, &P);
}

/// Sequence 1, non-preemptive tasks: the same, t2 running at t1's `Schedule`.
#[test]
fn rm_seq01_errors_non() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(RES[0])),
            ok(2, ReleaseResource(RES[0])),
            err(3, GetResource(INVALID), OsError::Id),
            ok(4, GetResource(RES[1])),
            ok(5, GetResource(RES[2])),
            ok(6, GetResource(RES[3])),
            ok(7, GetResource(RES[4])),
            ok(8, GetResource(RES[5])),
            ok(9, GetResource(RES[6])),
            ok(10, ReleaseResource(RES[6])),
            ok(11, ReleaseResource(RES[5])),
            ok(12, ReleaseResource(RES[4])),
            ok(13, ReleaseResource(RES[3])),
            err(14, ReleaseResource(RES[1]), OsError::NoFunc),
            ok(15, ReleaseResource(RES[2])),
            err(16, GetResource(RES[1]), OsError::Access),
            ok(17, ReleaseResource(RES[1])),
            ok(18, ActivateTask(T2)),
            ok(19, Schedule),
            err(23, ReleaseResource(INVALID), OsError::Id),
            err(24, ReleaseResource(RES[1]), OsError::NoFunc),
            err(25, ReleaseResource(RES_SCHEDULER), OsError::NoFunc),
            ok(26, TerminateTask),
        ],
        &[
            err(20, GetResource(RES[2]), OsError::Access),
            err(21, ReleaseResource(RES[1]), OsError::Access),
            ok(22, TerminateTask),
        ],
    ]);
    check_each::<2, 7, 0, 0, 0, 2>(&S01_NON, &P);
}

// ---- Sequences 2 and 3: the priority ceiling protocol (cases 4, 5, 11, 12), every class;
// t1 (1) autostart using Resource1, t2 (2), t3 (4), t4 (3) using Resource1 and never
// activated: Resource1's ceiling (3) lies between t2 and t3.

const R1: ResourceId = ResourceId(0);

const fn ceiling_set(
    class: ConformanceClass,
    status: Status,
    non: bool,
) -> OsConfig<4, 1, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart().uses(0b1), non),
                TaskConfig::basic("t2", 2),
                TaskConfig::basic("t3", 4),
                TaskConfig::basic("t4", 3).uses(0b1),
            ],
            [],
            [],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S02: [OsConfig<4, 1, 0, 0, 0>; 4] = [
    ceiling_set(Bcc1, Status::Extended, true),
    ceiling_set(Bcc2, Status::Extended, true),
    ceiling_set(Ecc1, Status::Extended, true),
    ceiling_set(Ecc2, Status::Extended, true),
];
static S03: [OsConfig<4, 1, 0, 0, 0>; 8] = [
    ceiling_set(Bcc1, Status::Standard, false),
    ceiling_set(Bcc1, Status::Extended, false),
    ceiling_set(Bcc2, Status::Standard, false),
    ceiling_set(Bcc2, Status::Extended, false),
    ceiling_set(Ecc1, Status::Standard, false),
    ceiling_set(Ecc1, Status::Extended, false),
    ceiling_set(Ecc2, Status::Standard, false),
    ceiling_set(Ecc2, Status::Extended, false),
];

/// Sequence 2 (extended status), non-preemptive t1: holding Resource1 it may not call
/// `Schedule` (`E_OS_RESOURCE`), and no activated task runs (case 4); releasing it does not
/// preempt t1 either (case 11): t3 and t2 run at the next `Schedule`, highest first.
#[test]
fn rm_seq02_ceiling_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(R1)),
            ok(2, ActivateTask(T2)),
            err(3, Schedule, OsError::Resource),
            ok(4, ActivateTask(T3)),
            err(5, Schedule, OsError::Resource),
            ok(6, ReleaseResource(R1)),
            ret(7, GetTaskState(T3), Returned::State(TaskState::Ready)),
            ok(8, Schedule),
            ok(11, TerminateTask),
        ],
        &[ok(10, TerminateTask)],
        &[ok(9, TerminateTask)],
        &[],
    ]);
    check_each::<4, 1, 0, 0, 0, 4>(&S02, &P);
}

/// Sequence 3 (standard and extended status), full preemption: t1 holding Resource1 runs
/// at its ceiling, so t2 (between t1 and the ceiling) does not preempt but t3 (above it)
/// does (case 5); t3's end resumes t1, and `ReleaseResource` lets t2 preempt at once
/// (case 12).
#[test]
fn rm_seq03_ceiling_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(R1)),
            ok(2, ActivateTask(T2)),
            ret(3, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(4, ActivateTask(T3)),
            ok(7, ReleaseResource(R1)),
            ok(9, TerminateTask),
        ],
        &[ok(8, TerminateTask)],
        &[
            ret(5, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(6, TerminateTask),
        ],
        &[],
    ]);
    check_each::<4, 1, 0, 0, 0, 4>(&S03, &P);
}

// ---- Sequence 4: RES_SCHEDULER (cases 6, 13, 14), extended status, every class; t1 (1)
// autostart, t2 (2), t3 (3).

const fn s04(class: ConformanceClass, non: bool) -> OsConfig<3, 0, 0, 0, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart(), non),
                TaskConfig::basic("t2", 2),
                TaskConfig::basic("t3", 3),
            ],
            [],
            [],
            [],
        )
        .class(class),
    )
}

static S04_FULL: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    s04(Bcc1, false),
    s04(Bcc2, false),
    s04(Ecc1, false),
    s04(Ecc2, false),
];
static S04_NON: [OsConfig<3, 0, 0, 0, 0>; 4] = [
    s04(Bcc1, true),
    s04(Bcc2, true),
    s04(Ecc1, true),
    s04(Ecc2, true),
];

/// Sequence 4, full preemption: holding `RES_SCHEDULER` (case 6) t1 is preempted by no
/// task, and `Schedule` is refused; releasing it lets t3 then t2 run at once (case 14).
#[test]
fn rm_seq04_res_scheduler_full() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(RES_SCHEDULER)),
            ok(2, ActivateTask(T2)),
            err(3, Schedule, OsError::Resource),
            ok(4, ActivateTask(T3)),
            err(5, Schedule, OsError::Resource),
            ok(6, ReleaseResource(RES_SCHEDULER)),
            ok(9, TerminateTask),
        ],
        &[ok(8, TerminateTask)],
        &[ok(7, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&S04_FULL, &P);
}

/// Sequence 4, non-preemptive t1: releasing `RES_SCHEDULER` does not preempt it (case 13);
/// t3 then t2 run at its `Schedule`.
#[test]
fn rm_seq04_res_scheduler_non() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, GetResource(RES_SCHEDULER)),
            ok(2, ActivateTask(T2)),
            err(3, Schedule, OsError::Resource),
            ok(4, ActivateTask(T3)),
            err(5, Schedule, OsError::Resource),
            ok(6, ReleaseResource(RES_SCHEDULER)),
            ret(7, GetTaskState(T3), Returned::State(TaskState::Ready)),
            ok(8, Schedule),
            ok(11, TerminateTask),
        ],
        &[ok(10, TerminateTask)],
        &[ok(9, TerminateTask)],
    ]);
    check_each::<3, 0, 0, 0, 0, 3>(&S04_NON, &P);
}

// ---- Sequence 5: resources in category-2 ISRs (cases 15 to 25), extended status, full
// preemption, every class; t1 (1) autostart using Resource3, isr1 (1) using Resource1 and
// Resource2, isr2 (2) using Resource1, isr3 (3): Resource1's ceiling is isr2's level,
// Resource2's isr1's, Resource3's t1's.

const RES1: ResourceId = ResourceId(0);
const RES2: ResourceId = ResourceId(1);
const RES3: ResourceId = ResourceId(2);

const fn s05(class: ConformanceClass) -> OsConfig<1, 3, 0, 0, 3> {
    config(
        OsDescription::new(
            [TaskConfig::basic("t1", 1).autostart().uses(0b100)],
            [],
            [],
            [
                IsrConfig::cat2("isr1", 1).uses(0b011),
                IsrConfig::cat2("isr2", 2).uses(0b001),
                IsrConfig::cat2("isr3", 3),
            ],
        )
        .class(class),
    )
}

static S05: [OsConfig<1, 3, 0, 0, 3>; 4] = [s05(Bcc1), s05(Bcc2), s05(Ecc1), s05(Ecc2)];

/// Sequence 5: isr1 gets `E_OS_ID` (cases 15, 20), `E_OS_ACCESS` for a resource whose
/// ceiling is below it (16), an occupied one (17) and `RES_SCHEDULER` (18, 24); holding
/// Resource1 it runs at isr2's level, so isr2 stays pending while isr3 (above the ceiling)
/// interrupts at once (19) and may not release Resource1 (23); out of order release is
/// `E_OS_NOFUNC` (22), and the release of Resource1 lets isr2 in at once (25); a resource
/// not held is `E_OS_NOFUNC` (21).
#[test]
fn rm_seq05_isr_resources() {
    static P: Program = Program::tasks(&[&[raise(1, ISR1), ok(22, TerminateTask)]]).isrs(&[
        &[
            err(2, GetResource(INVALID), OsError::Id),
            err(3, GetResource(RES3), OsError::Access),
            ok(4, GetResource(RES1)),
            err(5, GetResource(RES1), OsError::Access),
            err(6, GetResource(RES_SCHEDULER), OsError::Access),
            ok(7, GetResource(RES2)),
            raise(8, ISR2),
            raise(9, ISR3),
            err(12, ReleaseResource(RES1), OsError::NoFunc),
            ok(13, ReleaseResource(RES2)),
            ok(14, ReleaseResource(RES1)),
            err(18, ReleaseResource(INVALID), OsError::Id),
            err(19, ReleaseResource(RES1), OsError::NoFunc),
            err(20, ReleaseResource(RES_SCHEDULER), OsError::Access),
            end(21),
        ],
        &[
            ok(15, GetResource(RES1)),
            ok(16, ReleaseResource(RES1)),
            end(17),
        ],
        &[err(10, ReleaseResource(RES1), OsError::Access), end(11)],
    ]);
    check_each::<1, 3, 0, 0, 3, 1>(&S05, &P);
}

// ---- Sequence 6 (not in the plan): a resource a task shares with an ISR, extended status,
// every class, both policies; t1 (1) autostart and isr1 (1) using Resource1, t2 (2), isr2
// (2): Resource1's ceiling is isr1's level.

const fn s06(class: ConformanceClass, non: bool) -> OsConfig<2, 1, 0, 0, 2> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart().uses(0b1), non),
                TaskConfig::basic("t2", 2),
            ],
            [],
            [],
            [
                IsrConfig::cat2("isr1", 1).uses(0b1),
                IsrConfig::cat2("isr2", 2),
            ],
        )
        .class(class),
    )
}

static S06_FULL: [OsConfig<2, 1, 0, 0, 2>; 4] = [
    s06(Bcc1, false),
    s06(Bcc2, false),
    s06(Ecc1, false),
    s06(Ecc2, false),
];
static S06_NON: [OsConfig<2, 1, 0, 0, 2>; 4] = [
    s06(Bcc1, true),
    s06(Bcc2, true),
    s06(Ecc1, true),
    s06(Ecc2, true),
];

/// Sequence 6: t1 holding the resource it shares with isr1 masks isr1: its request stays
/// pending while isr2 (above the ceiling) is taken at once and may not take the resource
/// (`E_OS_ACCESS`); `ReleaseResource` lets isr1 in at once; isr1 takes the resource and
/// activates t2, which runs when isr1 returns under full preemption, and when t1 ends under
/// non-preemption.
#[test]
fn rm_seq06_resource_shared_with_isr() {
    static ISRS: [&[exec::Step]; 2] = [
        &[
            ret(7, GetTaskId, Returned::Task(Some(T1))),
            ok(8, GetResource(R1)),
            ok(9, ActivateTask(T2)),
            ok(10, ReleaseResource(R1)),
            end(11),
        ],
        &[err(4, GetResource(R1), OsError::Access), end(5)],
    ];
    static FULL: Program = Program::tasks(&[
        &[
            ok(1, GetResource(R1)),
            raise(2, ISR1),
            raise(3, ISR2),
            ok(6, ReleaseResource(R1)),
            ok(13, TerminateTask),
        ],
        &[ok(12, TerminateTask)],
    ])
    .isrs(&ISRS);
    static NON: Program = Program::tasks(&[
        &[
            ok(1, GetResource(R1)),
            raise(2, ISR1),
            raise(3, ISR2),
            ok(6, ReleaseResource(R1)),
            ret(12, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(13, TerminateTask),
        ],
        &[ok(14, TerminateTask)],
    ])
    .isrs(&ISRS);
    check_each::<2, 1, 0, 0, 2, 2>(&S06_FULL, &FULL);
    check_each::<2, 1, 0, 0, 2, 2>(&S06_NON, &NON);
}
