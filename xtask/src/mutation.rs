//! `cargo xtask mutation`: cargo-mutants over the verified kernels. Each mutant is one
//! small change cargo-mutants makes to the source (an operator swapped, a condition
//! negated, a function body replaced by a constant); cw-core's unit tests and OSEK
//! conformance suite must fail on it ("caught"). A mutant that builds and passes every
//! test ("missed") must be listed in `docs/src/mutants.md` as equivalent (no input can tell it
//! from the original), with the reason; any other missed mutant fails the command.
//!
//! - `cargo xtask mutation`: every mutant of every kernel file (about 1,200; hours on two
//!   cores), with each file's score at the end;
//! - `cargo xtask mutation --shard K/N`: the mutants `i` with `i % N == K` (cargo-mutants'
//!   round-robin sharding), so shards mix every file;
//! - `cargo xtask mutation --ci`: the check command's stage: shard `C % CI_SHARDS` of
//!   `CI_SHARDS`, where `C` is the number of commits on `HEAD`, so consecutive commits walk
//!   through every shard;
//! - `--file PATH` (repeatable) narrows either to some of the kernel files.
//!
//! What is left out, and why:
//! - the oracles under `spec::` (the reference definitions the tests compare against):
//!   they are the tests' side, and a mutated oracle is an oracle bug, not a kernel bug;
//! - the proofs by exhaustion (every u32 distance, 3.4e9 echo widths, ...) run 10-60 s
//!   each: per mutant they would cost more than the rest of the suite together, and the
//!   bolero harnesses beside them check the same properties on random inputs;
//! - doc tests (each one a separate build).
//!
//! cargo-mutants never looks inside a function named `new`; the kernels' constructors that
//! carry logic therefore hand it to a function of its own (`checked`, `init`), which is
//! mutated like the rest.
//!
//! The copy cargo-mutants makes of the workspace builds into a target directory of its own,
//! `target/mutation/build`: cargo names a workspace crate's artifacts by its path relative
//! to the workspace root, so a copy building into the workspace's target directory would
//! overwrite the workspace's own `cw-core` test binaries with mutated ones. The check
//! command's stage, on a clean working tree (a fresh clone, as in CI), mutates the tree in
//! place instead (`--in-place`, each file restored after its mutant) and reuses the
//! dependencies the `test` stage built; with uncommitted edits it works on a copy.

use crate::process::{root, target_dir, Cmd};
use crate::Result;
use std::collections::BTreeMap;
use std::path::Path;

/// What cargo-mutants made of a mutant: the file (`<outcome>.txt`) that lists it.
#[derive(Clone, Copy)]
enum Outcome {
    Caught,
    Timeout,
    Missed,
    Unviable,
}

/// The verified kernels' source files: every mutant cargo-mutants makes in them is run.
pub const KERNEL_FILES: &[&str] = &[
    "core/src/warning.rs",
    "core/src/sonar.rs",
    "core/src/sonar/uart.rs",
    "core/src/com/signal.rs",
    "core/src/com/ipdu.rs",
    "core/src/canif/mod.rs",
    "core/src/cansm/mod.rs",
    "core/src/os/queue.rs",
    "core/src/os/kernel/mod.rs",
    "core/src/os/kernel/alarm.rs",
    "core/src/os/kernel/control.rs",
    "core/src/os/kernel/event.rs",
    "core/src/os/kernel/interrupt.rs",
    "core/src/os/kernel/resource.rs",
    "core/src/os/kernel/task.rs",
];

/// Mutants matching this (cargo-mutants' `--exclude-re`, against the names `--list` shows)
/// are not generated: the test oracles.
const EXCLUDE_RE: &str = r"\bspec::";

/// Tests skipped for every mutant: the proofs by exhaustion (see the module comment).
pub const SKIPPED_TESTS: &[&str] = &[
    "sonar::tests::conversion_is_rounded_for_every_echo_below_the_timeout",
    "sonar::tests::round_trip_for_every_u16_distance_and_speed",
    "warning::tests::paper_level_exhaustive_over_all_u32",
];

/// Inputs per bolero harness for each mutant. (Without this, each harness runs for 1 s of
/// random inputs: about 40 s of the suite's time per mutant.) bolero draws them afresh on
/// every run (`BOLERO_RANDOM_SEED` only adds one replayed input), so a mutant that only a
/// rare input catches can be caught on one run and missed on another.
const BOLERO_ITERATIONS: &str = "1000";

/// Shards of the check command's stage: 12 or 13 mutants each, about 2 minutes on two
/// cores with the unmutated build.
pub const CI_SHARDS: u32 = 100;

/// The committed list of equivalent mutants.
const EQUIVALENTS: &str = "docs/src/mutants.md";

/// Which mutants to run.
#[derive(clap::Args)]
pub struct Options {
    /// Shard K of N (0 <= K < N) of the mutants
    #[arg(long, value_name = "K/N", value_parser = parse_shard, conflicts_with = "ci")]
    shard: Option<(u32, u32)>,
    /// The check command's shard, chosen by the number of commits on HEAD
    #[arg(long)]
    ci: bool,
    /// Only this kernel file (repeatable)
    #[arg(long = "file", value_name = "PATH", value_parser = kernel_file)]
    files: Vec<String>,
}

impl Options {
    /// The options of the check command's stage.
    pub fn ci() -> Self {
        Self {
            shard: None,
            ci: true,
            files: Vec::new(),
        }
    }
}

/// `--file`: one of the kernel files.
fn kernel_file(file: &str) -> Result<String> {
    if KERNEL_FILES.contains(&file) {
        Ok(file.to_string())
    } else {
        Err(format!(
            "`{file}` is not a kernel file; they are {}",
            KERNEL_FILES.join(", ")
        ))
    }
}

/// `K/N` with `K < N`.
fn parse_shard(text: &str) -> Result<(u32, u32)> {
    let bad = || format!("K/N with 0 <= K < N, not `{text}`");
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let k: u32 = k.trim().parse().map_err(|_| bad())?;
    let n: u32 = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || k >= n {
        return Err(bad());
    }
    Ok((k, n))
}

/// A mutant's name without its line and column, which move whenever the file above it
/// changes: `core/src/warning.rs: replace < with <= in level_for`.
fn key(line: &str) -> Option<String> {
    let (file, rest) = line.split_once(':')?;
    let mut parts = rest.splitn(3, ':');
    let _line = parts.next()?;
    let _column = parts.next()?;
    let what = parts.next()?.trim();
    Some(format!("{file}: {what}"))
}

/// The equivalent mutants listed in `docs/src/mutants.md`: each list item that starts with a
/// key in backticks (``- `core/src/x.rs: replace ... in f`: why``).
fn equivalents(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|line| {
            let rest = line.trim_start().strip_prefix("- `")?;
            let (key, _) = rest.split_once('`')?;
            key.contains(".rs: ").then(|| key.to_string())
        })
        .collect()
}

/// One outcome file of cargo-mutants (`caught.txt`, `missed.txt`, ...): one mutant per
/// line; absent when no mutant had that outcome.
fn outcome_lines(dir: &Path, name: &str) -> Result<Vec<String>> {
    let path = dir.join(name);
    match std::fs::read_to_string(&path) {
        Ok(text) => Ok(text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(str::to_string)
            .collect()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(format!("reading {}: {e}", path.display())),
    }
}

#[derive(Default)]
struct Tally {
    caught: usize,
    timeout: usize,
    missed: usize,
    equivalent: usize,
    unviable: usize,
}

/// Runs cargo-mutants on the chosen mutants and judges what it found.
pub fn run(options: &Options) -> Result {
    let shard = if options.ci {
        let count = Cmd::new("git")
            .args(["rev-list", "--count", "HEAD"])
            .read()?;
        let count: u32 = count
            .trim()
            .parse()
            .map_err(|_| format!("mutation: `git rev-list --count HEAD` said `{count}`"))?;
        let k = count % CI_SHARDS;
        println!(
            "mutation: shard {k}/{CI_SHARDS} ({count} commits on HEAD, mod {CI_SHARDS}); \
             again with `cargo xtask mutation --shard {k}/{CI_SHARDS}`"
        );
        Some((k, CI_SHARDS))
    } else {
        options.shard
    };
    let files: Vec<&str> = if options.files.is_empty() {
        KERNEL_FILES.to_vec()
    } else {
        options.files.iter().map(String::as_str).collect()
    };
    let out = target_dir().join("mutation");
    let listed = std::fs::read_to_string(root().join(EQUIVALENTS))
        .map_err(|e| format!("reading {EQUIVALENTS}: {e}"))?;
    let equivalent = equivalents(&listed);

    // In place only on a clean tree (a fresh clone, as in CI): a developer's uncommitted
    // edits are never under a mutant.
    let in_place = options.ci
        && Cmd::new("git")
            .args(["status", "--porcelain"])
            .read()?
            .trim()
            .is_empty();
    let build_dir = if in_place {
        target_dir()
    } else {
        out.join("build")
    };
    let mut cmd = Cmd::new("cargo")
        .env("CARGO_TARGET_DIR", build_dir)
        .env("BOLERO_RANDOM_ITERATIONS", BOLERO_ITERATIONS)
        .args(["mutants", "-p", "cw-core", "--no-shuffle"])
        .args(["--exclude-re", EXCLUDE_RE, "--output"])
        .arg(&out);
    for file in &files {
        cmd = cmd.args(["--file", file]);
    }
    if in_place {
        cmd = cmd.arg("--in-place");
    }
    if let Some((k, n)) = shard {
        cmd = cmd
            .arg("--shard")
            .arg(format!("{k}/{n}"))
            .args(["--sharding", "round-robin"]);
    }
    // The unit tests and the integration tests (the OSEK conformance suite), not the doc
    // tests or the benches.
    // After cargo-mutants' `--` come cargo test's arguments, so a second `--` for libtest.
    cmd = cmd.args([
        "--cargo-test-arg=--lib",
        "--cargo-test-arg=--tests",
        "--",
        "--",
    ]);
    for test in SKIPPED_TESTS {
        cmd = cmd.args(["--skip", test]);
    }
    // cargo-mutants' exit status says whether some mutant was missed or timed out; whether
    // that is a failure is decided below, against the list of equivalents.
    let status = cmd.status()?;
    let dir = out.join("mutants.out");
    if !dir.join("outcomes.json").is_file() {
        return Err(format!(
            "cargo mutants wrote no outcomes in {} (exit status {status:?})",
            dir.display()
        ));
    }
    // Exit status 4: the tests failed on the unmutated tree, so nothing was judged.
    if status == Some(4) {
        return Err("cargo mutants: the tests fail without any mutant; see its log".into());
    }

    let mut tally: BTreeMap<String, Tally> = files
        .iter()
        .map(|f| ((*f).to_string(), Tally::default()))
        .collect();
    let mut unexplained = Vec::new();
    for (name, outcome) in [
        ("caught.txt", Outcome::Caught),
        ("timeout.txt", Outcome::Timeout),
        ("missed.txt", Outcome::Missed),
        ("unviable.txt", Outcome::Unviable),
    ] {
        for line in outcome_lines(&dir, name)? {
            let file = line.split(':').next().unwrap_or_default().to_string();
            let t = tally.entry(file).or_default();
            match outcome {
                Outcome::Caught => t.caught += 1,
                Outcome::Timeout => t.timeout += 1,
                Outcome::Missed => {
                    let known = key(&line).is_some_and(|k| equivalent.contains(&k));
                    if known {
                        t.equivalent += 1;
                    } else {
                        t.missed += 1;
                        unexplained.push(line);
                    }
                }
                Outcome::Unviable => t.unviable += 1,
            }
        }
    }

    println!(
        "\nmutants of the kernels (score = caught / (caught + missed); timeouts count as caught,"
    );
    println!("equivalent mutants listed in {EQUIVALENTS} are left out):");
    println!(
        "{:<32} {:>7} {:>8} {:>7} {:>11} {:>9} {:>7}",
        "file", "caught", "timeout", "missed", "equivalent", "unviable", "score"
    );
    for (file, t) in &tally {
        let killed = t.caught + t.timeout;
        let judged = killed + t.missed;
        let score = if judged == 0 {
            "-".to_string()
        } else {
            format!("{:.1} %", 100.0 * killed as f64 / judged as f64)
        };
        println!(
            "{file:<32} {:>7} {:>8} {:>7} {:>11} {:>9} {score:>7}",
            t.caught, t.timeout, t.missed, t.equivalent, t.unviable
        );
    }
    if unexplained.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} mutant(s) survived every test and are not listed as equivalent in \
             {EQUIVALENTS}; kill each with a test, or list it there with the reason:\n  {}",
            unexplained.len(),
            unexplained.join("\n  ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_drops_line_and_column() {
        assert_eq!(
            key("core/src/warning.rs:148:38: replace && with || in level_for").as_deref(),
            Some("core/src/warning.rs: replace && with || in level_for")
        );
        assert_eq!(key("no colon here"), None);
    }

    #[test]
    fn equivalents_are_the_list_items_naming_a_mutant() {
        let text = "# Mutants\n\n- `core/src/a.rs: replace < with <= in f`: the bound is never \
                    reached\n- `not a mutant`: skipped\n  - `core/src/b.rs: delete ! in g`: why\n";
        assert_eq!(
            equivalents(text),
            [
                "core/src/a.rs: replace < with <= in f",
                "core/src/b.rs: delete ! in g"
            ]
        );
    }

    #[test]
    fn shards_are_k_of_n() {
        assert_eq!(parse_shard("3/40"), Ok((3, 40)));
        assert!(parse_shard("40/40").is_err());
        assert!(parse_shard("1/0").is_err());
        assert!(parse_shard("x").is_err());
    }
}
