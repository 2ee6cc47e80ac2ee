//! The task set's response-time analysis from the description, before generation: each
//! task's and ISR's execution budget and release (`OsTaskTimingProtection`,
//! `OsIsrTimingProtection`), its priority and the ceilings of its resources, analysed by
//! the kernel's own [`cw_core::os::rta`] (the evaluation's analysis). A task set in which
//! an item can miss its deadline is refused, naming it and what preempts it.
//!
//! What each item is:
//! - a task that an autostarted cyclic alarm activates (or whose event it sets): released
//!   every cycle (the kernel's counter counts the port's 1 ms system timer,
//!   [`crate::rte::TICK_MS`]);
//! - a task that a data-received event of the RTE activates: released once per job of the
//!   task whose runnable writes, as late as that job's end (its release jitter, the
//!   writer's response time: `rta::settle_jitter`);
//! - any other task: released at most once per `OsTaskTimeFrame` (above 0); without one,
//!   an autostarted basic task runs its one job at start-up and is not analysed (it is no
//!   periodic load); any other task is refused;
//! - an ISR with `OsIsrTimingProtection`: at most once per `OsIsrTimeFrame`, above every
//!   task. An ISR without it is left out (the report names it).
//!
//! A task released by the jobs of two tasks is refused (one writer each), as are interrupt
//! lock budgets above 0 (`Os...AllInterruptLockBudget`, `Os...OsInterruptLockBudget`: their
//! sections are not modelled).
//!
//! Every deadline is the item's period. A job holding a resource runs at its ceiling (the
//! highest priority of the tasks and ISRs that use it), a non-preemptive task at the
//! highest task priority: each such section is bounded by the item's whole budget. The
//! kernel's own sections (its lock around each call) are not in the description: the
//! evaluation's analysis of the image adds them with a measured figure. The kernel does
//! not enforce the budgets (it has no timing protection); the evaluation holds the
//! image's measured jobs to them.

use cw_core::os::rta::{self, Load, Response};

use crate::model::{Ecu, Timing};
use crate::validate::Error;

/// What releases an item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Release {
    /// Its cyclic alarm.
    Alarm,
    /// The job of this task (by name), whose runnable's write activates it.
    Task(String),
    /// Anything, at most once per its time frame.
    TimeFrame,
}

/// One task or ISR analysed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Item {
    /// Its name.
    pub name: String,
    /// Its path (its timing protection's where it has one).
    pub path: String,
    /// What releases it.
    pub release: Release,
    /// Its load, µs.
    pub load: Load,
    /// Its analysis.
    pub response: Response,
}

impl Item {
    /// One line: the item, what releases it, its budget, blocking and jitter, its worst
    /// response against its deadline.
    pub fn line(&self) -> String {
        let release = match &self.release {
            Release::Alarm => format!("every {} µs (alarm)", self.load.period),
            Release::Task(by) => format!("by {by}'s job, every {} µs", self.load.period),
            Release::TimeFrame => format!("at most every {} µs", self.load.period),
        };
        let response = match self.response {
            Response::Meets { response, .. } => format!("responds within {response}"),
            Response::Misses { at_least, .. } => format!("misses: at least {at_least}"),
            Response::NoPeriod => "not analysed".to_string(),
        };
        format!(
            "  {} (priority {}): released {release}; budget {}, blocking {}, jitter {}; {response} of {}",
            self.name,
            self.load.priority,
            self.load.wcet,
            crate::timing::blocking_of(self),
            self.load.jitter,
            self.load.deadline
        )
    }
}

fn blocking_of(item: &Item) -> u64 {
    match item.response {
        Response::Meets { blocking, .. } | Response::Misses { blocking, .. } => blocking,
        Response::NoPeriod => 0,
    }
}

/// What the analysis of a description gives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Analysis {
    /// No task or ISR has a timing protection: nothing analysed.
    NoBudgets,
    /// Every item analysed, each meeting its deadline; and the ISRs left out.
    Schedulable {
        /// The items, tasks then ISRs.
        items: Vec<Item>,
        /// The ISRs without a timing protection, by name.
        left_out: Vec<String>,
    },
}

/// A task's or ISR's timing field, where its timing protection gives it.
fn field(timing: Option<&Timing>, f: impl Fn(&Timing) -> Option<u64>) -> Option<u64> {
    timing.and_then(f)
}

/// Analyses `ecu`'s task set; `released_by` gives, by name, each task a data-received
/// event activates and the task whose job writes (the RTE's mapping).
///
/// # Errors
/// A task that runs after start-up without an execution budget or a release the analysis
/// can tell (or released by two tasks' jobs, or with a time frame of 0); an ISR's timing
/// protection without its budget or a time frame above 0; release jitters that do not
/// settle; an item that cannot be analysed, or can miss its deadline, named with the
/// items of its priority or above.
pub fn analyse(ecu: &Ecu, released_by: &[(String, String)]) -> Result<Analysis, Vec<Error>> {
    let os = &ecu.os;
    if os.tasks.iter().all(|t| t.timing.is_none()) && os.isrs.iter().all(|i| i.timing.is_none()) {
        return Ok(Analysis::NoBudgets);
    }
    let mut out = Vec::new();
    let top_task = os.tasks.iter().map(|t| t.priority).max().unwrap_or(0);
    // ISRs above every task, in their own order.
    let isr_priority = |p: u64| top_task.saturating_add(1).saturating_add(p);
    // Each resource's ceiling on that one scale.
    let ceiling = |resource: &str| {
        let tasks = os
            .tasks
            .iter()
            .filter(|t| t.resources.iter().any(|r| r == resource))
            .map(|t| t.priority);
        let isrs = os
            .isrs
            .iter()
            .filter(|i| i.resources.iter().any(|r| r == resource))
            .map(|i| isr_priority(i.priority));
        tasks.chain(isrs).max().unwrap_or(0)
    };
    let to_u16 = |p: u64| u16::try_from(p).unwrap_or(u16::MAX);
    let mut items: Vec<Item> = Vec::new();
    // Tasks already refused: a task they release is not refused again for it.
    let mut refused: Vec<String> = Vec::new();
    for t in &os.tasks {
        let cycle = crate::rte::task_period_ms(ecu, &t.name);
        let timing = t.timing.as_ref();
        let mut writers: Vec<&str> = released_by
            .iter()
            .filter(|(task, _)| *task == t.name)
            .map(|(_, by)| by.as_str())
            .collect();
        writers.sort_unstable();
        writers.dedup();
        if let [first, second, ..] = writers.as_slice() {
            out.push(Error::new(
                format!(
                    "task {} is released by the jobs of {first} and {second}: the analysis takes one writer per released task",
                    t.name
                ),
                &[&t.path],
            ));
            refused.push(t.name.clone());
            continue;
        }
        let frame = field(timing, |x| x.time_frame_us);
        if frame == Some(0) {
            out.push(Error::new(
                format!(
                    "task {}'s OsTaskTimeFrame is 0: releases need time between them",
                    t.name
                ),
                &[timing.map_or(t.path.as_str(), |x| x.path.as_str())],
            ));
            refused.push(t.name.clone());
            continue;
        }
        let releaser = writers.first().map(|by| (*by).to_string());
        let (release, period) = match (cycle, releaser, frame) {
            (Some(ms), _, _) => (Release::Alarm, ms.saturating_mul(1000)),
            // The writer's period, set below once every alarm's task is known.
            (None, Some(by), _) => (Release::Task(by), 0),
            (None, None, Some(frame)) => (Release::TimeFrame, frame),
            // A basic task started once: its one job is no periodic load. (An extended
            // one may wait for events for ever, and needs a time frame.)
            (None, None, None) if t.autostart && t.events.is_empty() => continue,
            (None, None, None) => {
                out.push(Error::new(
                    format!(
                        "task {} cannot be analysed: no cyclic alarm, data-received event or OsTaskTimeFrame gives its releases",
                        t.name
                    ),
                    &[&t.path],
                ));
                refused.push(t.name.clone());
                continue;
            }
        };
        let Some(budget) = field(timing, |x| x.budget_us) else {
            out.push(Error::new(
                format!(
                    "task {} has no OsTaskExecutionBudget: the task set's analysis needs every task's",
                    t.name
                ),
                &[timing.map_or(t.path.as_str(), |x| x.path.as_str())],
            ));
            refused.push(t.name.clone());
            continue;
        };
        let mut raises_to = t.resources.iter().map(|r| ceiling(r)).max().unwrap_or(0);
        if !t.preemptive {
            raises_to = raises_to.max(top_task);
        }
        let priority = to_u16(t.priority);
        items.push(Item {
            name: t.name.clone(),
            path: timing.map_or_else(|| t.path.clone(), |x| x.path.clone()),
            release,
            load: Load::periodic(priority, period, budget, to_u16(raises_to).max(priority)),
            response: Response::NoPeriod,
        });
    }
    let mut left_out = Vec::new();
    for i in &os.isrs {
        let Some(timing) = i.timing.as_ref() else {
            left_out.push(i.name.clone());
            continue;
        };
        let (Some(budget), Some(frame)) =
            (timing.budget_us, timing.time_frame_us.filter(|&f| f > 0))
        else {
            out.push(Error::new(
                format!(
                    "ISR {}'s timing protection needs both OsIsrExecutionBudget and an OsIsrTimeFrame above 0 for the analysis",
                    i.name
                ),
                &[&timing.path],
            ));
            continue;
        };
        let priority = isr_priority(i.priority);
        let raises_to = i
            .resources
            .iter()
            .map(|r| ceiling(r))
            .max()
            .unwrap_or(0)
            .max(priority);
        items.push(Item {
            name: i.name.clone(),
            path: timing.path.clone(),
            release: Release::TimeFrame,
            load: Load::periodic(to_u16(priority), frame, budget, to_u16(raises_to)),
            response: Response::NoPeriod,
        });
    }
    // A released task: its writer's period (again until none changes: a writer may be
    // released itself), and its writer's response as its jitter.
    let mut pairs = Vec::new();
    for _ in 0..items.len() {
        let mut changed = false;
        for k in 0..items.len() {
            let Some(Release::Task(by)) = items.get(k).map(|i| i.release.clone()) else {
                continue;
            };
            let writer = items.iter().position(|w| w.name == by);
            let period = writer
                .and_then(|w| items.get(w))
                .map_or(0, |w| w.load.period);
            if let Some(item) = items.get_mut(k) {
                if period > 0 && item.load.period != period {
                    item.load.period = period;
                    item.load.deadline = period;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    for (k, item) in items.iter().enumerate() {
        let Release::Task(by) = &item.release else {
            continue;
        };
        match items.iter().position(|w| w.name == *by) {
            Some(w) if item.load.period > 0 => pairs.push((k, w)),
            // Its writer's error says why.
            _ if refused.contains(by) => {}
            _ => out.push(Error::new(
                format!(
                    "task {} is released by {by}'s job, which the analysis does not release periodically",
                    item.name
                ),
                &[&item.path],
            )),
        }
    }
    if !out.is_empty() {
        return Err(out);
    }
    let mut loads: Vec<Load> = items.iter().map(|i| i.load).collect();
    // A releaser that misses is reported below, with the rest.
    let settled = rta::settle_jitter(&mut loads, &pairs);
    for (k, item) in items.iter_mut().enumerate() {
        if let Some(load) = loads.get(k) {
            item.load = *load;
        }
        item.response = rta::response_time(&loads, k);
    }
    if !settled && items.iter().all(|i| i.response.meets()) {
        let paths: Vec<&str> = pairs
            .iter()
            .filter_map(|&(k, _)| items.get(k).map(|i| i.path.as_str()))
            .collect();
        out.push(Error::new(
            "the release jitters of the tasks other tasks' jobs release did not settle: the analysis cannot bound them",
            &paths,
        ));
    }
    for item in &items {
        if item.response == Response::NoPeriod {
            out.push(Error::new(
                format!(
                    "{} cannot be analysed: it or an item above it has no period",
                    item.name
                ),
                &[&item.path],
            ));
        }
        if let Response::Misses { at_least, blocking } = item.response {
            let mut paths = vec![item.path.as_str()];
            paths.extend(
                items
                    .iter()
                    .filter(|o| o.name != item.name && o.load.priority >= item.load.priority)
                    .map(|o| o.path.as_str()),
            );
            out.push(Error::new(
                format!(
                    "{} can miss its deadline: its response can reach {at_least} µs (its budget {} µs, blocking {blocking} µs, jitter {} µs, and what preempts it), past its deadline of {} µs",
                    item.name, item.load.wcet, item.load.jitter, item.load.deadline
                ),
                &paths,
            ));
        }
    }
    if out.is_empty() {
        Ok(Analysis::Schedulable { items, left_out })
    } else {
        Err(out)
    }
}
