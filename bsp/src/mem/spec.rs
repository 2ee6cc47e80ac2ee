//! The memory functions' contract ([`super`]), for the bsp's tests, the `mem_functions`
//! fuzz target and a Kani proof: on any buffer, offsets (so every alignment of both
//! addresses), length and overlap, a copy, a move and a fill leave the bytes the standard
//! library's `copy_from_slice`, `copy_within` and `fill` leave.

use super::{copy, copy_forward, set};

/// A buffer of `N` bytes, word-aligned, so that an offset into it sets the alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(C, align(4))]
pub struct Buf<const N: usize>(pub [u8; N]);

/// A length and two starts in a buffer of `n` bytes, each range within it.
fn ranges(n: usize, from: u8, to: u8, len: u8) -> (usize, usize, usize) {
    let len = usize::from(len) % (n + 1);
    let room = n - len + 1;
    (usize::from(from) % room, usize::from(to) % room, len)
}

/// [`copy_forward`] between two buffers: the destination's bytes in the copy's reach are
/// the source's, and the others are untouched.
pub fn copy_agrees<const N: usize>(src: &Buf<N>, dest: &Buf<N>, from: u8, to: u8, len: u8) -> bool {
    let (from, to, len) = ranges(N, from, to, len);
    let mut out = *dest;
    // SAFETY: both ranges lie in their buffers (`ranges`), which do not overlap.
    unsafe { copy_forward(out.0.as_mut_ptr().add(to), src.0.as_ptr().add(from), len) };
    let mut expected = *dest;
    expected.0[to..to + len].copy_from_slice(&src.0[from..from + len]);
    out == expected
}

/// [`copy`] (`memmove`) within one buffer: as `copy_within`, whatever the overlap.
pub fn move_agrees<const N: usize>(buf: &Buf<N>, from: u8, to: u8, len: u8) -> bool {
    let (from, to, len) = ranges(N, from, to, len);
    let mut out = *buf;
    let base = out.0.as_mut_ptr();
    // SAFETY: both ranges lie in the buffer (`ranges`); `copy` allows the overlap.
    unsafe { copy(base.add(to), base.add(from), len) };
    let mut expected = *buf;
    expected.0.copy_within(from..from + len, to);
    out == expected
}

/// [`set`]: the bytes in its reach are `c`, the others untouched.
pub fn fill_agrees<const N: usize>(buf: &Buf<N>, at: u8, len: u8, c: u8) -> bool {
    let (at, _, len) = ranges(N, at, 0, len);
    let mut out = *buf;
    // SAFETY: the range lies in the buffer (`ranges`).
    unsafe { set(out.0.as_mut_ptr().add(at), c, len) };
    let mut expected = *buf;
    expected.0[at..at + len].fill(c);
    out == expected
}

/// All three on the buffers `a` and `b` with the same offsets and length.
pub fn all_agree<const N: usize>(a: &Buf<N>, b: &Buf<N>, [from, to, len, c]: [u8; 4]) -> bool {
    copy_agrees(a, b, from, to, len)
        && move_agrees(a, from, to, len)
        && fill_agrees(a, from, len, c)
}
