//! `cargo xtask qemu`: builds the ECU's Cortex-M4 image and runs it on QEMU's mps2-an386;
//! with `--compare`, checks that it is the same ECU as the host simulation.
//!
//! The image's CAN controller is UART0 speaking SLCAN; QEMU writes it to
//! `target/qemu/slcan.txt` (or serves it on a TCP port with `--serial tcp:PORT`). The LED
//! register's writes go to `target/qemu/fpgaio.log` (QEMU's `mps2_fpgaio_write` trace).
//! The run uses `-icount shift=0`: one instruction per nanosecond, so SysTick's
//! milliseconds are the image's own, independent of the host's speed.
//!
//! `--live` runs the image in real time (`-icount shift=0,sleep=on`: counted instructions
//! while the core runs, the host's clock while it sleeps) with UART0 on a TCP port and
//! `tests/slcan_live.py` against it: python-can's `slcan` interface receives the distance
//! frames and sends malformed lines and a `ThresholdConfig` frame that the ECU must apply;
//! the image's count of malformed lines and received frames must equal what was sent.
//!
//! `--scenario FILE` (repeatable; default `scenarios/figure7.txt`) names the scenarios the
//! image plays: it reads each over semihosting (`-semihosting-config ...,arg=--scenario,
//! arg=FILE`). Each run's files go to `target/qemu/<scenario name>/`.
//!
//! `--compare` runs the host simulation on each scenario and requires the same CAN frames
//! the ECU sent (id and payload, in order; the tester's frames of the scenario are on the
//! host's bus log but never on the image's UART) and the same transitions of each LED, in
//! order, with times within one OS tick. The image runs one frame further: its last
//! sample's frame leaves the UART at once, while the simulated bus is still transmitting
//! it when the simulation ends.

use std::path::{Path, PathBuf};

use cw_core::can::slcan;

use crate::process::{root, target_dir, Cmd};
use crate::Result;

const TARGET: &str = "thumbv7em-none-eabihf";
const FIGURE7: &str = "scenarios/figure7.txt";
const FAULTS: &str = "scenarios/faults.txt";

/// Options of `cargo xtask qemu`.
#[derive(Default)]
pub struct Options {
    scenarios: Vec<PathBuf>,
    compare: bool,
    live: bool,
    events: bool,
    serial: Option<String>,
}

impl Options {
    /// The options of the check command's `qemu` stage: the comparison, then the live test.
    pub fn ci() -> Self {
        Self {
            scenarios: vec![root().join(FIGURE7), root().join(FAULTS)],
            compare: true,
            live: true,
            events: true,
            serial: None,
        }
    }

    /// Parses `[--scenario FILE]... [--compare] [--live] [--events] [--serial tcp:PORT]`.
    pub fn parse(args: &[String]) -> Result<Self> {
        let mut options = Self::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            match arg.as_str() {
                "--compare" => options.compare = true,
                "--scenario" => {
                    let file = it.next().ok_or("qemu: --scenario takes a file")?;
                    options.scenarios.push(PathBuf::from(file));
                }
                "--live" => options.live = true,
                "--events" => options.events = true,
                "--serial" => {
                    let Some(port) = it.next().and_then(|a| a.strip_prefix("tcp:")) else {
                        return Err("qemu: --serial takes tcp:PORT".into());
                    };
                    let port: u16 = port
                        .parse()
                        .map_err(|_| format!("qemu: `{port}` is not a TCP port"))?;
                    options.serial = Some(format!("tcp:127.0.0.1:{port},server=on,wait=on"));
                }
                other => return Err(format!("qemu: unknown argument `{other}`")),
            }
        }
        Ok(options)
    }
}

/// Builds the ECU's image; returns its path.
pub fn build() -> Result<PathBuf> {
    build_bin("cw-qemu")
}

/// Builds image `bin` of cw-firmware for the board; returns its path.
fn build_bin(bin: &str) -> Result<PathBuf> {
    Cmd::new("cargo")
        .args([
            "build",
            "--release",
            "-p",
            "cw-firmware",
            "--no-default-features",
            "--features",
            "mps2",
            "--bin",
            bin,
            "--target",
            TARGET,
        ])
        .run()?;
    Ok(target_dir().join(TARGET).join("release").join(bin))
}

/// The machine and the image's log, exit and files (semihosting), for every run; the
/// image's command line names `scenario` if given.
fn qemu_machine(scenario: Option<&Path>) -> Vec<String> {
    let mut semihosting = String::from("enable=on,target=native,arg=cw-qemu");
    if let Some(file) = scenario {
        // QEMU's option syntax doubles a comma inside a value.
        let file = file.display().to_string().replace(',', ",,");
        semihosting.push_str(&format!(",arg=--scenario,arg={file}"));
    }
    [
        "-machine",
        "mps2-an386",
        "-nographic",
        "-monitor",
        "none",
        "-semihosting-config",
        &semihosting,
    ]
    .map(str::to_string)
    .to_vec()
}

/// Prints the image's report without its event lines and keeps it whole in `path`.
fn keep_report(report: &str, path: &Path) -> Result {
    print!(
        "{}",
        report
            .lines()
            .filter(|l| !l.starts_with("cw-qemu: event "))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    );
    std::fs::write(path, report).map_err(|e| format!("writing {}: {e}", path.display()))
}

/// Runs the image on QEMU; the SLCAN output and the LED trace go to `out`, the image's
/// semihosting report to `out/image.txt` (and the terminal).
fn run_image(image: &Path, out: &Path, serial: Option<&str>, scenario: Option<&Path>) -> Result {
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let slcan = out.join("slcan.txt");
    let leds = out.join("fpgaio.log");
    for f in [&slcan, &leds] {
        let _ = std::fs::remove_file(f);
    }
    let serial = serial.map_or_else(|| format!("file:{}", slcan.display()), str::to_string);
    let report = Cmd::new("qemu-system-arm")
        .args(qemu_machine(scenario))
        .args(["-icount", "shift=0,sleep=off"])
        .args(["-serial", &serial])
        .args(["-d", "trace:mps2_fpgaio_write", "-D"])
        .arg(&leds)
        .arg("-kernel")
        .arg(image)
        .read()?;
    keep_report(&report, &out.join("image.txt"))
}

/// Runs `cargo xtask qemu`.
pub fn run(options: &Options) -> Result {
    let out = target_dir().join("qemu");
    if options.events {
        events(&out)?;
        if !options.compare && !options.live && options.serial.is_none() {
            return Ok(());
        }
    }
    let image = build()?;
    if options.compare || !options.live {
        let default = [root().join(FIGURE7)];
        let scenarios = if options.scenarios.is_empty() {
            &default[..]
        } else {
            &options.scenarios[..]
        };
        for scenario in scenarios {
            let name = scenario
                .file_stem()
                .map_or_else(|| "scenario".into(), |s| s.to_string_lossy().to_string());
            let dir = out.join(&name);
            println!("qemu: scenario {}", scenario.display());
            run_image(&image, &dir, options.serial.as_deref(), Some(scenario))?;
            if options.compare {
                compare(&dir, scenario)?;
            }
        }
    }
    if options.live {
        live(&image, &out)?;
    }
    Ok(())
}

/// The extended-task demo (`cw-qemu-events`): it must end with `ok` (its waiter woke on
/// every alarm to the millisecond and on the ISR's events, then its deliberate stack
/// overflow was caught by the MPU guard and shut the OS down with `E_OS_STACKFAULT`).
fn events(out: &Path) -> Result {
    let image = build_bin("cw-qemu-events")?;
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let report = Cmd::new("qemu-system-arm")
        .args(qemu_machine(None))
        .args(["-icount", "shift=0,sleep=off"])
        .args(["-serial", "null"])
        .arg("-kernel")
        .arg(&image)
        .read()?;
    print!("{report}");
    if !report.lines().any(|l| l == "cw-qemu-events: ok") {
        return Err("qemu: the extended-task demo did not end with `ok`".into());
    }
    println!("qemu: extended tasks woke on alarm and ISR events; the stack overflow was caught and shut the OS down with E_OS_STACKFAULT");
    Ok(())
}

/// A free TCP port on the loopback interface (the OS picks it; QEMU binds it next).
fn free_port() -> Result<u16> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("qemu: no free TCP port: {e}"))
}

/// The image in real time with UART0 on a TCP port, `tests/slcan_live.py` against it;
/// its report (with the receive path's instruction counts) goes to `out/image-live.txt`.
fn live(image: &Path, out: &Path) -> Result {
    use std::io::Read;
    use std::process::{Command, Stdio};
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let port = free_port()?;
    let serial = format!("tcp:127.0.0.1:{port},server=on,wait=on");
    let leds = out.join("fpgaio-live.log");
    println!(
        "$ qemu-system-arm -machine mps2-an386 -icount shift=0,sleep=on -serial {serial} -kernel {}",
        image.display()
    );
    let mut qemu = Command::new("qemu-system-arm")
        .args(qemu_machine(None))
        // One instruction per ns while the core runs, real time while it sleeps (WFI):
        // the run keeps pace with python-can, and the image's spans are instructions.
        .args(["-icount", "shift=0,sleep=on"])
        .args(["-serial", &serial])
        .args(["-d", "trace:mps2_fpgaio_write", "-D"])
        .arg(&leds)
        .arg("-kernel")
        .arg(image)
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("qemu-system-arm: {e}"))?;
    let test = Cmd::new(crate::setup::venv_python())
        .arg(root().join("tests").join("slcan_live.py"))
        .arg(port.to_string())
        .arg(root().join("firmware").join("ecu.dbc"))
        .read();
    let test = match test {
        Ok(output) => output,
        Err(e) => {
            let _ = qemu.kill();
            let _ = qemu.wait();
            return Err(e);
        }
    };
    print!("{test}");
    let mut image_out = String::new();
    if let Some(mut stdout) = qemu.stdout.take() {
        stdout
            .read_to_string(&mut image_out)
            .map_err(|e| format!("reading QEMU's output: {e}"))?;
    }
    let status = qemu.wait().map_err(|e| format!("qemu-system-arm: {e}"))?;
    keep_report(&image_out, &out.join("image-live.txt"))?;
    if !status.success() {
        return Err(format!("qemu: the live image ended with {status}"));
    }
    let sent = counts_after(
        &test,
        "slcan-live: sent ",
        &[" malformed lines and ", " frames"],
    )?;
    let got = counts_after(
        &image_out,
        "cw-qemu: slcan received ",
        &[" frames, ", " commands, ", " malformed lines"],
    )?;
    let (sent_malformed, sent_frames) = (sent[0], sent[1]);
    let (got_frames, got_malformed) = (got[0], got[2]);
    if (got_malformed, got_frames) != (sent_malformed, sent_frames) {
        return Err(format!(
            "qemu: python-can sent {sent_malformed} malformed lines and {sent_frames} frames; \
             the image counted {got_malformed} malformed lines and received {got_frames} frames"
        ));
    }
    println!(
        "qemu: live SLCAN both ways: the image counted the {got_malformed} malformed lines python-can \
         sent and received its {got_frames} frames"
    );
    Ok(())
}

/// The numbers in the line of `text` that starts with `prefix`, each followed by the
/// next separator (`12 malformed lines and 1 frames` with separators ` malformed lines
/// and `, ` frames`).
fn counts_after(text: &str, prefix: &str, separators: &[&str]) -> Result<Vec<u32>> {
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(prefix))
        .ok_or_else(|| format!("qemu: no line starting `{prefix}` in:\n{text}"))?;
    let mut rest = line;
    let mut numbers = Vec::new();
    for sep in separators {
        let (number, tail) = rest
            .split_once(sep)
            .ok_or_else(|| format!("qemu: `{line}` lacks `{sep}`"))?;
        numbers.push(
            number
                .trim()
                .parse()
                .map_err(|_| format!("qemu: `{number}` in `{line}` is not a count"))?,
        );
        rest = tail;
    }
    Ok(numbers)
}

/// A frame as `ID#HEX` and when it went out, ms.
type Timed = (f64, String);

/// The image's frames from its SLCAN lines (`tIIILDD..SSSS`: Lawicel time stamps, ms
/// modulo 60 000, unwrapped here: the image sends at least one frame a minute).
fn slcan_frames(text: &str) -> Result<Vec<Timed>> {
    let mut frames = Vec::new();
    let mut minutes = 0u32;
    let mut last = 0u32;
    for (i, line) in text.split('\r').filter(|l| !l.is_empty()).enumerate() {
        let (frame, stamp) = slcan::parse_adapter_line(line.as_bytes())
            .map_err(|e| format!("SLCAN line {}: `{line}`: {e:?}", i + 1))?;
        let stamp =
            stamp.ok_or_else(|| format!("SLCAN line {}: `{line}` has no time stamp", i + 1))?;
        let stamp = u32::from(stamp);
        if stamp < last {
            minutes += 1;
        }
        last = stamp;
        let id = frame.can_id();
        let id = if id.is_extended() {
            format!("{:08X}", id.raw())
        } else {
            format!("{:03X}", id.raw())
        };
        let data: String = frame.bytes().iter().map(|b| format!("{b:02X}")).collect();
        let ms = minutes * slcan::TIMESTAMP_MODULUS + stamp;
        frames.push((f64::from(ms), format!("{id}#{data}")));
    }
    Ok(frames)
}

/// Frames from a candump log (`(SECONDS) can0 ID#HEX`), times in ms from the log's epoch
/// (the simulation's logs start at 1 700 000 000 s).
fn candump_frames(text: &str) -> Result<Vec<Timed>> {
    text.lines()
        .enumerate()
        .map(|(i, line)| {
            let bad = || {
                format!(
                    "candump line {}: `{line}` is not `(SECONDS) IFACE ID#DATA`",
                    i + 1
                )
            };
            let mut fields = line.split_whitespace();
            let stamp = fields
                .next()
                .and_then(|t| t.strip_prefix('(')?.strip_suffix(')'))
                .ok_or_else(bad)?;
            // Whole seconds and microseconds as integers: no rounding on the way.
            let (whole, micros) = stamp.split_once('.').ok_or_else(bad)?;
            let whole: i64 = whole.parse().map_err(|_| bad())?;
            let micros: i64 = format!("{micros:0<6}")
                .get(..6)
                .and_then(|m| m.parse().ok())
                .ok_or_else(bad)?;
            let us = (whole - 1_700_000_000) * 1_000_000 + micros;
            let frame = fields.nth(1).ok_or_else(bad)?;
            Ok((us as f64 / 1000.0, frame.to_string()))
        })
        .collect()
}

/// One LED's levels in order, each with the time it was taken, ms.
type Levels = Vec<(f64, bool)>;

/// The levels each LED (red, yellow) took, from the image's `led MS RED YELLOW` lines.
fn image_transitions(report: &str) -> Result<[Levels; 2]> {
    let mut seq: [Levels; 2] = [vec![(0.0, false)], vec![(0.0, false)]];
    for line in report.lines() {
        let Some(rest) = line.strip_prefix("cw-qemu: led ") else {
            continue;
        };
        let fields: Vec<u32> = rest
            .split_whitespace()
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| format!("image report: `{line}` is not `led MS RED YELLOW`"))?;
        let [at, red, yellow] = fields[..] else {
            return Err(format!("image report: `{line}` is not `led MS RED YELLOW`"));
        };
        push_level(&mut seq[0], f64::from(at), red == 1);
        push_level(&mut seq[1], f64::from(at), yellow == 1);
    }
    if report.contains("cw-qemu: led changes not logged") {
        return Err("image report: the LED log overflowed".into());
    }
    Ok(seq)
}

/// The levels each LED took, from the simulation's trace CSV (every 10 ms, after that
/// millisecond's tasks: the LED task's 10 ms period).
fn csv_transitions(text: &str) -> Result<[Levels; 2]> {
    // The LEDs are dark from Port_Init on.
    let mut seq: [Levels; 2] = [vec![(0.0, false)], vec![(0.0, false)]];
    for (i, line) in text.lines().enumerate().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let bad = || {
            format!(
                "trace line {}: `{line}` is not `time_ms,..,red,yellow,..`",
                i + 1
            )
        };
        let (Some(at), Some(red), Some(yellow)) = (cols.first(), cols.get(4), cols.get(5)) else {
            return Err(bad());
        };
        let at: f64 = at.parse().map_err(|_| bad())?;
        push_level(&mut seq[0], at, *red == "1");
        push_level(&mut seq[1], at, *yellow == "1");
    }
    Ok(seq)
}

fn push_level(seq: &mut Levels, at: f64, level: bool) {
    if seq.last().map(|l| l.1) != Some(level) {
        seq.push((at, level));
    }
}

/// The largest time difference between paired events, ms; an error naming the first pair
/// that differs in content.
fn max_skew<T: PartialEq + std::fmt::Debug>(
    what: &str,
    image: &[(f64, T)],
    host: &[(f64, T)],
) -> Result<f64> {
    let mut skew = 0f64;
    for (i, (a, b)) in image.iter().zip(host).enumerate() {
        if a.1 != b.1 {
            return Err(format!(
                "qemu: {what} {} differs: image {:?} at {} ms, simulation {:?} at {} ms",
                i + 1,
                a.1,
                a.0,
                b.1,
                b.0
            ));
        }
        skew = skew.max((a.0 - b.0).abs());
    }
    Ok(skew)
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| format!("reading {}: {e}", path.display()))
}

/// The image's frames and LED transitions against the host simulation's, on `scenario`.
fn compare(out: &Path, scenario: &Path) -> Result {
    let can_log = out.join("host.log");
    let trace = out.join("host.csv");
    Cmd::new("cargo")
        .args(["run", "--release", "--quiet", "--", "--scenario"])
        .arg(scenario)
        .arg("--can-log")
        .arg(&can_log)
        .arg("--trace")
        .arg(&trace)
        .run()?;
    let image = slcan_frames(&read(&out.join("slcan.txt"))?)?;
    let text = read(scenario)?;
    let tester = cw_core::scenario::Scenario::<64>::parse(&text)
        .map_err(|e| format!("{}: {e}", scenario.display()))?
        .frames;
    let host = ecu_frames(candump_frames(&read(&can_log)?)?, &tester);
    if host.is_empty() || image.len() < host.len() || image.len() > host.len() + 1 {
        return Err(format!(
            "qemu: {} frames from the image, {} from the simulation",
            image.len(),
            host.len()
        ));
    }
    // The image stamps a frame at Can_Write (whole ms); the simulation logs it when its
    // last bit has crossed the simulated 500 kbit/s bus, a fraction of a ms later.
    let frame_skew = max_skew("frame", &image, &host)?;
    let report = read(&out.join("image.txt"))?;
    let image_leds = image_transitions(&report)?;
    let host_leds = csv_transitions(&read(&trace)?)?;
    let mut led_skew = 0f64;
    for (name, (a, b)) in ["red", "yellow"]
        .iter()
        .zip(image_leds.iter().zip(&host_leds))
    {
        if a.len() != b.len() {
            return Err(format!(
                "qemu: the {name} LED took {} levels on the image, {} in the simulation",
                a.len(),
                b.len()
            ));
        }
        led_skew = led_skew.max(max_skew(&format!("{name} LED level"), a, b)?);
    }
    if frame_skew >= OS_TICK_MS || led_skew >= OS_TICK_MS {
        return Err(format!(
            "qemu: times differ by more than one OS tick: frames by up to {frame_skew:.3} ms, \
             LED changes by up to {led_skew:.3} ms"
        ));
    }
    let schedule = report
        .lines()
        .find_map(|l| l.strip_prefix("cw-qemu: schedule "))
        .ok_or("qemu: the image reported no schedule check")?;
    if !schedule.contains(" 0 not by a higher priority; 0 periodic tasks") {
        return Err(format!(
            "qemu: the image's schedule check failed: {schedule}"
        ));
    }
    let scenario = scenario.display();
    println!(
        "qemu: same ECU on {scenario}: {} CAN frames compared (id and payload, in order; the \
         image sent {} more), times within {frame_skew:.3} ms; {} red and {} yellow LED levels \
         compared in order, times within {led_skew:.3} ms; schedule: {schedule}",
        host.len(),
        image.len() - host.len(),
        host_leds[0].len(),
        host_leds[1].len()
    );
    Ok(())
}

/// The frames on the host's bus without the scenario's tester frames: each tester frame
/// takes the first frame equal to it at or after its time.
fn ecu_frames(mut frames: Vec<Timed>, tester: &[(u32, cw_core::can::CanFrame)]) -> Vec<Timed> {
    for (at, frame) in tester {
        let text = {
            let mut t = String::new();
            let _ = cw_core::can::text::write_frame(frame, &mut t);
            t
        };
        if let Some(i) = frames
            .iter()
            .position(|(t, f)| *t >= f64::from(*at) && *f == text)
        {
            frames.remove(i);
        }
    }
    frames
}

/// One OS tick, ms: the tolerance on times compared.
const OS_TICK_MS: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_read_their_formats_and_refuse_garbage() {
        assert_eq!(
            slcan_frames("t1008F4010000030000000028\rt2001AA0030\rt2001AA0001\r").unwrap(),
            [
                (40.0, "100#F401000003000000".to_string()),
                (48.0, "200#AA".to_string()),
                (60_001.0, "200#AA".to_string())
            ]
        );
        assert!(slcan_frames("x123\r").is_err());
        assert!(
            slcan_frames("t2001AA\r").is_err(),
            "a line without a time stamp"
        );
        assert_eq!(
            candump_frames("(1700000000.040250) can0 100#AA\n").unwrap(),
            [(40.25, "100#AA".to_string())]
        );
        assert!(candump_frames("garbage\n").is_err());
        let leds =
            image_transitions("cw-qemu: led 10 1 0\ncw-qemu: led 10 1 1\ncw-qemu: led 70 0 1\n")
                .unwrap();
        assert_eq!(leds[0], [(0.0, false), (10.0, true), (70.0, false)]);
        assert_eq!(leds[1], [(0.0, false), (10.0, true)]);
        assert!(image_transitions("cw-qemu: led 10 x\n").is_err());
        let csv = csv_transitions("h\n10,1,1,Red,1,0,d\n20,1,1,Red,1,1,d\n").unwrap();
        assert_eq!(
            csv,
            [
                vec![(0.0, false), (10.0, true)],
                vec![(0.0, false), (20.0, true)]
            ]
        );
        assert!(max_skew("frame", &[(1.0, 1)], &[(1.5, 2)]).is_err());
        assert_eq!(max_skew("frame", &[(1.0, 1)], &[(1.5, 1)]).unwrap(), 0.5);
    }
}
