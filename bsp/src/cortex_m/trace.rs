//! The task trace of the Cortex-M port: every job's start and end and every category-2
//! ISR's entry, time-stamped in microseconds, kept in RAM and read by the board at the
//! end of a run.
//!
//! Three records, each updated inside a short interrupt lock:
//!
//! - per task: jobs run, how often a job of it was preempted, the longest span of one job
//!   from its first to its last line (preemptions included);
//! - per pair: how often a job of one task started on top of a running job of another
//!   (preemption), and how often an ISR interrupted each task or the idle loop;
//! - the first [`EVENTS`] events in order, for reading the schedule itself (an ISR entry
//!   is listed when it interrupts a task; entries in the idle loop are only counted).
//!
//! - named spans the application marks ([`span_start`], [`span_end`]): count, sum,
//!   shortest and longest, for the instruction counts of the ECU's own paths.
//!
//! Spans and jobs are net of the ISRs that interrupt them: the application names the
//! spans that are ISRs ([`set_isr_spans`]), the trace sums what each ISR span took
//! itself (its nested ISRs taken off in turn), and every span or job subtracts what ISRs
//! took while it was open. A path's figure is then its own instructions, not its own
//! plus whichever interrupt happened to arrive (an ISR's row counts those). Only the
//! few instructions of an exception's entry before its span starts (the handler's
//! prologue, the vector's call) stay in the span it interrupted; so does an ISR the
//! application marks no span for (the category-1 `SensorRxIsr`).
//!
//! Times are SysTick counts since the OS started (the OS tick count times the counts per
//! tick, plus SysTick's progress into the current tick), so they need no peripheral beyond
//! the core's own (DWT's cycle counter reads 0 in QEMU). On QEMU's mps2-an386 under the
//! runs' `-icount shift=5` ([`crate::icount`]) one count (40 ns at 25 MHz) is 1.25
//! instructions (32 ns each): a single span is known to about one instruction.

use core::cell::UnsafeCell;

use cortex_m::peripheral::{SCB, SYST};

use super::MAX_TASKS;

/// Whether the trace records: cw-bsp's feature `trace` (the measuring images). Without it
/// the port's and the drivers' marks are nothing (they test this constant before reading
/// the time), so a production image carries neither the trace's code nor its RAM.
pub const ENABLED: bool = cfg!(feature = "trace");

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
pub const SPANS: usize = 12;

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
    /// The time from a job's first line to its last (preempting jobs included, ISRs
    /// not), counts.
    pub span: SpanRecord,
}

/// The lengths of one kind of span, in SysTick counts.
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
    /// The start of each span under way.
    open: [Option<(u32, u32)>; SPANS],
    /// The jobs in progress, innermost last (basic tasks nest in LIFO order), with their
    /// start times and `isr_counts` then.
    stack: [(u8, u32, u32); MAX_TASKS],
    depth: usize,
    /// Bit `id`: span `id` is an ISR's.
    isr_spans: u32,
    /// Counts spent in ISR spans so far, each net of the ISRs nested in it (wrapping).
    isr_counts: u32,
}

/// An unused slot: all zero bits, so the trace starts in `.bss` (no flash image).
const NO_EVENT: Event = Event {
    at: 0,
    kind: EventKind::JobStart(0),
};

impl Trace {
    const fn new() -> Self {
        Self {
            tasks: [TaskRecord {
                jobs: 0,
                preempted: 0,
                span: SpanRecord::EMPTY,
            }; MAX_TASKS],
            preemptions: [[0; MAX_TASKS]; MAX_TASKS],
            isr_over: [[0; MAX_TASKS + 1]; MAX_ISRS],
            events: [NO_EVENT; EVENTS],
            events_len: 0,
            events_dropped: 0,
            spans: [SpanRecord::EMPTY; SPANS],
            counts_per_ms: 0,
            open: [None; SPANS],
            stack: [(0, 0, 0); MAX_TASKS],
            depth: 0,
            isr_spans: 0,
            isr_counts: 0,
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
            .map(|&(t, _, _)| t)
    }

    fn job_started(&mut self, task: u8, at_us: u32) {
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
        if let Some(slot) = self.stack.get_mut(self.depth) {
            *slot = (task, at_us, self.isr_counts);
            self.depth += 1;
        }
        self.log(at_us, EventKind::JobStart(task));
    }

    fn job_finished(&mut self, task: u8, at_us: u32) {
        if self.running() == Some(task) {
            self.depth -= 1;
            let (start, isr_before) = self
                .stack
                .get(self.depth)
                .map_or((at_us, self.isr_counts), |&(_, s, i)| (s, i));
            let length = self.net(start, isr_before, at_us);
            if let Some(r) = self.tasks.get_mut(usize::from(task)) {
                r.span.add(length);
            }
        }
        self.log(at_us, EventKind::JobEnd(task));
    }

    /// The counts from `start` to `end`, less what ISRs took meanwhile (`isr_before`:
    /// `isr_counts` at `start`).
    fn net(&self, start: u32, isr_before: u32, end: u32) -> u32 {
        let gross = end.wrapping_sub(start);
        gross.saturating_sub(self.isr_counts.wrapping_sub(isr_before))
    }

    /// Span `started` ends at `at`; its length is filed under span `id`.
    fn span_end_as(&mut self, started: usize, id: usize, at: u32) {
        let Some((start, isr_before)) = self.open.get_mut(started).and_then(Option::take) else {
            return;
        };
        let length = self.net(start, isr_before, at);
        if let Some(record) = self.spans.get_mut(id) {
            record.add(length);
        }
        if self.isr_spans & (1 << id) != 0 {
            self.isr_counts = self.isr_counts.wrapping_add(length);
        }
    }

    fn isr_entered(&mut self, isr: u8, at_us: u32) {
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
}

struct TraceCell(UnsafeCell<Trace>);

// SAFETY: reached only inside `with`, under an interrupt lock, on a single core.
unsafe impl Sync for TraceCell {}

static TRACE: TraceCell = TraceCell(UnsafeCell::new(Trace::new()));

fn with<R>(f: impl FnOnce(&mut Trace) -> R) -> R {
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are off for the closure, and `with` is never called from
        // inside `f`, so this is the only reference to the trace.
        f(unsafe { &mut *TRACE.0.get() })
    })
}

/// SysTick counts since the OS started: the whole ticks, plus how far SysTick has counted
/// into the current one (a tick that is due but not yet handled counts). Wraps after
/// 2^32 counts (171 s at 25 MHz): spans are differences of two such times.
pub fn now() -> u32 {
    let (whole, into, per_tick) = systick_position();
    (whole as u32).wrapping_mul(per_tick).wrapping_add(into)
}

/// Where SysTick stands: (whole ticks, counts into the current tick, counts per tick),
/// read together with the port's millisecond count inside one critical section (a tick
/// that is due but not yet handled counts).
pub fn systick_position() -> (u64, u32, u32) {
    cortex_m::interrupt::free(|_| {
        let ms = super::now_ms_masked();
        let reload = SYST::get_reload();
        let current = SYST::get_current();
        let due = SCB::is_pendst_pending();
        // A wrap not yet counted: the SysTick interrupt is pending (held by the lock).
        let whole = if due { ms.wrapping_add(1) } else { ms };
        // The counter runs reload, .., 1, 0: reaching 0 is the tick (its interrupt), and
        // it reloads one count later. So 0 is the start of the tick `ms` counts.
        let into = (reload + 1 - current.min(reload)) % (reload + 1);
        (whole, into, reload + 1)
    })
}

/// Forgets the events logged so far (after a calibration), keeping the records.
pub fn clear_events() {
    with(|t| {
        t.events_len = 0;
        t.events_dropped = 0;
    });
}

/// Notes SysTick's counts per tick (at start).
pub(crate) fn set_counts_per_ms(counts: u32) {
    with(|t| t.counts_per_ms = counts);
}

/// Names the spans that are ISRs (bit `id` for span `id`): what they take is taken off
/// every span and job they interrupt.
pub fn set_isr_spans(mask: u32) {
    with(|t| t.isr_spans = mask);
}

/// Span `id` starts at `at` (a start while one is open restarts it).
pub fn span_start(id: usize, at: u32) {
    with(|t| {
        let isr_counts = t.isr_counts;
        if let Some(slot) = t.open.get_mut(id) {
            *slot = Some((at, isr_counts));
        }
    });
}

/// Span `id` ends at `at` (nothing if it was not started), net of the ISRs that
/// interrupted it.
pub fn span_end(id: usize, at: u32) {
    with(|t| t.span_end_as(id, id, at));
}

/// Span `started` ends at `at` (nothing if it was not started) and its length, net of
/// the ISRs that interrupted it, is filed under span `id`.
pub fn span_end_as(started: usize, id: usize, at: u32) {
    with(|t| t.span_end_as(started, id, at));
}

/// A job of `task` starts, at `at` (counts).
pub(crate) fn job_started(task: u8, at: u32) {
    with(|t| t.job_started(task, at));
}

/// The job of `task` ends, at `at` (counts).
pub(crate) fn job_finished(task: u8, at: u32) {
    with(|t| t.job_finished(task, at));
}

/// Category-2 ISR `isr` was entered, at `at` (counts).
pub fn isr_entered(isr: u8, at: u32) {
    with(|t| t.isr_entered(isr, at));
}

/// Reads the trace (under the interrupt lock: keep `f` short of anything slow, or call
/// it once the run is over).
pub fn read<R>(f: impl FnOnce(&Trace) -> R) -> R {
    with(|t| f(t))
}
