//! The memory functions against the standard library's copies and fills (`spec`).

extern crate std;

use std::vec::Vec;

use super::spec::{all_agree, move_agrees, Buf};

/// Every copy, move and fill of up to 12 bytes at every alignment, for any contents
/// (short enough for Kani to prove it).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(14))]
fn short_copies_moves_and_fills_agree_with_the_standard_library() {
    bolero::check!()
        .with_type::<([u8; 12], [u8; 12], [u8; 4])>()
        .cloned()
        .for_each(|(a, b, ops)| assert!(all_agree(&Buf(a), &Buf(b), ops)));
}

/// The same on buffers of 64 bytes, where the word loops run for longer (the
/// `mem_functions` fuzz target runs it under libFuzzer).
#[test]
fn copies_moves_and_fills_agree_with_the_standard_library() {
    bolero::check!()
        .with_type::<(Vec<u8>, [u8; 4])>()
        .for_each(|(bytes, ops)| {
            let mut a = Buf([0u8; 64]);
            for (slot, byte) in a.0.iter_mut().zip(bytes) {
                *slot = *byte;
            }
            let mut b = a;
            b.0.reverse();
            assert!(all_agree(&a, &b, *ops));
        });
}

/// Every move within 40 bytes, both ways, at every alignment of both ends and every
/// length: among them the overlaps where a forward copy would read bytes it has already
/// overwritten.
#[test]
fn every_move_keeps_the_source_bytes() {
    let buf = Buf(core::array::from_fn::<u8, 40, _>(|i| i as u8));
    for from in 0..40u8 {
        for to in 0..40u8 {
            for len in 0..=40u8 {
                assert!(move_agrees(&buf, from, to, len), "{from} {to} {len}");
            }
        }
    }
}
