//! Task runner of the workspace (`cargo xtask ...`, alias in `.cargo/config.toml`). The book
//! describes each check: [the check command](../../book/check.html).
//!
//! - `cargo xtask ci [--only S,..] [--skip S,..] [--keep-going]`: every check, in order,
//!   from installing the tools (`setup`) to the instruction counts (`bench`);
//! - `cargo xtask differential [--cases N] [--seed S]`: the Com signal codec against
//!   cantools on random layouts, values and PDU lengths;
//! - `cargo xtask dbc-differential [--frames N] [--seed S]`: `cw-can`'s DBC decoding and
//!   encoding against cantools on random DBCs;
//! - `cargo xtask log-formats [--frames N] [--seed S]`: python-can's ASC, BLF and candump
//!   writers against `cw-can`'s readers;
//! - `cargo xtask decode-speed [--frames N]`: `cw-can decode` and `cantools decode` timed
//!   on one large log;
//! - `cargo xtask callgrind`: instructions per call of the codec and scheduler probes;
//! - `cargo xtask coverage [--write]`: branch coverage of the core, every branch not taken
//!   both ways explained in `docs/src/coverage.md`;
//! - `cargo xtask mutants`: kernel mutants the OSEK conformance suite must catch;
//! - `cargo xtask mutation [--shard K/N | --ci] [--file PATH]..`: cargo-mutants over the
//!   verified kernels, every survivor killed or listed as equivalent in `docs/src/mutants.md`;
//! - `cargo xtask generate [--check]`: the firmware's configuration tables generated from
//!   the ECU's ARXML description (the paper's step 3), or checked against it;
//! - `cargo xtask system --from-dbc DBC | --to-dbc ARXML | --compare DBC ARXML [--out FILE]`:
//!   a bus's system description (ARXML) from its DBC, the DBC from the description, or the
//!   two compared;
//! - `cargo xtask qemu [--scenario FILE].. [--compare] [--live] [--events] [--profile]
//!   [--flash] [--serial tcp:PORT]`:
//!   the ECU's Cortex-M4 image on QEMU's mps2-an386, the emulator-in-the-loop tests against
//!   the host simulation (`tests/`), and python-can against it live;
//! - `cargo xtask eval [--duration S] [--scenario FILE] [--out DIR] [--book]`: the paper's
//!   evaluation on this ECU (its Table 1, task periodicity and jitter, on the Cortex-M4
//!   image), a Markdown report with its samples as CSV and its plots as SVG;
//! - `cargo xtask s32k144 [--uart-sensor] [--flash] [--probe VID:PID]`: the ECU's image for NXP's
//!   S32K144EVB built and checked (the flash configuration field at 0x400, the vector
//!   table, flash and RAM), then written to the board through a debug probe (probe-rs);
//! - `cargo xtask mpc5748g`: the MPC5748G board layer built for the Book E target
//!   (pinned nightly, `-Z build-std=core`) into the bring-up image, its boot header and
//!   memory checked from the ELF (it cannot run: the chip executes only VLE code);
//! - `cargo xtask view`: `cw-can view` in headless Chromium on the ECU's Figure 7 log,
//!   checked against the trace; the screenshots of the paper's Figure 8 in `docs/src/view/`;
//! - `cargo xtask docs [--file PATH].. [--no-examples]`: the book (mdBook) and the API docs
//!   (`cargo doc`, warnings denied) built, every relative link of the README, the book and
//!   the crate pages resolved, and every `console` example of the README and the book run
//!   and compared with its output as shown;
//! - `cargo xtask book [--open]`: the book built and its links checked (no examples), in
//!   `target/book/`;
//! - `cargo xtask qemu-runner IMAGE [ARGS]..`: cargo's runner for the boards' target
//!   (`cargo run` on an image): QEMU with `ARGS` as the image's command line, its defmt
//!   log decoded as it comes; the S32K144EVB's image (`cw-s32k144`) goes to the board
//!   through probe-rs instead.
//!
//! Every command the runner starts is printed first, prefixed with `$`. Child processes get
//! no stdin, so the runner behaves the same in a terminal and under `CI=true`.

mod callgrind;
mod ci;
mod coverage;
mod dbc_differential;
mod decode_speed;
mod differential;
mod docs;
mod eval;
mod generate;
mod image;
mod log_formats;
mod mpc5748g;
mod mutants;
mod mutation;
mod process;
mod profile;
mod qemu;
mod rng;
mod s32k144;
mod setup;
mod system;
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// What went wrong, in words meant for the person reading the CI log.
pub type Error = String;
/// Result of a task.
pub type Result<T = ()> = std::result::Result<T, Error>;

/// Task runner of the workspace: every check of `cargo xtask ci`, and each of its parts.
#[derive(Parser)]
#[command(name = "cargo xtask", bin_name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the checks in order (stages: setup, fmt, clippy, test, cross, miri, model,
    /// coverage, mutants, mutation, qemu, eval, differential, interop, view, docs, fuzz, bench); stop
    /// at the first failing stage unless --keep-going; each stage prints its time budget
    Ci(ci::Options),
    /// Install what the checks need (the check command's setup stage)
    Setup,
    /// Compare the Com signal codec with cantools on random layouts, values and PDU
    /// lengths
    Differential(differential::Options),
    /// Compare cw-can's decoding and encoding with cantools on random DBCs
    DbcDifferential(dbc_differential::Options),
    /// Write random frames with python-can as candump, ASC and BLF, and compare cw-can's
    /// readings with python-can's
    LogFormats(log_formats::Options),
    /// Time cw-can decode (release) and cantools decode on one large log
    DecodeSpeed(decode_speed::Options),
    /// Count instructions per call of each probe in core/examples/callgrind_probe.rs
    Callgrind(callgrind::Options),
    /// Branch coverage of core/ (cargo-llvm-cov on the pinned nightly); fails on a branch
    /// not taken both ways that docs/src/coverage.md does not explain, or one it lists that is
    /// covered now
    Coverage(coverage::Options),
    /// Plant each kernel mutant in a copy of the workspace and require the OSEK
    /// conformance sequences named for it to fail
    Mutants,
    /// cargo-mutants over the verified kernels; fails on a survivor not listed as
    /// equivalent in docs/src/mutants.md; prints each file's score
    Mutation(mutation::Options),
    /// Build the ECU's Cortex-M4 image and run it on QEMU's mps2-an386
    Qemu(qemu::Options),
    /// Generate the firmware's configuration tables (firmware/src/generated.rs) from the
    /// ECU's description (firmware/ecu.arxml); --check fails where they disagree
    Generate(generate::Options),
    /// A bus's system description (ARXML) from its DBC, the DBC from the description, or the
    /// two compared (firmware/system.arxml is generated from firmware/ecu.dbc by `generate`)
    System(system::Options),
    /// The paper's evaluation on this ECU: the periodicity of its tasks (the paper's
    /// Table 1) on the Cortex-M4 image, written as a report with its samples and plots
    Eval(eval::Options),
    /// Build and check the ECU's image for NXP's S32K144EVB (flash configuration field,
    /// vector table, flash and RAM); with --flash, write it to the board with probe-rs and
    /// show its log
    S32k144(s32k144::Options),
    /// Build the MPC5748G board's bring-up image for the Book E target (nightly,
    /// build-std) and check its boot header and memory (it cannot run: the chip executes
    /// only VLE code)
    Mpc5748g,
    /// Check `cw-can view` in headless Chromium on the ECU's Figure 7 log, and write the
    /// four screenshots of the paper's Figure 8 to docs/src/view/
    View,
    /// Build the book and the API docs (warnings denied), check every relative link of the
    /// README, the book and the crate pages, and run every `console` example of the README
    /// and the book, comparing its output with the one shown (the check command's docs stage)
    Docs(docs::Options),
    /// Build the book (installing mdBook if missing) and check its links; print where it is
    Book(docs::BookOptions),
    /// Cargo's runner for thumbv7em-none-eabihf: IMAGE on QEMU with ARGS on its
    /// semihosting command line, its defmt log decoded as it comes (the S32K144EVB's
    /// image, cw-s32k144: onto the board with probe-rs)
    QemuRunner {
        /// The image (ELF)
        image: String,
        /// The image's command line
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

fn main() -> ExitCode {
    // Usage errors are clap's (exit status 2); a failing task prints its error.
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("\nxtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(command: Command) -> Result {
    match command {
        Command::Ci(options) => ci::run(&options),
        Command::Generate(options) => generate::run(&options),
        Command::System(options) => system::run(&options),
        Command::Setup => ci::run(&ci::Options::only(&["setup"])),
        Command::Differential(options) => differential::run(&options),
        Command::DbcDifferential(options) => dbc_differential::run(&options),
        Command::LogFormats(options) => log_formats::run(&options),
        Command::DecodeSpeed(options) => decode_speed::run(&options),
        Command::Callgrind(options) => callgrind::run(&options),
        Command::Coverage(options) => coverage::run(&options),
        Command::Mutants => mutants::run(),
        Command::Mutation(options) => mutation::run(&options),
        Command::Qemu(options) => qemu::run(&options),
        Command::Eval(options) => eval::run(&options),
        Command::S32k144(options) => s32k144::run(&options),
        Command::Mpc5748g => mpc5748g::run(),
        Command::View => view::run(),
        Command::Docs(options) => docs::run(&options),
        Command::Book(options) => docs::book(&options),
        Command::QemuRunner { image, args } => {
            qemu::runner(&std::iter::once(image).chain(args).collect::<Vec<_>>())
        }
    }
}
