//! Instruction-count probes for `cargo xtask callgrind`.
//!
//! Usage: `callgrind_probe <op> <iterations>`. Each op calls one `#[inline(never)]`
//! function `probe_<op>` `iterations` times; callgrind counts only inside that function
//! (`--toggle-collect=*probe_<op>*`), and the runner takes the difference between two
//! iteration counts, so set-up and loop overhead cancel out. Inputs pass through
//! `black_box` so nothing is folded away that a real caller would compute at run time;
//! the "const" probes keep the layout a compile-time constant, as generated RTE/Com code
//! has it.

use cw_core::com::ipdu::{Com, ComConfig, ComConfigError, RxIpduConfig, TxIpduConfig, TxMode};
use cw_core::com::signal::{ByteOrder, SignalLayout, Signedness};
use cw_core::os::{
    AlarmAction, AlarmConfig, AlarmId, CounterConfig, CounterId, IsrConfig, Os, OsConfig,
    OsDescription, Status, TaskConfig, TaskId, OSDEFAULTAPPMODE,
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
const fn ok<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize>(
    cfg: Result<OsConfig<T, R, C, A, I>, cw_core::os::ConfigError>,
) -> OsConfig<T, R, C, A, I> {
    match cfg {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    }
}

/// Two tasks: High (5) runs, Low (1) is activated (shared with the criterion benchmarks).
#[path = "../benches/support/two_tasks.rs"]
mod two_tasks;
use two_tasks::{TICK_ISR, TWO};

cw_core::static_tables!(
    /// [`TWO`] as a build-time constant, as the ECU configures its kernel.
    TwoTables: OsConfig<2, 0, 1, 1, 1> = TWO
);

/// [`TWO`] in standard status: the fast paths must cost the same as in extended status.
static TWO_STANDARD: OsConfig<2, 0, 1, 1, 1> = ok(OsConfig::new(
    OsDescription::new(*TWO.tasks(), *TWO.counters(), *TWO.alarms(), *TWO.isrs())
        .status(Status::Standard),
));

cw_core::static_tables!(
    /// [`TWO_STANDARD`] as a build-time constant.
    TwoStandardTables: OsConfig<2, 0, 1, 1, 1> = TWO_STANDARD
);

/// 64 tasks at 64 priorities and 32 alarms on one counter: the same probes must cost the
/// same as with two tasks and one alarm.
static MANY: OsConfig<64, 0, 1, 32, 1> = {
    let mut tasks = [TaskConfig::basic("T", 0); 64];
    let mut i = 0;
    while i < 64 {
        tasks[i] = TaskConfig::basic("T", i as u8);
        i += 1;
    }
    let mut alarms = [AlarmConfig::new("Cb", CounterId(0), AlarmAction::Callback(0)); 32];
    let mut a = 0;
    while a < 32 {
        alarms[a].action = AlarmAction::Callback(a as u8);
        a += 1;
    }
    ok(OsConfig::new(OsDescription::new(
        tasks,
        [CounterConfig {
            max_allowed_value: u32::MAX - 1,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        alarms,
        [IsrConfig::cat2("Tick", 0)],
    )))
};

// Callgrind collects a probe by its function name, so every op has its own function;
// the ops that run the same call on different kernels share one body through this macro.
macro_rules! kernel_probe {
    ($(#[$doc:meta])* $name:ident($os:ident $(, $arg:ident: $ty:ty)*) $body:block) => {
        $(#[$doc])*
        #[inline(never)]
        fn $name<const T: usize, const A: usize, const Q: usize, K: Tables<OsConfig<T, 0, 1, A, 1>>>(
            $os: &mut Os<T, 0, 1, A, 1, Q, K>,
            $($arg: $ty),*
        ) {
            $body
        }
    };
}

kernel_probe!(probe_activate_task(os, task: TaskId) {
    let _ = os.activate_task(task);
});
kernel_probe!(probe_activate_task_64(os, task: TaskId) {
    let _ = os.activate_task(task);
});
kernel_probe!(
    /// The configuration a build-time constant (as in the ECU), the task id a run-time value.
    probe_activate_task_static(os, task: TaskId) {
        let _ = os.activate_task(task);
    }
);
kernel_probe!(
    /// As RTE-generated code calls it: the task id is a constant at the call site.
    probe_activate_task_const_id(os) {
        let _ = os.activate_task(TaskId(0));
    }
);
kernel_probe!(
    /// The same as `probe_activate_task_static`, in standard status.
    probe_activate_task_standard(os, task: TaskId) {
        let _ = os.activate_task(task);
    }
);
kernel_probe!(
    /// The timer ISR with nothing due, as the port runs it: entry, one tick, return (a
    /// task runs, nothing preempts it).
    probe_tick_isr_idle(os) {
        let _ = os.enter_isr(black_box(TICK_ISR));
        let _ = os.increment_counter(black_box(CounterId(0)));
        let _ = os.exit_isr();
    }
);
kernel_probe!(
    /// A `SuspendOSInterrupts`/`ResumeOSInterrupts` pair at task level.
    probe_suspend_resume_os(os) {
        let _ = os.suspend_os_interrupts();
        let _ = os.resume_os_interrupts();
    }
);
kernel_probe!(probe_alarm_tick_idle(os) {
    let _ = os.increment_counter(black_box(CounterId(0)));
});
kernel_probe!(probe_alarm_tick_idle_32(os) {
    let _ = os.increment_counter(black_box(CounterId(0)));
});

/// The alarm's callback runs (an empty one: the cost is the kernel's). Returns the status,
/// so that LLVM does not merge this probe with the idle one (the same call on the same
/// kernel type).
#[inline(never)]
fn probe_alarm_tick_due<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A, 1>>,
>(
    os: &mut Os<T, 0, 1, A, 1, Q, K>,
) -> bool {
    os.increment_counter(black_box(CounterId(0))).is_ok()
}

// Com main functions with nothing due. The runner needs 2000 consecutive idle calls, 20 s
// at the usual 10 ms main period, so the I-PDUs are slow ones (AUTOSAR allows cycle times
// and deadlines up to an hour): TX sent every 30 s, RX monitored with a 30 s deadline (a
// 10 s cycle, three missed frames). Offsets and deadlines step by one main period so the
// 32 I-PDUs spread over 32 cycles instead of sharing one. Before the measured calls, one
// turn of the wheel (64 calls, outside the probe) makes the first transmissions (offsets
// 0..310 ms); the next ones are due at call 3001, the first timeouts at call 3000.
// Whatever Com does for the pending I-PDUs in between (a one-level 64-slot wheel revisits
// each of them every 64 calls) is inside the measured calls and shows up, amortized, in
// the per-call figure.

/// Main period of the Com probes, ms.
const COM_PERIOD_MS: u32 = 10;
/// Main-function calls made before the measured ones (the first transmissions).
const COM_WARM_UP: u32 = 64;

// Evaluated only in `static` initialisers: a broken configuration stops the build.
#[allow(clippy::panic)]
const fn com_ok<const TX: usize, const RX: usize>(
    cfg: Result<ComConfig<8, TX, RX, 0>, ComConfigError>,
) -> ComConfig<8, TX, RX, 0> {
    match cfg {
        Ok(c) => c,
        Err(e) => panic!("{}", e.describe()),
    }
}

/// TX I-PDU `i`: periodic, 30 s, offset `i` main periods.
const fn slow_tx(i: u32) -> TxIpduConfig {
    TxIpduConfig {
        name: "SlowTx",
        len: 8,
        mode: TxMode::Periodic {
            period_ms: 30_000,
            offset_ms: i * COM_PERIOD_MS,
        },
        mdt_ms: 0,
    }
}

/// RX I-PDU `i`: deadline 30 s plus `i` main periods.
const fn slow_rx(i: u32) -> RxIpduConfig {
    RxIpduConfig {
        name: "SlowRx",
        len: 8,
        deadline_ms: 30_000 + i * COM_PERIOD_MS,
    }
}

/// One periodic TX I-PDU and one monitored RX I-PDU.
static COM_1: ComConfig<8, 1, 1, 0> = com_ok(ComConfig::new(
    COM_PERIOD_MS,
    [slow_tx(0)],
    [slow_rx(0)],
    [],
));

/// 32 periodic TX I-PDUs and 32 monitored RX I-PDUs.
static COM_32: ComConfig<8, 32, 32, 0> = {
    let mut tx = [slow_tx(0); 32];
    let mut rx = [slow_rx(0); 32];
    let mut i = 0;
    while i < 32 {
        tx[i] = slow_tx(i as u32);
        rx[i] = slow_rx(i as u32);
        i += 1;
    }
    com_ok(ComConfig::new(COM_PERIOD_MS, tx, rx, []))
};

cw_core::static_tables!(
    /// [`COM_1`] as a build-time constant, as the ECU configures Com.
    Com1Tables: ComConfig<8, 1, 1, 0> = COM_1
);
cw_core::static_tables!(
    /// [`COM_32`] as a build-time constant.
    Com32Tables: ComConfig<8, 32, 32, 0> = COM_32
);

/// Transmissions and timeouts seen by a main function call (none are expected).
#[derive(Default)]
struct ComEvents {
    sent: u32,
    timeouts: u32,
}

/// One `Com_MainFunctionTx` and one `Com_MainFunctionRx`, as the BSW task calls them.
fn com_main<const TX: usize, const RX: usize, C: Tables<ComConfig<8, TX, RX, 0>>>(
    com: &mut Com<8, TX, RX, 0, C>,
    events: &mut ComEvents,
) {
    com.main_function_tx(|_, _| {
        events.sent += 1;
        true
    });
    com.main_function_rx(|_| events.timeouts += 1);
}

#[inline(never)]
fn probe_com_main_idle_1<C: Tables<ComConfig<8, 1, 1, 0>>>(
    com: &mut Com<8, 1, 1, 0, C>,
    events: &mut ComEvents,
) {
    com_main(com, events);
}

#[inline(never)]
fn probe_com_main_idle_32<C: Tables<ComConfig<8, 32, 32, 0>>>(
    com: &mut Com<8, 32, 32, 0, C>,
    events: &mut ComEvents,
) {
    com_main(com, events);
}

/// Runs `probe` `n` times on a Com after the warm-up; fails if anything was due during the
/// measured calls (the probe would then not measure idle calls).
fn com_idle<const TX: usize, const RX: usize, C: Tables<ComConfig<8, TX, RX, 0>>>(
    cfg: C,
    n: u32,
    probe: fn(&mut Com<8, TX, RX, 0, C>, &mut ComEvents),
) -> Result<(), String> {
    let mut com = Com::new(cfg);
    let mut warm_up = ComEvents::default();
    for _ in 0..COM_WARM_UP {
        com_main(&mut com, &mut warm_up);
    }
    if warm_up.sent != TX as u32 {
        return Err(format!(
            "warm-up sent {} I-PDUs, expected {TX}",
            warm_up.sent
        ));
    }
    let mut events = ComEvents::default();
    for _ in 0..n {
        probe(black_box(&mut com), black_box(&mut events));
    }
    if events.sent + events.timeouts > 0 {
        return Err(format!(
            "not idle: {} transmissions, {} timeouts in {n} calls",
            events.sent, events.timeouts
        ));
    }
    Ok(())
}

/// Puts `high` running (started from the timer ISR, as nothing runs) and leaves `low`
/// suspended, so that activating `low` is a pure "queue it, no preemption" decision.
fn reset<const T: usize, const A: usize, const Q: usize, K: Tables<OsConfig<T, 0, 1, A, 1>>>(
    os: &mut Os<T, 0, 1, A, 1, Q, K>,
    high: TaskId,
) {
    while os.running().is_some() {
        let _ = os.terminate_task();
    }
    let _ = os.enter_isr(TICK_ISR);
    let _ = os.activate_task(high);
    let _ = os.exit_isr();
}

fn kernel<const T: usize, const A: usize, const Q: usize, K: Tables<OsConfig<T, 0, 1, A, 1>>>(
    cfg: K,
) -> Result<Os<T, 0, 1, A, 1, Q, K>, String> {
    let mut os = Os::<T, 0, 1, A, 1, Q, K>::new(cfg).map_err(|e| e.describe().to_string())?;
    os.start_os(OSDEFAULTAPPMODE)
        .map_err(|e| e.name().to_string())?;
    Ok(os)
}

/// A kernel inside the timer ISR, where the counter ticks.
fn in_tick_isr<
    const T: usize,
    const A: usize,
    const Q: usize,
    K: Tables<OsConfig<T, 0, 1, A, 1>>,
>(
    cfg: K,
) -> Result<Os<T, 0, 1, A, 1, Q, K>, String> {
    let mut os = kernel(cfg)?;
    os.enter_isr(TICK_ISR).map_err(|e| e.name().to_string())?;
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
        "activate_task_standard" => {
            let mut os = kernel::<2, 1, 2, _>(TwoStandardTables)?;
            for _ in 0..n {
                reset(&mut os, TaskId(1));
                probe_activate_task_standard(&mut os, black_box(TaskId(0)));
            }
        }
        "tick_isr_idle" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            reset(&mut os, TaskId(1));
            os.set_rel_alarm(AlarmId(0), u32::MAX - 1, 0)
                .map_err(|e| e.name())?;
            (0..n).for_each(|_| probe_tick_isr_idle(&mut os));
        }
        "suspend_resume_os" => {
            let mut os = kernel::<2, 1, 2, _>(&TWO)?;
            reset(&mut os, TaskId(1));
            (0..n).for_each(|_| probe_suspend_resume_os(&mut os));
        }
        "activate_task_64" => {
            let mut os = kernel::<64, 32, 64, _>(&MANY)?;
            for _ in 0..n {
                reset(&mut os, TaskId(63));
                probe_activate_task_64(&mut os, black_box(TaskId(0)));
            }
        }
        "alarm_tick_idle" => {
            let mut os = in_tick_isr::<2, 1, 2, _>(&TWO)?;
            os.set_rel_alarm(AlarmId(0), u32::MAX - 1, 0)
                .map_err(|e| e.name())?;
            (0..n).for_each(|_| probe_alarm_tick_idle(&mut os));
        }
        "alarm_tick_idle_32" => {
            let mut os = in_tick_isr::<64, 32, 64, _>(&MANY)?;
            for a in 0..32 {
                os.set_rel_alarm(AlarmId(a), u32::MAX - 1 - u32::from(a), 0)
                    .map_err(|e| e.name())?;
            }
            (0..n).for_each(|_| probe_alarm_tick_idle_32(&mut os));
        }
        "alarm_tick_due" => {
            let mut os = in_tick_isr::<2, 1, 2, _>(&TWO)?;
            os.set_rel_alarm(AlarmId(0), 1, 1).map_err(|e| e.name())?;
            (0..n).for_each(|_| sink += u64::from(probe_alarm_tick_due(&mut os)));
        }
        "com_main_idle_1" => com_idle(Com1Tables, n, probe_com_main_idle_1)?,
        "com_main_idle_32" => com_idle(Com32Tables, n, probe_com_main_idle_32)?,
        other => return Err(format!("unknown op {other}")),
    }
    println!("{op} x{n}: pdu {pdu:02x?} sink {sink}");
    Ok(())
}
