//! `cargo xtask decode-speed [--frames N]`: `cw-can decode` and `cantools decode
//! --single-line` (the same one line per frame) side by side on one large candump log, in one run: wall time of each whole command (start,
//! DBC load, reading, decoding, writing the text to a file), frames per second, and the
//! ratio.
//!
//! The log holds `N` frames (default 200,000) of `cantool/tests/data/features.dbc`'s
//! messages with random data: plain integer signals with factors and value tables, a
//! 64-bit raw value, IEEE float and double, a 64-byte FD message, simple and extended
//! multiplexing (with multiplexer values that select signals, so that neither tool
//! refuses a frame). `cw-can` is the release build.

use crate::process::{root, target_dir, Cmd};
use crate::rng::Rng;
use crate::setup::venv_python;
use crate::Result;
use std::fmt::Write as _;
use std::time::Instant;

/// Options of `cargo xtask decode-speed`.
#[derive(clap::Args)]
pub struct Options {
    /// Frames in the log
    #[arg(long, default_value_t = 200_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: u64,
}

/// The log: every message of features.dbc in turn, random bytes, multiplexers set.
fn log(n: usize) -> String {
    let mut rng = Rng::new(2026);
    let mut out = String::new();
    for i in 0..n {
        let (id, fd, len) = match i % 6 {
            0 => ("100", false, 8),
            1 => ("18FF0001", false, 8),
            2 => ("200", true, 12),
            3 => ("300", true, 64),
            4 => ("400", false, 8),
            _ => ("500", false, 8),
        };
        let mut data = vec![0u8; len];
        rng.fill(&mut data);
        match id {
            "400" => data[0] = (rng.below(2)) as u8,
            "500" => {
                data[0] = rng.pick(&[1u8, 3, 4, 5, 7], 1);
                data[1] = 2;
            }
            _ => {}
        }
        let hex = data.iter().fold(String::new(), |mut s, b| {
            let _ = write!(s, "{b:02X}");
            s
        });
        let sep = if fd { "##1" } else { "#" };
        let _ = writeln!(
            out,
            "({}.{:06}) can0 {id}{sep}{hex}",
            1_700_000_000 + i / 1000,
            (i % 1000) * 1000
        );
    }
    out
}

fn timed(
    mut cmd: std::process::Command,
    stdin: &std::path::Path,
    stdout: &std::path::Path,
) -> Result<f64> {
    let input = std::fs::File::open(stdin).map_err(|e| format!("{}: {e}", stdin.display()))?;
    let output = std::fs::File::create(stdout).map_err(|e| format!("{}: {e}", stdout.display()))?;
    let started = Instant::now();
    let status = cmd
        .stdin(input)
        .stdout(output)
        .status()
        .map_err(|e| format!("running {cmd:?}: {e}"))?;
    let seconds = started.elapsed().as_secs_f64();
    if !status.success() {
        return Err(format!("{cmd:?} failed: {status}"));
    }
    Ok(seconds)
}

/// Builds `cw-can` (release), writes the log, times both tools on it.
pub fn run(options: &Options) -> Result {
    Cmd::new("cargo")
        .args(["build", "--release", "-q", "-p", "cw-can"])
        .run()?;
    let dir = target_dir().join("xtask-decode-speed");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let log_path = dir.join("big.log");
    std::fs::write(&log_path, log(options.frames as usize))
        .map_err(|e| format!("writing {}: {e}", log_path.display()))?;
    let dbc = root().join("cantool/tests/data/features.dbc");
    let mut ours = std::process::Command::new(target_dir().join("release").join("cw-can"));
    ours.args(["decode", "--dbc"]).arg(&dbc).arg("-");
    let mut theirs = std::process::Command::new(venv_python());
    theirs
        .args(["-m", "cantools", "decode", "--single-line"])
        .arg(&dbc);
    println!(
        "$ cw-can decode --dbc {} - < {}",
        dbc.display(),
        log_path.display()
    );
    let t_ours = timed(ours, &log_path, &dir.join("cw-can.txt"))?;
    println!(
        "$ python -m cantools decode --single-line {} < {}",
        dbc.display(),
        log_path.display()
    );
    let t_theirs = timed(theirs, &log_path, &dir.join("cantools.txt"))?;
    let n = options.frames as f64;
    println!(
        "decode-speed: {} frames: cw-can {t_ours:.2} s ({:.0} frames/s), cantools {t_theirs:.2} s ({:.0} frames/s): cw-can {:.1}x faster",
        options.frames,
        n / t_ours,
        n / t_theirs,
        t_theirs / t_ours
    );
    Ok(())
}
