//! Task runner of the workspace (`cargo xtask ...`, alias in `.cargo/config.toml`).
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
//!   both ways explained in `docs/coverage.md`;
//! - `cargo xtask mutants`: kernel mutants the OSEK conformance suite must catch;
//! - `cargo xtask mutation [--shard K/N | --ci] [--file PATH]..`: cargo-mutants over the
//!   verified kernels, every survivor killed or listed as equivalent in `docs/mutants.md`;
//! - `cargo xtask qemu [--scenario FILE].. [--compare] [--live] [--events] [--profile]
//!   [--flash] [--serial tcp:PORT]`:
//!   the ECU's Cortex-M4 image on QEMU's mps2-an386, the emulator-in-the-loop tests against
//!   the host simulation (`tests/`), and python-can against it live;
//! - `cargo xtask qemu-runner IMAGE [ARGS]..`: cargo's runner for the board's target
//!   (`cargo run` on an image): QEMU with `ARGS` as the image's command line, its defmt
//!   log decoded as it comes.
//!
//! Every command the runner starts is printed first, prefixed with `$`. Child processes get
//! no stdin, so the runner behaves the same in a terminal and under `CI=true`.

mod callgrind;
mod ci;
mod coverage;
mod dbc_differential;
mod decode_speed;
mod differential;
mod log_formats;
mod mutants;
mod mutation;
mod process;
mod profile;
mod qemu;
mod rng;
mod setup;

use std::process::ExitCode;

/// What went wrong, in words meant for the person reading the CI log.
pub type Error = String;
/// Result of a task.
pub type Result<T = ()> = std::result::Result<T, Error>;

const USAGE: &str = "\
usage: cargo xtask <command> [options]

commands:
  ci [--only STAGE[,STAGE..]] [--skip STAGE[,STAGE..]] [--keep-going]
        run the checks in order; stages: setup, fmt, clippy, test, cross, miri, model,
        coverage, mutants, mutation, qemu, differential, interop, fuzz, bench. Stops at
        the first failing stage unless --keep-going. Each stage prints its time budget.
  differential [--cases N] [--seed SEED]
        compare the Com signal codec with cantools on N random cases (default 20000)
  dbc-differential [--frames N] [--seed SEED]
        compare cw-can's decoding and encoding with cantools on random DBCs, at least N
        frames (default 12000)
  log-formats [--frames N] [--seed SEED]
        write N random frames (default 3000) with python-can as candump, ASC and BLF,
        and compare cw-can's readings with python-can's
  decode-speed [--frames N]
        time cw-can decode (release) and cantools decode on one log of N frames
        (default 200000)
  callgrind [--binary PATH]
        count instructions per call of each probe in core/examples/callgrind_probe.rs
        (built in release), or in a prebuilt probe binary taking `<op> <iterations>`
  coverage [--write]
        branch coverage of core/ (cw-core's unit tests and OSEK suite, cargo-llvm-cov on
        the pinned nightly); fails on a branch not taken both ways that docs/coverage.md
        does not explain, or one it lists that is covered now; --write updates its table
  mutants
        plant each kernel mutant in a copy of the workspace and require the OSEK
        conformance sequences named for it to fail
  mutation [--shard K/N | --ci] [--file PATH]..
        cargo-mutants over the verified kernels (xtask/src/mutation.rs lists the files):
        every mutant, or shard K of N (--ci: the check command's shard, chosen by the
        number of commits on HEAD); fails on a mutant that survives every test and is not
        listed as equivalent in docs/mutants.md; prints each file's score
  qemu [--scenario FILE].. [--compare] [--live] [--events] [--profile] [--flash]
       [--serial tcp:PORT]
        build the ECU's Cortex-M4 image and run it on QEMU's mps2-an386 on each scenario
        file (default scenarios/figure7.txt; the image reads it over semihosting);
        --compare: the emulator-in-the-loop tests (tests/, cw-tests): figure7 and faults
        give the host simulation's CAN frames and LED levels, bad scenarios are refused;
        --live: run it in real time on a TCP port and test it with python-can (slcan)
        --events: run the extended-task and stack-guard demo image (cw-qemu-events)
        --profile: count where the image's instructions go, per function
        --flash: the production image (cw-mps2): its flash and RAM, then live
        --serial: serve the SLCAN UART on a TCP port (python-can: slcan, socket://)
  qemu-runner IMAGE [ARGS]..
        cargo's runner for thumbv7em-none-eabihf: IMAGE on QEMU's mps2-an386 with ARGS on
        its semihosting command line, its defmt log decoded by defmt-print as it comes
  setup
        same as `ci --only setup`: install or check every tool the checks need
  help
        this text
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("\nxtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &[String]) -> Result {
    let Some((command, rest)) = args.split_first() else {
        print!("{USAGE}");
        return Err("no command given".into());
    };
    match command.as_str() {
        "ci" => ci::run(&ci::Options::parse(rest)?),
        "setup" => {
            no_options(rest)?;
            ci::run(&ci::Options::parse(&["--only".into(), "setup".into()])?)
        }
        "differential" => differential::run(&differential::Options::parse(rest)?),
        "decode-speed" => decode_speed::run(&decode_speed::Options::parse(rest)?),
        "log-formats" => log_formats::run(&log_formats::Options::parse(rest)?),
        "dbc-differential" => dbc_differential::run(&dbc_differential::Options::parse(rest)?),
        "callgrind" => callgrind::run(&callgrind::Options::parse(rest)?),
        "qemu" => qemu::run(&qemu::Options::parse(rest)?),
        "qemu-runner" => qemu::runner(rest),
        "mutants" => {
            no_options(rest)?;
            mutants::run()
        }
        "coverage" => coverage::run(&coverage::Options::parse(rest)?),
        "mutation" => mutation::run(&mutation::Options::parse(rest)?),
        "help" | "--help" | "-h" => {
            print!("{USAGE}");
            Ok(())
        }
        other => {
            print!("{USAGE}");
            Err(format!("unknown command `{other}`"))
        }
    }
}

fn no_options(rest: &[String]) -> Result {
    match rest.first() {
        None => Ok(()),
        Some(arg) => Err(format!(
            "unexpected argument `{arg}`; see `cargo xtask help`"
        )),
    }
}

/// The value following an option such as `--cases`.
fn option_value<'a>(name: &str, it: &mut impl Iterator<Item = &'a String>) -> Result<&'a str> {
    it.next()
        .map(String::as_str)
        .ok_or_else(|| format!("option {name} needs a value"))
}
