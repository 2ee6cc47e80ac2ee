//! Instruction-count probes for `cargo xtask callgrind`.
//!
//! Usage: `callgrind_probe <op> <iterations>`. Each op calls one `#[inline(never)]`
//! function `probe_<op>` `iterations` times; callgrind counts only inside that function
//! (`--toggle-collect=*probe_<op>*`), and the runner takes the difference between two
//! iteration counts, so set-up and loop overhead cancel out. Inputs pass through
//! `black_box` so nothing is folded away that a real caller would compute at run time;
//! the "const" probes keep the layout a compile-time constant, as generated RTE/Com code
//! has it.

use cw_core::com::signal::{ByteOrder, SignalLayout, Signedness};
use cw_core::os::{
    AlarmAction, AlarmAutostart, AlarmConfig, AlarmId, CounterConfig, CounterId, Os, OsConfig,
    TaskConfig, TaskId,
};
use cw_core::tables::Tables;
use std::hint::black_box;

/// The paper's distance signal: 32-bit little-endian unsigned at bit 0 of an 8-byte PDU.
const DISTANCE: SignalLayout<8> =
    cw_core::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned);
/// A Motorola signal crossing three bytes: MSB at bit 12, 16 bits, signed.
const MOTOROLA: SignalLayout<8> =
    cw_core::signal_layout!(8; 12, 16, ByteOrder::Motorola, Signedness::Signed);
/// An unaligned Intel signal: 20 bits from bit 13.
const INTEL: SignalLayout<8> =
    cw_core::signal_layout!(8; 13, 20, ByteOrder::Intel, Signedness::Unsigned);

#[inline(never)]
fn probe_pack_distance_const(pdu: &mut [u8; 8], distance_mm: u32) {
    let _ = DISTANCE.pack_u64(pdu, u64::from(distance_mm));
}

#[inline(never)]
fn probe_unpack_distance_const(pdu: &[u8; 8]) -> u64 {
    DISTANCE.unpack_raw(pdu)
}

#[inline(never)]
fn probe_pack_motorola_runtime(layout: &SignalLayout<8>, pdu: &mut [u8; 8], value: i64) {
    let _ = layout.pack_i64(pdu, value);
}

#[inline(never)]
fn probe_unpack_motorola_runtime(layout: &SignalLayout<8>, pdu: &[u8; 8]) -> i64 {
    match layout.unpack(pdu) {
        cw_core::com::signal::SignalValue::Signed(v) => v,
        cw_core::com::signal::SignalValue::Unsigned(v) => v as i64,
    }
}

#[inline(never)]
fn probe_pack_intel_runtime(layout: &SignalLayout<8>, pdu: &mut [u8; 8], value: u64) {
    let _ = layout.pack_u64(pdu, value);
}

// Evaluated only in `static` initialisers: a broken configuration stops the build.
#[allow(clippy::panic)]
const fn ok<const T: usize, const R: usize, const C: usize, const A: usize>(
    cfg: Result<OsConfig<T, R, C, A>, cw_core::os::ConfigError>,
) -> OsConfig<T, R, C, A> {
    match cfg {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    }
}

/// Two tasks: High (5) runs, Low (1) is activated.
static TWO: OsConfig<2, 0, 1, 1> = ok(OsConfig::new(
    [TaskConfig::basic("Low", 1), TaskConfig::basic("High", 5)],
    [CounterConfig {
        max_allowed_value: u32::MAX - 1,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [AlarmConfig {
        name: "Cb",
        counter: CounterId(0),
        action: AlarmAction::Callback(0),
        autostart: AlarmAutostart::Off,
    }],
));

cw_core::static_tables!(
    /// [`TWO`] as a build-time constant, as the ECU configures its kernel.
    TwoTables: OsConfig<2, 0, 1, 1> = TWO
);

/// 64 tasks at 64 priorities and 32 alarms on one counter: the same probes must cost the
/// same as with two tasks and one alarm.
static MANY: OsConfig<64, 0, 1, 32> = {
    let mut tasks = [TaskConfig::basic("T", 0); 64];
    let mut i = 0;
    while i < 64 {
        tasks[i] = TaskConfig::basic("T", i as u8);
        i += 1;
    }
    let mut alarms = [AlarmConfig {
        name: "Cb",
        counter: CounterId(0),
        action: AlarmAction::Callback(0),
        autostart: AlarmAutostart::Off,
    }; 32];
    let mut a = 0;
    while a < 32 {
        alarms[a].action = AlarmAction::Callback(a as u8);
        a += 1;
    }
    ok(OsConfig::new(
        tasks,
        [CounterConfig {
            max_allowed_value: u32::MAX - 1,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        alarms,
    ))
};

#[inline(never)]
fn probe_activate_task<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
    task: TaskId,
) {
    let _ = os.activate_task(task);
}

/// The configuration a build-time constant (as in the ECU), the task id a run-time value.
#[inline(never)]
fn probe_activate_task_static<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
    task: TaskId,
) {
    let _ = os.activate_task(task);
}

/// As RTE-generated code calls it: the task id is a constant at the call site.
#[inline(never)]
fn probe_activate_task_const_id<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
) {
    let _ = os.activate_task(TaskId(0));
}

#[inline(never)]
fn probe_activate_task_64<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
    task: TaskId,
) {
    let _ = os.activate_task(task);
}

#[inline(never)]
fn probe_alarm_tick_idle<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
) {
    let _ = os.increment_counter(black_box(CounterId(0)));
}

#[inline(never)]
fn probe_alarm_tick_idle_32<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
) {
    let _ = os.increment_counter(black_box(CounterId(0)));
}

#[inline(never)]
fn probe_alarm_tick_due<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A>>,
>(
    os: &mut Os<T, 0, 1, A, Q, K>,
) -> u32 {
    os.increment_counter(black_box(CounterId(0)))
        .map_or(0, |r| r.callbacks)
}

/// Puts `high` running and leaves `low` suspended, so that activating `low` is a pure
/// "queue it, no preemption" decision.
fn reset<const T: usize, const A: usize, const Q: usize, K: Tables<OsConfig<T, 0, 1, A>>>(
    os: &mut Os<T, 0, 1, A, Q, K>,
    high: TaskId,
) {
    while os.running().is_some() {
        let _ = os.terminate_task();
    }
    let _ = os.activate_task(high);
}

fn kernel<const T: usize, const A: usize, const Q: usize, K: Tables<OsConfig<T, 0, 1, A>>>(
    cfg: K,
) -> Result<Os<T, 0, 1, A, Q, K>, String> {
    let mut os = Os::<T, 0, 1, A, Q, K>::new(cfg).map_err(|e| e.describe().to_string())?;
    os.start().map_err(|e| e.name().to_string())?;
    Ok(os)
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let op = args
        .next()
        .ok_or("usage: callgrind_probe <op> <iterations>")?;
    let n: u32 = args
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or("usage: callgrind_probe <op> <iterations>")?;
    let mut pdu = [0u8; 8];
    let mut sink = 0u64;
    match op.as_str() {
        "pack_distance_const" => {
            (0..n).for_each(|i| probe_pack_distance_const(black_box(&mut pdu), black_box(i)))
        }
        "unpack_distance_const" => {
            (0..n).for_each(|_| sink ^= probe_unpack_distance_const(black_box(&pdu)))
        }
        "pack_motorola_runtime" => (0..n).for_each(|i| {
            probe_pack_motorola_runtime(
                black_box(&MOTOROLA),
                black_box(&mut pdu),
                black_box(i64::from(i as i16)),
            )
        }),
        "unpack_motorola_runtime" => (0..n).for_each(|_| {
            sink ^= probe_unpack_motorola_runtime(black_box(&MOTOROLA), black_box(&pdu)) as u64;
        }),
        "pack_intel_runtime" => (0..n).for_each(|i| {
            probe_pack_intel_runtime(
                black_box(&INTEL),
                black_box(&mut pdu),
                black_box(u64::from(i & 0xF_FFFF)),
            )
        }),
        "activate_task" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            for _ in 0..n {
                reset(&mut os, TaskId(1));
                probe_activate_task(&mut os, black_box(TaskId(0)));
            }
        }
        "activate_task_static" => {
            let mut os = kernel::<2, 1, 2, _>(TwoTables)?;
            for _ in 0..n {
                reset(&mut os, TaskId(1));
                probe_activate_task_static(&mut os, black_box(TaskId(0)));
            }
        }
        "activate_task_const_id" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            for _ in 0..n {
                reset(&mut os, TaskId(1));
                probe_activate_task_const_id(&mut os);
            }
        }
        "activate_task_64" => {
            let mut os = kernel::<64, 32, 64, _>(&MANY)?;
            for _ in 0..n {
                reset(&mut os, TaskId(63));
                probe_activate_task_64(&mut os, black_box(TaskId(0)));
            }
        }
        "alarm_tick_idle" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            os.set_rel_alarm(AlarmId(0), u32::MAX - 1, 0)
                .map_err(|e| e.name())?;
            (0..n).for_each(|_| probe_alarm_tick_idle(&mut os));
        }
        "alarm_tick_idle_32" => {
            let mut os = kernel::<64, 32, 64, _>(&MANY)?;
            for a in 0..32 {
                os.set_rel_alarm(AlarmId(a), u32::MAX - 1 - u32::from(a), 0)
                    .map_err(|e| e.name())?;
            }
            (0..n).for_each(|_| probe_alarm_tick_idle_32(&mut os));
        }
        "alarm_tick_due" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            os.set_rel_alarm(AlarmId(0), 1, 1).map_err(|e| e.name())?;
            (0..n).for_each(|_| sink ^= u64::from(probe_alarm_tick_due(&mut os)));
        }
        other => return Err(format!("unknown op {other}")),
    }
    println!("{op} x{n}: pdu {pdu:02x?} sink {sink}");
    Ok(())
}
