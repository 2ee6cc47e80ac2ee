//! The same six frames (classic, 29-bit, FD with bit rate switch, remote, error, FD with
//! error state indicator and a 29-bit id) written by python-can 4.6.1's `ASCWriter`,
//! `BLFWriter` and `CanutilsLogWriter` (`tests/data/python-can.*`, made with
//! `tools/log_formats.py`), read by `cw-can` as python-can's readers read them, time
//! stamps included. `cargo xtask log-formats` does the same on thousands of random frames.

use std::path::Path;

use cw_can::log::{open, At, LogFormat};

fn read(file: &str) -> Vec<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file);
    open(&path, None)
        .expect("opens")
        .map(|r| match r {
            Ok((_, e)) => format!("{:?} {} {}", e.timestamp, e.channel, e.frame),
            Err(e) => format!("error {e}"),
        })
        .collect()
}

#[test]
fn python_cans_candump_log_reads_back() {
    assert_eq!(
        read("python-can.log"),
        [
            "1700000000.123456 can0 123#1122334455667788",
            "1700000000.2 can1 12345678#AABB",
            "1700000000.25 can0 300##1000102030405060708090A0B",
            "1700000000.3 can0 124#R",
            "1700000000.35 can0 20000080#",
            "1700000000.4 can0 00FFFFFF##2AA",
        ]
    );
}

#[test]
fn python_cans_asc_reads_back_with_relative_time_stamps() {
    // ASC time stamps count from the first frame, as python-can's reader gives them; the
    // channels are Vector's, from 1.
    assert_eq!(
        read("python-can.asc"),
        [
            "0.0 1 123#1122334455667788",
            "0.076544 2 12345678#AABB",
            "0.126544 1 300##1000102030405060708090A0B",
            "0.176544 1 124#R4",
            "0.226544 1 20000000#",
            "0.276544 1 00FFFFFF##2AA",
        ]
    );
}

#[test]
fn python_cans_blf_reads_back_with_python_cans_time_stamps() {
    // The time stamps python-can's BLFReader gives for this file (the start, kept to the
    // millisecond, plus each object's nanoseconds), bit for bit.
    assert_eq!(
        read("python-can.blf"),
        [
            "1700000000.123456 1 123#1122334455667788",
            "1700000000.2 2 12345678#AABB",
            "1700000000.25 1 300##1000102030405060708090A0B",
            "1700000000.3 1 124#R4",
            "1700000000.35 1 20000000#",
            "1700000000.4 1 00FFFFFF##2AA",
        ]
    );
}

#[test]
fn the_extension_picks_the_format_unless_told() {
    assert_eq!(LogFormat::of_path(Path::new("a.BLF")), LogFormat::Blf);
    assert_eq!(LogFormat::of_path(Path::new("a.asc")), LogFormat::Asc);
    assert_eq!(LogFormat::of_path(Path::new("a.log")), LogFormat::Candump);
    assert_eq!(LogFormat::of_path(Path::new("-")), LogFormat::Candump);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/python-can.blf");
    let as_text: Vec<_> = open(&path, Some(LogFormat::Candump))
        .expect("opens")
        .collect();
    assert!(
        as_text.iter().all(Result::is_err),
        "a BLF read as candump is all bad lines"
    );
}

#[test]
fn a_cut_or_corrupted_blf_is_an_error_at_a_byte_never_a_panic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/python-can.blf");
    let file = std::fs::read(&path).expect("readable");
    let whole = cw_can::blf::BlfReader::new(file.clone())
        .expect("a BLF")
        .filter(Result::is_ok)
        .count();
    assert_eq!(whole, 6);
    // Cut anywhere: the header refused, or fewer frames and an error naming a byte.
    for len in 0..file.len() {
        let cut = file.get(..len).expect("in range").to_vec();
        let Ok(reader) = cw_can::blf::BlfReader::new(cut) else {
            continue;
        };
        let items: Vec<_> = reader.collect();
        let frames = items.iter().filter(|i| i.is_ok()).count();
        assert!(frames < whole || len >= file.len() - 3, "cut at {len}");
        if frames < whole && len > 144 {
            let last = items.last().expect("something read");
            assert!(
                matches!(last, Err(e) if matches!(e.at, At::Byte(_))),
                "cut at {len}: {last:?}"
            );
        }
    }
    // Any byte changed: entries or errors, never a panic.
    for at in 0..file.len() {
        for value in [0x00, 0xFF, 0x80] {
            let mut bad = file.clone();
            if let Some(b) = bad.get_mut(at) {
                *b = value;
            }
            if let Ok(reader) = cw_can::blf::BlfReader::new(bad) {
                assert!(reader.count() <= 1_000);
            }
        }
    }
}
