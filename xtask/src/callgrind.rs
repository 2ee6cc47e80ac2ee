//! `cargo xtask callgrind`: instructions per call of each probe, counted by callgrind.
//!
//! The probe binary (`core/examples/callgrind_probe.rs`, release profile: fat LTO, one
//! codegen unit) takes `<op> <iterations>` and calls the `#[inline(never)]` function
//! `probe_<op>` that many times. Callgrind collects only inside that function
//! (`--collect-atstart=no --toggle-collect=*probe_<op>*`), once with `LOW` and once with
//! `HIGH` iterations; `(Ir(HIGH) - Ir(LOW)) / (HIGH - LOW)` cancels any fixed cost and is
//! the exact instruction count of one call (x86-64 of this machine, not the MPC5748G).

use crate::process::{target_dir, Cmd};
use crate::Result;
use std::path::{Path, PathBuf};

/// Probes, as (op, what one call does). `probe_<op>` must exist in the probe example.
pub const PROBES: &[(&str, &str)] = &[
    (
        "pack_distance_const",
        "Com pack of the 32-bit Intel distance, layout known at compile time",
    ),
    (
        "unpack_distance_const",
        "Com unpack of the 32-bit Intel distance, layout known at compile time",
    ),
    (
        "pack_motorola_runtime",
        "Com pack of a Motorola signal, layout chosen at run time",
    ),
    (
        "unpack_motorola_runtime",
        "Com unpack of a Motorola signal, layout chosen at run time",
    ),
    (
        "pack_intel_runtime",
        "Com pack of an Intel signal, layout chosen at run time",
    ),
    (
        "activate_task",
        "OS ActivateTask up to the scheduling decision, run-time task id, 2 tasks",
    ),
    (
        "activate_task_64",
        "OS ActivateTask up to the scheduling decision, run-time task id, 64 tasks",
    ),
    (
        "activate_task_static",
        "OS ActivateTask up to the scheduling decision, run-time task id, tables constant",
    ),
    (
        "activate_task_const_id",
        "OS ActivateTask up to the scheduling decision, constant task id (as RTE calls it)",
    ),
    (
        "activate_task_standard",
        "OS ActivateTask up to the scheduling decision, run-time task id, tables constant, standard status",
    ),
    (
        "alarm_tick_idle",
        "OS counter tick with no alarm due, 1 alarm armed",
    ),
    (
        "alarm_tick_idle_32",
        "OS counter tick with no alarm due, 32 alarms armed",
    ),
    (
        "alarm_tick_due",
        "OS counter tick that expires a cyclic alarm (callback)",
    ),
    (
        "tick_isr_idle",
        "OS timer ISR: enter_isr + IncrementCounter (nothing due) + exit_isr, a task running",
    ),
    (
        "suspend_resume_os",
        "OS SuspendOSInterrupts + ResumeOSInterrupts at task level",
    ),
    (
        "com_main_idle_1",
        "Com_MainFunctionTx + Rx, nothing due; 1 TX (30 s) + 1 RX (30 s deadline) pending",
    ),
    (
        "com_main_idle_32",
        "Com_MainFunctionTx + Rx, nothing due; 32 TX (30 s) + 32 RX (30 s deadline) pending",
    ),
];

/// Probes of the communication stack per layer (the paper's Figure 10),
/// `cw_firmware::stack_probe` through `firmware/examples/stack_probe.rs`, with the ECU's
/// own configuration.
pub const STACK_PROBES: &[(&str, &str)] = &[
    (
        "tx_path",
        "TX: SWC write -> RTE -> CanTranslate -> Com -> PduR -> CanIf -> mailbox",
    ),
    (
        "tx_com_down",
        "TX: Com_SendSignal -> PduR -> CanIf -> mailbox",
    ),
    (
        "tx_com_only",
        "TX: Com_SendSignal alone (pack, transfer property, MDT)",
    ),
    ("tx_pdur_down", "TX: PduR_ComTransmit -> CanIf -> mailbox"),
    ("tx_can", "TX: Can_Write alone (frame into the mailbox)"),
    (
        "rx_path",
        "RX: mailbox -> CanIf -> PduR -> Com -> Com_ReceiveSignal",
    ),
    (
        "rx_canif",
        "RX: CanIf_RxIndication alone (lookup, HRH, DLC)",
    ),
    (
        "rx_pdur_com",
        "RX: PduR_CanIfRxIndication -> Com_RxIndication",
    ),
    ("rx_com_read", "RX: Com_ReceiveSignal alone (unpack)"),
];

/// The ECU's own paths in the host build (`cw-ecu`), measured on Figure 7: (the function
/// callgrind collects in, inclusive of its callees, what it does). Each is out of line in
/// the ECU itself, so its instructions per call are the whole Ir collected inside it
/// divided by the calls callgrind counted into it.
pub const ECU_PATHS: &[(&str, &str)] = &[
    (
        "cw_firmware::ecu::Ecu<P,B>::com_task",
        "OsComTask job: RTE read under RES_RTE, CanTranslate, RES_COM, the send",
    ),
    (
        "cw_firmware::ecu::ComStack<C>::send",
        "its send: Com_SendSignal (level, distance) -> PduR -> CanIf -> host controller's write",
    ),
    (
        "cw_firmware::ecu::Ecu<P,B>::can_isr",
        "CanIsr: kernel entry/return, RES_COM, the controller's event, CanIf/PduR/Com",
    ),
];

/// The scenario the ECU paths are measured on.
const ECU_SCENARIO: &str = "scenarios/figure7.txt";

/// Iteration counts of the two runs per probe.
const LOW: u64 = 1000;
const HIGH: u64 = 2000;

const EXAMPLE: &str = "callgrind_probe";
const STACK_EXAMPLE: &str = "stack_probe";

/// Options of `cargo xtask callgrind`.
#[derive(Default, clap::Args)]
pub struct Options {
    /// A prebuilt probe binary to measure (taking `<op> <iterations>`) instead of
    /// building core/examples/callgrind_probe.rs in release
    #[arg(long, value_name = "PATH")]
    pub binary: Option<PathBuf>,
}

/// Builds the probe binary (unless one is given) and prints instructions per call for
/// every probe.
pub fn run(options: &Options) -> Result {
    // The stack probe, and the core's probe unless one is given, in one cargo build: the
    // two crates' release builds (each linked with fat LTO) then share the two cores,
    // about 18 s less than one after the other.
    let mut build = Cmd::new("cargo").args(["build", "--release", "-p", "cw-firmware"]);
    if options.binary.is_none() {
        build = build.args(["-p", "cw-core", "--example", EXAMPLE]);
    }
    build.args(["--example", STACK_EXAMPLE]).run()?;
    let binary = match &options.binary {
        Some(binary) => binary.clone(),
        None => target_dir().join("release").join("examples").join(EXAMPLE),
    };
    if !binary.exists() {
        return Err(format!("probe binary {} not found", binary.display()));
    }
    let out_dir = out_dir()?;

    let stack_binary = target_dir()
        .join("release")
        .join("examples")
        .join(STACK_EXAMPLE);
    let probes = PROBES
        .iter()
        .map(|p| (&binary, p))
        .chain(STACK_PROBES.iter().map(|p| (&stack_binary, p)));

    let mut rows = Vec::new();
    let mut errors = Vec::new();
    for (description, measured) in ecu_paths()? {
        match measured {
            Ok((per_call, calls)) => {
                rows.push(("ecu", description, format!("{per_call:.1} ({calls} calls)")))
            }
            Err(e) => {
                rows.push(("ecu", description, "ERROR".into()));
                errors.push(e);
            }
        }
    }
    for (binary, &(op, description)) in probes {
        match measure_probe(binary, &out_dir, op) {
            Ok(per_call) => rows.push((op, description, format!("{per_call:.2}"))),
            Err(e) => {
                rows.push((op, description, "ERROR".into()));
                errors.push(format!("{op}: {e}"));
            }
        }
    }

    let w_op = rows.iter().map(|r| r.0.len()).max().unwrap_or(2).max(2);
    let w_desc = rows.iter().map(|r| r.1.len()).max().unwrap_or(11).max(11);
    println!(
        "\ninstructions per call (callgrind Ir, ({HIGH} calls - {LOW} calls) / {}, x86-64 release build)",
        HIGH - LOW
    );
    println!(
        "{:<w_op$} | {:<w_desc$} | instructions/call",
        "op", "description"
    );
    println!(
        "{}-|-{}-|-{}",
        "-".repeat(w_op),
        "-".repeat(w_desc),
        "-".repeat(17)
    );
    for (op, description, value) in &rows {
        println!("{op:<w_op$} | {description:<w_desc$} | {value:>17}");
    }
    println!("callgrind output files: {}", out_dir.display());
    if errors.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} probe(s) failed:\n  {}",
            errors.len(),
            errors.join("\n  ")
        ))
    }
}

/// Instructions per call of `probe_<op>` in `binary`: two runs, [`LOW`] and [`HIGH`]
/// calls, so that whatever does not grow with the calls cancels.
fn measure_probe(binary: &Path, out_dir: &Path, op: &str) -> Result<f64> {
    let low = measure(binary, out_dir, op, LOW)?;
    let high = measure(binary, out_dir, op, HIGH)?;
    per_call(op, low, high)
}

/// The output files' folder.
fn out_dir() -> Result<PathBuf> {
    let out_dir = target_dir().join("xtask-callgrind");
    std::fs::create_dir_all(&out_dir)
        .map_err(|e| format!("creating {}: {e}", out_dir.display()))?;
    Ok(out_dir)
}

/// Builds the stack probe (`firmware/examples/stack_probe.rs`) and gives its path.
pub fn stack_probe_binary() -> Result<PathBuf> {
    Cmd::new("cargo")
        .args([
            "build",
            "--release",
            "-p",
            "cw-firmware",
            "--example",
            STACK_EXAMPLE,
        ])
        .run()?;
    Ok(target_dir()
        .join("release")
        .join("examples")
        .join(STACK_EXAMPLE))
}

/// Instructions per call of the stack probe `op` in `binary` ([`stack_probe_binary`]).
pub fn stack_probe(binary: &Path, op: &str) -> Result<f64> {
    measure_probe(binary, &out_dir()?, op).map_err(|e| format!("{op}: {e}"))
}

/// One of [`ECU_PATHS`] measured: what it does, and its instructions per call and the
/// calls, or what went wrong.
pub type EcuPath = (&'static str, Result<(f64, u64)>);

/// Builds `cw-ecu` and measures each of [`ECU_PATHS`] on Figure 7.
pub fn ecu_paths() -> Result<Vec<EcuPath>> {
    Cmd::new("cargo")
        .args(["build", "--release", "-p", "cw-firmware", "--bin", "cw-ecu"])
        .run()?;
    let ecu = target_dir().join("release").join("cw-ecu");
    let out_dir = out_dir()?;
    Ok(ECU_PATHS
        .iter()
        .enumerate()
        .map(|(i, &(function, description))| {
            (
                description,
                measure_ecu(&ecu, &out_dir, i, function).map_err(|e| format!("{function}: {e}")),
            )
        })
        .collect())
}

/// Runs one probe under callgrind and returns the collected instruction count.
fn measure(binary: &Path, out_dir: &Path, op: &str, iterations: u64) -> Result<u64> {
    let out_file = out_dir.join(format!("callgrind.out.{op}.{iterations}"));
    let iterations = iterations.to_string();
    let text = collect(
        binary,
        &[op, &iterations],
        &format!("*probe_{op}*"),
        &out_file,
    )?;
    read_total(&text)
        .ok_or_else(|| format!("no `totals:` or `summary:` line in {}", out_file.display()))
}

/// Runs `binary args..` under callgrind collecting only inside functions matching
/// `toggle` (and what they call); returns the output file's text.
fn collect(binary: &Path, args: &[&str], toggle: &str, out_file: &Path) -> Result<String> {
    let _ = std::fs::remove_file(out_file);
    let mut out_arg = std::ffi::OsString::from("--callgrind-out-file=");
    out_arg.push(out_file);
    let run = Cmd::new("valgrind")
        .args(["--tool=callgrind", "--collect-atstart=no"])
        .arg(out_arg)
        .arg(format!("--toggle-collect={toggle}"))
        .arg(binary)
        .args(args)
        .capture()?;
    if !run.success {
        return Err(format!(
            "the run of {} failed:\n{}{}",
            binary.display(),
            run.stdout,
            tail(&run.stderr, 20)
        ));
    }
    std::fs::read_to_string(out_file).map_err(|e| format!("reading {}: {e}", out_file.display()))
}

/// Runs the ECU on Figure 7 collecting only inside `function` (and what it calls);
/// returns its instructions per call and the calls.
fn measure_ecu(binary: &Path, out_dir: &Path, index: usize, function: &str) -> Result<(f64, u64)> {
    let out_file = out_dir.join(format!("callgrind.out.ecu.{index}"));
    let scenario = crate::process::root().join(ECU_SCENARIO);
    let scenario = scenario.to_string_lossy();
    let text = collect(binary, &["--scenario", &scenario], function, &out_file)?;
    let total = read_total(&text)
        .ok_or_else(|| format!("no `totals:` or `summary:` line in {}", out_file.display()))?;
    let calls = calls_into(&text, function);
    if calls == 0 || total == 0 {
        return Err(format!(
            "callgrind counted {calls} calls into `{function}` and {total} instructions: is it \
             in the binary (`nm -C` lists it) and #[inline(never)]?"
        ));
    }
    Ok((total as f64 / calls as f64, calls))
}

/// The calls into `function` that a callgrind output file records: every `calls=N` line
/// after a `cfn=` naming it (by name, or by the id its first mention gave it, in a `fn=`
/// or a `cfn=` line).
fn calls_into(text: &str, function: &str) -> u64 {
    let mut id: Option<&str> = None;
    let mut current = false;
    let mut calls = 0u64;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("fn=") {
            if let (tag, Some(name)) = split_tag(rest) {
                if name == function {
                    id = Some(tag);
                }
            }
        } else if let Some(rest) = line.strip_prefix("cfn=") {
            let (tag, name) = split_tag(rest);
            if name == Some(function) {
                id = Some(tag);
            }
            current = name == Some(function) || (name.is_none() && Some(tag) == id);
        } else if let Some(rest) = line.strip_prefix("calls=") {
            if current {
                calls += rest
                    .split_whitespace()
                    .next()
                    .and_then(|n| n.parse::<u64>().ok())
                    .unwrap_or(0);
            }
            current = false;
        }
    }
    calls
}

/// `(id) name` or `(id)`: the id and the name if given.
fn split_tag(rest: &str) -> (&str, Option<&str>) {
    match rest.split_once(' ') {
        Some((tag, name)) => (tag, Some(name)),
        None => (rest, None),
    }
}

/// The instruction count of a callgrind output file: its `totals:` line, else `summary:`
/// (first event, which is `Ir` with the default options).
fn read_total(text: &str) -> Option<u64> {
    let field = |prefix: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|n| n.parse::<u64>().ok())
    };
    field("totals:").or_else(|| field("summary:"))
}

fn per_call(op: &str, low: u64, high: u64) -> Result<f64> {
    if low == 0 || high <= low {
        return Err(format!(
            "Ir({LOW}) = {low}, Ir({HIGH}) = {high}: callgrind collected nothing that grows with the \
             iterations; is `probe_{op}` in the binary (`nm -C` lists it), marked #[inline(never)], and not merged by LLVM with an identical probe body?"
        ));
    }
    Ok((high - low) as f64 / (HIGH - LOW) as f64)
}

fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_calls_by_name_and_by_id() {
        let file = "fn=(1) main\ncfn=(2) a::job\ncalls=3 10\n5 9\ncfn=(3) b\ncalls=7 1\n\
                    fn=(4) other\ncfn=(2)\ncalls=4 12\nfn=(5) c\n1 1\nfn=(1)\ncfn=(5)\ncalls=2 3\n";
        assert_eq!(calls_into(file, "a::job"), 7);
        assert_eq!(calls_into(file, "b"), 7);
        assert_eq!(calls_into(file, "c"), 2);
        assert_eq!(calls_into(file, "d"), 0);
    }

    #[test]
    fn reads_totals_then_summary() {
        let file = "version: 1\nevents: Ir\nsummary: 4200\nfn=(1) x\n0 4200\ntotals: 4100\n";
        assert_eq!(read_total(file), Some(4100));
        assert_eq!(read_total("events: Ir\nsummary: 77\n"), Some(77));
        assert_eq!(read_total("events: Ir\n"), None);
    }

    #[test]
    fn per_call_cancels_fixed_cost() {
        assert_eq!(per_call("x", 1000 * 12 + 300, 2000 * 12 + 300), Ok(12.0));
        assert!(per_call("x", 0, 0).is_err());
    }
}
