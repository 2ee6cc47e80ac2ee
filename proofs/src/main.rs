//! Runs every model to exhaustion and prints the number of states explored.
use cw_proofs::{check, check_modes, configs, Outcome};
use std::process::ExitCode;
use std::time::Instant;

/// A model's name on the command line and its run.
type Run = (&'static str, fn(usize) -> Outcome);

fn main() -> ExitCode {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let runs: [Run; 6] = [
        ("paper", |n| check(configs::paper(), n)),
        ("ceiling", |n| check(configs::ceiling(), n)),
        ("fifo", |n| check(configs::fifo(), n)),
        ("events", |n| check(configs::events(), n)),
        ("interrupts", |n| check(configs::interrupts(), n)),
        ("modes", check_modes),
    ];
    // `cw-proofs NAME...` runs only those models.
    let only: Vec<String> = std::env::args().skip(1).collect();
    if let Some(unknown) = only.iter().find(|o| runs.iter().all(|(n, _)| n != o)) {
        let names: Vec<&str> = runs.iter().map(|(n, _)| *n).collect();
        eprintln!(
            "cw-proofs: no model `{unknown}`; models: {}",
            names.join(", ")
        );
        return ExitCode::FAILURE;
    }
    let mut total = 0;
    let mut failed = false;
    for (name, run) in runs {
        if !only.is_empty() && !only.iter().any(|o| o == name) {
            continue;
        }
        let start = Instant::now();
        let outcome = run(threads);
        total += outcome.unique_states;
        println!(
            "{:<72} {:>9} states ({} generated) in {:.1?}",
            outcome.name,
            outcome.unique_states,
            outcome.states,
            start.elapsed()
        );
        for f in &outcome.failures {
            println!("  FAILED {f}");
            failed = true;
        }
    }
    println!(
        "model check: {total} distinct states explored, all properties hold: {}",
        !failed
    );
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
