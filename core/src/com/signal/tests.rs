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
    assert_eq!(
        SignalLayout::<0>::new(0, 1, ByteOrder::Intel, Signedness::Unsigned),
        Err(LayoutError::PduLength { pdu_len: 0 })
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

/// The layout raw inputs name: start bits up to one byte past the PDU and lengths up to
/// 65, so refused layouts are drawn as well.
fn drawn<const N: usize>(
    start: u16,
    len: u8,
    moto: bool,
    signed: bool,
) -> (u16, u8, ByteOrder, Signedness) {
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
    (start % (8 * N as u16 + 8), len % 66, order, sign)
}

fn bolero_case<const N: usize>(
    start: u16,
    len: u8,
    moto: bool,
    signed: bool,
    value: i128,
    bg: [u8; N],
) {
    let (start, len, order, sign) = drawn::<N>(start, len, moto, signed);
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

/// The whole contract ([`spec::codec_contract`], with its bit-by-bit reference loops) on
/// random layouts, values and backgrounds. Tests and fuzz targets only: the reference walks
/// up to 64 bits with symbolic PDU indices, which no solver finishes for all layouts at
/// once; the same properties are proved one symbolic bit at a time in [`proofs`].
#[test]
fn codec_matches_reference_classic_can() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 8])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<8>(start, len, moto, signed, value, bg)
        });
}

#[test]
fn codec_matches_reference_can_fd() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 64])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<64>(start, len, moto, signed, value, bg)
        });
}

#[test]
fn codec_matches_reference_odd_pdu() {
    bolero::check!()
        .with_type::<(u16, u8, bool, bool, i128, [u8; 11])>()
        .cloned()
        .for_each(|(start, len, moto, signed, value, bg)| {
            bolero_case::<11>(start, len, moto, signed, value, bg)
        });
}

/// Proofs of the codec for every layout and every value of each PDU size, written so that
/// Kani finishes them: instead of walking the signal bit by bit (the loops of
/// [`spec::reference_pack`]), each harness states its property for one symbolic bit, which
/// under Kani stands for every bit at once. Together they are the reference's definition:
/// - [`layout_case`]: a layout exists exactly when every bit of the signal lies inside the
///   PDU, and it keeps what it was given;
/// - [`pack_case`]: packing any in-range value writes bit `i` of the value to the PDU bit
///   the DBC convention names ([`spec::bit_position`]), and leaves every other PDU bit as it
///   was; unpacking gives the value back;
/// - [`unpack_case`]: unpacking any PDU reads exactly the signal's bits, sign-extended by
///   arithmetic for signed signals;
/// - [`range_case`]: any value, in range or not: refused exactly outside the range with the
///   PDU untouched, and the saturating variant clamps.
///
/// The proofs run for three PDU sizes, one for each way the codec reads its window:
/// 8 bytes (classic CAN: the whole PDU is one 64-bit word), 12 bytes (a 16-byte window
/// filled partly) and 64 bytes (the largest CAN FD frame: a 16-byte window at one of seven
/// aligned places). The other sizes are checked exhaustively or at random above.
mod proofs {
    use super::*;

    /// Bit `p` of a PDU, as the DBC numbers bits.
    fn bit_at(pdu: &[u8], p: usize) -> u8 {
        (pdu[p / 8] >> (p % 8)) & 1
    }

    /// The in-range value whose low `len` bits (two's complement) are those of `raw`: each
    /// value of the signal's range, and only those, is drawn this way.
    fn in_range_value(raw: u64, len: u8, sign: Signedness) -> SignalValue {
        let low = if len >= 64 {
            raw
        } else {
            raw & ((1u64 << len) - 1)
        };
        match sign {
            Signedness::Unsigned => SignalValue::Unsigned(low),
            Signedness::Signed => {
                let low = i128::from(low);
                let value = if low >= 1i128 << (len - 1) {
                    low - (1i128 << len)
                } else {
                    low
                };
                SignalValue::Signed(value as i64)
            }
        }
    }

    /// Layout validity for start bit, length and byte order, for one symbolic signal bit `i`.
    pub(super) fn layout_case<const N: usize>(
        start: u16,
        len: u8,
        moto: bool,
        signed: bool,
        i: u8,
    ) {
        let (start, len, order, sign) = drawn::<N>(start, len, moto, signed);
        let bits = 8 * N;
        match SignalLayout::<N>::new(start, len, order, sign) {
            Ok(layout) => {
                assert!((1..=64).contains(&len));
                assert_eq!(layout.start_bit(), start);
                assert_eq!(layout.length_bits(), len);
                assert_eq!(layout.byte_order(), order);
                assert_eq!(layout.signedness(), sign);
                if i < len {
                    assert!(spec::bit_position(start, len, order, i) < bits);
                }
            }
            Err(LayoutError::Length { length_bits }) => {
                assert_eq!(length_bits, len);
                assert!(len == 0 || len > 64);
            }
            Err(LayoutError::OutsidePdu {
                start_bit,
                length_bits,
            }) => {
                assert_eq!((start_bit, length_bits), (start, len));
                assert!((1..=64).contains(&len));
                // The bit that lies outside: an Intel signal's MSB, a Motorola signal's LSB
                // (the last one in sawtooth order; when the start bit itself is outside,
                // every bit is).
                let outside = match order {
                    ByteOrder::Intel => len - 1,
                    ByteOrder::Motorola => 0,
                };
                assert!(spec::bit_position(start, len, order, outside) >= bits);
            }
            Err(LayoutError::PduLength { .. }) => panic!("a PDU of {N} bytes was refused"),
        }
    }

    /// The layout the proofs of one byte order draw, or `None` for a refused one (those are
    /// [`layout_case`]'s).
    fn layout_of<const N: usize>(
        start: u16,
        len: u8,
        order: ByteOrder,
        signed: bool,
    ) -> Option<SignalLayout<N>> {
        let (start, len, _, sign) = drawn::<N>(start, len, false, signed);
        SignalLayout::<N>::new(start, len, order, sign).ok()
    }

    /// The in-range value `raw` names, packed into `background` with the layout drawn for
    /// one byte order: the layout, the value's two's complement bits and the PDU, or `None`
    /// for a refused layout (those are [`layout_case`]'s). Packing it must succeed.
    fn packed<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        order: ByteOrder,
        raw: u64,
        background: [u8; N],
    ) -> Option<(SignalLayout<N>, u64, [u8; N])> {
        let layout = layout_of::<N>(start, len, order, signed)?;
        let value = in_range_value(raw, layout.length_bits(), layout.signedness());
        let bits = match value {
            SignalValue::Unsigned(v) => v,
            SignalValue::Signed(v) => v as u64,
        };
        let mut pdu = background;
        assert_eq!(layout.pack(&mut pdu, value), Ok(()));
        Some((layout, bits, pdu))
    }

    /// Packing an in-range value puts its bit `i` (one symbolic bit) where the reference
    /// says: [`spec::bit_position`].
    pub(super) fn place_case<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        order: ByteOrder,
        raw: u64,
        background: [u8; N],
        i: u8,
    ) {
        let Some((layout, bits, pdu)) = packed((start, len, signed), order, raw, background) else {
            return;
        };
        let (start, len) = (layout.start_bit(), layout.length_bits());
        let i = i % len;
        let q = spec::bit_position(start, len, order, i);
        assert_eq!(bit_at(&pdu, q), ((bits >> i) & 1) as u8);
    }

    /// Packing an in-range value leaves PDU bit `p` (one symbolic bit) as it was unless `p`
    /// belongs to the signal.
    pub(super) fn keep_case<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        order: ByteOrder,
        raw: u64,
        background: [u8; N],
        p: u16,
    ) {
        let Some((layout, _, pdu)) = packed((start, len, signed), order, raw, background) else {
            return;
        };
        let (start, len) = (layout.start_bit(), layout.length_bits());
        let p = usize::from(p) % (8 * N);
        match spec::signal_bit_at(start, len, order, p) {
            Some(j) => {
                assert!(j < len);
                assert_eq!(spec::bit_position(start, len, order, j), p);
            }
            None => assert_eq!(bit_at(&pdu, p), bit_at(&background, p)),
        }
    }

    /// Unpacking any PDU, for one symbolic bit `i` of the result.
    pub(super) fn unpack_case<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        order: ByteOrder,
        pdu: [u8; N],
        i: u8,
    ) {
        let Some(layout) = layout_of::<N>(start, len, order, signed) else {
            return;
        };
        let (start, len, sign) = (
            layout.start_bit(),
            layout.length_bits(),
            layout.signedness(),
        );
        let raw = layout.unpack_raw(&pdu);
        let i = i % 64;
        let want = if i < len {
            bit_at(&pdu, spec::bit_position(start, len, order, i))
        } else {
            0
        };
        assert_eq!(((raw >> i) & 1) as u8, want);
        match (sign, layout.unpack(&pdu)) {
            (Signedness::Unsigned, SignalValue::Unsigned(v)) => assert_eq!(v, raw),
            (Signedness::Signed, SignalValue::Signed(v)) => {
                let top = (raw >> (len - 1)) & 1 == 1;
                let want = if top {
                    i128::from(raw) - (1i128 << len)
                } else {
                    i128::from(raw)
                };
                assert_eq!(i128::from(v), want);
            }
            (sign, value) => panic!("a {sign:?} signal unpacked as {value:?}"),
        }
    }

    /// Packing any value, in range or not, through both entry points: refused exactly
    /// outside the signal's range, and a refused value leaves the PDU as it was. (That an
    /// accepted value unpacks to itself follows from [`place_case`], [`keep_case`] and
    /// [`unpack_case`]; [`round_trip_case`] checks it directly, by tests.)
    pub(super) fn range_case<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        order: ByteOrder,
        value: u64,
        as_signed: bool,
        background: [u8; N],
    ) {
        let Some(layout) = layout_of::<N>(start, len, order, signed) else {
            return;
        };
        let (lo, hi) = spec::value_range(layout.length_bits(), layout.signedness());
        let mut pdu = background;
        let (result, v) = if as_signed {
            let v = value as i64;
            (layout.pack_i64(&mut pdu, v), i128::from(v))
        } else {
            (layout.pack_u64(&mut pdu, value), i128::from(value))
        };
        if lo <= v && v <= hi {
            assert_eq!(result, Ok(()));
        } else {
            assert_eq!(result, Err(SignalError::OutOfRange));
            assert!(pdu == background);
        }
    }

    /// Any value: an accepted one unpacks to itself, and the saturating variant packs the
    /// value clamped into the range. A test and fuzz target: under Kani, packing and then
    /// unpacking a 64-byte PDU in one harness does not finish, and the round trip is a
    /// consequence of the per-bit proofs.
    pub(super) fn round_trip_case<const N: usize>(
        (start, len, signed): (u16, u8, bool),
        moto: bool,
        value: u64,
        as_signed: bool,
        background: [u8; N],
    ) {
        let (_, _, order, _) = drawn::<N>(start, len, moto, signed);
        let Some(layout) = layout_of::<N>(start, len, order, signed) else {
            return;
        };
        let (lo, hi) = spec::value_range(layout.length_bits(), layout.signedness());
        let v = if as_signed {
            i128::from(value as i64)
        } else {
            i128::from(value)
        };
        let mut saturated = background;
        layout.pack_saturating(&mut saturated, v);
        assert_eq!(layout.unpack(&saturated).as_i128(), v.clamp(lo, hi));
        let mut packed = background;
        let result = if as_signed {
            layout.pack_i64(&mut packed, value as i64)
        } else {
            layout.pack_u64(&mut packed, value)
        };
        if result.is_ok() {
            assert_eq!(layout.unpack(&packed).as_i128(), v);
            assert_eq!(packed, saturated);
        }
    }

    /// The proofs for one PDU size, each a bolero test, fuzz target and Kani proof; those
    /// that pack or unpack come once per byte order, so that each stays small enough for
    /// the solver.
    macro_rules! for_pdu_size {
        ($($module:ident: $n:literal),* $(,)?) => {$(
            mod $module {
                use super::*;

                #[test]
                #[cfg_attr(kani, kani::proof)]
                fn layout_exists_exactly_when_every_bit_fits() {
                    bolero::check!()
                        .with_type::<(u16, u8, bool, bool, u8)>()
                        .cloned()
                        .for_each(|(start, len, moto, signed, i)| {
                            layout_case::<$n>(start, len, moto, signed, i)
                        });
                }

                #[test]
                fn accepted_values_round_trip_and_saturation_clamps() {
                    bolero::check!()
                        .with_type::<((u16, u8, bool), bool, u64, bool, [u8; $n])>()
                        .cloned()
                        .for_each(|(layout, moto, value, as_signed, bg)| {
                            round_trip_case::<$n>(layout, moto, value, as_signed, bg)
                        });
                }

                for_byte_order!($n, intel: ByteOrder::Intel, motorola: ByteOrder::Motorola);
            }
        )*};
    }

    macro_rules! for_byte_order {
        ($n:literal, $($module:ident: $order:expr),*) => {$(
            mod $module {
                use super::*;

                #[test]
                #[cfg_attr(kani, kani::proof)]
                fn pack_writes_each_signal_bit() {
                    bolero::check!()
                        .with_type::<((u16, u8, bool), u64, [u8; $n], u8)>()
                        .cloned()
                        .for_each(|(layout, raw, bg, i)| place_case::<$n>(layout, $order, raw, bg, i));
                }

                #[test]
                #[cfg_attr(kani, kani::proof)]
                fn pack_changes_no_other_bit() {
                    bolero::check!()
                        .with_type::<((u16, u8, bool), u64, [u8; $n], u16)>()
                        .cloned()
                        .for_each(|(layout, raw, bg, p)| keep_case::<$n>(layout, $order, raw, bg, p));
                }

                #[test]
                #[cfg_attr(kani, kani::proof)]
                fn unpack_reads_each_signal_bit_and_no_other() {
                    bolero::check!()
                        .with_type::<((u16, u8, bool), [u8; $n], u8)>()
                        .cloned()
                        .for_each(|(layout, pdu, i)| unpack_case::<$n>(layout, $order, pdu, i));
                }

                #[test]
                #[cfg_attr(kani, kani::proof)]
                fn out_of_range_values_are_refused_and_change_nothing() {
                    bolero::check!()
                        .with_type::<((u16, u8, bool), u64, bool, [u8; $n])>()
                        .cloned()
                        .for_each(|(layout, value, as_signed, bg)| {
                            range_case::<$n>(layout, $order, value, as_signed, bg)
                        });
                }
            }
        )*};
    }

    for_pdu_size!(pdu_8: 8, pdu_12: 12, pdu_64: 64);
}
