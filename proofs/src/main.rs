//! Runs every model to exhaustion and prints the number of states explored.
use cw_proofs::{check, check_modes, configs, Outcome};
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let runs: [fn(usize) -> Outcome; 5] = [
        |n| check(configs::paper(), n),
        |n| check(configs::ceiling(), n),
        |n| check(configs::fifo(), n),
        |n| check(configs::events(), n),
        check_modes,
    ];
    let mut total = 0;
    let mut failed = false;
    for run in runs {
        let start = Instant::now();
        let outcome = run(threads);
        total += outcome.unique_states;
        println!(
            "{:<62} {:>9} states ({} generated) in {:.1?}",
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
