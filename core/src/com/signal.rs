//! Com signal codec: packing signal values into I-PDUs and unpacking them (AUTOSAR SWS
//! COM, `Com_SendSignal`/`Com_ReceiveSignal` data path; DBC bit numbering).
//!
//! A [`SignalLayout`] says where a signal lives in an `N`-byte PDU (1 <= N <= 64, so
//! classic CAN and CAN FD): its start bit, length (1..=64 bits), byte order and signedness.
//!
//! Bit numbering follows the DBC convention, which cantools and Arctic Core share:
//! - bit `b` is bit `b % 8` (LSB = 0) of byte `b / 8`;
//! - [`ByteOrder::Intel`] (little endian): the start bit is the signal's LSB and the
//!   signal grows toward higher bit numbers;
//! - [`ByteOrder::Motorola`] (big endian): the start bit is the signal's MSB and the
//!   signal grows toward the LSB in "sawtooth" order: bit 7 of byte 0, then bit 6, ...
//!   bit 0, then bit 15 (bit 7 of byte 1), and so on.
//!
//! Invariants:
//! - a layout exists only if every bit of the signal lies inside the PDU
//!   ([`spec::layout_fits`]); since the PDU is a `[u8; N]` and `N` is part of the layout's
//!   type, no layout can make the codec touch a byte outside the PDU;
//! - `pack` writes exactly the signal's bits and leaves every other bit as it was;
//! - `unpack` sign-extends signed signals;
//! - an out-of-range value is an error and leaves the PDU untouched; [`SignalLayout::pack_masked`]
//!   and [`SignalLayout::pack_saturating`] are the explicit lossy variants.
//!
//! How: the signal spans at most 9 bytes, so it always lies inside an 8-byte window (PDUs
//! of up to 8 bytes) or a 16-byte window (larger PDUs) read as one little-endian (Intel) or
//! big-endian (Motorola) integer. In that integer the signal is a contiguous run of bits at
//! a shift fixed at construction, so packing is one mask-and-merge. With a layout known at
//! compile time the whole operation folds to a few instructions.

/// Byte order of a signal (DBC `@1` is Intel, `@0` is Motorola).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ByteOrder {
    /// Little endian: start bit is the least significant bit.
    Intel,
    /// Big endian: start bit is the most significant bit, sawtooth numbering.
    Motorola,
}

/// Signedness of a signal (DBC `+` unsigned, `-` two's complement signed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Signedness {
    /// Raw values `0 ..= 2^len - 1`.
    Unsigned,
    /// Raw values `-2^(len-1) ..= 2^(len-1) - 1`, two's complement.
    Signed,
}

/// Why a layout was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutError {
    /// The PDU length `N` is 0 or above 64 bytes.
    PduLength {
        /// The refused PDU length, in bytes.
        pdu_len: usize,
    },
    /// The signal length is 0 or above 64 bits.
    Length {
        /// The refused signal length, in bits.
        length_bits: u8,
    },
    /// The signal does not fit inside the PDU.
    OutsidePdu {
        /// The start bit as given.
        start_bit: u16,
        /// The signal length, in bits.
        length_bits: u8,
    },
}

/// Why a value was not packed. The PDU is left untouched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignalError {
    /// The value cannot be represented in the signal's length and signedness.
    OutOfRange,
}

/// A signal value, typed by the signal's signedness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SignalValue {
    /// Value of an unsigned signal.
    Unsigned(u64),
    /// Value of a signed signal, sign-extended.
    Signed(i64),
}

impl SignalValue {
    /// The value as an `i128`, which holds both variants exactly.
    pub const fn as_i128(self) -> i128 {
        match self {
            Self::Unsigned(v) => v as i128,
            Self::Signed(v) => v as i128,
        }
    }
}

/// Where a signal lives in an `N`-byte PDU. Only [`SignalLayout::new`] makes one, and only
/// for a signal that fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SignalLayout<const N: usize> {
    start_bit: u16,
    length_bits: u8,
    order: ByteOrder,
    signedness: Signedness,
    /// First PDU byte of the window (always 0 when `N <= 8`).
    window_byte: u8,
    /// Position of the signal's LSB inside the window integer.
    shift: u8,
}

/// Largest PDU the codec accepts (CAN FD), in bytes.
pub const MAX_PDU_LEN: usize = 64;

const fn min(a: usize, b: usize) -> usize {
    if a < b {
        a
    } else {
        b
    }
}

impl<const N: usize> SignalLayout<N> {
    /// Validates a layout for an `N`-byte PDU.
    ///
    /// # Errors
    /// [`LayoutError::PduLength`] unless `1 <= N <= 64`, [`LayoutError::Length`] unless
    /// `1 <= length_bits <= 64`, [`LayoutError::OutsidePdu`] if any bit would fall outside.
    pub const fn new(
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
        signedness: Signedness,
    ) -> Result<Self, LayoutError> {
        Self::checked(start_bit, length_bits, order, signedness)
    }

    /// [`Self::new`]'s checks and placement. (A function of its own because cargo-mutants
    /// leaves functions named `new` alone: see `docs/src/mutants.md`.)
    const fn checked(
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
        signedness: Signedness,
    ) -> Result<Self, LayoutError> {
        if N == 0 || N > MAX_PDU_LEN {
            return Err(LayoutError::PduLength { pdu_len: N });
        }
        if length_bits == 0 || length_bits > 64 {
            return Err(LayoutError::Length { length_bits });
        }
        let outside = Err(LayoutError::OutsidePdu {
            start_bit,
            length_bits,
        });
        let bits = 8 * N;
        let start = start_bit as usize;
        let len = length_bits as usize;
        if start >= bits {
            return outside;
        }
        match order {
            ByteOrder::Intel => {
                if start + len > bits {
                    return outside;
                }
            }
            ByteOrder::Motorola => {
                // Position of the MSB in the PDU read as a big-endian integer.
                let msb_pos = (N - 1 - start / 8) * 8 + start % 8;
                if msb_pos + 1 < len {
                    return outside;
                }
            }
        }
        // First byte the signal touches (for both orders, the start bit's byte), and the
        // window for N > 16: it starts at the multiple of 8 at or below that byte (the signal
        // spans at most 9 bytes, so it ends inside the 16), clamped to the PDU's end. Aligned
        // windows start at one of N / 8 places, which keeps the codec's proofs tractable.
        let first_byte = start / 8;
        let (window_len, window_byte) = if N <= 8 {
            (8, 0)
        } else if N < 16 {
            (16, 0)
        } else {
            (16, min(first_byte - first_byte % 8, N - 16))
        };
        let shift = match order {
            ByteOrder::Intel => start - 8 * window_byte,
            ByteOrder::Motorola => {
                let msb_in_window = (window_len - 1 - (start / 8 - window_byte)) * 8 + start % 8;
                msb_in_window + 1 - len
            }
        };
        Ok(Self {
            start_bit,
            length_bits,
            order,
            signedness,
            window_byte: window_byte as u8,
            shift: shift as u8,
        })
    }

    /// The start bit (DBC convention).
    pub const fn start_bit(&self) -> u16 {
        self.start_bit
    }

    /// The length in bits.
    pub const fn length_bits(&self) -> u8 {
        self.length_bits
    }

    /// The byte order.
    pub const fn byte_order(&self) -> ByteOrder {
        self.order
    }

    /// The signedness.
    pub const fn signedness(&self) -> Signedness {
        self.signedness
    }

    /// All ones in the low `length_bits` bits.
    #[inline(always)]
    pub const fn mask(&self) -> u64 {
        u64::MAX >> (64 - self.length_bits as u32)
    }

    /// Smallest representable value.
    #[inline(always)]
    pub const fn min_value(&self) -> i64 {
        match self.signedness {
            Signedness::Unsigned => 0,
            Signedness::Signed => i64::MIN >> (64 - self.length_bits as u32),
        }
    }

    /// Largest representable value.
    #[inline(always)]
    pub const fn max_value(&self) -> u64 {
        match self.signedness {
            Signedness::Unsigned => self.mask(),
            Signedness::Signed => self.mask() >> 1,
        }
    }

    /// Writes the low `length_bits` bits of `raw` into the signal and nothing else.
    /// The masking variant: higher bits of `raw` are dropped on purpose.
    #[inline(always)]
    pub fn pack_masked(&self, pdu: &mut [u8; N], raw: u64) {
        let shift = self.shift as u32;
        if N <= 8 {
            let n = min(N, 8);
            let mut bytes = [0u8; 8];
            bytes[..n].copy_from_slice(&pdu[..n]);
            let word = match self.order {
                ByteOrder::Intel => u64::from_le_bytes(bytes),
                ByteOrder::Motorola => u64::from_be_bytes(bytes),
            };
            let field = self.mask() << shift;
            let word = (word & !field) | ((raw << shift) & field);
            let bytes = match self.order {
                ByteOrder::Intel => word.to_le_bytes(),
                ByteOrder::Motorola => word.to_be_bytes(),
            };
            pdu[..n].copy_from_slice(&bytes[..n]);
        } else {
            let (start, len) = self.window16();
            let mut bytes = [0u8; 16];
            bytes[..len].copy_from_slice(&pdu[start..start + len]);
            let word = match self.order {
                ByteOrder::Intel => u128::from_le_bytes(bytes),
                ByteOrder::Motorola => u128::from_be_bytes(bytes),
            };
            let field = (self.mask() as u128) << shift;
            let word = (word & !field) | (((raw as u128) << shift) & field);
            let bytes = match self.order {
                ByteOrder::Intel => word.to_le_bytes(),
                ByteOrder::Motorola => word.to_be_bytes(),
            };
            pdu[start..start + len].copy_from_slice(&bytes[..len]);
        }
    }

    /// Reads the signal's bits, zero-extended.
    #[inline(always)]
    pub fn unpack_raw(&self, pdu: &[u8; N]) -> u64 {
        let shift = self.shift as u32;
        if N <= 8 {
            let n = min(N, 8);
            let mut bytes = [0u8; 8];
            bytes[..n].copy_from_slice(&pdu[..n]);
            let word = match self.order {
                ByteOrder::Intel => u64::from_le_bytes(bytes),
                ByteOrder::Motorola => u64::from_be_bytes(bytes),
            };
            (word >> shift) & self.mask()
        } else {
            let (start, len) = self.window16();
            let mut bytes = [0u8; 16];
            bytes[..len].copy_from_slice(&pdu[start..start + len]);
            let word = match self.order {
                ByteOrder::Intel => u128::from_le_bytes(bytes),
                ByteOrder::Motorola => u128::from_be_bytes(bytes),
            };
            ((word >> shift) as u64) & self.mask()
        }
    }

    /// The 16-byte window for PDUs above 8 bytes: first byte and number of PDU bytes in it.
    /// The number is fixed by `N` (`N < 16` PDUs fill the window partly, from byte 0), so
    /// the copies have a constant length. Construction guarantees `window_byte + len <= N`:
    /// the window starts at byte 0 when `N < 16` and at most at byte `N - 16` otherwise.
    #[inline(always)]
    fn window16(&self) -> (usize, usize) {
        (self.window_byte as usize, min(N, 16))
    }

    /// Packs an unsigned value.
    ///
    /// # Errors
    /// [`SignalError::OutOfRange`] if `value` exceeds [`Self::max_value`]; the PDU is untouched.
    #[inline(always)]
    pub fn pack_u64(&self, pdu: &mut [u8; N], value: u64) -> Result<(), SignalError> {
        if value > self.max_value() {
            return Err(SignalError::OutOfRange);
        }
        self.pack_masked(pdu, value);
        Ok(())
    }

    /// Packs a signed value (two's complement for signed signals).
    ///
    /// # Errors
    /// [`SignalError::OutOfRange`] outside [`Self::min_value`]..=[`Self::max_value`]; the
    /// PDU is untouched.
    #[inline(always)]
    pub fn pack_i64(&self, pdu: &mut [u8; N], value: i64) -> Result<(), SignalError> {
        if value < self.min_value() || (value >= 0 && value as u64 > self.max_value()) {
            return Err(SignalError::OutOfRange);
        }
        self.pack_masked(pdu, value as u64);
        Ok(())
    }

    /// Packs a typed value.
    ///
    /// # Errors
    /// [`SignalError::OutOfRange`] when the value does not fit; the PDU is untouched.
    #[inline]
    pub fn pack(&self, pdu: &mut [u8; N], value: SignalValue) -> Result<(), SignalError> {
        match value {
            SignalValue::Unsigned(v) => self.pack_u64(pdu, v),
            SignalValue::Signed(v) => self.pack_i64(pdu, v),
        }
    }

    /// Packs `value` clamped into the representable range (the saturating variant).
    #[inline]
    pub fn pack_saturating(&self, pdu: &mut [u8; N], value: i128) {
        let lo = self.min_value() as i128;
        let hi = self.max_value() as i128;
        let clamped = if value < lo {
            lo
        } else if value > hi {
            hi
        } else {
            value
        };
        self.pack_masked(pdu, clamped as u64);
    }

    /// Reads the signal, sign-extended for signed signals.
    #[inline(always)]
    pub fn unpack(&self, pdu: &[u8; N]) -> SignalValue {
        let raw = self.unpack_raw(pdu);
        match self.signedness {
            Signedness::Unsigned => SignalValue::Unsigned(raw),
            Signedness::Signed => {
                let unused = 64 - self.length_bits as u32;
                SignalValue::Signed(((raw << unused) as i64) >> unused)
            }
        }
    }
}

/// Builds a [`SignalLayout`] at compile time; an invalid layout is a build error.
///
/// ```
/// use cw_core::com::signal::{ByteOrder, Signedness};
/// let distance = cw_core::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned);
/// let mut pdu = [0u8; 8];
/// distance.pack_u64(&mut pdu, 1500).unwrap();
/// assert_eq!(pdu, [0xDC, 0x05, 0, 0, 0, 0, 0, 0]);
/// ```
#[macro_export]
macro_rules! signal_layout {
    ($n:literal; $start:expr, $len:expr, $order:expr, $sign:expr) => {
        const {
            match $crate::com::signal::SignalLayout::<$n>::new($start, $len, $order, $sign) {
                Ok(layout) => layout,
                Err(_) => panic!("signal layout does not fit its PDU"),
            }
        }
    };
}

/// Named predicates and the reference formulation of the codec, written bit by bit from
/// the DBC definition, independently of the window arithmetic above.
pub mod spec {
    use super::{ByteOrder, SignalError, SignalLayout, SignalValue, Signedness};

    /// PDU bit number (`byte * 8 + bit`, LSB = 0) of the signal bit `i` counted from the
    /// signal's LSB (`i < length_bits`). It may lie beyond the PDU: see [`layout_fits`].
    pub const fn bit_position(start_bit: u16, length_bits: u8, order: ByteOrder, i: u8) -> usize {
        match order {
            ByteOrder::Intel => start_bit as usize + i as usize,
            ByteOrder::Motorola => {
                // Walk the sawtooth from the MSB: linear index 0 is byte 0 bit 7, 1 is byte 0
                // bit 6, ..., 8 is byte 1 bit 7. The MSB sits at the start bit; bit i (from
                // the LSB) is (length - 1 - i) steps further.
                let s = start_bit as usize;
                let msb_linear = (s / 8) * 8 + (7 - s % 8);
                let linear = msb_linear + (length_bits as usize - 1 - i as usize);
                (linear / 8) * 8 + (7 - linear % 8)
            }
        }
    }

    /// The inverse of [`bit_position`]: which signal bit (counted from the LSB) PDU bit `p`
    /// holds, or `None` if `p` is not part of the signal. Written in closed form so a proof
    /// can ask it for one symbolic `p` instead of walking the signal; the proofs check every
    /// `Some(i)` against [`bit_position`], so a wrong answer here cannot hide a fault.
    pub const fn signal_bit_at(
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
        p: usize,
    ) -> Option<u8> {
        let start = start_bit as usize;
        let len = length_bits as usize;
        let from_lsb = match order {
            ByteOrder::Intel => {
                if p < start || p - start >= len {
                    return None;
                }
                p - start
            }
            ByteOrder::Motorola => {
                // Sawtooth (linear) index: byte 0 bit 7 is 0, byte 0 bit 0 is 7, byte 1 bit 7
                // is 8. The signal occupies `len` linear positions from its MSB's.
                let linear = (p / 8) * 8 + (7 - p % 8);
                let msb_linear = (start / 8) * 8 + (7 - start % 8);
                if linear < msb_linear || linear - msb_linear >= len {
                    return None;
                }
                len - 1 - (linear - msb_linear)
            }
        };
        Some(from_lsb as u8)
    }

    /// The layout is acceptable: PDU of 1..=64 bytes, length 1..=64, every bit inside.
    pub const fn layout_fits(
        pdu_len: usize,
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
    ) -> bool {
        if pdu_len == 0 || pdu_len > 64 || length_bits == 0 || length_bits > 64 {
            return false;
        }
        if start_bit as usize >= pdu_len * 8 {
            return false;
        }
        let mut i = 0;
        while i < length_bits {
            if bit_position(start_bit, length_bits, order, i) >= pdu_len * 8 {
                return false;
            }
            i += 1;
        }
        true
    }

    /// Sets, in `pdu`, the bits the signal occupies (bit `p` is `pdu[p / 8] >> (p % 8)`).
    pub fn occupied(pdu: &mut [u8], start_bit: u16, length_bits: u8, order: ByteOrder) {
        for i in 0..length_bits {
            let p = bit_position(start_bit, length_bits, order, i);
            pdu[p / 8] |= 1 << (p % 8);
        }
    }

    /// Reference pack: writes bit `i` of `raw` to its position, one bit at a time.
    pub fn reference_pack(
        pdu: &mut [u8],
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
        raw: u64,
    ) {
        for i in 0..length_bits {
            let p = bit_position(start_bit, length_bits, order, i);
            let bit = ((raw >> i) & 1) as u8;
            pdu[p / 8] = (pdu[p / 8] & !(1 << (p % 8))) | (bit << (p % 8));
        }
    }

    /// Reference unpack: gathers the bits one at a time, then sign-extends by arithmetic
    /// (`raw - 2^len` when the top bit is set) rather than by shifts.
    pub fn reference_unpack(
        pdu: &[u8],
        start_bit: u16,
        length_bits: u8,
        order: ByteOrder,
        signedness: Signedness,
    ) -> i128 {
        let mut raw: u128 = 0;
        for i in 0..length_bits {
            let p = bit_position(start_bit, length_bits, order, i);
            raw |= (((pdu[p / 8] >> (p % 8)) & 1) as u128) << i;
        }
        let top = 1u128 << (length_bits - 1);
        match signedness {
            Signedness::Signed if raw & top != 0 => raw as i128 - (1i128 << length_bits),
            _ => raw as i128,
        }
    }

    /// The whole contract of the codec for one case: `value` (in range or not) is packed
    /// into `background` with `layout`, and
    /// - out of range: a clear error and the PDU unchanged;
    /// - in range: the bytes equal the bit-by-bit reference, no bit outside the signal
    ///   changed, and unpacking (ours and the reference's) gives the value back,
    ///   sign-extended; unpacking the background agrees with the reference too.
    ///
    /// Returns whether the value was in range, or the name of the broken property.
    pub fn codec_contract<const N: usize>(
        layout: &SignalLayout<N>,
        value: i128,
        background: &[u8; N],
    ) -> Result<bool, &'static str> {
        let (start, len, order, sign) = (
            layout.start_bit(),
            layout.length_bits(),
            layout.byte_order(),
            layout.signedness(),
        );
        if !layout_fits(N, start, len, order) {
            return Err("a layout exists that does not fit its PDU");
        }
        let (lo, hi) = value_range(len, sign);
        let mut pdu = *background;
        let result = match (u64::try_from(value), i64::try_from(value)) {
            (Ok(v), _) if sign == Signedness::Unsigned => {
                layout.pack(&mut pdu, SignalValue::Unsigned(v))
            }
            (_, Ok(v)) => layout.pack(&mut pdu, SignalValue::Signed(v)),
            (Ok(v), Err(_)) => layout.pack_u64(&mut pdu, v),
            (Err(_), Err(_)) => Err(SignalError::OutOfRange),
        };
        let in_range = lo <= value && value <= hi;
        if !in_range {
            if result != Err(SignalError::OutOfRange) {
                return Err("an out-of-range value was not refused");
            }
            if &pdu != background {
                return Err("a refused value changed the PDU");
            }
            return Ok(false);
        }
        if result.is_err() {
            return Err("an in-range value was refused");
        }
        let mut expected = *background;
        reference_pack(&mut expected, start, len, order, value as u64);
        if pdu != expected {
            return Err("packed bytes differ from the bit-by-bit reference");
        }
        let mut occupied_bits = [0u8; N];
        occupied(&mut occupied_bits, start, len, order);
        for i in 0..N {
            if (pdu[i] ^ background[i]) & !occupied_bits[i] != 0 {
                return Err("a bit outside the signal changed");
            }
        }
        if layout.unpack(&pdu).as_i128() != value {
            return Err("unpack does not give the packed value back");
        }
        if reference_unpack(&pdu, start, len, order, sign) != value {
            return Err("the reference unpack disagrees with the packed value");
        }
        if layout.unpack_raw(&pdu) != (value as u64) & layout.mask() {
            return Err("unpack_raw is not the value's low bits");
        }
        if layout.unpack(background).as_i128()
            != reference_unpack(background, start, len, order, sign)
        {
            return Err("unpack of an arbitrary PDU disagrees with the reference");
        }
        Ok(true)
    }

    /// The value range of a signal, as `i128` bounds computed by powers of two.
    pub const fn value_range(length_bits: u8, signedness: Signedness) -> (i128, i128) {
        match signedness {
            Signedness::Unsigned => (0, (1i128 << length_bits) - 1),
            Signedness::Signed => (
                -(1i128 << (length_bits - 1)),
                (1i128 << (length_bits - 1)) - 1,
            ),
        }
    }
}

#[cfg(test)]
mod tests;
