//! `cargo xtask ci`: every check, in order, each a named stage with a banner, its commands
//! and its wall time, then a summary table. A missing tool is a failure, never a skip.

use crate::process::Cmd;
use crate::setup::NIGHTLY;
use crate::{callgrind, differential, setup, Result};
use std::time::Instant;

/// Fuzz targets run by the `fuzz` stage: bolero tests in the `cw-fuzz` package. cargo-bolero
/// selects the test with `cargo test <name> -- --exact`, so each name is the test's full
/// libtest path (`codec_roundtrip` for a test at the root of an integration-test file,
/// `tests::codec_roundtrip` for one in `mod tests` of the library).
pub const FUZZ_TARGETS: &[&str] = &[
    "targets::codec_roundtrip",
    "targets::scheduler_api",
    "targets::slcan_stream",
    "targets::scenario_text",
    "targets::sensor_uart_stream",
    "targets::dbc_and_log",
    "targets::blf_bytes",
    "targets::view_replay",
    "targets::port_switch",
    "targets::mem_functions",
    "targets::wdgm_alive",
    "targets::slcan_controller",
    "targets::bit_timing",
    "targets::cansm_modes",
    "targets::flexcan_mailboxes",
    "targets::frame_stuffing",
    "targets::os_timeline",
    "targets::arxml_description",
    "targets::bus_description",
];

/// How long the `fuzz` stage runs each target (cargo-bolero `-T`).
const FUZZ_TIME: &str = "6s";

/// Random iterations per bolero harness under Miri (bolero reads `BOLERO_RANDOM_ITERATIONS`
/// in `bolero-engine`'s `rng::Options`; when it is set the 1 s default time limit is lifted,
/// and it takes precedence over `.with_iterations(..)` in a harness).
const MIRI_BOLERO_ITERATIONS: &str = "16";

/// Big-endian target for Miri (like the MPC5748G's PowerPC cores).
const MIRI_BIG_ENDIAN_TARGET: &str = "s390x-unknown-linux-gnu";

/// Stage names, in the order they run.
pub const STAGES: &[&str] = &[
    "setup",
    "fmt",
    "clippy",
    "test",
    "cross",
    "miri",
    "model",
    "coverage",
    "mutants",
    "mutation",
    "qemu",
    "differential",
    "interop",
    "view",
    "docs",
    "fuzz",
    "bench",
    // After `bench`, which builds the release `cw-ecu` and the stack probe it also runs.
    "eval",
];

/// Each stage's time budget on CI's 2-core machine, seconds: printed with the stage and in
/// the summary, where a stage over its budget is marked (the whole run must stay within 45
/// minutes). `setup` is given what a fresh machine needs (the nightly, cargo-bolero,
/// defmt-print, mdBook, valgrind, QEMU, llvm, the Python venv); it takes seconds once those
/// are there.
const BUDGET_S: &[(&str, u32)] = &[
    ("setup", 400),
    ("fmt", 5),
    ("clippy", 90),
    ("test", 305),
    ("cross", 73),
    ("miri", 487),
    ("model", 48),
    ("coverage", 190),
    ("mutants", 78),
    ("mutation", 280),
    ("qemu", 100),
    ("eval", 32),
    ("differential", 6),
    ("interop", 15),
    ("view", 6),
    ("docs", 166),
    ("fuzz", 367),
    ("bench", 50),
];

fn budget_s(stage: &str) -> u32 {
    BUDGET_S
        .iter()
        .find(|(name, _)| *name == stage)
        .map_or(0, |(_, s)| *s)
}

/// Which stages to run.
#[derive(clap::Args)]
pub struct Options {
    /// Run only these stages (comma-separated, repeatable)
    #[arg(long, value_name = "STAGE,..", value_delimiter = ',', value_parser = stage)]
    only: Vec<&'static str>,
    /// Skip these stages (comma-separated, repeatable)
    #[arg(long, value_name = "STAGE,..", value_delimiter = ',', value_parser = stage)]
    skip: Vec<&'static str>,
    /// Go on after a failing stage (the summary still fails)
    #[arg(long)]
    keep_going: bool,
}

impl Options {
    /// Only the given stages.
    pub fn only(stages: &[&'static str]) -> Self {
        Self {
            only: stages.to_vec(),
            skip: Vec::new(),
            keep_going: false,
        }
    }

    /// The stages to run, in order.
    fn stages(&self) -> Result<Vec<&'static str>> {
        let stages: Vec<&'static str> = STAGES
            .iter()
            .copied()
            .filter(|s| self.only.is_empty() || self.only.contains(s))
            .filter(|s| !self.skip.contains(s))
            .collect();
        if stages.is_empty() {
            return Err("ci: --only/--skip leave no stage to run".into());
        }
        Ok(stages)
    }
}

/// A stage's name.
fn stage(name: &str) -> Result<&'static str> {
    STAGES
        .iter()
        .copied()
        .find(|s| *s == name.trim())
        .ok_or_else(|| format!("unknown stage `{name}`; stages are {}", STAGES.join(", ")))
}

enum Outcome {
    Passed,
    Failed(String),
    NotRun,
}

/// Runs the selected stages and prints the summary; fails if any stage failed.
pub fn run(options: &Options) -> Result {
    let stages = options.stages()?;
    println!(
        "xtask ci: stages {} (CI={})",
        stages.join(", "),
        std::env::var("CI").unwrap_or_default()
    );
    let mut results: Vec<(&str, Outcome, f64)> = Vec::new();
    let mut stop = false;
    for &stage in &stages {
        if stop {
            results.push((stage, Outcome::NotRun, 0.0));
            continue;
        }
        println!("\n== stage: {stage} (budget {} s)", budget_s(stage));
        let start = Instant::now();
        let result = run_stage(stage);
        let secs = start.elapsed().as_secs_f64();
        match result {
            Ok(()) => {
                println!("== stage: {stage} passed in {secs:.1} s");
                results.push((stage, Outcome::Passed, secs));
            }
            Err(e) => {
                println!("== stage: {stage} FAILED in {secs:.1} s\n{e}");
                results.push((stage, Outcome::Failed(e), secs));
                stop = !options.keep_going;
            }
        }
    }

    let passed = results
        .iter()
        .filter(|r| matches!(r.1, Outcome::Passed))
        .count();
    let failed = results
        .iter()
        .filter(|r| matches!(r.1, Outcome::Failed(_)))
        .count();
    let not_run = results
        .iter()
        .filter(|r| matches!(r.1, Outcome::NotRun))
        .count();
    println!("\n== summary");
    println!(
        "{:<14} {:<8} {:>9} {:>9}",
        "stage", "result", "seconds", "budget"
    );
    for (stage, outcome, secs) in &results {
        let budget = budget_s(stage);
        let (word, shown) = match outcome {
            Outcome::Passed => ("pass", format!("{secs:.1}")),
            Outcome::Failed(_) => ("FAIL", format!("{secs:.1}")),
            Outcome::NotRun => ("not run", "-".into()),
        };
        let over = if *secs > f64::from(budget) {
            "  OVER BUDGET"
        } else {
            ""
        };
        println!("{stage:<14} {word:<8} {shown:>9} {budget:>9}{over}");
    }
    let total: f64 = results.iter().map(|r| r.2).sum();
    let total_budget: u32 = results.iter().map(|r| budget_s(r.0)).sum();
    println!("{:<14} {:<8} {total:>9.1} {total_budget:>9}", "total", "");
    if not_run == 0 {
        println!("{passed} passed, {failed} failed");
    } else {
        println!("{passed} passed, {failed} failed, {not_run} not run");
    }
    if failed == 0 {
        Ok(())
    } else {
        let first = results
            .iter()
            .find_map(|(stage, outcome, _)| match outcome {
                Outcome::Failed(e) => Some(format!("stage `{stage}`: {e}")),
                _ => None,
            })
            .unwrap_or_default();
        Err(format!("{failed} stage(s) failed; first: {first}"))
    }
}

fn run_stage(stage: &str) -> Result {
    match stage {
        "setup" => setup::run(),
        "fmt" => Cmd::new("cargo").args(["fmt", "--all", "--check"]).run(),
        "clippy" => {
            // The committed tables are what the ECU's description generates (the
            // generator is part of this stage's build: xtask links it).
            crate::generate::run(&crate::generate::Options { check: true })?;
            Cmd::new("cargo")
                .args([
                    "clippy",
                    "--workspace",
                    "--all-targets",
                    "--",
                    "-D",
                    "warnings",
                ])
                .run()
        }
        // The emulator-in-the-loop tests (`cw-tests`) need the image: the `qemu` stage
        // builds it and runs them.
        "test" => Cmd::new("cargo")
            .args(["test", "--workspace", "--exclude", "cw-tests"])
            .run(),
        "cross" => {
            Cmd::new("cargo")
                .args([
                    "build",
                    "-p",
                    "cw-core",
                    "--release",
                    "--target",
                    "thumbv7em-none-eabihf",
                ])
                .run()?;
            // The Cortex-M port and the boards pass clippy as the host code does: mps2 with
            // the scenario images' trace and bus-fault model (also with the paper's
            // extended tasks, which the evaluation measures), and as the production image
            // has them (without); the S32K144EVB's image with either sensor.
            for features in [
                "scenario",
                "scenario,extended-tasks",
                "mps2",
                "s32k144evb",
                "s32k144evb-uart",
            ] {
                Cmd::new("cargo")
                    .args([
                        "clippy",
                        "-p",
                        "cw-firmware",
                        "--no-default-features",
                        "--features",
                        features,
                        "--bins",
                        "--release",
                        "--target",
                        "thumbv7em-none-eabihf",
                        "--",
                        "-D",
                        "warnings",
                    ])
                    .run()?;
            }
            // The S32K144EVB's image as it will be flashed (the whole ECU for the
            // Cortex-M4F): its flash configuration field, vector table, flash and RAM read
            // back from the ELF.
            crate::s32k144::build()?;
            // The MPC5748G's board layer, the core and the FlexCAN driver for the Book E
            // target (big-endian 32-bit PowerPC), linked with the boot header.
            crate::mpc5748g::run()
        }
        "miri" => {
            // One run, on the big-endian target: it executes the unit tests the host run
            // did, with the same undefined-behaviour checks (the only `unsafe` code the
            // core's tests reach is in its dependencies and the standard library, and
            // Miri checks it on either target), plus the OSEK conformance suite, on the
            // byte order of the MPC5748G. Little-endian behaviour is what the `test` stage
            // runs natively. criterion, whose build needs a target C compiler, is a
            // dev-dependency of cw-core only off s390x (see core/Cargo.toml).
            Cmd::new("cargo")
                .arg(format!("+{NIGHTLY}"))
                .args(["miri", "test", "-p", "cw-core", "--target"])
                .arg(MIRI_BIG_ENDIAN_TARGET)
                .env("MIRIFLAGS", "-Zmiri-disable-isolation")
                .env("BOLERO_RANDOM_ITERATIONS", MIRI_BOLERO_ITERATIONS)
                // Per-test wall time, so slow harnesses under Miri are visible in the log.
                .args(["--", "-Zunstable-options", "--report-time"])
                .run()?;
            // The FlexCAN driver and its model on the same byte order: the driver's one
            // `unsafe` (volatile accesses) and its data words, as the MPC5748G sees them.
            Cmd::new("cargo")
                .arg(format!("+{NIGHTLY}"))
                .args(["miri", "test", "-p", "cw-bsp", "--lib", "--target"])
                .arg(MIRI_BIG_ENDIAN_TARGET)
                .env("MIRIFLAGS", "-Zmiri-disable-isolation")
                .env("BOLERO_RANDOM_ITERATIONS", MIRI_BOLERO_ITERATIONS)
                .args(["--", "chip::flexcan", "-Zunstable-options", "--report-time"])
                .run()
        }
        "model" => Cmd::new("cargo")
            .args(["run", "--release", "-p", "cw-proofs"])
            .run(),
        "coverage" => crate::coverage::run(&crate::coverage::Options::ci()),
        "mutants" => crate::mutants::run(),
        "mutation" => crate::mutation::run(&crate::mutation::Options::ci()),
        "qemu" => crate::qemu::run(&crate::qemu::Options::ci()),
        "eval" => crate::eval::run(&crate::eval::Options::ci()),
        "differential" => {
            differential::run(&differential::Options::default())?;
            crate::dbc_differential::run(&crate::dbc_differential::Options::default())
        }
        "interop" => interop(),
        "view" => crate::view::run(),
        "docs" => crate::docs::run(&crate::docs::Options::ci()),
        "fuzz" => {
            for target in FUZZ_TARGETS {
                // libFuzzer engine (the default) with AddressSanitizer: needs the nightly.
                // Build: `--profile fuzz` (defined in the workspace Cargo.toml), target dir
                // `target/fuzz/build_<hash of RUSTFLAGS>`. Corpus: `<dir of the test
                // file>/__fuzz__/<test path with :: as __>/corpus`, crashes beside it.
                Cmd::new("cargo")
                    .args([
                        "bolero",
                        "test",
                        "--toolchain",
                        NIGHTLY,
                        "--engine",
                        "libfuzzer",
                    ])
                    .args(["-p", "cw-fuzz", target, "-T", FUZZ_TIME])
                    .run()?;
            }
            Ok(())
        }
        "bench" => {
            println!("$ cargo xtask callgrind   (in-process)");
            callgrind::run(&callgrind::Options::default())?;
            // Simulation speed: the paper ran its ECU for 30 minutes.
            ecu_run()
                .args(["--scenario", "scenarios/approach.txt", "--duration", "1800"])
                .run()
        }
        other => Err(format!("no such stage `{other}`")),
    }
}

/// `cargo run --release` of the ECU simulation (`cw-ecu`); its options follow.
pub(crate) fn ecu_run() -> Cmd {
    Cmd::new("cargo").args([
        "run",
        "--quiet",
        "--release",
        "-p",
        "cw-firmware",
        "--bin",
        "cw-ecu",
        "--",
    ])
}

/// The ECU's CAN log and trace, read back by python-can and cantools with the DBC: every
/// distance on the bus equals what the ECU measured, for each example scenario. Then
/// random frames written by python-can as candump, ASC and BLF, read back by `cw-can`.
fn interop() -> Result {
    let out = crate::process::root().join("target").join("interop");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    for scenario in ["figure7", "faults", "approach", "shutdown"] {
        let trace = out.join(format!("{scenario}.csv"));
        let log = out.join(format!("{scenario}.log"));
        ecu_run()
            .arg("--scenario")
            .arg(format!("scenarios/{scenario}.txt"))
            .arg("--trace")
            .arg(&trace)
            .arg("--can-log")
            .arg(&log)
            .run()?;
        let dbc = crate::process::root().join("firmware").join("ecu.dbc");
        crate::setup::run_python_tool("interop_check.py", &[&dbc, &log, &trace])?;
    }
    // canmatrix's export of the DBC as AUTOSAR ARXML, read by the generator's reader:
    // the same bus.
    let dbc = crate::process::root().join(cw_gen::DBC);
    let exported = out.join("ecu-canmatrix.arxml");
    Cmd::new(crate::setup::venv_dir().join("bin").join("canconvert"))
        .arg(&dbc)
        .arg(&exported)
        .run()?;
    crate::system::compare(&dbc, &exported)?;
    // And the other way: canmatrix imports the generated system description as a DBC.
    // It reads no DATA-CONSTR (it gives each signal its type's range), so the ranges are
    // not compared; everything else is.
    let imported = out.join("system-canmatrix.dbc");
    Cmd::new(crate::setup::venv_dir().join("bin").join("canconvert"))
        .arg(crate::process::root().join(cw_gen::SYSTEM))
        .arg(&imported)
        .run()?;
    // canmatrix names its output after the cluster: `system-canmatrix_CAN.dbc`.
    let imported = out.join("system-canmatrix_CAN.dbc");
    let without_ranges = |mut bus: cw_gen::system::System| {
        for s in bus.frames.iter_mut().flat_map(|f| f.signals.iter_mut()) {
            s.range = None;
        }
        bus
    };
    let ours = without_ranges(crate::system::dbc_system(&dbc)?);
    let theirs = without_ranges(crate::system::dbc_system(&imported)?);
    let (differences, _) = cw_gen::system::differences(&ours, &theirs);
    if !differences.is_empty() {
        return Err(format!(
            "canmatrix's DBC of {} differs from {}:\n{}",
            cw_gen::SYSTEM,
            cw_gen::DBC,
            differences.join("\n")
        ));
    }
    println!(
        "interop: canmatrix imports {} as {}'s bus (the ranges, which it does not read, not compared)",
        cw_gen::SYSTEM,
        cw_gen::DBC
    );
    // python-can's log writers against cw-can's readers.
    crate::log_formats::run(&crate::log_formats::Options::default())
}
