//! End-to-end latencies, from the host simulation in virtual time (`cw-ecu
//! --end-to-end`): from each echo to the distance frame that carries it on the bus, and
//! from each time the obstacle's true distance crosses a threshold to the LEDs showing
//! the level it entered.
//!
//! The run repeats the scenario for the evaluation's duration, each repetition followed
//! by a hold of its last position for 40 to 79 ms, so that the next, the k-th, starts at
//! `7k mod 40` ms into the tasks' 40 ms hyperperiod: its crossings fall at every phase of
//! it (7 and 40 share no factor) instead of the same phase each time.

use std::fmt::Write as _;
use std::path::Path;

use super::Stats;
use crate::process::target_dir;
use crate::Result;

/// The step of the hold after each repetition, ms.
const SHIFT_MS: u64 = 7;

/// The latencies, ms.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct EndToEnd {
    /// Echo to its frame's end on the bus.
    pub echo_to_frame: Vec<f64>,
    /// (the level entered, the latency to the LEDs; `None`: never shown).
    pub crossing_to_led: Vec<(String, Option<f64>)>,
    /// ECU time run, ms.
    pub ecu_ms: u64,
    /// The scenario's repetitions.
    pub repetitions: u64,
    /// The runs they were split into.
    pub runs: usize,
}

/// Movement lines per run: the host simulation's scenarios hold at most 64
/// (`cw_firmware::host::Scenario`), so the repetitions are split over several runs, each
/// from power-on.
const LINES_PER_RUN: usize = 64;

/// `scenario` (hold and ramp lines only: the others have absolute times) repeated to last
/// at least `duration_ms`, each repetition followed by a hold of its last position long
/// enough (40 to 79 ms) that the next, the k-th, starts `k * SHIFT_MS mod 40` ms into a
/// 40 ms period of its run, split into runs of at most [`LINES_PER_RUN`] lines (each from
/// power-on, its first repetition at 0); and the repetitions. An error names a line that cannot be repeated.
pub(super) fn repeated(scenario: &str, duration_ms: u64) -> Result<(Vec<String>, u64)> {
    let mut moves = Vec::new();
    let (mut length_ms, mut last_mm) = (0u64, None);
    for (n, line) in scenario.lines().enumerate() {
        let text = line.split('#').next().unwrap_or("").trim();
        if text.is_empty() {
            continue;
        }
        let words: Vec<&str> = text.split_whitespace().collect();
        let bad = || {
            format!(
                "the end-to-end run repeats the scenario, and only its `hold` and `ramp` lines \
                 can be repeated: line {} is `{line}`",
                n + 1
            )
        };
        let number = |w: &str| w.parse::<u64>().map_err(|_| bad());
        match words.as_slice() {
            ["hold", mm, ms] => {
                last_mm = Some(number(mm)?);
                length_ms += number(ms)?;
            }
            ["ramp", _, to, ms] => {
                last_mm = Some(number(to)?);
                length_ms += number(ms)?;
            }
            _ => return Err(bad()),
        }
        moves.push(text.to_string());
    }
    let last_mm = last_mm.ok_or("the scenario has no `hold` or `ramp` line to repeat")?;
    let per_run = LINES_PER_RUN / (moves.len() + 1);
    if per_run == 0 {
        return Err(format!(
            "the scenario has {} movement lines: a repetition and its hold must fit in {LINES_PER_RUN}",
            moves.len()
        ));
    }
    let header = "# Written by `cargo xtask eval`: the scenario repeated, the k-th repetition \
                  starting 7k mod 40 ms into a 40 ms period.\n";
    let (mut runs, mut total, mut k) = (Vec::new(), 0u64, 0u64);
    let mut run = String::from(header);
    let (mut in_run, mut t_run) = (0, 0u64);
    while total < duration_ms {
        for m in &moves {
            run.push_str(m);
            run.push('\n');
        }
        k += 1;
        t_run += length_ms;
        let target = k * SHIFT_MS % 40;
        let hold = (target + 40 - t_run % 40) % 40 + 40;
        let _ = writeln!(run, "hold {last_mm} {hold}");
        t_run += hold;
        total += length_ms + hold;
        in_run += 1;
        if in_run == per_run {
            runs.push(std::mem::replace(&mut run, String::from(header)));
            (in_run, t_run) = (0, 0);
        }
    }
    if in_run > 0 {
        runs.push(run);
    }
    Ok((runs, k))
}

/// Runs `cw-ecu` (built by the caller) in virtual time on `scenario` repeated for
/// `duration_ms` (several runs, [`repeated`]), showing the runs left, and reads its
/// latencies.
pub(super) fn run(scenario: &Path, duration_ms: u64, out: &Path) -> Result<EndToEnd> {
    let text = std::fs::read_to_string(scenario)
        .map_err(|e| format!("reading {}: {e}", scenario.display()))?;
    let (runs, repetitions) =
        repeated(&text, duration_ms).map_err(|e| format!("{}: {e}", scenario.display()))?;
    let ecu = target_dir().join("release").join("cw-ecu");
    let bar = super::progress(runs.len() as u64, "end to end, host simulation", "runs")?;
    let mut e2e = EndToEnd::default();
    let mut csv_all = String::from("path,at_us,level,latency_us\n");
    for (i, text) in runs.iter().enumerate() {
        let path = out.join(format!("end-to-end-scenario-{i}.txt"));
        std::fs::write(&path, text).map_err(|e| format!("writing {}: {e}", path.display()))?;
        let csv = out.join("end-to-end-run.csv");
        let mut command = std::process::Command::new(&ecu);
        command
            .arg("--scenario")
            .arg(&path)
            .arg("--end-to-end")
            .arg(&csv)
            .stdin(std::process::Stdio::null());
        if i == 0 {
            println!(
                "$ {}   (and {} more runs like it)",
                crate::process::shown(&command),
                runs.len() - 1
            );
        }
        let output = command
            .output()
            .map_err(|e| format!("starting {}: {e}", ecu.display()))?;
        if !output.status.success() {
            return Err(format!(
                "eval: cw-ecu --end-to-end failed ({}):\n{}{}",
                output.status,
                String::from_utf8_lossy(&output.stdout),
                String::from_utf8_lossy(&output.stderr)
            ));
        }
        let text =
            std::fs::read_to_string(&csv).map_err(|e| format!("reading {}: {e}", csv.display()))?;
        let part = parse(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
        csv_all.extend(text.lines().skip(1).map(|l| format!("{l}\n")));
        e2e.echo_to_frame.extend(part.echo_to_frame);
        e2e.crossing_to_led.extend(part.crossing_to_led);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let all = out.join("end-to-end.csv");
    std::fs::write(&all, csv_all).map_err(|e| format!("writing {}: {e}", all.display()))?;
    e2e.ecu_ms = duration_ms;
    e2e.repetitions = repetitions;
    e2e.runs = runs.len();
    Ok(e2e)
}

/// Reads `cw-ecu --end-to-end`'s CSV; an error names the line.
pub(super) fn parse(text: &str) -> Result<EndToEnd> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, "path,at_us,level,latency_us")) => {}
        _ => return Err("line 1 is not the header `path,at_us,level,latency_us`".into()),
    }
    let mut e2e = EndToEnd::default();
    for (n, line) in lines {
        let bad = || {
            format!(
                "line {}: `{line}` is not path,at_us,level,latency_us",
                n + 1
            )
        };
        let fields: Vec<&str> = line.split(',').collect();
        let [path, at, level, latency] = fields.as_slice() else {
            return Err(bad());
        };
        at.parse::<u64>().map_err(|_| bad())?;
        let latency_ms = match *latency {
            "" => None,
            l => Some(l.parse::<u64>().map_err(|_| bad())? as f64 / 1000.0),
        };
        match (*path, latency_ms) {
            ("echo_to_frame", Some(ms)) if level.is_empty() => e2e.echo_to_frame.push(ms),
            ("crossing_to_led", ms) if !level.is_empty() => {
                e2e.crossing_to_led.push(((*level).to_string(), ms))
            }
            _ => return Err(bad()),
        }
    }
    Ok(e2e)
}

/// The check: both paths measured, every crossing shown on the LEDs, the figures finite
/// and in order.
pub(super) fn check(e2e: &EndToEnd) -> Result {
    if e2e.echo_to_frame.is_empty() {
        return Err("eval: no echo reached the bus in the end-to-end run".into());
    }
    if e2e.crossing_to_led.is_empty() {
        return Err("eval: the end-to-end run crossed no threshold".into());
    }
    if let Some((level, _)) = e2e.crossing_to_led.iter().find(|(_, l)| l.is_none()) {
        return Err(format!(
            "eval: a crossing into {level} did not show on the LEDs before the next crossing or the run's end, in the end-to-end run"
        ));
    }
    for (what, samples) in [
        ("echo to frame", e2e.echo_to_frame.clone()),
        ("crossing to LEDs", shown(e2e)),
    ] {
        let s = Stats::of(&samples).ok_or_else(|| format!("eval: no {what} latency"))?;
        let finite = s.row().iter().all(|x| x.is_finite());
        if !finite || s.max < s.avg || s.avg < s.min || s.min < 0.0 {
            return Err(format!(
                "eval: the {what} latencies are inconsistent: {s:?}"
            ));
        }
    }
    Ok(())
}

/// The crossings' latencies, ms.
fn shown(e2e: &EndToEnd) -> Vec<f64> {
    e2e.crossing_to_led.iter().filter_map(|(_, l)| *l).collect()
}

/// The plots' file names.
pub(super) const PLOTS: [&str; 2] = [
    "end-to-end-echo-to-frame.svg",
    "end-to-end-crossing-to-led.svg",
];

/// The two histograms.
pub(super) fn write_plots(e2e: &EndToEnd, dir: &Path) -> Result {
    let us = |v: &[f64]| v.iter().map(|ms| ms * 1000.0).collect::<Vec<_>>();
    for (name, samples, caption, what, counted) in [
        (
            PLOTS[0],
            us(&e2e.echo_to_frame),
            "an echo to its distance frame's end on the bus (host simulation, virtual time)",
            "latency",
            "echoes",
        ),
        (
            PLOTS[1],
            us(&shown(e2e)),
            "a threshold crossed to the LEDs showing it (host simulation, virtual time)",
            "latency",
            "crossings",
        ),
    ] {
        let path = dir.join(name);
        super::histogram_us(&samples, caption, what, counted, &path)
            .map_err(|e| format!("plotting {}: {e}", path.display()))?;
    }
    Ok(())
}

/// The report's section.
pub(super) fn markdown(e2e: &EndToEnd, plots_dir: &str, md: &mut String) {
    let _ = writeln!(
        md,
        "\n## End to end\n\n\
         From the host simulation in virtual time (`cw-ecu --end-to-end`), about {} ms of \
         ECU time: the scenario repeated {} times over {} runs from power-on, each \
         repetition's last position held 40 to 79 ms more so that the k-th starts 7k mod 40 \
         ms into the tasks' 40 ms hyperperiod: the obstacle's moves fall at every phase of \
         it. Two paths: from each echo (its capture in `OsSonarTask`) to the \
         end of the distance frame that carries it on the 500 kbit/s bus; and from each \
         time the obstacle's true distance crosses the paper's 1 m or 2 m to both LEDs \
         showing the level it entered. The host simulation's jobs take no virtual time \
         (only the sensor's trigger pulse and the bus do): these are the latencies the \
         schedule makes (the tasks' periods and order, the bus), without the execution \
         times, which add a few µs on the image ([the schedulability \
         table](#schedulability-response-time-analysis)).\n",
        e2e.ecu_ms, e2e.repetitions, e2e.runs
    );
    let _ = writeln!(
        md,
        "| path | samples | avg (ms) | max | min | σ |\n|---|---|---|---|---|---|"
    );
    let row = |md: &mut String, what: &str, samples: &[f64]| {
        if let Some(s) = Stats::of(samples) {
            let _ = writeln!(
                md,
                "| {what} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
                samples.len(),
                s.avg,
                s.max,
                s.min,
                s.sd
            );
        }
    };
    row(md, "echo to its frame on the bus", &e2e.echo_to_frame);
    row(md, "threshold crossed to the LEDs", &shown(e2e));
    for level in ["Red", "Yellow", "Off"] {
        let samples: Vec<f64> = e2e
            .crossing_to_led
            .iter()
            .filter(|(l, _)| l == level)
            .filter_map(|(_, ms)| *ms)
            .collect();
        row(md, &format!("... into {level}"), &samples);
    }
    let _ = writeln!(
        md,
        "\nWhy these figures: a crossing is seen at the next sonar job (every 40 ms), \
         its level decided at the next `OsObstacleDetectionTask` job (every 20 ms) and \
         shown at the next `OsLEDTask` job (every 10 ms), so the latency spreads over about \
         70 ms by the phases alone; an echo's frame leaves as soon as `OsComTask` runs \
         after the sonar job, and its latency is the bus's: arbitration and the frame's \
         bits at 500 kbit/s. The paper gives no end-to-end figure.\n"
    );
    for name in PLOTS {
        let _ = writeln!(md, "![{name}]({plots_dir}/{name})\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scenario_repeats_with_a_growing_hold_and_other_lines_are_refused() {
        // 150 ms a repetition: held 57 ms each time, the next starts at 207 (7 into its
        // 40 ms), then at 414 (14).
        let (runs, k) = repeated("# c\nhold 500 100\nramp 500 900 50 # x\n", 400).unwrap();
        assert_eq!(k, 2);
        let text = runs.concat();
        let holds: Vec<&str> = text.lines().filter(|l| l.starts_with("hold 900")).collect();
        assert_eq!(holds, ["hold 900 57", "hold 900 57"]);
        assert_eq!(text.lines().filter(|l| l.starts_with("ramp")).count(), 2);
        let error = repeated("hold 500 100\nnoise 5\n", 400).unwrap_err();
        assert!(error.contains("line 2"), "{error}");
        assert!(repeated("# only\n", 10).is_err());
    }

    #[test]
    fn long_runs_are_split_within_the_simulations_64_movements() {
        // 5 lines and a hold per repetition: 10 repetitions per run.
        let figure7 =
            "hold 500 3000\nhold 1000 3000\nhold 1500 3000\nhold 2000 3000\nhold 2500 3000\n";
        let (runs, k) = repeated(figure7, 1_800_000).unwrap();
        assert_eq!(k, 120);
        assert_eq!(runs.len(), 12);
        // Every phase of the 40 ms period is a repetition's start.
        let mut phases: Vec<u64> = (1..k).map(|k| k * SHIFT_MS % 40).collect();
        phases.sort_unstable();
        phases.dedup();
        assert_eq!(phases.len(), 40);
        for run in &runs {
            let moves = run.lines().filter(|l| !l.starts_with('#')).count();
            assert!(moves <= LINES_PER_RUN, "{moves}");
        }
    }

    #[test]
    fn the_latencies_are_read_and_a_crossing_never_shown_fails_the_check() {
        let text = "path,at_us,level,latency_us\n\
            echo_to_frame,40000,,260\n\
            crossing_to_led,3000000,Yellow,41000\n";
        let e2e = parse(text).unwrap();
        assert_eq!(e2e.echo_to_frame, [0.26]);
        assert_eq!(e2e.crossing_to_led, [("Yellow".to_string(), Some(41.0))]);
        assert_eq!(check(&e2e), Ok(()));
        let never = parse(&text.replace(",41000", ",")).unwrap();
        assert!(check(&never).unwrap_err().contains("did not show"));
        assert!(parse(&text.replace(",,260", ",Red,260"))
            .unwrap_err()
            .contains("line 2"));
        assert!(parse("x\n").unwrap_err().contains("line 1"));
    }
}
