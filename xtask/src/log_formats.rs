//! `cargo xtask log-formats`: random frames (classic, FD with its flags, 11- and 29-bit
//! ids, remote and error frames, on four channels) written by python-can's ASC, BLF and
//! candump writers (`tools/log_formats.py`), read back by python-can's readers and by
//! `cw-can`'s: both readings must be the same frames with the same time stamps, bit for
//! bit, and the frames those the writers were given.

use crate::process::target_dir;
use crate::rng::Rng;
use crate::Result;
use cw_can::frame::{FrameKind, FD_LENGTHS};
use cw_can::log::{open, Entry, LogFormat};
use cw_can::report::hex;

/// How many disagreements to print in full.
const SHOW: usize = 5;

/// The default `--frames`.
const FRAMES: usize = 3_000;

/// Options of `cargo xtask log-formats`.
#[derive(clap::Args)]
pub struct Options {
    /// Frames written
    #[arg(long, default_value_t = FRAMES)]
    pub frames: usize,
    #[command(flatten)]
    pub seed: crate::rng::Seed,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            frames: FRAMES,
            seed: crate::rng::Seed::default(),
        }
    }
}

/// One written frame, in python-can's terms.
#[derive(Clone, PartialEq, Debug)]
struct Written {
    timestamp: f64,
    channel: i64,
    id: u32,
    extended: bool,
    kind: &'static str,
    brs: bool,
    esi: bool,
    dlc: u8,
    data: Vec<u8>,
}

fn unhex(text: &str) -> Vec<u8> {
    (0..text.len() / 2)
        .filter_map(|i| u8::from_str_radix(text.get(2 * i..2 * i + 2)?, 16).ok())
        .collect()
}

fn generate(rng: &mut Rng, n: usize) -> Vec<Written> {
    // Whole microseconds, as candump writes them.
    let mut micros: u64 = 1_700_000_000_000_000 + rng.below(1_000_000_000);
    (0..n)
        .map(|_| {
            micros += 1 + rng.below(20_000);
            let extended = rng.one_in(3);
            let id = if extended {
                rng.below(1 << 29) as u32
            } else {
                rng.below(0x800) as u32
            };
            let kind = match rng.below(10) {
                0 => "remote",
                1 => "error",
                2..=4 => "fd",
                _ => "classic",
            };
            let len = match kind {
                "fd" => rng.pick(&FD_LENGTHS, 8),
                "classic" => rng.below(9) as usize,
                _ => 0,
            };
            let mut data = vec![0u8; len];
            rng.fill(&mut data);
            Written {
                timestamp: micros as f64 / 1e6,
                channel: rng.below(4) as i64,
                id: if kind == "error" { 0 } else { id },
                extended: extended && kind != "error",
                kind,
                brs: kind == "fd" && rng.one_in(2),
                esi: kind == "fd" && rng.one_in(2),
                dlc: if kind == "remote" {
                    rng.below(9) as u8
                } else {
                    0
                },
                data,
            }
        })
        .collect()
}

/// `cw-can`'s entry in python-can's terms; the channel as python-can numbers it.
fn as_written(e: &Entry, format: LogFormat) -> Written {
    let f = &e.frame;
    let (brs, esi) = match f.kind {
        FrameKind::Fd { brs, esi } => (brs, esi),
        _ => (false, false),
    };
    let channel = match format {
        // candump: `canN` is python-can's channel N.
        LogFormat::Candump => e
            .channel
            .strip_prefix("can")
            .and_then(|n| n.parse().ok())
            .unwrap_or(-1),
        // Vector numbers channels from 1, python-can from 0.
        LogFormat::Asc | LogFormat::Blf => e.channel.parse::<i64>().map_or(-1, |c| c - 1),
    };
    Written {
        timestamp: e.timestamp,
        channel,
        id: f.id,
        extended: f.extended,
        kind: f.kind.name(),
        brs,
        esi,
        dlc: f.dlc.unwrap_or(0),
        data: f.data.clone(),
    }
}

/// Whether two readings of one frame agree in what the format keeps: every field, but
/// for an error frame only its time stamp and channel (python-can's readers give error
/// frames different ids and flags per format), and for a remote frame no data (BLF
/// stores zeros).
fn same(a: &Written, b: &Written, channel_kept: bool) -> bool {
    let base = a.timestamp.to_bits() == b.timestamp.to_bits()
        && a.kind == b.kind
        && (!channel_kept || a.channel == b.channel);
    match a.kind {
        "error" => base,
        "remote" => base && a.id == b.id && a.extended == b.extended,
        _ => {
            base && a.id == b.id
                && a.extended == b.extended
                && a.brs == b.brs
                && a.esi == b.esi
                && a.data == b.data
        }
    }
}

/// Writes, reads back with both, compares.
pub fn run(options: &Options) -> Result {
    let seed = options.seed.or_fresh();
    println!("log-formats: seed {seed} (replay with --seed {seed})");
    let mut rng = Rng::new(seed);
    let frames = generate(&mut rng, options.frames);
    let dir = target_dir().join("xtask-log-formats");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let mut text = String::new();
    for f in &frames {
        let obj = serde_json::json!({
            "timestamp": f.timestamp, "channel": f.channel, "id": f.id,
            "extended": f.extended, "kind": f.kind, "brs": f.brs, "esi": f.esi,
            "dlc": f.dlc, "data": hex(&f.data),
        });
        text.push_str(&obj.to_string());
        text.push('\n');
    }
    let frames_path = dir.join("frames.jsonl");
    std::fs::write(&frames_path, text)
        .map_err(|e| format!("writing {}: {e}", frames_path.display()))?;
    crate::setup::run_python_tool("log_formats.py", &[&frames_path, &dir])?;
    let mut problems = Vec::new();
    let mut python_can_asc_quirks = 0;
    for (ext, format) in [
        ("log", LogFormat::Candump),
        ("asc", LogFormat::Asc),
        ("blf", LogFormat::Blf),
    ] {
        let theirs_path = dir.join(format!("{ext}.jsonl"));
        let theirs_text = std::fs::read_to_string(&theirs_path)
            .map_err(|e| format!("reading {}: {e}", theirs_path.display()))?;
        let mut theirs = Vec::new();
        for (n, line) in theirs_text.lines().enumerate() {
            let v: serde_json::Value = serde_json::from_str(line)
                .map_err(|e| format!("{}:{}: {e}", theirs_path.display(), n + 1))?;
            let kind = match v["kind"].as_str() {
                Some("fd") => "fd",
                Some("remote") => "remote",
                Some("error") => "error",
                _ => "classic",
            };
            theirs.push(Written {
                timestamp: v["timestamp"]
                    .as_str()
                    .and_then(|t| t.parse().ok())
                    .unwrap_or(f64::NAN),
                // python-can's channel: a number (ASC, BLF) or the interface (`can1`).
                channel: v["channel"].as_i64().unwrap_or_else(|| {
                    v["channel"]
                        .as_str()
                        .and_then(|c| c.strip_prefix("can"))
                        .and_then(|n| n.parse().ok())
                        .unwrap_or(-1)
                }),
                id: v["id"].as_u64().map_or(u32::MAX, |i| i as u32),
                extended: v["extended"].as_bool().unwrap_or(false),
                kind,
                brs: v["brs"].as_bool().unwrap_or(false),
                esi: v["esi"].as_bool().unwrap_or(false),
                dlc: v["dlc"].as_u64().map_or(0, |d| d as u8),
                data: unhex(v["data"].as_str().unwrap_or("")),
            });
        }
        let path = dir.join(format!("frames.{ext}"));
        let mut ours = Vec::new();
        for item in open(&path, None)? {
            match item {
                Ok((_, e)) => ours.push(as_written(&e, format)),
                Err(e) => problems.push(format!("{ext}: cw-can: {}:{e}", path.display())),
            }
        }
        if ours.len() != theirs.len() || ours.len() != frames.len() {
            problems.push(format!(
                "{ext}: {} frames written, python-can read {}, cw-can {}",
                frames.len(),
                theirs.len(),
                ours.len()
            ));
        }
        // python-can's candump reader gives an error frame no channel.
        let channel_kept = |w: &Written| format != LogFormat::Candump || w.kind != "error";
        for (i, ((o, t), w)) in ours.iter().zip(&theirs).zip(&frames).enumerate() {
            // python-can's ASC reader takes an FD frame without data for a remote
            // frame (its rule: data length 0); cw-can reads the line's FD flag.
            let quirk = format == LogFormat::Asc
                && t.kind == "remote"
                && o.kind == "fd"
                && o.data.is_empty();
            if quirk {
                python_can_asc_quirks += 1;
            } else if !same(o, t, channel_kept(t)) {
                problems.push(format!("{ext} frame {i}: cw-can {o:?}\n  python-can {t:?}"));
            }
            // Against what was written: ASC keeps time from the first frame.
            let mut written = w.clone();
            if format == LogFormat::Asc {
                written.timestamp = t.timestamp;
            }
            if format == LogFormat::Blf {
                // BLF keeps the start to the millisecond and the rest in nanoseconds.
                written.timestamp = o.timestamp;
                if (o.timestamp - w.timestamp).abs() > 2e-6 {
                    problems.push(format!(
                        "{ext} frame {i}: time {} written, {} read",
                        w.timestamp, o.timestamp
                    ));
                }
            }
            if !same(o, &written, channel_kept(t)) {
                problems.push(format!(
                    "{ext} frame {i}: cw-can {o:?}\n  written {written:?}"
                ));
            }
        }
    }
    println!(
        "log-formats: {} frames written by python-can as candump, ASC and BLF; read back by cw-can as written and as python-can reads them: {} disagreements ({python_can_asc_quirks} FD frames without data that python-can's ASC reader takes for remote frames)",
        frames.len(),
        problems.len()
    );
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} disagreements (seed {seed}); the first {}:\n{}",
            problems.len(),
            SHOW.min(problems.len()),
            problems
                .iter()
                .take(SHOW)
                .cloned()
                .collect::<Vec<_>>()
                .join("\n")
        ))
    }
}
