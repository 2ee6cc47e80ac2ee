//! The configurations the model checker explores: the paper's task set and small
//! adversarial sets chosen to stress one rule each.

use crate::OsModel;
use cw_core::os::{
    AlarmAction, AlarmAutostart, AlarmConfig, CounterConfig, CounterId, OsConfig, TaskConfig,
    TaskId,
};

// Evaluated only in `static` initialisers: a broken configuration stops the build.
#[allow(clippy::panic)]
const fn unwrap<const T: usize, const R: usize, const C: usize, const A: usize>(
    cfg: Result<OsConfig<T, R, C, A>, cw_core::os::ConfigError>,
) -> OsConfig<T, R, C, A> {
    match cfg {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    }
}

const fn cyclic(name: &'static str, task: u8, offset: u32, period: u32) -> AlarmConfig {
    AlarmConfig {
        name,
        counter: CounterId(0),
        action: AlarmAction::ActivateTask(TaskId(task)),
        autostart: AlarmAutostart::Relative {
            increment: offset,
            cycle: period,
        },
    }
}

/// The paper's tasks (§3.2, ARCHITECTURE §1) on a 1 ms counter that wraps every 80 ms
/// (twice the hyperperiod of 10/20/40 ms, the smallest range that admits a 40 ms cycle, so the model stays finite without losing a phase).
/// Priorities: start-up 6 (non-preemptive, autostart), LED 5, BSW 4, obstacle 3, Com 2,
/// sonar 1. The sonar task activates the Com task (data received at SonarRecv); one
/// resource guards the sonar data shared by sonar, obstacle and Com.
pub static PAPER: OsConfig<6, 1, 1, 4> = unwrap(OsConfig::new(
    [
        TaskConfig::basic("OsStartupTask", 6)
            .non_preemptive()
            .autostart(),
        TaskConfig::basic("OsLEDTask", 5),
        TaskConfig::basic("OsBswServiceTask", 4),
        TaskConfig::basic("OsObstacleDetectionTask", 3).uses(0b1),
        TaskConfig::basic("OsComTask", 2).uses(0b1),
        TaskConfig::basic("OsSonarTask", 1).uses(0b1),
    ],
    [CounterConfig {
        max_allowed_value: 79,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [
        cyclic("LedAlarm", 1, 10, 10),
        cyclic("BswAlarm", 2, 10, 10),
        cyclic("ObstacleAlarm", 3, 20, 20),
        cyclic("SonarAlarm", 5, 40, 40),
    ],
));

/// The paper's set, with the sonar task able to activate the Com task.
pub fn paper() -> OsModel<6, 1, 1, 4, 6> {
    OsModel {
        name: "paper task set (6 tasks, 4 cyclic alarms, 1 resource)",
        cfg: &PAPER,
        event_masks: &[],
        activations: &[(TaskId(5), TaskId(4))],
        isr_services: true,
        adversarial: false,
    }
}

/// Ceilings and LIFO: three tasks sharing two nested resources, every service allowed.
pub static CEILING: OsConfig<3, 2, 0, 0> = unwrap(OsConfig::new(
    [
        TaskConfig::basic("L", 1).activations(2).uses(0b11),
        TaskConfig::basic("M", 2).uses(0b10),
        TaskConfig::basic("H", 4).uses(0b01),
    ],
    [],
    [],
));

/// Ceiling and LIFO stress.
pub fn ceiling() -> OsModel<3, 2, 0, 0, 4> {
    OsModel {
        name: "adversarial: ceilings and nested resources",
        cfg: &CEILING,
        event_masks: &[],
        activations: &[],
        isr_services: true,
        adversarial: true,
    }
}

/// FIFO: several tasks and activations at one priority, a non-preemptive task and a
/// higher one preempting them.
pub static FIFO: OsConfig<4, 0, 0, 0> = unwrap(OsConfig::new(
    [
        TaskConfig::basic("A", 1).activations(2),
        TaskConfig::basic("B", 1).activations(2),
        TaskConfig::basic("N", 1).non_preemptive(),
        TaskConfig::basic("H", 3),
    ],
    [],
    [],
));

/// FIFO stress.
pub fn fifo() -> OsModel<4, 0, 0, 0, 6> {
    OsModel {
        name: "adversarial: FIFO within a priority, multiple activations",
        cfg: &FIFO,
        event_masks: &[],
        activations: &[],
        isr_services: true,
        adversarial: true,
    }
}

/// Events: two extended tasks and a basic one; an alarm sets an event cyclically.
pub static EVENTS: OsConfig<3, 1, 1, 2> = unwrap(OsConfig::new(
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
        AlarmConfig {
            name: "EvE1",
            counter: CounterId(0),
            action: AlarmAction::SetEvent(TaskId(0), 0b01),
            autostart: AlarmAutostart::Relative {
                increment: 2,
                cycle: 2,
            },
        },
        AlarmConfig {
            name: "ActB",
            counter: CounterId(0),
            action: AlarmAction::ActivateTask(TaskId(2)),
            autostart: AlarmAutostart::Absolute { start: 3, cycle: 4 },
        },
    ],
));

/// Event stress.
pub fn events() -> OsModel<3, 1, 1, 2, 4> {
    OsModel {
        name: "adversarial: events, waiting and alarm-driven release",
        cfg: &EVENTS,
        event_masks: &[0b01, 0b10, 0b11],
        activations: &[],
        isr_services: true,
        adversarial: true,
    }
}
