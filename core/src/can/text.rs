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
    let (id_text, data_text) = text
        .split_once('#')
        .ok_or(FrameTextError::NoSeparator(text))?;
    if id_text.is_empty() || id_text.len() > 8 {
        return Err(FrameTextError::BadId(id_text));
    }
    let mut raw = 0u32;
    for c in id_text.bytes() {
        let digit = hex_digit(c).ok_or(FrameTextError::BadId(id_text))?;
        raw = (raw << 4) | u32::from(digit);
    }
    let id = if id_text.len() > 3 {
        CanId::extended(raw)
    } else {
        u16::try_from(raw).ok().and_then(CanId::standard)
    }
    .ok_or(FrameTextError::IdOutOfRange(id_text))?;
    let digits = data_text.as_bytes();
    if digits.len() % 2 != 0 {
        return Err(FrameTextError::OddDigits(data_text));
    }
    let len = digits.len() / 2;
    if len > 8 && digits.iter().all(|&c| hex_digit(c).is_some()) {
        return Err(FrameTextError::TooLong(len));
    }
    let mut data = [0u8; 8];
    for (slot, pair) in data.iter_mut().zip(digits.chunks_exact(2)) {
        let (Some(hi), Some(lo)) = (
            pair.first().copied().and_then(hex_digit),
            pair.get(1).copied().and_then(hex_digit),
        ) else {
            return Err(FrameTextError::BadData(data_text));
        };
        *slot = (hi << 4) | lo;
    }
    if len > 8 {
        return Err(FrameTextError::BadData(data_text));
    }
    CanFrame::from_parts(id, data.get(..len).unwrap_or(&[])).ok_or(FrameTextError::TooLong(len))
}

/// Writes `frame` as `ID#HEXDATA` (three id digits for an 11-bit id, eight for a 29-bit
/// one, upper case), the form [`parse_frame`] reads back.
///
/// # Errors
/// Only the writer's.
pub fn write_frame(frame: &CanFrame, out: &mut impl fmt::Write) -> fmt::Result {
    let id = frame.can_id();
    if id.is_extended() {
        write!(out, "{:08X}#", id.raw())?;
    } else {
        write!(out, "{:03X}#", id.raw())?;
    }
    for b in frame.bytes() {
        write!(out, "{b:02X}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
