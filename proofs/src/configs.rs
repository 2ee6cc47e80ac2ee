//! The configurations the model checker explores: the paper's task set with its two ISRs,
//! and small adversarial sets chosen to stress one part of the standard each.

use crate::{IsrBody, OsModel, Reach, TICK};
use cw_core::os::{
    AlarmAction, AlarmConfig, ConformanceClass, CounterConfig, CounterId, Dialect, HookSet,
    IsrConfig, IsrId, OsConfig, OsDescription, ResourceId, ServiceCall, TaskConfig, TaskId,
};

// Evaluated only in `static` initialisers: a broken configuration stops the build.
#[allow(clippy::panic)]
const fn unwrap<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize>(
    cfg: Result<OsConfig<T, R, C, A, I>, cw_core::os::ConfigError>,
) -> OsConfig<T, R, C, A, I> {
    match cfg {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    }
}

const fn cyclic(name: &'static str, task: u8, offset: u32, period: u32) -> AlarmConfig {
    AlarmConfig::new(name, CounterId(0), AlarmAction::ActivateTask(TaskId(task)))
        .relative(offset, period)
}

/// The paper's tasks (§3.2, ARCHITECTURE §1) with their periods in ticks of 10 ms (10, 10,
/// 20 and 40 ms are 1, 1, 2 and 4 ticks) on a counter that wraps every 8 ticks (twice the
/// hyperperiod, the smallest range that admits the 4-tick cycle, so the model stays finite
/// without losing a phase). Against the ECU's 1 ms counter this leaves out only the ticks
/// at which nothing is due; every order of expiries stays. With the ECU's two category-2
/// ISRs:
/// `SysTickIsr` (priority 2) ticks the counter, `CanIsr` (priority 1) writes the Com
/// receive buffer, which the obstacle-detection task reads: resource 1, shared by them,
/// whose ceiling lies at `CanIsr`'s level. Priorities: start-up 6 (non-preemptive,
/// autostart), LED 5, BSW 4, obstacle 3, Com 2, sonar 1. The sonar task activates the Com
/// task (data received at SonarRecv); resource 0 guards the sonar data shared by sonar,
/// obstacle and Com.
pub static PAPER: OsConfig<6, 2, 1, 4, 2> = unwrap(OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("OsStartupTask", 6)
                .non_preemptive()
                .autostart(),
            TaskConfig::basic("OsLEDTask", 5),
            TaskConfig::basic("OsBswServiceTask", 4),
            TaskConfig::basic("OsObstacleDetectionTask", 3).uses(0b11),
            TaskConfig::basic("OsComTask", 2).uses(0b01),
            TaskConfig::basic("OsSonarTask", 1).uses(0b01),
        ],
        [CounterConfig {
            max_allowed_value: 7,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        [
            cyclic("LedAlarm", 1, 1, 1),
            cyclic("BswAlarm", 2, 1, 1),
            cyclic("ObstacleAlarm", 3, 2, 2),
            cyclic("SonarAlarm", 5, 4, 4),
        ],
        [
            IsrConfig::cat2("SysTickIsr", 2),
            IsrConfig::cat2("CanIsr", 1).uses(0b10),
        ],
    )
    .class(ConformanceClass::Bcc1)
    .dialect(Dialect::Autosar)
    .hooks(HookSet::ALL),
));

/// The paper's set, with the sonar task able to activate the Com task.
pub fn paper() -> OsModel<6, 2, 1, 4, 2, 6> {
    OsModel {
        name: "paper task set (6 tasks, 4 cyclic alarms, 2 resources, 2 ISRs)",
        cfg: &PAPER,
        event_masks: &[],
        activations: &[(TaskId(5), TaskId(4))],
        isr_bodies: &[
            (IsrId(0), IsrBody::Script(&[TICK])),
            (
                IsrId(1),
                IsrBody::Script(&[
                    ServiceCall::GetResource(ResourceId(1)),
                    ServiceCall::ReleaseResource(ResourceId(1)),
                ]),
            ),
        ],
        task_locks: false,
        adversarial: false,
        missing_ends: false,
        reach: &[
            Reach::Preemption,
            Reach::TwoQueued,
            Reach::Isr2Nesting,
            Reach::HeldInterrupt,
            Reach::IsrResource,
        ],
    }
}

/// An ISR body that activates every task of a three- or four-task set.
const ACTIVATE_ANY: &[ServiceCall] = &[
    ServiceCall::ActivateTask(TaskId(0)),
    ServiceCall::ActivateTask(TaskId(1)),
    ServiceCall::ActivateTask(TaskId(2)),
    ServiceCall::ActivateTask(TaskId(3)),
];

/// Ceilings and LIFO: three tasks sharing two nested resources, every service allowed.
pub static CEILING: OsConfig<3, 2, 0, 0, 1> = unwrap(OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("L", 1).activations(2).uses(0b11),
            TaskConfig::basic("M", 2).uses(0b10),
            TaskConfig::basic("H", 4).uses(0b01),
        ],
        [],
        [],
        [IsrConfig::cat2("Isr", 0)],
    )
    .hooks(HookSet::ALL),
));

/// Ceiling and LIFO stress.
pub fn ceiling() -> OsModel<3, 2, 0, 0, 1, 4> {
    OsModel {
        name: "adversarial: ceilings and nested resources",
        cfg: &CEILING,
        event_masks: &[],
        activations: &[],
        isr_bodies: &[(IsrId(0), IsrBody::Whole(ACTIVATE_ANY))],
        task_locks: false,
        adversarial: true,
        missing_ends: true,
        reach: &[Reach::Preemption, Reach::TwoQueued],
    }
}

/// FIFO: several tasks and activations at one priority, a non-preemptive task and a
/// higher one preempting them.
pub static FIFO: OsConfig<4, 0, 0, 0, 1> = unwrap(OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("A", 1).activations(2),
            TaskConfig::basic("B", 1).activations(2),
            TaskConfig::basic("N", 1).non_preemptive(),
            TaskConfig::basic("H", 3),
        ],
        [],
        [],
        [IsrConfig::cat2("Isr", 0)],
    )
    .class(ConformanceClass::Bcc2)
    .hooks(HookSet::ALL),
));

/// FIFO stress.
pub fn fifo() -> OsModel<4, 0, 0, 0, 1, 6> {
    OsModel {
        name: "adversarial: FIFO within a priority, multiple activations",
        cfg: &FIFO,
        event_masks: &[],
        activations: &[],
        isr_bodies: &[(IsrId(0), IsrBody::Whole(ACTIVATE_ANY))],
        task_locks: false,
        adversarial: true,
        missing_ends: true,
        reach: &[Reach::Preemption, Reach::TwoQueued],
    }
}

/// Events: two extended tasks and a basic one; an alarm sets an event cyclically, another
/// activates the basic task; the timer ISR ticks and may activate any task or set events.
pub static EVENTS: OsConfig<3, 1, 1, 2, 1> = unwrap(OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::extended("E1", 2).uses(0b1),
            TaskConfig::extended("E2", 2),
            TaskConfig::basic("B", 3).activations(2).uses(0b1),
        ],
        [CounterConfig {
            max_allowed_value: 7,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        [
            AlarmConfig::new("EvE1", CounterId(0), AlarmAction::SetEvent(TaskId(0), 0b01))
                .relative(2, 2),
            AlarmConfig::new("ActB", CounterId(0), AlarmAction::ActivateTask(TaskId(2)))
                .absolute(3, 4),
        ],
        [IsrConfig::cat2("Tick", 0)],
    )
    .hooks(HookSet::ALL),
));

/// Event stress.
pub fn events() -> OsModel<3, 1, 1, 2, 1, 4> {
    OsModel {
        name: "adversarial: events, waiting and alarm-driven release",
        cfg: &EVENTS,
        event_masks: &[0b01, 0b10, 0b11],
        activations: &[],
        isr_bodies: &[(
            IsrId(0),
            IsrBody::Whole(&[
                TICK,
                ServiceCall::ActivateTask(TaskId(0)),
                ServiceCall::ActivateTask(TaskId(1)),
                ServiceCall::ActivateTask(TaskId(2)),
                ServiceCall::SetEvent(TaskId(0), 0b01),
                ServiceCall::SetEvent(TaskId(0), 0b10),
                ServiceCall::SetEvent(TaskId(1), 0b11),
            ]),
        )],
        task_locks: false,
        adversarial: true,
        missing_ends: true,
        reach: &[Reach::Preemption, Reach::TwoQueued, Reach::Waiting],
    }
}

/// Interrupts: two category-2 ISRs at different priorities and a category-1 ISR above
/// them; the low ISR shares a resource with the low task (its ceiling at interrupt level)
/// and sets an event; the high ISR activates the high task under `SuspendOSInterrupts` and
/// returns without resuming (AUTOSAR's cleanup must undo it); the category-1 ISR takes
/// `SuspendAllInterrupts`. Tasks take every interrupt lock and may end without
/// `TerminateTask`.
pub static INTERRUPTS: OsConfig<3, 1, 0, 0, 3> = unwrap(OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("L", 1).uses(0b1).autostart(),
            TaskConfig::extended("E", 2),
            TaskConfig::basic("H", 3),
        ],
        [],
        [],
        [
            IsrConfig::cat2("Low2", 1).uses(0b1),
            IsrConfig::cat2("High2", 3),
            IsrConfig::cat1("Fast1", 5),
        ],
    )
    .class(ConformanceClass::Ecc1)
    .dialect(Dialect::Autosar)
    .hooks(HookSet::ALL),
));

/// Interrupt stress: nesting, masking by ceilings and locks, category 1 under
/// `SuspendOSInterrupts`, ISRs and tasks that end holding what they took.
pub fn interrupts() -> OsModel<3, 1, 0, 0, 3, 3> {
    OsModel {
        name: "adversarial: ISR nesting, interrupt locks, ISR resources, missing ends",
        cfg: &INTERRUPTS,
        event_masks: &[0b1],
        activations: &[(TaskId(0), TaskId(2)), (TaskId(0), TaskId(1))],
        isr_bodies: &[
            (
                IsrId(0),
                IsrBody::Script(&[
                    ServiceCall::GetResource(ResourceId(0)),
                    ServiceCall::SetEvent(TaskId(1), 0b1),
                    ServiceCall::ReleaseResource(ResourceId(0)),
                ]),
            ),
            (
                IsrId(1),
                IsrBody::Script(&[
                    ServiceCall::SuspendOsInterrupts,
                    ServiceCall::ActivateTask(TaskId(2)),
                ]),
            ),
            (
                IsrId(2),
                IsrBody::Script(&[
                    ServiceCall::SuspendAllInterrupts,
                    ServiceCall::ResumeAllInterrupts,
                ]),
            ),
        ],
        task_locks: true,
        adversarial: false,
        missing_ends: true,
        reach: &[
            Reach::Preemption,
            Reach::Isr2Nesting,
            Reach::HeldInterrupt,
            Reach::IsrResource,
            Reach::Cat1UnderSuspendOs,
            Reach::Waiting,
        ],
    }
}
