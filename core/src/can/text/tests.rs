//! `ID#HEXDATA`: named refusals, and any frame written and read back is itself.
extern crate std;

use super::*;
use crate::testing::FixedText;
use std::string::{String, ToString};

fn written(frame: &CanFrame) -> String {
    let mut s = String::new();
    match write_frame(frame, &mut s) {
        Ok(()) => s,
        Err(_) => panic!("a String takes any text"),
    }
}

#[test]
fn frames_of_both_id_formats_are_read() {
    let f = parse_frame("200#F401e803").map(|f| written(&f));
    assert_eq!(f.as_deref(), Ok("200#F401E803"));
    let f = parse_frame("1ABCDEF0#").map(|f| written(&f));
    assert_eq!(f.as_deref(), Ok("1ABCDEF0#"));
    let f = parse_frame("7FF#0001020304050607").map(|f| f.len());
    assert_eq!(f, Ok(8));
}

#[test]
fn every_refusal_names_the_part_that_is_wrong() {
    let cases = [
        ("100", "`100` is not a frame (expected ID#HEXDATA)"),
        ("#00", "`` is not a hex CAN id"),
        ("+10#00", "`+10` is not a hex CAN id"),
        ("123456789#00", "`123456789` is not a hex CAN id"),
        ("800#00", "CAN id 800 is out of range"),
        ("20000000#00", "CAN id 20000000 is out of range"),
        ("100#0", "`0` has an odd number of hex digits"),
        ("100#0é0", "`0é0` is not hex data"),
        ("100#é", "`é` is not hex data"),
        ("100#+F", "`+F` is not hex data"),
        (
            "100#000000000000000000",
            "9 data bytes; a CAN frame holds at most 8",
        ),
        (
            "100#0000000000000000zz",
            "`0000000000000000zz` is not hex data",
        ),
    ];
    for (text, message) in cases {
        match parse_frame(text) {
            Ok(f) => panic!("`{text}` was read as {f:?}"),
            Err(e) => assert_eq!(e.to_string(), message, "{text}"),
        }
    }
}

/// Any frame, written and read back, is itself.
fn round_trip_case(frame: CanFrame) {
    // The longest frame text is 8 + 1 + 16 characters.
    let mut out = FixedText::<25>::new();
    assert!(write_frame(&frame, &mut out).is_ok());
    let text = out.as_str();
    assert_eq!(text.map(parse_frame), Some(Ok(frame)));
}

/// Any frame with an 11-bit id (three id digits) round-trips through its text.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(26))]
fn any_standard_frame_round_trips_through_its_text() {
    bolero::check!()
        .with_type::<(u16, u8, [u8; 8])>()
        .cloned()
        .for_each(|(raw, len, data)| {
            round_trip_case(CanFrame::masked(
                CanId::masked(raw.into(), false),
                len,
                data,
            ));
        });
}

/// Any frame with a 29-bit id (eight id digits) round-trips through its text.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(26))]
fn any_extended_frame_round_trips_through_its_text() {
    bolero::check!()
        .with_type::<(u32, u8, [u8; 8])>()
        .cloned()
        .for_each(|(raw, len, data)| {
            round_trip_case(CanFrame::masked(CanId::masked(raw, true), len, data));
        });
}

/// Any text: read or refused, never a panic; what is read writes back to a text that
/// reads as the same frame.
#[cfg(not(kani))]
#[test]
fn any_text_is_read_or_refused() {
    bolero::check!()
        .with_type::<String>()
        .for_each(|text: &String| {
            if let Ok(frame) = parse_frame(text) {
                assert_eq!(parse_frame(&written(&frame)), Ok(frame));
            }
        });
}
