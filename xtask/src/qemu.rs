//! `cargo xtask qemu`: builds the ECU's Cortex-M4 image and runs it on QEMU's mps2-an386;
//! with `--compare`, checks that it is the same ECU as the host simulation.
//!
//! The image's CAN controller is UART0 speaking SLCAN; QEMU writes it to
//! `target/qemu/slcan.txt` (or serves it on a TCP port with `--serial tcp:PORT`). The LED
//! register's writes go to `target/qemu/fpgaio.log` (QEMU's `mps2_fpgaio_write` trace).
//! The run uses `-icount shift=0`: one instruction per nanosecond, so SysTick's
//! milliseconds are the image's own, independent of the host's speed.
//!
//! `--compare` runs the host simulation on the same scenario (Figure 7) and requires the
//! same CAN frames (id and payload, in order) and the same transitions of each LED, in
//! order. The image runs one frame further: its last sample's frame leaves the UART at
//! once, while the simulated bus is still transmitting it when the simulation ends.

use std::path::{Path, PathBuf};

use crate::process::{root, target_dir, Cmd};
use crate::Result;

const TARGET: &str = "thumbv7em-none-eabihf";
const SCENARIO: &str = "scenarios/figure7.txt";

/// Options of `cargo xtask qemu`.
#[derive(Default)]
pub struct Options {
    compare: bool,
    serial: Option<String>,
}

impl Options {
    /// Parses `[--compare] [--serial tcp:PORT]`.
    pub fn parse(args: &[String]) -> Result<Self> {
        let mut options = Self::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            match arg.as_str() {
                "--compare" => options.compare = true,
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

/// Builds the image; returns its path.
pub fn build() -> Result<PathBuf> {
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
            "cw-qemu",
            "--target",
            TARGET,
        ])
        .run()?;
    Ok(target_dir().join(TARGET).join("release").join("cw-qemu"))
}

/// Runs the image on QEMU; the SLCAN output and the LED trace go to `out`.
fn run_image(image: &Path, out: &Path, serial: Option<&str>) -> Result {
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let slcan = out.join("slcan.txt");
    let leds = out.join("fpgaio.log");
    for f in [&slcan, &leds] {
        let _ = std::fs::remove_file(f);
    }
    let serial = serial.map_or_else(|| format!("file:{}", slcan.display()), str::to_string);
    Cmd::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-nographic", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", "shift=0,sleep=off"])
        .args(["-serial", &serial])
        .args(["-d", "trace:mps2_fpgaio_write", "-D"])
        .arg(&leds)
        .arg("-kernel")
        .arg(image)
        .run()
}

/// Runs `cargo xtask qemu`.
pub fn run(options: &Options) -> Result {
    let image = build()?;
    let out = target_dir().join("qemu");
    run_image(&image, &out, options.serial.as_deref())?;
    if options.compare {
        compare(&out)?;
    }
    Ok(())
}

/// Frames as `ID#HEX` from the image's SLCAN lines (`tIIILDD..`).
fn slcan_frames(text: &str) -> Result<Vec<String>> {
    text.split('\r')
        .filter(|l| !l.is_empty())
        .enumerate()
        .map(|(i, line)| {
            let bad = || {
                format!(
                    "SLCAN line {}: `{line}` is not a standard data frame",
                    i + 1
                )
            };
            let rest = line.strip_prefix('t').ok_or_else(bad)?;
            let id = rest.get(..3).ok_or_else(bad)?;
            let data = rest.get(4..).ok_or_else(bad)?;
            Ok(format!("{id}#{data}"))
        })
        .collect()
}

/// Frames as `ID#HEX` from a candump log.
fn candump_frames(text: &str) -> Result<Vec<String>> {
    text.lines()
        .enumerate()
        .map(|(i, line)| {
            line.split_whitespace()
                .nth(2)
                .map(str::to_string)
                .ok_or_else(|| format!("candump line {}: `{line}` has no frame", i + 1))
        })
        .collect()
}

/// The levels each LED (red, yellow) took, in order, from the FPGAIO trace.
fn fpgaio_transitions(text: &str) -> Result<[Vec<bool>; 2]> {
    let mut seq: [Vec<bool>; 2] = [Vec::new(), Vec::new()];
    for (i, line) in text.lines().enumerate() {
        if !line.contains("mps2_fpgaio_write") || !line.contains("offset 0x0 ") {
            continue;
        }
        let value = line
            .split("data ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|v| u32::from_str_radix(v.trim_start_matches("0x"), 16).ok())
            .ok_or_else(|| format!("LED trace line {}: `{line}` has no data", i + 1))?;
        for (bit, s) in seq.iter_mut().enumerate() {
            push_level(s, value & (1 << bit) != 0);
        }
    }
    Ok(seq)
}

/// The levels each LED took, in order, from the simulation's trace CSV (every 10 ms, after
/// that millisecond's tasks: the LED task's 10 ms period).
fn csv_transitions(text: &str) -> Result<[Vec<bool>; 2]> {
    let mut seq: [Vec<bool>; 2] = [Vec::new(), Vec::new()];
    // The LEDs are dark from Port_Init on.
    push_level(&mut seq[0], false);
    push_level(&mut seq[1], false);
    for (i, line) in text.lines().enumerate().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let (Some(red), Some(yellow)) = (cols.get(4), cols.get(5)) else {
            return Err(format!(
                "trace line {}: `{line}` has too few columns",
                i + 1
            ));
        };
        push_level(&mut seq[0], *red == "1");
        push_level(&mut seq[1], *yellow == "1");
    }
    Ok(seq)
}

fn push_level(seq: &mut Vec<bool>, level: bool) {
    if seq.last() != Some(&level) {
        seq.push(level);
    }
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| format!("reading {}: {e}", path.display()))
}

/// The image's frames and LED transitions against the host simulation's.
fn compare(out: &Path) -> Result {
    let can_log = out.join("host.log");
    let trace = out.join("host.csv");
    Cmd::new("cargo")
        .args(["run", "--release", "--quiet", "--", "--scenario"])
        .arg(root().join(SCENARIO))
        .arg("--can-log")
        .arg(&can_log)
        .arg("--trace")
        .arg(&trace)
        .run()?;
    let image = slcan_frames(&read(&out.join("slcan.txt"))?)?;
    let host = candump_frames(&read(&can_log)?)?;
    if host.is_empty() || image.len() < host.len() || image.len() > host.len() + 1 {
        return Err(format!(
            "qemu: {} frames from the image, {} from the simulation",
            image.len(),
            host.len()
        ));
    }
    if let Some(i) = image.iter().zip(&host).position(|(a, b)| a != b) {
        return Err(format!(
            "qemu: frame {} differs: image {}, simulation {}",
            i + 1,
            image.get(i).map_or("", String::as_str),
            host.get(i).map_or("", String::as_str)
        ));
    }
    let image_leds = fpgaio_transitions(&read(&out.join("fpgaio.log"))?)?;
    let host_leds = csv_transitions(&read(&trace)?)?;
    for (name, (a, b)) in ["red", "yellow"]
        .iter()
        .zip(image_leds.iter().zip(&host_leds))
    {
        if a != b {
            return Err(format!(
                "qemu: the {name} LED's transitions differ: image {} levels, simulation {}",
                a.len(),
                b.len()
            ));
        }
    }
    println!(
        "qemu: same ECU on {SCENARIO}: {} CAN frames compared (id and payload, in order; the \
         image sent {} more), {} red and {} yellow LED levels compared in order",
        host.len(),
        image.len() - host.len(),
        host_leds[0].len(),
        host_leds[1].len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_read_their_formats_and_refuse_garbage() {
        assert_eq!(
            slcan_frames("t1008F401000003000000\rt2001AA\r").unwrap(),
            ["100#F401000003000000", "200#AA"]
        );
        assert!(slcan_frames("x123\r").is_err());
        assert_eq!(candump_frames("(1.0) can0 100#AA\n").unwrap(), ["100#AA"]);
        let leds = fpgaio_transitions(
            "mps2_fpgaio_write MPS2 FPGAIO write: offset 0x0 data 0x0 size 4\n\
             mps2_fpgaio_write MPS2 FPGAIO write: offset 0x0 data 0x1 size 4\n\
             mps2_fpgaio_write MPS2 FPGAIO write: offset 0x0 data 0x3 size 4\n",
        )
        .unwrap();
        assert_eq!(leds, [vec![false, true], vec![false, true]]);
        let csv = csv_transitions("h\n10,1,1,Red,1,0,d\n20,1,1,Red,1,1,d\n").unwrap();
        assert_eq!(csv, [vec![false, true], vec![false, true]]);
    }
}
