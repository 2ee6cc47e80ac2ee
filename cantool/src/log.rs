//! CAN logs, read line by line: a bad line is an error naming its line number, and the
//! lines after it are still read.
//!
//! candump's log form (`candump -L`, what `canplayer` replays and python-can's
//! `CanutilsLogReader` reads): `(SECONDS) CHANNEL FRAME`, the frame in can-utils' compact
//! form ([`crate::frame`]).

use std::fmt;
use std::io::BufRead;

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

/// Why a line is not a log entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub what: String,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.what)
    }
}

impl std::error::Error for LineError {}

/// Reads one `(1700000000.123456) can0 123#DEADBEEF` line.
///
/// # Errors
/// A sentence naming the part that is wrong.
pub fn parse_candump(line: &str) -> Result<Entry, String> {
    let mut parts = line.split_whitespace();
    let (Some(stamp), Some(channel), Some(text), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(format!(
            "`{line}` is not a candump log line: (SECONDS) CHANNEL ID#DATA"
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
    reader: R,
    line: usize,
    buf: Vec<u8>,
    failed: bool,
}

impl<R: BufRead> CandumpReader<R> {
    /// A reader over a log's bytes.
    pub fn new(reader: R) -> Self {
        Self {
            reader,
            line: 0,
            buf: Vec::new(),
            failed: false,
        }
    }
}

impl<R> CandumpReader<R> {
    /// The number of the line read last (1-based).
    pub fn line(&self) -> usize {
        self.line
    }
}

impl<R: BufRead> Iterator for CandumpReader<R> {
    type Item = Result<Entry, LineError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.failed {
                return None;
            }
            self.buf.clear();
            self.line += 1;
            let line = self.line;
            match self.reader.read_until(b'\n', &mut self.buf) {
                Ok(0) => return None,
                Ok(_) => {}
                Err(e) => {
                    self.failed = true;
                    return Some(Err(LineError {
                        line,
                        what: format!("cannot read: {e}"),
                    }));
                }
            }
            let Ok(text) = std::str::from_utf8(&self.buf) else {
                return Some(Err(LineError {
                    line,
                    what: "not text (a byte that is not UTF-8)".into(),
                }));
            };
            let text = text.trim();
            if text.is_empty() {
                continue;
            }
            return Some(parse_candump(text).map_err(|what| LineError { line, what }));
        }
    }
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
            (4.000000) can1 123#R\n";
        let items: Vec<_> = CandumpReader::new(log).collect();
        let lines: Vec<_> = items
            .iter()
            .map(|r| match r {
                Ok(e) => format!("ok {} {} {}", e.timestamp, e.channel, e.frame),
                Err(e) => format!("err {}", e.line),
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
                "ok 4 can1 123#R"
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
                    Err(e) => assert!((1..=lines).contains(&e.line)),
                }
            }
        });
    }
}
