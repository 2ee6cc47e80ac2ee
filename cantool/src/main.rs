//! `cw-can`: read CAN logs back with a DBC, or build a frame from signal values (the
//! engineer's PC of paper §4.4; what `python -m cantools decode` and `encode` do).
//!
//! ```text
//! cw-can decode --dbc firmware/ecu.dbc can.log            # or - for standard input
//! cw-can decode --dbc firmware/ecu.dbc --format json can.log
//! cw-can encode --dbc firmware/ecu.dbc ThresholdConfig RedBelow=500 YellowBelow=1000
//! cw-can view --dbc firmware/ecu.dbc --replay can.log           # http://127.0.0.1:8080/
//! cw-can view --dbc firmware/ecu.dbc --simulate scenarios/figure7.txt
//! cw-can view --dbc firmware/ecu.dbc --slcan socket://127.0.0.1:5555
//! ```
//!
//! Exit status: 0 when every line was read and decoded; 1 when some line was not (each
//! reported on standard error as `FILE:LINE: what is wrong`, the others still decoded;
//! `--strict` stops at the first); 2 when nothing could be done (usage, an unreadable or
//! refused DBC, an unreadable log, a value that cannot be encoded).

#![forbid(unsafe_code)]
// Input from outside (a DBC, a log line, a value typed by the engineer) is an error value
// with its line, never a panic.
#![cfg_attr(
    not(test),
    warn(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use cw_can::codec::{self, Input};
use cw_can::dbc::{Database, Strictness};
use cw_can::log::{Entries, LogFormat};
use cw_can::report::{self, Format};
use cw_can::slcan::{Limits, SlcanSource};
use cw_can::view::feed::Control;
use cw_can::view::live;
use cw_can::view::server::View;
use cw_firmware::host::Scenario;
use std::sync::{Arc, Mutex};

/// Decode CAN logs with a DBC, or encode signal values into a frame.
#[derive(Parser)]
#[command(name = "cw-can", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Decode CAN logs (candump, ASC, BLF): every frame, with its message and signals.
    Decode {
        #[command(flatten)]
        dbc: DbcArgs,
        /// Stop at the first bad line instead of reporting it and going on.
        #[arg(long)]
        strict: bool,
        /// Output form.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// The logs' format [default: by extension: .asc ASC, .blf BLF, else candump].
        #[arg(long, value_enum)]
        log_format: Option<LogFormat>,
        #[command(flatten)]
        adapter: Adapter,
        /// With `--slcan`: stop after this many frames.
        #[arg(long, value_name = "N")]
        frames: Option<usize>,
        /// With `--slcan`: stop after this many seconds.
        #[arg(long, value_name = "S")]
        seconds: Option<f64>,
        /// Log files, or - for standard input.
        #[arg(required_unless_present = "slcan", conflicts_with = "slcan")]
        logs: Vec<PathBuf>,
    },
    /// Serve the view of the bus (paper Figure 8) as a local web page: the scene from above
    /// and from the side, the ECU's LEDs, the distance and the level, a chart, from the
    /// `DistanceFrame`s alone; and a panel that sends `ThresholdConfig` to a live bus.
    #[command(group(clap::ArgGroup::new("source").required(true).args(["replay", "simulate", "slcan"])))]
    View {
        #[command(flatten)]
        dbc: DbcArgs,
        /// Replay a log (candump, ASC, BLF), with play, pause, speed and seek on the page.
        #[arg(long, value_name = "LOG")]
        replay: Option<PathBuf>,
        /// Run the ECU's host simulation of a scenario file live, in real time, with the
        /// PC on its bus.
        #[arg(long, value_name = "SCENARIO")]
        simulate: Option<PathBuf>,
        /// The simulated sensor's noise seed (`--simulate`).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[command(flatten)]
        adapter: Adapter,
        /// The log's format [default: by extension: .asc ASC, .blf BLF, else candump].
        #[arg(long, value_enum, requires = "replay")]
        log_format: Option<LogFormat>,
        /// Where to listen; port 0 takes a free one. The page's address is printed.
        #[arg(long, default_value = "127.0.0.1:8080", value_name = "ADDR:PORT")]
        listen: String,
        /// The replay's speed, log seconds per second (0.05 to 1000).
        #[arg(long, default_value_t = 1.0, requires = "replay")]
        speed: f64,
        /// Start the replay paused (the page's Play starts it).
        #[arg(long, requires = "replay")]
        paused: bool,
    },
    /// Encode signal values into a frame of a message, printed as `ID#DATA`.
    Encode {
        #[command(flatten)]
        dbc: DbcArgs,
        /// The message's name.
        message: String,
        /// `SIGNAL=VALUE`: a number or a name from the signal's value table.
        values: Vec<String>,
    },
}

/// The DBC and how strictly it is read.
#[derive(clap::Args)]
struct DbcArgs {
    /// The DBC file (UTF-8 or Windows-1252).
    #[arg(long)]
    dbc: PathBuf,
    /// Keep messages whose signals share bits or lie beyond the message, as cantools'
    /// `--no-strict` does: each is a warning, and only a frame that carries such signals
    /// together is refused.
    #[arg(long)]
    no_strict: bool,
}

/// A live bus through an SLCAN adapter (`decode` and `view`).
#[derive(clap::Args)]
struct Adapter {
    /// Read a live bus from an SLCAN adapter: a serial device (`/dev/ttyACM0`) or
    /// `socket://HOST:PORT` (the QEMU image's UART), as python-can names them.
    #[arg(long, value_name = "PORT")]
    slcan: Option<String>,
    /// The serial device's baud rate (`--slcan` on a device).
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Set the adapter's CAN bit rate first: SLCAN's index, 0 (10 kbit/s) to 8
    /// (1 Mbit/s); 6 is 500 kbit/s.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=8))]
    bitrate: Option<u8>,
}

/// Something that stops the run (exit status 2).
struct Fatal(String);

/// Loads the DBC; lenient, each fault it keeps is a warning on standard error.
fn load(args: &DbcArgs) -> Result<Database, Fatal> {
    let strictness = if args.no_strict {
        Strictness::Lenient
    } else {
        Strictness::Strict
    };
    let db = Database::load_with(&args.dbc, strictness).map_err(Fatal)?;
    for warning in db.warnings() {
        eprintln!("cw-can: warning: {}: {warning}", args.dbc.display());
    }
    Ok(db)
}

fn out_err(e: std::io::Error) -> Fatal {
    Fatal(format!("standard output: {e}"))
}

/// Where `decode` reads frames from.
enum Source<'a> {
    Logs(&'a [PathBuf], Option<LogFormat>),
    Slcan {
        port: &'a str,
        baud: u32,
        bitrate: Option<u8>,
        limits: Limits,
    },
}

/// Decodes every log; returns how many lines were bad.
fn decode(dbc: &DbcArgs, strict: bool, format: Format, source: Source<'_>) -> Result<usize, Fatal> {
    let db = load(dbc)?;
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    if format == Format::Csv {
        writeln!(out, "{}", report::CSV_HEADER).map_err(out_err)?;
    }
    let live = matches!(source, Source::Slcan { .. });
    let inputs: Vec<(String, Entries)> = match source {
        Source::Logs(logs, log_format) => logs
            .iter()
            .map(|log| {
                let name = log.display().to_string();
                cw_can::log::open(log, log_format)
                    .map(|entries| (name, entries))
                    .map_err(Fatal)
            })
            .collect::<Result<_, _>>()?,
        Source::Slcan {
            port,
            baud,
            bitrate,
            limits,
        } => {
            let live = SlcanSource::open(port, baud, bitrate, limits).map_err(Fatal)?;
            vec![(port.to_string(), Box::new(live) as Entries)]
        }
    };
    let mut bad = 0;
    for (name, entries) in inputs {
        for item in entries {
            let problem = match &item {
                Err(e) => Some(format!("{name}:{e}")),
                Ok((at, entry)) => match report::decode(&db, entry) {
                    Ok(r) => {
                        writeln!(out, "{}", r.render(format)).map_err(out_err)?;
                        if live {
                            out.flush().map_err(out_err)?;
                        }
                        None
                    }
                    Err(e) => Some(format!("{name}:{at}: {}: {e}", entry.frame)),
                },
            };
            if let Some(problem) = problem {
                bad += 1;
                out.flush().map_err(out_err)?;
                eprintln!("cw-can: {problem}");
                if strict {
                    return Ok(bad);
                }
            }
        }
    }
    out.flush().map_err(out_err)?;
    Ok(bad)
}

fn encode(dbc: &DbcArgs, message: &str, values: &[String]) -> Result<(), Fatal> {
    let db = load(dbc)?;
    let m = db
        .by_name(message)
        .ok_or_else(|| Fatal(format!("no message `{message}` in {}", dbc.dbc.display())))?;
    let values = values
        .iter()
        .map(|p| {
            let (name, value) = p
                .split_once('=')
                .ok_or_else(|| Fatal(format!("`{p}` is not SIGNAL=VALUE")))?;
            let value = Input::parse(value).map_err(|e| Fatal(format!("{name}: {e}")))?;
            Ok((name.to_string(), value))
        })
        .collect::<Result<Vec<_>, Fatal>>()?;
    let frame = codec::encode_frame(m, &values).map_err(Fatal)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{frame}").map_err(out_err)
}

/// Where the view's frames come from.
enum ViewSource<'a> {
    Replay {
        log: &'a Path,
        format: Option<LogFormat>,
        speed: f64,
        paused: bool,
    },
    Simulate {
        scenario: &'a Path,
        seed: u64,
    },
    Slcan {
        port: &'a str,
        baud: u32,
        bitrate: Option<u8>,
    },
}

/// Serves the view until the process ends.
fn view(dbc: &DbcArgs, source: ViewSource<'_>, listen: &str) -> Result<(), Fatal> {
    let db = load(dbc)?;
    let (feed, what) = match source {
        ViewSource::Replay {
            log,
            format,
            speed,
            paused,
        } => {
            let mut feed = cw_can::view::replay(&db, log, format).map_err(Fatal)?;
            feed.control(Control {
                play: Some(!paused),
                speed: Some(speed),
                seek: None,
            })
            .map_err(Fatal)?;
            (
                Arc::new(Mutex::new(feed)),
                format!("replay of {}", log.display()),
            )
        }
        ViewSource::Simulate { scenario, seed } => {
            let text = std::fs::read_to_string(scenario)
                .map_err(|e| Fatal(format!("cannot read scenario {}: {e}", scenario.display())))?;
            let parsed = Scenario::parse(&text)
                .map_err(|e| Fatal(format!("scenario {}: {e}", scenario.display())))?;
            let name = scenario.display().to_string();
            let feed = live::simulation(&db, parsed, seed, &name).map_err(Fatal)?;
            (feed, format!("the host simulation of {name}, live"))
        }
        ViewSource::Slcan {
            port,
            baud,
            bitrate,
        } => {
            let feed = live::slcan(&db, port, baud, bitrate).map_err(Fatal)?;
            (feed, format!("SLCAN adapter {port}, live"))
        }
    };
    let config = db.by_name("ThresholdConfig").cloned();
    let view = View::bind(listen, feed, config).map_err(Fatal)?;
    let addr = view.addr().map_err(Fatal)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "cw-can view: http://{addr}/ ({what})")
        .and_then(|()| out.flush())
        .map_err(out_err)?;
    drop(out);
    view.run().map_err(Fatal)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Decode {
            dbc,
            strict,
            format,
            log_format,
            adapter:
                Adapter {
                    slcan,
                    baud,
                    bitrate,
                },
            frames,
            seconds,
            logs,
        } => {
            let source = match slcan {
                Some(port) => Source::Slcan {
                    port,
                    baud: *baud,
                    bitrate: *bitrate,
                    limits: Limits {
                        frames: *frames,
                        duration: seconds
                            .filter(|s| s.is_finite() && *s >= 0.0)
                            .map(std::time::Duration::from_secs_f64),
                    },
                },
                None => Source::Logs(logs, *log_format),
            };
            decode(dbc, *strict, *format, source)
        }
        Command::View {
            dbc,
            replay,
            simulate,
            seed,
            adapter:
                Adapter {
                    slcan,
                    baud,
                    bitrate,
                },
            log_format,
            listen,
            speed,
            paused,
        } => {
            let source = match (replay, simulate, slcan) {
                (Some(log), _, _) => Some(ViewSource::Replay {
                    log,
                    format: *log_format,
                    speed: *speed,
                    paused: *paused,
                }),
                (_, Some(scenario), _) => Some(ViewSource::Simulate {
                    scenario,
                    seed: *seed,
                }),
                (_, _, Some(port)) => Some(ViewSource::Slcan {
                    port,
                    baud: *baud,
                    bitrate: *bitrate,
                }),
                // clap requires one of the three.
                (None, None, None) => None,
            };
            match source {
                Some(source) => view(dbc, source, listen).map(|()| 0),
                None => Err(Fatal("give --replay, --simulate or --slcan".into())),
            }
        }
        Command::Encode {
            dbc,
            message,
            values,
        } => encode(dbc, message, values).map(|()| 0),
    };
    match result {
        Ok(0) => ExitCode::SUCCESS,
        Ok(bad) => {
            eprintln!("cw-can: {bad} bad line(s)");
            ExitCode::from(1)
        }
        Err(Fatal(e)) => {
            eprintln!("cw-can: {e}");
            ExitCode::from(2)
        }
    }
}
