//! Criterion benchmarks of the verified kernels: Com signal packing and unpacking (the
//! paper's 32-bit little-endian distance with a compile-time layout, and a Motorola signal
//! with a run-time layout), `ActivateTask` with and without dispatch, and a counter tick
//! with nothing due and with an alarm due. Instruction counts per call come from
//! `cargo xtask callgrind` (see the book: `docs/src/performance.md`).

use criterion::{criterion_group, criterion_main, Criterion};
use cw_core::com::signal::{ByteOrder, SignalLayout, Signedness};
use cw_core::os::{AlarmId, CounterId, Os, TaskId, OSDEFAULTAPPMODE};
use std::hint::black_box;

const DISTANCE: SignalLayout<8> =
    cw_core::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned);
const MOTOROLA: SignalLayout<8> =
    cw_core::signal_layout!(8; 12, 16, ByteOrder::Motorola, Signedness::Signed);

fn codec(c: &mut Criterion) {
    let mut g = c.benchmark_group("com_signal");
    let mut pdu = [0u8; 8];
    g.bench_function("pack distance u32 LE (const layout)", |b| {
        b.iter(|| DISTANCE.pack_u64(black_box(&mut pdu), black_box(1500)))
    });
    g.bench_function("unpack distance u32 LE (const layout)", |b| {
        b.iter(|| DISTANCE.unpack_raw(black_box(&pdu)))
    });
    let layout = black_box(MOTOROLA);
    g.bench_function("pack Motorola i16 (runtime layout)", |b| {
        b.iter(|| layout.pack_i64(black_box(&mut pdu), black_box(-1234)))
    });
    g.bench_function("unpack Motorola i16 (runtime layout)", |b| {
        b.iter(|| layout.unpack(black_box(&pdu)))
    });
    g.finish();
}

#[path = "support/two_tasks.rs"]
mod two_tasks;
use two_tasks::{TICK_ISR, TWO};

/// The kernel with Low running (started from the timer ISR), so the measured services are
/// called from a task, as in an application.
fn kernel() -> Os<2, 0, 1, 1, 1, 2> {
    let Ok(mut os) = Os::new(&TWO) else {
        panic!("kernel refused the configuration");
    };
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    assert_eq!(os.enter_isr(TICK_ISR), Ok(()));
    assert_eq!(os.activate_task(TaskId(0)), Ok(()));
    assert_eq!(os.exit_isr(), Ok(()));
    os
}

fn scheduler(c: &mut Criterion) {
    let mut g = c.benchmark_group("os");
    let mut os = kernel();
    g.bench_function(
        "ActivateTask + dispatch + TerminateTask (Low -> High -> Low)",
        |b| {
            b.iter(|| {
                let _ = os.activate_task(black_box(TaskId(1)));
                let _ = os.terminate_task();
            })
        },
    );
    let mut os = kernel();
    let _ = os.chain_task(TaskId(1));
    g.bench_function(
        "ActivateTask, no preemption (+ High ends, Low chains High again)",
        |b| {
            b.iter(|| {
                let _ = os.activate_task(black_box(TaskId(0)));
                let _ = os.terminate_task();
                let _ = os.chain_task(TaskId(1));
            })
        },
    );
    let mut os = kernel();
    let _ = os.set_rel_alarm(AlarmId(0), u32::MAX - 1, 0);
    g.bench_function("IncrementCounter, nothing due", |b| {
        b.iter(|| os.increment_counter(black_box(CounterId(0))))
    });
    let mut os = kernel();
    let _ = os.set_rel_alarm(AlarmId(0), 1, 1);
    g.bench_function("IncrementCounter, cyclic alarm due (callback)", |b| {
        b.iter(|| os.increment_counter(black_box(CounterId(0))))
    });
    g.finish();
}

criterion_group!(benches, codec, scheduler);
criterion_main!(benches);
