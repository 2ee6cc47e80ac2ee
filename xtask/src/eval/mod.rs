//! `cargo xtask eval`: the paper's evaluation (its section 5) measured on this ECU, written
//! as a report a reader can check and plot: Markdown, the raw samples as CSV, SVG plots.
//!
//! What it measures:
//! - the periodicity of the periodic tasks (the paper's Table 1), with the paper's
//!   definitions: `T_period` is the time between two consecutive starts of a task's jobs,
//!   each observed at the job's first line, and `T_jitter = |T_cycle - T_period|`. Every
//!   period of a run is a sample; none is summarised where it is measured. Three settings:
//!   - the host simulation in virtual time with the image's execution times ([`timed`]):
//!     its releases replayed through the OS's timing model (`cw_core::os::timeline`),
//!     each job taking what the image's run measured for it;
//!   - the Cortex-M4 image under QEMU (`-icount shift=5`: 32 ns of virtual time per
//!     instruction, [`cw_bsp::icount`]), which writes every job's start and end to a host
//!     file as it runs (`--job-records`, over semihosting, from its idle loop:
//!     `cw_bsp::cortex_m::trace::job_record`), with the ECU's basic tasks and again with
//!     the paper's extended tasks (feature `extended-tasks`), whose costs [`structure`]
//!     sets side by side;
//!   - the host simulation paced to the wall clock (`cw-ecu --realtime --job-starts`):
//!     each millisecond of ECU time stepped at its millisecond of the monotonic clock, by
//!     absolute-deadline sleeps, in `SCHED_FIFO` where the system permits it
//!     ([`cw_bsp::realtime`]), each job's start read on that clock;
//! - schedulability ([`schedule`]): the image's response-time analysis of its own task set
//!   with the run's longest jobs and ISRs, beside each task's worst response measured from
//!   the same run's job records;
//! - the communication stack's latency per layer, the paper's Figure 10 ([`stack`]): the
//!   same probes counted on the image and by callgrind on x86-64;
//! - end-to-end latencies ([`end_to_end`]), from the host simulation in virtual time.
//!
//! The book's chapter ([`BOOK`]) is this command's report from a real run
//! (`cargo xtask eval --book`).

use std::fmt::Write as _;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use cw_bsp::port::trace::job_record::{JobEdge, Unwrapper};
use plotters::prelude::*;

use crate::process::{root, target_dir};
use crate::Result;

mod end_to_end;
mod schedule;
mod stack;
mod structure;
mod timed;

/// The book's chapter the report becomes with `--book`, and its plots' folder.
const BOOK: &str = "docs/src/evaluation.md";
const BOOK_PLOTS: &str = "docs/src/evaluation";

/// Options of `cargo xtask eval`.
#[derive(clap::Args)]
pub struct Options {
    /// ECU time to run, seconds (the paper ran 30 minutes)
    #[arg(long, default_value_t = 1800.0, value_parser = duration_s)]
    pub duration: f64,
    /// The scenario the ECU plays (its last position is held to the end; default the
    /// paper's Figure 7)
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// Wall time of the host's real-time setting, seconds (default: --duration)
    #[arg(long, value_name = "SECONDS", value_parser = duration_s)]
    pub realtime_duration: Option<f64>,
    /// Where the report, the samples and the plots go (default target/eval)
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write the report as the book's chapter (docs/src/evaluation.md, its plots in
    /// docs/src/evaluation/) as well
    #[arg(long)]
    pub book: bool,
}

impl Options {
    /// The check command's `eval` stage: 60 s of ECU time on Figure 7 on the image, 10 s
    /// in real time on the host, the report in `target/eval-ci` (the book's chapter
    /// untouched), checked ([`check`]).
    pub fn ci() -> Self {
        Self {
            duration: 60.0,
            realtime_duration: Some(10.0),
            scenario: None,
            out: Some(target_dir().join("eval-ci")),
            book: false,
        }
    }
}

/// `--duration`: seconds, at least 1 and at most 86,400 (a day of ECU time).
fn duration_s(text: &str) -> Result<f64> {
    let seconds: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if (1.0..=86_400.0).contains(&seconds) {
        Ok(seconds)
    } else {
        Err(format!("{text} s is not between 1 s and 86,400 s"))
    }
}

/// The paper's Table 1 (ms): `T_period` and `T_jitter`, avg, max, min and σ, for its
/// three periodic tasks: τ1 `OsLEDTask` (10 ms, high priority), τ2
/// `OsObstacleDetectionTask` (20 ms, middle), τ3 `OsSonarTask` (40 ms, low). Measured on
/// the MPC5748G at 160 MHz over 30 minutes.
const PAPER: [(&str, [f64; 4], [f64; 4]); 3] = [
    (
        "OsLEDTask",
        [9.984680, 10.077800, 9.893725, 0.024978],
        [0.022939, 0.106275, 0.001025, 0.017580],
    ),
    (
        "OsObstacleDetectionTask",
        [20.007748, 20.199025, 19.794700, 0.030898],
        [0.023442, 0.205300, 0.002375, 0.022102],
    ),
    (
        "OsSonarTask",
        [40.000080, 40.502225, 39.596200, 0.043450],
        [0.026439, 0.502225, 0.000000, 0.034481],
    ),
];

/// Runs `cargo xtask eval`.
pub fn run(options: &Options) -> Result {
    let out = options
        .out
        .clone()
        .unwrap_or_else(|| target_dir().join("eval"));
    std::fs::create_dir_all(&out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let scenario = options
        .scenario
        .clone()
        .unwrap_or_else(|| root().join(crate::qemu::FIGURE7));
    let duration_ms = (options.duration * 1000.0).round() as u64;
    let realtime_ms = options
        .realtime_duration
        .map_or(duration_ms, |s| (s * 1000.0).round() as u64);
    let image = crate::qemu::build()?;
    let started = Instant::now();
    let run = run_image(&image, &scenario, duration_ms, &out, "")?;
    let image_wall = started.elapsed();
    let image_setting = Setting {
        key: "cortex-m4-qemu",
        label: "Cortex-M4 image, QEMU".into(),
        ecu_ms: duration_ms,
        wall: image_wall,
        tasks: periodicity(&run.task_starts())?,
    };
    let started = Instant::now();
    let (host, scheduling) = run_host_realtime(&scenario, realtime_ms, &out)?;
    let host_setting = Setting {
        key: "host-realtime",
        label: format!("host, real time ({scheduling})"),
        ecu_ms: realtime_ms,
        wall: started.elapsed(),
        tasks: periodicity(&host)?,
    };
    let end_to_end = end_to_end::run(&scenario, duration_ms, &out)?;
    let mut schedule = schedule::parse(&run.log)?;
    schedule.analyse(
        &run.records,
        run.counts_per_ms,
        schedule::isr_marks(&run.log)?,
    )?;
    let description = crate::process::root().join(cw_gen::DESCRIPTION);
    let bytes = std::fs::read(&description)
        .map_err(|e| format!("reading {}: {e}", description.display()))?;
    let ecu = cw_gen::arxml::read(&bytes, cw_gen::DESCRIPTION)
        .map_err(|e| format!("{}", cw_gen::Refused(e)))?
        .ecu;
    schedule.budgets(&ecu, cw_gen::DESCRIPTION)?;
    let started = Instant::now();
    let costs = timed::Costs::measure(&run, &schedule, schedule::isr_marks(&run.log)?)?;
    let timed = timed::run(&scenario, duration_ms, &out, &schedule, &costs)?;
    let timed_setting = Setting {
        key: "host-timed",
        label: "host simulation, the image's times".into(),
        ecu_ms: duration_ms,
        wall: started.elapsed(),
        tasks: periodicity(&timed.starts)?,
    };
    let image = crate::qemu::build_extended()?;
    let started = Instant::now();
    let extended = run_image(&image, &scenario, duration_ms, &out, "extended-")?;
    let extended_setting = Setting {
        key: "cortex-m4-qemu-extended",
        label: "Cortex-M4 image, extended tasks (the paper's structure), QEMU".into(),
        ecu_ms: duration_ms,
        wall: started.elapsed(),
        tasks: periodicity(&extended.task_starts())?,
    };
    let structures = structure::Structures::measure(&run, &extended, &schedule)?;
    let mut stack = stack::Stack::default();
    stack::parse_image(&run.log, &mut stack)?;
    stack::measure_x86(&mut stack)?;
    let report = Report {
        command: command_line(options),
        scenario: scenario
            .strip_prefix(root())
            .unwrap_or(&scenario)
            .display()
            .to_string(),
        settings: vec![timed_setting, image_setting, extended_setting, host_setting],
        structures: Some(structures),
        timed: Some((costs, timed.refused, timed.load)),
        schedule: Some(schedule),
        stack: Some(stack),
        end_to_end: Some(end_to_end),
    };
    // Written first, so that a report that fails its checks can be read.
    write_report(&report, &out, "plots")?;
    check(&report)?;
    check_plots(&report, &out.join("plots"))?;
    println!("eval: the report is {}", out.join("report.md").display());
    if options.book {
        let book = root().join(BOOK);
        let plots = root().join(BOOK_PLOTS);
        std::fs::create_dir_all(&plots)
            .map_err(|e| format!("creating {}: {e}", plots.display()))?;
        write_plots(&report, &plots)?;
        check_plots(&report, &plots)?;
        let text = markdown(&report, "evaluation");
        std::fs::write(&book, text).map_err(|e| format!("writing {}: {e}", book.display()))?;
        println!("eval: the book's chapter is {}", book.display());
    }
    Ok(())
}

/// The command as a reader would type it again.
fn command_line(options: &Options) -> String {
    let mut line = format!("cargo xtask eval --duration {}", options.duration);
    if let Some(rt) = options.realtime_duration {
        line.push_str(&format!(" --realtime-duration {rt}"));
    }
    if let Some(scenario) = &options.scenario {
        line.push_str(&format!(" --scenario {}", scenario.display()));
    }
    if options.book {
        line.push_str(" --book");
    }
    line
}

/// One setting's measurement: its tasks' periodicity.
struct Setting {
    /// Its name in the samples' CSV and the plots' file names.
    key: &'static str,
    /// Its name in the report.
    label: String,
    /// ECU time it ran, ms.
    ecu_ms: u64,
    /// Wall time it took.
    wall: Duration,
    tasks: Vec<TaskPeriodicity>,
}

/// What the image's run gave: its log's facts and every job's start and end.
struct ImageRun {
    /// SysTick counts per OS tick (1 ms).
    counts_per_ms: u32,
    /// The periodic tasks: slot, name, period (ms).
    periodic: Vec<(u8, String, u32)>,
    /// Every job start and end, in order (times in counts since the OS started).
    records: Vec<JobEdge>,
    /// Its log (the report's lines).
    log: String,
}

/// A periodic task's job starts in one setting: its name, its cycle (ms) and each start
/// (ms, on the setting's clock).
#[derive(Debug)]
struct TaskStarts {
    name: String,
    cycle_ms: u32,
    starts_ms: Vec<f64>,
}

/// Runs the host simulation paced to the wall clock for `duration_ms` (`cw-ecu --realtime
/// --job-starts`), showing the time left; returns the periodic tasks' starts (ms on the
/// monotonic clock) and the scheduling the run had, in its own words.
fn run_host_realtime(
    scenario: &Path,
    duration_ms: u64,
    out: &Path,
) -> Result<(Vec<TaskStarts>, String)> {
    crate::process::Cmd::new("cargo")
        .args(["build", "--release", "-p", "cw-firmware", "--bin", "cw-ecu"])
        .run()?;
    let ecu = target_dir().join("release").join("cw-ecu");
    let csv = out.join("host-realtime-starts.csv");
    let mut command = std::process::Command::new(&ecu);
    command
        .arg("--scenario")
        .arg(scenario)
        .arg("--duration")
        .arg(format!("{}", duration_ms as f64 / 1000.0))
        .arg("--realtime")
        .arg("--job-starts")
        .arg(&csv)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    println!("$ {}", crate::process::shown(&command));
    let child = command
        .spawn()
        .map_err(|e| format!("starting {}: {e}", ecu.display()))?;
    let waiter = std::thread::spawn(move || child.wait_with_output());
    let bar = progress(duration_ms, "host in real time", "ms")?;
    let started = Instant::now();
    while !waiter.is_finished() {
        std::thread::sleep(Duration::from_millis(200));
        bar.set_position((started.elapsed().as_millis() as u64).min(duration_ms));
    }
    bar.finish_and_clear();
    let output = waiter
        .join()
        .map_err(|_| "the thread waiting for cw-ecu panicked".to_string())?
        .map_err(|e| format!("waiting for {}: {e}", ecu.display()))?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        return Err(format!(
            "eval: cw-ecu --realtime failed ({}):\n{}{}",
            output.status,
            stdout,
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    std::fs::write(out.join("host-realtime.txt"), stdout.as_bytes())
        .map_err(|e| format!("writing {}: {e}", out.display()))?;
    let scheduling = stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("real time: "))
        .ok_or("eval: cw-ecu --realtime did not say how it was scheduled (no `real time:` line)")?
        .to_string();
    let text =
        std::fs::read_to_string(&csv).map_err(|e| format!("reading {}: {e}", csv.display()))?;
    let starts = host_starts(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
    println!(
        "eval: the host in real time ({scheduling}): {} periodic tasks over {duration_ms} ms",
        starts.len()
    );
    Ok((starts, scheduling))
}

/// One row of `cw-ecu --job-starts`'s CSV: its line, the task's (or ISR's) name, its cycle
/// (ms; 0 where not periodic), the time in virtual µs and, in a real-time run, on the wall
/// clock (ns).
#[derive(Debug, Clone, PartialEq, Eq)]
struct StartRow {
    line: usize,
    name: String,
    cycle_ms: u32,
    at_us: u64,
    wall_ns: Option<u64>,
}

/// Reads `cw-ecu --job-starts`'s CSV (`task,cycle_ms,virtual_us,wall_ns`, the wall time
/// empty where there is none); an error names the line.
fn start_rows(text: &str) -> Result<Vec<StartRow>> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, "task,cycle_ms,virtual_us,wall_ns")) => {}
        _ => return Err("line 1 is not the header `task,cycle_ms,virtual_us,wall_ns`".into()),
    }
    lines
        .map(|(n, line)| {
            let bad = || {
                format!(
                    "line {}: `{line}` is not task,cycle_ms,virtual_us,wall_ns",
                    n + 1
                )
            };
            let fields: Vec<&str> = line.split(',').collect();
            let [name, cycle, at, wall] = fields.as_slice() else {
                return Err(bad());
            };
            Ok(StartRow {
                line: n + 1,
                name: (*name).to_string(),
                cycle_ms: cycle.parse().map_err(|_| bad())?,
                at_us: at.parse().map_err(|_| bad())?,
                wall_ns: match *wall {
                    "" => None,
                    w => Some(w.parse().map_err(|_| bad())?),
                },
            })
        })
        .collect()
}

/// The periodic tasks' starts in `cw-ecu --job-starts`'s CSV, on the wall clock, in ms
/// since the first start; an error names the line (a periodic task's start without a wall
/// time among them).
fn host_starts(text: &str) -> Result<Vec<TaskStarts>> {
    let mut tasks: Vec<TaskStarts> = Vec::new();
    let mut first_ns = None;
    // Not periodic: the start-up task, an ISR's entry.
    for row in start_rows(text)?.into_iter().filter(|r| r.cycle_ms > 0) {
        let wall = row
            .wall_ns
            .ok_or_else(|| format!("line {}: {} has no wall time", row.line, row.name))?;
        let first = *first_ns.get_or_insert(wall);
        let at_ms = wall.saturating_sub(first) as f64 / 1e6;
        match tasks.iter_mut().find(|t| t.name == row.name) {
            Some(t) => t.starts_ms.push(at_ms),
            None => tasks.push(TaskStarts {
                name: row.name,
                cycle_ms: row.cycle_ms,
                starts_ms: vec![at_ms],
            }),
        }
    }
    if tasks.is_empty() {
        return Err("no periodic task started a job".into());
    }
    Ok(tasks)
}

/// Runs the measuring image for `duration_ms` of ECU time on `scenario`, its job starts
/// and ends to `out/job-records.bin`, showing the ECU time reached (read from the file as it grows)
/// and the time left; returns what it measured, or an error with the image's log.
fn run_image(
    image: &Path,
    scenario: &Path,
    duration_ms: u64,
    out: &Path,
    prefix: &str,
) -> Result<ImageRun> {
    let starts_file = out.join(format!("{prefix}job-records.bin"));
    let _ = std::fs::remove_file(&starts_file);
    let (scenario_arg, starts_arg) = (
        scenario.display().to_string(),
        starts_file.display().to_string(),
    );
    let duration_arg = duration_ms.to_string();
    let mut qemu = std::process::Command::new("qemu-system-arm");
    qemu.args(cw_tests::qemu::machine(
        "cw-qemu",
        &[
            "--scenario",
            &scenario_arg,
            "--duration-ms",
            &duration_arg,
            "--job-records",
            &starts_arg,
        ],
    ))
    .args(["-icount", cw_bsp::icount::VIRTUAL])
    .arg("-serial")
    .arg(format!(
        "file:{}",
        out.join(format!("{prefix}slcan.txt")).display()
    ))
    .arg("-kernel")
    .arg(image);
    println!("$ {}", crate::process::shown(&qemu));
    let image_path = image.to_path_buf();
    let runner = std::thread::spawn(move || cw_tests::qemu::run(qemu, &image_path));
    let what = match prefix.trim_end_matches('-') {
        "" => "Cortex-M4 image".to_string(),
        variant => format!("Cortex-M4 image, {variant} tasks"),
    };
    let bar = progress(duration_ms, &what, "ms of ECU time")?;
    let mut follower = Follower::default();
    while !runner.is_finished() {
        std::thread::sleep(Duration::from_millis(200));
        if let Some(ms) = follower.poll(&starts_file) {
            bar.set_position(ms.min(duration_ms));
        }
    }
    bar.finish_and_clear();
    let (success, log) = runner
        .join()
        .map_err(|_| "the thread running QEMU panicked".to_string())??;
    std::fs::write(out.join(format!("{prefix}image.txt")), &log)
        .map_err(|e| format!("writing {}: {e}", out.display()))?;
    if !success {
        return Err(format!("eval: the image on QEMU failed:\n{log}"));
    }
    let facts = image_facts(&log)?;
    let bytes = std::fs::read(&starts_file)
        .map_err(|e| format!("reading {}: {e}", starts_file.display()))?;
    let records = decode_records(&bytes).map_err(|e| format!("{}: {e}", starts_file.display()))?;
    if facts.dropped != 0 || facts.lost != 0 || facts.written != records.len() as u64 {
        return Err(format!(
            "eval: the record of job starts and ends is not whole: the image dropped {}, failed to write {}, wrote {}; the file holds {}",
            facts.dropped,
            facts.lost,
            facts.written,
            records.len()
        ));
    }
    println!(
        "eval: {} job starts and ends over {} ms of ECU time",
        records.len(),
        duration_ms
    );
    Ok(ImageRun {
        counts_per_ms: facts.counts_per_ms,
        periodic: facts.periodic,
        records,
        log,
    })
}

impl ImageRun {
    /// The periodic tasks' starts, in ms since the OS started.
    fn task_starts(&self) -> Vec<TaskStarts> {
        let per_ms = f64::from(self.counts_per_ms);
        self.periodic
            .iter()
            .map(|(slot, name, cycle)| TaskStarts {
                name: name.clone(),
                cycle_ms: *cycle,
                starts_ms: self
                    .records
                    .iter()
                    .filter(|r| r.task == *slot && !r.end)
                    .map(|r| r.at as f64 / per_ms)
                    .collect(),
            })
            .collect()
    }
}

/// Follows the job-start file as the image writes it: the ECU time of the last start
/// read so far (ms), from the new whole records since the last call.
#[derive(Default)]
struct Follower {
    read: u64,
    unwrapper: Unwrapper,
    last: u64,
}

impl Follower {
    /// The ECU time of the newest start (ms, at the mps2 image's SysTick counts,
    /// [`cw_bsp::icount::NS_PER_SYSTICK_COUNT`]), `None` while the file holds none.
    fn poll(&mut self, path: &Path) -> Option<u64> {
        let mut file = std::fs::File::open(path).ok()?;
        let len = file.metadata().ok()?.len();
        let whole = len - len % 4;
        if whole > self.read {
            file.seek(SeekFrom::Start(self.read)).ok()?;
            let mut bytes = vec![0u8; usize::try_from(whole - self.read).ok()?];
            file.read_exact(&mut bytes).ok()?;
            for word in bytes.chunks_exact(4) {
                let word = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
                self.last = self.unwrapper.next(word).at;
            }
            self.read = whole;
        }
        (self.read > 0).then_some(self.last * cw_bsp::icount::NS_PER_SYSTICK_COUNT / 1_000_000)
    }
}

/// The job starts and ends in a file the image wrote: little-endian words, each a task
/// slot, start or end, and a time stamp ([`cw_bsp::port::trace::job_record`]), unwrapped
/// in order.
fn decode_records(bytes: &[u8]) -> Result<Vec<JobEdge>> {
    if bytes.len() % 4 != 0 {
        return Err(format!(
            "{} bytes is not a whole number of 4-byte records (the last starts at byte {})",
            bytes.len(),
            bytes.len() - bytes.len() % 4
        ));
    }
    let mut unwrapper = Unwrapper::new();
    Ok(bytes
        .chunks_exact(4)
        .map(|w| unwrapper.next(u32::from_le_bytes([w[0], w[1], w[2], w[3]])))
        .collect())
}

/// What the image's log says of its job records.
#[derive(Debug, PartialEq)]
struct ImageFacts {
    counts_per_ms: u32,
    periodic: Vec<(u8, String, u32)>,
    dropped: u64,
    written: u64,
    lost: u64,
}

/// Reads the image's `job records` lines (`cw-qemu: job records time base N counts per
/// ms`, `... periodic SLOT NAME PERIOD ms`, `... D dropped, W written, L not written`);
/// an error names the line that is missing or malformed.
fn image_facts(log: &str) -> Result<ImageFacts> {
    let mut counts_per_ms = None;
    let mut periodic = Vec::new();
    let mut totals = None;
    for (n, line) in log.lines().enumerate() {
        let Some(rest) = line.strip_prefix("cw-qemu: job records ") else {
            continue;
        };
        let bad = || format!("the image's log, line {}: `{line}` is malformed", n + 1);
        let words: Vec<&str> = rest.split_whitespace().collect();
        match words.as_slice() {
            ["time", "base", counts, "counts", "per", "ms"] => {
                counts_per_ms = Some(counts.parse::<u32>().map_err(|_| bad())?);
            }
            ["periodic", slot, name, period, "ms"] => periodic.push((
                slot.parse::<u8>().map_err(|_| bad())?,
                (*name).to_string(),
                period.parse::<u32>().map_err(|_| bad())?,
            )),
            [dropped, "dropped,", written, "written,", lost, "not", "written"] => {
                let number = |w: &str| w.parse::<u64>().map_err(|_| bad());
                totals = Some((number(dropped)?, number(written)?, number(lost)?));
            }
            ["to", ..] => {}
            _ => return Err(bad()),
        }
    }
    let counts_per_ms = counts_per_ms
        .filter(|&c| c > 0)
        .ok_or("the image's log has no `job records time base` line")?;
    let (dropped, written, lost) =
        totals.ok_or("the image's log has no `job records ... dropped` line")?;
    if periodic.is_empty() {
        return Err("the image's log names no periodic task".into());
    }
    Ok(ImageFacts {
        counts_per_ms,
        periodic,
        dropped,
        written,
        lost,
    })
}

/// avg, max, min and σ (population standard deviation) of samples.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stats {
    avg: f64,
    max: f64,
    min: f64,
    sd: f64,
}

impl Stats {
    fn of(samples: &[f64]) -> Option<Self> {
        if samples.is_empty() {
            return None;
        }
        let n = samples.len() as f64;
        let avg = samples.iter().sum::<f64>() / n;
        let var = samples.iter().map(|x| (x - avg).powi(2)).sum::<f64>() / n;
        Some(Self {
            avg,
            max: samples.iter().copied().fold(f64::MIN, f64::max),
            min: samples.iter().copied().fold(f64::MAX, f64::min),
            sd: var.sqrt(),
        })
    }

    fn row(&self) -> [f64; 4] {
        [self.avg, self.max, self.min, self.sd]
    }
}

/// One periodic task's periods and jitters.
struct TaskPeriodicity {
    name: String,
    cycle_ms: u32,
    /// (start, T_period, T_jitter), ms, one per job after the first.
    samples: Vec<(f64, f64, f64)>,
    period: Stats,
    jitter: Stats,
}

/// `T_period` and `T_jitter` of every periodic task from its job starts.
fn periodicity(tasks: &[TaskStarts]) -> Result<Vec<TaskPeriodicity>> {
    tasks
        .iter()
        .map(|t| {
            let samples: Vec<(f64, f64, f64)> = t
                .starts_ms
                .windows(2)
                .map(|w| {
                    let period = w[1] - w[0];
                    (w[1], period, (f64::from(t.cycle_ms) - period).abs())
                })
                .collect();
            let stats = |pick: fn(&(f64, f64, f64)) -> f64| {
                Stats::of(&samples.iter().map(pick).collect::<Vec<_>>())
                    .ok_or_else(|| format!("eval: {} started fewer than two jobs", t.name))
            };
            Ok(TaskPeriodicity {
                name: t.name.clone(),
                cycle_ms: t.cycle_ms,
                period: stats(|s| s.1)?,
                jitter: stats(|s| s.2)?,
                samples,
            })
        })
        .collect()
}

/// What the report holds.
struct Report {
    command: String,
    scenario: String,
    settings: Vec<Setting>,
    /// What each task structure costs on the image (basic and extended tasks).
    structures: Option<structure::Structures>,
    /// The timed host setting's costs, its releases refused and its CPU load.
    timed: Option<(timed::Costs, u64, f64)>,
    /// The image's response-time analysis and the measured responses.
    schedule: Option<schedule::Schedule>,
    /// The stack's layers (the paper's Figure 10).
    stack: Option<stack::Stack>,
    /// The end-to-end latencies.
    end_to_end: Option<end_to_end::EndToEnd>,
}

/// The report's own checks, in every setting: every periodic task present with about as
/// many periods as the run's length gives, every figure finite and in order (max at least
/// avg, avg at least min, min at least 0), and the periods' mean within half of what one
/// job lost or gained would move it (the cycle over the number of periods) of the cycle:
/// the mean is the last start less the first over the periods, so the first and the
/// last start's delays move it by their difference over the periods, and a job lost or
/// gained by a whole cycle over the periods.
fn check(report: &Report) -> Result {
    if let Some(s) = &report.schedule {
        schedule::check(s)?;
    }
    if let Some(s) = &report.stack {
        stack::check(s)?;
    }
    if let Some(e) = &report.end_to_end {
        end_to_end::check(e)?;
    }
    if let Some(s) = &report.structures {
        structure::check(s)?;
    }
    if let Some((_, refused, _)) = &report.timed {
        if *refused != 0 {
            return Err(format!(
                "eval: the timed host setting refused {refused} releases: a job was still \
                 running at its next release"
            ));
        }
    }
    for setting in &report.settings {
        for t in &setting.tasks {
            let expected = setting.ecu_ms / u64::from(t.cycle_ms);
            if (t.samples.len() as u64 + 2) < expected {
                return Err(format!(
                    "eval: {}: {} has {} periods in {} ms, expected about {expected}",
                    setting.label,
                    t.name,
                    t.samples.len(),
                    setting.ecu_ms
                ));
            }
            for (what, s) in [("T_period", t.period), ("T_jitter", t.jitter)] {
                let finite = s.row().iter().all(|x| x.is_finite());
                if !finite || s.max < s.avg || s.avg < s.min || s.min < 0.0 || s.sd < 0.0 {
                    return Err(format!(
                        "eval: {}: {} {what} is inconsistent: {s:?}",
                        setting.label, t.name
                    ));
                }
            }
            let one_job = f64::from(t.cycle_ms) / t.samples.len() as f64;
            if (t.period.avg - f64::from(t.cycle_ms)).abs() > one_job / 2.0 {
                return Err(format!(
                    "eval: {}: {}'s mean period is {} ms for a {} ms cycle",
                    setting.label, t.name, t.period.avg, t.cycle_ms
                ));
            }
        }
    }
    Ok(())
}

/// Writes `report.md`, `periods.csv` and the plots (under `out/plots_dir`).
fn write_report(report: &Report, out: &Path, plots_dir: &str) -> Result {
    let plots = out.join(plots_dir);
    std::fs::create_dir_all(&plots).map_err(|e| format!("creating {}: {e}", plots.display()))?;
    write_plots(report, &plots)?;
    let mut csv = String::from("setting,task,cycle_ms,start_ms,period_ms,jitter_ms\n");
    for setting in &report.settings {
        for t in &setting.tasks {
            for (start, period, jitter) in &t.samples {
                let _ = writeln!(
                    csv,
                    "{},{},{},{start:.6},{period:.6},{jitter:.6}",
                    setting.key, t.name, t.cycle_ms
                );
            }
        }
    }
    let path = out.join("periods.csv");
    std::fs::write(&path, csv).map_err(|e| format!("writing {}: {e}", path.display()))?;
    let path = out.join("report.md");
    std::fs::write(&path, markdown(report, plots_dir))
        .map_err(|e| format!("writing {}: {e}", path.display()))
}

/// Every plot of the report is there and is an SVG document.
fn check_plots(report: &Report, dir: &Path) -> Result {
    let stack_plots = report
        .stack
        .iter()
        .flat_map(|_| ["Transmit", "Receive"].map(stack::plot_name))
        .chain(
            report
                .end_to_end
                .iter()
                .flat_map(|_| end_to_end::PLOTS.map(String::from)),
        );
    let jitter_plots = report.settings.iter().flat_map(|setting| {
        setting
            .tasks
            .iter()
            .map(|t| plot_name(setting.key, &t.name))
    });
    for name in jitter_plots.chain(stack_plots) {
        {
            let path = dir.join(name);
            let text = std::fs::read_to_string(&path)
                .map_err(|e| format!("eval: the plot {}: {e}", path.display()))?;
            if !(text.starts_with("<svg") && text.trim_end().ends_with("</svg>")) {
                return Err(format!("eval: {} is not an SVG document", path.display()));
            }
        }
    }
    Ok(())
}

/// The SVG file of a task's jitter histogram in a setting.
fn plot_name(setting: &str, task: &str) -> String {
    format!("jitter-{setting}-{task}.svg")
}

/// One histogram per periodic task and setting: its jobs by `T_jitter`, in µs; the
/// stack's layers per direction.
fn write_plots(report: &Report, dir: &Path) -> Result {
    if let Some(s) = &report.stack {
        stack::write_plots(s, dir)?;
    }
    if let Some(e) = &report.end_to_end {
        end_to_end::write_plots(e, dir)?;
    }
    for setting in &report.settings {
        for t in &setting.tasks {
            let path = dir.join(plot_name(setting.key, &t.name));
            histogram(t, &setting.label, &path)
                .map_err(|e| format!("plotting {}: {e}", path.display()))?;
        }
    }
    Ok(())
}

/// A task's jobs by `T_jitter` in one setting ([`histogram_us`]).
fn histogram(t: &TaskPeriodicity, setting: &str, path: &Path) -> std::result::Result<(), String> {
    let jitters: Vec<f64> = t.samples.iter().map(|s| s.2 * 1000.0).collect();
    histogram_us(
        &jitters,
        &format!(
            "{} (T_cycle {} ms), {} jobs: {setting}",
            t.name,
            t.cycle_ms,
            t.samples.len() + 1
        ),
        "T_jitter",
        "jobs",
        path,
    )
}

/// A progress bar for a part that takes more than a few seconds: `len` steps of `unit`,
/// with the time so far and the time left.
fn progress(len: u64, what: &str, unit: &str) -> Result<indicatif::ProgressBar> {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "eval: {what} {{bar:30}} {{pos}}/{{len}} {unit}, {{elapsed}} so far, about {{eta}} left"
        ))
        .map_err(|e| format!("the progress bar's template: {e}"))?,
    );
    Ok(bar)
}

/// Samples (µs) as 40 bars from 0 to the 99.9th percentile (a rare long stall of the host
/// would otherwise squeeze every other sample into the first bar), the last bar also
/// counting the samples beyond it, which the axis's label names.
fn histogram_us(
    values_us: &[f64],
    caption: &str,
    what: &str,
    counted: &str,
    path: &Path,
) -> std::result::Result<(), String> {
    const BINS: usize = 40;
    let mut sorted = values_us.to_vec();
    sorted.sort_by(f64::total_cmp);
    let at = (sorted.len() * 999 / 1000).min(sorted.len().saturating_sub(1));
    let top_us = sorted.get(at).copied().unwrap_or(0.0).max(1.0);
    let max_us = sorted.last().copied().unwrap_or(0.0);
    let width = top_us / BINS as f64;
    let mut counts = [0u32; BINS];
    let mut beyond = 0u32;
    for value in &sorted {
        if *value > top_us {
            beyond += 1;
        }
        let bin = ((value / width) as usize).min(BINS - 1);
        if let Some(c) = counts.get_mut(bin) {
            *c += 1;
        }
    }
    let tail = if beyond > 0 {
        format!("; last bar: {beyond} beyond {top_us:.1} µs, up to {max_us:.1}")
    } else {
        String::new()
    };
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    let root = SVGBackend::new(path, (640, 360)).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 14))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..top_us * 1.02, 0u32..top + top / 10 + 1)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(format!("{what} (µs){tail}"))
        .y_desc(counted)
        .draw()
        .map_err(|x| e(&x))?;
    chart
        .draw_series(counts.iter().enumerate().map(|(i, &c)| {
            let x0 = i as f64 * width;
            Rectangle::new([(x0, 0), (x0 + width, c)], BLUE.mix(0.7).filled())
        }))
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))
}

/// A row of four figures, as the paper prints them (ms, six decimals).
fn row(s: [f64; 4]) -> String {
    s.iter()
        .map(|x| format!("{x:.6}"))
        .collect::<Vec<_>>()
        .join(" | ")
}

/// The report in Markdown; the plots are under `plots_dir`, relative to it.
fn markdown(report: &Report, plots_dir: &str) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# The evaluation (the paper's section 5)\n");
    let _ = writeln!(
        md,
        "Written by `{}` on {} ({}; {}), on `{}` (its last position held to the end). \
         The settings:\n",
        report.command,
        today(),
        machine(),
        qemu_version(),
        report.scenario,
    );
    for setting in &report.settings {
        let _ = writeln!(
            md,
            "- {}: {} ms of ECU time in {:.0} s of wall time;",
            setting.label,
            setting.ecu_ms,
            setting.wall.as_secs_f64()
        );
    }
    let _ = writeln!(
        md,
        "\n## Task periodicity (the paper's Table 1)\n\n\
         The paper's definitions: `T_period` is the time between two consecutive starts of a \
         task's jobs, each observed at the job's first line, and `T_jitter = |T_cycle - T_period|` \
         (the paper's equation 2). Every job of a run is a sample. Statistics: avg, max, min \
         and σ (the population's standard deviation) in ms, as the paper gives them.\n\n\
         **The Cortex-M4 image** runs on QEMU's mps2-an386 with `-icount shift=5`: every \
         instruction takes 32 ns of virtual time (31.25 million instructions per second) and \
         SysTick counts at 25 MHz, so a time here is the image's own instructions, one count \
         40 ns. The image writes each job's start and end (the port's job marks, a SysTick \
         count) to a host file as it runs, from its idle loop. The paper's MPC5748G runs at 160 MHz: \
         at one instruction per cycle the same instructions would take a fifth of the time (an \
         assumption, not a measurement: the e200z4's pipeline and memories differ).\n\n\
         **The host in real time** is the host simulation (`cw-ecu --realtime`, release build) \
         paced to the wall clock: each millisecond of ECU time is stepped at its millisecond \
         after the start, by a sleep to that absolute deadline on the monotonic clock \
         (`clock_nanosleep` with `TIMER_ABSTIME`), in the scheduling class the setting's name \
         gives (`SCHED_FIFO` where the system permits it), and each job's start is read on \
         that clock. Its jitter is the host's: the kernel's wake-up latency, the other \
         processes and the machine's virtualisation, plus the jobs' own time on the host.\n"
    );
    if let Some((costs, refused, load)) = &report.timed {
        timed::markdown(costs, *refused, *load, &mut md);
    }
    let _ = writeln!(
        md,
        "| task | setting | jobs | T_period avg | max | min | σ | T_jitter avg | max | min | σ |\n\
         |---|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut names: Vec<(&str, u32)> = Vec::new();
    for t in report.settings.iter().flat_map(|s| &s.tasks) {
        if !names.iter().any(|(n, _)| *n == t.name) {
            names.push((&t.name, t.cycle_ms));
        }
    }
    for (name, cycle) in &names {
        let mut first = true;
        for setting in &report.settings {
            if let Some(t) = setting.tasks.iter().find(|t| t.name == *name) {
                let task = if first {
                    format!("`{name}` ({cycle} ms)")
                } else {
                    String::new()
                };
                first = false;
                let _ = writeln!(
                    md,
                    "| {task} | {} | {} | {} | {} |",
                    setting.label,
                    t.samples.len() + 1,
                    row(t.period.row()),
                    row(t.jitter.row())
                );
            }
        }
        if let Some((_, period, jitter)) = PAPER.iter().find(|(n, _, _)| n == name) {
            let _ = writeln!(
                md,
                "| | the paper, MPC5748G | 30 min | {} | {} |",
                row(*period),
                row(*jitter)
            );
        }
    }
    let _ = writeln!(
        md,
        "\nThe paper measured `OsLEDTask` (τ1), `OsObstacleDetectionTask` (τ2) and \
         `OsSonarTask` (τ3); `OsBswServiceTask` runs the basic software's main functions every \
         10 ms here and is not in its table.\n"
    );
    let _ = writeln!(
        md,
        "Against the paper's jitter (the goal: at or below it on the image):\n"
    );
    for setting in &report.settings {
        for t in &setting.tasks {
            if let Some((_, _, jitter)) = PAPER.iter().find(|(name, _, _)| *name == t.name) {
                let met = t.jitter.avg <= jitter[0] && t.jitter.max <= jitter[1];
                let _ = writeln!(
                    md,
                    "- {}, `{}`: avg {:.6} ms against {:.6}, max {:.6} ms against {:.6}: {}",
                    setting.label,
                    t.name,
                    t.jitter.avg,
                    jitter[0],
                    t.jitter.max,
                    jitter[1],
                    if met { "at or below" } else { "above" }
                );
            }
        }
    }
    let _ = writeln!(
        md,
        "\nWhat makes the jitter on the image: every alarm is due on a tick (1 ms), so a job \
         starts after the tick's ISR, which activates the tasks whose alarms are due, and after \
         the jobs of higher priority released on the same tick. `T_jitter` is how much that \
         delay differs between two consecutive releases: the ISR's length with two alarms due \
         or with four, the higher jobs' lengths as the distance and the level change.\n\n\
         Where this measurement is stronger than the paper's: every job of a run is a sample \
         and every sample is published; the image's run is deterministic (QEMU counts \
         instructions, so the same build gives the same figures on any host) and one command \
         reproduces it; the image's time stamps come from the clock that also drives the OS \
         tick, and cost the measured jobs nothing (the trace's marks are taken off the jobs' \
         instruction counts, and the record is written from the idle loop); the host in real \
         time shows what a general-purpose OS adds. Where it is weaker: QEMU's virtual time \
         is not a chip's clock. It has no caches, flash wait states, bus contention or \
         interrupt entry cycles, and every instruction takes the same time, so it shows the \
         jitter the software makes, not the hardware's. The image's mean period is the cycle to within \
         the first and the last start's delays over the run (the OS tick and the time stamps \
         share SysTick: no drift between two clocks); the paper's means \
         (9.984680 ms for 10 ms) show its measuring timer and its OS counter running from \
         different clocks, or drift between them. No run on an MPC5748G or any other chip is \
         behind these figures.\n"
    );
    let _ = writeln!(md, "Each task's jobs by `T_jitter`, per setting:\n");
    for setting in &report.settings {
        for t in &setting.tasks {
            let _ = writeln!(
                md,
                "![{} T_jitter histogram, {}]({}/{})\n",
                t.name,
                setting.label,
                plots_dir,
                plot_name(setting.key, &t.name)
            );
        }
    }
    let _ = writeln!(
        md,
        "The samples: `periods.csv` beside the report (`setting,task,cycle_ms,start_ms,\
         period_ms,jitter_ms`, one row per job after each task's first; the start on the \
         setting's clock), the image's record itself, `job-records.bin` (little-endian words: \
         the task's slot in the top four bits, 1 in the next for a job's end and 0 for its \
         start, the SysTick count in the low 27), and \
         the host's, `host-realtime-starts.csv` (`task,cycle_ms,virtual_us,wall_ns`)."
    );
    if let Some(s) = &report.structures {
        structure::markdown(s, &mut md);
    }
    if let Some(s) = &report.schedule {
        schedule::markdown(s, &mut md);
    }
    if let Some(s) = &report.stack {
        stack::markdown(s, plots_dir, &mut md);
    }
    if let Some(e) = &report.end_to_end {
        end_to_end::markdown(e, plots_dir, &mut md);
    }
    md
}

/// Today's date (UTC), as YYYY-MM-DD.
fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    civil_date(days)
}

/// The date `days` after 1970-01-01 (proleptic Gregorian), as YYYY-MM-DD.
fn civil_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The host: its CPU's model and count.
fn machine() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .and_then(|l| l.split_once(':'))
        .map_or("an unknown CPU", |(_, m)| m.trim())
        .to_string();
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{cores} cores of {model}")
}

/// QEMU's version line.
fn qemu_version() -> String {
    std::process::Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|s| s.lines().next().map(str::to_string))
        .unwrap_or_else(|| "QEMU of an unknown version".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use cw_bsp::port::trace::job_record::encode;

    const LOG: &str = "cw-qemu: job records to /tmp/x.bin\n\
        cw-qemu: job records time base 25000 counts per ms\n\
        cw-qemu: job records periodic 1 OsLEDTask 10 ms\n\
        cw-qemu: job records periodic 5 OsSonarTask 40 ms\n\
        cw-qemu: job records 0 dropped, 7 written, 0 not written\n";

    #[test]
    fn the_image_log_gives_the_time_base_the_tasks_and_the_totals() {
        let facts = image_facts(LOG).unwrap();
        assert_eq!(facts.counts_per_ms, 25_000);
        assert_eq!(
            facts.periodic,
            [(1, "OsLEDTask".into(), 10), (5, "OsSonarTask".into(), 40)]
        );
        assert_eq!((facts.dropped, facts.written, facts.lost), (0, 7, 0));
    }

    #[test]
    fn a_malformed_or_missing_line_is_named() {
        let bad = LOG.replace("periodic 5 OsSonarTask 40", "periodic x OsSonarTask 40");
        assert!(image_facts(&bad).unwrap_err().contains("line 4"));
        let missing = LOG.replace("cw-qemu: job records time base 25000 counts per ms\n", "");
        assert!(image_facts(&missing).unwrap_err().contains("time base"));
    }

    #[test]
    fn a_file_cut_inside_a_record_is_refused_with_where() {
        assert!(decode_records(&[0; 9]).unwrap_err().contains("byte 8"));
    }

    /// Starts every 10 ms, one of them 0.1 ms late: two periods off by 0.1 ms.
    #[test]
    fn periods_and_jitter_follow_the_papers_definitions() {
        let per_ms = 25_000u32;
        let times = [0u32, 10, 20, 30, 40].map(|ms| ms * per_ms);
        let mut bytes = Vec::new();
        for (i, at) in times.iter().enumerate() {
            let at = if i == 2 { at + per_ms / 10 } else { *at };
            bytes.extend(encode(1, false, at).to_le_bytes());
            bytes.extend(encode(1, true, at + 5).to_le_bytes());
            bytes.extend(encode(2, false, at + 7).to_le_bytes());
        }
        let run = ImageRun {
            counts_per_ms: per_ms,
            periodic: vec![(1, "OsLEDTask".into(), 10)],
            records: decode_records(&bytes).unwrap(),
            log: String::new(),
        };
        let tasks = periodicity(&run.task_starts()).unwrap();
        let t = &tasks[0];
        assert_eq!(t.samples.len(), 4);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(close(t.period.max, 10.1) && close(t.period.min, 9.9));
        assert!(close(t.period.avg, 10.0));
        assert!(close(t.jitter.max, 0.1) && close(t.jitter.min, 0.0));
        assert!(close(t.jitter.avg, 0.05));
        assert!(close(t.jitter.sd, 0.05));
    }

    #[test]
    fn the_hosts_starts_are_read_per_periodic_task_and_a_bad_line_is_named() {
        let text = "task,cycle_ms,virtual_us,wall_ns\n\
            OsLEDTask,10,10000,5000000\n\
            OsComTask,0,10010,5010000\n\
            OsLEDTask,10,20000,15100000\n";
        let tasks = host_starts(text).unwrap();
        assert_eq!(tasks.len(), 1);
        assert_eq!(
            (tasks[0].name.as_str(), tasks[0].cycle_ms),
            ("OsLEDTask", 10)
        );
        assert_eq!(tasks[0].starts_ms, [0.0, 10.1]);
        let bad = text.replace("20000,15100000", "20000,");
        assert!(host_starts(&bad).unwrap_err().contains("line 4"));
        assert!(host_starts("task,x\n").unwrap_err().contains("line 1"));
    }

    /// Starts 10 ms apart over 100 ms, in a report's one setting.
    fn report_of(starts_ms: Vec<f64>) -> Report {
        let tasks = periodicity(&[TaskStarts {
            name: "OsLEDTask".into(),
            cycle_ms: 10,
            starts_ms,
        }])
        .unwrap();
        Report {
            command: String::new(),
            scenario: String::new(),
            schedule: None,
            stack: None,
            end_to_end: None,
            structures: None,
            timed: None,
            settings: vec![Setting {
                key: "test",
                label: "test".into(),
                ecu_ms: 100,
                wall: Duration::ZERO,
                tasks,
            }],
        }
    }

    #[test]
    fn a_lost_job_fails_the_check_and_the_starts_delays_do_not() {
        // Every other start 7 µs late, the last one too: the mean is off by 0.7 µs.
        let delayed = (0..=10)
            .map(|k| f64::from(k) * 10.0 + if k % 2 == 1 { 0.007 } else { 0.0 })
            .collect();
        assert_eq!(check(&report_of(delayed)), Ok(()));
        // One job lost: its neighbours 20 ms apart, the mean a ninth of a cycle off.
        let mut lost: Vec<f64> = (0..=10).map(|k| f64::from(k) * 10.0).collect();
        lost.remove(5);
        let error = check(&report_of(lost)).unwrap_err();
        assert!(error.contains("OsLEDTask's mean period"), "{error}");
        // Too few periods for the run's length.
        let short = (0..=4).map(|k| f64::from(k) * 10.0).collect();
        assert!(check(&report_of(short)).unwrap_err().contains("4 periods"));
    }

    #[test]
    fn civil_dates_of_known_days() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(11_016), "2000-02-29");
        assert_eq!(civil_date(20_785), "2026-11-28");
    }
}
