//! CAN logs, read line by line: a bad line is an error naming its line number, and the
//! lines after it are still read.
//!
//! candump's log form (`candump -L`, what `canplayer` replays and python-can's
//! `CanutilsLogReader` reads): `(SECONDS) CHANNEL FRAME`, the frame in can-utils' compact
//! form ([`crate::frame`]), and the direction `R` or `T` that python-can's writer adds.

use std::fmt;
use std::io::{BufRead, Read};
use std::path::Path;

use crate::frame::{self, Frame};

/// One frame of a log, with when and where it was seen.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Entry {
    /// Seconds (since the epoch, for a live capture).
    pub timestamp: f64,
    /// The interface (`can0`, `vcan0`, `slcan0`).
    pub channel: String,
    /// The frame.
    pub frame: Frame,
}

/// Where in a log something is wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum At {
    /// A text log's line (1-based).
    Line(usize),
    /// A binary log's byte offset.
    Byte(u64),
}

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Line(n) => write!(f, "{n}"),
            Self::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

/// Why a line (or an object of a binary log) is not a log entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineError {
    /// Where.
    pub at: At,
    /// What is wrong.
    pub what: String,
}

impl LineError {
    /// An error at a text log's line.
    pub fn line(line: usize, what: impl Into<String>) -> Self {
        Self {
            at: At::Line(line),
            what: what.into(),
        }
    }

    /// The line number, for a text log's error.
    pub fn line_number(&self) -> Option<usize> {
        match self.at {
            At::Line(n) => Some(n),
            At::Byte(_) => None,
        }
    }
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.at, self.what)
    }
}

impl std::error::Error for LineError {}

/// Reads a text log's lines as bytes, so that a line that is not UTF-8 is one bad line,
/// not the end of the log: each non-blank line, trimmed, with its number.
pub struct Lines<R> {
    reader: R,
    line: usize,
    buf: Vec<u8>,
    failed: bool,
}

impl<R: BufRead> Lines<R> {
    /// Lines of `reader`.
    pub fn new(reader: R) -> Self {
        Self {
            reader,
            line: 0,
            buf: Vec::new(),
            failed: false,
        }
    }

    /// The next non-blank line and its number, or its error; `None` at the end.
    pub fn next_line(&mut self) -> Option<(usize, Result<&str, LineError>)> {
        loop {
            if self.failed {
                return None;
            }
            self.buf.clear();
            self.line += 1;
            match self.reader.read_until(b'\n', &mut self.buf) {
                Ok(0) => return None,
                Ok(_) => {}
                Err(e) => {
                    self.failed = true;
                    let line = self.line;
                    return Some((
                        line,
                        Err(LineError::line(line, format!("cannot read: {e}"))),
                    ));
                }
            }
            let blank = std::str::from_utf8(&self.buf).is_ok_and(|t| t.trim().is_empty());
            if !blank {
                break;
            }
        }
        let line = self.line;
        Some(match std::str::from_utf8(&self.buf) {
            Ok(text) => (line, Ok(text.trim())),
            Err(_) => (
                line,
                Err(LineError::line(line, "not text (a byte that is not UTF-8)")),
            ),
        })
    }
}

impl<R> Lines<R> {
    /// The number of the line read last.
    pub fn line(&self) -> usize {
        self.line
    }
}

/// Reads one `(1700000000.123456) can0 123#DEADBEEF` line.
///
/// # Errors
/// A sentence naming the part that is wrong.
pub fn parse_candump(line: &str) -> Result<Entry, String> {
    let mut parts = line.split_whitespace();
    // python-can's CanutilsLogWriter adds the direction, `R` or `T`.
    let (Some(stamp), Some(channel), Some(text), None | Some("R" | "T"), None) = (
        parts.next(),
        parts.next(),
        parts.next(),
        parts.next(),
        parts.next(),
    ) else {
        return Err(format!(
            "`{line}` is not a candump log line: (SECONDS) CHANNEL ID#DATA [R|T]"
        ));
    };
    let timestamp = stamp
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .filter(|s| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit() || c == b'.'))
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| format!("`{stamp}` is not a (seconds) time stamp"))?;
    let frame = frame::parse(text).map_err(|e| e.to_string())?;
    Ok(Entry {
        timestamp,
        channel: channel.to_string(),
        frame,
    })
}

/// The entries of a candump log, one per non-blank line, each an entry or the error of
/// its line. Reading stops only when the reader fails (an I/O error, reported as the
/// last item).
pub struct CandumpReader<R> {
    lines: Lines<R>,
}

impl<R: BufRead> CandumpReader<R> {
    /// A reader over a log's bytes.
    pub fn new(reader: R) -> Self {
        Self {
            lines: Lines::new(reader),
        }
    }
}

impl<R> CandumpReader<R> {
    /// The number of the line read last (1-based).
    pub fn line(&self) -> usize {
        self.lines.line
    }
}

impl<R: BufRead> Iterator for CandumpReader<R> {
    type Item = Result<Entry, LineError>;

    fn next(&mut self) -> Option<Self::Item> {
        let (line, text) = self.lines.next_line()?;
        Some(text.and_then(|t| parse_candump(t).map_err(|what| LineError::line(line, what))))
    }
}

/// The log formats `cw-can` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormat {
    /// `candump -L` (and python-can's `CanutilsLogWriter`).
    Candump,
    /// Vector ASC (text).
    Asc,
    /// Vector BLF (binary).
    Blf,
}

impl LogFormat {
    /// The format a file's extension names: `.asc` ASC, `.blf` BLF, anything else candump.
    pub fn of_path(path: &Path) -> Self {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("asc") => Self::Asc,
            Some("blf") => Self::Blf,
            _ => Self::Candump,
        }
    }
}

/// A log's entries, each with where it is (its line, or its BLF container's offset).
pub type Entries = Box<dyn Iterator<Item = Result<(At, Entry), LineError>>>;

/// Opens a log (`-` is standard input) in `format`, or the format its extension names.
///
/// # Errors
/// A file that cannot be read, or a BLF file whose header is not one.
pub fn open(path: &Path, format: Option<LogFormat>) -> Result<Entries, String> {
    let name = path.display().to_string();
    let format = format.unwrap_or_else(|| LogFormat::of_path(path));
    let reader: Box<dyn BufRead> = if name == "-" {
        Box::new(std::io::BufReader::new(std::io::stdin()))
    } else {
        Box::new(std::io::BufReader::new(
            std::fs::File::open(path).map_err(|e| format!("cannot read {name}: {e}"))?,
        ))
    };
    Ok(match format {
        LogFormat::Candump => {
            let mut r = CandumpReader::new(reader);
            Box::new(std::iter::from_fn(move || {
                r.next().map(|x| x.map(|e| (At::Line(r.line()), e)))
            }))
        }
        LogFormat::Asc => {
            let mut r = crate::asc::AscReader::new(reader);
            Box::new(std::iter::from_fn(move || {
                r.next().map(|x| x.map(|e| (At::Line(r.line()), e)))
            }))
        }
        LogFormat::Blf => {
            let mut bytes = Vec::new();
            let mut reader = reader;
            reader
                .read_to_end(&mut bytes)
                .map_err(|e| format!("cannot read {name}: {e}"))?;
            let mut r = crate::blf::BlfReader::new(bytes).map_err(|e| format!("{name}: {e}"))?;
            Box::new(std::iter::from_fn(move || {
                r.next()
                    .map(|x| x.map(|e| (At::Byte(r.container() as u64), e)))
            }))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_lines_are_named_and_the_rest_is_read() {
        let log: &[u8] = b"(1.000000) can0 100#00\n\
            garbage\n\
            \n\
            (2.000000) can0 100#0\xE90\n\
            (3.000000) can0 123##1AABB\n\
            (x) can0 100#00\n\
            (4.000000) can1 123#R\n\
            (5.000000) can0 123#00 R\n\
            (6.000000) can0 123#00 X\n";
        let items: Vec<_> = CandumpReader::new(log).collect();
        let lines: Vec<_> = items
            .iter()
            .map(|r| match r {
                Ok(e) => format!("ok {} {} {}", e.timestamp, e.channel, e.frame),
                Err(e) => format!("err {}", e.at),
            })
            .collect();
        assert_eq!(
            lines,
            [
                "ok 1 can0 100#00",
                "err 2",
                "err 4",
                "ok 3 can0 123##1AABB",
                "err 6",
                "ok 4 can1 123#R",
                "ok 5 can0 123#00",
                "err 9"
            ]
        );
    }

    #[test]
    fn any_bytes_are_entries_or_named_errors() {
        bolero::check!().with_type::<Vec<u8>>().for_each(|bytes| {
            let lines = bytes.split(|b| *b == b'\n').count();
            for item in CandumpReader::new(&bytes[..]) {
                match item {
                    Ok(e) => assert!(parse_candump(&format!(
                        "({:.6}) {} {}",
                        e.timestamp, e.channel, e.frame
                    ))
                    .is_ok()),
                    Err(e) => assert!(e.line_number().is_some_and(|n| (1..=lines).contains(&n))),
                }
            }
        });
    }
}
