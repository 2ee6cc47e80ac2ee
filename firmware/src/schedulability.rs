//! The ECU's task set for the response-time analysis ([`cw_core::os::rta`]): every task
//! and category-2 ISR of [`config::OS`] that runs after start-up, with its release, its
//! deadline, the priorities it raises to, and the execution times a measurement gives.
//! A measuring image prints it (`cargo xtask eval` analyses it with the run's figures).
//!
//! What each item is:
//! - a task its alarm activates ([`config::PERIOD_MS`]): released every period at the
//!   tick, deadline its period;
//! - `OsComTask`, which `OsSonarTask`'s write activates ([`RELEASED_BY`]): released once
//!   per sonar job, as late as the sonar job's end after the sonar's release (its release
//!   jitter, [`released_by`], set by `rta::settle_jitter`), deadline the sonar's period
//!   (the frame leaves before the next sample);
//! - `SysTickIsr`: every 1 ms, deadline the next tick;
//! - `CanIsr`: once per distance frame the ECU sends (its transmit confirmation: the frame
//!   goes directly, no repetition, once per sonar job), so at the sonar's period,
//!   deadline the same. The frames the ECU receives (the tester's thresholds) are not in
//!   the analysis: their rate is the tester's, and the measured runs receive none. (At
//!   the bus's worst, one accepted frame every 158 µs, the measuring image's CAN ISR,
//!   which writes each event as an SLCAN line to a UART, would not keep up.)
//!
//! Blocking: every task raises its priority to its resources' ceilings while it holds
//! them. Those sections are not measured one by one, so each is bounded by the task's
//! whole execution time: the analysis is an upper bound, pessimistic in its blocking.
//! The kernel's lock (every category-2 ISR masked for one kernel call) is one more
//! section any item may wait for: not in this table, the analysis adds it with a figure
//! of the kernel's own (`cargo xtask eval`: the longest dispatch a run shows).
//!
//! `OsStartupTask` runs once, before any alarm; the category-1 `SensorRxIsr` serves only
//! the UART ranging module and is left out where that sensor is not used (the measuring
//! runs use the scenario's sensor).

use cw_core::os::rta::Load;
use cw_core::os::TaskId;

use crate::config;

/// Tasks activated by another task's job, not by an alarm: (task, the task whose job
/// activates it), as the generated RTE maps the data-received events and their senders'
/// runnables to tasks.
pub const RELEASED_BY: [(TaskId, TaskId); crate::rte::tasks::RELEASED_BY.len()] =
    crate::rte::tasks::RELEASED_BY;

/// The tasks and ISRs analysed, in this order: the five tasks after start-up, then
/// `SysTickIsr` and `CanIsr`.
pub const ITEMS: usize = 7;

/// The tasks analysed, by slot.
const TASKS: [TaskId; 5] = [
    config::os::OS_LED_TASK,
    config::os::OS_BSW_SERVICE_TASK,
    config::os::OS_OBSTACLE_DETECTION_TASK,
    config::os::OS_COM_TASK,
    config::os::OS_SONAR_TASK,
];

/// What the analysis takes from a measurement, in one unit of time: the measuring
/// image's own figures, net of its measuring marks (`cargo xtask eval` analyses the
/// measuring image itself with figures from its job records instead, marks included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Measured {
    /// Units per ms.
    pub per_ms: u64,
    /// Per task slot of [`config::OS`]: its longest job without what preempted it.
    pub task_wcet: [u64; 6],
    /// `SysTickIsr`'s longest run.
    pub tick_wcet: u64,
    /// `CanIsr`'s longest run.
    pub can_isr_wcet: u64,
}

/// Item `i`'s name in the configuration and, for a task, its slot (`None` past the last
/// item).
pub fn item(i: usize) -> Option<(&'static str, Option<TaskId>)> {
    match TASKS.get(i) {
        Some(&task) => {
            let name = config::OS
                .tasks()
                .get(usize::from(task.0))
                .map_or("?", |t| t.name);
            Some((name, Some(task)))
        }
        None => {
            let isr = match i.checked_sub(TASKS.len())? {
                0 => config::os::SYS_TICK_ISR,
                1 => config::os::CAN_ISR,
                _ => return None,
            };
            let name = config::OS
                .isrs()
                .get(usize::from(isr.0))
                .map_or("?", |c| c.name);
            Some((name, None))
        }
    }
}

/// A task's priority and the highest priority it raises to (its resources' ceilings; the
/// kernel's lock, which every kernel call takes, is the analysis's to add: its sections
/// are the kernel's, not the task's).
fn task_priorities(task: TaskId) -> (u16, u16) {
    let t = config::OS.tasks().get(usize::from(task.0));
    let priority = t.map_or(0, |t| u16::from(t.priority));
    let resources = t.map_or(0, |t| t.resources);
    let ceiling = (0..u32::BITS as usize)
        .filter(|r| resources & (1 << r) != 0)
        .filter_map(|r| config::OS.resource_ceiling(r))
        .max()
        .map_or(0, u16::from);
    (priority, ceiling.max(priority))
}

/// The task set, item by item as [`item`] names them, with `measured`'s execution times
/// and every release jitter 0: [`released_by`] gives the items whose jitter
/// `rta::settle_jitter` then sets. Each item's analysis is `rta::response_time(&set, i)`.
/// (One array of loads: small enough for a Cortex-M image's task stack.)
pub fn loads(measured: &Measured) -> [Load; ITEMS] {
    let ms = measured.per_ms;
    let period_of = |t: TaskId| {
        u64::from(
            config::PERIOD_MS
                .get(usize::from(t.0))
                .copied()
                .unwrap_or(0),
        ) * ms
    };
    let task = |id: TaskId| {
        let (priority, raises_to) = task_priorities(id);
        let wcet = measured
            .task_wcet
            .get(usize::from(id.0))
            .copied()
            .unwrap_or(0);
        let released_by = RELEASED_BY
            .iter()
            .find(|(t, _)| *t == id)
            .map(|&(_, by)| by);
        Load::periodic(
            priority,
            period_of(released_by.unwrap_or(id)),
            wcet,
            raises_to,
        )
    };
    let isr = |index: usize, period: u64, wcet: u64| {
        let priority = u16::from(config::OS.isr_level(index).unwrap_or(0));
        Load::periodic(priority, period, wcet, priority)
    };
    [
        task(TASKS[0]),
        task(TASKS[1]),
        task(TASKS[2]),
        task(TASKS[3]),
        task(TASKS[4]),
        isr(
            usize::from(config::os::SYS_TICK_ISR.0),
            ms,
            measured.tick_wcet,
        ),
        isr(
            usize::from(config::os::CAN_ISR.0),
            period_of(config::os::OS_SONAR_TASK),
            measured.can_isr_wcet,
        ),
    ]
}

/// [`RELEASED_BY`] as item indices, `(released, releaser)`.
pub fn released_by() -> [(usize, usize); RELEASED_BY.len()] {
    let index = |t: TaskId| TASKS.iter().position(|&x| x == t).unwrap_or(usize::MAX);
    RELEASED_BY.map(|(task, by)| (index(task), index(by)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use cw_core::os::rta::{self, Response};

    /// The image's figures of 2026-11-28 (instructions; 31,250 per ms at QEMU's 32 ns).
    fn measured() -> Measured {
        Measured {
            per_ms: 31_250,
            task_wcet: [0, 120, 500, 140, 300, 1_600],
            tick_wcet: 750,
            can_isr_wcet: 1_500,
        }
    }

    #[test]
    fn the_ecus_set_meets_every_deadline_with_the_images_figures() {
        let mut set = loads(&measured());
        assert!(rta::settle_jitter(&mut set, &released_by()));
        for i in 0..ITEMS {
            assert!(rta::response_time(&set, i).meets(), "{:?}", item(i));
        }
        let names = [0, 1, 2, 3, 4, 5, 6].map(|i| item(i).map(|(name, _)| name));
        assert_eq!(
            names,
            [
                "OsLEDTask",
                "OsBswServiceTask",
                "OsObstacleDetectionTask",
                "OsComTask",
                "OsSonarTask",
                "SysTickIsr",
                "CanIsr"
            ]
            .map(Some)
        );
        assert_eq!(item(ITEMS), None);
        assert_eq!(item(3).and_then(|(_, t)| t), Some(config::os::OS_COM_TASK));
        // CanIsr: one transmit confirmation per sonar job.
        assert_eq!(set[6].period, 40 * 31_250);
        // OsComTask is released as late as the sonar job's end.
        assert_eq!(Some(set[3].jitter), rta::response_time(&set, 4).time());
        // The highest task is blocked by the longest lower job that takes RES_RTE (the
        // sonar's).
        assert_eq!(
            rta::response_time(&set, 0),
            Response::Meets {
                response: 120 + 1_600 + 750 + 1_500,
                blocking: 1_600
            }
        );
        // CanIsr by the longest that takes RES_COM (OsBswServiceTask's).
        assert_eq!(rta::blocking(&set, 6), 500);
    }

    #[test]
    fn a_job_longer_than_the_sonars_period_is_found_and_named() {
        let mut m = measured();
        m.task_wcet[usize::from(config::os::OS_SONAR_TASK.0)] = 40 * 31_250;
        let mut set = loads(&m);
        let _ = rta::settle_jitter(&mut set, &released_by());
        let missed: Vec<_> = (0..ITEMS)
            .filter(|&i| !rta::response_time(&set, i).meets())
            .filter_map(|i| item(i).map(|(name, _)| name))
            .collect();
        assert!(missed.contains(&"OsSonarTask"), "{missed:?}");
    }
}
