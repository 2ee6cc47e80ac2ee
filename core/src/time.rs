//! Milliseconds as the OS and the ECU count them: 64 bits (no wrap in an ECU's life), with
//! the 32-bit arithmetic a Cortex-M4 does without a library division.

/// `x % m` in 32-bit operations: the Cortex-M4 has no 64-bit divide, and the library's
/// takes 0.9 KiB of flash. With `x = hi * 2^32 + lo`, `x mod m` is `(hi mod m) * (2^32 mod
/// m) + lo mod m`, taken mod `m` again; for `m` below 2^16 every term fits in a `u32`.
/// `m = 0` gives 0.
pub const fn rem_u64(x: u64, m: u16) -> u32 {
    if m == 0 {
        return 0;
    }
    let m = m as u32;
    let (hi, lo) = ((x >> 32) as u32, x as u32);
    let wrap = (u32::MAX % m + 1) % m;
    ((hi % m) * wrap + lo % m) % m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_32_bit_remainder_is_the_64_bit_one() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let edges = [
            0,
            1,
            499,
            500,
            u64::from(u32::MAX),
            1 << 32,
            u64::MAX - 1,
            u64::MAX,
        ];
        for m in [
            1u16,
            2,
            3,
            10,
            20,
            40,
            250,
            500,
            1000,
            4096,
            60_000,
            65_521,
            u16::MAX,
        ] {
            for v in edges {
                assert_eq!(u64::from(rem_u64(v, m)), v % u64::from(m), "{v} % {m}");
            }
            // Under Miri (the check command's big-endian run) fewer: each is slow there.
            for _ in 0..if cfg!(miri) { 100 } else { 10_000 } {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                assert_eq!(u64::from(rem_u64(x, m)), x % u64::from(m), "{x} % {m}");
            }
        }
        assert_eq!(rem_u64(12345, 0), 0);
    }

    /// Any value and modulus: the 32-bit remainder is the 64-bit one.
    #[test]
    #[cfg_attr(kani, kani::proof)]
    fn any_remainder_is_the_64_bit_one() {
        bolero::check!()
            .with_type::<(u64, u16)>()
            .cloned()
            .for_each(|(x, m)| {
                let expected = if m == 0 { 0 } else { x % u64::from(m) };
                assert_eq!(u64::from(rem_u64(x, m)), expected);
            });
    }
}
