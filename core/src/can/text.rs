//! Frames as text in can-utils' compact form, `ID#HEXDATA` (`cansend`, candump logs):
//! three hex digits or fewer for an 11-bit id, more for a 29-bit id, then up to eight
//! data bytes as hex pairs (`123#`, `123#DEADBEEF`, `1ABCDEF0#00`).
//!
//! Scenario files (the host simulation's and the image's) and the PC tool read frames
//! with [`parse_frame`]; it refuses what is not exactly that form with a
//! [`FrameTextError`] naming the part that is wrong.

use core::fmt;

use super::{CanFrame, CanId};

/// Why a text is not a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameTextError<'a> {
    /// No `#` between id and data.
    NoSeparator(&'a str),
    /// The id is empty or not hex.
    BadId(&'a str),
    /// The id does not fit its format (above 0x7FF with three digits or fewer, above
    /// 0x1FFF_FFFF with more).
    IdOutOfRange(&'a str),
    /// The data has an odd number of hex digits.
    OddDigits(&'a str),
    /// The data is not hex.
    BadData(&'a str),
    /// More than eight data bytes (the count).
    TooLong(usize),
}

impl fmt::Display for FrameTextError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoSeparator(text) => write!(f, "`{text}` is not a frame (expected ID#HEXDATA)"),
            Self::BadId(id) => write!(f, "`{id}` is not a hex CAN id"),
            Self::IdOutOfRange(id) => write!(f, "CAN id {id} is out of range"),
            Self::OddDigits(data) => write!(f, "`{data}` has an odd number of hex digits"),
            Self::BadData(data) => write!(f, "`{data}` is not hex data"),
            Self::TooLong(n) => write!(f, "{n} data bytes; a CAN frame holds at most 8"),
        }
    }
}

/// The value of one ASCII hex digit.
const fn hex_digit(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Reads `ID#HEXDATA`.
///
/// # Errors
/// The first part that is wrong, with the text of that part.
pub fn parse_frame(text: &str) -> Result<CanFrame, FrameTextError<'_>> {
    // Every loop here runs to its end (a bound Kani sees, where there is one) and the
    // checks follow it: the verdicts of stopping at the first fault, in far fewer paths
    // for Kani.
    let bytes = text.as_bytes();
    // The first `#` (ASCII: its byte is the character).
    let mut separator = bytes.len();
    let mut i = bytes.len();
    while i > 0 {
        i -= 1;
        if bytes.get(i) == Some(&b'#') {
            separator = i;
        }
    }
    let (Some(id_text), Some(data_text)) = (text.get(..separator), text.get(separator + 1..))
    else {
        return Err(FrameTextError::NoSeparator(text));
    };
    let id_digits = id_text.as_bytes();
    if id_digits.is_empty() || id_digits.len() > 8 {
        return Err(FrameTextError::BadId(id_text));
    }
    let mut raw = 0u32;
    let mut id_is_hex = true;
    for k in 0..8 {
        if let Some(&c) = id_digits.get(k) {
            match hex_digit(c) {
                Some(digit) => raw = (raw << 4) | u32::from(digit),
                None => id_is_hex = false,
            }
        }
    }
    if !id_is_hex {
        return Err(FrameTextError::BadId(id_text));
    }
    let id = if id_digits.len() > 3 {
        CanId::extended(raw)
    } else {
        u16::try_from(raw).ok().and_then(CanId::standard)
    }
    .ok_or(FrameTextError::IdOutOfRange(id_text))?;
    let digits = data_text.as_bytes();
    if digits.len() % 2 != 0 {
        return Err(FrameTextError::OddDigits(data_text));
    }
    let mut data_is_hex = true;
    let mut k = 0;
    while k < digits.len() {
        data_is_hex &= digits.get(k).copied().and_then(hex_digit).is_some();
        k += 1;
    }
    if !data_is_hex {
        return Err(FrameTextError::BadData(data_text));
    }
    let len = digits.len() / 2;
    if len > 8 {
        return Err(FrameTextError::TooLong(len));
    }
    let mut data = [0u8; 8];
    for (k, byte) in data.iter_mut().enumerate() {
        if k < len {
            let digit = |i: usize| digits.get(i).copied().and_then(hex_digit).unwrap_or(0);
            *byte = (digit(2 * k) << 4) | digit(2 * k + 1);
        }
    }
    // `data` holds the `len` bytes, then zeros: what `CanFrame::from_parts` makes of
    // them, built directly (its copy loop has a length Kani cannot see is at most 8).
    Ok(CanFrame {
        id,
        dlc: len as u8,
        data,
    })
}

/// Writes `frame` as `ID#HEXDATA` (three id digits for an 11-bit id, eight for a 29-bit
/// one, upper case), the form [`parse_frame`] reads back.
///
/// # Errors
/// Only the writer's.
pub fn write_frame(frame: &CanFrame, out: &mut impl fmt::Write) -> fmt::Result {
    let id = frame.can_id();
    let id_digits = if id.is_extended() { 8 } else { 3 };
    write_hex(out, id.raw(), id_digits)?;
    out.write_str("#")?;
    for &b in frame.bytes().iter().take(8) {
        write_hex(out, u32::from(b), 2)?;
    }
    Ok(())
}

/// The upper-case hexadecimal digit of the low nibble of `value`, as text.
const fn hex_digit_text(value: u32) -> &'static str {
    match value & 0xF {
        0 => "0",
        1 => "1",
        2 => "2",
        3 => "3",
        4 => "4",
        5 => "5",
        6 => "6",
        7 => "7",
        8 => "8",
        9 => "9",
        10 => "A",
        11 => "B",
        12 => "C",
        13 => "D",
        14 => "E",
        _ => "F",
    }
}

/// Writes the low `digits` nibbles of `value` in upper-case hex, the most significant
/// first: what `{:0digits$X}` writes for a value that fits, without `core::fmt`'s
/// padding and radix machinery (which Kani proofs cannot afford).
fn write_hex(out: &mut impl fmt::Write, value: u32, digits: u32) -> fmt::Result {
    // At most 8 digits: `take` makes the bound plain to Kani.
    for i in (0..digits).rev().take(8) {
        out.write_str(hex_digit_text(value >> (4 * i)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
