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

/// One bit into the CRC-15 register (the shift register of ISO 11898-1, 10.4.2.6).
const fn crc15_step(crc: u16, bit: bool) -> u16 {
    let feedback = bit != ((crc >> 14) & 1 == 1);
    let crc = (crc << 1) & 0x7FFF;
    if feedback {
        crc ^ CRC15_POLY
    } else {
        crc
    }
}

/// The register after eight zero bits from `i` in its top eight bits: with it, eight
/// bits at once (`crc' = (crc << 8) ^ T[(crc >> 7) ^ byte]`, the CRC being linear).
const CRC15_BYTE: [u16; 256] = {
    let mut table = [0; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u16) << 7;
        let mut k = 0;
        while k < 8 {
            crc = crc15_step(crc, false);
            k += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
};

/// The stuffing state on the wire: the last bit's value (bit 2) and how many equal bits
/// end there, less one (bits 0 and 1: a run of 1 to 4; a fifth gets its stuff bit at
/// once). Before SOF (dominant) it is a recessive run of one, so that SOF starts a run.
const STUFF_START: u8 = 0b100;

/// One bit through the stuffing state: the new state, and whether a stuff bit (the
/// complement, which starts the next run) follows it.
const fn stuff_step(state: u8, bit: bool) -> (u8, bool) {
    let last = state & 0b100 != 0;
    if bit != last {
        return ((bit as u8) << 2, false);
    }
    let run = (state & 0b11) + 2;
    if run == 5 {
        (((!bit) as u8) << 2, true)
    } else {
        (state & 0b100 | (run - 1), false)
    }
}

/// Eight bits at once: for state `s` and byte `b`, at `s * 256 + b`, the new state (bits
/// 0 to 2) and the stuff bits inserted (bits 3 and 4: at most two in eight bits).
const STUFF_BYTE: [u8; 8 * 256] = {
    let mut table = [0; 8 * 256];
    let mut i = 0;
    while i < 8 * 256 {
        let mut state = (i / 256) as u8;
        let mut stuffed = 0;
        let mut k = 0;
        while k < 8 {
            let (next, stuff) = stuff_step(state, (i >> (7 - k)) & 1 == 1);
            state = next;
            stuffed += stuff as u8;
            k += 1;
        }
        table[i] = state | stuffed << 3;
        i += 1;
    }
    table
};

/// A frame's bits from SOF to the end of the CRC before stuffing (at most 54 + 64 = 118),
/// the first in the highest of the `len` low bits of `bits`.
#[derive(Clone, Copy)]
struct StuffableBits {
    bits: u128,
    len: u32,
}

impl StuffableBits {
    fn push(&mut self, value: u32, width: u32) {
        let mask = (1u128 << width) - 1;
        self.bits = (self.bits << width) | (u128::from(value) & mask);
        self.len += width;
    }

    /// The `count` (at most 8) bits after the first `from`, as a number.
    fn field(&self, from: u32, count: u32) -> u32 {
        let shift = self.len - from - count;
        ((self.bits >> shift) & ((1u128 << count) - 1)) as u32
    }

    /// Each bit, its register or state: first bit by bit up to a multiple of eight
    /// from the end, then eight bits at once by `byte`.
    fn fold<S: Copy>(&self, start: S, bit: impl Fn(S, bool) -> S, byte: impl Fn(S, u32) -> S) -> S {
        let head = self.len % 8;
        let mut acc = start;
        for i in 0..head {
            acc = bit(acc, self.field(i, 1) == 1);
        }
        let mut at = head;
        while at < self.len {
            acc = byte(acc, self.field(at, 8));
            at += 8;
        }
        acc
    }

    /// The CRC-15 of the bits so far.
    fn crc15(&self) -> u16 {
        self.fold(0u16, crc15_step, |crc, byte| {
            let index = ((u32::from(crc) >> 7) ^ byte) & 0xFF;
            let entry = CRC15_BYTE.get(index as usize).copied().unwrap_or(0);
            ((crc << 8) & 0x7FFF) ^ entry
        })
    }

    /// The stuff bits the transmitter inserts (after every run of five equal bits, a
    /// complement bit, which itself starts the next run).
    fn stuff_bits(&self) -> u32 {
        let (_, stuffed) = self.fold(
            (STUFF_START, 0u32),
            |(state, n), bit| {
                let (next, stuff) = stuff_step(state, bit);
                (next, n + u32::from(stuff))
            },
            |(state, n), byte| {
                let index = usize::from(state) * 256 + byte as usize;
                let entry = STUFF_BYTE.get(index).copied().unwrap_or(0);
                (entry & 0b111, n + u32::from(entry >> 3))
            },
        );
        stuffed
    }

    fn of(frame: &CanFrame) -> Self {
        let mut s = Self { bits: 0, len: 0 };
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
        let crc = s.crc15();
        s.push(u32::from(crc), 15);
        s
    }
}

/// The CAN CRC-15 over a bit sequence (most significant bit first, initial value 0).
pub fn crc15(bits: &[bool]) -> u16 {
    bits.iter().fold(0, |crc, &bit| crc15_step(crc, bit))
}

/// Stuffable bits before stuffing (SOF through CRC).
fn stuffable_len(frame: &CanFrame) -> u32 {
    let header = if frame.can_id().is_extended() { 54 } else { 34 };
    header + 8 * u32::from(frame.len())
}

/// The stuff bits `frame` gets under `stuffing`.
pub fn stuff_bits(frame: &CanFrame, stuffing: Stuffing) -> u32 {
    match stuffing {
        Stuffing::Exact => StuffableBits::of(frame).stuff_bits(),
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

/// The stuff-bit count's specification: the frame's bits from SOF to the end of the CRC
/// one by one, the CRC-15 bit by bit over them, and the stuffing rule bit by bit. The
/// tables' count must equal it on every frame ([`spec::stuffing_agrees`]: the tests, the
/// `frame_stuffing` fuzz target, a Kani harness).
pub mod spec {
    use super::{crc15, stuff_bits, stuffable_len, StuffableBits, Stuffing};
    use crate::can::CanFrame;

    /// The frame's bits from SOF to the end of the CRC, one by one (at most 118), and how
    /// many there are.
    pub fn bits_one_by_one(frame: &CanFrame) -> ([bool; 118], usize) {
        fn push(bits: &mut [bool; 118], len: &mut usize, value: u32, width: u32) {
            for i in (0..width).rev() {
                if let Some(slot) = bits.get_mut(*len) {
                    *slot = (value >> i) & 1 == 1;
                    *len += 1;
                }
            }
        }
        let (mut bits, mut len) = ([false; 118], 0);
        let id = frame.can_id();
        push(&mut bits, &mut len, 0, 1);
        if id.is_extended() {
            push(&mut bits, &mut len, id.raw() >> 18, 11);
            push(&mut bits, &mut len, 0b11, 2);
            push(&mut bits, &mut len, id.raw() & 0x3_FFFF, 18);
            push(&mut bits, &mut len, 0, 3);
        } else {
            push(&mut bits, &mut len, id.raw(), 11);
            push(&mut bits, &mut len, 0, 3);
        }
        push(&mut bits, &mut len, u32::from(frame.len()), 4);
        for &byte in frame.bytes() {
            push(&mut bits, &mut len, u32::from(byte), 8);
        }
        let crc = crc15(bits.get(..len).unwrap_or(&[]));
        push(&mut bits, &mut len, u32::from(crc), 15);
        (bits, len)
    }

    /// The stuff bits the transmitter inserts into `bits`, one by one: after every run of
    /// five equal bits, a complement bit, which itself starts the next run.
    pub fn count_stuff_bits(bits: &[bool]) -> u32 {
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

    /// The tables' bits (the CRC included) are the frame's bits one by one, and their
    /// stuff-bit count is the count one by one.
    pub fn stuffing_agrees(frame: &CanFrame) -> bool {
        let (bits, len) = bits_one_by_one(frame);
        let Some(bits) = bits.get(..len) else {
            return false;
        };
        let fast = StuffableBits::of(frame);
        len as u32 == stuffable_len(frame)
            && fast.len as usize == len
            && bits
                .iter()
                .enumerate()
                .all(|(i, &bit)| (fast.field(i as u32, 1) == 1) == bit)
            && stuff_bits(frame, Stuffing::Exact) == count_stuff_bits(bits)
    }
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

    fn agrees_with_the_oracle(f: &CanFrame) {
        assert!(spec::stuffing_agrees(f), "{f:?}");
    }

    /// Any frame: the stuff bits counted eight bits at a time (the tables) are those the
    /// bits one by one get, the CRC computed eight bits at a time included.
    #[test]
    #[cfg_attr(kani, kani::proof, kani::unwind(120))]
    fn any_frame_is_stuffed_as_its_bits_one_by_one() {
        bolero::check!()
            .with_type::<(bool, u32, u8, [u8; 8])>()
            .cloned()
            .for_each(|(extended, raw, len, data)| {
                agrees_with_the_oracle(&CanFrame::masked(CanId::masked(raw, extended), len, data));
            });
    }

    /// Every standard identifier with every length, over payloads of runs, alternations
    /// and the identifier's own bits: the same (under Miri, a stride through them).
    #[test]
    fn every_standard_id_and_length_is_stuffed_as_its_bits_one_by_one() {
        let stride = if cfg!(miri) { 1023 } else { 1 };
        for raw in (0..0x800u16).step_by(stride) {
            let [hi, lo] = raw.to_be_bytes();
            for data in [
                [0; 8],
                [0xFF; 8],
                [0x55; 8],
                [hi, lo, !hi, !lo, 0x0F, 0xF0, lo, hi],
            ] {
                for len in 0..=8 {
                    agrees_with_the_oracle(&CanFrame::masked(
                        CanId::masked(raw.into(), false),
                        len,
                        data,
                    ));
                }
            }
        }
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
        assert_eq!(spec::count_stuff_bits(&[false; 5]), 1);
        assert_eq!(spec::count_stuff_bits(&[false; 4]), 0);
        // 00000 (stuff 1) 1111: the stuff bit plus four ones is another run of five.
        let mut bits = [false; 9];
        bits[5..].fill(true);
        assert_eq!(spec::count_stuff_bits(&bits), 2);
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
