//! `cargo xtask qemu --profile`: where the image's instructions go, function by function.
//!
//! QEMU runs the image one instruction per translation block (`-singlestep`) and logs
//! every block it executes (`-d exec,nochain`): one line per executed instruction, with
//! its address. The addresses are counted as the log streams in, then `llvm-symbolizer`
//! names each distinct one with its chain of inlined functions (the release image keeps
//! line tables and inlining records, `debug = 1`). Two views follow:
//!
//! - **self**: the innermost source function of each instruction (where the work is, even
//!   inside code LLVM inlined into a task's body);
//! - **inclusive**: every function on an instruction's inline chain (a layer's whole cost
//!   where it was inlined; a function called out of line counts only in itself).
//!
//! The counts are of the whole run, start-up and the end-of-run report included; a
//! function's share per call follows from the run's job and ISR counts in the report.
//!
//! QEMU logs a block again when it starts it again without having executed it: an
//! access to a device that must end its block (`cpu_io_recompile: rewound execution of
//! TB`, every read and write of a peripheral register), or the instruction budget of
//! `-icount` spent on entry. So an address logged twice in a row is one instruction
//! ([`Executed`]); the image's only branch to itself follows the idle loop, which never
//! returns. (Counted line by line, the Figure 7 run held about 2.7 % such repeats.)

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::Result;

/// How many functions each view prints (all of them go to the file).
const SHOWN: usize = 40;

/// The trace's one out-of-line function for every mark (the measuring images' spans, jobs
/// and ISR entries): what the measuring itself executes, but for the constant and the call
/// at each mark's site.
const MARK: &str = "cw_bsp::cortex_m::trace::mark_word";

/// The address of an executed instruction in one `-d exec` line (`Trace 0: 0xHOST
/// [0000000a/PC/flags/cflags] symbol`), `None` for a line of another kind.
///
/// # Errors
/// A trace line whose address is not hexadecimal.
fn executed_pc(line: &str) -> std::result::Result<Option<u32>, String> {
    if !line.starts_with("Trace ") {
        return Ok(None);
    }
    let fields = line
        .split_once('[')
        .and_then(|(_, rest)| rest.split_once(']'))
        .map(|(inside, _)| inside);
    let pc = fields.and_then(|f| f.split('/').nth(1));
    match pc.map(|pc| u32::from_str_radix(pc, 16)) {
        Some(Ok(pc)) => Ok(Some(pc)),
        _ => Err(format!("not an executed block's address: `{line}`")),
    }
}

/// The instructions executed, by address, from the log's addresses in order: an address
/// logged again at once is the same instruction started again (the module's note).
#[derive(Debug, Default)]
struct Executed {
    counts: HashMap<u32, u64>,
    last: Option<u32>,
}

impl Executed {
    fn logged(&mut self, pc: u32) {
        if self.last != Some(pc) {
            *self.counts.entry(pc).or_default() += 1;
        }
        self.last = Some(pc);
    }
}

/// A symbol as rustc's legacy mangling leaves it after LLVM's demangler: `$LT$` and the
/// other escapes decoded, `..` as `::`, the hash suffix dropped.
fn readable(name: &str) -> String {
    let name = match name.rsplit_once("::h") {
        Some((head, hash)) if hash.len() == 16 && hash.bytes().all(|b| b.is_ascii_hexdigit()) => {
            head
        }
        _ => name,
    };
    let mut out = name
        .replace("$LT$", "<")
        .replace("$GT$", ">")
        .replace("$u20$", " ")
        .replace("$C$", ",")
        .replace("$RF$", "&")
        .replace("$BP$", "*")
        .replace("$u7b$", "{")
        .replace("$u7d$", "}")
        .replace("$u27$", "'")
        .replace("..", "::");
    if out.starts_with("_<") {
        out.remove(0);
    }
    out
}

/// The inline chains of `pcs` (innermost function first), from `llvm-symbolizer`.
///
/// # Errors
/// The symbolizer cannot run, or answers with fewer chains than addresses asked.
fn inline_chains(image: &Path, pcs: &[u32]) -> Result<Vec<Vec<String>>> {
    let mut child = Command::new("llvm-symbolizer")
        .arg(format!("--obj={}", image.display()))
        .args(["--inlining", "--functions=linkage"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("llvm-symbolizer: {e} (`cargo xtask setup` installs it)"))?;
    let input: String = pcs.iter().map(|pc| format!("{pc:#x}\n")).collect();
    let mut stdin = child.stdin.take().ok_or("llvm-symbolizer: no stdin")?;
    // The answers for a few thousand addresses fit the pipe only in part: write from a
    // thread while the answers are read here.
    let writer = std::thread::spawn(move || stdin.write_all(input.as_bytes()));
    let out = child
        .wait_with_output()
        .map_err(|e| format!("llvm-symbolizer: {e}"))?;
    writer
        .join()
        .map_err(|_| "llvm-symbolizer: the writer thread failed")?
        .map_err(|e| format!("llvm-symbolizer: {e}"))?;
    if !out.status.success() {
        return Err(format!("llvm-symbolizer failed: {}", out.status));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    // One block per address: (function, file:line:col) pairs, then an empty line.
    let chains: Vec<Vec<String>> = text
        .split("\n\n")
        .filter(|block| !block.trim().is_empty())
        .map(|block| block.lines().step_by(2).map(readable).collect())
        .collect();
    if chains.len() != pcs.len() {
        return Err(format!(
            "llvm-symbolizer named {} of {} addresses",
            chains.len(),
            pcs.len()
        ));
    }
    Ok(chains)
}

/// Runs `image` on `machine` (QEMU's arguments before the image's) instruction by
/// instruction, and writes the two views to `out` (and their heads to the terminal).
pub fn run(image: &Path, machine: &[String], out: &Path) -> Result {
    // The image's log, as it left QEMU (defmt frames): read it with
    // `defmt-print -e IMAGE < FILE` when the run failed.
    let report_path = out.with_extension("log.defmt");
    let report = std::fs::File::create(&report_path)
        .map_err(|e| format!("creating {}: {e}", report_path.display()))?;
    let mut qemu = Command::new("qemu-system-arm")
        .args(machine)
        .args(["-icount", "shift=0,sleep=off", "-serial", "null"])
        .args(["-singlestep", "-d", "exec,nochain"])
        .arg("-kernel")
        .arg(image)
        .stdout(report)
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("qemu-system-arm: {e}"))?;
    let log = qemu.stderr.take().ok_or("qemu-system-arm: no log pipe")?;
    let mut executed = Executed::default();
    let mut reader = BufReader::with_capacity(1 << 20, log);
    let mut line = String::new();
    let mut number = 0u64;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .map_err(|e| format!("reading QEMU's log: {e}"))?;
        if n == 0 {
            break;
        }
        number += 1;
        let pc =
            executed_pc(line.trim_end()).map_err(|e| format!("QEMU log line {number}: {e}"))?;
        if let Some(pc) = pc {
            executed.logged(pc);
        }
    }
    let status = qemu.wait().map_err(|e| format!("qemu-system-arm: {e}"))?;
    if !status.success() {
        return Err(format!(
            "the profiled run failed ({status}); its log is {} (`{} -e {} < {}` reads it)",
            report_path.display(),
            cw_tests::qemu::DECODER,
            image.display(),
            report_path.display()
        ));
    }
    let counts = executed.counts;
    let mut pcs: Vec<u32> = counts.keys().copied().collect();
    pcs.sort_unstable();
    let chains = inline_chains(image, &pcs)?;
    let mut own: HashMap<&str, u64> = HashMap::new();
    let mut inclusive: HashMap<&str, u64> = HashMap::new();
    for (pc, chain) in pcs.iter().zip(&chains) {
        let n = counts.get(pc).copied().unwrap_or(0);
        if let Some(innermost) = chain.first() {
            *own.entry(innermost).or_default() += n;
        }
        let mut seen: Vec<&str> = Vec::new();
        for f in chain {
            if !seen.contains(&f.as_str()) {
                seen.push(f);
                *inclusive.entry(f).or_default() += n;
            }
        }
    }
    let total: u64 = counts.values().sum();
    let ranked = |map: &HashMap<&str, u64>| {
        let mut rows: Vec<(u64, String)> = map.iter().map(|(f, n)| (*n, f.to_string())).collect();
        rows.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        rows
    };
    let table = |title: &str, rows: &[(u64, String)], limit: usize| {
        let mut t = format!("{title}\n");
        for (n, f) in rows.iter().take(limit) {
            let share = *n as f64 * 100.0 / total.max(1) as f64;
            t.push_str(&format!("{n:>12} {share:>6.2}%  {f}\n"));
        }
        t
    };
    let measuring = inclusive.get(MARK).copied().unwrap_or(0);
    let (own, inclusive) = (ranked(&own), ranked(&inclusive));
    let head = format!(
        "profile: {total} instructions executed at {} addresses (the whole run: start-up, \
         the OS, the end-of-run report); {measuring} of them the trace's marks (`{MARK}`, \
         the measuring), {} the rest\n",
        pcs.len(),
        total.saturating_sub(measuring)
    );
    let own_title = "self: instructions whose innermost (inlined) function is";
    let inclusive_title = "inclusive: instructions with the function on their inline chain";
    print!(
        "{head}{}{}",
        table(own_title, &own, SHOWN),
        table(inclusive_title, &inclusive, SHOWN)
    );
    let all = format!(
        "{head}{}{}",
        table(own_title, &own, usize::MAX),
        table(inclusive_title, &inclusive, usize::MAX)
    );
    std::fs::write(out, all).map_err(|e| format!("writing {}: {e}", out.display()))?;
    println!(
        "profile: every function in {}; the image's report in {}",
        out.display(),
        report_path.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_lines_give_their_address_and_other_lines_none() {
        let line = "Trace 0: 0x7fd900000100 [00800408/0000273c/00000110/ff020201] DefaultPreInit";
        assert_eq!(executed_pc(line), Ok(Some(0x273c)));
        assert_eq!(executed_pc("Linking TBs"), Ok(None));
        assert!(executed_pc("Trace 0: 0x7fd9 [00800408/zz/00000110]").is_err());
        assert!(executed_pc("Trace 0: cut").is_err());
    }

    #[test]
    fn an_address_logged_again_at_once_is_one_instruction() {
        let mut executed = Executed::default();
        // A loop of two (0x10, 0x12) run twice; the load at 0x12 restarted once for its
        // device access; then 0x10 again.
        for pc in [0x10, 0x12, 0x12, 0x10, 0x12, 0x10] {
            executed.logged(pc);
        }
        assert_eq!(executed.counts.get(&0x10), Some(&3));
        assert_eq!(executed.counts.get(&0x12), Some(&2));
        assert_eq!(executed.counts.len(), 2);
    }

    #[test]
    fn mangled_names_become_readable() {
        assert_eq!(
            readable("_$LT$cw_firmware..mps2..Mps2App$u20$as$u20$cw_bsp..cortex_m..App$GT$::run_job::hf5ad753ee5adbad8"),
            "<cw_firmware::mps2::Mps2App as cw_bsp::cortex_m::App>::run_job"
        );
        assert_eq!(
            readable("<core::fmt::Formatter>::pad"),
            "<core::fmt::Formatter>::pad"
        );
        assert_eq!(readable("cw_port_switch"), "cw_port_switch");
    }
}
