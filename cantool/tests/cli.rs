//! The `cw-can` command as an engineer runs it: its output, its errors on standard error
//! as `FILE:LINE: what is wrong`, and its exit status.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn ecu_dbc() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../firmware/ecu.dbc")
}

fn features_dbc() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/features.dbc")
}

fn run(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_cw-can"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cw-can starts");
    // A command that refuses its arguments (a DBC strict loading refuses) exits before it
    // reads its input: the rest of the input then meets a closed pipe, which is no error
    // of the test's.
    match child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin.as_bytes())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => panic!("stdin written: {e}"),
        _ => {}
    }
    child.wait_with_output().expect("cw-can ends")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

const LOG: &str = "\
(1700000000.000000) can0 100#E803000001000000
(1700000000.040000) can0 100#E8030000010000
garbage
(1700000000.080000) can0 7FF#00
(1700000000.120000) can0 100#R
(1700000000.160000) can0 20000080#0000000000000000
(1700000000.200000) can0 200#F401E803
";

#[test]
fn decode_reports_each_bad_line_and_goes_on() {
    let dbc = ecu_dbc();
    let out = run(&["decode", "--dbc", dbc.to_str().expect("path"), "-"], LOG);
    assert_eq!(out.status.code(), Some(1), "some lines were bad");
    assert_eq!(
        text(&out.stdout),
        "\
(1700000000.000000) can0 100#E803000001000000 DistanceFrame(Distance: 1000 mm, WarningLevel: Yellow)
(1700000000.080000) can0 7FF#00 (not in the DBC)
(1700000000.120000) can0 100#R (remote frame)
(1700000000.160000) can0 20000080#0000000000000000 (error frame)
(1700000000.200000) can0 200#F401E803 ThresholdConfig(RedBelow: 500 mm, YellowBelow: 1000 mm)
"
    );
    assert_eq!(
        text(&out.stderr),
        "\
cw-can: -:2: 100#E8030000010000: 7 data bytes, but the message has 8: the frame is too short
cw-can: -:3: `garbage` is not a candump log line: (SECONDS) CHANNEL ID#DATA [R|T]
cw-can: 2 bad line(s)
"
    );
}

#[test]
fn strict_stops_at_the_first_bad_line() {
    let dbc = ecu_dbc();
    let out = run(
        &[
            "decode",
            "--strict",
            "--dbc",
            dbc.to_str().expect("path"),
            "-",
        ],
        LOG,
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stdout).lines().count(), 1);
    assert!(text(&out.stderr).starts_with("cw-can: -:2: "));
}

#[test]
fn a_clean_log_exits_0_and_json_is_one_object_per_frame() {
    let dbc = features_dbc();
    let mut data = [0u8; 64];
    (data[0], data[1], data[63]) = (0x12, 0x34, 0x99);
    let hex: String = data.iter().map(|b| format!("{b:02X}")).collect();
    let log = format!("(1.500000) vcan0 300##1{hex}\n");
    let out = run(
        &[
            "decode",
            "--format",
            "json",
            "--dbc",
            dbc.to_str().expect("path"),
            "-",
        ],
        &log,
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let frame: serde_json::Value =
        serde_json::from_str(text(&out.stdout).trim()).expect("one JSON object");
    assert_eq!(frame["kind"], "fd");
    assert_eq!(frame["brs"], true);
    assert_eq!(frame["message"], "Fd64");
    assert_eq!(frame["timestamp"], 1.5);
    assert_eq!(frame["signals"][0]["name"], "Head");
    assert_eq!(frame["signals"][0]["value"], 4660);
    assert_eq!(frame["signals"][1]["name"], "Tail");
    assert_eq!(frame["signals"][1]["raw"], 153);
}

#[test]
fn csv_is_one_row_per_signal_under_a_header() {
    let dbc = ecu_dbc();
    let out = run(
        &[
            "decode",
            "--format",
            "csv",
            "--dbc",
            dbc.to_str().expect("path"),
            "-",
        ],
        "(2.000000) can0 100#FFFFFFFF03000000\n(2.100000) can0 123#\n",
    );
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        text(&out.stdout),
        "\
timestamp,channel,id,extended,kind,data,message,signal,raw,value,unit,choice
2.000000,can0,256,false,classic,FFFFFFFF03000000,DistanceFrame,Distance,4294967295,4294967295,mm,Invalid
2.000000,can0,256,false,classic,FFFFFFFF03000000,DistanceFrame,WarningLevel,3,3,,Fault
2.100000,can0,291,false,classic,,,,,,,
"
    );
}

#[test]
fn encode_prints_the_frame_and_refuses_what_does_not_fit() {
    let dbc = ecu_dbc();
    let dbc = dbc.to_str().expect("path");
    let out = run(
        &[
            "encode",
            "--dbc",
            dbc,
            "ThresholdConfig",
            "RedBelow=500",
            "YellowBelow=1000",
        ],
        "",
    );
    assert_eq!(text(&out.stdout), "200#F401E803\n");
    assert_eq!(out.status.code(), Some(0));
    let out = run(
        &["encode", "--dbc", dbc, "ThresholdConfig", "RedBelow=500"],
        "",
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("YellowBelow is missing"));
    let out = run(
        &[
            "encode",
            "--dbc",
            dbc,
            "ThresholdConfig",
            "RedBelow=nan",
            "YellowBelow=1",
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr),
        "cw-can: RedBelow: `nan` is not a finite number\n"
    );
}

#[test]
fn a_message_the_dbc_marks_as_fd_encodes_as_an_fd_frame() {
    let dbc = features_dbc();
    let out = run(
        &[
            "encode",
            "--dbc",
            dbc.to_str().expect("path"),
            "SmallFd",
            "Word=0x10",
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(2), "0x10 is no number");
    let out = run(
        &[
            "encode",
            "--dbc",
            dbc.to_str().expect("path"),
            "SmallFd",
            "Word=16",
        ],
        "",
    );
    assert_eq!(text(&out.stdout), "600##010000000\n");
}

#[test]
fn usage_errors_and_missing_files_exit_2() {
    assert_eq!(run(&["decode"], "").status.code(), Some(2));
    assert_eq!(run(&["frobnicate"], "").status.code(), Some(2));
    let out = run(&["decode", "--dbc", "/nonexistent.dbc", "-"], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).starts_with("cw-can: cannot read /nonexistent.dbc"));
    assert_eq!(run(&["--help"], "").status.code(), Some(0));
}

#[test]
fn asc_and_blf_logs_decode_by_their_extension_or_as_told() {
    let dbc = ecu_dbc();
    let dbc = dbc.to_str().expect("path");
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for file in ["python-can.asc", "python-can.blf", "python-can.log"] {
        let path = data.join(file);
        let out = run(&["decode", "--dbc", dbc, path.to_str().expect("path")], "");
        assert_eq!(out.status.code(), Some(0), "{file}: {}", text(&out.stderr));
        let stdout = text(&out.stdout);
        assert_eq!(stdout.lines().count(), 6, "{file}");
        assert!(
            stdout.contains(" 300##1000102030405060708090A0B (not in the DBC)"),
            "{file}: {stdout}"
        );
    }
    // A BLF read as candump: every line bad, exit status 1.
    let blf = data.join("python-can.blf");
    let out = run(
        &[
            "decode",
            "--log-format",
            "candump",
            "--dbc",
            dbc,
            blf.to_str().expect("path"),
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(1));
}

/// A fake SLCAN adapter on a TCP port: checks the opening commands, sends `lines`, and
/// closes the connection.
fn adapter(lines: &'static [u8]) -> (String, std::thread::JoinHandle<Vec<u8>>) {
    use std::io::Read;
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("a free port");
    let port = listener.local_addr().expect("bound").port();
    let handle = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().expect("cw-can connects");
        let mut got = Vec::new();
        let mut byte = [0u8; 1];
        while !got.ends_with(b"O\r") {
            match stream.read(&mut byte) {
                Ok(1) => got.push(byte[0]),
                _ => break,
            }
        }
        stream.write_all(lines).expect("lines sent");
        got
    });
    (format!("socket://127.0.0.1:{port}"), handle)
}

#[test]
fn a_live_slcan_adapter_is_decoded_as_it_sends() {
    let dbc = ecu_dbc();
    let (url, handle) =
        adapter(b"\r\rt1008E8030000010000001234\rz\rt2004F401E803\rT123456782AABB\rxyz\r\x07r1004\rb2FF9000102030405060708090A0B\r");
    let out = run(
        &[
            "decode",
            "--dbc",
            dbc.to_str().expect("path"),
            "--slcan",
            &url,
            "--bitrate",
            "6",
        ],
        "",
    );
    let opened = handle.join().expect("adapter thread");
    assert_eq!(opened, b"C\rS6\rO\r", "closed, bit rate set, opened");
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout
        .lines()
        .map(|l| l.split_once(") ").map_or(l, |(_, rest)| rest))
        .collect();
    assert_eq!(
        lines,
        [
            format!(
                "{url} 100#E803000001000000 DistanceFrame(Distance: 1000 mm, WarningLevel: Yellow)"
            ),
            format!("{url} 200#F401E803 ThresholdConfig(RedBelow: 500 mm, YellowBelow: 1000 mm)"),
            format!("{url} 12345678#AABB (not in the DBC)"),
            format!("{url} 100#R4 (remote frame)"),
            format!("{url} 2FF##1000102030405060708090A0B (not in the DBC)"),
        ]
    );
    assert_eq!(
        text(&out.stderr),
        format!(
            "cw-can: {url}:7: `xyz` is no SLCAN frame\ncw-can: {url}:8: the adapter refused a command (BEL)\ncw-can: 2 bad line(s)\n"
        )
    );
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn a_live_source_stops_after_the_frames_asked_for() {
    let dbc = ecu_dbc();
    let (url, handle) = adapter(b"t3001AA\rt3001BB\rt3001CC\r");
    let out = run(
        &[
            "decode",
            "--dbc",
            dbc.to_str().expect("path"),
            "--slcan",
            &url,
            "--frames",
            "2",
        ],
        "",
    );
    handle.join().expect("adapter thread");
    assert_eq!(
        text(&out.stdout).lines().count(),
        2,
        "{}",
        text(&out.stderr)
    );
    let out = run(
        &[
            "decode",
            "--dbc",
            dbc.to_str().expect("path"),
            "--slcan",
            "socket://127.0.0.1:1",
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(2), "nothing listens there");
}

#[test]
fn view_needs_one_source_and_refuses_what_it_cannot_open() {
    let dbc = ecu_dbc();
    let dbc = dbc.to_str().expect("the DBC's path is UTF-8");
    let none = run(&["view", "--dbc", dbc], "");
    assert_eq!(none.status.code(), Some(2));
    assert!(text(&none.stderr).contains("--replay <LOG>|--simulate <SCENARIO>|--slcan <PORT>"));
    let two = run(
        &["view", "--dbc", dbc, "--replay", "a.log", "--slcan", "x"],
        "",
    );
    assert_eq!(two.status.code(), Some(2));
    let missing = run(
        &["view", "--dbc", dbc, "--replay", "/nonexistent/a.log"],
        "",
    );
    assert_eq!(missing.status.code(), Some(2));
    assert!(
        text(&missing.stderr).contains("cannot read /nonexistent/a.log"),
        "{}",
        text(&missing.stderr)
    );
    let scenario = run(
        &["view", "--dbc", dbc, "--simulate", "/nonexistent/s.txt"],
        "",
    );
    assert_eq!(scenario.status.code(), Some(2));
    assert!(text(&scenario.stderr).contains("cannot read scenario /nonexistent/s.txt"));
    let speed = run(
        &["view", "--dbc", dbc, "--simulate", "x.txt", "--speed", "2"],
        "",
    );
    assert_eq!(speed.status.code(), Some(2), "--speed is a replay's");
}

#[test]
fn no_strict_keeps_what_strict_refuses_as_warnings_and_refuses_only_the_frames_it_cannot_read() {
    let dbc = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/opendbc-faults.dbc");
    let dbc = dbc.to_str().expect("path");
    let log = "(0.0) can0 001#1234\n(0.1) can0 002#1234\n(0.2) can0 006#0205\n";
    let strict = run(&["decode", "--dbc", dbc, "-"], log);
    assert_eq!(strict.status.code(), Some(2));
    assert_eq!(
        text(&strict.stderr),
        format!("cw-can: {dbc}: message Overlap: signals S and T share bits\n")
    );
    let lenient = run(&["decode", "--no-strict", "--dbc", dbc, "-"], log);
    assert_eq!(lenient.status.code(), Some(1), "one frame was refused");
    assert_eq!(
        text(&lenient.stdout),
        "\
(0.100000) can0 002#1234 Orders(L: 18, B: 18)
(0.200000) can0 006#0205 Named(Index: two)
"
    );
    let stderr = text(&lenient.stderr);
    assert!(stderr.starts_with(&format!(
        "cw-can: warning: {dbc}: message Overlap: signals S and T share bits\n"
    )));
    assert_eq!(stderr.matches("cw-can: warning: ").count(), 5);
    assert!(stderr.ends_with(
        "cw-can: -:1: 001#1234: message Overlap: signals S and T share bits (kept by --no-strict): the frame carries them and cannot be decoded\ncw-can: 1 bad line(s)\n"
    ));
}
