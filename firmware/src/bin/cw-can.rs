//! `cw-can`: read the ECU's CAN traffic back with a DBC, or build a frame for it (the
//! engineer's PC of paper §4.4; what `python -m cantools decode` does).
//!
//! ```text
//! cw-can decode --dbc firmware/ecu.dbc can.log      # or - for standard input
//! cw-can encode --dbc firmware/ecu.dbc ThresholdConfig RedBelow=500 YellowBelow=1000
//! ```

use std::io::{BufRead, Write};
use std::process::ExitCode;

use cw_firmware::host::cantool::{decode, encode, format_frame, load_dbc, parse_log_line};

const HELP: &str = "\
cw-can: decode a candump log with a DBC, or encode signal values into a frame.

USAGE:
  cw-can decode --dbc FILE LOG      LOG is a candump log file, or - for standard input
  cw-can encode --dbc FILE MESSAGE SIGNAL=VALUE...
";

fn run(args: &[String]) -> Result<(), String> {
    let (command, rest) = args
        .split_first()
        .ok_or("a command is needed (see --help)")?;
    if command == "--help" || command == "-h" {
        print!("{HELP}");
        return Ok(());
    }
    let (flag, rest) = rest.split_first().ok_or("--dbc FILE is needed")?;
    if flag != "--dbc" {
        return Err(format!("expected --dbc FILE, found `{flag}`"));
    }
    let (dbc_path, rest) = rest.split_first().ok_or("--dbc needs a file")?;
    let text =
        std::fs::read_to_string(dbc_path).map_err(|e| format!("cannot read {dbc_path}: {e}"))?;
    let dbc = load_dbc(&text).map_err(|e| format!("{dbc_path}: {e}"))?;
    let mut out = std::io::stdout().lock();
    match command.as_str() {
        "decode" => {
            let [log] = rest else {
                return Err("decode takes one log file (or -)".into());
            };
            let reader: Box<dyn BufRead> = if log == "-" {
                Box::new(std::io::stdin().lock())
            } else {
                Box::new(std::io::BufReader::new(
                    std::fs::File::open(log).map_err(|e| format!("cannot read {log}: {e}"))?,
                ))
            };
            for (n, line) in reader.lines().enumerate() {
                let line = line.map_err(|e| format!("{log}: {e}"))?;
                if line.trim().is_empty() {
                    continue;
                }
                let entry =
                    parse_log_line(&line).map_err(|e| format!("{log}: line {}: {e}", n + 1))?;
                let text = match decode(&dbc, &entry.frame)? {
                    None => format!(
                        "({:.6}) {} {} (not in the DBC)",
                        entry.timestamp,
                        entry.interface,
                        format_frame(&entry.frame)
                    ),
                    Some((message, signals)) => {
                        let values: Vec<String> = signals
                            .iter()
                            .map(|s| match &s.label {
                                Some(label) => format!("{}: {label}", s.name),
                                None if s.unit.is_empty() => format!("{}: {}", s.name, s.physical),
                                None => format!("{}: {} {}", s.name, s.physical, s.unit),
                            })
                            .collect();
                        format!(
                            "({:.6}) {} {} {}({})",
                            entry.timestamp,
                            entry.interface,
                            format_frame(&entry.frame),
                            message.name,
                            values.join(", ")
                        )
                    }
                };
                writeln!(out, "{text}").map_err(|e| format!("stdout: {e}"))?;
            }
            Ok(())
        }
        "encode" => {
            let (message, pairs) = rest.split_first().ok_or("encode needs a message name")?;
            let values = pairs
                .iter()
                .map(|p| {
                    let (name, value) = p
                        .split_once('=')
                        .ok_or_else(|| format!("`{p}` is not SIGNAL=VALUE"))?;
                    let v: f64 = value
                        .parse()
                        .map_err(|_| format!("`{value}` is not a number"))?;
                    Ok((name.to_string(), v))
                })
                .collect::<Result<Vec<_>, String>>()?;
            let frame = encode(&dbc, message, &values)?;
            writeln!(out, "{}", format_frame(&frame)).map_err(|e| format!("stdout: {e}"))
        }
        other => Err(format!("unknown command `{other}` (see --help)")),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("cw-can: {e}");
            ExitCode::FAILURE
        }
    }
}
