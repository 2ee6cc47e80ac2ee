//! `cw-ecu`: the collision-warning ECU on the simulated host board (the main job).
//!
//! Runs a scenario (by default the paper's Figure 7) in virtual time and prints, per
//! obstacle position, the distance measured and the LEDs lit, as the paper reports it,
//! then a summary. See `--help`; the options are parsed by clap.

use std::io::Write;

use clap::Parser;
use std::process::ExitCode;
use std::time::Instant;

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
    /// Pace the simulation to the wall clock (absolute-deadline sleeps; SCHED_FIFO where
    /// permitted)
    #[arg(long)]
    realtime: bool,
    /// Write every job's start as CSV (task,cycle_ms,virtual_us,wall_ns), and each entry
    /// into CanIsr (cycle 0)
    #[arg(long, value_name = "FILE")]
    job_starts: Option<String>,
    /// Write the end-to-end latencies as CSV (path,at_us,level,latency_us): each echo to
    /// its distance frame on the bus, each threshold crossing to the LEDs
    #[arg(long, value_name = "FILE")]
    end_to_end: Option<String>,
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
    let scheduling = if o.realtime {
        Some(run_in_real_time(&mut sim, end_ms, o.job_starts.is_some())?)
    } else {
        sim.run_until_ms(end_ms);
        None
    };
    let wall = started.elapsed();
    if let Some(path) = &o.job_starts {
        write_job_starts(&mut sim, path)?;
    }
    if let Some(path) = &o.end_to_end {
        write_end_to_end(&sim, path)?;
    }

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
         {}\
         \x20        {} CAN frames on the bus; distance frames sent {}, refused {}; received frames dropped {}\n\
         \x20        bus-offs {}, kernel errors {}, thresholds red < {} mm, yellow < {} mm\n\
         \x20        EcuM state at the end: {:?}\n\
         {}",
        figure7_table(sim.scenario(), sim.trace()),
        simulated_s,
        wall.as_secs_f64() * 1000.0,
        ratio,
        scheduling.map_or_else(String::new, |s| format!("         real time: {s}\n")),
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

/// Runs the simulation to `end_ms` paced to the wall clock: each millisecond of ECU time
/// stepped at its own millisecond after the start, by a sleep to that absolute deadline
/// on the monotonic clock (a late step does not delay the ones after it), in the
/// real-time scheduling class where the system permits it; with `wall_starts`, every
/// job's start noted on that clock too. Returns the scheduling it had.
#[cfg(target_os = "linux")]
fn run_in_real_time(
    sim: &mut Simulation,
    end_ms: u64,
    wall_starts: bool,
) -> Result<cw_bsp::realtime::Scheduling, String> {
    let scheduling = cw_bsp::realtime::enter_realtime();
    if wall_starts {
        sim.ecu().port().record_wall_starts();
    }
    let origin = cw_bsp::realtime::now_ns();
    let first = sim.now_ms();
    while sim.now_ms() < end_ms && sim.reset_at_us().is_none() {
        let next = sim.now_ms() + 1;
        let deadline = origin + (next - first) * 1_000_000;
        cw_bsp::realtime::sleep_until_ns(deadline)
            .map_err(|e| format!("the real-time sleep was refused (error {e})"))?;
        sim.run_until_ms(next);
    }
    Ok(scheduling)
}

/// `--realtime` needs Linux's clock_nanosleep and SCHED_FIFO.
#[cfg(not(target_os = "linux"))]
fn run_in_real_time(_: &mut Simulation, _: u64, _: bool) -> Result<String, String> {
    Err("--realtime runs on Linux only (clock_nanosleep, SCHED_FIFO)".into())
}

/// `--job-starts`: every job's start, in order, as CSV (`task,cycle_ms,virtual_us,
/// wall_ns`): the task's name, its period (0: not periodic), the start in virtual time
/// and, where the run was paced to the wall clock, on the monotonic clock (then from the
/// first paced millisecond on: the start-up before it is not paced). Each entry into
/// `CanIsr` is a row too, its cycle 0 and no wall time (the evaluation's timing model
/// replays them, `cargo xtask eval`).
fn write_job_starts(sim: &mut Simulation, path: &str) -> Result<(), String> {
    let can_isr = cw_firmware::config::OS
        .isrs()
        .get(usize::from(cw_firmware::config::os::CAN_ISR.0))
        .map_or("?", |i| i.name);
    let mut isr_entries = sim.can_isr_entries().to_vec().into_iter().peekable();
    let port = sim.ecu().port();
    let wall = port.wall_job_starts();
    let starts: Vec<(cw_core::os::TaskId, u64, Option<u64>)> = if wall.is_empty() {
        port.job_starts()
            .iter()
            .map(|&(t, us)| (t, us, None))
            .collect()
    } else {
        wall.iter().map(|&(t, us, ns)| (t, us, Some(ns))).collect()
    };
    let mut text = String::from("task,cycle_ms,virtual_us,wall_ns\n");
    for (task, at_us, wall_ns) in starts {
        while let Some(isr_us) = isr_entries.next_if(|&isr_us| isr_us <= at_us) {
            text.push_str(&format!("{can_isr},0,{isr_us},\n"));
        }
        let slot = usize::from(task.0);
        let name = cw_firmware::config::OS
            .tasks()
            .get(slot)
            .map_or("?", |t| t.name);
        let cycle = cw_firmware::config::PERIOD_MS
            .get(slot)
            .copied()
            .unwrap_or(0);
        let wall_ns = wall_ns.map(|ns| ns.to_string()).unwrap_or_default();
        text.push_str(&format!("{name},{cycle},{at_us},{wall_ns}\n"));
    }
    for isr_us in isr_entries {
        text.push_str(&format!("{can_isr},0,{isr_us},\n"));
    }
    std::fs::write(path, text).map_err(|e| format!("cannot write job starts {path}: {e}"))
}

/// `--end-to-end`: the run's end-to-end latencies (`Simulation::end_to_end`), in virtual
/// time, as CSV (`path,at_us,level,latency_us`): `echo_to_frame` rows (the echo's capture,
/// no level, the time to its frame's end on the bus), then `crossing_to_led` rows (the
/// crossing, the level entered, the time until the LEDs showed it; empty where they never
/// did). No crossing rows where the scenario sends the ECU frames (the thresholds may
/// change).
fn write_end_to_end(sim: &Simulation, path: &str) -> Result<(), String> {
    let e2e = sim.end_to_end();
    let mut text = String::from("path,at_us,level,latency_us\n");
    for (at, latency) in &e2e.echo_to_frame {
        text.push_str(&format!("echo_to_frame,{at},,{latency}\n"));
    }
    for c in e2e.crossing_to_led.iter().flatten() {
        let latency = c.latency_us.map(|l| l.to_string()).unwrap_or_default();
        text.push_str(&format!(
            "crossing_to_led,{},{:?},{latency}\n",
            c.at_us, c.level
        ));
    }
    std::fs::write(path, text).map_err(|e| format!("cannot write end-to-end latencies {path}: {e}"))
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
