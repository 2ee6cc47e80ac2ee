//! The task trace's records, independent of the CPU: every job's start and end and every
//! category-2 ISR's entry, time-stamped by the CPU's port (`crate::cortex_m::trace` keeps
//! one in RAM under an interrupt lock and reads the time from SysTick).
//!
//! Four records, each updated by the port inside a short interrupt lock:
//!
//! - per task: jobs run, how often a job of it was preempted, the span of its jobs from
//!   the first line to the last (preemptions included);
//! - per pair: how often a job of one task started on top of a running job of another
//!   (preemption), and how often an ISR interrupted each task or the idle loop;
//! - the first [`EVENTS`] events in order, for reading the schedule itself (an ISR entry
//!   is listed when it interrupts a task; entries in the idle loop are only counted);
//! - named spans the application marks ([`Trace::span_start`], [`Trace::span_end_as`]):
//!   count, sum, shortest and longest, for the instruction counts of the ECU's own paths.
//!
//! Spans and jobs are net of the ISRs that interrupt them: the application names the
//! spans that are ISRs ([`Trace::set_isr_spans`]), the trace sums what each ISR span took
//! itself (its nested ISRs taken off in turn), and every span or job subtracts what ISRs
//! took while it was open. A path's figure is then its own instructions, not its own
//! plus whichever interrupt happened to arrive (an ISR's row counts those). Only the
//! few instructions of an exception's entry before its span starts (the handler's
//! prologue, the vector's call) stay in the span it interrupted; so does an ISR the
//! application marks no span for (the category-1 `SensorRxIsr`).
//!
//! Spans and jobs are also net of the trace's own marks made while they were open: a
//! span nested in another, a job's start and end marks inside a span, an ISR's entry
//! mark, and an ISR span's marks themselves. Each kind of mark's whole cost, as a span
//! around it sees it, is measured once before the OS starts ([`MarkCosts`], set by
//! [`Trace::calibrated`]); every mark adds its cost to a running sum that every open span
//! and job subtracts, as they subtract the ISRs. What is left of a span's own two marks (the
//! part of each on the span's side of its time stamp, [`MarkCosts::span_inside`]) the
//! report takes off.
//!
//! Times are counts of the CPU's clock, in the units the port's time stamps have (SysTick
//! counts on the Cortex-M port); lengths are kept in sixteenths of a count
//! ([`PER_COUNT`]).

use super::preempt::MAX_TASKS;

/// Events kept in order from the start of the run.
pub const EVENTS: usize = 64;
/// ISRs traced (by `IsrId`).
pub const MAX_ISRS: usize = 4;
/// The row and column of the idle loop in [`Trace::isr_over`].
pub const IDLE_ROW: usize = MAX_TASKS;

/// What happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// A job of this task started.
    JobStart(u8),
    /// The job of this task ended.
    JobEnd(u8),
    /// This ISR was entered.
    Isr(u8),
}

/// Spans the application can mark.
pub const SPANS: usize = 14;

/// The unit of every length the trace keeps: a sixteenth of a SysTick count, so that a
/// mark's cost, measured as a mean, is taken off to a fraction of an instruction.
pub const PER_COUNT: u32 = crate::icount::SIXTEENTHS as u32;

/// What each kind of mark costs, in sixteenths of a SysTick count, as a span open around
/// it sees it (all of the mark: reading the time, the record). Measured by the
/// application before the OS starts ([`Trace::calibrated`]); zero until then.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MarkCosts {
    /// A span's start mark.
    pub span_start: u32,
    /// A span's end mark.
    pub span_end: u32,
    /// A job's start mark.
    pub job_start: u32,
    /// A job's end mark.
    pub job_end: u32,
    /// An ISR's entry mark.
    pub isr_entered: u32,
    /// What a span's own two marks leave inside it: an empty span's length. The report
    /// takes it off every span, and the trace off every ISR span's length before that
    /// length is taken off the spans and jobs the ISR interrupted (whose running sum of
    /// marks already holds the ISR span's two marks whole).
    pub span_inside: u32,
    /// What a job's own two marks leave inside it: an empty job's length.
    pub job_inside: u32,
}

/// One event and its time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Event {
    /// SysTick counts since the OS started.
    pub at: u32,
    /// What happened.
    pub kind: EventKind,
}

/// What a task's jobs did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TaskRecord {
    /// Jobs started.
    pub jobs: u32,
    /// Jobs of this task that another task's job preempted (counted once per preemption).
    pub preempted: u32,
    /// The time from a job's first line to its last (preempting jobs included, ISRs and
    /// the trace's marks not).
    pub span: SpanRecord,
    /// The same less the jobs that preempted it: what the job executed itself.
    pub own: SpanRecord,
}

/// The lengths of one kind of span, in sixteenths of a SysTick count ([`PER_COUNT`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SpanRecord {
    /// Spans measured.
    pub count: u32,
    /// Their sum.
    pub sum: u64,
    /// The shortest.
    pub min: u32,
    /// The longest.
    pub max: u32,
}

impl SpanRecord {
    const EMPTY: Self = Self {
        count: 0,
        sum: 0,
        min: 0,
        max: 0,
    };

    fn add(&mut self, length: u32) {
        self.min = if self.count == 0 {
            length
        } else {
            self.min.min(length)
        };
        self.max = self.max.max(length);
        self.count = self.count.saturating_add(1);
        self.sum = self.sum.saturating_add(u64::from(length));
    }
}

/// The whole trace.
#[derive(Debug)]
pub struct Trace {
    /// Per task.
    pub tasks: [TaskRecord; MAX_TASKS],
    /// `preemptions[by][over]`: jobs of task `by` that started on top of a job of `over`.
    pub preemptions: [[u16; MAX_TASKS]; MAX_TASKS],
    /// `isr_over[isr][task]`: entries of `isr` while `task` ran (`IDLE_ROW`: idle).
    pub isr_over: [[u32; MAX_TASKS + 1]; MAX_ISRS],
    /// The first events, in order.
    pub events: [Event; EVENTS],
    /// How many of `events` are filled.
    pub events_len: usize,
    /// Events after the first `EVENTS` (counted, not kept).
    pub events_dropped: u32,
    /// The application's spans.
    pub spans: [SpanRecord; SPANS],
    /// SysTick counts per OS tick (ms), to convert.
    pub counts_per_ms: u32,
    /// What each kind of mark costs (zero until [`Trace::calibrated`]).
    pub costs: MarkCosts,
    /// The start of each span under way.
    open: [Option<Open>; SPANS],
    /// The jobs in progress, innermost last (basic tasks nest in LIFO order), with their
    /// starts.
    stack: [(u8, Open); MAX_TASKS],
    depth: usize,
    /// Bit `id`: span `id` is an ISR's.
    isr_spans: u32,
    /// Sixteenths of a count spent in ISR spans so far, each net of the ISRs and marks
    /// nested in it and of its own marks (wrapping).
    isr_counts: u32,
    /// Sixteenths of a count that the marks made so far cost (wrapping).
    marks: u32,
    /// Sixteenths of a count that the jobs ended so far executed themselves (wrapping).
    jobs_own: u32,
}

/// Where a span or job started: its time stamp (counts), and the ISRs' and the marks'
/// running sums then.
#[derive(Debug, Clone, Copy)]
struct Open {
    at: u32,
    isr_counts: u32,
    marks: u32,
    jobs_own: u32,
}

const NOT_OPEN: Open = Open {
    at: 0,
    isr_counts: 0,
    marks: 0,
    jobs_own: 0,
};

/// An unused slot: all zero bits, so the trace starts in `.bss` (no flash image).
const NO_EVENT: Event = Event {
    at: 0,
    kind: EventKind::JobStart(0),
};

impl Trace {
    /// An empty trace (costs zero until [`Trace::calibrated`]).
    pub const fn new() -> Self {
        Self {
            tasks: [TaskRecord {
                jobs: 0,
                preempted: 0,
                span: SpanRecord::EMPTY,
                own: SpanRecord::EMPTY,
            }; MAX_TASKS],
            preemptions: [[0; MAX_TASKS]; MAX_TASKS],
            isr_over: [[0; MAX_TASKS + 1]; MAX_ISRS],
            events: [NO_EVENT; EVENTS],
            events_len: 0,
            events_dropped: 0,
            spans: [SpanRecord::EMPTY; SPANS],
            counts_per_ms: 0,
            costs: MarkCosts {
                span_start: 0,
                span_end: 0,
                job_start: 0,
                job_end: 0,
                isr_entered: 0,
                span_inside: 0,
                job_inside: 0,
            },
            open: [None; SPANS],
            stack: [(0, NOT_OPEN); MAX_TASKS],
            depth: 0,
            isr_spans: 0,
            isr_counts: 0,
            marks: 0,
            jobs_own: 0,
        }
    }

    /// A span or job starts now, at `at`, after its own start mark's cost (`cost`) was
    /// added: the marks it will take off are the later ones.
    fn open(&mut self, at: u32, cost: u32) -> Open {
        self.marks = self.marks.wrapping_add(cost);
        Open {
            at,
            isr_counts: self.isr_counts,
            marks: self.marks,
            jobs_own: self.jobs_own,
        }
    }

    fn log(&mut self, at: u32, kind: EventKind) {
        match self.events.get_mut(self.events_len) {
            Some(slot) => {
                *slot = Event { at, kind };
                self.events_len += 1;
            }
            None => self.events_dropped = self.events_dropped.saturating_add(1),
        }
    }

    /// The job running now (innermost), if any.
    fn running(&self) -> Option<u8> {
        self.depth
            .checked_sub(1)
            .and_then(|i| self.stack.get(i))
            .map(|&(t, _)| t)
    }

    /// A job of `task` starts at `at_us` (counts).
    pub fn job_started(&mut self, task: u8, at_us: u32) {
        let t = usize::from(task);
        if let Some(over) = self.running() {
            let over = usize::from(over);
            if let Some(cell) = self.preemptions.get_mut(t).and_then(|r| r.get_mut(over)) {
                *cell = cell.saturating_add(1);
            }
            if let Some(r) = self.tasks.get_mut(over) {
                r.preempted = r.preempted.saturating_add(1);
            }
        }
        if let Some(r) = self.tasks.get_mut(t) {
            r.jobs = r.jobs.saturating_add(1);
        }
        let open = self.open(at_us, self.costs.job_start);
        if let Some(slot) = self.stack.get_mut(self.depth) {
            *slot = (task, open);
            self.depth += 1;
        }
        self.log(at_us, EventKind::JobStart(task));
    }

    /// The job of `task` ends at `at_us` (counts).
    pub fn job_finished(&mut self, task: u8, at_us: u32) {
        if self.running() == Some(task) {
            self.depth -= 1;
            let open = self.stack.get(self.depth).map(|&(_, open)| open);
            let length = open.map_or(0, |open| self.net(open, at_us));
            // What the jobs that ended inside it executed themselves (theirs nested in
            // turn are in their own figures once).
            let preempting = open.map_or(0, |open| self.jobs_own.wrapping_sub(open.jobs_own));
            let own = length.saturating_sub(preempting);
            self.jobs_own = self.jobs_own.wrapping_add(own);
            if let Some(r) = self.tasks.get_mut(usize::from(task)) {
                r.span.add(length);
                r.own.add(own);
            }
        }
        self.marks = self.marks.wrapping_add(self.costs.job_end);
        self.log(at_us, EventKind::JobEnd(task));
    }

    /// The length from `open` to `end` in sixteenths of a count, less what ISRs and the
    /// marks took meanwhile.
    fn net(&self, open: Open, end: u32) -> u32 {
        let gross = end.wrapping_sub(open.at).saturating_mul(PER_COUNT);
        gross
            .saturating_sub(self.isr_counts.wrapping_sub(open.isr_counts))
            .saturating_sub(self.marks.wrapping_sub(open.marks))
    }

    /// Span `started` ends at `at` (nothing if it was not started); its length, net of
    /// the ISRs and marks meanwhile, is filed under span `id`.
    pub fn span_end_as(&mut self, started: usize, id: usize, at: u32) {
        if let Some(open) = self.open.get_mut(started).and_then(Option::take) {
            let length = self.net(open, at);
            if let Some(record) = self.spans.get_mut(id) {
                record.add(length);
            }
            if self.isr_spans & (1 << id) != 0 {
                // The ISR span's own marks are in `marks` whole: what they left inside
                // its length is not the ISR's.
                let own = length.saturating_sub(self.costs.span_inside);
                self.isr_counts = self.isr_counts.wrapping_add(own);
            }
        }
        self.marks = self.marks.wrapping_add(self.costs.span_end);
    }

    /// Category-2 ISR `isr` was entered, at `at_us` (counts).
    pub fn isr_entered(&mut self, isr: u8, at_us: u32) {
        self.marks = self.marks.wrapping_add(self.costs.isr_entered);
        let over = self.running().map_or(IDLE_ROW, usize::from);
        if let Some(cell) = self
            .isr_over
            .get_mut(usize::from(isr))
            .and_then(|r| r.get_mut(over))
        {
            *cell = cell.saturating_add(1);
        }
        // The event list keeps the schedule's shape: ISR entries in idle are counted only.
        if over != IDLE_ROW {
            self.log(at_us, EventKind::Isr(isr));
        }
    }

    /// Span `id` starts at `at` (a start while one is open restarts it).
    pub fn span_start(&mut self, id: usize, at: u32) {
        let open = self.open(at, self.costs.span_start);
        if let Some(slot) = self.open.get_mut(id) {
            *slot = Some(open);
        }
    }

    /// Takes span `id`'s record so far, leaving it empty (for the calibration's phases).
    pub fn take_span(&mut self, id: usize) -> SpanRecord {
        self.spans
            .get_mut(id)
            .map(core::mem::take)
            .unwrap_or_default()
    }

    /// Takes the record of task slot `task`'s jobs so far, leaving it empty.
    pub fn take_jobs(&mut self, task: u8) -> SpanRecord {
        self.tasks
            .get_mut(usize::from(task))
            .map(|r| core::mem::take(&mut r.span))
            .unwrap_or_default()
    }

    /// Names the spans that are ISRs (bit `id` for span `id`): what they take is taken
    /// off every span and job they interrupt.
    pub fn set_isr_spans(&mut self, mask: u32) {
        self.isr_spans = mask;
    }

    /// The marks' costs are measured: every mark from now on adds its own, and every
    /// record, count and event so far (the calibration's) is forgotten.
    pub fn calibrated(&mut self, costs: MarkCosts) {
        // In place: the trace is too large for a copy on the stack.
        for r in &mut self.tasks {
            *r = TaskRecord::default();
        }
        for row in &mut self.preemptions {
            row.fill(0);
        }
        for row in &mut self.isr_over {
            row.fill(0);
        }
        self.events_len = 0;
        self.events_dropped = 0;
        self.spans.fill(SpanRecord::EMPTY);
        self.open.fill(None);
        self.depth = 0;
        self.isr_counts = 0;
        self.marks = 0;
        self.jobs_own = 0;
        self.costs = costs;
    }
}

/// The record of job starts and ends a measuring image writes for the evaluation (`cargo
/// xtask eval`: the paper's Table 1 from the starts, the measured response times from
/// both): one 32-bit word per start or end, the task's slot in the top four bits, whether
/// it is an end in the next, and the time stamp (counts since the OS started) in the low
/// [`job_record::TIME_BITS`]. The image writes the words little-endian to a host file;
/// [`job_record::Unwrapper`] gives the times back in full.
pub mod job_record {
    use super::MAX_TASKS;

    /// Bits of the time stamp a record keeps: at the Cortex-M port's 25 MHz SysTick they
    /// wrap after 5.4 s, and every periodic task starts a job at least every 40 ms, so two
    /// records in a row are never half that far apart ([`Unwrapper`]).
    pub const TIME_BITS: u32 = 27;
    /// The time stamp's bits.
    pub const TIME_MASK: u32 = (1 << TIME_BITS) - 1;
    /// The bit that marks a job's end.
    pub const END: u32 = 1 << TIME_BITS;
    /// Where the task's slot starts.
    const TASK_SHIFT: u32 = TIME_BITS + 1;

    // Every task slot fits in the bits above the end bit.
    const _: () = assert!(MAX_TASKS <= 1 << (32 - TASK_SHIFT));

    /// The record of a job of task slot `task` that started (or, if `end`, ended) at `at`
    /// (counts).
    #[inline(always)]
    pub const fn encode(task: u8, end: bool, at: u32) -> u32 {
        (task as u32) << TASK_SHIFT | if end { END } else { 0 } | at & TIME_MASK
    }

    /// One record read back.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct JobEdge {
        /// The task's slot.
        pub task: u8,
        /// Whether the job ended here (else it started).
        pub end: bool,
        /// The time stamp in full: counts since the OS started.
        pub at: u64,
    }

    /// Reads records in the order they were written, each time stamp unwrapped against
    /// the one before it (the first is taken as it is): counts since the OS started. Two
    /// records in a row may be out of order by less than half the stamp's range (a job's
    /// mark reads the time before it takes the lock that puts the record on the ring, so
    /// an interrupt between the two lets a later job's record in first): a step of half
    /// the range or more is read as backwards. Ahead, two records in a row must be less
    /// than half the range apart (2.7 s at 25 MHz).
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
    pub struct Unwrapper {
        last: Option<u64>,
    }

    /// Half the time stamp's range: the longest step read as ahead.
    pub const HALF: u32 = 1 << (TIME_BITS - 1);

    impl Unwrapper {
        /// A reader before the first record.
        pub const fn new() -> Self {
            Self { last: None }
        }

        /// The next record, its time stamp in full (a step back before the first record's
        /// time is read as that time).
        pub fn next(&mut self, word: u32) -> JobEdge {
            let low = word & TIME_MASK;
            let at = match self.last {
                None => u64::from(low),
                Some(last) => {
                    let ahead = low.wrapping_sub(last as u32) & TIME_MASK;
                    if ahead < HALF {
                        last + u64::from(ahead)
                    } else {
                        last.saturating_sub(u64::from((1 << TIME_BITS) - ahead))
                    }
                }
            };
            self.last = Some(at);
            JobEdge {
                task: (word >> TASK_SHIFT) as u8,
                end: word & END != 0,
                at,
            }
        }
    }

    /// The contract: records of job starts and ends at times `first`, then each `steps`
    /// later (a step of either sign, less than [`HALF`] long; a step back that would go
    /// before `first` is taken ahead), read back give every task, edge and time in full,
    /// counted from `first`'s low bits.
    pub fn round_trip(first: u32, edges: &[(u8, bool, i32)]) -> bool {
        let mut reader = Unwrapper::new();
        let first_edge = reader.next(encode(0, false, first));
        if first_edge
            != (JobEdge {
                task: 0,
                end: false,
                at: u64::from(first & TIME_MASK),
            })
        {
            return false;
        }
        let (mut at, mut expected) = (first, first_edge.at);
        edges.iter().all(|&(task, end, step)| {
            let task = task % MAX_TASKS as u8;
            let mut step = i64::from(step) % i64::from(HALF);
            if i64::try_from(expected).map_or(true, |e| e + step < 0) {
                step = -step;
            }
            at = at.wrapping_add(step as u32);
            expected = expected.wrapping_add(step as u64);
            reader.next(encode(task, end, at))
                == JobEdge {
                    task,
                    end,
                    at: expected,
                }
        })
    }
}

impl Default for Trace {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests;
