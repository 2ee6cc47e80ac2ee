//! Vector ASC logs (text), as CANoe, CANalyzer and python-can's `ASCWriter` write them:
//!
//! ```text
//! date Mon Nov 24 12:00:00.000 2026
//! base hex  timestamps absolute
//! internal events logged
//! Begin Triggerblock Mon Nov 24 12:00:00.000 2026
//!    0.000000 Start of measurement
//!    0.001000 1  123             Rx   d 8 11 22 33 44 55 66 77 88
//!    0.002000 1  1ABCDEF0x       Tx   d 2 AA BB
//!    0.003000 1  123             Rx   r 4
//!    0.004000 1  ErrorFrame
//!    0.005000 CANFD   1 Rx        123                                  1 0 9 12 00 .. 0 0 3000 0 0 0 0 0
//! End TriggerBlock
//! ```
//!
//! The rules are python-can's `ASCReader`'s: time stamps as written (relative to the
//! measurement's start); `base dec` switches ids, DLCs and data to decimal; an id ending
//! in `x` is a 29-bit id; a classic line's data is the first `min(8, length(DLC))` bytes
//! after the DLC (CANoe may append `Length = ...` fields); an FD line names bit rate
//! switch, error state indicator, DLC and data length, and after the data its message
//! flags say FD (0x1000) or remote (0x10); lines that are no frame (statistics, J1939,
//! status, comments) are skipped. One difference from python-can's reader: an FD frame
//! without data is read as one (python-can reads it as a remote frame, as its rule is a
//! data length of 0; that rule is kept for lines without the flags column).
//! The channel is kept as written (Vector numbers channels from 1). A line that looks
//! like a frame but cannot be read is an error naming the line, and reading goes on.

use std::io::BufRead;

use crate::frame::{Frame, FrameKind, FD_LENGTHS};
use crate::log::{Entry, LineError, Lines};

/// The data length of a DLC (CAN FD's table above 8).
pub fn dlc_to_len(dlc: u8) -> usize {
    FD_LENGTHS.get(usize::from(dlc)).copied().unwrap_or(64)
}

/// The entries of an ASC log.
pub struct AscReader<R> {
    lines: Lines<R>,
    parser: Parser,
}

/// What a line's meaning depends on: the number base the log's `base` line set.
#[derive(Debug, Default)]
struct Parser {
    decimal: bool,
}

impl<R: BufRead> AscReader<R> {
    /// A reader over an ASC log's bytes.
    pub fn new(reader: R) -> Self {
        Self {
            lines: Lines::new(reader),
            parser: Parser::default(),
        }
    }
}

/// `\d+\.\d+`: an ASC time stamp.
fn timestamp(token: &str) -> Option<f64> {
    let (whole, frac) = token.split_once('.')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
    (digits(whole) && digits(frac)).then(|| token.parse().ok())?
}

fn is_word(token: &str) -> bool {
    !token.is_empty()
        && token
            .bytes()
            .all(|c| c.is_ascii_alphanumeric() || c == b'_')
}

fn is_direction(token: &str) -> bool {
    token.eq_ignore_ascii_case("rx") || token.eq_ignore_ascii_case("tx")
}

impl<R> AscReader<R> {
    /// The number of the line read last (1-based).
    pub fn line(&self) -> usize {
        self.lines.line()
    }
}

impl Parser {
    fn number(&self, text: &str, what: &str) -> Result<u64, String> {
        let radix = if self.decimal { 10 } else { 16 };
        u64::from_str_radix(text, radix).map_err(|_| {
            format!(
                "`{text}` is not a {} {what}",
                if self.decimal { "decimal" } else { "hex" }
            )
        })
    }

    fn id(&self, text: &str) -> Result<(u32, bool), String> {
        let (digits, extended) = match text.strip_suffix(['x', 'X']) {
            Some(d) => (d, true),
            None => (text, false),
        };
        let id = self.number(digits, "CAN id")?;
        let max = if extended { 0x1FFF_FFFF } else { 0x7FF };
        u32::try_from(id)
            .ok()
            .filter(|id| *id <= max)
            .map(|id| (id, extended))
            .ok_or_else(|| format!("CAN id {text} is out of range"))
    }

    fn data(&self, tokens: &[&str], len: usize) -> Result<Vec<u8>, String> {
        let bytes = tokens
            .get(..len)
            .ok_or_else(|| format!("{} data bytes given, {len} expected", tokens.len()))?;
        bytes
            .iter()
            .map(|b| {
                self.number(b, "data byte")
                    .and_then(|v| u8::try_from(v).map_err(|_| format!("`{b}` is not a byte")))
            })
            .collect()
    }

    fn dlc(&self, text: &str) -> Result<u8, String> {
        self.number(text, "DLC")
            .ok()
            .and_then(|d| u8::try_from(d).ok())
            .filter(|d| *d <= 15)
            .ok_or_else(|| format!("`{text}` is not a DLC (0 to F)"))
    }

    /// One line: `None` for a header or a line that is not a frame.
    fn parse(&mut self, line: &str) -> Option<Result<Entry, String>> {
        let tokens: Vec<&str> = line.split_whitespace().collect();
        let (first, second) = (tokens.first()?, tokens.get(1));
        if first.eq_ignore_ascii_case("base") {
            match second.map(|b| b.to_ascii_lowercase()).as_deref() {
                Some("hex") => self.decimal = false,
                Some("dec") => self.decimal = true,
                _ => return Some(Err(format!("`{line}`: base is hex or dec"))),
            }
            return None;
        }
        let time = timestamp(first)?;
        let second = *second?;
        // python-can's ASC_MESSAGE_REGEX: `CH ErrorFrame`, `CH WORD Rx|Tx`, or `CANFD`.
        let third = tokens.get(2).copied().unwrap_or("");
        let fourth = tokens.get(3).copied().unwrap_or("");
        let channel_digits = !second.is_empty() && second.bytes().all(|c| c.is_ascii_digit());
        let frame = if second.eq_ignore_ascii_case("canfd") {
            self.fd(tokens.get(2..).unwrap_or(&[]))
        } else if channel_digits && third.eq_ignore_ascii_case("errorframe") {
            Ok((second.to_string(), error_frame()))
        } else if channel_digits && is_word(third) && is_direction(fourth) {
            self.classic(third, tokens.get(4..).unwrap_or(&[]))
                .map(|f| (second.to_string(), f))
        } else {
            return None;
        };
        Some(frame.map(|(channel, frame)| Entry {
            timestamp: time,
            channel,
            frame,
        }))
    }

    fn classic(&self, id: &str, rest: &[&str]) -> Result<Frame, String> {
        let (id, extended) = self.id(id)?;
        match rest {
            [kind, more @ ..] if kind.eq_ignore_ascii_case("r") => {
                let dlc = match more.first() {
                    Some(d) if d.bytes().all(|c| c.is_ascii_digit()) => Some(self.dlc(d)?),
                    _ => None,
                };
                Ok(Frame {
                    kind: FrameKind::Remote,
                    dlc,
                    ..Frame::classic(id, extended, &[])
                })
            }
            [kind, dlc, data @ ..] if kind.eq_ignore_ascii_case("d") => {
                let dlc = self.dlc(dlc)?;
                let len = dlc_to_len(dlc).min(8);
                let data = self.data(data, len)?;
                Ok(Frame {
                    dlc: (dlc > 8).then_some(dlc),
                    ..Frame::classic(id, extended, &data)
                })
            }
            _ => Err("expected `d DLC DATA..` or `r [DLC]` after the direction".into()),
        }
    }

    fn fd(&self, rest: &[&str]) -> Result<(String, Frame), String> {
        let [channel, direction, id, after @ ..] = rest else {
            return Err("a CANFD line needs a channel, a direction and an id".into());
        };
        if !is_direction(direction) {
            return Err(format!("`{direction}` is not Rx or Tx"));
        }
        if channel.is_empty() || !channel.bytes().all(|c| c.is_ascii_digit()) {
            return Err(format!("`{channel}` is not a channel number"));
        }
        if id.eq_ignore_ascii_case("errorframe") {
            return Ok((channel.to_string(), error_frame()));
        }
        let (id, extended) = self.id(id)?;
        // A symbolic name may stand between the id and the flags.
        let after = match after.first() {
            Some(t) if !t.bytes().all(|c| c.is_ascii_digit()) => after.get(1..).unwrap_or(&[]),
            _ => after,
        };
        let [brs, esi, dlc, length, data @ ..] = after else {
            return Err("a CANFD line needs BRS, ESI, DLC and the data length".into());
        };
        let flag = |t: &str| match t {
            "0" => Ok(false),
            "1" => Ok(true),
            _ => Err(format!("`{t}` is not a flag (0 or 1)")),
        };
        let (brs, esi) = (flag(brs)?, flag(esi)?);
        let dlc = self.dlc(dlc)?;
        let length: usize = length
            .parse()
            .ok()
            .filter(|l| FD_LENGTHS.contains(l))
            .ok_or_else(|| format!("`{length}` is not an FD data length"))?;
        // The message flags column, after the data, the duration and the bit length:
        // 0x1000 an FD frame (EDL), 0x10 a remote frame. A line without it follows
        // python-can's rule: a data length of 0 is a remote frame.
        let flags = data
            .get(length + 2)
            .and_then(|t| u32::from_str_radix(t, 16).ok());
        let remote = match flags {
            Some(f) => f & 0x10 != 0 || f & 0x1000 == 0,
            None => length == 0,
        };
        if remote && length == 0 {
            return Ok((
                channel.to_string(),
                Frame {
                    kind: FrameKind::Remote,
                    dlc: Some(dlc),
                    ..Frame::classic(id, extended, &[])
                },
            ));
        }
        if dlc_to_len(dlc) != length {
            return Err(format!(
                "DLC {dlc:X} means {} bytes, the line says {length}",
                dlc_to_len(dlc)
            ));
        }
        let data = self.data(data, length)?;
        Ok((
            channel.to_string(),
            Frame {
                kind: FrameKind::Fd { brs, esi },
                ..Frame::classic(id, extended, &data)
            },
        ))
    }
}

fn error_frame() -> Frame {
    Frame {
        kind: FrameKind::Error,
        ..Frame::classic(0, false, &[])
    }
}

impl<R: BufRead> Iterator for AscReader<R> {
    type Item = Result<Entry, LineError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let (line, text) = self.lines.next_line()?;
            let text = match text {
                Ok(t) => t,
                Err(e) => return Some(Err(e)),
            };
            if let Some(result) = self.parser.parse(text) {
                return Some(result.map_err(|what| LineError::line(line, what)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Vec<String> {
        AscReader::new(text.as_bytes())
            .map(|r| match r {
                Ok(e) => format!("{} {} {}", e.timestamp, e.channel, e.frame),
                Err(e) => format!("error {e}"),
            })
            .collect()
    }

    #[test]
    fn every_frame_form_python_can_and_canoe_write_is_read() {
        let log = "\
date Mon Nov 24 12:00:00.000 2026
base hex  timestamps absolute
internal events logged
// version 9.0.0
Begin Triggerblock Mon Nov 24 12:00:00.000 2026
   0.000000 Start of measurement
   0.001000 1  123             Rx   d 8 11 22 33 44 55 66 77 88
   0.002000 2  1ABCDEF0x       Tx   d 2 AA BB
   0.003000 1  123             Rx   r 4
   0.003500 1  124             Rx   r
   0.004000 1  ErrorFrame
   0.004500 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%
   0.005000 CANFD   1 Rx        300                                  1 0 9 12 00 01 02 03 04 05 06 07 08 09 0A 0B        0    0     3000        0        0        0        0        0
   0.006000 CANFD   1 Rx        301  Sym   0 1 2  2 AA BB
   0.006500 CANFD   1 Rx        302                                   0 0 0  0        0    0     1000        0        0        0        0        0
   0.006600 CANFD   1 Rx        303                                   0 0 3  0        0    0     1010        0        0        0        0        0
   0.007000 1  100             Rx   d 8 01 02 03 04 05 06 07 08  Length = 0 BitCount = 0 ID = 256
End TriggerBlock
";
        assert_eq!(
            read(log),
            [
                "0.001 1 123#1122334455667788",
                "0.002 2 1ABCDEF0#AABB",
                "0.003 1 123#R4",
                "0.0035 1 124#R",
                "0.004 1 20000000#",
                "0.005 1 300##1000102030405060708090A0B",
                "0.006 1 301##2AABB",
                "0.0065 1 302##0",
                "0.0066 1 303#R3",
                "0.007 1 100#0102030405060708",
            ]
        );
    }

    #[test]
    fn base_dec_reads_decimal_ids_and_data() {
        let log = "base dec\n 1.500000 1  291  Rx   d 2 170 187\n";
        assert_eq!(read(log), ["1.5 1 123#AABB"]);
    }

    #[test]
    fn bad_frame_lines_are_named_and_the_rest_is_read() {
        let log = "\
 0.1 1  123  Rx   d 8 11 22
 0.2 1  800  Rx   d 1 00
 0.3 1  123  Rx   d 1 GG
 0.4 CANFD 1 Rx 123 1 0 9 11 00
 0.5 1  123  Rx   d 1 01
";
        assert_eq!(
            read(log),
            [
                "error 1: 2 data bytes given, 8 expected",
                "error 2: CAN id 800 is out of range",
                "error 3: `GG` is not a hex data byte",
                "error 4: `11` is not an FD data length",
                "0.5 1 123#01",
            ]
        );
    }

    #[test]
    fn any_text_is_entries_or_named_errors() {
        bolero::check!().with_type::<String>().for_each(|text| {
            let lines = text.split('\n').count();
            for item in AscReader::new(text.as_bytes()) {
                if let Err(e) = item {
                    assert!(e.line_number().is_some_and(|n| (1..=lines).contains(&n)));
                }
            }
        });
    }
}
