//! How long a classic CAN data frame occupies the bus (ISO 11898-1), in bits.
//!
//! Unstuffed lengths, SOF through end of frame:
//!
//! | part | standard (11-bit id) | extended (29-bit id) |
//! |---|---|---|
//! | SOF, arbitration, control | 1 + 11 + 1 (RTR) + 1 (IDE) + 1 (r0) + 4 (DLC) = 19 | 1 + 11 + 1 (SRR) + 1 (IDE) + 18 + 1 (RTR) + 2 (r1, r0) + 4 = 39 |
//! | data | 8 x DLC | 8 x DLC |
//! | CRC | 15 | 15 |
//! | CRC delimiter, ACK slot, ACK delimiter, EOF | 1 + 1 + 1 + 7 = 10 | 10 |
//! | **total** | **44 + 8 x DLC** | **64 + 8 x DLC** |
//!
//! followed by 3 bits of intermission before the next SOF (so 47 + 8 x DLC bits per
//! standard frame on a saturated bus, before stuffing).
//!
//! Bit stuffing (a complement bit after five equal bits) applies from SOF to the end of
//! the CRC. [`Stuffing::Exact`] (the default) builds that bit sequence, computes the real
//! CRC-15 and counts the stuff bits the frame really gets, so the bus timing matches a
//! logic analyser trace. [`Stuffing::WorstCase`] uses the bound `floor((g + 8 x DLC - 1) /
//! 4)` with `g` = 34 (standard) or 54 (extended) stuffable header and CRC bits, the figure
//! used by schedulability analysis: at most 135 bits for a standard 8-byte frame with
//! intermission, 160 for an extended one.
//!
//! A failed attempt (an error detected by the transmitter, modelled at the ACK slot, as
//! for a missing acknowledgement) occupies the bus up to and including the ACK slot, then
//! an error frame of 6 flag + 8 delimiter bits, then the intermission.

use super::CanFrame;

/// Recessive bits between two frames.
pub const INTERMISSION_BITS: u32 = 3;
/// Error flag (6) plus error delimiter (8).
pub const ERROR_FRAME_BITS: u32 = 14;
/// Extra bits an error-passive transmitter waits after its own transmission.
pub const SUSPEND_TRANSMISSION_BITS: u32 = 8;
/// Bus-off recovery: 128 occurrences of 11 consecutive recessive bits.
pub const BUS_OFF_RECOVERY_BITS: u32 = 128 * 11;

/// How stuff bits are counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Stuffing {
    /// The stuff bits the frame really gets (real CRC, real bit pattern).
    #[default]
    Exact,
    /// The worst case for the frame's id format and length.
    WorstCase,
}

/// CAN CRC-15 generator polynomial (x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1).
const CRC15_POLY: u16 = 0x4599;

/// Bits of a frame from SOF to the end of the CRC, before stuffing (at most 54 + 64 = 118).
struct StuffableBits {
    bits: [bool; 118],
    len: usize,
}

impl StuffableBits {
    fn push(&mut self, value: u32, width: u32) {
        for i in (0..width).rev() {
            if let Some(slot) = self.bits.get_mut(self.len) {
                *slot = (value >> i) & 1 == 1;
                self.len += 1;
            }
        }
    }

    fn of(frame: &CanFrame) -> Self {
        let mut s = Self {
            bits: [false; 118],
            len: 0,
        };
        let id = frame.can_id();
        let dlc = u32::from(frame.len());
        s.push(0, 1); // SOF, dominant
        if id.is_extended() {
            s.push(id.raw() >> 18, 11); // base id
            s.push(0b11, 2); // SRR, IDE: recessive
            s.push(id.raw() & 0x3_FFFF, 18);
            s.push(0, 3); // RTR (data frame), r1, r0
        } else {
            s.push(id.raw(), 11);
            s.push(0, 3); // RTR (data frame), IDE (standard), r0
        }
        s.push(dlc, 4);
        for &byte in frame.bytes() {
            s.push(u32::from(byte), 8);
        }
        let crc = crc15(&s.bits[..s.len]);
        s.push(u32::from(crc), 15);
        s
    }
}

/// The CAN CRC-15 over a bit sequence (most significant bit first, initial value 0).
pub fn crc15(bits: &[bool]) -> u16 {
    let mut crc: u16 = 0;
    for &bit in bits {
        let feedback = bit ^ ((crc >> 14) & 1 == 1);
        crc = (crc << 1) & 0x7FFF;
        if feedback {
            crc ^= CRC15_POLY;
        }
    }
    crc
}

/// Number of stuff bits the transmitter inserts into `bits` (after every run of five
/// equal bits, a complement bit, which itself starts the next run).
fn count_stuff_bits(bits: &[bool]) -> u32 {
    let mut stuffed = 0;
    let mut last = None;
    let mut run = 0;
    for &bit in bits {
        if Some(bit) == last {
            run += 1;
        } else {
            last = Some(bit);
            run = 1;
        }
        if run == 5 {
            stuffed += 1;
            last = Some(!bit);
            run = 1;
        }
    }
    stuffed
}

/// Stuffable bits before stuffing (SOF through CRC).
fn stuffable_len(frame: &CanFrame) -> u32 {
    let header = if frame.can_id().is_extended() { 54 } else { 34 };
    header + 8 * u32::from(frame.len())
}

/// The stuff bits `frame` gets under `stuffing`.
pub fn stuff_bits(frame: &CanFrame, stuffing: Stuffing) -> u32 {
    match stuffing {
        Stuffing::Exact => {
            let s = StuffableBits::of(frame);
            count_stuff_bits(&s.bits[..s.len])
        }
        Stuffing::WorstCase => (stuffable_len(frame) - 1) / 4,
    }
}

/// Bits from SOF through the end of EOF, stuff bits included, intermission excluded.
pub fn frame_bits(frame: &CanFrame, stuffing: Stuffing) -> u32 {
    // CRC delimiter, ACK slot, ACK delimiter, 7 EOF bits.
    stuffable_len(frame) + stuff_bits(frame, stuffing) + 10
}

/// Bits a failed attempt occupies, from SOF to the end of the error delimiter
/// (intermission excluded): the frame up to the ACK slot, then the error frame.
pub fn failed_attempt_bits(frame: &CanFrame, stuffing: Stuffing) -> u32 {
    // CRC delimiter and ACK slot, then error flag and delimiter.
    stuffable_len(frame) + stuff_bits(frame, stuffing) + 2 + ERROR_FRAME_BITS
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use crate::can::CanId;

    fn frame(id: CanId, data: &[u8]) -> CanFrame {
        match CanFrame::from_parts(id, data) {
            Some(f) => f,
            None => panic!("bad test frame"),
        }
    }

    fn std_id(raw: u16) -> CanId {
        CanId::standard(raw).unwrap_or_else(|| panic!("bad id"))
    }

    fn ext_id(raw: u32) -> CanId {
        CanId::extended(raw).unwrap_or_else(|| panic!("bad id"))
    }

    #[test]
    fn unstuffed_lengths_follow_the_frame_format() {
        // With worst-case stuffing removed, 44 + 8n and 64 + 8n.
        for n in 0..=8u32 {
            let data = [0x55u8; 8];
            let s = frame(std_id(0x100), &data[..n as usize]);
            let e = frame(ext_id(0x100), &data[..n as usize]);
            assert_eq!(
                frame_bits(&s, Stuffing::WorstCase) - stuff_bits(&s, Stuffing::WorstCase),
                44 + 8 * n
            );
            assert_eq!(
                frame_bits(&e, Stuffing::WorstCase) - stuff_bits(&e, Stuffing::WorstCase),
                64 + 8 * n
            );
        }
    }

    #[test]
    fn worst_case_matches_the_textbook_maxima() {
        // 135 and 160 bits per 8-byte frame including the intermission.
        let s = frame(std_id(0x7FF), &[0; 8]);
        let e = frame(ext_id(0x1FFF_FFFF), &[0; 8]);
        assert_eq!(frame_bits(&s, Stuffing::WorstCase) + INTERMISSION_BITS, 135);
        assert_eq!(frame_bits(&e, Stuffing::WorstCase) + INTERMISSION_BITS, 160);
        let empty = frame(std_id(0), &[]);
        assert_eq!(frame_bits(&empty, Stuffing::WorstCase), 44 + 8);
    }

    #[test]
    fn exact_stuffing_of_an_all_dominant_frame() {
        // Id 0, DLC 0: SOF..DLC is 19 zeros and the CRC of zeros is 0, so 34 zeros: a stuff
        // bit after every fifth, 6 in all.
        let f = frame(std_id(0), &[]);
        assert_eq!(stuff_bits(&f, Stuffing::Exact), 6);
        assert_eq!(frame_bits(&f, Stuffing::Exact), 50);
        assert_eq!(failed_attempt_bits(&f, Stuffing::Exact), 34 + 6 + 2 + 14);
    }

    #[test]
    fn exact_stuffing_never_exceeds_the_worst_case() {
        let ids = [
            std_id(0),
            std_id(0x7FF),
            std_id(0x123),
            ext_id(0),
            ext_id(0x1FFF_FFFF),
        ];
        let payloads: [&[u8]; 5] = [&[], &[0; 8], &[0xFF; 8], &[0x0F, 0xF0, 0x0F], &[0xAA; 5]];
        for id in ids {
            for data in payloads {
                let f = frame(id, data);
                assert!(stuff_bits(&f, Stuffing::Exact) <= stuff_bits(&f, Stuffing::WorstCase));
            }
        }
        // Alternating bits are never stuffed in the data field.
        let f = frame(std_id(0x555), &[0x55; 8]);
        assert!(stuff_bits(&f, Stuffing::Exact) < 6);
    }

    #[test]
    fn stuffing_counts_runs_across_stuff_bits() {
        assert_eq!(count_stuff_bits(&[false; 5]), 1);
        assert_eq!(count_stuff_bits(&[false; 4]), 0);
        // 00000 (stuff 1) 1111: the stuff bit plus four ones is another run of five.
        let mut bits = [false; 9];
        bits[5..].fill(true);
        assert_eq!(count_stuff_bits(&bits), 2);
    }

    #[test]
    fn crc15_detects_a_single_bit_change() {
        let a = [true, false, true, true, false, false, true];
        let mut b = a;
        b[3] = false;
        assert_ne!(crc15(&a), crc15(&b));
        assert_eq!(crc15(&[false; 20]), 0);
        assert!(crc15(&a) <= 0x7FFF);
    }

    #[test]
    fn crc15_matches_the_catalogue_check_value() {
        // CRC-15/CAN of the ASCII "123456789" is 0x059E (Greg Cook's CRC catalogue).
        let bits: std::vec::Vec<bool> = b"123456789"
            .iter()
            .flat_map(|&byte| (0..8).rev().map(move |i| (byte >> i) & 1 == 1))
            .collect();
        assert_eq!(crc15(&bits), 0x059E);
    }
}
