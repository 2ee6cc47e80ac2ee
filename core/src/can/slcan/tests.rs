//! The SLCAN decoder and encoder: named malformed lines, round trips of any frame, and
//! the stream contract on any bytes.
extern crate std;

use super::*;
use std::vec::Vec;

fn std_frame(raw: u16, data: &[u8]) -> CanFrame {
    match CanId::standard(raw).and_then(|id| CanFrame::from_parts(id, data)) {
        Some(f) => f,
        None => panic!("test frame out of range"),
    }
}

fn decode_all(bytes: &[u8]) -> Vec<Result<Command, LineError>> {
    let mut decoder = Decoder::new();
    bytes.iter().filter_map(|&b| decoder.push(b)).collect()
}

#[test]
fn the_lines_python_can_sends_are_understood() {
    // `slcan` with bitrate=500000 opens with `C`, `S6`, `O`; `send` writes `t...`.
    let got = decode_all(b"C\rS6\rO\rt2004F401E803\rT123456780\rV\rN\rL\r");
    let Some(ext) = CanId::extended(0x1234_5678).and_then(|id| CanFrame::from_parts(id, &[]))
    else {
        panic!("test frame out of range")
    };
    assert_eq!(
        got,
        [
            Ok(Command::Close),
            Ok(Command::Bitrate(6)),
            Ok(Command::Open),
            Ok(Command::Frame(std_frame(0x200, &[0xF4, 0x01, 0xE8, 0x03]))),
            Ok(Command::Frame(ext)),
            Ok(Command::Version),
            Ok(Command::SerialNumber),
            Ok(Command::ListenOnly),
        ]
    );
    let replies: Vec<&[u8]> = got.iter().flatten().map(Command::reply).collect();
    assert_eq!(replies[3], b"z\r");
    assert_eq!(replies[4], b"Z\r");
    assert_eq!(replies[0], b"\r");
}

#[test]
fn lower_case_hex_and_newlines_are_accepted() {
    assert_eq!(
        decode_all(b"t1ff2abcd\n\r\n"),
        [Ok(Command::Frame(std_frame(0x1FF, &[0xAB, 0xCD])))]
    );
}

#[test]
fn every_malformed_line_is_named_and_the_next_line_still_decodes() {
    let cases: &[(&[u8], LineError)] = &[
        (b"x123", LineError::UnknownCommand),
        (b"\xff\xfe", LineError::UnknownCommand),
        (b"r1230", LineError::Unsupported),
        (b"d1230", LineError::Unsupported),
        (b"F", LineError::Unsupported),
        (b"Z2", LineError::BadHex),
        (b"Z", LineError::BadLength),
        (b"t12", LineError::BadLength),
        (b"t123", LineError::BadLength),
        (b"t1232AB", LineError::BadLength),
        (b"t1231ABC", LineError::BadLength),
        (b"OX", LineError::BadLength),
        (b"S", LineError::BadLength),
        (b"S9", LineError::BadBitrate),
        (b"Sz", LineError::BadHex),
        (b"t12G0", LineError::BadHex),
        (b"t1231GG", LineError::BadHex),
        (b"t123\xc3\xa9", LineError::BadHex),
        (b"t8000", LineError::IdOutOfRange),
        (b"T200000000", LineError::IdOutOfRange),
        (b"t1239", LineError::BadDlc),
        (b"t123F", LineError::BadDlc),
        (b"T123456788112233445566778", LineError::BadLength),
        (b"t12380011223344556677889900", LineError::TooLong),
    ];
    let good = std_frame(0x200, &[1, 2, 3, 4]);
    for (line, error) in cases {
        let mut stream = line.to_vec();
        stream.extend_from_slice(b"\rt200401020304\r");
        assert_eq!(
            decode_all(&stream),
            [Err(*error), Ok(Command::Frame(good))],
            "line {:?}",
            std::string::String::from_utf8_lossy(line)
        );
    }
}

#[test]
fn an_endless_line_is_refused_once_at_its_end() {
    let mut stream = std::vec![b'7'; 2_000];
    stream.extend_from_slice(b"\rt1000\r");
    assert_eq!(
        decode_all(&stream),
        [
            Err(LineError::TooLong),
            Ok(Command::Frame(std_frame(0x100, &[])))
        ]
    );
}

#[test]
fn the_longest_lines_fit() {
    let Some(f) = CanId::extended(0x1FFF_FFFF).and_then(|id| CanFrame::from_parts(id, &[0xFF; 8]))
    else {
        panic!("test frame out of range")
    };
    let mut line = [0u8; FRAME_LINE_MAX];
    let n = encode_frame(&f, &mut line);
    assert_eq!(&line[..n], b"T1FFFFFFF8FFFFFFFFFFFFFFFF\r");
    assert_eq!(decode_all(&line[..n]), [Ok(Command::Frame(f))]);
    let n = encode_frame_at(&f, Some(59_999), &mut line);
    assert_eq!(n, FRAME_LINE_MAX);
    assert_eq!(&line[..], b"T1FFFFFFF8FFFFFFFFFFFFFFFFEA5F\r");
}

#[test]
fn adapter_lines_carry_optional_time_stamps() {
    let f = std_frame(0x100, &[0xAB]);
    assert_eq!(parse_adapter_line(b"t1001AB"), Ok((f, None)));
    assert_eq!(parse_adapter_line(b"t1001AB0010"), Ok((f, Some(16))));
    assert_eq!(
        parse_adapter_line(b"t1001ABEA60"),
        Err(LineError::BadLength)
    );
    assert_eq!(parse_adapter_line(b"t1001AB001"), Err(LineError::BadLength));
    assert_eq!(parse_adapter_line(b"O"), Err(LineError::UnknownCommand));
    assert_eq!(
        decode_all(b"Z1\rZ0\r"),
        [
            Ok(Command::Timestamps(true)),
            Ok(Command::Timestamps(false))
        ]
    );
    let mut line = [0u8; FRAME_LINE_MAX];
    let n = encode_frame_at(&f, Some(60_016), &mut line);
    assert_eq!(&line[..n], b"t1001AB0010\r");
}

fn any_frame(raw: u32, extended: bool, len: u8, data: [u8; 8]) -> CanFrame {
    CanFrame::masked(CanId::masked(raw, extended), len, data)
}

/// Runs `check` on any frame and the body of its line (the line without its `\r`, which
/// must end it).
fn for_any_frame_line(check: impl Fn(CanFrame, &[u8]) + std::panic::RefUnwindSafe) {
    bolero::check!()
        .with_type::<(u32, bool, u8, [u8; 8])>()
        .cloned()
        .for_each(|(raw, extended, len, data)| {
            let frame = any_frame(raw, extended, len, data);
            let mut line = [0u8; FRAME_LINE_MAX];
            let n = encode_frame(&frame, &mut line);
            assert_eq!(line[n - 1], b'\r');
            check(frame, &line[..n - 1]);
        });
}

/// Any frame, encoded and decoded, is itself. (That its line is canonical is
/// [`accepted_lines_are_canonical`]; the bolero runs check it here as well.)
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(32))]
fn any_frame_round_trips() {
    for_any_frame_line(|frame, body| {
        assert_eq!(parse_line(body), Ok(Command::Frame(frame)));
        #[cfg(not(kani))]
        assert!(spec::accepted_line_is_canonical(body, &frame));
    });
}

/// Any frame's line, read as an adapter's line, is that frame without a time stamp.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(32))]
fn any_frame_reads_back_as_an_adapter_line() {
    for_any_frame_line(|frame, body| {
        assert_eq!(parse_adapter_line(body), Ok((frame, None)));
    });
}

/// Any frame with any time stamp: the PC side reads the frame and the stamp (modulo
/// [`TIMESTAMP_MODULUS`]) back.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(32))]
fn any_stamped_frame_round_trips() {
    bolero::check!()
        .with_type::<(u32, bool, u8, [u8; 8], u32)>()
        .cloned()
        .for_each(|(raw, extended, len, data, at_ms)| {
            let frame = any_frame(raw, extended, len, data);
            let mut line = [0u8; FRAME_LINE_MAX];
            let n = encode_frame_at(&frame, Some(at_ms), &mut line);
            assert_eq!(line[n - 1], b'\r');
            let want = (at_ms % TIMESTAMP_MODULUS) as u16;
            assert_eq!(parse_adapter_line(&line[..n - 1]), Ok((frame, Some(want))));
        });
}

/// Any bytes, then a good frame's line: every accepted line is canonical, at most one
/// verdict per line end, and the good frame is decoded intact (the stream contract).
///
/// A test and fuzz target over whole streams. Kani proves the contract for streams of any
/// length, one byte at a time: [`every_byte_follows_the_line_rule`] (no verdict but at a
/// line end, a line end judges exactly the bytes since the last one and starts afresh,
/// whatever came before), [`accepted_lines_are_canonical`] and [`any_frame_round_trips`]
/// (the good frame's line is read as that frame). Run whole under Kani, the ten garbage
/// bytes alone put up to eleven line verdicts, each a parse of a symbolic line, in one
/// program, which does not finish in 300 s.
#[test]
fn garbage_never_costs_the_next_good_frame() {
    bolero::check!()
        .with_type::<([u8; 10], u8, u32, bool, u8, [u8; 8])>()
        .cloned()
        .for_each(|(garbage, garbage_len, raw, extended, len, data)| {
            let frame = any_frame(raw, extended, len, data);
            let garbage = &garbage[..usize::from(garbage_len % 11)];
            assert!(spec::stream_contract(garbage, &frame));
        });
}

/// A decoder in any state: any bytes (a stale tail beyond `len` included) and any length
/// up to its capacity, in an overlong line or not.
fn any_decoder(line: [u8; LINE_CAPACITY], len: u8, too_long: bool) -> Decoder {
    Decoder {
        line,
        len: usize::from(len) % (LINE_CAPACITY + 1),
        too_long,
    }
}

/// Any byte, pushed in any state: a byte that ends no line gives no verdict and is kept
/// (or marks the line overlong once it is full); a line end gives the verdict on exactly
/// the bytes kept since the last line end (none for an empty line, `TooLong` for an
/// overlong one, else the parser's) and leaves the decoder as a new one would judge the
/// next line. By induction over the bytes, on a stream of any length: at most one verdict
/// per line end, each line judged as the parser judges it, and nothing before a line end
/// costs the line after it.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(28))]
fn every_byte_follows_the_line_rule() {
    bolero::check!()
        .with_type::<([u8; LINE_CAPACITY], u8, bool, u8)>()
        .cloned()
        .for_each(|(line, len, too_long, byte)| {
            let before = any_decoder(line, len, too_long);
            let mut decoder = before.clone();
            let verdict = decoder.push(byte);
            if byte == b'\r' || byte == b'\n' {
                let kept = &before.line[..before.len];
                let expected = if before.too_long {
                    Some(Err(LineError::TooLong))
                } else if kept.is_empty() {
                    None
                } else {
                    Some(parse_line(kept))
                };
                assert_eq!(verdict, expected);
                assert_eq!((decoder.len, decoder.too_long), (0, false));
            } else {
                assert_eq!(verdict, None);
                if !before.too_long && before.len < LINE_CAPACITY {
                    assert_eq!(decoder.len, before.len + 1);
                    assert_eq!(decoder.line[before.len], byte);
                    assert!(!decoder.too_long);
                } else {
                    assert_eq!(decoder.len, before.len);
                    assert!(decoder.too_long);
                }
                // The bytes kept before stay as they were.
                assert_eq!(decoder.line[..before.len], before.line[..before.len]);
            }
        });
}

/// Any line of up to [`LINE_CAPACITY`] bytes the parser reads as a frame is that frame's
/// canonical line, up to the case of its hex digits: the decoder accepts exactly the
/// well-formed frame lines.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(28))]
fn accepted_lines_are_canonical() {
    bolero::check!()
        .with_type::<([u8; LINE_CAPACITY], u8)>()
        .cloned()
        .for_each(|(bytes, len)| {
            let line = &bytes[..usize::from(len) % (LINE_CAPACITY + 1)];
            if let Ok(Command::Frame(frame)) = parse_line(line) {
                assert!(spec::accepted_line_is_canonical(line, &frame));
            }
        });
}

/// Any single line: the decoder's verdict is the parser's, and an accepted frame line is
/// canonical.
#[cfg(not(kani))]
#[test]
fn any_line_is_judged_like_the_parser_judges_it() {
    bolero::check!()
        .with_type::<Vec<u8>>()
        .for_each(|bytes: &Vec<u8>| {
            let body: Vec<u8> = bytes
                .iter()
                .copied()
                .filter(|&b| b != b'\r' && b != b'\n')
                .collect();
            let mut decoder = Decoder::new();
            for &b in &body {
                assert_eq!(decoder.push(b), None);
            }
            let verdict = decoder.push(b'\r');
            if body.is_empty() {
                assert_eq!(verdict, None);
            } else if body.len() > LINE_CAPACITY {
                assert_eq!(verdict, Some(Err(LineError::TooLong)));
            } else {
                assert_eq!(verdict, Some(parse_line(&body)));
            }
            if let Some(Ok(Command::Frame(f))) = verdict {
                assert!(spec::accepted_line_is_canonical(&body, &f));
            }
        });
}
