//! Decoded frames as an engineer reads or scripts them: a text line per frame (candump's
//! line, then the message and its signals), a JSON object per frame, or a CSV row per
//! signal.

use std::fmt::Write as _;

use serde::Serialize;

use crate::codec::{self, Decoded, Physical, Raw};
use crate::dbc::Database;
use crate::frame::FrameKind;
use crate::log::Entry;

/// Output form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// `(SECONDS) CHANNEL FRAME Message(Signal: value unit, ...)`.
    Text,
    /// One JSON object per frame, one per line (JSON Lines).
    Json,
    /// One row per decoded signal (a frame no message describes: one row, no signal).
    Csv,
}

/// A frame decoded with the DBC.
pub struct Report<'a> {
    /// The log entry.
    pub entry: &'a Entry,
    /// The message and its present signals, when the DBC knows the frame's id and it is a
    /// data frame.
    pub message: Option<(&'a str, Vec<Decoded<'a>>)>,
    /// Bytes beyond the message's size (decoded without them, as cantools does).
    pub excess: usize,
}

/// Decodes one entry with the database.
///
/// # Errors
/// A frame shorter than its message.
pub fn decode<'a>(db: &'a Database, entry: &'a Entry) -> Result<Report<'a>, codec::DecodeError> {
    let frame = &entry.frame;
    let message = frame
        .is_data()
        .then(|| db.by_id(frame.id, frame.extended))
        .flatten();
    match message {
        None => Ok(Report {
            entry,
            message: None,
            excess: 0,
        }),
        Some(m) => Ok(Report {
            entry,
            message: Some((m.name.as_str(), codec::decode(m, &frame.data)?)),
            excess: codec::excess(m, &frame.data),
        }),
    }
}

#[derive(Serialize)]
#[serde(untagged)]
enum Number {
    Int(i128),
    Float(f64),
}

#[derive(Serialize)]
struct JsonSignal<'a> {
    name: &'a str,
    raw: Number,
    value: Number,
    unit: &'a str,
    choice: Option<&'a str>,
}

#[derive(Serialize)]
struct JsonFrame<'a> {
    timestamp: f64,
    channel: &'a str,
    id: u32,
    extended: bool,
    kind: &'a str,
    brs: bool,
    esi: bool,
    dlc: Option<u8>,
    data: String,
    message: Option<&'a str>,
    signals: Vec<JsonSignal<'a>>,
    excess_bytes: usize,
}

/// Upper-case hex of bytes, no separators (`DEADBEEF`).
pub fn hex(data: &[u8]) -> String {
    data.iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02X}");
        s
    })
}

fn raw_number(raw: Raw) -> Number {
    match raw {
        Raw::Int(v) => Number::Int(v),
        Raw::Float(v) => Number::Float(v),
    }
}

fn physical_number(p: Physical) -> Number {
    match p {
        Physical::Int(v) => Number::Int(v),
        Physical::Float(v) => Number::Float(v),
    }
}

/// The CSV header for [`Format::Csv`].
pub const CSV_HEADER: &str =
    "timestamp,channel,id,extended,kind,data,message,signal,raw,value,unit,choice";

fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

impl Report<'_> {
    /// The report in `format` (for CSV, one line per signal, without the header).
    pub fn render(&self, format: Format) -> String {
        let e = self.entry;
        let f = &e.frame;
        match format {
            Format::Text => {
                let mut line = format!("({:.6}) {} {}", e.timestamp, e.channel, f);
                match (&self.message, f.kind) {
                    (_, FrameKind::Remote) => line.push_str(" (remote frame)"),
                    (_, FrameKind::Error) => line.push_str(" (error frame)"),
                    (None, _) => line.push_str(" (not in the DBC)"),
                    (Some((name, signals)), _) => {
                        let values: Vec<String> = signals
                            .iter()
                            .map(|d| match (d.choice, d.signal.unit.as_str()) {
                                (Some(c), _) => format!("{}: {c}", d.signal.name),
                                (None, "") => format!("{}: {}", d.signal.name, d.physical),
                                (None, unit) => format!("{}: {} {unit}", d.signal.name, d.physical),
                            })
                            .collect();
                        let _ = write!(line, " {name}({})", values.join(", "));
                        if self.excess > 0 {
                            let _ = write!(line, " [{} bytes beyond the message]", self.excess);
                        }
                    }
                }
                line
            }
            Format::Json => {
                let (brs, esi) = match f.kind {
                    FrameKind::Fd { brs, esi } => (brs, esi),
                    _ => (false, false),
                };
                let frame = JsonFrame {
                    timestamp: e.timestamp,
                    channel: &e.channel,
                    id: f.id,
                    extended: f.extended,
                    kind: f.kind.name(),
                    brs,
                    esi,
                    dlc: f.dlc,
                    data: hex(&f.data),
                    message: self.message.as_ref().map(|(n, _)| *n),
                    signals: self
                        .message
                        .iter()
                        .flat_map(|(_, s)| s)
                        .map(|d| JsonSignal {
                            name: &d.signal.name,
                            raw: raw_number(d.raw),
                            value: physical_number(d.physical),
                            unit: &d.signal.unit,
                            choice: d.choice,
                        })
                        .collect(),
                    excess_bytes: self.excess,
                };
                // Serialising these plain fields cannot fail; a failure would be a bug
                // worth seeing, so it is written into the output rather than hidden.
                serde_json::to_string(&frame)
                    .unwrap_or_else(|err| format!("{{\"error\":\"{err}\"}}"))
            }
            Format::Csv => {
                let head = format!(
                    "{:.6},{},{},{},{},{}",
                    e.timestamp,
                    csv_field(&e.channel),
                    f.id,
                    f.extended,
                    f.kind.name(),
                    hex(&f.data)
                );
                match &self.message {
                    Some((name, signals)) if !signals.is_empty() => signals
                        .iter()
                        .map(|d| {
                            format!(
                                "{head},{},{},{},{},{},{}",
                                csv_field(name),
                                csv_field(&d.signal.name),
                                d.raw,
                                d.physical,
                                csv_field(&d.signal.unit),
                                csv_field(d.choice.unwrap_or(""))
                            )
                        })
                        .collect::<Vec<_>>()
                        .join("\n"),
                    Some((name, _)) => format!("{head},{},,,,,", csv_field(name)),
                    None => format!("{head},,,,,,"),
                }
            }
        }
    }
}
