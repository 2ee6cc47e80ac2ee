//! The UART output of the common waterproof ultrasonic modules (A02YYUW, JSN-SR04T in
//! UART mode, ME007YS): 9600 baud, 8N1, one frame per measurement, every 100 ms
//! ("real-time" output) to 300 ms ("processed" output):
//!
//! | byte | value |
//! |---|---|
//! | 0 | header `0xFF` |
//! | 1 | distance, mm, high byte |
//! | 2 | distance, mm, low byte |
//! | 3 | checksum: the low 8 bits of the sum of bytes 0 to 2 |
//!
//! The protocol has no escaping: `0xFF` may appear in any data byte. [`Decoder`] hunts
//! for a header, takes the three bytes after it and checks the sum. A frame whose sum is
//! wrong is a [`Frame::BadChecksum`], and the hunt resumes at the first `0xFF` *inside*
//! it, so a byte lost on the wire costs the frame it was lost from, not the good frame
//! after it. Bytes that neither start a candidate frame nor end in a good one (line
//! noise, and the data bytes of a bad frame that hold no header) are counted as stray. The decoder is
//! exactly the batch rule of [`spec::reference`] run on the whole stream
//! ([`spec::matches_reference`]).
//!
//! [`Ranger`] turns the byte stream into one sample per run of the sensor task, which
//! samples faster than the module sends: the newest frame decides; a bad checksum or a
//! distance inside the module's blind zone is a bad sample ([`Measurement::Invalid`]);
//! between frames the last good distance stands, until the module has been silent for
//! the configured number of samples, after which every sample is invalid.

use super::SonarConfig;
use crate::warning::Measurement;

/// The first byte of every frame.
pub const HEADER: u8 = 0xFF;
/// Bytes in a frame.
pub const FRAME_LEN: usize = 4;
/// Closer than this the module cannot measure (A02YYUW: 3 cm); a reading below it is not
/// a distance.
pub const BLIND_ZONE_MM: u16 = 30;
/// The modules' line rate, baud (8N1: one byte takes 10 bit times).
pub const BAUD: u32 = 9600;

/// The checksum of a frame carrying `distance_mm`.
pub const fn checksum(distance_mm: u16) -> u8 {
    let [hi, lo] = distance_mm.to_be_bytes();
    HEADER.wrapping_add(hi).wrapping_add(lo)
}

/// The frame a module sends for `distance_mm`.
pub const fn encode(distance_mm: u16) -> [u8; FRAME_LEN] {
    let [hi, lo] = distance_mm.to_be_bytes();
    [HEADER, hi, lo, checksum(distance_mm)]
}

/// A frame's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Frame {
    /// A frame whose checksum holds.
    Distance {
        /// The distance it carries, mm.
        mm: u16,
    },
    /// A header and three bytes whose checksum does not hold.
    BadChecksum,
}

/// The streaming frame decoder: one byte at a time, from any starting point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decoder {
    /// The candidate frame's data bytes so far. Its header is not kept: a candidate
    /// always starts with one.
    data: [u8; 2],
    /// Bytes of the candidate, its header included (0: hunting for a header).
    len: u8,
    /// Bytes that neither started a candidate nor ended in a good frame.
    stray: u32,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder hunting for a header.
    pub const fn new() -> Self {
        Self {
            data: [0; 2],
            len: 0,
            stray: 0,
        }
    }

    /// Bytes since start that neither started a candidate frame nor ended in a good
    /// one.
    pub const fn stray_bytes(&self) -> u32 {
        self.stray
    }

    /// Bytes of an unfinished candidate frame.
    pub const fn pending(&self) -> usize {
        self.len as usize
    }

    /// Takes one byte; a frame's verdict when `byte` ends a candidate.
    pub fn push(&mut self, byte: u8) -> Option<Frame> {
        let [hi, lo] = self.data;
        match self.len {
            0 => {
                if byte == HEADER {
                    self.len = 1;
                } else {
                    self.stray = self.stray.saturating_add(1);
                }
                None
            }
            1 => {
                self.data[0] = byte;
                self.len = 2;
                None
            }
            2 => {
                self.data[1] = byte;
                self.len = 3;
                None
            }
            _ => {
                let mm = u16::from_be_bytes([hi, lo]);
                if checksum(mm) == byte {
                    self.len = 0;
                    return Some(Frame::Distance { mm });
                }
                // Hunt again from the byte after the bad header: the bytes before the
                // next 0xFF among them were part of no frame, the bytes from it on are
                // the new candidate: that 0xFF is its header and the bytes after it its
                // data (a stale data slot is excluded by `len`). Spelt out rather than
                // searched and copied by iterators, which Kani unwinds into a far larger
                // program.
                let from: u8 = if hi == HEADER {
                    0
                } else if lo == HEADER {
                    1
                } else if byte == HEADER {
                    2
                } else {
                    3
                };
                self.stray = self.stray.saturating_add(u32::from(from));
                match from {
                    0 => self.data = [lo, byte],
                    1 => self.data[0] = byte,
                    _ => {}
                }
                self.len = FRAME_LEN as u8 - 1 - from;
                Some(Frame::BadChecksum)
            }
        }
    }
}

/// What a [`Ranger`] has counted since start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RangerCounts {
    /// Frames with a good checksum (blind-zone readings included).
    pub frames: u32,
    /// Frames with a bad checksum.
    pub bad_checksums: u32,
    /// Good frames whose distance lay in the blind zone.
    pub blind: u32,
    /// Bytes that neither started a candidate frame nor ended in a good one (noise, and
    /// the data bytes of bad frames).
    pub stray_bytes: u32,
    /// Samples taken while the module was silent (no good frame for the configured
    /// number of samples).
    pub silent_samples: u32,
}

/// A UART ranging module sampled by a periodic task: the byte stream in, one
/// [`Measurement`] per sample out (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ranger {
    decoder: Decoder,
    /// The newest good distance outside the blind zone.
    last_good: Option<u16>,
    /// Samples taken since the newest good frame (saturating).
    since_good: u8,
    /// After this many samples without a good frame the module is silent.
    silent_after: u8,
    counts: RangerCounts,
}

impl Ranger {
    /// A ranger that reports the module silent after `silent_after_samples` samples
    /// without a good frame. 0 acts as 1: a sample without a new good frame then never
    /// repeats the last one (the count of samples since the last good frame is at least 1
    /// when it is compared).
    pub const fn new(silent_after_samples: u8) -> Self {
        Self {
            decoder: Decoder::new(),
            last_good: None,
            since_good: u8::MAX,
            silent_after: silent_after_samples,
            counts: RangerCounts {
                frames: 0,
                bad_checksums: 0,
                blind: 0,
                stray_bytes: 0,
                silent_samples: 0,
            },
        }
    }

    /// What it counted.
    pub const fn counts(&self) -> RangerCounts {
        let mut counts = self.counts;
        counts.stray_bytes = self.decoder.stray_bytes();
        counts
    }

    /// One sample: the bytes received since the last one, and the measurement they give
    /// with the ECU's sensor parameters (`config`: its rated range).
    pub fn sample(
        &mut self,
        bytes: impl IntoIterator<Item = u8>,
        config: &SonarConfig,
    ) -> Measurement {
        let mut newest = None;
        for byte in bytes {
            match self.decoder.push(byte) {
                Some(Frame::Distance { mm }) => {
                    self.counts.frames = self.counts.frames.saturating_add(1);
                    if mm < BLIND_ZONE_MM {
                        self.counts.blind = self.counts.blind.saturating_add(1);
                    } else {
                        self.last_good = Some(mm);
                        self.since_good = 0;
                    }
                    newest = Some(Frame::Distance { mm });
                }
                Some(Frame::BadChecksum) => {
                    self.counts.bad_checksums = self.counts.bad_checksums.saturating_add(1);
                    newest = Some(Frame::BadChecksum);
                }
                None => {}
            }
        }
        match newest {
            Some(Frame::Distance { mm }) if mm >= BLIND_ZONE_MM => {
                config.classify_distance(u32::from(mm))
            }
            Some(_) => {
                self.since_good = self.since_good.saturating_add(1);
                Measurement::Invalid
            }
            None => {
                self.since_good = self.since_good.saturating_add(1);
                match self.last_good {
                    Some(mm) if self.since_good < self.silent_after => {
                        config.classify_distance(u32::from(mm))
                    }
                    _ => {
                        self.counts.silent_samples = self.counts.silent_samples.saturating_add(1);
                        Measurement::Invalid
                    }
                }
            }
        }
    }
}

/// Named predicates: the contract of this module.
pub mod spec {
    use super::{checksum, Decoder, Frame, FRAME_LEN, HEADER};

    /// The decoding rule on a whole stream, by index: at a header with three bytes after
    /// it, a frame (good if the sum holds, the next candidate after its fourth byte; bad
    /// otherwise, the next candidate after its header); any other byte is stray; a header
    /// without three bytes after it ends the stream (pending). Calls `verdict(at, frame)`
    /// with the index of the byte that decides each frame, in order, and returns the
    /// stray and pending byte counts.
    pub fn reference(bytes: &[u8], mut verdict: impl FnMut(usize, Frame)) -> (u32, usize) {
        let mut stray = 0u32;
        let mut i = 0usize;
        while let Some(&b) = bytes.get(i) {
            if b != HEADER {
                stray = stray.saturating_add(1);
                i += 1;
                continue;
            }
            let (Some(&hi), Some(&lo), Some(&sum)) =
                (bytes.get(i + 1), bytes.get(i + 2), bytes.get(i + 3))
            else {
                return (stray, bytes.len() - i);
            };
            let mm = u16::from_be_bytes([hi, lo]);
            if checksum(mm) == sum {
                verdict(i + FRAME_LEN - 1, Frame::Distance { mm });
                i += FRAME_LEN;
            } else {
                verdict(i + FRAME_LEN - 1, Frame::BadChecksum);
                i += 1;
            }
        }
        (stray, 0)
    }

    /// The streaming [`Decoder`], fed `bytes` one at a time, gives exactly the verdicts
    /// of [`reference()`], at the same bytes, and the same stray and pending counts.
    pub fn matches_reference(bytes: &[u8]) -> bool {
        let mut decoder = Decoder::new();
        let mut agree = true;
        let (stray, pending) = {
            let mut streamed = bytes
                .iter()
                .enumerate()
                .filter_map(|(at, &b)| decoder.push(b).map(|f| (at, f)));
            let counts = reference(bytes, |at, frame| {
                agree &= streamed.next() == Some((at, frame));
            });
            agree &= streamed.next().is_none();
            counts
        };
        agree && decoder.stray_bytes() == stray && decoder.pending() == pending
    }
}

#[cfg(test)]
mod tests;
