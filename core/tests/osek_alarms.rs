//! OSEK OS conformance, alarms (the OSEK/VDX OS test plan's sequences for `GetAlarmBase`,
//! `GetAlarm`, `SetRelAlarm`, `SetAbsAlarm`, `CancelAlarm` and the three expiry actions, from
//! tasks and from category-2 ISRs, in the conformance classes, preemption policies, statuses
//! and dialects each sequence names). Counters advance only through `IncrementCounter`,
//! called by a task or by a category-2 ISR the task raises (the plan's "wait alarm
//! expires"). Each test runs one sequence with the executive in `osek/exec.rs`: the steps'
//! numbers are the one order of execution the standard allows.

#[path = "osek/exec.rs"]
mod exec;

use cw_core::os::{
    AlarmAction, AlarmBase, AlarmConfig, AlarmId, ConformanceClass, CounterConfig, CounterId,
    Dialect, EventMask, HookSet, IsrConfig, IsrId, OsConfig, OsDescription, OsError, Returned,
    ServiceCall, ServiceCall::*, Status, TaskConfig, TaskId, TaskState, TickType,
};
use exec::{check_each, config, end, err, hook, ok, raise, ret, HookCall, Program, Step};
use ConformanceClass::{Bcc1, Bcc2, Ecc1, Ecc2};

const T1: TaskId = TaskId(0);
const T2: TaskId = TaskId(1);
const T3: TaskId = TaskId(2);
const T4: TaskId = TaskId(3);
const A1: AlarmId = AlarmId(0);
const A2: AlarmId = AlarmId(1);
const A3: AlarmId = AlarmId(2);
const A4: AlarmId = AlarmId(3);
const A5: AlarmId = AlarmId(4);
const INVALID: AlarmId = AlarmId(60);
const C0: CounterId = CounterId(0);
const ISR1: IsrId = IsrId(0);
const E1: EventMask = 0b01;
const E2: EventMask = 0b10;
/// `-1` as a `TickType`.
const MINUS_ONE: TickType = TickType::MAX;

/// The plan's counter: `MAXALLOWEDVALUE` 16, `TICKSPERBASE` 10, `MINCYCLE` 1.
const COUNTER: CounterConfig = CounterConfig {
    max_allowed_value: 16,
    ticks_per_base: 10,
    min_cycle: 1,
};
const BASE: AlarmBase = AlarmBase {
    max_allowed_value: 16,
    ticks_per_base: 10,
    min_cycle: 1,
};
/// The same with `MINCYCLE` 2, so that `mincycle - 1` (1) is not a valid cycle as 0 is.
const COUNTER_MIN2: CounterConfig = CounterConfig {
    min_cycle: 2,
    ..COUNTER
};
const BASE_MIN2: AlarmBase = AlarmBase {
    min_cycle: 2,
    ..BASE
};

/// An alarm on counter 0, not armed at start.
const fn alarm(name: &'static str, action: AlarmAction) -> AlarmConfig {
    AlarmConfig::new(name, C0, action)
}

/// `SetRelAlarm(alarm, increment, cycle)`.
const fn rel(alarm: AlarmId, increment: TickType, cycle: TickType) -> ServiceCall {
    SetRelAlarm {
        alarm,
        increment,
        cycle,
    }
}

/// `SetAbsAlarm(alarm, start, cycle)`.
const fn abs(alarm: AlarmId, start: TickType, cycle: TickType) -> ServiceCall {
    SetAbsAlarm {
        alarm,
        start,
        cycle,
    }
}

/// The same task, non-preemptive if `non`.
const fn policy(t: TaskConfig, non: bool) -> TaskConfig {
    if non {
        t.non_preemptive()
    } else {
        t
    }
}

// ---- Sequence 1: E_OS_ID and E_OS_VALUE (test cases 1, 3, 8, 12, 13, 14, 15, 19, 23, 24,
// 25, 26, 30), extended status, every class, both policies; t1 (1) autostart, t2 (2),
// Alarm1 activating t2 on a counter of mincycle 2.

const fn s01(class: ConformanceClass, non: bool) -> OsConfig<2, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart(), non),
                TaskConfig::basic("t2", 2),
            ],
            [COUNTER_MIN2],
            [alarm("Alarm1", AlarmAction::ActivateTask(T2))],
            [],
        )
        .class(class),
    )
}

static S01: [OsConfig<2, 0, 1, 1, 0>; 8] = [
    s01(Bcc1, false),
    s01(Bcc1, true),
    s01(Bcc2, false),
    s01(Bcc2, true),
    s01(Ecc1, false),
    s01(Ecc1, true),
    s01(Ecc2, false),
    s01(Ecc2, true),
];

/// Sequence 1: invalid alarm ids, increments and starts below 0 (`-1` wraps to the largest
/// `TickType`) and above `maxallowedvalue`, cycles below `mincycle` and above
/// `maxallowedvalue`. Increment 0 with a bad cycle is refused for the cycle (the OSEK
/// dialect accepts increment 0). None of the refused calls armed the alarm.
#[test]
fn al_seq01_id_and_value_errors() {
    static P: Program = Program::tasks(&[
        &[
            err(1, GetAlarmBase(INVALID), OsError::Id),
            err(2, GetAlarm(INVALID), OsError::Id),
            ret(3, GetAlarmBase(A1), Returned::Base(BASE_MIN2)),
            err(4, rel(INVALID, 0, 0), OsError::Id),
            err(5, rel(A1, MINUS_ONE, 0), OsError::Value),
            err(6, rel(A1, 17, 0), OsError::Value),
            err(7, rel(A1, 0, 1), OsError::Value),
            err(8, rel(A1, 0, 17), OsError::Value),
            err(9, abs(INVALID, 0, 0), OsError::Id),
            err(10, abs(A1, MINUS_ONE, 0), OsError::Value),
            err(11, abs(A1, 17, 0), OsError::Value),
            err(12, abs(A1, 0, 1), OsError::Value),
            err(13, abs(A1, 0, 17), OsError::Value),
            err(14, CancelAlarm(INVALID), OsError::Id),
            err(15, GetAlarm(A1), OsError::NoFunc),
            ok(16, TerminateTask),
        ],
        &[],
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S01, &P);
}

// ---- Sequence 2: an alarm activating a task (cases 2, 4, 5, 9, 16, 20, 27, 31, 32),
// standard and extended status, every class, both policies; t1 (1) autostart, t2 (2),
// Alarm1 activating t2, isr1 counting.

const fn s02(class: ConformanceClass, status: Status, non: bool) -> OsConfig<2, 0, 1, 1, 1> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart(), non),
                TaskConfig::basic("t2", 2),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::ActivateTask(T2))],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class)
        .status(status),
    )
}

const fn s02_all(non: bool) -> [OsConfig<2, 0, 1, 1, 1>; 8] {
    [
        s02(Bcc1, Status::Standard, non),
        s02(Bcc1, Status::Extended, non),
        s02(Bcc2, Status::Standard, non),
        s02(Bcc2, Status::Extended, non),
        s02(Ecc1, Status::Standard, non),
        s02(Ecc1, Status::Extended, non),
        s02(Ecc2, Status::Standard, non),
        s02(Ecc2, Status::Extended, non),
    ]
}

static S02_FULL: [OsConfig<2, 0, 1, 1, 1>; 8] = s02_all(false);
static S02_NON: [OsConfig<2, 0, 1, 1, 1>; 8] = s02_all(true);

/// Sequence 2, full preemption: `GetAlarmBase`; `GetAlarm` and `CancelAlarm` of an unused
/// alarm (`E_OS_NOFUNC`); a cyclic `SetAbsAlarm` (`E_OS_STATE` when set again) activates t2
/// every 2 ticks, and t2 preempts t1 when isr1 returns; `CancelAlarm`; a single
/// `SetRelAlarm` (`E_OS_STATE` again) with `GetAlarm` counting down, unused once expired.
#[test]
fn al_seq02_activate_task_full() {
    static P: Program = Program::tasks(&[
        &[
            ret(1, GetAlarmBase(A1), Returned::Base(BASE)),
            err(2, GetAlarm(A1), OsError::NoFunc),
            err(3, CancelAlarm(A1), OsError::NoFunc),
            ok(4, abs(A1, 2, 2)),
            err(5, abs(A1, 3, 0), OsError::State),
            ret(6, GetAlarm(A1), Returned::Ticks(2)),
            raise(7, ISR1),
            ret(10, GetAlarm(A1), Returned::Ticks(1)),
            raise(11, ISR1),
            ret(15, GetAlarm(A1), Returned::Ticks(2)),
            raise(16, ISR1),
            raise(19, ISR1),
            ok(23, CancelAlarm(A1)),
            ok(24, rel(A1, 2, 0)),
            err(25, rel(A1, 3, 0), OsError::State),
            ret(26, GetAlarm(A1), Returned::Ticks(2)),
            raise(27, ISR1),
            raise(30, ISR1),
            err(34, GetAlarm(A1), OsError::NoFunc),
            ok(35, TerminateTask),
        ],
        &[
            ok(14, TerminateTask),
            ok(22, TerminateTask),
            ok(33, TerminateTask),
        ],
    ])
    .isrs(&[&[
        ok(8, IncrementCounter(C0)),
        end(9),
        ok(12, IncrementCounter(C0)),
        end(13),
        ok(17, IncrementCounter(C0)),
        end(18),
        ok(20, IncrementCounter(C0)),
        end(21),
        ok(28, IncrementCounter(C0)),
        end(29),
        ok(31, IncrementCounter(C0)),
        end(32),
    ]]);
    check_each::<2, 0, 1, 1, 1, 2>(&S02_FULL, &P);
}

/// Sequence 2, non-preemptive t1: the activated t2 stays ready after isr1 returns and runs
/// at t1's `Schedule`.
#[test]
fn al_seq02_activate_task_non() {
    static P: Program = Program::tasks(&[
        &[
            ret(1, GetAlarmBase(A1), Returned::Base(BASE)),
            err(2, GetAlarm(A1), OsError::NoFunc),
            err(3, CancelAlarm(A1), OsError::NoFunc),
            ok(4, abs(A1, 2, 2)),
            err(5, abs(A1, 3, 0), OsError::State),
            ret(6, GetAlarm(A1), Returned::Ticks(2)),
            raise(7, ISR1),
            raise(10, ISR1),
            ret(13, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(14, Schedule),
            ret(16, GetAlarm(A1), Returned::Ticks(2)),
            raise(17, ISR1),
            raise(20, ISR1),
            ok(23, Schedule),
            ok(25, CancelAlarm(A1)),
            ok(26, rel(A1, 2, 0)),
            err(27, rel(A1, 3, 0), OsError::State),
            ret(28, GetAlarm(A1), Returned::Ticks(2)),
            raise(29, ISR1),
            raise(32, ISR1),
            ok(35, Schedule),
            err(37, GetAlarm(A1), OsError::NoFunc),
            ok(38, TerminateTask),
        ],
        &[
            ok(15, TerminateTask),
            ok(24, TerminateTask),
            ok(36, TerminateTask),
        ],
    ])
    .isrs(&[&[
        ok(8, IncrementCounter(C0)),
        end(9),
        ok(11, IncrementCounter(C0)),
        end(12),
        ok(18, IncrementCounter(C0)),
        end(19),
        ok(21, IncrementCounter(C0)),
        end(22),
        ok(30, IncrementCounter(C0)),
        end(31),
        ok(33, IncrementCounter(C0)),
        end(34),
    ]]);
    check_each::<2, 0, 1, 1, 1, 2>(&S02_NON, &P);
}

// ---- Sequence 3: an alarm setting an event (cases 6, 10, 17, 21, 28, 33, 40/42),
// standard and extended status, ECC1/ECC2, both policies; t1 (1) autostart, t2 extended
// (2) autostart, Alarm1 setting Event2 of t2; t1 counts.

const fn s03(class: ConformanceClass, status: Status, non: bool) -> OsConfig<2, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 1).autostart(), non),
                policy(TaskConfig::extended("t2", 2).autostart(), non),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::SetEvent(T2, E2))],
            [],
        )
        .class(class)
        .status(status),
    )
}

const fn s03_all(non: bool) -> [OsConfig<2, 0, 1, 1, 0>; 4] {
    [
        s03(Ecc1, Status::Standard, non),
        s03(Ecc1, Status::Extended, non),
        s03(Ecc2, Status::Standard, non),
        s03(Ecc2, Status::Extended, non),
    ]
}

static S03_FULL: [OsConfig<2, 0, 1, 1, 0>; 4] = s03_all(false);
static S03_NON: [OsConfig<2, 0, 1, 1, 0>; 4] = s03_all(true);

/// Sequence 3, full preemption: t2 waits for Event2; the cyclic alarm's expiry inside t1's
/// `IncrementCounter` releases t2, which preempts t1 there (twice); then a single
/// `SetRelAlarm` does it once more.
#[test]
fn al_seq03_set_event_full() {
    static P: Program = Program::tasks(&[
        &[
            ok(2, abs(A1, 2, 2)),
            err(3, abs(A1, 3, 0), OsError::State),
            ret(4, GetAlarm(A1), Returned::Ticks(2)),
            ok(5, IncrementCounter(C0)),
            ok(6, IncrementCounter(C0)),
            ok(9, IncrementCounter(C0)),
            ok(10, IncrementCounter(C0)),
            ok(13, CancelAlarm(A1)),
            ok(14, rel(A1, 2, 0)),
            err(15, rel(A1, 3, 0), OsError::State),
            ret(16, GetAlarm(A1), Returned::Ticks(2)),
            ok(17, IncrementCounter(C0)),
            ok(18, IncrementCounter(C0)),
            ok(20, TerminateTask),
        ],
        &[
            ok(1, WaitEvent(E2)),
            ok(7, ClearEvent(E2)),
            ok(8, WaitEvent(E2)),
            ok(11, ClearEvent(E2)),
            ok(12, WaitEvent(E2)),
            ok(19, TerminateTask),
        ],
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S03_FULL, &P);
}

/// Sequence 3, non-preemptive tasks: the released t2 stays ready until t1's `Schedule`.
#[test]
fn al_seq03_set_event_non() {
    static P: Program = Program::tasks(&[
        &[
            ok(2, abs(A1, 2, 2)),
            err(3, abs(A1, 3, 0), OsError::State),
            ret(4, GetAlarm(A1), Returned::Ticks(2)),
            ok(5, IncrementCounter(C0)),
            ok(6, IncrementCounter(C0)),
            ret(7, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(8, Schedule),
            ok(11, IncrementCounter(C0)),
            ok(12, IncrementCounter(C0)),
            ok(13, Schedule),
            ok(16, CancelAlarm(A1)),
            ok(17, rel(A1, 2, 0)),
            err(18, rel(A1, 3, 0), OsError::State),
            ret(19, GetAlarm(A1), Returned::Ticks(2)),
            ok(20, IncrementCounter(C0)),
            ok(21, IncrementCounter(C0)),
            ok(22, Schedule),
            ok(24, TerminateTask),
        ],
        &[
            ok(1, WaitEvent(E2)),
            ok(9, ClearEvent(E2)),
            ok(10, WaitEvent(E2)),
            ok(14, ClearEvent(E2)),
            ok(15, WaitEvent(E2)),
            ok(23, TerminateTask),
        ],
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S03_NON, &P);
}

// ---- Sequence 4: an alarm callback (cases 7, 11, 18, 22, 29, 34, 43), standard and
// extended status, every class, both policies; t1 (1) autostart, Alarm1 calling callback
// 0; t1 counts.

const fn s04(class: ConformanceClass, status: Status, non: bool) -> OsConfig<1, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [policy(TaskConfig::basic("t1", 1).autostart(), non)],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::Callback(0))],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S04: [OsConfig<1, 0, 1, 1, 0>; 16] = [
    s04(Bcc1, Status::Standard, false),
    s04(Bcc1, Status::Extended, false),
    s04(Bcc2, Status::Standard, false),
    s04(Bcc2, Status::Extended, false),
    s04(Ecc1, Status::Standard, false),
    s04(Ecc1, Status::Extended, false),
    s04(Ecc2, Status::Standard, false),
    s04(Ecc2, Status::Extended, false),
    s04(Bcc1, Status::Standard, true),
    s04(Bcc1, Status::Extended, true),
    s04(Bcc2, Status::Standard, true),
    s04(Bcc2, Status::Extended, true),
    s04(Ecc1, Status::Standard, true),
    s04(Ecc1, Status::Extended, true),
    s04(Ecc2, Status::Standard, true),
    s04(Ecc2, Status::Extended, true),
];

/// Sequence 4: the callback runs inside the `IncrementCounter` at whose tick the alarm
/// expires, at each expiry of the cyclic `SetAbsAlarm` and once for the single
/// `SetRelAlarm`; it may suspend and resume all interrupts; `E_OS_STATE` for an armed alarm,
/// `GetAlarm` counting down, `CancelAlarm`.
#[test]
fn al_seq04_callback() {
    static P: Program = Program::tasks(&[&[
        ok(1, abs(A1, 2, 2)),
        err(2, abs(A1, 3, 0), OsError::State),
        ret(3, GetAlarm(A1), Returned::Ticks(2)),
        ok(4, IncrementCounter(C0)),
        ok(5, IncrementCounter(C0)),
        ret(10, GetAlarm(A1), Returned::Ticks(2)),
        ok(11, IncrementCounter(C0)),
        ok(12, IncrementCounter(C0)),
        ok(15, CancelAlarm(A1)),
        ok(16, rel(A1, 2, 0)),
        err(17, rel(A1, 3, 0), OsError::State),
        ret(18, GetAlarm(A1), Returned::Ticks(2)),
        ok(19, IncrementCounter(C0)),
        ok(20, IncrementCounter(C0)),
        err(23, GetAlarm(A1), OsError::NoFunc),
        ok(24, TerminateTask),
    ]])
    .callbacks(&[
        hook(6, HookCall::Callback(0)),
        ok(7, SuspendAllInterrupts),
        ok(8, ResumeAllInterrupts),
        end(9),
        hook(13, HookCall::Callback(0)),
        end(14),
        hook(21, HookCall::Callback(0)),
        end(22),
    ]);
    check_each::<1, 0, 1, 1, 0, 1>(&S04, &P);
}

// ---- Sequence 5: expiry activating a task while the running task is non-preemptive
// (case 36), standard and extended status, every class; t1 (1) non-preemptive autostart,
// t2 (2), Alarm1 activating t2 on a counter of maxallowedvalue 3; t1 counts. The plan arms
// the alarm with increment 0, which the dialects treat differently.

const COUNTER3: CounterConfig = CounterConfig {
    max_allowed_value: 3,
    ticks_per_base: 1,
    min_cycle: 1,
};

const fn s05(class: ConformanceClass, status: Status, dialect: Dialect) -> OsConfig<2, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).non_preemptive().autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [COUNTER3],
            [alarm("Alarm1", AlarmAction::ActivateTask(T2))],
            [],
        )
        .class(class)
        .status(status)
        .dialect(dialect),
    )
}

const fn s05_all(dialect: Dialect) -> [OsConfig<2, 0, 1, 1, 0>; 8] {
    [
        s05(Bcc1, Status::Standard, dialect),
        s05(Bcc1, Status::Extended, dialect),
        s05(Bcc2, Status::Standard, dialect),
        s05(Bcc2, Status::Extended, dialect),
        s05(Ecc1, Status::Standard, dialect),
        s05(Ecc1, Status::Extended, dialect),
        s05(Ecc2, Status::Standard, dialect),
        s05(Ecc2, Status::Extended, dialect),
    ]
}

static S05_OSEK: [OsConfig<2, 0, 1, 1, 0>; 8] = s05_all(Dialect::Osek);
static S05_AUTOSAR: [OsConfig<2, 0, 1, 1, 0>; 8] = s05_all(Dialect::Autosar);

/// Sequence 5, OSEK dialect: `SetRelAlarm` with increment 0 arms a full counter revolution
/// (`maxallowedvalue + 1` = 4 ticks, the kernel's documented choice where OSEK leaves it to
/// the implementation); at expiry t2 becomes ready without preempting the non-preemptive t1.
/// `SetAbsAlarm` at the counter's current value also waits a full revolution.
#[test]
fn al_seq05_expiry_non_preemptive_osek() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, rel(A1, 0, 0)),
            ret(2, GetAlarm(A1), Returned::Ticks(4)),
            ok(3, IncrementCounter(C0)),
            ok(4, IncrementCounter(C0)),
            ok(5, IncrementCounter(C0)),
            ret(6, GetAlarm(A1), Returned::Ticks(1)),
            ret(7, GetTaskState(T2), Returned::State(TaskState::Suspended)),
            ok(8, IncrementCounter(C0)),
            ret(9, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ret(10, GetCounterValue(C0), Returned::Ticks(0)),
            ok(11, abs(A1, 0, 0)),
            ret(12, GetAlarm(A1), Returned::Ticks(4)),
            ok(13, CancelAlarm(A1)),
            ok(14, TerminateTask),
        ],
        &[ok(15, TerminateTask)],
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S05_OSEK, &P);
}

/// Sequence 5, AUTOSAR dialect: increment 0 is `E_OS_VALUE` in both statuses
/// (SWS_Os_00304) and arms nothing; armed with increment 1, the expiry makes t2 ready
/// without preempting t1. `SetAbsAlarm` at the current value waits a full revolution.
#[test]
fn al_seq05_expiry_non_preemptive_autosar() {
    static P: Program = Program::tasks(&[
        &[
            err(1, rel(A1, 0, 0), OsError::Value),
            err(2, GetAlarm(A1), OsError::NoFunc),
            ok(3, rel(A1, 1, 0)),
            ok(4, IncrementCounter(C0)),
            ret(5, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(6, abs(A1, 1, 0)),
            ret(7, GetAlarm(A1), Returned::Ticks(4)),
            ok(8, CancelAlarm(A1)),
            ok(9, TerminateTask),
        ],
        &[ok(10, TerminateTask)],
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S05_AUTOSAR, &P);
}

// ---- Sequence 6: expiry activating a task while the running task is preemptive (cases
// 37, 38), standard and extended status, every class; t1 (1) autostart, t2 (2), t3 (3),
// Alarm1 activating t2; the running task counts.

const fn s06(class: ConformanceClass, status: Status) -> OsConfig<3, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
                TaskConfig::basic("t3", 3),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::ActivateTask(T2))],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S06: [OsConfig<3, 0, 1, 1, 0>; 8] = [
    s06(Bcc1, Status::Standard),
    s06(Bcc1, Status::Extended),
    s06(Bcc2, Status::Standard),
    s06(Bcc2, Status::Extended),
    s06(Ecc1, Status::Standard),
    s06(Ecc1, Status::Extended),
    s06(Ecc2, Status::Standard),
    s06(Ecc2, Status::Extended),
];

/// Sequence 6: t2, above t1, preempts it inside the `IncrementCounter` of the expiry (case
/// 37); below t3 it only becomes ready (case 38), and runs when t3 ends.
#[test]
fn al_seq06_expiry_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, rel(A1, 2, 0)),
            ok(2, IncrementCounter(C0)),
            ok(3, IncrementCounter(C0)),
            ok(6, ChainTask(T3)),
        ],
        &[
            ret(4, GetTaskState(T1), Returned::State(TaskState::Ready)),
            ok(5, TerminateTask),
            ok(12, TerminateTask),
        ],
        &[
            ok(7, rel(A1, 2, 0)),
            ok(8, IncrementCounter(C0)),
            ok(9, IncrementCounter(C0)),
            ret(10, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(11, TerminateTask),
        ],
    ]);
    check_each::<3, 0, 1, 1, 0, 3>(&S06, &P);
}

// ---- Sequence 7: expiry setting an event while the running task is non-preemptive
// (cases 39, 40), standard and extended status, ECC1/ECC2; t1 (1) non-preemptive
// autostart, t2 extended (2), Alarm1 setting Event1 of t2, isr1 counting.

const fn s07(class: ConformanceClass, status: Status) -> OsConfig<2, 0, 1, 1, 1> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).non_preemptive().autostart(),
                TaskConfig::extended("t2", 2),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::SetEvent(T2, E1))],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class)
        .status(status),
    )
}

static S07: [OsConfig<2, 0, 1, 1, 1>; 4] = [
    s07(Ecc1, Status::Standard),
    s07(Ecc1, Status::Extended),
    s07(Ecc2, Status::Standard),
    s07(Ecc2, Status::Extended),
];

/// Sequence 7: the event is set on the ready t2 (case 39); later t2 waits for it, and the
/// expiry makes t2 ready without preempting t1, neither in isr1 nor when it returns (40).
#[test]
fn al_seq07_set_event_non_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, ActivateTask(T2)),
            ok(2, rel(A1, 2, 0)),
            raise(3, ISR1),
            raise(6, ISR1),
            ret(9, GetEvent(T2), Returned::Events(E1)),
            ok(10, Schedule),
            ok(13, rel(A1, 2, 0)),
            raise(14, ISR1),
            raise(17, ISR1),
            ret(20, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(21, TerminateTask),
        ],
        &[
            ok(11, ClearEvent(E1)),
            ok(12, WaitEvent(E1)),
            ok(22, TerminateTask),
        ],
    ])
    .isrs(&[&[
        ok(4, IncrementCounter(C0)),
        end(5),
        ok(7, IncrementCounter(C0)),
        end(8),
        ok(15, IncrementCounter(C0)),
        end(16),
        ok(18, IncrementCounter(C0)),
        end(19),
    ]]);
    check_each::<2, 0, 1, 1, 1, 2>(&S07, &P);
}

// ---- Sequence 8: expiry setting an event while the running task is preemptive (cases
// 41, 42), standard and extended status, ECC1/ECC2; t1 (1) autostart, t2 extended (2)
// autostart, t3 (3), t4 (4), Alarm1 setting Event2 of t2; the running task counts.

const fn s08(class: ConformanceClass, status: Status) -> OsConfig<4, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::extended("t2", 2).autostart(),
                TaskConfig::basic("t3", 3),
                TaskConfig::basic("t4", 4),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::SetEvent(T2, E2))],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S08: [OsConfig<4, 0, 1, 1, 0>; 4] = [
    s08(Ecc1, Status::Standard),
    s08(Ecc1, Status::Extended),
    s08(Ecc2, Status::Standard),
    s08(Ecc2, Status::Extended),
];

/// Sequence 8: expiring in t3 (above t2), the event releases the waiting t2 without
/// preemption; expiring in t4 while t2 does not wait, the event is only set (case 41);
/// expiring in t1 (below t2) while t2 waits, t2 preempts t1 inside its `IncrementCounter`
/// (case 42, the plan's owner "waiting for this event").
#[test]
fn al_seq08_set_event_full_preemptive() {
    static P: Program = Program::tasks(&[
        &[
            ok(2, ActivateTask(T3)),
            ok(18, IncrementCounter(C0)),
            ok(20, TerminateTask),
        ],
        &[
            ok(1, WaitEvent(E2)),
            ok(8, ClearEvent(E2)),
            ok(9, ActivateTask(T4)),
            ok(15, ClearEvent(E2)),
            ok(16, rel(A1, 1, 0)),
            ok(17, WaitEvent(E2)),
            ok(19, TerminateTask),
        ],
        &[
            ok(3, rel(A1, 2, 0)),
            ok(4, IncrementCounter(C0)),
            ok(5, IncrementCounter(C0)),
            ret(6, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(7, TerminateTask),
        ],
        &[
            ok(10, rel(A1, 2, 0)),
            ok(11, IncrementCounter(C0)),
            ok(12, IncrementCounter(C0)),
            ret(13, GetEvent(T2), Returned::Events(E2)),
            ok(14, TerminateTask),
        ],
    ]);
    check_each::<4, 0, 1, 1, 0, 4>(&S08, &P);
}

// ---- Sequence 9: the alarm services from a category-2 ISR (cases 1 to 34), extended
// status, ECC1/ECC2, both policies for t1; t1 (2) autostart, t2 (4), t3 (1), t4 extended
// (3) autostart; Alarm1 activating t2, Alarm2 activating t3, Alarm3 and Alarm4 setting
// Event1 and Event2 of t4, Alarm5 calling callback 0, on a counter of mincycle 2; isr1
// counts itself. The plan's alarms per action and kind of setting are folded into these
// five.

const fn s09(class: ConformanceClass, non: bool) -> OsConfig<4, 0, 1, 5, 1> {
    config(
        OsDescription::new(
            [
                policy(TaskConfig::basic("t1", 2).autostart(), non),
                TaskConfig::basic("t2", 4),
                TaskConfig::basic("t3", 1),
                TaskConfig::extended("t4", 3).autostart(),
            ],
            [COUNTER_MIN2],
            [
                alarm("Alarm1", AlarmAction::ActivateTask(T2)),
                alarm("Alarm2", AlarmAction::ActivateTask(T3)),
                alarm("Alarm3", AlarmAction::SetEvent(T4, E1)),
                alarm("Alarm4", AlarmAction::SetEvent(T4, E2)),
                alarm("Alarm5", AlarmAction::Callback(0)),
            ],
            [IsrConfig::cat2("isr1", 1)],
        )
        .class(class),
    )
}

static S09_FULL: [OsConfig<4, 0, 1, 5, 1>; 2] = [s09(Ecc1, false), s09(Ecc2, false)];
static S09_NON: [OsConfig<4, 0, 1, 5, 1>; 2] = [s09(Ecc1, true), s09(Ecc2, true)];

/// isr1's one run: every error of sequence 1 and the unused-alarm `E_OS_NOFUNC`s; then, per
/// action, a relative and an absolute setting (`E_OS_STATE` when set again, `GetAlarm`),
/// two ticks of `IncrementCounter` to its expiry, and `CancelAlarm`. The activated tasks
/// and the released t4 only become ready: nothing switches inside the ISR.
static S09_ISR: [Step; 56] = [
    err(3, GetAlarmBase(INVALID), OsError::Id),
    ret(4, GetAlarmBase(A1), Returned::Base(BASE_MIN2)),
    err(5, GetAlarm(INVALID), OsError::Id),
    err(6, GetAlarm(A1), OsError::NoFunc),
    err(7, rel(INVALID, 0, 0), OsError::Id),
    err(8, rel(A1, MINUS_ONE, 0), OsError::Value),
    err(9, rel(A1, 17, 0), OsError::Value),
    err(10, rel(A1, 0, 1), OsError::Value),
    err(11, rel(A1, 0, 17), OsError::Value),
    err(12, abs(INVALID, 0, 0), OsError::Id),
    err(13, abs(A1, MINUS_ONE, 0), OsError::Value),
    err(14, abs(A1, 17, 0), OsError::Value),
    err(15, abs(A1, 0, 1), OsError::Value),
    err(16, abs(A1, 0, 17), OsError::Value),
    err(17, CancelAlarm(INVALID), OsError::Id),
    err(18, CancelAlarm(A1), OsError::NoFunc),
    // Activating a task, relative and cyclic (counter 0 -> 2).
    ok(19, rel(A1, 2, 2)),
    err(20, rel(A1, 2, 2), OsError::State),
    ret(21, GetAlarm(A1), Returned::Ticks(2)),
    ok(22, IncrementCounter(C0)),
    ok(23, IncrementCounter(C0)),
    ret(24, GetTaskState(T2), Returned::State(TaskState::Ready)),
    ret(25, GetAlarm(A1), Returned::Ticks(2)),
    ok(26, CancelAlarm(A1)),
    // Activating a task, absolute (counter 2 -> 4).
    ok(27, abs(A2, 4, 2)),
    err(28, abs(A2, 4, 2), OsError::State),
    ret(29, GetAlarm(A2), Returned::Ticks(2)),
    ok(30, IncrementCounter(C0)),
    ok(31, IncrementCounter(C0)),
    ret(32, GetTaskState(T3), Returned::State(TaskState::Ready)),
    ok(33, CancelAlarm(A2)),
    // Setting an event, relative (counter 4 -> 6): the waiting t4 becomes ready.
    ok(34, rel(A3, 2, 2)),
    err(35, rel(A3, 2, 2), OsError::State),
    ret(36, GetAlarm(A3), Returned::Ticks(2)),
    ok(37, IncrementCounter(C0)),
    ok(38, IncrementCounter(C0)),
    ret(39, GetTaskState(T4), Returned::State(TaskState::Ready)),
    ok(40, CancelAlarm(A3)),
    // Setting an event, absolute (counter 6 -> 8), on the ready t4.
    ok(41, abs(A4, 8, 2)),
    err(42, abs(A4, 8, 2), OsError::State),
    ok(43, IncrementCounter(C0)),
    ok(44, IncrementCounter(C0)),
    ret(45, GetEvent(T4), Returned::Events(E1 | E2)),
    ok(46, CancelAlarm(A4)),
    // A callback, relative (counter 8 -> 10).
    ok(47, rel(A5, 2, 2)),
    err(48, rel(A5, 2, 2), OsError::State),
    ret(49, GetAlarm(A5), Returned::Ticks(2)),
    ok(50, IncrementCounter(C0)),
    ok(51, IncrementCounter(C0)),
    ok(54, CancelAlarm(A5)),
    // A callback, absolute and single (counter 10 -> 12).
    ok(55, abs(A5, 12, 0)),
    err(56, abs(A5, 12, 0), OsError::State),
    ok(57, IncrementCounter(C0)),
    ok(58, IncrementCounter(C0)),
    err(61, GetAlarm(A5), OsError::NoFunc),
    end(62),
];

/// The callback's two runs inside isr1.
static S09_CALLBACK: [Step; 4] = [
    hook(52, HookCall::Callback(0)),
    end(53),
    hook(59, HookCall::Callback(0)),
    end(60),
];

/// Sequence 9, full preemption: when isr1 returns, the ready tasks run by priority: t2,
/// t4, the preempted t1, t3.
#[test]
fn al_seq09_services_from_isr_full() {
    static P: Program = Program::tasks(&[
        &[raise(2, ISR1), ok(65, TerminateTask)],
        &[ok(63, TerminateTask)],
        &[ok(66, TerminateTask)],
        &[ok(1, WaitEvent(E1)), ok(64, TerminateTask)],
    ])
    .isrs(&[&S09_ISR])
    .callbacks(&S09_CALLBACK);
    check_each::<4, 0, 1, 5, 1, 4>(&S09_FULL, &P);
}

/// Sequence 9, non-preemptive t1: it ends before the tasks made ready in isr1 run.
#[test]
fn al_seq09_services_from_isr_non() {
    static P: Program = Program::tasks(&[
        &[raise(2, ISR1), ok(63, TerminateTask)],
        &[ok(64, TerminateTask)],
        &[ok(66, TerminateTask)],
        &[ok(1, WaitEvent(E1)), ok(65, TerminateTask)],
    ])
    .isrs(&[&S09_ISR])
    .callbacks(&S09_CALLBACK);
    check_each::<4, 0, 1, 5, 1, 4>(&S09_NON, &P);
}

// ---- Sequence 10: the services an alarm callback may call, standard and extended status,
// every class, full preemption, both dialects; t1 (1) autostart, t2 (2), Alarm1 calling
// callback 0; t1 counts.

const fn s10(class: ConformanceClass, status: Status, dialect: Dialect) -> OsConfig<2, 0, 1, 1, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [COUNTER],
            [alarm("Alarm1", AlarmAction::Callback(0))],
            [],
        )
        .class(class)
        .status(status)
        .dialect(dialect),
    )
}

const fn s10_all(dialect: Dialect) -> [OsConfig<2, 0, 1, 1, 0>; 8] {
    [
        s10(Bcc1, Status::Standard, dialect),
        s10(Bcc1, Status::Extended, dialect),
        s10(Bcc2, Status::Standard, dialect),
        s10(Bcc2, Status::Extended, dialect),
        s10(Ecc1, Status::Standard, dialect),
        s10(Ecc1, Status::Extended, dialect),
        s10(Ecc2, Status::Standard, dialect),
        s10(Ecc2, Status::Extended, dialect),
    ]
}

static S10_OSEK: [OsConfig<2, 0, 1, 1, 0>; 8] = s10_all(Dialect::Osek);
static S10_AUTOSAR: [OsConfig<2, 0, 1, 1, 0>; 8] = s10_all(Dialect::Autosar);

/// t1's script, the same in both dialects: the callback activates nothing.
static S10_T1: [Step; 5] = [
    ok(1, rel(A1, 2, 0)),
    ok(2, IncrementCounter(C0)),
    ok(3, IncrementCounter(C0)),
    ret(12, GetTaskState(T2), Returned::State(TaskState::Suspended)),
    ok(13, TerminateTask),
];

/// Sequence 10, OSEK dialect: in a callback `ActivateTask` (and any other OS service, e.g.
/// `GetTaskID`) is `E_OS_CALLEVEL`; of the interrupt services only `SuspendAllInterrupts`
/// and `ResumeAllInterrupts` are allowed.
#[test]
fn al_seq10_callback_call_level_osek() {
    static P: Program = Program::tasks(&[&S10_T1, &[]]).callbacks(&[
        hook(4, HookCall::Callback(0)),
        err(5, ActivateTask(T2), OsError::CallLevel),
        err(6, GetTaskId, OsError::CallLevel),
        err(7, SuspendOsInterrupts, OsError::CallLevel),
        err(8, ResumeOsInterrupts, OsError::CallLevel),
        ok(9, SuspendAllInterrupts),
        ok(10, ResumeAllInterrupts),
        end(11),
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S10_OSEK, &P);
}

/// Sequence 10, AUTOSAR dialect: `ActivateTask` and `GetTaskID` are still
/// `E_OS_CALLEVEL`, but all the interrupt services are allowed.
#[test]
fn al_seq10_callback_call_level_autosar() {
    static P: Program = Program::tasks(&[&S10_T1, &[]]).callbacks(&[
        hook(4, HookCall::Callback(0)),
        err(5, ActivateTask(T2), OsError::CallLevel),
        err(6, GetTaskId, OsError::CallLevel),
        ok(7, SuspendOsInterrupts),
        ok(8, ResumeOsInterrupts),
        ok(9, SuspendAllInterrupts),
        ok(10, ResumeAllInterrupts),
        end(11),
    ]);
    check_each::<2, 0, 1, 1, 0, 2>(&S10_AUTOSAR, &P);
}

// ---- Sequence 11: autostart and cyclic alarms, standard and extended status, every
// class, full preemption; t1 (1) autostart, t2 (2), t3 (3); Alarm1 activating t2, armed at
// start with increment 1; Alarm2 activating t3, armed at start at value 2 with cycle 2;
// the counter's maxallowedvalue is 4 (it wraps after 4); t1 counts.

const COUNTER4: CounterConfig = CounterConfig {
    max_allowed_value: 4,
    ticks_per_base: 1,
    min_cycle: 1,
};

const fn s11(class: ConformanceClass, status: Status) -> OsConfig<3, 0, 1, 2, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 1).autostart(),
                TaskConfig::basic("t2", 2),
                TaskConfig::basic("t3", 3),
            ],
            [COUNTER4],
            [
                alarm("Alarm1", AlarmAction::ActivateTask(T2)).relative(1, 0),
                alarm("Alarm2", AlarmAction::ActivateTask(T3)).absolute(2, 2),
            ],
            [],
        )
        .class(class)
        .status(status),
    )
}

static S11: [OsConfig<3, 0, 1, 2, 0>; 8] = [
    s11(Bcc1, Status::Standard),
    s11(Bcc1, Status::Extended),
    s11(Bcc2, Status::Standard),
    s11(Bcc2, Status::Extended),
    s11(Ecc1, Status::Standard),
    s11(Ecc1, Status::Extended),
    s11(Ecc2, Status::Standard),
    s11(Ecc2, Status::Extended),
];

/// Sequence 11: `StartOS` arms both alarms; the single one activates t2 once, the cyclic
/// one activates t3 every 2 ticks, across the counter's wrap (values 2, 4, then 1), each
/// preempting t1 inside its `IncrementCounter`; after `CancelAlarm` nothing more expires.
#[test]
fn al_seq11_autostart_and_cyclic() {
    static P: Program = Program::tasks(&[
        &[
            ret(1, GetAlarm(A1), Returned::Ticks(1)),
            ret(2, GetAlarm(A2), Returned::Ticks(2)),
            ok(3, IncrementCounter(C0)),
            ok(5, IncrementCounter(C0)),
            err(7, GetAlarm(A1), OsError::NoFunc),
            ret(8, GetAlarm(A2), Returned::Ticks(2)),
            ok(9, IncrementCounter(C0)),
            ok(10, IncrementCounter(C0)),
            ok(12, IncrementCounter(C0)),
            ret(13, GetCounterValue(C0), Returned::Ticks(0)),
            ok(14, IncrementCounter(C0)),
            ok(16, CancelAlarm(A2)),
            ok(17, IncrementCounter(C0)),
            ok(18, IncrementCounter(C0)),
            err(19, GetAlarm(A2), OsError::NoFunc),
            ok(20, TerminateTask),
        ],
        &[ok(4, TerminateTask)],
        &[
            ok(6, TerminateTask),
            ok(11, TerminateTask),
            ok(15, TerminateTask),
        ],
    ]);
    check_each::<3, 0, 1, 2, 0, 3>(&S11, &P);
}

// ---- Sequence 12 (not in the plan, which leaves it out of conformance testing): an
// expiry action that fails, standard and extended status, ECC1/ECC2, with ErrorHook; t1
// (2) autostart, t2 (1), t3 extended (3) never activated; Alarm1 activating t2, Alarm2
// setting Event1 of t3; t1 counts.

const fn s12(class: ConformanceClass, status: Status) -> OsConfig<3, 0, 1, 2, 0> {
    config(
        OsDescription::new(
            [
                TaskConfig::basic("t1", 2).autostart(),
                TaskConfig::basic("t2", 1),
                TaskConfig::extended("t3", 3),
            ],
            [COUNTER],
            [
                alarm("Alarm1", AlarmAction::ActivateTask(T2)),
                alarm("Alarm2", AlarmAction::SetEvent(T3, E1)),
            ],
            [],
        )
        .class(class)
        .status(status)
        .hooks(HookSet {
            error: true,
            ..HookSet::NONE
        }),
    )
}

static S12: [OsConfig<3, 0, 1, 2, 0>; 4] = [
    s12(Ecc1, Status::Standard),
    s12(Ecc1, Status::Extended),
    s12(Ecc2, Status::Standard),
    s12(Ecc2, Status::Extended),
];

/// Sequence 12: an activation beyond t2's limit and an event for the suspended t3 each call
/// ErrorHook with the action's own service and parameters (`E_OS_LIMIT` of
/// `ActivateTask(t2)`, `E_OS_STATE` of `SetEvent(t3, Event1)`), inside the
/// `IncrementCounter` that expired them, which itself returns `E_OK` (AUTOSAR
/// SWS_Os_00321, the kernel's documented choice).
#[test]
fn al_seq12_failed_action_reaches_error_hook() {
    static P: Program = Program::tasks(&[
        &[
            ok(1, rel(A1, 1, 1)),
            ok(2, rel(A2, 3, 0)),
            ok(3, IncrementCounter(C0)),
            ok(4, IncrementCounter(C0)),
            ok(7, CancelAlarm(A1)),
            ok(8, IncrementCounter(C0)),
            ret(11, GetTaskState(T2), Returned::State(TaskState::Ready)),
            ok(12, TerminateTask),
        ],
        &[ok(13, TerminateTask)],
        &[],
    ])
    .error_hook(&[
        hook(5, HookCall::Error(OsError::Limit, ActivateTask(T2))),
        end(6),
        hook(9, HookCall::Error(OsError::State, SetEvent(T3, E1))),
        end(10),
    ]);
    check_each::<3, 0, 1, 2, 0, 3>(&S12, &P);
}
