//! Schedulability: a response-time analysis (`cw_core::os::rta`) of the task set the
//! image prints (`cw_firmware::schedulability`: priorities, releases, deadlines, the
//! ceilings each item raises to), with execution times taken from the same run's record
//! of every job's start and end, beside each task's worst response measured from that
//! record.
//!
//! The analysis is of the measuring image itself, so that the measured responses can be
//! held against it: every figure is what the CPU spent there, the trace's marks
//! included. A task's execution time is its longest job from its first line's time stamp
//! to its last's, less the jobs that preempted it (ISRs and kernel calls inside it
//! kept), plus the longest dispatch the run shows (a job's end to the next job's start
//! within one millisecond: the kernel's termination and the next job's start). The tick's
//! is the longest time from a millisecond to the first job it released (its ISR with its
//! alarms, and that job's dispatch); `CanIsr`'s, its longest span with its marks and one
//! dispatch for its entry and return.
//!
//! A measured response runs from the job's release to its last line: for a task its alarm
//! activates, the tick the alarm fell due on (the last multiple of its period from the
//! OS's start, where its alarm expires, at or before the job's start); for a task another
//! task's job activates, that job's release.

use std::fmt::Write as _;

use cw_bsp::port::trace::job_record::JobEdge;
use cw_core::os::rta::{self, Load, Response};

use crate::Result;

/// One task or ISR as the image describes it, with its analysis and what the run
/// measured.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Analysed {
    pub name: String,
    /// The task's slot (`None` for an ISR).
    pub slot: Option<u8>,
    /// `tick`, `event` (an ISR) or the task whose job releases it.
    pub released_by: String,
    /// Instructions, as every figure below; `load.wcet` is the analysis's, `net` the
    /// image's own figure without the marks.
    pub load: Load,
    pub net: u64,
    pub response: Response,
    /// The longest measured response and the jobs measured (tasks only).
    pub measured: Option<(u64, usize)>,
    /// Its execution budget in the ECU's description (`OsTaskExecutionBudget`,
    /// `OsIsrExecutionBudget`), µs: the generator's analysis took it.
    pub budget_us: Option<u64>,
}

/// The analysis.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Schedule {
    /// Instructions per ms.
    pub per_ms: u64,
    pub items: Vec<Analysed>,
    /// The longest dispatch and the tick's figure, instructions.
    pub dispatch: u64,
    pub tick: u64,
}

/// Reads the image's `rta` lines and the marks' costs; an error names the line that is
/// malformed, or says what is missing.
pub(super) fn parse(log: &str) -> Result<Schedule> {
    let mut per_ms = None;
    let mut items = Vec::new();
    for (n, line) in log.lines().enumerate() {
        let Some(rest) = line.strip_prefix("cw-qemu: rta ") else {
            continue;
        };
        let bad = || format!("the image's log, line {}: `{line}` is malformed", n + 1);
        let words: Vec<&str> = rest.split_whitespace().collect();
        let number = |w: &str| w.parse::<u64>().map_err(|_| bad());
        let small = |w: &str| w.parse::<u16>().map_err(|_| bad());
        match words.as_slice() {
            ["unit", "instructions,", ms, "per", "ms"] => per_ms = Some(number(ms)?),
            [name, "slot", slot, "released-by", by, "priority", priority, "raises-to", raises, "period", period, "deadline", deadline, "wcet", wcet] =>
            {
                let slot: u8 = slot.parse().map_err(|_| bad())?;
                let net = number(wcet)?;
                items.push(Analysed {
                    name: (*name).to_string(),
                    slot: (slot != u8::MAX).then_some(slot),
                    released_by: (*by).to_string(),
                    load: Load {
                        priority: small(priority)?,
                        period: number(period)?,
                        jitter: 0,
                        wcet: net,
                        deadline: number(deadline)?,
                        section: net,
                        raises_to: small(raises)?,
                    },
                    net,
                    response: Response::NoPeriod,
                    measured: None,
                    budget_us: None,
                });
            }
            _ => return Err(bad()),
        }
    }
    let per_ms = per_ms
        .filter(|&m| m > 0)
        .ok_or("the image's log has no `rta unit` line")?;
    if items.is_empty() {
        return Err("the image's log has no `rta` line of a task or ISR".into());
    }
    Ok(Schedule {
        per_ms,
        items,
        dispatch: 0,
        tick: 0,
    })
}

/// The marks of an ISR span (its start, its end, the ISR's entry mark), instructions, from
/// the image's calibration line.
pub(super) fn isr_marks(log: &str) -> Result<u64> {
    let line = log
        .lines()
        .find_map(|l| l.strip_prefix("cw-qemu: marks seen from a span around them"))
        .ok_or("the image's log has no calibration line (`marks seen from a span around them`)")?;
    let words: Vec<&str> = line.split_whitespace().collect();
    let after = |key: &[&str]| {
        words
            .windows(key.len() + 1)
            .find(|w| w[..key.len()] == *key)
            .and_then(|w| w[key.len()].trim_end_matches(',').parse::<u64>().ok())
    };
    match (
        after(&["span", "start"]),
        after(&["end"]),
        after(&["ISR", "entry"]),
    ) {
        (Some(a), Some(b), Some(c)) => Ok(a + b + c),
        _ => Err(format!(
            "the image's calibration line is malformed: `{line}`"
        )),
    }
}

/// Each job's and each gap's time in the job records, in counts.
#[derive(Debug, Default, PartialEq, Eq)]
pub(super) struct JobTimes {
    /// Each job's time from its first line to its last, less the jobs that preempted it,
    /// with its task, in the order the jobs ended.
    pub(super) own: Vec<(u8, u64)>,
    /// Each dispatch within a millisecond: a job's end to the start of the next job a tick
    /// released.
    pub(super) dispatch: Vec<u64>,
    /// Each millisecond (its index) whose tick released a job while the CPU was idle, and
    /// the time from the millisecond to that job's start.
    pub(super) tick: Vec<(u64, u64)>,
}

/// The times of [`JobTimes`] in the job records (times in counts, `counts_per_ms` to a
/// millisecond). `tick_released` names the tasks an alarm releases (only their jobs start
/// at a dispatch). Records may be out of order by a little (a mark reads the time before
/// it takes the lock that puts its record on the ring): a nested job counts only for its
/// part inside its outer job, and a gap that comes out negative is no sample.
pub(super) fn job_times(records: &[JobEdge], counts_per_ms: u32, tick_released: &[u8]) -> JobTimes {
    let cpm = u64::from(counts_per_ms.max(1));
    // Open jobs: (task, start, the jobs that ended inside it: (start, end)).
    type Open = (u8, u64, Vec<(u64, u64)>);
    let mut open: Vec<Open> = Vec::new();
    let mut times = JobTimes::default();
    let mut previous: Option<&JobEdge> = None;
    for r in records {
        if r.end {
            if let Some(pos) = open.iter().rposition(|(t, _, _)| *t == r.task) {
                let (task, start, nested) = open.remove(pos);
                // Each nested job's part between this job's start and its end.
                let inside: u64 = nested
                    .iter()
                    .map(|&(s, e)| e.min(r.at).saturating_sub(s.max(start)))
                    .sum();
                let own = r.at.saturating_sub(start).saturating_sub(inside);
                if let Some(outer) = open.last_mut() {
                    outer.2.push((start, r.at));
                }
                times.own.push((task, own));
            }
        } else {
            let boundary = r.at / cpm * cpm;
            // Only a job its tick released starts at a dispatch: one another job releases
            // starts where that job's own code put it.
            if tick_released.contains(&r.task) {
                match previous {
                    Some(p) if p.end && p.at >= boundary => {
                        if let Some(gap) = r.at.checked_sub(p.at) {
                            times.dispatch.push(gap);
                        }
                    }
                    Some(p) if p.end && open.is_empty() && p.at < boundary => {
                        times.tick.push((boundary / cpm, r.at - boundary));
                    }
                    _ => {}
                }
            }
            open.push((r.task, r.at, Vec::new()));
        }
        previous = Some(r);
    }
    times
}

/// From the job records ([`job_times`]), converted at `per_ms` instructions per ms: each
/// task's longest job less the jobs that preempted it, the longest dispatch within a
/// millisecond, and the longest time from a millisecond to the first job it released
/// while the CPU was idle.
pub(super) fn demands(
    records: &[JobEdge],
    counts_per_ms: u32,
    per_ms: u64,
    tick_released: &[u8],
) -> (Vec<(u8, u64)>, u64, u64) {
    let cpm = u64::from(counts_per_ms.max(1));
    let to_instructions = |counts: u64| (counts * per_ms).div_ceil(cpm);
    let times = job_times(records, counts_per_ms, tick_released);
    let mut gross: Vec<(u8, u64)> = Vec::new();
    for &(task, own) in &times.own {
        match gross.iter_mut().find(|(t, _)| *t == task) {
            Some(g) => g.1 = g.1.max(own),
            None => gross.push((task, own)),
        }
    }
    (
        gross
            .into_iter()
            .map(|(t, g)| (t, to_instructions(g)))
            .collect(),
        to_instructions(times.dispatch.into_iter().max().unwrap_or(0)),
        to_instructions(times.tick.into_iter().map(|t| t.1).max().unwrap_or(0)),
    )
}

/// The latencies of [`JobTimes::tick`] by the number of alarms due at each tick (the
/// tick-released tasks of `periodic`, `(slot, name, cycle in ms)`, whose cycle divides its
/// millisecond): `(alarms, latencies)`, fewest alarms first.
pub(super) fn by_alarms_due(
    ticks: &[(u64, u64)],
    periodic: &[(u8, String, u32)],
    tick_released: &[u8],
) -> Vec<(usize, Vec<u64>)> {
    let cycles: Vec<u64> = periodic
        .iter()
        .filter(|(slot, _, cycle)| tick_released.contains(slot) && *cycle > 0)
        .map(|(_, _, cycle)| u64::from(*cycle))
        .collect();
    let mut by_due: Vec<(usize, Vec<u64>)> = Vec::new();
    for &(ms, latency) in ticks {
        let n = cycles.iter().filter(|&&c| ms % c == 0).count();
        match by_due.iter_mut().find(|(k, _)| *k == n) {
            Some(b) => b.1.push(latency),
            None => by_due.push((n, vec![latency])),
        }
    }
    by_due.sort_by_key(|b| b.0);
    by_due
}

impl Schedule {
    /// Each item's execution budget from the ECU's description (`ecu`, read from
    /// `source`), where the generator's analysis took it.
    ///
    /// # Errors
    /// An item of the image's task set without one: the description's analysis left it out.
    pub(super) fn budgets(&mut self, ecu: &cw_gen::model::Ecu, source: &str) -> Result {
        for item in &mut self.items {
            let timing = ecu
                .os
                .tasks
                .iter()
                .find(|t| t.name == item.name)
                .and_then(|t| t.timing.as_ref())
                .or_else(|| {
                    ecu.os
                        .isrs
                        .iter()
                        .find(|i| i.name == item.name)
                        .and_then(|i| i.timing.as_ref())
                });
            item.budget_us = timing.and_then(|t| t.budget_us);
            if item.budget_us.is_none() {
                return Err(format!(
                    "eval: {} has no execution budget in {source}: the description's analysis of the task set leaves out an item the image runs",
                    item.name
                ));
            }
        }
        Ok(())
    }

    /// `us` in the image's instructions (rounded down: a budget is an upper bound).
    pub(super) fn instructions(&self, us: u64) -> u64 {
        us.saturating_mul(self.per_ms) / 1000
    }

    /// The slots of the tasks an alarm releases.
    pub(super) fn tick_released(&self) -> Vec<u8> {
        self.items
            .iter()
            .filter(|i| i.released_by == "tick")
            .filter_map(|i| i.slot)
            .collect()
    }

    /// The analysis with the run's figures ([`demands`]; `CanIsr` and any other ISR: its
    /// longest span, `isr_marks` and one dispatch), then each task's worst measured
    /// response.
    pub(super) fn analyse(
        &mut self,
        records: &[JobEdge],
        counts_per_ms: u32,
        isr_marks: u64,
    ) -> Result {
        let tick_released = self.tick_released();
        let (gross, dispatch, tick) = demands(records, counts_per_ms, self.per_ms, &tick_released);
        self.dispatch = dispatch;
        self.tick = tick;
        for item in &mut self.items {
            let wcet = match item.slot {
                Some(slot) => gross
                    .iter()
                    .find(|(t, _)| *t == slot)
                    .map_or(0, |&(_, g)| g + dispatch),
                None if item.released_by == "event" && item.load.period == self.per_ms => tick,
                None => item.net + isr_marks + dispatch,
            };
            item.load.wcet = wcet;
            item.load.section = wcet;
        }
        let mut set: Vec<Load> = self.items.iter().map(|i| i.load).collect();
        let released_by: Vec<(usize, usize)> = self
            .items
            .iter()
            .enumerate()
            .filter_map(|(i, item)| {
                let by = self.items.iter().position(|o| o.name == item.released_by)?;
                Some((i, by))
            })
            .collect();
        // The kernel's lock: one section any item may wait for (every category-2 ISR
        // masked), as long as the longest dispatch, which runs under it.
        set.push(Load {
            priority: 0,
            period: u64::MAX,
            jitter: 0,
            wcet: 0,
            deadline: u64::MAX,
            section: dispatch,
            raises_to: u16::MAX,
        });
        let settled = rta::settle_jitter(&mut set, &released_by);
        for (i, item) in self.items.iter_mut().enumerate() {
            item.response = rta::response_time(&set, i);
            if let Some(l) = set.get(i) {
                item.load = *l;
            }
        }
        if !settled && self.items.iter().all(|i| i.response.meets()) {
            return Err(
                "eval: the release jitters of the tasks another task releases did not settle"
                    .into(),
            );
        }
        self.measure(records, counts_per_ms);
        Ok(())
    }

    /// Each task's worst measured response time, from the job records (times in counts,
    /// `counts_per_ms` to a millisecond), converted to instructions at `per_ms` per ms.
    fn measure(&mut self, records: &[JobEdge], counts_per_ms: u32) {
        let cpm = u64::from(counts_per_ms.max(1));
        let slot_of = |name: &str| {
            self.items
                .iter()
                .find(|i| i.name == name)
                .and_then(|i| i.slot)
        };
        // Per slot: the releaser (None: its alarm), and its period in counts (its alarm's
        // releases fall on the multiples of it from the OS's start: the alarms are set
        // relative to it, their first expiry one period on).
        let releaser: Vec<(u8, Option<u8>, u64)> = self
            .items
            .iter()
            .filter_map(|i| {
                let by = match i.released_by.as_str() {
                    "tick" => None,
                    other => Some(slot_of(other)?),
                };
                let period = (i.load.period * cpm / self.per_ms).max(1);
                Some((i.slot?, by, period))
            })
            .collect();
        let slots = 1 + releaser
            .iter()
            .map(|&(s, _, _)| usize::from(s))
            .max()
            .unwrap_or(0);
        let mut open: Vec<Option<u64>> = vec![None; slots];
        let mut last: Vec<Option<u64>> = vec![None; slots];
        let mut worst: Vec<(u64, usize)> = vec![(0, 0); slots];
        for r in records {
            let s = usize::from(r.task);
            let Some(&(_, by, period)) = releaser.iter().find(|&&(slot, _, _)| slot == r.task)
            else {
                continue;
            };
            if !r.end {
                let release = match by {
                    None => Some(r.at / period * period),
                    Some(b) => last.get(usize::from(b)).copied().flatten(),
                };
                if let (Some(o), Some(l)) = (open.get_mut(s), last.get_mut(s)) {
                    *o = release;
                    *l = release;
                }
            } else if let Some(release) = open.get_mut(s).and_then(Option::take) {
                if let Some(w) = worst.get_mut(s) {
                    w.0 = w.0.max(r.at.saturating_sub(release));
                    w.1 += 1;
                }
            }
        }
        let per_ms = self.per_ms;
        for item in &mut self.items {
            if let Some(&(counts, jobs)) = item.slot.and_then(|s| worst.get(usize::from(s))) {
                let instructions = (counts * per_ms).div_ceil(cpm);
                item.measured = (jobs > 0).then_some((instructions, jobs));
            }
        }
    }
}

/// The analysis's own checks: every item analysed and meeting its deadline, every task
/// measured, no measured response above the analysed one, and no item's execution above
/// its budget in the ECU's description. An error names the item.
pub(super) fn check(s: &Schedule) -> Result {
    for item in &s.items {
        // (The run's figures come with every item's budget: `Schedule::budgets`; the unit
        // tests' logs have none.)
        if let Some(budget) = item.budget_us {
            let allowed = s.instructions(budget);
            if item.load.wcet > allowed {
                return Err(format!(
                    "eval: {}'s execution on the image, {} instructions ({} ms), is above its budget in {}, {budget} µs ({allowed} instructions): the description's analysis of the task set does not hold",
                    item.name,
                    item.load.wcet,
                    ms(item.load.wcet, s.per_ms),
                    cw_gen::DESCRIPTION
                ));
            }
        }
        let response = match item.response {
            Response::NoPeriod => {
                return Err(format!(
                    "eval: {} cannot be analysed (no period for it or an item above it)",
                    item.name
                ))
            }
            Response::Misses { at_least, blocking } => {
                return Err(format!(
                    "eval: the task set is not schedulable: {}'s worst-case response time is at least {at_least} instructions, past its deadline of {} ({} ms); its own execution {}, its blocking {blocking}",
                    item.name,
                    item.load.deadline,
                    ms(item.load.deadline, s.per_ms),
                    item.load.wcet,
                ))
            }
            Response::Meets { response, .. } => response,
        };
        if item.slot.is_some() {
            match item.measured {
                None => {
                    return Err(format!(
                        "eval: {} ran no whole job in the run: its response time was not measured",
                        item.name
                    ))
                }
                Some((measured, _)) if measured > response => {
                    return Err(format!(
                        "eval: {}'s measured response time, {measured} instructions, is above the analysed worst case, {response}: the analysis misses a cost",
                        item.name
                    ))
                }
                Some(_) => {}
            }
        }
    }
    Ok(())
}

/// `instructions` at `per_ms` per ms, in ms.
fn ms(instructions: u64, per_ms: u64) -> String {
    format!("{:.4}", instructions as f64 / per_ms.max(1) as f64)
}

/// The report's section.
pub(super) fn markdown(s: &Schedule, md: &mut String) {
    let _ = writeln!(
        md,
        "\n## Schedulability (response-time analysis)\n\n\
         The image prints its task set at the end of the run \
         (`cw_firmware::schedulability`: priorities, releases, deadlines, the ceilings each \
         item raises to), and `cw_core::os::rta` analyses it: fixed priorities, full \
         preemption, ISRs above every task, the ceilings' blocking (a job waits for at most \
         one lower section, bounded here by that item's whole execution: the sections are \
         not measured one by one) and release jitter. `OsComTask` is released by the sonar \
         job's write, as late as that job's end; `CanIsr` once per distance frame the ECU \
         sends (its transmit confirmation, at the sonar's period). The frames the ECU \
         receives (the tester's thresholds) are not in the analysis: their rate is the \
         tester's and the run receives none; at the bus's worst, one accepted frame every \
         158 µs, the measuring image's CAN ISR (which writes each event as an SLCAN line to \
         a UART: {} instructions) would not keep up.\n\n\
         The analysis is of the measuring image, so that each task's worst response \
         measured in the same run can be held against it: every execution time is what the \
         CPU spent there, from the run's record of every job's start and end, the trace's \
         marks included. A task's: its longest job from its first line to its last, less the \
         jobs that preempted it, plus the longest dispatch seen (a job's end to the next \
         job's start within a millisecond: {} instructions). The tick's: the longest time \
         from a millisecond to the first job it released with the CPU idle before it ({} \
         instructions: the ISR with its alarms, and that job's dispatch). `CanIsr`'s: its longest span with its marks and \
         one dispatch for its entry and return. The image's own figures without the marks \
         (its jobs' and ISRs' net instructions, as the production image runs them) are in \
         the \"net\" column. A measured response runs from the release (the tick the \
         alarm fell due on: the last multiple of its period, or the activator's release) to \
         the job's last line. The \"budget\" column is each item's execution budget in the \
         ECU's description (`OsTaskExecutionBudget`, `OsIsrExecutionBudget`, with which \
         `cargo xtask generate` analysed the task set before generating it), in the image's \
         instructions: the check fails where the execution analysed here exceeds it. Figures in \
         the image's instructions ({} per ms under QEMU's `-icount shift=5`), times in ms of \
         that virtual clock.\n",
        s.items
            .iter()
            .find(|i| i.name == "CanIsr")
            .map_or(0, |i| i.net),
        s.dispatch,
        s.tick,
        s.per_ms
    );
    let _ = writeln!(
        md,
        "| item | priority | released by | period (ms) | net | execution analysed | budget | blocking | jitter | analysed worst response | deadline | measured worst response (jobs) | |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for i in &s.items {
        let measured = i.measured.map_or("-".to_string(), |(m, jobs)| {
            format!("{m} = {} ms ({jobs})", ms(m, s.per_ms))
        });
        let (response, blocking, verdict) = match i.response {
            Response::Meets { response, blocking } => (
                format!("{response} = {} ms", ms(response, s.per_ms)),
                blocking.to_string(),
                "meets",
            ),
            Response::Misses { at_least, blocking } => (
                format!("at least {at_least}"),
                blocking.to_string(),
                "misses",
            ),
            Response::NoPeriod => ("-".into(), "-".into(), "-"),
        };
        let budget = i.budget_us.map_or("-".to_string(), |us| {
            format!("{} = {us} µs", s.instructions(us))
        });
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ms | {} | {} |",
            i.name,
            i.load.priority,
            i.released_by,
            ms(i.load.period, s.per_ms),
            i.net,
            i.load.wcet,
            budget,
            blocking,
            i.load.jitter,
            response,
            ms(i.load.deadline, s.per_ms),
            measured,
            verdict
        );
    }
    let _ = writeln!(
        md,
        "\nThe check command runs the same analysis on its short run and fails, naming the \
         item, when an item misses its deadline, a measured response exceeds the analysed \
         one, or an execution exceeds its budget. The paper gives no schedulability analysis; its Table 1 shows periods, not \
         response times.\n"
    );
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// An image's calibration and `rta` lines.
    pub(in crate::eval) const LOG: &str = "cw-qemu: marks seen from a span around them (calibration, taken off every span and job they fall in): span start 59 end 110, job start 116 end 199, ISR entry 80\n\
        cw-qemu: rta unit instructions, 31250 per ms\n\
        cw-qemu: rta OsLEDTask slot 1 released-by tick priority 6 raises-to 6 period 312500 deadline 312500 wcet 100\n\
        cw-qemu: rta OsComTask slot 4 released-by OsSonarTask priority 3 raises-to 65 period 1250000 deadline 1250000 wcet 300\n\
        cw-qemu: rta OsSonarTask slot 5 released-by tick priority 2 raises-to 6 period 1250000 deadline 1250000 wcet 1700\n\
        cw-qemu: rta SysTickIsr slot 255 released-by event priority 66 raises-to 66 period 31250 deadline 31250 wcet 600\n\
        cw-qemu: rta CanIsr slot 255 released-by event priority 65 raises-to 65 period 4937 deadline 4937 wcet 1400\n";

    fn edge(task: u8, end: bool, at: u64) -> JobEdge {
        JobEdge { task, end, at }
    }

    /// 25,000 counts per ms (a count is 40 ns, 1.25 instructions at 31,250 per ms): the
    /// sonar (5) released at 40 ms, the LED task (1) preempting it, the sonar's job
    /// releasing OsComTask (4); then the LED task alone at 50 ms; the LED task and the
    /// sonar at 80 ms.
    fn records() -> Vec<JobEdge> {
        let ms = 25_000;
        vec![
            edge(5, false, 40 * ms + 500),
            edge(1, false, 40 * ms + 1_000),
            edge(1, true, 40 * ms + 1_200),
            edge(4, false, 40 * ms + 2_000),
            edge(4, true, 40 * ms + 3_000),
            edge(5, true, 40 * ms + 4_000),
            edge(1, false, 50 * ms + 100),
            edge(1, true, 50 * ms + 200),
            edge(1, false, 80 * ms + 100),
            edge(1, true, 80 * ms + 200),
            edge(5, false, 80 * ms + 260),
            edge(5, true, 80 * ms + 300),
        ]
    }

    #[test]
    fn the_images_task_set_is_read_and_a_bad_line_is_named() {
        let s = parse(LOG).unwrap();
        assert_eq!(s.per_ms, 31_250);
        assert_eq!(s.items.len(), 5);
        assert_eq!(s.items[1].released_by, "OsSonarTask");
        assert_eq!(s.items[3].slot, None);
        assert_eq!(s.items[1].load.raises_to, 65);
        assert_eq!(isr_marks(LOG), Ok(59 + 110 + 80));
        let bad = LOG.replace("wcet 300", "wcet x");
        assert!(parse(&bad).unwrap_err().contains("line 4"));
        assert!(parse("").unwrap_err().contains("rta unit"));
        assert!(isr_marks("").is_err());
    }

    #[test]
    fn ticks_are_grouped_by_the_alarms_due() {
        // The LED task (slot 1, 10 ms) and the sonar (5, 40 ms) released by the tick;
        // OsComTask (4) by the sonar's job: not an alarm.
        let periodic = vec![
            (1, "OsLEDTask".to_string(), 10),
            (4, "OsComTask".to_string(), 0),
            (5, "OsSonarTask".to_string(), 40),
        ];
        let ticks = [(10, 100), (40, 300), (20, 120), (80, 310)];
        assert_eq!(
            by_alarms_due(&ticks, &periodic, &[1, 5]),
            [(1, vec![100, 120]), (2, vec![300, 310])]
        );
    }

    #[test]
    fn the_demands_come_from_the_records() {
        let (gross, dispatch, tick) = demands(&records(), 25_000, 31_250, &[1, 5]);
        // The sonar: 3,500 counts less the LED job's 200 and OsComTask's 1,000.
        let of = |t: u8| gross.iter().find(|g| g.0 == t).map(|g| g.1);
        assert_eq!(of(5), Some(2_300 * 5 / 4));
        assert_eq!(of(1), Some(200 * 5 / 4));
        // Dispatch: the LED job's end at 80 ms + 200 to the sonar's start, 60 counts
        // (OsComTask's start, which the sonar's job makes, is none).
        assert_eq!(dispatch, 60 * 5 / 4);
        // The tick: 100 counts from 50 ms (and from 80 ms) to the LED job's start, the CPU
        // idle before (the first record has nothing before it to tell).
        assert_eq!(tick, 100 * 5 / 4);
    }

    #[test]
    fn responses_run_from_the_tick_or_from_the_activators_release() {
        let mut s = parse(LOG).unwrap();
        s.analyse(&records(), 25_000, isr_marks(LOG).unwrap())
            .unwrap();
        let measured = |name: &str| s.items.iter().find(|i| i.name == name).unwrap().measured;
        // The LED task: 1,200 counts after its tick at 40 ms, then 200 twice.
        assert_eq!(measured("OsLEDTask"), Some((1_200 * 5 / 4, 3)));
        // OsComTask from the sonar's release (the 40 ms tick), not from its own start.
        assert_eq!(measured("OsComTask"), Some((3_000 * 5 / 4, 1)));
        assert_eq!(measured("OsSonarTask"), Some((4_000 * 5 / 4, 2)));
        assert_eq!(measured("SysTickIsr"), None);
        // OsComTask's jitter is the sonar's analysed response.
        let com = &s.items[1];
        assert_eq!(Some(com.load.jitter), s.items[2].response.time());
        assert_eq!(check(&s), Ok(()));
    }

    #[test]
    fn a_miss_or_a_measurement_above_the_analysis_fails_naming_the_item() {
        let mut s = parse(LOG).unwrap();
        s.analyse(&records(), 25_000, isr_marks(LOG).unwrap())
            .unwrap();
        assert_eq!(check(&s), Ok(()));
        let mut late = s.clone();
        late.items[2].measured = Some((u64::MAX, 3));
        let error = check(&late).unwrap_err();
        assert!(error.contains("OsSonarTask's measured response"), "{error}");
        let mut missed = s.clone();
        missed.items[1].response = Response::Misses {
            at_least: 2_000_000,
            blocking: 0,
        };
        assert!(check(&missed)
            .unwrap_err()
            .contains("OsComTask's worst-case"));
        // An execution above its budget in the description.
        let mut over = s.clone();
        over.items[0].budget_us = Some(1);
        let error = check(&over).unwrap_err();
        assert!(
            error.contains("OsLEDTask's execution on the image")
                && error.contains("1 µs (31 instructions)"),
            "{error}"
        );
        let mut unmeasured = s;
        unmeasured.items[0].measured = None;
        assert!(check(&unmeasured)
            .unwrap_err()
            .contains("OsLEDTask ran no whole job"));
    }
}
