//! A timing model of this OS's scheduling on one CPU: jobs of tasks and ISRs, each with an
//! execution time, run by fixed priority with full preemption, the earliest released first
//! among equal priorities (OSEK's queue per priority), an item's jobs one after the other
//! in the order of their releases.
//!
//! The evaluation replays the host simulation's releases through it with the execution
//! times measured on the Cortex-M4 image (`cargo xtask eval`), so that a job starts where
//! the jobs and ISRs before it leave the CPU, as on a chip; the response-time analysis
//! ([`super::rta`]) bounds the same schedule. The model is event-driven: [`Timeline::advance`]
//! moves time to the next job's end or to the caller's next release, whichever is first,
//! so a run costs its jobs, not its duration.
//!
//! What it leaves out: sections at a raised priority (a job runs at its item's priority
//! throughout) and the cost of switching between jobs, which a caller adds to the jobs'
//! execution times.

use heapless::Deque;

/// One task or ISR of the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Item {
    /// Its priority on one scale for tasks and ISRs (higher runs first).
    pub priority: u16,
    /// How many of its jobs may be released and not ended at once, the running one
    /// included (a basic task's maximum activations; 2 for an interrupt, one in service and
    /// one pending). Held to the timeline's queue length.
    pub limit: u8,
}

/// A job that ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Job {
    /// Its item, by index.
    pub item: usize,
    /// When it was released.
    pub released: u64,
    /// When it first had the CPU.
    pub started: u64,
    /// When it ended.
    pub ended: u64,
}

/// Why a release was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    /// No item of that index.
    NoItem,
    /// The item has as many jobs released and not ended as its limit allows (OSEK's
    /// `E_OS_LIMIT`): the release is lost, as on the chip.
    Limit,
}

/// A released job not yet ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Pending {
    released: u64,
    started: Option<u64>,
    left: u64,
}

/// The CPU and its released jobs: `N` items, at most `Q` jobs of each released at once.
#[derive(Debug, Clone)]
pub struct Timeline<const N: usize, const Q: usize> {
    items: [Item; N],
    queues: [Deque<Pending, Q>; N],
    now: u64,
    busy: u64,
}

impl<const N: usize, const Q: usize> Timeline<N, Q> {
    /// An idle CPU at time 0.
    pub fn new(items: [Item; N]) -> Self {
        Self {
            items,
            queues: core::array::from_fn(|_| Deque::new()),
            now: 0,
            busy: 0,
        }
    }

    /// The time now.
    pub const fn now(&self) -> u64 {
        self.now
    }

    /// The time the CPU has run jobs so far.
    pub const fn busy(&self) -> u64 {
        self.busy
    }

    /// Jobs of `item` released and not ended (0 for an index outside the set).
    pub fn pending(&self, item: usize) -> usize {
        self.queues.get(item).map_or(0, Deque::len)
    }

    /// Releases a job of `item` now that takes `cost` of CPU time.
    ///
    /// # Errors
    /// [`Refused`]: an index outside the set, or the item at its limit.
    pub fn release(&mut self, item: usize, cost: u64) -> Result<(), Refused> {
        let (limit, queue) = self
            .items
            .iter()
            .zip(self.queues.iter_mut())
            .nth(item)
            .ok_or(Refused::NoItem)?;
        if queue.len() >= usize::from(limit.limit) {
            return Err(Refused::Limit);
        }
        queue
            .push_back(Pending {
                released: self.now,
                started: None,
                left: cost,
            })
            .map_err(|_| Refused::Limit)
    }

    /// The item whose job has the CPU: the highest priority with a job released, the
    /// earliest released among equals, then the lowest index.
    pub fn running(&self) -> Option<usize> {
        let mut best: Option<(usize, u16, u64)> = None;
        for (i, (item, queue)) in self.items.iter().zip(&self.queues).enumerate() {
            if let Some(head) = queue.front() {
                if first(item.priority, head.released, best.map(|b| (b.1, b.2))) {
                    best = Some((i, item.priority, head.released));
                }
            }
        }
        best.map(|(i, _, _)| i)
    }

    /// The running item's index and its jobs.
    fn running_queue(&mut self) -> Option<(usize, &mut Deque<Pending, Q>)> {
        let mut best: Option<(usize, u16, u64, &mut Deque<Pending, Q>)> = None;
        for (i, (item, queue)) in self.items.iter().zip(self.queues.iter_mut()).enumerate() {
            if let Some(released) = queue.front().map(|head| head.released) {
                if first(item.priority, released, best.as_ref().map(|b| (b.1, b.2))) {
                    best = Some((i, item.priority, released, queue));
                }
            }
        }
        best.map(|(i, _, _, queue)| (i, queue))
    }

    /// Runs the CPU from now towards `to`, stopping at the first job that ends on the way:
    /// that job, with the time now at its end. `None` when no job ended before `to`: the
    /// time is then `to` (not moved where `to` is not after now). A job that takes no time
    /// ends as it gets the CPU, so the caller's releases at a time come before it.
    pub fn advance(&mut self, to: u64) -> Option<Job> {
        if to <= self.now {
            return None;
        }
        let now = self.now;
        let Some((item, queue)) = self.running_queue() else {
            self.now = to;
            return None;
        };
        let mut run = 0;
        let ended = queue.pop_front_if(|head| {
            head.started.get_or_insert(now);
            run = head.left.min(to - now);
            head.left -= run;
            head.left == 0
        });
        self.now = now + run;
        self.busy = self.busy.saturating_add(run);
        ended.map(|job| Job {
            item,
            released: job.released,
            started: job.started.unwrap_or(now),
            ended: now + run,
        })
    }
}

/// Whether a job of `priority` released at `released` runs before the best so far
/// (`(priority, released)`): a higher priority, or an earlier release at the same one
/// (the lower index, met first, wins a tie).
fn first(priority: u16, released: u64, best: Option<(u16, u64)>) -> bool {
    best.is_none_or(|(p, r)| priority > p || (priority == p && released < r))
}

/// The model's promises as a named predicate, for the harnesses and the fuzz target.
pub mod spec {
    use super::{Item, Timeline};

    /// Replays `releases` (the time since the previous release, the item, the cost) on four
    /// items, then runs the CPU until every job has ended, and checks what the model
    /// promises: every job ends after it started and was released, by the time it is
    /// reported, with no job of a higher priority waiting; an item's jobs end in the order
    /// of their releases; no item holds more jobs than its limit allows; and, in the end,
    /// nothing is left and the CPU was busy for exactly the costs of the releases accepted.
    /// Items past the fourth are refused.
    pub fn replay_keeps_its_promises(items: &[Item; 4], releases: &[(u32, u8, u32)]) -> bool {
        let mut timeline = Timeline::<4, 2>::new(*items);
        let mut accepted: u64 = 0;
        let mut last_end = [0u64; 4];
        let mut at: u64 = 0;
        let mut ok = true;
        let mut check_job = |timeline: &Timeline<4, 2>, job: super::Job| {
            let priority = items.get(job.item).map_or(0, |i| i.priority);
            let higher_waiting = items
                .iter()
                .enumerate()
                .any(|(h, i)| i.priority > priority && timeline.pending(h) > 0);
            let before = last_end.get(job.item).copied().unwrap_or(0);
            if let Some(e) = last_end.get_mut(job.item) {
                *e = job.released;
            }
            job.released <= job.started
                && job.started <= job.ended
                && job.ended == timeline.now()
                && !higher_waiting
                && job.released >= before
        };
        for &(gap, item, cost) in releases {
            at += u64::from(gap);
            while let Some(job) = timeline.advance(at) {
                ok &= check_job(&timeline, job);
            }
            let item = usize::from(item);
            match timeline.release(item, u64::from(cost)) {
                Ok(()) => accepted += u64::from(cost),
                Err(super::Refused::NoItem) => ok &= item >= 4,
                Err(super::Refused::Limit) => {
                    let limit = items.get(item).map_or(0, |i| usize::from(i.limit.min(2)));
                    ok &= timeline.pending(item) >= limit;
                }
            }
            ok &= (0..4).all(|i| {
                timeline.pending(i) <= items.get(i).map_or(0, |x| usize::from(x.limit.min(2)))
            });
        }
        let horizon = at + accepted + 1;
        while let Some(job) = timeline.advance(horizon) {
            ok &= check_job(&timeline, job);
        }
        ok && (0..4).all(|i| timeline.pending(i) == 0) && timeline.busy() == accepted
    }
}

#[cfg(test)]
mod tests;
