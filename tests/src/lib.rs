//! Emulator in the loop: the ECU's Cortex-M4 image on QEMU's mps2-an386 against the host
//! simulation, on the same scenario file.
//!
//! The book: [the Cortex-M4 image](../../book/cortex-m4.html#the-same-ecu-emulator-in-the-loop).
//!
//! - [`run_image`] runs the image (`-icount shift=5`, `cw_bsp::icount`: 32 ns per
//!   instruction, so its milliseconds are its own) with the scenario on its semihosting command line; UART0
//!   (the SLCAN CAN controller) goes to a file, the image's report (its `defmt` log,
//!   decoded: [`qemu`]) to the caller.
//! - [`simulate`] runs the host simulation in-process on the same file.
//! - [`compare`] requires the same frames the ECU sent (id and payload, in order) and the
//!   same levels of each LED, in order, with times within one OS tick.
//!
//! The image stamps a frame with the OS ms of the moment its line leaves (Lawicel time
//! stamps); the simulation logs it when its last bit has crossed the simulated 500 kbit/s
//! bus. The image runs one frame further: its last sample's frame leaves the UART at
//! once, while the simulated bus is still transmitting it when the simulation ends.
//!
//! The tests (`tests/emulator.rs`) take the image from `CW_QEMU_IMAGE`, which
//! `cargo xtask qemu --compare` sets after building it.

use std::path::{Path, PathBuf};
use std::process::Command;

pub mod qemu;

use cw_core::can::{slcan, text, CanFrame};
use cw_firmware::host::{Scenario, Simulation};

/// One OS tick, ms: the tolerance on times compared.
pub const OS_TICK_MS: f64 = 1.0;

/// A frame as `ID#HEX` and when it went out, ms.
pub type Timed = (f64, String);

/// One LED's levels in order, each with the time it was taken, ms (starting dark at 0).
pub type Levels = Vec<(f64, bool)>;

/// What a run showed: the ECU's frames and the levels of the red and yellow LEDs.
#[derive(Debug, Default)]
pub struct Trace {
    /// The frames the ECU sent, in order.
    pub frames: Vec<Timed>,
    /// The red LED's levels.
    pub red: Levels,
    /// The yellow LED's levels.
    pub yellow: Levels,
}

/// An image run.
#[derive(Debug)]
pub struct ImageRun {
    /// Whether the image ended with success (semihosting `SYS_EXIT`).
    pub success: bool,
    /// Its log, decoded.
    pub report: String,
    /// Its UART0 output (SLCAN).
    pub slcan: String,
}

/// The image to test: `CW_QEMU_IMAGE`.
///
/// # Errors
/// A sentence saying how to build it when the variable is not set.
pub fn image() -> Result<PathBuf, String> {
    std::env::var_os("CW_QEMU_IMAGE")
        .map(PathBuf::from)
        .ok_or_else(|| {
            "CW_QEMU_IMAGE is not set: run these tests with `cargo xtask qemu --compare`, \
         which builds the image and names it"
                .to_string()
        })
}

/// Runs `image` on QEMU with `scenario` on its command line (none: the compiled-in
/// Figure 7); UART0 goes to `dir/slcan.txt`.
///
/// # Errors
/// QEMU cannot be started or its files cannot be written or read.
pub fn run_image(
    image: &Path,
    scenario: Option<&Path>,
    seed: u64,
    dir: &Path,
) -> Result<ImageRun, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let uart = dir.join("slcan.txt");
    let _ = std::fs::remove_file(&uart);
    let scenario = scenario.map(|file| file.display().to_string());
    let seed = seed.to_string();
    let mut args = vec!["--seed", seed.as_str()];
    if let Some(file) = scenario.as_deref() {
        args.extend(["--scenario", file]);
    }
    let mut command = Command::new("qemu-system-arm");
    command
        .args(qemu::machine("cw-qemu", &args))
        .args(["-icount", cw_bsp::icount::VIRTUAL])
        .arg("-serial")
        .arg(format!("file:{}", uart.display()))
        .arg("-kernel")
        .arg(image);
    let (success, report) = qemu::run(command, image)?;
    std::fs::write(dir.join("image.txt"), &report)
        .map_err(|e| format!("writing {}: {e}", dir.display()))?;
    let slcan = std::fs::read(&uart).map_or_else(
        |_| String::new(),
        |b| String::from_utf8_lossy(&b).into_owned(),
    );
    Ok(ImageRun {
        success,
        report,
        slcan,
    })
}

/// The frame as `ID#HEX`.
fn frame_text(frame: &CanFrame) -> String {
    let mut t = String::new();
    // Writing to a String cannot fail.
    let _ = text::write_frame(frame, &mut t);
    t
}

fn push_level(seq: &mut Levels, at: f64, level: bool) {
    if seq.last().map(|l| l.1) != Some(level) {
        seq.push((at, level));
    }
}

impl ImageRun {
    /// The image's trace: its SLCAN frames (Lawicel time stamps, ms modulo 60 000,
    /// unwrapped: the ECU sends a frame at least every minute) and its `led MS RED
    /// YELLOW` report lines.
    ///
    /// # Errors
    /// A line that is not what the image writes, naming it.
    pub fn trace(&self) -> Result<Trace, String> {
        let mut t = Trace {
            frames: Vec::new(),
            red: vec![(0.0, false)],
            yellow: vec![(0.0, false)],
        };
        let mut minutes = 0u32;
        let mut last = 0u32;
        for (i, line) in self.slcan.split('\r').filter(|l| !l.is_empty()).enumerate() {
            let (frame, stamp) = slcan::parse_adapter_line(line.as_bytes())
                .map_err(|e| format!("SLCAN line {}: `{line}`: {e:?}", i + 1))?;
            let stamp = u32::from(
                stamp.ok_or_else(|| format!("SLCAN line {}: `{line}` has no time stamp", i + 1))?,
            );
            if stamp < last {
                minutes += 1;
            }
            last = stamp;
            let ms = minutes * slcan::TIMESTAMP_MODULUS + stamp;
            t.frames.push((f64::from(ms), frame_text(&frame)));
        }
        for line in self.report.lines() {
            let Some(rest) = line.strip_prefix("cw-qemu: led ") else {
                continue;
            };
            let bad = || format!("image report: `{line}` is not `led MS RED YELLOW`");
            let fields: Vec<u32> = rest
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            let [at, red, yellow] = fields[..] else {
                return Err(bad());
            };
            push_level(&mut t.red, f64::from(at), red == 1);
            push_level(&mut t.yellow, f64::from(at), yellow == 1);
        }
        if self.report.contains("cw-qemu: led changes not logged") {
            return Err("image report: the LED log overflowed".into());
        }
        Ok(t)
    }

    /// The image's `schedule` line (its check that every preemption was by a higher
    /// priority and no periodic job outlasted its period).
    pub fn schedule(&self) -> Option<&str> {
        self.report
            .lines()
            .find_map(|l| l.strip_prefix("cw-qemu: schedule "))
    }
}

/// The host simulation on the scenario in `path`, for as long as the scenario lasts:
/// the frames the ECU sent (not the scenario's tester frames) and the LED pins' levels.
///
/// # Errors
/// The file cannot be read or parsed, or the ECU's configuration is inconsistent.
pub fn simulate(path: &Path, seed: u64) -> Result<Trace, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let scenario = Scenario::parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut sim = Simulation::new(scenario, seed).map_err(|e| e.to_string())?;
    sim.run();
    let ecu = sim.ecu().com_stack().can.node();
    let ms = |us: u64| us as f64 / 1000.0;
    let levels = |history: Vec<(u64, bool)>| {
        let mut seq = vec![(0.0, false)];
        for (at, level) in history {
            push_level(&mut seq, ms(at), level);
        }
        seq
    };
    Ok(Trace {
        frames: sim
            .frames()
            .iter()
            .filter(|r| r.sender == ecu)
            .map(|r| (ms(r.time_us), frame_text(&r.frame)))
            .collect(),
        red: levels(sim.red_led().history()),
        yellow: levels(sim.yellow_led().history()),
    })
}

/// What agreed: the counts compared and the largest time differences, ms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agreement {
    /// Frames compared.
    pub frames: usize,
    /// Frames the image sent beyond the simulation's end.
    pub image_extra: usize,
    /// Largest frame time difference.
    pub frame_skew_ms: f64,
    /// Red LED levels compared.
    pub red: usize,
    /// Yellow LED levels compared.
    pub yellow: usize,
    /// Largest LED time difference.
    pub led_skew_ms: f64,
}

/// The largest time difference between paired events, ms; an error naming the first pair
/// that differs in content.
fn max_skew<T: PartialEq + std::fmt::Debug>(
    what: &str,
    image: &[(f64, T)],
    host: &[(f64, T)],
) -> Result<f64, String> {
    let mut skew = 0f64;
    for (i, (a, b)) in image.iter().zip(host).enumerate() {
        if a.1 != b.1 {
            return Err(format!(
                "{what} {} differs: image {:?} at {} ms, simulation {:?} at {} ms",
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

/// The image's trace against the simulation's: the same frames in order (the image may
/// send one more), the same LED levels in order, every time within one OS tick.
///
/// # Errors
/// The first difference, named.
pub fn compare(image: &Trace, host: &Trace) -> Result<Agreement, String> {
    let (i, h) = (image.frames.len(), host.frames.len());
    if h == 0 || i < h || i > h + 1 {
        return Err(format!(
            "{i} frames from the image, {h} from the simulation"
        ));
    }
    let frame_skew_ms = max_skew("frame", &image.frames, &host.frames)?;
    let mut led_skew_ms = 0f64;
    for (name, a, b) in [
        ("red", &image.red, &host.red),
        ("yellow", &image.yellow, &host.yellow),
    ] {
        if a.len() != b.len() {
            return Err(format!(
                "the {name} LED took {} levels on the image, {} in the simulation",
                a.len(),
                b.len()
            ));
        }
        led_skew_ms = led_skew_ms.max(max_skew(&format!("{name} LED level"), a, b)?);
    }
    if frame_skew_ms >= OS_TICK_MS || led_skew_ms >= OS_TICK_MS {
        return Err(format!(
            "times differ by more than one OS tick: frames by up to {frame_skew_ms:.3} ms, \
             LED changes by up to {led_skew_ms:.3} ms"
        ));
    }
    Ok(Agreement {
        frames: h,
        image_extra: i - h,
        frame_skew_ms,
        red: host.red.len(),
        yellow: host.yellow.len(),
        led_skew_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(report: &str, slcan: &str) -> ImageRun {
        ImageRun {
            success: true,
            report: report.into(),
            slcan: slcan.into(),
        }
    }

    #[test]
    fn image_output_is_read_and_garbage_named() {
        let t = run(
            "cw-qemu: led 10 1 0\ncw-qemu: led 70 0 0\n",
            "t1008DC05000001000000EA5F\rt1008DC050000010000000001\r",
        )
        .trace()
        .map_err(|e| panic!("{e}"))
        .unwrap_or_default();
        assert_eq!(t.frames[0], (59_999.0, "100#DC05000001000000".into()));
        assert_eq!(t.frames[1].0, 60_001.0, "the stamp wrapped: a minute later");
        assert_eq!(t.red, vec![(0.0, false), (10.0, true), (70.0, false)]);
        assert!(run("cw-qemu: led 10 x 0\n", "").trace().is_err());
        assert!(run("", "t100\r").trace().is_err());
        assert!(run("", "t1001AB\r").trace().is_err(), "no time stamp");
    }

    #[test]
    fn a_comparison_names_the_first_difference() {
        let host = Trace {
            frames: vec![(0.3, "100#01".into()), (40.3, "100#02".into())],
            red: vec![(0.0, false)],
            yellow: vec![(0.0, false), (10.0, true)],
        };
        let mut image = Trace {
            frames: vec![
                (0.0, "100#01".into()),
                (40.0, "100#02".into()),
                (80.0, "100#03".into()),
            ],
            red: vec![(0.0, false)],
            yellow: vec![(0.0, false), (10.0, true)],
        };
        let a = compare(&image, &host).map_err(|e| panic!("{e}"));
        assert_eq!(a.map(|a| (a.frames, a.image_extra)), Ok((2, 1)));
        image.frames[1].1 = "100#FF".into();
        let e = compare(&image, &host).err().unwrap_or_default();
        assert!(e.starts_with("frame 2 differs"), "{e}");
        image.frames[1] = (41.5, "100#02".into());
        let e = compare(&image, &host).err().unwrap_or_default();
        assert!(
            e.starts_with("times differ by more than one OS tick"),
            "{e}"
        );
        image.frames[1].0 = 40.0;
        image.yellow.push((20.0, false));
        let e = compare(&image, &host).err().unwrap_or_default();
        assert!(e.contains("yellow LED took 3 levels"), "{e}");
    }
}
