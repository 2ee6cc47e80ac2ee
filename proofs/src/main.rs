//! Runs every model to exhaustion (the step exploration to its depth) and prints the
//! number of states explored.
use clap::Parser;
use cw_proofs::{check, check_modes, configs, steps, Outcome};
use std::process::ExitCode;
use std::time::Instant;

/// A model's name on the command line and its run.
type Run = (&'static str, Box<dyn Fn(usize) -> Outcome>);

/// Model checks of the OSEK kernel and the communication modes.
#[derive(Parser)]
struct Cli {
    /// Run only these models (paper, ceiling, fifo, events, interrupts, steps, modes)
    models: Vec<String>,
    /// Length of the step sequences the `steps` exploration covers
    #[arg(long, default_value_t = 5)]
    depth: usize,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let depth = cli.depth;
    let runs: [Run; 7] = [
        ("paper", Box::new(|n| check(configs::paper(), n))),
        ("ceiling", Box::new(|n| check(configs::ceiling(), n))),
        ("fifo", Box::new(|n| check(configs::fifo(), n))),
        ("events", Box::new(|n| check(configs::events(), n))),
        ("interrupts", Box::new(|n| check(configs::interrupts(), n))),
        ("steps", Box::new(move |n| steps::check_steps(depth, n))),
        ("modes", Box::new(check_modes)),
    ];
    let only = cli.models;
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
