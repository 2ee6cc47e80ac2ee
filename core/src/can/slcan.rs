//! SLCAN, the Lawicel CAN232/CANUSB ASCII protocol: CAN frames and adapter commands as
//! text lines on a serial link. It is what python-can's `slcan` interface, Linux's
//! `slcand` and most USB-CAN adapters speak, so a UART that speaks it is a CAN bus those
//! tools can use.
//!
//! A line is a command letter, its fields in hexadecimal and a carriage return:
//!
//! | line | meaning | reply |
//! |---|---|---|
//! | `tIIILDD..` | data frame, 11-bit id `III`, DLC `L` (0..=8), `L` data bytes | `z\r` |
//! | `TIIIIIIIILDD..` | data frame, 29-bit id | `Z\r` |
//! | `O`, `L`, `C` | open the channel, open listen-only, close | `\r` |
//! | `Sn` | bit rate `n` (0 = 10 kbit/s .. 8 = 1 Mbit/s) | `\r` |
//! | `Z0`, `Z1` | time stamps on received frames off, on | `\r` |
//! | `V`, `N` | version, serial number | `V0101\r`, `NCW01\r` |
//! | anything else | | BEL (`\x07`) |
//!
//! [`Decoder`] takes received bytes one at a time and gives one verdict per line: a
//! [`Command`] or the [`LineError`] that names what is wrong with it. A bad line never
//! spoils the next one: the decoder starts afresh after every line end (`\r`, or `\n` as
//! some terminals send), and a line longer than any valid one is rejected when it ends,
//! without being stored. Remote frames (`r`, `R`), CAN FD frames (`d`, `D`, `b`, `B`) and
//! the other Lawicel commands are understood as such and refused ([`LineError::Unsupported`]):
//! this stack carries classic data frames only.
//!
//! [`encode_frame`] writes the line of a frame (upper-case hex, as Lawicel adapters send),
//! with the adapter's optional time stamp: 4 hex digits after the data, milliseconds
//! modulo [`TIMESTAMP_MODULUS`]. A PC reads such lines with [`parse_adapter_line`]; tools
//! that know no time stamps (python-can's `slcan`) read the frame and ignore them.
//! [`spec`] holds the contract the harnesses check.

use super::{CanFrame, CanId};

/// The longest line body this decoder accepts: `T`, 8 id digits, the DLC, 16 data digits.
pub const LINE_CAPACITY: usize = 26;

/// The longest frame line [`encode_frame`] writes: the longest line body, a time stamp's
/// 4 digits and the `\r`.
pub const FRAME_LINE_MAX: usize = LINE_CAPACITY + 4 + 1;

/// Lawicel time stamps count milliseconds modulo one minute.
pub const TIMESTAMP_MODULUS: u32 = 60_000;

/// The reply to a line that is refused (ASCII BEL).
pub const ERROR_REPLY: &[u8] = b"\x07";

/// A well-formed SLCAN line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `t` or `T`: transmit this data frame.
    Frame(CanFrame),
    /// `O`: open the channel.
    Open,
    /// `L`: open the channel listen-only.
    ListenOnly,
    /// `C`: close the channel.
    Close,
    /// `Sn`: the bit rate's table index, 0 (10 kbit/s) to 8 (1 Mbit/s).
    Bitrate(u8),
    /// `Z0`/`Z1`: time stamps on the frames the adapter sends off or on.
    Timestamps(bool),
    /// `V`: the adapter's hardware and software versions.
    Version,
    /// `N`: the adapter's serial number.
    SerialNumber,
}

impl Command {
    /// What the adapter answers to this command.
    pub fn reply(&self) -> &'static [u8] {
        match self {
            Self::Frame(f) if f.can_id().is_extended() => b"Z\r",
            Self::Frame(_) => b"z\r",
            Self::Version => b"V0101\r",
            Self::SerialNumber => b"NCW01\r",
            Self::Open
            | Self::ListenOnly
            | Self::Close
            | Self::Bitrate(_)
            | Self::Timestamps(_) => b"\r",
        }
    }
}

/// Why a line was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineError {
    /// The first character is no SLCAN command.
    UnknownCommand,
    /// A Lawicel command this adapter does not carry out: remote frames, CAN FD frames,
    /// bit timing registers, time stamps, status flags, acceptance filters.
    Unsupported,
    /// The line's length does not match its command and DLC.
    BadLength,
    /// A character where a hexadecimal digit must be.
    BadHex,
    /// An 11-bit id above `0x7FF` or a 29-bit id above `0x1FFF_FFFF`.
    IdOutOfRange,
    /// A DLC above 8.
    BadDlc,
    /// A bit rate index above 8.
    BadBitrate,
    /// The line is longer than any valid line ([`LINE_CAPACITY`] characters).
    TooLong,
}

/// Splits received bytes into lines and decodes each: one verdict per non-empty line.
#[derive(Debug, Clone)]
pub struct Decoder {
    line: [u8; LINE_CAPACITY],
    len: usize,
    too_long: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder at the start of a line.
    pub const fn new() -> Self {
        Self {
            line: [0; LINE_CAPACITY],
            len: 0,
            too_long: false,
        }
    }

    /// Takes one received byte. At a line's end (`\r` or `\n`) gives the line's verdict;
    /// an empty line gives none.
    pub fn push(&mut self, byte: u8) -> Option<Result<Command, LineError>> {
        if byte == b'\r' || byte == b'\n' {
            let verdict = if self.too_long {
                Some(Err(LineError::TooLong))
            } else {
                self.line
                    .get(..self.len)
                    .filter(|l| !l.is_empty())
                    .map(parse_line)
            };
            self.len = 0;
            self.too_long = false;
            return verdict;
        }
        match self.line.get_mut(self.len) {
            Some(slot) if !self.too_long => {
                *slot = byte;
                self.len += 1;
            }
            _ => self.too_long = true,
        }
        None
    }
}

/// The value of a hexadecimal digit (either case).
fn hex_value(c: u8) -> Option<u32> {
    match c {
        b'0'..=b'9' => Some(u32::from(c - b'0')),
        b'A'..=b'F' => Some(u32::from(c - b'A' + 10)),
        b'a'..=b'f' => Some(u32::from(c - b'a' + 10)),
        _ => None,
    }
}

/// The number written by `digits` (at most 8 hex digits: every caller passes 2, 3, 4 or
/// 8). The loop reads every digit and the verdict follows it, with a bound Kani sees: the
/// verdict of stopping at the first bad digit, in far fewer paths.
fn hex_number(digits: &[u8]) -> Result<u32, LineError> {
    let mut n = 0u32;
    let mut all_hex = true;
    for &c in digits.iter().take(8) {
        match hex_value(c) {
            Some(v) => n = (n << 4) | v,
            None => all_hex = false,
        }
    }
    if all_hex {
        Ok(n)
    } else {
        Err(LineError::BadHex)
    }
}

/// Decodes one line without its terminator.
///
/// # Errors
/// The [`LineError`] naming the first thing wrong with the line.
pub fn parse_line(line: &[u8]) -> Result<Command, LineError> {
    let Some((&command, rest)) = line.split_first() else {
        return Err(LineError::BadLength);
    };
    match command {
        b't' | b'T' => parse_frame(command == b'T', rest).map(Command::Frame),
        b'O' | b'L' | b'C' | b'V' | b'N' if !rest.is_empty() => Err(LineError::BadLength),
        b'O' => Ok(Command::Open),
        b'L' => Ok(Command::ListenOnly),
        b'C' => Ok(Command::Close),
        b'V' => Ok(Command::Version),
        b'N' => Ok(Command::SerialNumber),
        b'S' => match rest {
            [digit] => match hex_value(*digit) {
                Some(n @ 0..=8) => Ok(Command::Bitrate(n as u8)),
                Some(_) => Err(LineError::BadBitrate),
                None => Err(LineError::BadHex),
            },
            _ => Err(LineError::BadLength),
        },
        b'Z' => match rest {
            [b'0'] => Ok(Command::Timestamps(false)),
            [b'1'] => Ok(Command::Timestamps(true)),
            [_] => Err(LineError::BadHex),
            _ => Err(LineError::BadLength),
        },
        // Remote and CAN FD frames, BTR registers, status flags, acceptance code and
        // mask, auto-poll, the UART's own rate.
        b'r' | b'R' | b'd' | b'D' | b'b' | b'B' | b's' | b'F' | b'M' | b'm' | b'X' | b'U'
        | b'P' | b'A' | b'Q' | b'W' => Err(LineError::Unsupported),
        _ => Err(LineError::UnknownCommand),
    }
}

/// A data frame's fields after `t` (3 id digits) or `T` (8 id digits).
fn parse_frame(extended: bool, fields: &[u8]) -> Result<CanFrame, LineError> {
    let id_digits = if extended { 8 } else { 3 };
    let (Some(id_text), Some(&dlc_char)) = (fields.get(..id_digits), fields.get(id_digits)) else {
        return Err(LineError::BadLength);
    };
    let raw = hex_number(id_text)?;
    let id = if extended {
        CanId::extended(raw)
    } else {
        u16::try_from(raw).ok().and_then(CanId::standard)
    }
    .ok_or(LineError::IdOutOfRange)?;
    let dlc = hex_value(dlc_char).ok_or(LineError::BadHex)?;
    if dlc > 8 {
        return Err(LineError::BadDlc);
    }
    let data_text = fields.get(id_digits + 1..).unwrap_or_default();
    let dlc = dlc as usize;
    if data_text.len() != 2 * dlc {
        return Err(LineError::BadLength);
    }
    // Every pair is read, and the verdict follows (as in `hex_number`).
    let mut data = [0u8; 8];
    let mut all_hex = true;
    for (byte, pair) in data.iter_mut().zip(data_text.chunks_exact(2)) {
        let digit = |i| pair.get(i).copied().and_then(hex_value);
        match (digit(0), digit(1)) {
            (Some(hi), Some(lo)) => *byte = ((hi << 4) | lo) as u8,
            _ => all_hex = false,
        }
    }
    if !all_hex {
        return Err(LineError::BadHex);
    }
    // `data` holds the `dlc` bytes, then zeros: what `CanFrame::from_parts` makes of
    // them, built directly (its copy loop has a length Kani cannot see is at most 8).
    Ok(CanFrame {
        id,
        dlc: dlc as u8,
        data,
    })
}

/// An upper-case hexadecimal digit.
fn hex_digit(nibble: u32) -> u8 {
    match (nibble & 0xF) as u8 {
        n @ 0..=9 => b'0' + n,
        n => b'A' + n - 10,
    }
}

/// A frame line as an adapter sends it to the PC: the frame, and the time stamp (ms
/// modulo [`TIMESTAMP_MODULUS`]) when the line carries one.
///
/// # Errors
/// As [`parse_line`]; a line that is no `t`/`T` frame is [`LineError::UnknownCommand`].
pub fn parse_adapter_line(line: &[u8]) -> Result<(CanFrame, Option<u16>), LineError> {
    let stamped = line.len() >= 5
        && match (line.first(), line.get(4), line.get(9)) {
            (Some(b't'), Some(&dlc), _) | (Some(b'T'), _, Some(&dlc)) => hex_value(dlc)
                .is_some_and(|dlc| {
                    let id_digits = if line.first() == Some(&b'T') { 8 } else { 3 };
                    line.len() == 1 + id_digits + 1 + 2 * dlc as usize + 4
                }),
            _ => false,
        };
    let (body, stamp) = if stamped {
        let (body, digits) = line.split_at(line.len() - 4);
        let ms = hex_number(digits)?;
        if ms >= TIMESTAMP_MODULUS {
            return Err(LineError::BadLength);
        }
        (body, Some(ms as u16))
    } else {
        (line, None)
    };
    match parse_line(body)? {
        Command::Frame(frame) => Ok((frame, stamp)),
        _ => Err(LineError::UnknownCommand),
    }
}

/// Writes the SLCAN line of `frame` (`t`/`T`, id, DLC, data, `\r`) into `out`; returns
/// its length.
pub fn encode_frame(frame: &CanFrame, out: &mut [u8; FRAME_LINE_MAX]) -> usize {
    encode_frame_at(frame, None, out)
}

/// Writes the SLCAN line of `frame` into `out`, with the time stamp `at_ms` (taken modulo
/// [`TIMESTAMP_MODULUS`]) when given; returns its length.
pub fn encode_frame_at(
    frame: &CanFrame,
    at_ms: Option<u32>,
    out: &mut [u8; FRAME_LINE_MAX],
) -> usize {
    let id = frame.can_id();
    let (command, digits) = if id.is_extended() {
        (b'T', 8)
    } else {
        (b't', 3)
    };
    let mut n = 0;
    let mut put = |b: u8| {
        if n < FRAME_LINE_MAX {
            out[n] = b;
            n += 1;
        }
    };
    put(command);
    // At most 8 digits and 8 bytes: `take` makes the bounds plain to Kani.
    for i in (0..digits).rev().take(8) {
        put(hex_digit(id.raw() >> (4 * i)));
    }
    put(hex_digit(u32::from(frame.len())));
    for &b in frame.bytes().iter().take(8) {
        put(hex_digit(u32::from(b) >> 4));
        put(hex_digit(u32::from(b)));
    }
    if let Some(ms) = at_ms {
        let ms = ms % TIMESTAMP_MODULUS;
        for i in (0..4).rev() {
            put(hex_digit(ms >> (4 * i)));
        }
    }
    put(b'\r');
    n
}

/// The contract of the decoder, shared by the harnesses here and the fuzz target.
pub mod spec {
    use super::{encode_frame, Command, Decoder, FRAME_LINE_MAX, LINE_CAPACITY};
    use crate::can::CanFrame;

    /// A frame line the decoder accepted is the canonical line of its frame, up to the
    /// case of its hex digits: the decoder accepts exactly the well-formed frame lines.
    pub fn accepted_line_is_canonical(line: &[u8], frame: &CanFrame) -> bool {
        let mut canonical = [0u8; FRAME_LINE_MAX];
        // The line without its `\r` (at most `LINE_CAPACITY` bytes: it has no time
        // stamp), compared byte by byte over that many (a bound Kani sees):
        // `eq_ignore_ascii_case` on the two slices.
        let body = encode_frame(frame, &mut canonical).saturating_sub(1);
        let mut same = line.len() == body && body <= LINE_CAPACITY;
        for (k, c) in canonical.iter().enumerate().take(LINE_CAPACITY) {
            if k < body {
                same &= line.get(k).is_some_and(|l| l.eq_ignore_ascii_case(c));
            }
        }
        same
    }

    /// Any bytes, then a line end, then the line of `frame`: every frame the decoder
    /// accepted along the way is canonical (checked by re-encoding the line it came
    /// from), there is at most one verdict per line end, and the good frame after the
    /// garbage comes out intact: garbage never costs the next good line.
    pub fn stream_contract(garbage: &[u8], frame: &CanFrame) -> bool {
        let mut decoder = Decoder::new();
        let mut line = [0u8; FRAME_LINE_MAX];
        let mut line_len = 0usize;
        let mut ends = 0usize;
        let mut verdicts = 0usize;
        let mut good = [0u8; FRAME_LINE_MAX];
        let good_len = encode_frame(frame, &mut good);
        let tail = good.get(..good_len).unwrap_or_default();
        let mut last = None;
        for &byte in garbage.iter().chain(b"\r").chain(tail) {
            let end = byte == b'\r' || byte == b'\n';
            let verdict = decoder.push(byte);
            if end {
                ends += 1;
                if let Some(Ok(Command::Frame(f))) = verdict {
                    let text = line.get(..line_len).unwrap_or_default();
                    if !accepted_line_is_canonical(text, &f) {
                        return false;
                    }
                }
                line_len = 0;
            } else {
                if let Some(slot) = line.get_mut(line_len) {
                    *slot = byte;
                }
                line_len = line_len.saturating_add(1);
                if verdict.is_some() {
                    return false;
                }
            }
            if verdict.is_some() {
                verdicts += 1;
                last = verdict;
            }
        }
        verdicts <= ends && last == Some(Ok(Command::Frame(*frame)))
    }
}

#[cfg(test)]
mod tests;
