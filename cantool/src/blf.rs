//! Vector BLF logs (binary), as CANoe, CANalyzer and python-can's `BLFWriter` write them.
//!
//! No official specification is published; the layout here is the one python-can's
//! `BLFReader` reads (after Toby Lorenz' Vector BLF library), all little-endian:
//!
//! - a file header: `LOGG`, its size (at byte 4), ..., the measurement's start as a
//!   Windows `SYSTEMTIME` (8 `u16`: year, month, weekday, day, hour, minute, second,
//!   millisecond; UTC) at byte 40;
//! - then objects, each `LOBJ`, header size `u16`, header version `u16`, object size `u32`,
//!   object type `u32`, followed by `object size % 4` padding bytes. At the top level the
//!   objects are log containers (type 10): compression method `u16` (0 none, 2 zlib), 6
//!   bytes, uncompressed size `u32`, 4 bytes, then the data;
//! - the containers' data, joined, is again a sequence of objects (an object may continue
//!   in the next container), each with a second header (version 1: flags `u32`, client
//!   `u16`, version `u16`, time stamp `u64`; version 2: flags `u32`, status `u8`, 1 byte,
//!   version `u16`, time stamp `u64`, 8 bytes); flags 1 means the time stamp counts 10 us,
//!   else ns, from the start;
//! - CAN objects: message (1, and 86): channel `u16`, flags `u8` (0x80 remote, 0x01 Tx),
//!   DLC `u8`, id `u32` (bit 31: 29-bit), 8 data bytes; error frame (73): channel `u16`,
//!   length `u16`, flags `u32`, ecc, position, DLC `u8`, 1 byte, frame length `u32`, id
//!   `u32`, flags `u16`, 2 bytes, 8 data bytes; FD message (100): channel `u16`, flags
//!   `u8`, DLC `u8`, id `u32`, frame length `u32`, bit count `u8`, FD flags `u8` (EDL 1,
//!   BRS 2, ESI 4), valid data bytes `u8`, 5 bytes, 64 data bytes; FD message 64 (101):
//!   channel, DLC, valid data bytes, tx count (`u8` each), id `u32`, frame length `u32`,
//!   flags `u32` (0x10 remote, 0x1000 FD, 0x2000 BRS, 0x4000 ESI), 4 more `u32`, bit count
//!   `u16`, direction `u8`, extended data offset `u8`, CRC `u32`, then the data.
//!
//! Other objects are skipped, as python-can skips them. Time stamps are the start plus the
//! object's offset, computed as python-can computes them. A file that is truncated or
//! corrupt is an error naming the byte offset of the container (and the object's place in
//! its data), never a panic; the objects before it are still read.

use crate::frame::{Frame, FrameKind, FD_LENGTHS};
use crate::log::{At, Entry, LineError};

const FILE_HEADER_MIN: usize = 72;
const OBJ_HEADER: usize = 16;
const LOG_CONTAINER: u32 = 10;
const CAN_MESSAGE: u32 = 1;
const CAN_ERROR_EXT: u32 = 73;
const CAN_MESSAGE2: u32 = 86;
const CAN_FD_MESSAGE: u32 = 100;
const CAN_FD_MESSAGE_64: u32 = 101;
/// Largest container data accepted (Vector's and python-can's hold 128 KiB).
const MAX_CONTAINER: usize = 64 << 20;

fn u16_at(data: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(data.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(data: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(data.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(data: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(data.get(at..at + 8)?.try_into().ok()?))
}

/// Days from 1970-01-01 to a date of the proleptic Gregorian calendar.
fn days_from_civil(year: i64, month: i64, day: i64) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// A `SYSTEMTIME` (UTC) as Unix seconds; 0 when it is no valid date (as python-can).
pub fn systemtime_to_unix(st: [u16; 8]) -> f64 {
    let [year, month, _, day, hour, minute, second, ms] = st.map(i64::from);
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    let days_in_month = match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => 0,
    };
    if !(1..=9999).contains(&year)
        || !(1..=days_in_month).contains(&day)
        || hour > 23
        || minute > 59
        || second > 59
        || ms > 999
    {
        return 0.0;
    }
    let secs = days_from_civil(year, month, day) * 86_400 + hour * 3600 + minute * 60 + second;
    // python-can: datetime(...).timestamp(), whole seconds plus the microseconds / 1e6.
    secs as f64 + (ms * 1000) as f64 / 1e6
}

/// The entries of a BLF file held in memory.
pub struct BlfReader {
    file: Vec<u8>,
    /// The next top-level object.
    pos: usize,
    start: f64,
    /// Joined container data not read yet, and where in it the next object is.
    data: Vec<u8>,
    at: usize,
    /// File offset of the container that gave the data at `at`.
    container: usize,
    done: bool,
}

impl BlfReader {
    /// Reads a BLF file's header.
    ///
    /// # Errors
    /// A file that does not start with a BLF header.
    pub fn new(file: Vec<u8>) -> Result<Self, LineError> {
        let bad = |what: &str| LineError {
            at: At::Byte(0),
            what: what.into(),
        };
        if file.get(..4) != Some(b"LOGG") {
            return Err(bad("not a BLF file (no LOGG signature)"));
        }
        let size = u32_at(&file, 4).map_or(0, |s| s as usize);
        if size < FILE_HEADER_MIN || size > file.len() {
            return Err(bad(&format!(
                "file header of {size} bytes in a file of {}",
                file.len()
            )));
        }
        let mut st = [0u16; 8];
        for (i, v) in st.iter_mut().enumerate() {
            *v = u16_at(&file, 40 + 2 * i).unwrap_or(0);
        }
        Ok(Self {
            pos: size,
            start: systemtime_to_unix(st),
            file,
            data: Vec::new(),
            at: 0,
            container: 0,
            done: false,
        })
    }

    /// The file offset of the container the last entry came from.
    pub fn container(&self) -> usize {
        self.container
    }

    /// The measurement's start (Unix seconds; 0 if the file does not say).
    pub fn start(&self) -> f64 {
        self.start
    }

    fn fail(&mut self, at: usize, what: String) -> Option<Result<Entry, LineError>> {
        self.done = true;
        Some(Err(LineError {
            at: At::Byte(at as u64),
            what,
        }))
    }

    /// Loads the next container's data after what is left; `Ok(false)` at the end.
    fn next_container(&mut self) -> Result<bool, (usize, String)> {
        loop {
            let pos = self.pos;
            let Some(rest) = self.file.get(pos..).filter(|r| !r.is_empty()) else {
                return Ok(false);
            };
            if rest.len() < OBJ_HEADER || rest.get(..4) != Some(b"LOBJ") {
                return Err((
                    pos,
                    "no LOBJ object here: the file is truncated or corrupt".into(),
                ));
            }
            let size = u32_at(rest, 8).map_or(0, |s| s as usize);
            let kind = u32_at(rest, 12).unwrap_or(0);
            if size < OBJ_HEADER || size > rest.len() {
                return Err((
                    pos,
                    format!("object of {size} bytes, {} left in the file", rest.len()),
                ));
            }
            self.pos = pos + size + size % 4;
            if kind != LOG_CONTAINER {
                continue;
            }
            let body = rest.get(OBJ_HEADER..size).unwrap_or(&[]);
            let method = u16_at(body, 0).ok_or((pos, "container header cut short".into()))?;
            let declared = u32_at(body, 8).ok_or((pos, "container header cut short".into()))?;
            let packed = body.get(16..).unwrap_or(&[]);
            let unpacked = match method {
                0 => packed.to_vec(),
                2 => miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(
                    packed,
                    (declared as usize).min(MAX_CONTAINER),
                )
                .map_err(|e| {
                    (
                        pos,
                        format!("container data does not inflate: {:?}", e.status),
                    )
                })?,
                m => return Err((pos, format!("unknown compression method {m}"))),
            };
            self.data.drain(..self.at.min(self.data.len()));
            self.data.extend_from_slice(&unpacked);
            self.at = 0;
            self.container = pos;
            return Ok(true);
        }
    }
}

/// One object of the containers' data: its frame, `Ok(None)` for an object that is no
/// frame, or what is wrong with it.
fn object(obj: &[u8], start: f64) -> Result<Option<(f64, String, Frame)>, String> {
    let version = u16_at(obj, 6).unwrap_or(0);
    let kind = u32_at(obj, 12).unwrap_or(0);
    let (flags, stamp, payload) = match version {
        1 => (u32_at(obj, 16), u64_at(obj, 24), 32),
        2 => (u32_at(obj, 16), u64_at(obj, 24), 40),
        _ => return Ok(None),
    };
    let (Some(flags), Some(stamp)) = (flags, stamp) else {
        return Err(format!("object header of version {version} cut short"));
    };
    let time = start
        + if flags == 1 {
            stamp as f64 / 1e5
        } else {
            stamp as f64 / 1e9
        };
    let p = obj.get(payload..).unwrap_or(&[]);
    let short = || format!("object of type {kind} too short ({} bytes)", obj.len());
    let id_of = |raw: u32| (raw & 0x1FFF_FFFF, raw & 0x8000_0000 != 0);
    let frame = match kind {
        CAN_MESSAGE | CAN_MESSAGE2 => {
            let channel = u16_at(p, 0).ok_or_else(short)?;
            let flags = *p.get(2).ok_or_else(short)?;
            let dlc = *p.get(3).ok_or_else(short)?;
            let (id, extended) = id_of(u32_at(p, 4).ok_or_else(short)?);
            let bytes = p.get(8..16).ok_or_else(short)?;
            check_dlc(dlc)?;
            let frame = if flags & 0x80 != 0 {
                Frame {
                    kind: FrameKind::Remote,
                    dlc: Some(dlc),
                    ..Frame::classic(id, extended, &[])
                }
            } else {
                Frame {
                    dlc: (dlc > 8).then_some(dlc),
                    ..Frame::classic(
                        id,
                        extended,
                        bytes.get(..usize::from(dlc.min(8))).unwrap_or(&[]),
                    )
                }
            };
            (channel, frame)
        }
        CAN_ERROR_EXT => {
            let channel = u16_at(p, 0).ok_or_else(short)?;
            let dlc = *p.get(10).ok_or_else(short)?;
            let (id, extended) = id_of(u32_at(p, 16).ok_or_else(short)?);
            let bytes = p.get(24..32).ok_or_else(short)?;
            check_dlc(dlc)?;
            let data = bytes.get(..usize::from(dlc.min(8))).unwrap_or(&[]);
            (
                channel,
                Frame {
                    kind: FrameKind::Error,
                    ..Frame::classic(id, extended, data)
                },
            )
        }
        CAN_FD_MESSAGE => {
            let channel = u16_at(p, 0).ok_or_else(short)?;
            let flags = *p.get(2).ok_or_else(short)?;
            let dlc = *p.get(3).ok_or_else(short)?;
            let (id, extended) = id_of(u32_at(p, 4).ok_or_else(short)?);
            let fd_flags = *p.get(13).ok_or_else(short)?;
            let valid = usize::from(*p.get(14).ok_or_else(short)?);
            let bytes = p.get(20..84).ok_or_else(short)?;
            check_dlc(dlc)?;
            let fd = fd_flags & 1 != 0;
            let frame = fd_frame(
                id,
                extended,
                flags & 0x80 != 0,
                fd.then_some((fd_flags & 2 != 0, fd_flags & 4 != 0)),
                dlc,
                bytes
                    .get(..valid)
                    .ok_or(format!("{valid} valid data bytes of 64"))?,
            )?;
            (channel, frame)
        }
        CAN_FD_MESSAGE_64 => {
            let channel = u16::from(*p.first().ok_or_else(short)?);
            let dlc = *p.get(1).ok_or_else(short)?;
            let valid = usize::from(*p.get(2).ok_or_else(short)?);
            let (id, extended) = id_of(u32_at(p, 4).ok_or_else(short)?);
            let fd_flags = u32_at(p, 12).ok_or_else(short)?;
            let ext_offset = usize::from(*p.get(35).ok_or_else(short)?);
            check_dlc(dlc)?;
            // python-can (its issue 1905): the data may be shorter than `valid`; it is
            // padded with zeros, as CANoe does.
            let header = usize::from(u16_at(obj, 4).unwrap_or(0));
            let end = if ext_offset == 0 {
                obj.len()
            } else {
                ext_offset
            };
            let field = valid.min(end.saturating_sub(header + 40));
            let mut data = p.get(40..40 + field).unwrap_or(&[]).to_vec();
            data.resize(valid, 0);
            let fd = fd_flags & 0x1000 != 0;
            let frame = fd_frame(
                id,
                extended,
                fd_flags & 0x10 != 0,
                fd.then_some((fd_flags & 0x2000 != 0, fd_flags & 0x4000 != 0)),
                dlc,
                &data,
            )?;
            (channel, frame)
        }
        _ => return Ok(None),
    };
    Ok(Some((time, frame.0.to_string(), frame.1)))
}

fn check_dlc(dlc: u8) -> Result<(), String> {
    if dlc > 15 {
        Err(format!("DLC {dlc} (at most 15)"))
    } else {
        Ok(())
    }
}

fn fd_frame(
    id: u32,
    extended: bool,
    remote: bool,
    fd: Option<(bool, bool)>,
    dlc: u8,
    data: &[u8],
) -> Result<Frame, String> {
    let frame = Frame::classic(id, extended, &[]);
    Ok(match (remote, fd) {
        (true, _) => Frame {
            kind: FrameKind::Remote,
            dlc: Some(dlc),
            ..frame
        },
        (false, Some((brs, esi))) => {
            if !FD_LENGTHS.contains(&data.len()) {
                return Err(format!("{} data bytes: no FD length", data.len()));
            }
            Frame {
                kind: FrameKind::Fd { brs, esi },
                data: data.to_vec(),
                ..frame
            }
        }
        (false, None) => {
            if data.len() > 8 {
                return Err(format!("{} data bytes in a classic frame", data.len()));
            }
            Frame {
                data: data.to_vec(),
                dlc: (dlc > 8 && data.len() == 8).then_some(dlc),
                ..frame
            }
        }
    })
}

impl Iterator for BlfReader {
    type Item = Result<Entry, LineError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.done {
                return None;
            }
            // The next object in the data, found as python-can finds it: `LOBJ` within
            // 8 bytes (padding differs between writers).
            let window = self.data.get(self.at..).unwrap_or(&[]);
            let found = window.windows(4).take(5).position(|w| w == b"LOBJ");
            let (window_len, pending) = (window.len(), window.iter().any(|b| *b != 0));
            let complete = found.and_then(|skip| {
                let obj = window.get(skip..)?;
                let size = u32_at(obj, 8)? as usize;
                (obj.len() >= size).then_some((skip, size))
            });
            match (found, complete) {
                (_, Some((skip, size))) => {
                    let obj_at = self.at + skip;
                    self.at = obj_at + size.max(OBJ_HEADER);
                    let obj = self.data.get(obj_at..obj_at + size).unwrap_or(&[]);
                    if size < OBJ_HEADER {
                        let container = self.container;
                        return self.fail(
                            container,
                            format!(
                                "object of {size} bytes at byte {obj_at} of the container data"
                            ),
                        );
                    }
                    match object(obj, self.start) {
                        Ok(None) => continue,
                        Ok(Some((timestamp, channel, frame))) => {
                            return Some(Ok(Entry {
                                timestamp,
                                channel,
                                frame,
                            }))
                        }
                        Err(what) => {
                            return Some(Err(LineError {
                                at: At::Byte(self.container as u64),
                                what: format!(
                                    "object at byte {obj_at} of the container data: {what}"
                                ),
                            }))
                        }
                    }
                }
                (None, None) if window_len >= 8 => {
                    let container = self.container;
                    let at = self.at;
                    return self.fail(
                        container,
                        format!("no LOBJ object at byte {at} of the container data"),
                    );
                }
                // The object continues in the next container (or is cut off).
                _ => match self.next_container() {
                    Ok(true) => continue,
                    Ok(false) => {
                        let left = self.data.len().saturating_sub(self.at);
                        if left > 0 && pending {
                            let container = self.container;
                            return self.fail(
                                container,
                                format!("the file ends inside an object ({left} bytes of it)"),
                            );
                        }
                        return None;
                    }
                    Err((at, what)) => return self.fail(at, what),
                },
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn systemtime_is_unix_time_in_utc() {
        assert_eq!(systemtime_to_unix([1970, 1, 4, 1, 0, 0, 0, 0]), 0.0);
        assert_eq!(
            systemtime_to_unix([2026, 11, 2, 24, 12, 30, 15, 250]),
            1_795_523_415.25
        );
        assert_eq!(
            systemtime_to_unix([2024, 2, 4, 29, 0, 0, 0, 0]),
            1_709_164_800.0
        );
        assert_eq!(systemtime_to_unix([2023, 2, 2, 29, 0, 0, 0, 0]), 0.0);
        assert_eq!(systemtime_to_unix([0; 8]), 0.0);
    }

    #[test]
    fn what_is_not_blf_is_named() {
        assert!(BlfReader::new(b"LOGX".to_vec()).is_err());
        assert!(BlfReader::new(Vec::new()).is_err());
        let mut header = b"LOGG".to_vec();
        header.extend_from_slice(&200u32.to_le_bytes());
        assert!(BlfReader::new(header).is_err_and(|e| e.what.contains("file header of 200")));
    }

    #[test]
    fn any_bytes_after_a_header_are_entries_or_named_errors() {
        bolero::check!().with_type::<Vec<u8>>().for_each(|bytes| {
            let mut file = b"LOGG".to_vec();
            file.extend_from_slice(&144u32.to_le_bytes());
            file.resize(144, 0);
            file.extend_from_slice(bytes);
            let Ok(reader) = BlfReader::new(file) else {
                panic!("the header is valid")
            };
            for item in reader.take(10_000) {
                if let Err(e) = item {
                    assert!(matches!(e.at, At::Byte(_)));
                }
            }
        });
    }
}
