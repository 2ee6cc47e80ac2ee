//! `cargo xtask coverage`: branch coverage of `core/` (cw-core) under its unit tests and
//! OSEK conformance suite, measured with LLVM's source-based coverage (cargo-llvm-cov on
//! the pinned nightly, `--branch` and `-Z coverage-options=condition`: every operand of
//! `&&` and `||` is a branch of its own).
//!
//! A branch is one condition of an `if`, `while`, `match` guard or pattern, or lazy boolean
//! operand; it is covered when the tests took it both ways. Generic code has one copy per
//! instantiation, and a branch counts as covered when some instantiations took it each way.
//! Test modules (`mod tests`) are not counted, nor the test files. The oracles
//! (`mod spec`, `os/spec.rs`) are counted, apart from the kernels.
//!
//! Every branch not covered must be listed in `docs/src/coverage.md` with the reason, as a list
//! item ``- `FILE: FUNCTION: `CONDITION` never true`: why``; a branch not listed fails the
//! command, and so does a listed one that is covered now (the list stays exact). The
//! oracles' branches are reported, not judged: which of their sides the random inputs of
//! the OS harnesses reach differs between runs (bolero draws new inputs each time).
//! `--write` rewrites the generated part of `docs/src/coverage.md` (between its markers) with
//! the per-file table.
//!
//! MC/DC is not measured: the nightly's rustc no longer has `-Z coverage-options=mcdc`
//! (removed from rustc in 2025, rust-lang/rust#144999, not yet back).

use crate::process::{root, target_dir, Cmd};
use crate::setup::NIGHTLY;
use crate::{mutation, Result};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

/// The committed report with the reasons for uncovered branches.
const REPORT: &str = "docs/src/coverage.md";
const BEGIN: &str = "<!-- coverage:begin (cargo xtask coverage --write) -->";
const END: &str = "<!-- coverage:end -->";

/// Inputs per bolero harness. bolero draws them afresh on every run, so the branches only
/// random inputs reach can differ from run to run: the oracles' (see the module comment).
const BOLERO_ITERATIONS: &str = "1000";

/// The proofs by exhaustion add no branch the rest of the suite misses, and instrumented
/// they take minutes.
const SKIPPED_TESTS: &[&str] = mutation::SKIPPED_TESTS;

/// Options of `cargo xtask coverage`.
#[derive(clap::Args)]
pub struct Options {
    /// Update docs/src/coverage.md's table from this run
    #[arg(long)]
    write: bool,
}

impl Options {
    /// The check command's stage: measure and judge, write nothing.
    pub fn ci() -> Self {
        Self { write: false }
    }
}

/// Which side of a branch the tests never took.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Missing {
    True,
    False,
    Both,
}

impl Missing {
    fn words(self) -> &'static str {
        match self {
            Self::True => "never true",
            Self::False => "never false",
            Self::Both => "never reached",
        }
    }
}

/// One branch the tests did not take both ways.
struct Uncovered {
    line: u64,
    oracle: bool,
    key: String,
}

#[derive(Default)]
struct FileCoverage {
    branches: usize,
    covered: usize,
    oracle_branches: usize,
    oracle_covered: usize,
    lines_percent: f64,
    uncovered: Vec<Uncovered>,
    /// Names of the functions inside the file's `mod spec`.
    spec_functions: BTreeSet<String>,
}

/// Lines (1-based, inclusive) of each `mod NAME {` block in `src`, found by counting braces
/// from its opening line (the kernels' sources have no braces in strings or characters
/// inside these modules).
fn module_lines(src: &[&str], name: &str) -> Vec<(u64, u64)> {
    let mut ranges = Vec::new();
    let opening = format!("mod {name} {{");
    let mut i = 0;
    while i < src.len() {
        let line = src.get(i).copied().unwrap_or_default();
        if line
            .trim_start()
            .trim_start_matches("pub ")
            .starts_with(&opening)
        {
            let mut depth = 0i64;
            let mut end = i;
            for (j, l) in src.iter().enumerate().skip(i) {
                depth += l.matches('{').count() as i64 - l.matches('}').count() as i64;
                end = j;
                if depth <= 0 {
                    break;
                }
            }
            ranges.push((i as u64 + 1, end as u64 + 1));
            i = end + 1;
        } else {
            i += 1;
        }
    }
    ranges
}

/// The name of the function whose body holds line `line` (1-based): the nearest `fn NAME`
/// at or above it.
fn function_at(src: &[&str], line: u64) -> String {
    let upto = usize::try_from(line).unwrap_or(0).min(src.len());
    src.iter()
        .take(upto)
        .rev()
        .find_map(|l| fn_name(l))
        .unwrap_or_else(|| "?".into())
}

/// The name of the function a line declares (`fn NAME`), if it declares one.
fn fn_name(line: &str) -> Option<String> {
    let (_, after) = line.split_once("fn ")?;
    let name: String = after
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

fn number(v: &Value) -> u64 {
    v.as_u64().unwrap_or(0)
}

/// Reads llvm-cov's JSON export: each file of `core/src`, its branches summed over
/// instantiations.
fn analyse(export: &Value) -> Result<BTreeMap<String, FileCoverage>> {
    let files = export
        .pointer("/data/0/files")
        .and_then(Value::as_array)
        .ok_or("coverage: the llvm-cov export has no data[0].files")?;
    let root = root();
    let mut out = BTreeMap::new();
    for file in files {
        let path = file
            .get("filename")
            .and_then(Value::as_str)
            .ok_or("coverage: a file without a name in the llvm-cov export")?;
        let rel = std::path::Path::new(path)
            .strip_prefix(&root)
            .map_or_else(|_| path.to_string(), |p| p.display().to_string());
        if !rel.starts_with("core/src/") {
            continue;
        }
        let text = std::fs::read_to_string(path).map_err(|e| format!("reading {path}: {e}"))?;
        let src: Vec<&str> = text.lines().collect();
        let tests = module_lines(&src, "tests");
        let specs = module_lines(&src, "spec");
        let inside =
            |ranges: &[(u64, u64)], line: u64| ranges.iter().any(|&(a, b)| (a..=b).contains(&line));
        let whole_file_oracle = rel.ends_with("/spec.rs");

        // (line, column, end line, end column) -> (times true, times false)
        let mut spans: BTreeMap<(u64, u64, u64, u64), (u64, u64)> = BTreeMap::new();
        for b in file
            .get("branches")
            .and_then(Value::as_array)
            .map_or(&[][..], Vec::as_slice)
        {
            let Some(f) = b.as_array() else { continue };
            let field = |i: usize| f.get(i).map_or(0, number);
            let (line, col, end_line, end_col) = (field(0), field(1), field(2), field(3));
            if inside(&tests, line) {
                continue;
            }
            let counts = spans.entry((line, col, end_line, end_col)).or_default();
            counts.0 += field(4);
            counts.1 += field(5);
        }
        // The functions declared inside the `spec` modules, each once.
        let spec_functions: BTreeSet<String> = specs
            .iter()
            .flat_map(|&(a, b)| {
                (a..=b).filter_map(|l| fn_name(src.get(usize::try_from(l).ok()?.checked_sub(1)?)?))
            })
            .collect();
        let mut fc = FileCoverage {
            spec_functions,
            lines_percent: file
                .pointer("/summary/lines/percent")
                .and_then(Value::as_f64)
                .unwrap_or(0.0),
            ..FileCoverage::default()
        };
        for (&(line, col, end_line, end_col), &(t, f)) in &spans {
            let oracle = whole_file_oracle || inside(&specs, line);
            let covered = t > 0 && f > 0;
            if oracle {
                fc.oracle_branches += 1;
                fc.oracle_covered += usize::from(covered);
            } else {
                fc.branches += 1;
                fc.covered += usize::from(covered);
            }
            if covered {
                continue;
            }
            let missing = match (t, f) {
                (0, 0) => Missing::Both,
                (0, _) => Missing::True,
                _ => Missing::False,
            };
            let source = src
                .get(usize::try_from(line).unwrap_or(usize::MAX).wrapping_sub(1))
                .copied()
                .unwrap_or_default();
            let from = usize::try_from(col).unwrap_or(1).saturating_sub(1);
            let to = if end_line == line {
                usize::try_from(end_col).unwrap_or(1).saturating_sub(1)
            } else {
                source.len()
            };
            let condition = source.get(from..to).unwrap_or(source).trim();
            fc.uncovered.push(Uncovered {
                line,
                oracle,
                key: format!(
                    "{rel}: {}: `{condition}` {}",
                    function_at(&src, line),
                    missing.words()
                ),
            });
        }
        out.insert(rel, fc);
    }
    Ok(out)
}

/// The reasons listed in the report: list items ``- `KEY`: reason``, where a key names a
/// file of `core/src` and ends with what the tests never did (a key keeps the condition's
/// own backticks, so it ends at the first "never true`", "never false`" or
/// "never reached`").
fn reasons(text: &str) -> Vec<String> {
    let ends = [Missing::True, Missing::False, Missing::Both].map(Missing::words);
    text.lines()
        .filter_map(|line| {
            let rest = line.trim_start().strip_prefix("- `core/src/")?;
            let end = ends
                .iter()
                .filter_map(|w| rest.find(&format!("{w}`")).map(|at| at + w.len()))
                .min()?;
            Some(format!("core/src/{}", rest.get(..end)?))
        })
        .collect()
}

fn percent(covered: usize, total: usize) -> String {
    if total == 0 {
        "-".into()
    } else {
        format!("{:.1} %", 100.0 * covered as f64 / total as f64)
    }
}

/// Whether a listed key names an oracle's branch: one in `os/spec.rs`, or in a `spec`
/// function of a file whose other uncovered branches say so.
fn is_oracle_key(key: &str, files: &BTreeMap<String, FileCoverage>) -> bool {
    let file = key.split(": ").next().unwrap_or_default();
    if file.ends_with("/spec.rs") {
        return true;
    }
    let function = key.split(": ").nth(1).unwrap_or_default();
    files
        .get(file)
        .is_some_and(|f| f.spec_functions.contains(function))
}

/// The per-file table, as Markdown.
fn table(files: &BTreeMap<String, FileCoverage>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| file | kernel | branches | covered | branch coverage | oracle branches covered | line coverage |"
    );
    let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|");
    let (mut kb, mut kc, mut ob, mut oc, mut ab, mut ac) = (0, 0, 0, 0, 0, 0);
    for (name, f) in files {
        let kernel = mutation::KERNEL_FILES.contains(&name.as_str());
        if kernel {
            kb += f.branches;
            kc += f.covered;
        }
        ab += f.branches;
        ac += f.covered;
        ob += f.oracle_branches;
        oc += f.oracle_covered;
        let oracle = if f.oracle_branches == 0 {
            "-".to_string()
        } else {
            format!("{}/{}", f.oracle_covered, f.oracle_branches)
        };
        let _ = writeln!(
            s,
            "| `{name}` | {} | {} | {} | {} | {oracle} | {:.1} % |",
            if kernel { "yes" } else { "" },
            f.branches,
            f.covered,
            percent(f.covered, f.branches),
            f.lines_percent
        );
    }
    let _ = writeln!(
        s,
        "| **kernels** | | {kb} | {kc} | {} | | |",
        percent(kc, kb)
    );
    let _ = writeln!(
        s,
        "| **all of core** | | {ab} | {ac} | {} | {oc}/{ob} | |",
        percent(ac, ab)
    );
    s
}

/// Measures, prints, judges against the report's reasons and, with `--write`, updates the
/// report's table.
pub fn run(options: &Options) -> Result {
    let toolchain = format!("+{NIGHTLY}");
    let mut cmd = Cmd::new("cargo")
        .arg(&toolchain)
        .env("RUSTFLAGS", "-Zcoverage-options=condition")
        .env("BOLERO_RANDOM_ITERATIONS", BOLERO_ITERATIONS)
        .args(["llvm-cov", "--no-report", "--branch", "-p", "cw-core"])
        .args(["--lib", "--tests", "--"]);
    for test in SKIPPED_TESTS {
        cmd = cmd.args(["--skip", test]);
    }
    cmd.run()?;
    let json = target_dir().join("coverage.json");
    Cmd::new("cargo")
        .arg(&toolchain)
        .args(["llvm-cov", "report", "--branch", "-p", "cw-core", "--json"])
        .arg("--output-path")
        .arg(&json)
        .run()?;
    let text =
        std::fs::read_to_string(&json).map_err(|e| format!("reading {}: {e}", json.display()))?;
    let export: Value = serde_json::from_str(&text)
        .map_err(|e| format!("coverage: {} is not JSON: {e}", json.display()))?;
    let files = analyse(&export)?;

    let table = table(&files);
    println!("\nbranch coverage of core/src (tests and oracles apart):\n{table}");

    let report_path = root().join(REPORT);
    let report =
        std::fs::read_to_string(&report_path).map_err(|e| format!("reading {REPORT}: {e}"))?;
    let listed = reasons(&report);
    let uncovered: Vec<(&String, &Uncovered)> = files
        .iter()
        .flat_map(|(name, f)| f.uncovered.iter().map(move |u| (name, u)))
        .collect();
    let unexplained: Vec<String> = uncovered
        .iter()
        .filter(|(_, u)| !u.oracle && !listed.contains(&u.key))
        .map(|(name, u)| {
            let oracle = if u.oracle { " (oracle)" } else { "" };
            format!("{name}:{}{oracle}: {}", u.line, u.key)
        })
        .collect();
    let stale: Vec<&String> = listed
        .iter()
        .filter(|k| !is_oracle_key(k, &files) && !uncovered.iter().any(|(_, u)| &u.key == *k))
        .collect();
    let oracle_changes = uncovered
        .iter()
        .filter(|(_, u)| u.oracle && !listed.contains(&u.key))
        .count();
    if oracle_changes > 0 {
        println!(
            "note: {oracle_changes} oracle branch(es) not taken both ways on this run are not in \
             {REPORT} (random inputs; not judged)"
        );
    }
    println!(
        "{} branches not taken both ways, {} of them explained in {REPORT}",
        uncovered.len(),
        uncovered.len() - unexplained.len()
    );

    if options.write {
        let (Some(begin), Some(end)) = (report.find(BEGIN), report.find(END)) else {
            return Err(format!("{REPORT} lacks the markers `{BEGIN}` and `{END}`"));
        };
        let mut updated = String::new();
        updated.push_str(report.get(..begin + BEGIN.len()).unwrap_or_default());
        updated.push('\n');
        updated.push_str(&table);
        updated.push_str(report.get(end..).unwrap_or_default());
        std::fs::write(&report_path, updated).map_err(|e| format!("writing {REPORT}: {e}"))?;
        println!("wrote the table into {REPORT}");
    }

    let mut problems = Vec::new();
    if !unexplained.is_empty() {
        problems.push(format!(
            "{} branch(es) not taken both ways and not listed in {REPORT} (add a test, or \
             list the key with the reason):\n  {}",
            unexplained.len(),
            unexplained.join("\n  ")
        ));
    }
    if !stale.is_empty() {
        problems.push(format!(
            "{} branch(es) listed in {REPORT} are covered now or gone; remove them:\n  {}",
            stale.len(),
            stale
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join("\n  ")
        ));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modules_run_to_their_closing_brace() {
        let src = [
            "fn a() {}",
            "pub mod spec {",
            "    fn b() {",
            "    }",
            "}",
            "#[cfg(test)]",
            "mod tests {",
            "}",
        ];
        assert_eq!(module_lines(&src, "spec"), [(2, 5)]);
        assert_eq!(module_lines(&src, "tests"), [(7, 8)]);
        assert_eq!(function_at(&src, 4), "b");
        assert_eq!(function_at(&src, 1), "a");
    }

    #[test]
    fn reasons_are_the_list_items_naming_a_core_branch() {
        let text = "- `core/src/a.rs: f: `x == 0` never true`: x is never 0 (`f`: ok)\n\
                    - `xtask/src/b.rs: g: `y` never false`: not core\n\
                    no item\n";
        assert_eq!(reasons(text), ["core/src/a.rs: f: `x == 0` never true"]);
    }
}
