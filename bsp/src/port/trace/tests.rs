//! The trace's arithmetic: what a span and a job are net of.

use super::*;
use std::vec::Vec;

/// Mark costs in counts (the trace keeps sixteenths): start 5, end 9, job start 6, job
/// end 11, ISR entry 7; an empty span 3, an empty job 4.
fn costs() -> MarkCosts {
    let c = |counts: u32| counts * PER_COUNT;
    MarkCosts {
        span_start: c(5),
        span_end: c(9),
        job_start: c(6),
        job_end: c(11),
        isr_entered: c(7),
        span_inside: c(3),
        job_inside: c(4),
    }
}

fn calibrated() -> Trace {
    let mut t = Trace::new();
    t.calibrated(costs());
    t
}

const OUTER: usize = 0;
const INNER: usize = 1;
const ISR: usize = 2;

#[test]
fn a_span_is_net_of_a_span_nested_in_it_but_not_of_its_own_marks() {
    let mut t = calibrated();
    t.span_start(OUTER, 100);
    t.span_start(INNER, 130);
    t.span_end_as(INNER, INNER, 160);
    t.span_end_as(OUTER, OUTER, 300);
    // The inner span: its 30 counts, nothing nested.
    assert_eq!(t.spans[INNER].sum, u64::from(30 * PER_COUNT));
    // The outer: 200 counts less the inner span's two marks whole (5 + 9).
    assert_eq!(t.spans[OUTER].sum, u64::from((200 - 14) * PER_COUNT));
    assert_eq!(t.spans[OUTER].count, 1);
}

#[test]
fn an_isr_span_is_taken_off_whole_with_its_marks_and_its_entry_mark() {
    let mut t = calibrated();
    t.set_isr_spans(1 << ISR);
    t.span_start(OUTER, 0);
    t.span_start(ISR, 50);
    t.isr_entered(0, 60);
    t.span_end_as(ISR, ISR, 150);
    t.span_end_as(OUTER, OUTER, 400);
    // The ISR's span: 100 counts less its entry mark (7); the report takes its own
    // marks' inside (3) off.
    assert_eq!(t.spans[ISR].sum, u64::from(93 * PER_COUNT));
    // The outer: 400 less the ISR's own work (93 - 3 = 90) and its three marks whole
    // (5 + 7 + 9): the ISR's marks' inside is not taken off twice.
    assert_eq!(t.spans[OUTER].sum, u64::from((400 - 90 - 21) * PER_COUNT));
}

#[test]
fn a_job_is_net_of_the_spans_in_it_and_a_job_that_preempts_it_keeps_its_work() {
    let mut t = calibrated();
    t.job_started(1, 0);
    t.span_start(OUTER, 20);
    t.span_end_as(OUTER, OUTER, 40);
    // A job of task 2 preempts: its work stays in task 1's job, its marks do not.
    t.job_started(2, 100);
    t.job_finished(2, 150);
    t.job_finished(1, 500);
    assert_eq!(t.tasks[2].span.sum, u64::from(50 * PER_COUNT));
    // 500 less the span's marks (14) and task 2's job marks (6 + 11).
    assert_eq!(t.tasks[1].span.sum, u64::from((500 - 14 - 17) * PER_COUNT));
    assert_eq!(t.tasks[1].preempted, 1);
    assert_eq!(t.preemptions[2][1], 1);
}

#[test]
fn an_end_mark_without_its_start_records_nothing_but_still_costs_the_spans_around_it() {
    let mut t = calibrated();
    t.span_start(OUTER, 0);
    t.span_end_as(INNER, INNER, 10);
    t.span_end_as(OUTER, OUTER, 100);
    assert_eq!(t.spans[INNER].count, 0);
    assert_eq!(t.spans[OUTER].sum, u64::from((100 - 9) * PER_COUNT));
}

#[test]
fn a_span_shorter_than_the_marks_in_it_is_zero_not_a_wrapped_length() {
    let mut t = calibrated();
    t.span_start(OUTER, 0);
    t.span_start(INNER, 1);
    t.span_end_as(INNER, INNER, 2);
    t.span_end_as(OUTER, OUTER, 3);
    assert_eq!(t.spans[OUTER].sum, 0);
    assert_eq!(t.spans[OUTER].min, 0);
}

#[test]
fn calibration_forgets_the_records_and_keeps_the_isr_spans() {
    let mut t = Trace::new();
    t.set_isr_spans(1 << ISR);
    t.job_started(1, 0);
    t.span_start(OUTER, 0);
    t.span_end_as(OUTER, OUTER, 10);
    t.isr_entered(0, 12);
    assert_eq!(t.take_span(OUTER).count, 1);
    assert_eq!(t.take_span(OUTER).count, 0);
    t.span_start(OUTER, 20);
    t.calibrated(costs());
    assert_eq!(t.costs, costs());
    assert_eq!(t.spans[OUTER], SpanRecord::default());
    assert_eq!(t.tasks[1], TaskRecord::default());
    assert_eq!((t.events_len, t.isr_over[0][1]), (0, 0));
    // No job and no span open: an end now records nothing.
    t.span_end_as(OUTER, OUTER, 30);
    t.job_finished(1, 30);
    assert_eq!((t.spans[OUTER].count, t.tasks[1].span.count), (0, 0));
    // The ISR spans are the application's, kept.
    t.span_start(ISR, 40);
    t.span_end_as(ISR, ISR, 50);
    t.span_start(OUTER, 60);
    t.span_start(ISR, 70);
    t.span_end_as(ISR, ISR, 80);
    t.span_end_as(OUTER, OUTER, 100);
    assert_eq!(
        t.spans[OUTER].sum,
        u64::from((40 - (10 - 3) - 14) * PER_COUNT)
    );
}

#[test]
fn job_records_come_back_whole_across_the_time_stamps_wrap() {
    use super::job_record::{encode, JobEdge, Unwrapper, TIME_MASK};
    let edge = |task, end, at| JobEdge { task, end, at };
    let mut reader = Unwrapper::new();
    // The first record as it is; 4 ms later across the 27 bits' wrap; 4 ms after that
    // across the u32 counter's own wrap.
    assert_eq!(
        reader.next(encode(5, false, TIME_MASK - 10)),
        edge(5, false, u64::from(TIME_MASK) - 10)
    );
    let at = u64::from(TIME_MASK) + 99_990;
    assert_eq!(
        reader.next(encode(1, true, TIME_MASK.wrapping_add(99_990))),
        edge(1, true, at)
    );
    // A record out of order (a later job's start put on the ring first): read as a step
    // back, not as 5.4 s ahead.
    let mut reader = Unwrapper::new();
    assert_eq!(reader.next(encode(3, false, 1_000)), edge(3, false, 1_000));
    assert_eq!(reader.next(encode(4, false, 900)), edge(4, false, 900));
    assert_eq!(reader.next(encode(4, true, 0)), edge(4, true, 0));
    // Back past the first record's time: held there.
    assert_eq!(
        reader.next(encode(4, false, TIME_MASK - 5)),
        edge(4, false, 0)
    );
    let mut reader = Unwrapper::new();
    let first = u32::MAX - 50;
    assert_eq!(
        reader.next(encode(15, true, first)),
        edge(15, true, u64::from(TIME_MASK) - 50)
    );
    assert_eq!(
        reader.next(encode(2, false, first.wrapping_add(100_000))),
        edge(2, false, u64::from(TIME_MASK) - 50 + 100_000)
    );
}

/// Any run of job starts and ends, at any first time and with any steps ahead or back
/// below half the time stamp's range, reads back whole.
#[test]
fn job_records_round_trip() {
    bolero::check!()
        .with_type::<(u32, Vec<(u8, bool, i32)>)>()
        .for_each(|(first, edges)| assert!(super::job_record::round_trip(*first, edges)));
}

/// Kani: two records after the first, any times, tasks and edges.
#[cfg(kani)]
#[kani::proof]
#[kani::unwind(3)]
fn every_two_job_records_round_trip() {
    let first: u32 = kani::any();
    let edges: [(u8, bool, i32); 2] = kani::any();
    assert!(super::job_record::round_trip(first, &edges));
}

#[test]
fn a_jobs_own_time_is_net_of_the_jobs_that_preempted_it_once_each() {
    let mut t = calibrated();
    // Task 2 from 0 to 1000; task 1 preempts it from 100 to 400; task 0 preempts task 1
    // from 200 to 250.
    t.job_started(2, 0);
    t.job_started(1, 100);
    t.job_started(0, 200);
    t.job_finished(0, 250);
    t.job_finished(1, 400);
    t.job_finished(2, 1000);
    let marks = |starts: u32, ends: u32| (6 * starts + 11 * ends) * PER_COUNT;
    let span = |task: usize| t.tasks[task].span.sum;
    let own = |task: usize| t.tasks[task].own.sum;
    // Task 0: nothing nested.
    assert_eq!(span(0), u64::from(50 * PER_COUNT));
    assert_eq!(own(0), span(0));
    // Task 1: 300 less task 0's two marks; its own time less task 0's too.
    assert_eq!(span(1), u64::from(300 * PER_COUNT - marks(1, 1)));
    assert_eq!(own(1), span(1) - own(0));
    // Task 2: the whole, less both jobs' marks; its own time less what each executed,
    // task 0's counted once (not again inside task 1's).
    assert_eq!(span(2), u64::from(1000 * PER_COUNT - marks(2, 2)));
    assert_eq!(own(2), span(2) - own(1) - own(0));
}
