//! The Cortex-M port's task trace: one [`Trace`] in RAM, reached under an interrupt lock,
//! its times SysTick counts since the OS started (the OS tick count times the counts per
//! tick, plus SysTick's progress into the current tick), so they need no peripheral
//! beyond the core's own (DWT's cycle counter reads 0 in QEMU). The board reads it at the
//! end of a run. What the records keep, and how spans and jobs are net of the ISRs and of
//! the trace's own marks: [`crate::port::trace`].
//!
//! On QEMU's mps2-an386 under the runs' `-icount shift=5` ([`crate::icount`]) one count
//! (40 ns at 25 MHz) is 1.25 instructions (32 ns each): a single span is known to about
//! one instruction.

use core::cell::UnsafeCell;

use cortex_m::peripheral::{SCB, SYST};

use crate::port::preempt::Mark;
pub use crate::port::trace::{
    job_record, Event, EventKind, MarkCosts, SpanRecord, TaskRecord, Trace, EVENTS, IDLE_ROW,
    MAX_ISRS, PER_COUNT, SPANS,
};
use crate::ring::{RingStats, WordRing};

/// Whether the trace records: cw-bsp's feature `trace` (the measuring images). Without it
/// the port's and the drivers' marks are nothing (they test this constant before reading
/// the time), so a production image carries neither the trace's code nor its RAM.
pub const ENABLED: bool = cfg!(feature = "trace");

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

/// Notes SysTick's counts per tick (at start).
pub(crate) fn set_counts_per_ms(counts: u32) {
    with(|t| t.counts_per_ms = counts);
}

/// Names the spans that are ISRs ([`Trace::set_isr_spans`]).
pub fn set_isr_spans(mask: u32) {
    with(|t| t.set_isr_spans(mask));
}

/// A mark of the port's or the application's, time-stamped now. The mark goes out of
/// line as one word in a register ([`MarkWord`]), a constant where the mark is (one
/// instruction to load it), and the time is read inside: every call site's mark leaves
/// the same instructions on either side of its time stamp, so the calibration's costs
/// ([`MarkCosts`]) are every mark's. (A mark passed as itself went through a copy on the
/// stack, which the calibration's repeated marks half reused: a span measured about 2
/// instructions more than it executed.)
#[inline(always)]
pub fn mark(mark: Mark) {
    mark_word(MarkWord::of(mark));
}

// Every kind of mark, with the largest numbers the trace keeps, comes back from its word
// as it went in (the trace's tables: 16 task slots, 4 ISRs, 14 spans).
const _: () = {
    let mut kind = 0;
    while kind <= MarkWord::SPAN_END_AS {
        let word = MarkWord::new(
            kind,
            255,
            if kind == MarkWord::SPAN_END_AS { 13 } else { 0 },
        );
        assert!(MarkWord::of(word.mark()).0 == word.0);
        kind += 1;
    }
};

/// [`mark`]'s out-of-line part.
#[inline(never)]
fn mark_word(word: MarkWord) {
    let at = now();
    match word.mark() {
        Mark::JobStarted(t) => job_started(t.0, at),
        Mark::JobFinished(t) => job_finished(t.0, at),
        Mark::IsrEntered(i) => isr_entered(i.0, at),
        Mark::SpanStart(id) => span_start(id, at),
        Mark::SpanEnd(id) => span_end(id, at),
        Mark::SpanEndAs { started, id } => span_end_as(started, id, at),
    }
}

/// A [`Mark`] in one word: its kind in bits 16 and up, its first number (the task, the
/// ISR, the span) in bits 8-15 and the span it is filed under in bits 0-7. Every number a
/// mark carries fits in a byte (the trace's tables are smaller; a larger one is cut to
/// its low byte, which the trace's bounds checks then refuse or file elsewhere).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct MarkWord(u32);

impl MarkWord {
    const JOB_STARTED: u32 = 0;
    const JOB_FINISHED: u32 = 1;
    const ISR_ENTERED: u32 = 2;
    const SPAN_START: u32 = 3;
    const SPAN_END: u32 = 4;
    const SPAN_END_AS: u32 = 5;

    #[inline(always)]
    const fn new(kind: u32, first: usize, second: usize) -> Self {
        Self(kind << 16 | (first as u32 & 0xFF) << 8 | second as u32 & 0xFF)
    }

    #[inline(always)]
    const fn of(mark: Mark) -> Self {
        match mark {
            Mark::JobStarted(t) => Self::new(Self::JOB_STARTED, t.0 as usize, 0),
            Mark::JobFinished(t) => Self::new(Self::JOB_FINISHED, t.0 as usize, 0),
            Mark::IsrEntered(i) => Self::new(Self::ISR_ENTERED, i.0 as usize, 0),
            Mark::SpanStart(id) => Self::new(Self::SPAN_START, id, 0),
            Mark::SpanEnd(id) => Self::new(Self::SPAN_END, id, 0),
            Mark::SpanEndAs { started, id } => Self::new(Self::SPAN_END_AS, started, id),
        }
    }

    #[inline(always)]
    const fn mark(self) -> Mark {
        let first = (self.0 >> 8 & 0xFF) as u8;
        let second = (self.0 & 0xFF) as usize;
        match self.0 >> 16 {
            Self::JOB_STARTED => Mark::JobStarted(cw_core::os::TaskId(first)),
            Self::JOB_FINISHED => Mark::JobFinished(cw_core::os::TaskId(first)),
            Self::ISR_ENTERED => Mark::IsrEntered(cw_core::os::IsrId(first)),
            Self::SPAN_START => Mark::SpanStart(first as usize),
            Self::SPAN_END => Mark::SpanEnd(first as usize),
            _ => Mark::SpanEndAs {
                started: first as usize,
                id: second,
            },
        }
    }
}

/// Span `id` starts at `at` ([`Trace::span_start`]).
pub fn span_start(id: usize, at: u32) {
    with(|t| t.span_start(id, at));
}

/// Takes span `id`'s record so far ([`Trace::take_span`]).
pub fn take_span(id: usize) -> SpanRecord {
    with(|t| t.take_span(id))
}

/// Takes the record of task slot `task`'s jobs so far ([`Trace::take_jobs`]).
pub fn take_jobs(task: u8) -> SpanRecord {
    with(|t| t.take_jobs(task))
}

/// The marks' costs are measured ([`Trace::calibrated`]); the calibration's job records
/// are taken off the ring.
pub fn calibrated(costs: MarkCosts) {
    with(|t| t.calibrated(costs));
    while JOB_RECORDS.pop().is_some() {}
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

/// The job starts and ends not yet taken by the image ([`take_job_record`]): the
/// evaluation's record of them ([`job_record`]), for the paper's Table 1 and the measured
/// response times. The producers are the job-start and job-end marks, under the trace's
/// interrupt lock (a job that preempts another's mark waits for it); the consumer is the
/// image's idle loop, without a lock. 1,024 words: the idle loop runs every millisecond,
/// and a millisecond starts and ends at most a handful of jobs.
static JOB_RECORDS: WordRing<1024> = WordRing::new();

/// A job of `task` starts, at `at` (counts). Out of line, so that the ring's code leaves
/// the other marks' code in [`mark_word`] as it was.
#[inline(never)]
pub(crate) fn job_started(task: u8, at: u32) {
    with(|t| {
        t.job_started(task, at);
        // (A full ring counts the record as dropped: the image reports it.)
        let _ = JOB_RECORDS.push(job_record::encode(task, false, at));
    });
}

/// The job of `task` ends, at `at` (counts). Out of line, as [`job_started`].
#[inline(never)]
pub(crate) fn job_finished(task: u8, at: u32) {
    with(|t| {
        t.job_finished(task, at);
        let _ = JOB_RECORDS.push(job_record::encode(task, true, at));
    });
}

/// The oldest job record not yet taken ([`job_record`]). One context at a time may take
/// them (the ring has one reader).
pub fn take_job_record() -> Option<u32> {
    JOB_RECORDS.pop()
}

/// How many job records wait on the ring (as the producer last left it).
pub fn job_records_waiting() -> u32 {
    JOB_RECORDS.len()
}

/// The job records made since the image started, and those a full ring dropped.
pub fn job_records_stats() -> RingStats {
    JOB_RECORDS.stats()
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
