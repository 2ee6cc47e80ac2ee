//! Table 1's first setting: the host simulation in virtual time, its jobs taking the times
//! the Cortex-M4 image measured.
//!
//! The host simulation's jobs take no virtual time: it decides what is released when (its
//! alarms, the sonar job's activation of `OsComTask`, the CAN controller's interrupts),
//! and [`cw_core::os::timeline`] gives each release the CPU time the image spent on it,
//! under the OS's priorities with full preemption. The times are the image's, from the
//! same evaluation's run (marks included, as the image ran them):
//! - a task's `k`-th job takes the image's `k`-th job of that task (its own time, less the
//!   jobs that preempted it; the image's jobs in turn where the host has more), plus the
//!   image's mean dispatch (a job's end to the next job's start within a millisecond); its
//!   first line comes after the dispatch;
//! - the tick with `n` alarms due takes the image's mean time from a millisecond to the
//!   first job it released, over the ticks with `n` alarms due, less the dispatch; the tick
//!   with none due its span (`SysTickIsr, nothing due`) with its marks;
//! - `CanIsr` its longest span with its marks;
//! - a task another task's job releases (`OsComTask`) is released at that job's end (on
//!   the image, at its write, near its end); the CAN interrupts come at the host's times
//!   (its bus), not moved by the time the transmitting job took.

use std::collections::{BTreeMap, VecDeque};
use std::fmt::Write as _;
use std::path::Path;

use cw_core::os::timeline::{Item, Timeline};

use super::schedule::{by_alarms_due, job_times, Analysed, Schedule};
use super::{start_rows, ImageRun, StartRow, TaskStarts};
use crate::process::target_dir;
use crate::Result;

/// The most tasks and ISRs the model holds.
const ITEMS: usize = 8;

/// The image's times the model gives its jobs, ns.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Costs {
    /// Per task slot: its jobs' own times, in order.
    own: Vec<(u8, Vec<u64>)>,
    /// The mean dispatch.
    pub(super) dispatch: u64,
    /// The tick with `n` alarms due: `(n, time)`, the dispatch taken off.
    pub(super) tick_due: Vec<(usize, u64)>,
    /// The tick with no alarm due.
    pub(super) tick_idle: u64,
    /// Each ISR other than the tick: its name and time.
    isrs: Vec<(String, u64)>,
}

/// The mean of `samples`, rounded (0 for none).
fn mean(samples: impl Iterator<Item = u64>) -> u64 {
    let (sum, n) = samples.fold((0u128, 0u128), |(s, n), x| (s + u128::from(x), n + 1));
    u64::try_from((sum + n / 2) / n.max(1)).unwrap_or(u64::MAX)
}

/// The image's line `cw-qemu: span NAME: N times, instructions mean X ...`: X.
fn span_mean(log: &str, name: &str) -> Result<u64> {
    let prefix = format!("cw-qemu: span {name}: ");
    let line = log
        .lines()
        .find_map(|l| l.strip_prefix(&prefix))
        .ok_or_else(|| format!("the image's log has no `span {name}` line"))?;
    line.split_whitespace()
        .skip_while(|w| *w != "mean")
        .nth(1)
        .and_then(|w| w.trim_end_matches(',').parse().ok())
        .ok_or_else(|| format!("the image's `span {name}` line is malformed: `{line}`"))
}

impl Costs {
    /// The costs from the image's run and its analysis (its task set, its marks).
    pub(super) fn measure(run: &ImageRun, schedule: &Schedule, isr_marks: u64) -> Result<Self> {
        let cpm = u64::from(run.counts_per_ms.max(1));
        let counts = |c: u64| c * 1_000_000 / cpm;
        let instructions = |i: u64| i * 1_000_000 / schedule.per_ms.max(1);
        let tick_released = schedule.tick_released();
        let times = job_times(&run.records, run.counts_per_ms, &tick_released);
        let mut own: Vec<(u8, Vec<u64>)> = Vec::new();
        for &(task, t) in &times.own {
            match own.iter_mut().find(|(s, _)| *s == task) {
                Some(o) => o.1.push(counts(t)),
                None => own.push((task, vec![counts(t)])),
            }
        }
        let dispatch = counts(mean(times.dispatch.iter().copied()));
        // The number of alarms due at each millisecond: the tick-released periodic tasks
        // whose cycle divides it.
        let by_due = by_alarms_due(&times.tick, &run.periodic, &tick_released);
        let tick_due = by_due
            .into_iter()
            .map(|(n, l)| (n, counts(mean(l.into_iter())).saturating_sub(dispatch)))
            .collect();
        let tick_idle = instructions(span_mean(&run.log, "SysTickIsr, nothing due")? + isr_marks);
        let isrs = schedule
            .items
            .iter()
            .filter(|i| i.slot.is_none() && i.load.period != schedule.per_ms)
            .map(|i| (i.name.clone(), instructions(i.net + isr_marks)))
            .collect();
        Ok(Self {
            own,
            dispatch,
            tick_due,
            tick_idle,
            isrs,
        })
    }
}

/// What the model gave.
#[derive(Debug)]
pub(super) struct Timed {
    /// The periodic tasks' starts (their first lines), ms.
    pub(super) starts: Vec<TaskStarts>,
    /// Releases the model refused (a job of the same item not ended).
    pub(super) refused: u64,
    /// The share of the run the CPU was busy.
    pub(super) load: f64,
}

/// The replay's state.
struct Replay<'a> {
    set: &'a [Analysed],
    costs: &'a Costs,
    timeline: Timeline<ITEMS, 2>,
    /// Per item, its jobs released and not ended, in order: the item each releases at its
    /// end, if any.
    chains: Vec<VecDeque<Option<usize>>>,
    /// Per item, its jobs released so far (and accepted).
    released: [usize; ITEMS],
    /// Per item, its jobs' first lines, ms.
    starts: Vec<Vec<f64>>,
    refused: u64,
}

impl Replay<'_> {
    /// The `k`-th job of task or ISR `i`: its cost.
    fn cost(&self, i: usize, k: usize) -> Result<u64> {
        let a = self.set.get(i).ok_or("eval: no such item")?;
        match a.slot {
            Some(slot) => {
                let own = self
                    .costs
                    .own
                    .iter()
                    .find(|(s, o)| *s == slot && !o.is_empty())
                    .map(|(_, o)| o)
                    .ok_or_else(|| format!("eval: the image measured no job of {}", a.name))?;
                let k = k % own.len();
                Ok(own.get(k).copied().unwrap_or(0) + self.costs.dispatch)
            }
            None => self
                .costs
                .isrs
                .iter()
                .find(|(n, _)| *n == a.name)
                .map(|&(_, c)| c)
                .ok_or_else(|| format!("eval: the image measured no {}", a.name)),
        }
    }

    /// Releases a job of `i` taking `cost` now, which releases `then` at its end.
    fn release(&mut self, i: usize, cost: u64, then: Option<usize>) {
        match self.timeline.release(i, cost) {
            Ok(()) => {
                if let Some(n) = self.released.get_mut(i) {
                    *n += 1;
                }
                if let Some(c) = self.chains.get_mut(i) {
                    c.push_back(then);
                }
            }
            Err(_) => self.refused += 1,
        }
    }

    /// Releases the next job of task or ISR `i` now.
    fn release_job(&mut self, i: usize, then: Option<usize>) -> Result {
        let cost = self.cost(i, self.released.get(i).copied().unwrap_or(0))?;
        self.release(i, cost, then);
        Ok(())
    }

    /// Runs the CPU to `at`: each job that ends notes its first line and releases what it
    /// releases.
    fn run_to(&mut self, at: u64) -> Result {
        while let Some(job) = self.timeline.advance(at) {
            if let Some(s) = self.starts.get_mut(job.item) {
                s.push((job.started + self.costs.dispatch) as f64 / 1e6);
            }
            let then = self
                .chains
                .get_mut(job.item)
                .and_then(VecDeque::pop_front)
                .flatten();
            if let Some(next) = then {
                self.release_job(next, None)?;
            }
        }
        Ok(())
    }
}

/// Replays the host's releases (`rows`, over `duration_ms`) through the image's task set
/// (`schedule`) with `costs`. An error names a task or ISR the image did not measure.
pub(super) fn replay(
    rows: &[StartRow],
    duration_ms: u64,
    schedule: &Schedule,
    costs: &Costs,
) -> Result<Timed> {
    let set = schedule.items.as_slice();
    if set.len() > ITEMS {
        return Err(format!(
            "eval: the task set has {} items, the model at most {ITEMS}",
            set.len()
        ));
    }
    let mut items = [Item {
        priority: 0,
        limit: 0,
    }; ITEMS];
    for (item, a) in items.iter_mut().zip(set) {
        *item = Item {
            priority: a.load.priority,
            // A basic task's one activation; an interrupt in service and one pending.
            limit: if a.slot.is_some() { 1 } else { 2 },
        };
    }
    let index = |name: &str| set.iter().position(|i| i.name == name);
    let tick = set
        .iter()
        .position(|i| i.slot.is_none() && i.load.period == schedule.per_ms)
        .ok_or("eval: the image's task set has no tick (an ISR with a 1 ms period)")?;
    // Events: (µs, item); the alarms due per millisecond; the jobs another's job releases,
    // by (releaser, the releaser's start in µs).
    let mut events: Vec<(u64, usize)> = Vec::with_capacity(rows.len());
    let mut due: BTreeMap<u64, usize> = BTreeMap::new();
    let mut chained: BTreeMap<(usize, u64), (usize, usize)> = BTreeMap::new();
    let mut cycles: Vec<(usize, u32)> = Vec::new();
    // Each item's job starts on the host, for the jobs another's job releases: that job
    // is the releaser's last one started by then (on the host its jobs take no time but
    // their delays, such as the sonar's trigger pulse).
    let mut host_starts: BTreeMap<usize, Vec<u64>> = BTreeMap::new();
    for row in rows {
        if let Some(i) = index(&row.name) {
            host_starts.entry(i).or_default().push(row.at_us);
        }
    }
    for row in rows {
        let Some(i) = index(&row.name) else {
            // The start-up task runs at 0, before the first tick, and is not in the set.
            if row.at_us == 0 {
                continue;
            }
            return Err(format!(
                "eval: line {}: {} is not in the image's task set",
                row.line, row.name
            ));
        };
        if row.cycle_ms > 0 && !cycles.iter().any(|&(c, _)| c == i) {
            cycles.push((i, row.cycle_ms));
        }
        match set.get(i).map_or("", |a| a.released_by.as_str()) {
            "tick" => {
                events.push((row.at_us, i));
                *due.entry(row.at_us / 1000).or_default() += 1;
            }
            "event" => events.push((row.at_us, i)),
            releaser => {
                let r = index(releaser).ok_or_else(|| {
                    format!(
                        "eval: {} is released by {releaser}, not in the set",
                        row.name
                    )
                })?;
                let started = host_starts
                    .get(&r)
                    .and_then(|s| s.iter().rev().find(|&&at| at <= row.at_us))
                    .copied()
                    .ok_or_else(|| {
                        format!(
                            "eval: line {}: {} released by {releaser}, which has not started",
                            row.line, row.name
                        )
                    })?;
                if chained.insert((r, started), (i, row.line)).is_some() {
                    return Err(format!(
                        "eval: line {}: {} released a second time by {releaser}'s job of {started} µs",
                        row.line, row.name
                    ));
                }
            }
        }
    }
    // Every millisecond's tick, first at its time: it releases the rest.
    events.extend((1..=duration_ms).map(|ms| (ms * 1000, tick)));
    events.sort_by_key(|&(at, i)| (at, i != tick, i));
    let mut replay = Replay {
        set,
        costs,
        timeline: Timeline::new(items),
        chains: vec![VecDeque::new(); ITEMS],
        released: [0; ITEMS],
        starts: vec![Vec::new(); ITEMS],
        refused: 0,
    };
    for &(at_us, i) in &events {
        replay.run_to(at_us.saturating_mul(1000))?;
        if i == tick {
            let cost = match due.get(&(at_us / 1000)).copied().unwrap_or(0) {
                0 => costs.tick_idle,
                n => costs
                    .tick_due
                    .iter()
                    .find(|(k, _)| *k == n)
                    .map(|&(_, c)| c)
                    .ok_or_else(|| format!("eval: the image saw no tick with {n} alarms due"))?,
            };
            replay.release(i, cost, None);
        } else {
            let then = chained.remove(&(i, at_us)).map(|(released, _)| released);
            replay.release_job(i, then)?;
        }
    }
    if let Some((&(r, at_us), &(i, line))) = chained.iter().next() {
        return Err(format!(
            "eval: line {line}: {} released by {} at {at_us} µs, where no job of {} was \
             released",
            set.get(i).map_or("?", |a| a.name.as_str()),
            set.get(r).map_or("?", |a| a.name.as_str()),
            set.get(r).map_or("?", |a| a.name.as_str()),
        ));
    }
    let end = duration_ms.saturating_add(1) * 1_000_000;
    replay.run_to(end)?;
    let starts = cycles
        .iter()
        .filter_map(|&(i, cycle_ms)| {
            Some(TaskStarts {
                name: set.get(i)?.name.clone(),
                cycle_ms,
                starts_ms: replay.starts.get(i)?.clone(),
            })
        })
        .collect();
    Ok(Timed {
        starts,
        refused: replay.refused,
        load: replay.timeline.busy() as f64 / end as f64,
    })
}

/// Runs the host simulation in virtual time for `duration_ms` (`cw-ecu --job-starts`) and
/// replays its releases with the image's costs.
pub(super) fn run(
    scenario: &Path,
    duration_ms: u64,
    out: &Path,
    schedule: &Schedule,
    costs: &Costs,
) -> Result<Timed> {
    crate::process::Cmd::new("cargo")
        .args(["build", "--release", "-p", "cw-firmware", "--bin", "cw-ecu"])
        .run()?;
    let ecu = target_dir().join("release").join("cw-ecu");
    let csv = out.join("host-timed-releases.csv");
    let ran = crate::process::Cmd::new(&ecu)
        .arg("--scenario")
        .arg(scenario)
        .arg("--duration")
        .arg(format!("{}", duration_ms as f64 / 1000.0))
        .arg("--job-starts")
        .arg(&csv)
        .capture()?;
    if !ran.success {
        return Err(format!(
            "eval: cw-ecu failed:\n{}{}",
            ran.stdout, ran.stderr
        ));
    }
    let text =
        std::fs::read_to_string(&csv).map_err(|e| format!("reading {}: {e}", csv.display()))?;
    let rows = start_rows(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
    let timed = replay(&rows, duration_ms, schedule, costs)?;
    println!(
        "eval: the host's releases timed with the image's costs: {} periodic tasks, {} releases refused, CPU load {:.2} %",
        timed.starts.len(),
        timed.refused,
        timed.load * 100.0
    );
    Ok(timed)
}

/// The report's paragraph on the setting.
pub(super) fn markdown(costs: &Costs, refused: u64, load: f64, md: &mut String) {
    let us = |ns: u64| format!("{:.3} µs", ns as f64 / 1000.0);
    let ticks: Vec<String> = {
        let mut t = costs.tick_due.clone();
        t.sort_unstable();
        t.iter()
            .map(|&(n, c)| format!("{} with {n} alarms due", us(c)))
            .collect()
    };
    let isrs: Vec<String> = costs
        .isrs
        .iter()
        .map(|(n, c)| format!("`{n}` {}", us(*c)))
        .collect();
    let _ = writeln!(
        md,
        "**The host simulation with the image's times** is the host simulation in virtual time \
         (`cw-ecu --job-starts`), whose jobs take no time, replayed through a timing model of \
         the OS (`cw_core::os::timeline`: fixed priorities, full preemption, the earliest \
         released first among equals) in which every release takes the CPU time the image \
         spent on it in its run: a task's k-th job the image's k-th job of that task (from \
         its first line to its last, less the jobs that preempted it), plus the image's mean \
         dispatch ({}), its first line after the dispatch; the tick {}, and {} with no alarm \
         due; {}. A task another task's job releases (`OsComTask`) is released at that job's \
         end (on the image, at its write, near its end); the CAN interrupts come at the \
         host's times, not moved by the time the transmitting job took. The CPU was busy {:.2} % \
         of the run; {refused} releases found a job of the same task or ISR not ended. The \
         setting shows the schedule that the host's releases and the image's execution times \
         make, without QEMU: where it matches the image's own figures, the model explains \
         them.\n",
        us(costs.dispatch),
        ticks.join(", "),
        us(costs.tick_idle),
        isrs.join(", "),
        load * 100.0,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::schedule::{parse, tests::LOG};

    /// The LED task (1 µs) every 10 ms, the sonar (5 µs, then 6) every 40 released with
    /// it, its job releasing `OsComTask` (2 µs); a dispatch of 0.5 µs; the tick 3 µs with
    /// one alarm due, 4 with two, 0.1 with none; `CanIsr` 7 µs.
    fn costs() -> Costs {
        Costs {
            own: vec![(1, vec![1000]), (4, vec![2000]), (5, vec![5000, 6000])],
            dispatch: 500,
            tick_due: vec![(1, 3000), (2, 4000)],
            tick_idle: 100,
            isrs: vec![("CanIsr".into(), 7000)],
        }
    }

    fn host(can_isr_us: u64) -> Vec<StartRow> {
        let text = format!(
            "task,cycle_ms,virtual_us,wall_ns\n\
             OsStartupTask,0,0,\n\
             OsLEDTask,10,10000,\n\
             OsLEDTask,10,20000,\n\
             OsLEDTask,10,30000,\n\
             OsLEDTask,10,40000,\n\
             OsSonarTask,40,40000,\n\
             OsComTask,0,40000,\n\
             CanIsr,0,{can_isr_us},\n"
        );
        start_rows(&text).unwrap()
    }

    fn starts(timed: &Timed, name: &str) -> Vec<f64> {
        timed
            .starts
            .iter()
            .find(|t| t.name == name)
            .map(|t| t.starts_ms.clone())
            .unwrap()
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    #[test]
    fn the_host_rows_are_read_and_a_bad_line_is_named() {
        assert_eq!(host(40300).len(), 8);
        assert!(start_rows("task\n").unwrap_err().contains("line 1"));
        let bad = "task,cycle_ms,virtual_us,wall_ns\nOsLEDTask,10,x,\n";
        assert!(start_rows(bad).unwrap_err().contains("line 2"));
    }

    #[test]
    fn each_job_starts_after_the_tick_the_dispatch_and_the_jobs_above_it() {
        let schedule = parse(LOG).unwrap();
        let timed = replay(&host(40300), 41, &schedule, &costs()).unwrap();
        assert_eq!(timed.refused, 0);
        // The tick (3 µs with one alarm due, 4 with two), the dispatch, then the first line.
        assert!(close(
            &starts(&timed, "OsLEDTask"),
            &[10.0035, 20.0035, 30.0035, 40.0045]
        ));
        // Below the LED task at 40 ms: after its 1.5 µs.
        assert!(close(&starts(&timed, "OsSonarTask"), &[40.006]));
        // Not periodic: not in Table 1.
        assert!(timed.starts.iter().all(|t| t.name != "OsComTask"));
        // Busy: 41 ticks, 4 LED jobs, the sonar, OsComTask, CanIsr.
        let busy = 3 * 3000 + 4000 + 37 * 100 + 4 * 1500 + 5500 + 2500 + 7000;
        let end = 42_000_000.0;
        assert!((timed.load - f64::from(busy) / end).abs() < 1e-12);
    }

    #[test]
    fn an_interrupt_inside_a_job_delays_its_end_and_what_it_releases() {
        let schedule = parse(LOG).unwrap();
        // (OsComTask starts 10 µs into the sonar's job on the host: the trigger pulse.)
        // CanIsr at 40.010 ms, inside the sonar's job (40.0055 to 40.011 alone).
        let mut costs = costs();
        // OsComTask made periodic for the test, to see its start.
        let rows: Vec<StartRow> = host(40010)
            .into_iter()
            .map(|mut r| {
                if r.name == "OsComTask" {
                    r.cycle_ms = 40;
                    r.at_us = 40010;
                }
                r
            })
            .collect();
        costs.tick_idle = 0;
        let timed = replay(&rows, 41, &schedule, &costs).unwrap();
        // The sonar's job ends 7 µs later, at 40.018; OsComTask is released there.
        assert!(close(&starts(&timed, "OsComTask"), &[40.0185]));
    }

    #[test]
    fn a_job_still_running_at_its_next_release_refuses_it() {
        let schedule = parse(LOG).unwrap();
        let mut costs = costs();
        costs.own[0].1 = vec![15_000_000];
        let timed = replay(&host(40300), 41, &schedule, &costs).unwrap();
        // Each LED job runs 15 ms: the releases at 20 and 40 ms are refused, the one at 30
        // comes after the first job's end (and its job has not ended by the run's).
        assert_eq!(timed.refused, 2);
        assert!(close(&starts(&timed, "OsLEDTask"), &[10.0035]));
    }

    #[test]
    fn a_row_outside_the_set_or_released_by_no_job_is_named() {
        let schedule = parse(LOG).unwrap();
        let mut rows = host(40300);
        rows[2].name = "OsUnknownTask".into();
        let e = replay(&rows, 41, &schedule, &costs()).unwrap_err();
        assert!(e.contains("line 4") && e.contains("OsUnknownTask"), "{e}");
        let mut rows = host(40300);
        // OsComTask at 30 ms: no sonar job had started.
        rows[6].at_us = 30000;
        let e = replay(&rows, 41, &schedule, &costs()).unwrap_err();
        assert!(e.contains("line 8") && e.contains("OsComTask"), "{e}");
        // Two releases of OsComTask by the one sonar job: the second names its line.
        let mut rows = host(40300);
        let mut again = rows[6].clone();
        again.line = 9;
        again.at_us = 40020;
        rows.insert(7, again);
        let e = replay(&rows, 41, &schedule, &costs()).unwrap_err();
        assert!(e.contains("line 9") && e.contains("second time"), "{e}");
    }

    #[test]
    fn a_tick_the_image_never_measured_is_named() {
        let schedule = parse(LOG).unwrap();
        let mut costs = costs();
        costs.tick_due.retain(|&(n, _)| n != 2);
        let e = replay(&host(40300), 41, &schedule, &costs).unwrap_err();
        assert!(e.contains("2 alarms due"), "{e}");
        let mut costs = self::costs();
        costs.own.retain(|&(slot, _)| slot != 5);
        let e = replay(&host(40300), 41, &schedule, &costs).unwrap_err();
        assert!(e.contains("OsSonarTask"), "{e}");
    }

    #[test]
    fn the_image_costs_are_read_from_its_spans() {
        let log = "cw-qemu: span SysTickIsr, nothing due: 7200 times, instructions mean 45 min 45 max 45\n";
        assert_eq!(span_mean(log, "SysTickIsr, nothing due").unwrap(), 45);
        assert!(span_mean(log, "CanIsr (entry to return)").is_err());
        let bad = "cw-qemu: span SysTickIsr, nothing due: 7200 times, instructions mean x\n";
        assert!(span_mean(bad, "SysTickIsr, nothing due")
            .unwrap_err()
            .contains("malformed"));
        assert_eq!(mean([1, 2].into_iter()), 2);
        assert_eq!(mean(std::iter::empty()), 0);
    }
}
