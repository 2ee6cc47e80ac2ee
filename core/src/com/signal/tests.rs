//! Harnesses for the signal codec. Each property is stated once in [`check_case`] and
//! driven three ways: exhaustively over every layout of an 8-byte PDU, exhaustively over
//! every value of short signals, and by bolero (random, fuzzing, Kani) for any PDU size.
extern crate std;

use super::spec;
use super::*;

const ORDERS: [ByteOrder; 2] = [ByteOrder::Intel, ByteOrder::Motorola];
const SIGNS: [Signedness; 2] = [Signedness::Unsigned, Signedness::Signed];

/// Small deterministic generator for backgrounds (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn bytes<const N: usize>(&mut self) -> [u8; N] {
        let mut b = [0u8; N];
        for chunk in b.chunks_mut(8) {
            let r = self.next().to_le_bytes();
            chunk.copy_from_slice(&r[..chunk.len()]);
        }
        b
    }
}

/// Every property of one case ([`spec::codec_contract`]); returns whether it was in range.
fn check_case<const N: usize>(layout: &SignalLayout<N>, value: i128, background: &[u8; N]) -> bool {
    match spec::codec_contract(layout, value, background) {
        Ok(in_range) => in_range,
        Err(broken) => panic!("{broken}: {layout:?} value {value} background {background:02x?}"),
    }
}

/// Boundary and pattern values for a signal, plus the first values outside its range.
fn interesting_values(len: u8, sign: Signedness) -> impl Iterator<Item = i128> {
    let (lo, hi) = spec::value_range(len, sign);
    let pattern_a = 0x5555_5555_5555_5555u64 as i128 & ((1i128 << len) - 1);
    let pattern_b = 0xAAAA_AAAA_AAAA_AAAAu64 as i128 & ((1i128 << len) - 1);
    let wrap = |v: i128| {
        if sign == Signedness::Signed && v > hi {
            v - (1i128 << len)
        } else {
            v
        }
    };
    [
        lo,
        lo + 1,
        -1,
        0,
        1,
        hi - 1,
        hi,
        hi / 2,
        wrap(pattern_a),
        wrap(pattern_b),
        lo - 1,
        hi + 1,
    ]
    .into_iter()
    .filter(move |v| (lo - 1..=hi + 1).contains(v))
}

/// Calls `f` with every valid layout of an `N`-byte PDU and checks that validity equals
/// [`spec::layout_fits`] for every candidate, valid or not. Under Miri (about a thousand
/// times slower) a strided subset of start bits and lengths is walked instead.
fn for_every_layout<const N: usize>(mut f: impl FnMut(SignalLayout<N>)) -> (usize, usize) {
    let (mut valid, mut refused) = (0, 0);
    let (start_step, len_step) = if cfg!(miri) { (13, 7) } else { (1, 1) };
    for start in (0..(8 * N as u16 + 8)).step_by(start_step) {
        for len in (0..=65u8).step_by(len_step) {
            for order in ORDERS {
                for sign in SIGNS {
                    let made = SignalLayout::<N>::new(start, len, order, sign);
                    assert_eq!(
                        made.is_ok(),
                        spec::layout_fits(N, start, len, order),
                        "start {start} len {len} {order:?}"
                    );
                    match made {
                        Ok(layout) => {
                            valid += 1;
                            f(layout);
                        }
                        Err(_) => refused += 1,
                    }
                }
            }
        }
    }
    (valid, refused)
}

/// Every layout of an 8-byte PDU (all start bits, lengths, byte orders, signedness) with
/// boundary values on three backgrounds.
#[test]
fn exhaustive_every_layout_of_an_8_byte_pdu() {
    let mut rng = Rng(0x1234_5678_9ABC_DEF1);
    let mut cases = 0u64;
    let (valid, refused) = for_every_layout::<8>(|layout| {
        let backgrounds = [[0u8; 8], [0xFF; 8], rng.bytes::<8>()];
        for value in interesting_values(layout.length_bits(), layout.signedness()) {
            for bg in &backgrounds {
                check_case(&layout, value, bg);
                cases += 1;
                if cfg!(miri) {
                    break;
                }
            }
        }
    });
    // Per byte order and signedness: Intel fits when start + len <= 64, Motorola when
    // len <= msb position + 1; both give sum over start of (positions left) = 64 * 65 / 2.
    if !cfg!(miri) {
        assert_eq!(valid, 4 * 64 * 65 / 2);
    }
    assert!(refused > 0);
    std::println!("8-byte PDU: {valid} layouts, {cases} cases");
}

/// Small and odd PDU sizes, every layout, a few values each.
#[test]
fn exhaustive_every_layout_of_short_and_odd_pdus() {
    fn run<const N: usize>() -> usize {
        let mut rng = Rng(0xDEAD_BEEF ^ N as u64);
        let (valid, _) = for_every_layout::<N>(|layout| {
            let bg = rng.bytes::<N>();
            let (lo, hi) = spec::value_range(layout.length_bits(), layout.signedness());
            for value in [
                lo,
                hi,
                hi + 1,
                (rng.next() as i128).rem_euclid(hi - lo + 1) + lo,
            ] {
                check_case(&layout, value, &bg);
            }
        });
        valid
    }
    if cfg!(miri) {
        run::<1>();
        return;
    }
    assert_eq!(run::<1>(), 4 * 8 * 9 / 2);
    run::<3>();
    run::<12>();
    run::<20>();
}

/// Every value of every signal up to 16 bits long, at representative positions:
/// byte-aligned, unaligned, at the PDU's start and end, crossing byte boundaries.
#[test]
fn exhaustive_every_value_up_to_16_bits() {
    let mut cases = 0u64;
    let max_len = if cfg!(miri) { 4 } else { 16 };
    for len in 1..=max_len {
        let mut starts: std::vec::Vec<(u16, ByteOrder)> = std::vec::Vec::new();
        for s in [0u16, 3, 8, 13, 64 - u16::from(len)] {
            starts.push((s, ByteOrder::Intel));
        }
        // Motorola: MSB at byte 0 bit 7, an unaligned MSB, and the last possible MSB.
        for s in [
            7u16,
            12,
            7 + 8 * ((64 - u16::from(len)) / 8) - (64 - u16::from(len)) % 8,
        ] {
            starts.push((s, ByteOrder::Motorola));
        }
        for (start, order) in starts {
            for sign in SIGNS {
                let Ok(layout) = SignalLayout::<8>::new(start, len, order, sign) else {
                    panic!("representative layout start {start} len {len} {order:?} refused");
                };
                let (lo, hi) = spec::value_range(len, sign);
                let bg = [0xA5u8; 8];
                for value in lo..=hi {
                    check_case(&layout, value, &bg);
                    cases += 1;
                }
            }
        }
    }
    std::println!("every value up to {max_len} bits: {cases} cases");
}

/// The DBC convention, pinned with hand-worked examples.
#[test]
fn dbc_examples() {
    // The paper's distance: 32-bit little-endian unsigned at bit 0.
    let distance = crate::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned);
    let mut pdu = [0u8; 8];
    assert_eq!(distance.pack_u64(&mut pdu, 0x1234_5678), Ok(()));
    assert_eq!(pdu, [0x78, 0x56, 0x34, 0x12, 0, 0, 0, 0]);
    assert_eq!(
        distance.pack_u64(&mut pdu, 1 << 32),
        Err(SignalError::OutOfRange)
    );
    assert_eq!(pdu, [0x78, 0x56, 0x34, 0x12, 0, 0, 0, 0]);

    // Motorola 16-bit with MSB at bit 7 (byte 0 bit 7): bytes 0..2 big-endian.
    let m = crate::signal_layout!(8; 7, 16, ByteOrder::Motorola, Signedness::Unsigned);
    let mut pdu = [0u8; 8];
    assert_eq!(m.pack_u64(&mut pdu, 0xABCD), Ok(()));
    assert_eq!(pdu, [0xAB, 0xCD, 0, 0, 0, 0, 0, 0]);

    // Motorola 12-bit with MSB at bit 3: byte0 bits 3..0 then byte1 bits 7..0.
    let m = crate::signal_layout!(8; 3, 12, ByteOrder::Motorola, Signedness::Signed);
    let mut pdu = [0u8; 8];
    assert_eq!(m.pack_i64(&mut pdu, -2), Ok(()));
    assert_eq!(pdu, [0x0F, 0xFE, 0, 0, 0, 0, 0, 0]);
    assert_eq!(m.unpack(&pdu), SignalValue::Signed(-2));

    // A Motorola signal whose LSB would fall past the end is refused.
    assert_eq!(
        SignalLayout::<8>::new(56 + 3, 5, ByteOrder::Motorola, Signedness::Unsigned),
        Err(LayoutError::OutsidePdu {
            start_bit: 59,
            length_bits: 5
        })
    );
    assert_eq!(
        SignalLayout::<8>::new(0, 0, ByteOrder::Intel, Signedness::Unsigned),
        Err(LayoutError::Length { length_bits: 0 })
    );
    assert_eq!(
        SignalLayout::<65>::new(0, 8, ByteOrder::Intel, Signedness::Unsigned),
        Err(LayoutError::PduLength { pdu_len: 65 })
    );
}

#[test]
fn saturating_and_masking_variants_are_explicit() {
    let s = crate::signal_layout!(8; 4, 8, ByteOrder::Intel, Signedness::Signed);
    let mut pdu = [0u8; 8];
    s.pack_saturating(&mut pdu, 1000);
    assert_eq!(s.unpack(&pdu), SignalValue::Signed(127));
    s.pack_saturating(&mut pdu, -1000);
    assert_eq!(s.unpack(&pdu), SignalValue::Signed(-128));
    s.pack_masked(&mut pdu, 0x1FF);
    assert_eq!(s.unpack_raw(&pdu), 0xFF);
    assert_eq!(pdu, [0xF0, 0x0F, 0, 0, 0, 0, 0, 0]);
}

fn bolero_case<const N: usize>(
    start: u16,
    len: u8,
    moto: bool,
    signed: bool,
    value: i128,
    bg: [u8; N],
) {
    let order = if moto {
        ByteOrder::Motorola
    } else {
        ByteOrder::Intel
    };
    let sign = if signed {
        Signedness::Signed
    } else {
        Signedness::Unsigned
    };
    let start = start % (8 * N as u16 + 8);
    let len = len % 66;
    match SignalLayout::<N>::new(start, len, order, sign) {
        Ok(layout) => {
            assert!(spec::layout_fits(N, start, len, order));
            // Bias the value into the interesting region around the signal's range.
            let (lo, hi) = spec::value_range(len, sign);
            let span = hi - lo + 3;
            check_case(&layout, value.rem_euclid(span) + lo - 1, &bg);
        }
        Err(_) => assert!(!spec::layout_fits(N, start, len, order)),
    }
}

#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(66))]
fn codec_matches_reference_classic_can() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 8])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<8>(start, len, moto, signed, value, bg)
        });
}

#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(66))]
fn codec_matches_reference_can_fd() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 64])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<64>(start, len, moto, signed, value, bg)
        });
}

#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(66))]
fn codec_matches_reference_odd_pdu() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 11])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<11>(start, len, moto, signed, value, bg)
        });
}
