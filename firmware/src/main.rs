//! `cw-ecu`: the collision-warning ECU on the simulated host board (the main job).
//!
//! Runs a scenario (by default the paper's Figure 7) in virtual time and prints, per
//! obstacle position, the distance measured and the LEDs lit, as the paper reports it,
//! then a summary. See `--help`; the options are parsed by clap.

use std::io::Write;

use clap::Parser;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use cw_bsp::host::CandumpLog;
use cw_core::warning::{Measurement, WarningLevel};
use cw_firmware::host::{Scenario, Simulation, TraceRow};

/// The collision-warning ECU (Kim et al., open-source AUTOSAR on an MPC5748G), simulated
/// on a host board in virtual time: runs a scenario (by default the paper's Figure 7) and
/// prints, per obstacle position, the distance measured and the LEDs lit, then a summary.
#[derive(Parser)]
#[command(name = "cw-ecu", version)]
struct Options {
    /// Run this scenario instead of the paper's Figure 7 (format:
    /// firmware/src/host/scenario.rs, examples in scenarios/)
    #[arg(long, value_name = "FILE")]
    scenario: Option<String>,
    /// Write a CSV row every 10 ms: time_ms,true_distance_mm,measured_distance_mm,level,
    /// red,yellow,measurement
    #[arg(long, value_name = "FILE")]
    trace: Option<String>,
    /// Write every CAN frame on the bus in candump log format
    #[arg(long, value_name = "FILE")]
    can_log: Option<String>,
    /// Run this long instead of the scenario's length (more than 0, at most 10^7 s)
    #[arg(long = "duration", value_name = "SECONDS", value_parser = duration_ms, allow_negative_numbers = true)]
    duration_ms: Option<u64>,
    /// Seed of the sensor noise
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Pace the simulation to the wall clock
    #[arg(long)]
    realtime: bool,
}

/// `--duration`: seconds, more than 0 and at most 10^7, as whole milliseconds.
fn duration_ms(v: &str) -> Result<u64, String> {
    let seconds: f64 = v
        .parse()
        .map_err(|_| format!("`{v}` is not a number of seconds"))?;
    if !(seconds > 0.0 && seconds <= 1.0e7) {
        return Err(format!("{v} s is not between 0 and 10^7 s"));
    }
    Ok((seconds * 1000.0).round() as u64)
}

fn on_off(lit: bool) -> &'static str {
    if lit {
        "ON"
    } else {
        "off"
    }
}

/// The Figure-7 table: for each held position, the state at the end of the hold.
fn figure7_table(scenario: &Scenario, trace: &[TraceRow]) -> String {
    let mut out = String::from(
        "Obstacle held at each distance (paper Figure 7; state at the end of each hold)\n\
         distance   measured   level    red   yellow\n",
    );
    for seg in scenario.segments.iter().filter(|s| s.from_mm == s.to_mm) {
        let end = seg.end_ms();
        let Some(row) = trace
            .iter()
            .rev()
            .find(|r| r.time_ms < end && r.time_ms > seg.start_ms)
        else {
            continue;
        };
        let measured = match row.measured {
            Measurement::Distance { distance_mm } => format!("{distance_mm} mm"),
            Measurement::NothingInRange => "none".into(),
            Measurement::Invalid => "invalid".into(),
        };
        let level = match row.level {
            WarningLevel::Off => "off",
            WarningLevel::Yellow => "yellow",
            WarningLevel::Red => "red",
            WarningLevel::Fault => "FAULT",
        };
        out.push_str(&format!(
            "{:>5.2} m   {:>9}   {:<7}  {:<4}  {}\n",
            f64::from(seg.from_mm) / 1000.0,
            measured,
            level,
            on_off(row.red),
            on_off(row.yellow)
        ));
    }
    out
}

fn run(o: &Options) -> Result<(), String> {
    let scenario = match &o.scenario {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read scenario {path}: {e}"))?;
            Scenario::parse(&text).map_err(|e| format!("scenario {path}: {e}"))?
        }
        None => Scenario::figure7(),
    };
    let end_ms = o.duration_ms.unwrap_or_else(|| scenario.duration_ms());
    let mut sim = Simulation::new(scenario, o.seed).map_err(|e| e.to_string())?;
    let started = Instant::now();
    if o.realtime {
        while sim.now_ms() < end_ms {
            let next = (sim.now_ms() + 10).min(end_ms);
            sim.run_until_ms(next);
            let due = Duration::from_millis(next);
            if let Some(wait) = due.checked_sub(started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
    } else {
        sim.run_until_ms(end_ms);
    }
    let wall = started.elapsed();

    if let Some(path) = &o.trace {
        let mut text = String::from(TraceRow::CSV_HEADER);
        text.push('\n');
        for row in sim.trace() {
            text.push_str(&row.csv());
            text.push('\n');
        }
        std::fs::write(path, text).map_err(|e| format!("cannot write trace {path}: {e}"))?;
    }
    if let Some(path) = &o.can_log {
        let file =
            std::fs::File::create(path).map_err(|e| format!("cannot write CAN log {path}: {e}"))?;
        let mut log = CandumpLog::new(std::io::BufWriter::new(file));
        log.record_all(sim.frames())
            .and_then(|()| log.flush())
            .map_err(|e| format!("cannot write CAN log {path}: {e}"))?;
    }

    let mut out = std::io::stdout().lock();
    let ecu = sim.ecu();
    let stats = ecu.stats();
    let bus_offs = ecu.cansm().bus_off_total();
    let thresholds = ecu.thresholds();
    let ecum_state = ecu.ecum().state();
    let supervision = ecu.supervision();
    let watchdog = supervision_summary(
        supervision.and_then(|(_, failure)| failure),
        sim.watchdog().triggers(),
        sim.watchdog().last_trigger_us(),
        sim.reset_at_us(),
    );
    let simulated_s = sim.now_ms() as f64 / 1000.0;
    let ratio = simulated_s / wall.as_secs_f64().max(1e-9);
    let text = format!(
        "{}\nsummary: {:.1} s of ECU time simulated in {:.1} ms of wall time ({:.0}x real time)\n\
         \x20        {} CAN frames on the bus; distance frames sent {}, refused {}; received frames dropped {}\n\
         \x20        bus-offs {}, kernel errors {}, thresholds red < {} mm, yellow < {} mm\n\
         \x20        EcuM state at the end: {:?}\n\
         {}",
        figure7_table(sim.scenario(), sim.trace()),
        simulated_s,
        wall.as_secs_f64() * 1000.0,
        ratio,
        sim.frames().len(),
        stats.frames_requested,
        stats.frames_refused,
        stats.rx_dropped,
        bus_offs,
        stats.os_errors,
        thresholds.red_below_mm(),
        thresholds.yellow_below_mm(),
        ecum_state,
        watchdog,
    );
    out.write_all(text.as_bytes())
        .map_err(|e| format!("cannot write to stdout: {e}"))
}

/// The summary's lines on WdgM and the watchdog: every supervision held, or which failed
/// when, and the watchdog's reset.
fn supervision_summary(
    failure: Option<cw_core::wdgm::Failure>,
    triggers: u64,
    last_trigger_us: Option<u64>,
    reset_at_us: Option<u64>,
) -> String {
    let mut text = match failure {
        None => format!(
            "         WdgM: every alive supervision held; the watchdog was triggered {triggers} times\n"
        ),
        Some(f) => format!(
            "         WdgM: the alive supervision of {} failed at {} ms ({} of {} alive indications): LEDs dark from then on, the watchdog no longer triggered\n",
            f.name,
            u64::from(f.main_function) * u64::from(cw_firmware::config::BSW_PERIOD_MS),
            f.counted,
            f.expected
        ),
    };
    if let Some(reset) = reset_at_us {
        text.push_str(&format!(
            "         watchdog: last triggered at {:.3} ms, reset the ECU at {:.3} ms; the run ends there\n",
            last_trigger_us.unwrap_or(0) as f64 / 1000.0,
            reset as f64 / 1000.0
        ));
    }
    text
}

fn main() -> ExitCode {
    // Usage errors (an unknown option, a bad value) are clap's: a message and exit status 2.
    let options = Options::parse();
    match run(&options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("cw-ecu: {e}");
            ExitCode::FAILURE
        }
    }
}
