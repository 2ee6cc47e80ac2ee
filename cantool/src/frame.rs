//! A frame as a log holds it: classic or FD data, remote request or error frame, with an
//! 11- or 29-bit id and up to 64 data bytes. Written and read in can-utils' compact form
//! (`candump -L`, `cansend`).

use std::fmt;

/// Largest CAN FD payload, in bytes.
pub const MAX_FD_LEN: usize = 64;

/// The payload lengths a CAN FD frame can carry (one per DLC value).
pub const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// What kind of frame a log line holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameKind {
    /// A classic data frame, 0 to 8 bytes.
    Classic,
    /// A CAN FD data frame (bit rate switch and error state indicator flags).
    Fd {
        /// Bit rate switch: the data phase ran at the data bit rate.
        brs: bool,
        /// Error state indicator: the sender was error passive.
        esi: bool,
    },
    /// A remote (request) frame: no data, a requested length.
    Remote,
    /// An error frame as SocketCAN reports it: the id holds the error class, the data
    /// the details.
    Error,
}

impl FrameKind {
    /// The kind's name: `classic`, `fd`, `remote` or `error` (as in JSON and CSV output).
    pub fn name(self) -> &'static str {
        match self {
            Self::Classic => "classic",
            Self::Fd { .. } => "fd",
            Self::Remote => "remote",
            Self::Error => "error",
        }
    }
}

/// One frame of a log.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Frame {
    /// The identifier: 11 bits, or 29 when `extended`; for an error frame, the error
    /// class bits.
    pub id: u32,
    /// A 29-bit identifier.
    pub extended: bool,
    /// Data, remote or error frame.
    pub kind: FrameKind,
    /// The data bytes (empty for a remote frame).
    pub data: Vec<u8>,
    /// The DLC of a remote frame (its requested length), or a classic 8-byte frame's raw
    /// DLC of 9 to 15; else `None`.
    pub dlc: Option<u8>,
}

impl Frame {
    /// A classic data frame (at most 8 bytes; ids checked by the caller).
    pub fn classic(id: u32, extended: bool, data: &[u8]) -> Self {
        Self {
            id,
            extended,
            kind: FrameKind::Classic,
            data: data.to_vec(),
            dlc: None,
        }
    }

    /// Whether this frame carries data a DBC message can describe (classic or FD).
    pub fn is_data(&self) -> bool {
        matches!(self.kind, FrameKind::Classic | FrameKind::Fd { .. })
    }

    /// The frame as the ECU's stack carries it (`cw_core::can::CanFrame`): a classic data
    /// frame of at most 8 bytes with a valid id, or `None`.
    pub fn to_classic(&self) -> Option<cw_core::can::CanFrame> {
        use cw_core::can::{CanFrame, CanId};
        if self.kind != FrameKind::Classic {
            return None;
        }
        let id = if self.extended {
            CanId::extended(self.id)
        } else {
            u16::try_from(self.id).ok().and_then(CanId::standard)
        }?;
        CanFrame::from_parts(id, &self.data)
    }
}

fn hex(out: &mut fmt::Formatter<'_>, data: &[u8]) -> fmt::Result {
    data.iter().try_for_each(|b| write!(out, "{b:02X}"))
}

/// can-utils' compact form, as `candump -L` writes it: `123#DEADBEEF`, `12345678#00`,
/// `123##1DEADBEEF` (FD, the flags as one hex digit), `123#R`, `123#R5`, `123#1122334455667788_9`
/// (8 bytes, raw DLC 9), `20000080#0000000000000000` (an error frame).
impl fmt::Display for Frame {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            FrameKind::Error => write!(out, "{:08X}#", self.id | ERR_FLAG)?,
            _ if self.extended => write!(out, "{:08X}#", self.id)?,
            _ => write!(out, "{:03X}#", self.id)?,
        }
        match self.kind {
            FrameKind::Classic | FrameKind::Error => {
                hex(out, &self.data)?;
                match self.dlc {
                    Some(dlc) => write!(out, "_{dlc:X}"),
                    None => Ok(()),
                }
            }
            FrameKind::Fd { brs, esi } => {
                write!(out, "#{:X}", u8::from(brs) | u8::from(esi) << 1)?;
                hex(out, &self.data)
            }
            FrameKind::Remote => match self.dlc {
                Some(dlc) if dlc > 8 => write!(out, "R8_{dlc:X}"),
                Some(dlc) => write!(out, "R{dlc:X}"),
                None => write!(out, "R"),
            },
        }
    }
}

/// SocketCAN's flag for an error frame in a 32-bit id.
pub const ERR_FLAG: u32 = 0x2000_0000;

/// Why a text is not a frame. Each names the part that is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameError {
    /// No `#` after the id.
    NoSeparator(String),
    /// The id is not 3 or 8 hex digits.
    BadId(String),
    /// A 3-digit id above 0x7FF, or an 8-digit one with bits above the 29 (other than
    /// the error flag).
    IdOutOfRange(String),
    /// Data that is not hex byte pairs (dots between bytes are allowed).
    BadData(String),
    /// More data bytes than the frame kind carries.
    TooLong {
        /// Bytes found.
        len: usize,
        /// The kind's most.
        max: usize,
    },
    /// An FD payload length no DLC encodes (0-8, 12, 16, 20, 24, 32, 48, 64).
    FdLength(usize),
    /// A raw DLC suffix (`_X`) that is not 9 to F, or on a frame that is not 8 bytes.
    BadDlc(String),
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoSeparator(t) => write!(f, "`{t}` is not a frame (expected ID#DATA)"),
            Self::BadId(t) => write!(
                f,
                "`{t}` is not a CAN id (3 hex digits for 11 bits, 8 for 29 bits)"
            ),
            Self::IdOutOfRange(t) => write!(f, "CAN id {t} is out of range"),
            Self::BadData(t) => write!(f, "`{t}` is not hex data"),
            Self::TooLong { len, max } => {
                write!(
                    f,
                    "{len} data bytes; this kind of frame holds at most {max}"
                )
            }
            Self::FdLength(n) => write!(
                f,
                "{n} data bytes: a CAN FD frame holds 0-8, 12, 16, 20, 24, 32, 48 or 64"
            ),
            Self::BadDlc(t) => write!(f, "`{t}` is not a raw DLC of 9 to F after 8 bytes"),
        }
    }
}

impl std::error::Error for FrameError {}

fn nibble(c: u8) -> Option<u8> {
    char::from(c)
        .to_digit(16)
        .and_then(|d| u8::try_from(d).ok())
}

/// Hex byte pairs, optionally separated by dots (`11.22.33`), at most `max` of them.
fn parse_data(text: &str, max: usize) -> Result<Vec<u8>, FrameError> {
    let mut data = Vec::new();
    let mut digits = text.bytes().filter(|&c| c != b'.');
    if text.starts_with('.') || text.ends_with('.') || text.contains("..") {
        return Err(FrameError::BadData(text.to_string()));
    }
    loop {
        match (digits.next(), digits.next()) {
            (None, _) => break,
            (Some(hi), Some(lo)) => match (nibble(hi), nibble(lo)) {
                (Some(hi), Some(lo)) => data.push(hi << 4 | lo),
                _ => return Err(FrameError::BadData(text.to_string())),
            },
            (Some(_), None) => return Err(FrameError::BadData(text.to_string())),
        }
    }
    // A dot must sit between two whole bytes.
    let mut pos = 0;
    for c in text.bytes() {
        if c == b'.' {
            if pos % 2 != 0 {
                return Err(FrameError::BadData(text.to_string()));
            }
        } else {
            pos += 1;
        }
    }
    if data.len() > max {
        return Err(FrameError::TooLong {
            len: data.len(),
            max,
        });
    }
    Ok(data)
}

/// Reads a frame in can-utils' compact form (see [`Frame`]'s `Display`): what
/// `candump -L` writes and `cansend` reads.
///
/// # Errors
/// A [`FrameError`] naming the part that is wrong.
pub fn parse(text: &str) -> Result<Frame, FrameError> {
    let (id_text, rest) = text
        .split_once('#')
        .ok_or_else(|| FrameError::NoSeparator(text.to_string()))?;
    if !id_text.bytes().all(|c| c.is_ascii_hexdigit()) {
        return Err(FrameError::BadId(id_text.to_string()));
    }
    let raw = u32::from_str_radix(id_text, 16).map_err(|_| FrameError::BadId(id_text.into()))?;
    let (id, extended, error) = match id_text.len() {
        3 if raw <= 0x7FF => (raw, false, false),
        8 if raw & !(0x1FFF_FFFF | ERR_FLAG) == 0 => {
            (raw & 0x1FFF_FFFF, raw & ERR_FLAG == 0, raw & ERR_FLAG != 0)
        }
        3 | 8 => return Err(FrameError::IdOutOfRange(id_text.to_string())),
        _ => return Err(FrameError::BadId(id_text.to_string())),
    };
    if error {
        let data = parse_data(rest, 8)?;
        return Ok(Frame {
            id,
            extended: false,
            kind: FrameKind::Error,
            data,
            dlc: None,
        });
    }
    if let Some(fd) = rest.strip_prefix('#') {
        let mut chars = fd.bytes();
        let flags = chars
            .next()
            .and_then(nibble)
            .ok_or_else(|| FrameError::BadData(fd.to_string()))?;
        let data = parse_data(fd.get(1..).unwrap_or(""), MAX_FD_LEN)?;
        if !FD_LENGTHS.contains(&data.len()) {
            return Err(FrameError::FdLength(data.len()));
        }
        return Ok(Frame {
            id,
            extended,
            kind: FrameKind::Fd {
                brs: flags & 1 != 0,
                esi: flags & 2 != 0,
            },
            data,
            dlc: None,
        });
    }
    if let Some(len) = rest.strip_prefix('R') {
        let dlc = match len.as_bytes() {
            [] => None,
            [d] => Some(
                nibble(*d)
                    .filter(|d| *d <= 8)
                    .ok_or_else(|| FrameError::BadDlc(len.to_string()))?,
            ),
            // `R8_9`: a raw DLC above 8 on a remote frame of 8.
            [b'8', b'_', d] => Some(
                nibble(*d)
                    .filter(|d| *d > 8)
                    .ok_or_else(|| FrameError::BadDlc(len.to_string()))?,
            ),
            _ => return Err(FrameError::BadDlc(len.to_string())),
        };
        return Ok(Frame {
            id,
            extended,
            kind: FrameKind::Remote,
            data: Vec::new(),
            dlc,
        });
    }
    let (data_text, dlc) = match rest.split_once('_') {
        None => (rest, None),
        Some((data_text, dlc)) => (data_text, Some(dlc)),
    };
    let data = parse_data(data_text, 8)?;
    let dlc = match dlc {
        None => None,
        Some(d) => Some(
            match d.as_bytes() {
                [c] if data.len() == 8 => nibble(*c).filter(|v| *v > 8),
                _ => None,
            }
            .ok_or_else(|| FrameError::BadDlc(d.to_string()))?,
        ),
    };
    Ok(Frame {
        id,
        extended,
        kind: FrameKind::Classic,
        data,
        dlc,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_form_candump_writes_reads_back_as_written() {
        for text in [
            "123#",
            "123#DEADBEEF",
            "7FF#0011223344556677",
            "12345678#00",
            "00000000#",
            "1FFFFFFF#FF",
            "123##1DEADBEEF",
            "123##0",
            "123##3",
            "12345678##200112233445566778899AABBCCDDEEFF",
            "123#R",
            "123#R5",
            "123#R0",
            "12345678#R8",
            "123#R8_C",
            "123#0011223344556677_9",
            "123#0011223344556677_F",
            "20000080#0000000000000000",
            "20000004#0004000000000000",
        ] {
            let frame = parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(frame.to_string(), text);
        }
    }

    #[test]
    fn the_forms_mean_what_can_utils_says() {
        let fd = parse("123##3AABB").expect("an FD frame");
        assert_eq!(
            fd.kind,
            FrameKind::Fd {
                brs: true,
                esi: true
            }
        );
        assert_eq!(fd.data, [0xAA, 0xBB]);
        let remote = parse("00000123#R3").expect("a remote frame");
        assert_eq!(
            (remote.id, remote.extended, remote.kind, remote.dlc),
            (0x123, true, FrameKind::Remote, Some(3))
        );
        let err = parse("20000080#0000000000000000").expect("an error frame");
        assert_eq!((err.id, err.kind), (0x80, FrameKind::Error));
        // Dots between bytes are allowed (cansend's form) and are not written back.
        assert_eq!(
            parse("123#11.22.33").map(|f| f.data),
            Ok(vec![0x11, 0x22, 0x33])
        );
        let fd64 = format!("123##1{}", "AB".repeat(64));
        assert_eq!(parse(&fd64).map(|f| f.data.len()), Ok(64));
    }

    #[test]
    fn malformed_frames_are_named() {
        use FrameError as E;
        let cases: [(&str, FrameError); 16] = [
            ("123", E::NoSeparator("123".into())),
            ("12#00", E::BadId("12".into())),
            ("1234#00", E::BadId("1234".into())),
            ("800#00", E::IdOutOfRange("800".into())),
            ("40000000#00", E::IdOutOfRange("40000000".into())),
            ("12G#00", E::BadId("12G".into())),
            ("123#0", E::BadData("0".into())),
            ("123#0é", E::BadData("0é".into())),
            ("123#+F", E::BadData("+F".into())),
            ("123#1.122", E::BadData("1.122".into())),
            ("123#001122334455667788", E::TooLong { len: 9, max: 8 }),
            ("123##1001122334455667788", E::FdLength(9)),
            ("123##G00", E::BadData("G00".into())),
            ("123#R9", E::BadDlc("9".into())),
            ("123#00_9", E::BadDlc("9".into())),
            ("123#0011223344556677_8", E::BadDlc("8".into())),
        ];
        for (text, want) in cases {
            assert_eq!(parse(text), Err(want), "{text}");
        }
    }

    #[test]
    fn any_text_is_a_frame_that_prints_back_or_an_error() {
        bolero::check!().with_type::<String>().for_each(|text| {
            if let Ok(frame) = parse(text) {
                let again = parse(&frame.to_string());
                assert_eq!(again.as_ref(), Ok(&frame), "{text}");
            }
        });
    }

    #[test]
    fn any_frame_round_trips_through_its_text() {
        bolero::check!()
            .with_type::<(u32, bool, u8, Vec<u8>, u8)>()
            .for_each(|(id, extended, kind, data, dlc)| {
                let id = if *extended {
                    id & 0x1FFF_FFFF
                } else {
                    id & 0x7FF
                };
                let mut data = data.clone();
                let frame = match kind % 4 {
                    0 => {
                        data.truncate(8);
                        let dlc = (data.len() == 8 && *dlc > 8 && *dlc <= 15).then_some(*dlc);
                        Frame {
                            dlc,
                            ..Frame::classic(id, *extended, &data)
                        }
                    }
                    1 => {
                        let len = FD_LENGTHS.iter().rev().find(|l| **l <= data.len());
                        data.truncate(len.copied().unwrap_or(0));
                        Frame {
                            kind: FrameKind::Fd {
                                brs: dlc & 1 != 0,
                                esi: dlc & 2 != 0,
                            },
                            ..Frame::classic(id, *extended, &data)
                        }
                    }
                    2 => Frame {
                        kind: FrameKind::Remote,
                        dlc: (*dlc <= 15).then_some(*dlc),
                        ..Frame::classic(id, *extended, &[])
                    },
                    _ => {
                        data.truncate(8);
                        Frame {
                            kind: FrameKind::Error,
                            extended: false,
                            ..Frame::classic(id, false, &data)
                        }
                    }
                };
                assert_eq!(parse(&frame.to_string()), Ok(frame));
            });
    }
}
