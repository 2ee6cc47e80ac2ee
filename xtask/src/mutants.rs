//! `cargo xtask mutants`: shows that the OSEK conformance suite can fail. Each mutant is a
//! small, deliberate fault in the kernel of the kind the suite exists to catch (a preempted
//! task queued at the tail, `ErrorHook` not called for one service, an ISR nesting at equal
//! priority, ...). The runner copies the workspace's source into `target/mutants/src`,
//! plants one mutant at a time (the original text must occur exactly once, so a change to
//! the kernel that moves it makes this command fail loudly rather than test nothing),
//! runs the conformance test binaries that must catch it, and requires each named sequence
//! to fail. A mutant that no sequence catches fails the command.
//!
//! The copy builds into the workspace's target directory, so the registry dependencies are
//! shared and built once. Cargo names a workspace crate's artifacts by its path relative to
//! the workspace root, so the copy's `cw-core` test binaries replace the workspace's own;
//! each mutant's file is restored after its test, which leaves them older than their
//! sources, and the workspace's next `cargo test` rebuilds them.

use crate::process::{root, target_dir, Cmd};
use crate::Result;
use std::path::Path;

/// One planted fault.
struct Mutant {
    /// What the fault is.
    name: &'static str,
    /// The file, relative to the workspace root.
    file: &'static str,
    /// Text that occurs exactly once in the file.
    original: &'static str,
    /// What replaces it.
    replacement: &'static str,
    /// The conformance test binary and the sequences in it that must fail.
    caught_by: (&'static str, &'static [&'static str]),
}

const MUTANTS: &[Mutant] = &[
    Mutant {
        name: "a preempted task goes to the tail of its priority's queue",
        file: "core/src/os/kernel/mod.rs",
        original: "let _ = self.ready.push_front(self.running_prio, r as u8);",
        replacement: "let _ = self.ready.push_back(self.running_prio, r as u8);",
        caught_by: ("osek_tasks", &["tm_seq12_preempted_task_is_the_oldest"]),
    },
    Mutant {
        name: "ErrorHook is not called when GetEvent fails",
        file: "core/src/os/kernel/mod.rs",
        original: "if self.cfg().hooks.error && self.error_call.is_none() && running {",
        replacement: "if self.cfg().hooks.error && self.error_call.is_none() && running && call.id() != ServiceId::GetEvent {",
        caught_by: (
            "osek_hooks",
            &[
                "eh_seq02_pre_and_post_task_hooks",
                "eh_seq05_error_hook_for_every_service",
            ],
        ),
    },
    Mutant {
        name: "an ISR of equal priority nests in the running one",
        file: "core/src/os/irq.rs",
        original: "Self::UpTo(level) => isr_priority > level,",
        replacement: "Self::UpTo(level) => isr_priority >= level,",
        caught_by: (
            "osek_interrupts",
            &[
                "ip_seq02_return_to_a_non_preemptive_task",
                "ip_seq03_return_to_a_preemptive_task",
            ],
        ),
    },
    Mutant {
        name: "an ISR does not defer rescheduling to its return",
        file: "core/src/os/kernel/interrupt.rs",
        original: "self.preempt_at = u8::MAX;",
        replacement: "self.preempt_at = self.running_prio.saturating_add(1);",
        caught_by: ("osek_tasks", &["tm_seq15_services_from_an_isr"]),
    },
    Mutant {
        name: "the first ResumeAllInterrupts ends every nested SuspendAllInterrupts",
        file: "core/src/os/kernel/interrupt.rs",
        original: "locks.suspend_all = locks.suspend_all.checked_sub(1).ok_or(OsError::NoFunc)?;",
        replacement: "locks.suspend_all = 0;",
        caught_by: ("osek_interrupts", &["ip_seq01_interrupt_services_and_nesting"]),
    },
    Mutant {
        name: "SuspendOSInterrupts lets other services through (no E_OS_DISABLEDINT)",
        file: "core/src/os/kernel/mod.rs",
        original: "self.lock_denied = if locks.any() {",
        replacement: "self.lock_denied = if locks.masks_all() {",
        caught_by: ("osek_interrupts", &["ip_seq05_mismatched_pairs_and_disabledint"]),
    },
    Mutant {
        name: "PostTaskHook is not called when a task waits",
        file: "core/src/os/kernel/event.rs",
        original: "if !os.post_task_hook() {\n                    return Ok(());\n                }\n                os.waiting[t] = true;",
        replacement: "os.waiting[t] = true;",
        caught_by: ("osek_hooks", &["eh_seq02_pre_and_post_task_hooks"]),
    },
    Mutant {
        name: "ActivateTask is allowed in the pre- and post-task hooks",
        file: "core/src/os/callevel.rs",
        original: "const HOOK_QUERIES: u64 = mask(&[\n    S::GetTaskId,",
        replacement: "const HOOK_QUERIES: u64 = mask(&[\n    S::ActivateTask,\n    S::GetTaskId,",
        caught_by: (
            "osek_callevels",
            &[
                "cl_osek_every_service_in_every_context",
                "cl_autosar_every_service_in_every_context",
            ],
        ),
    },
    Mutant {
        name: "a resource shared with an ISR gets a task-level ceiling",
        file: "core/src/os/config.rs",
        original: "if isr.resources & (1 << r) != 0 && level > ceilings[r] {",
        replacement: "if isr.resources & (1 << r) != 0 && level > ceilings[r] && false {",
        caught_by: (
            "osek_resources",
            &["rm_seq05_isr_resources", "rm_seq06_resource_shared_with_isr"],
        ),
    },
];

/// Copies the files git knows (tracked, or untracked and not ignored) into `dest`.
fn copy_workspace(dest: &Path) -> Result {
    let listing = Cmd::new("git")
        .args([
            "ls-files",
            "--cached",
            "--others",
            "--exclude-standard",
            "-z",
        ])
        .read()?;
    let root = root();
    for file in listing.split('\0').filter(|f| !f.is_empty()) {
        let from = root.join(file);
        if !from.is_file() {
            // Deleted in the working tree but still in the index.
            continue;
        }
        let to = dest.join(file);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| format!("creating {}: {e}", parent.display()))?;
        }
        std::fs::copy(&from, &to)
            .map_err(|e| format!("copying {} to {}: {e}", from.display(), to.display()))?;
    }
    Ok(())
}

/// The tests `cargo test` reported as failed in `output`.
fn failed_tests(output: &str) -> Vec<String> {
    output
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix("test ")?;
            let name = rest.strip_suffix(" ... FAILED")?;
            Some(name.to_string())
        })
        .collect()
}

/// Plants every mutant in turn and checks the suite catches each.
pub fn run() -> Result {
    let work = target_dir().join("mutants");
    let src = work.join("src");
    if src.exists() {
        std::fs::remove_dir_all(&src).map_err(|e| format!("removing {}: {e}", src.display()))?;
    }
    copy_workspace(&src)?;
    let target = target_dir();
    let mut rows = Vec::new();
    let mut survivors = Vec::new();
    for mutant in MUTANTS {
        let path = src.join(mutant.file);
        let original = std::fs::read_to_string(root().join(mutant.file))
            .map_err(|e| format!("reading {}: {e}", mutant.file))?;
        let occurrences = original.matches(mutant.original).count();
        if occurrences != 1 {
            return Err(format!(
                "mutant `{}` no longer applies: its text occurs {occurrences} times in {} \
                 (the kernel changed; update xtask/src/mutants.rs)",
                mutant.name, mutant.file
            ));
        }
        let mutated = original.replacen(mutant.original, mutant.replacement, 1);
        std::fs::write(&path, mutated).map_err(|e| format!("writing {}: {e}", path.display()))?;
        println!("\n-- mutant: {} ({})", mutant.name, mutant.file);
        let (binary, sequences) = mutant.caught_by;
        let out = Cmd::new("cargo")
            .dir(&src)
            .env("CARGO_TARGET_DIR", &target)
            .args(["test", "-p", "cw-core", "--test", binary])
            .capture()?;
        std::fs::write(&path, &original)
            .map_err(|e| format!("restoring {}: {e}", path.display()))?;
        let failed = failed_tests(&out.stdout);
        if out.success || failed.is_empty() {
            // The suite passed, or did not even build and run: either way nothing caught it.
            if !out.success {
                println!("{}{}", out.stdout, out.stderr);
            }
            survivors.push(format!("{} (the suite ran: {})", mutant.name, out.success));
            rows.push((mutant.name, "SURVIVED".to_string()));
            continue;
        }
        let missed: Vec<&str> = sequences
            .iter()
            .copied()
            .filter(|s| !failed.iter().any(|f| f == s))
            .collect();
        if missed.is_empty() {
            rows.push((mutant.name, format!("caught by {}", failed.join(", "))));
        } else {
            survivors.push(format!(
                "{}: {} did not fail (failed: {})",
                mutant.name,
                missed.join(", "),
                failed.join(", ")
            ));
            rows.push((mutant.name, "NOT CAUGHT where expected".to_string()));
        }
    }
    println!("\nkernel mutants against the OSEK conformance suite:");
    for (name, result) in &rows {
        println!("  {name:<72} {result}");
    }
    if survivors.is_empty() {
        println!("{} of {} mutants caught", rows.len(), MUTANTS.len());
        Ok(())
    } else {
        Err(format!(
            "{} mutant(s) not caught:\n  {}",
            survivors.len(),
            survivors.join("\n  ")
        ))
    }
}
