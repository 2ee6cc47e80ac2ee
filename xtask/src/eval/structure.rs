//! The paper's task structure beside the ECU's, on the Cortex-M4 image: what each costs.
//!
//! The ECU's periodic tasks are basic tasks an alarm activates: each job is a dispatch of
//! the task from its first line, ended by `TerminateTask`. The paper's (its `Rte.c` loops)
//! are extended tasks that wait for the event their alarm sets (`WaitEvent`, `ClearEvent`,
//! the job, `WaitEvent` again), each on its own stack. The evaluation runs the measuring
//! image both ways (the second built with the feature `extended-tasks`) over the same
//! scenario and compares, from each run's job records: the time from a millisecond to the
//! first line of the first job its tick released, by the number of alarms due, and the
//! dispatch from one job's end to the next job's first line within a millisecond. The
//! extended image also reports the deepest use of each task's own stack.

use std::fmt::Write as _;

use super::schedule::{by_alarms_due, job_times, Schedule};
use super::ImageRun;
use crate::Result;

/// One structure's figures, instructions (the image's: 32 ns each under QEMU).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Figures {
    /// By alarms due: (alarms, mean, samples) from the millisecond to the first line of
    /// the first job its tick released.
    pub(super) first_line: Vec<(usize, f64, usize)>,
    /// A job's end to the next job's first line within a millisecond: (mean, samples).
    pub(super) dispatch: (f64, usize),
}

/// Both structures, and the extended tasks' own stacks (name, bytes used).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Structures {
    pub(super) basic: Figures,
    pub(super) extended: Figures,
    pub(super) stacks: Vec<(String, u64)>,
}

/// The figures of one run, converted at `per_ms` instructions per ms.
fn figures(run: &ImageRun, schedule: &Schedule) -> Figures {
    let tick_released = schedule.tick_released();
    let cpm = f64::from(run.counts_per_ms.max(1));
    let per_count = schedule.per_ms as f64 / cpm;
    let times = job_times(&run.records, run.counts_per_ms, &tick_released);
    let first_line = by_alarms_due(&times.tick, &run.periodic, &tick_released)
        .into_iter()
        .map(|(n, l)| {
            let mean = l.iter().map(|&x| x as f64).sum::<f64>() / l.len().max(1) as f64;
            (n, mean * per_count, l.len())
        })
        .collect();
    let n = times.dispatch.len();
    let dispatch = times.dispatch.iter().map(|&d| d as f64).sum::<f64>() / n.max(1) as f64;
    Figures {
        first_line,
        dispatch: (dispatch * per_count, n),
    }
}

/// The extended image's lines `cw-qemu: extended task NAME: own stack used N bytes`; an
/// error names a malformed one.
fn stacks(log: &str) -> Result<Vec<(String, u64)>> {
    log.lines()
        .filter_map(|l| l.strip_prefix("cw-qemu: extended task "))
        .map(|rest| {
            let bad = || format!("the image's line `extended task {rest}` is malformed");
            let (name, used) = rest.split_once(": own stack used ").ok_or_else(bad)?;
            let bytes = used.strip_suffix(" bytes").ok_or_else(bad)?;
            Ok((name.to_string(), bytes.parse().map_err(|_| bad())?))
        })
        .collect()
}

impl Structures {
    /// Both runs' figures; `schedule` is the basic image's task set (the same slots and
    /// releases in both).
    pub(super) fn measure(
        basic: &ImageRun,
        extended: &ImageRun,
        schedule: &Schedule,
    ) -> Result<Self> {
        Ok(Self {
            basic: figures(basic, schedule),
            extended: figures(extended, schedule),
            stacks: stacks(&extended.log)?,
        })
    }
}

/// The checks: both structures measured for the same numbers of alarms due, every figure
/// finite and positive, every extended task's stack reported.
pub(super) fn check(s: &Structures) -> Result {
    let due = |f: &Figures| f.first_line.iter().map(|b| b.0).collect::<Vec<_>>();
    if due(&s.basic) != due(&s.extended) || s.basic.first_line.is_empty() {
        return Err(format!(
            "eval: the task structures were measured for different alarms due: basic {:?}, extended {:?}",
            due(&s.basic),
            due(&s.extended)
        ));
    }
    for (name, f) in [("basic", &s.basic), ("extended", &s.extended)] {
        let ok = f
            .first_line
            .iter()
            .map(|b| b.1)
            .chain([f.dispatch.0])
            .all(|x| x.is_finite() && x > 0.0);
        if !ok || f.dispatch.1 == 0 {
            return Err(format!(
                "eval: the {name} tasks' figures are not all measured: {f:?}"
            ));
        }
    }
    if s.stacks.is_empty() {
        return Err("eval: the extended image reported no task's own stack".into());
    }
    Ok(())
}

/// The report's section.
pub(super) fn markdown(s: &Structures, md: &mut String) {
    let _ = writeln!(
        md,
        "\n## The paper's task structure beside the ECU's\n\n\
         The ECU's periodic tasks are basic tasks their alarms activate: each job is the \
         task's dispatch from its first line, ended by `TerminateTask`, on the one stack the \
         basic tasks share. The paper's (the loops of its `Rte.c`) are extended tasks that \
         wait for the event their alarm sets: `WaitEvent`, `ClearEvent`, the job, \
         `WaitEvent` again, each on its own stack. The image runs both ways over the same \
         scenario and duration (the second built with the feature `extended-tasks`: the \
         setting \"extended tasks\" in the table above), and each run's job records give what \
         the structure costs, in the image's instructions (marks included, the same in \
         both):\n"
    );
    let _ = writeln!(
        md,
        "| | basic tasks (the ECU) | extended tasks (the paper) |\n|---|---|---|"
    );
    for (b, e) in s.basic.first_line.iter().zip(&s.extended.first_line) {
        let _ = writeln!(
            md,
            "| a millisecond to the first line of its first job, {} alarms due (mean) | {:.0} ({} ticks) | {:.0} ({} ticks) |",
            b.0, b.1, b.2, e.1, e.2
        );
    }
    let _ = writeln!(
        md,
        "| a job's end to the next job's first line (mean) | {:.0} ({} dispatches) | {:.0} ({} dispatches) |",
        s.basic.dispatch.0, s.basic.dispatch.1, s.extended.dispatch.0, s.extended.dispatch.1
    );
    let stacks: Vec<String> = s
        .stacks
        .iter()
        .map(|(name, used)| format!("`{name}` {used} B"))
        .collect();
    let _ = writeln!(
        md,
        "\nThe first figure holds the tick's ISR with its alarms (an activation each, or an \
         event set) and the switch to the first job; the second, the end of one job \
         (`TerminateTask`, or the next `WaitEvent`) and the switch to the next; for the \
         extended tasks both also hold the `ClearEvent` between the wait's return and the \
         job's first line. The extended \
         tasks' own stacks, deepest use: {} (2,048 B each in this image, its 256-byte guard included; the basic tasks \
         share one).\n",
        stacks.join(", ")
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stack_lines_are_read_and_a_bad_one_is_named() {
        let log = "cw-qemu: extended task OsLEDTask: own stack used 412 bytes\n\
                   cw-qemu: end at 8002 ms\n";
        assert_eq!(stacks(log).unwrap(), [("OsLEDTask".to_string(), 412)]);
        let bad = "cw-qemu: extended task OsLEDTask: own stack used many bytes\n";
        assert!(stacks(bad).unwrap_err().contains("malformed"));
    }

    fn figures(first: &[(usize, f64, usize)], dispatch: f64) -> Figures {
        Figures {
            first_line: first.to_vec(),
            dispatch: (dispatch, 3),
        }
    }

    #[test]
    fn structures_measured_differently_or_not_at_all_fail_the_check() {
        let good = Structures {
            basic: figures(&[(2, 400.0, 5), (4, 700.0, 2)], 500.0),
            extended: figures(&[(2, 450.0, 5), (4, 760.0, 2)], 520.0),
            stacks: vec![("OsLEDTask".into(), 400)],
        };
        assert!(check(&good).is_ok());
        let mut md = String::new();
        markdown(&good, &mut md);
        assert!(md.contains("| 400 (5 ticks) | 450 (5 ticks) |"), "{md}");
        let mut other = good.clone();
        other.extended.first_line.pop();
        assert!(check(&other).unwrap_err().contains("different alarms due"));
        let mut zero = good.clone();
        zero.basic.dispatch = (0.0, 0);
        assert!(check(&zero).unwrap_err().contains("basic"));
        let mut none = good;
        none.stacks.clear();
        assert!(check(&none).unwrap_err().contains("own stack"));
    }
}
