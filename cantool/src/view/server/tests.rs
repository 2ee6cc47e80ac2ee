//! The server as a client meets it, over real sockets: the page, the snapshot, the
//! controls, the sender panel, refusals with their reasons, and the event streams' bound.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::thread::JoinHandle;
use std::time::Instant;

use super::*;
use crate::dbc::Database;
use crate::frame::Frame;
use crate::log::Entry;
use crate::view::feed::Live;
use crate::view::state::{Replay, ViewFrames};

const ECU_DBC: &[u8] = include_bytes!("../../../../firmware/ecu.dbc");

fn db() -> Database {
    Database::from_bytes(ECU_DBC).unwrap_or_else(|e| panic!("ecu.dbc: {e}"))
}

/// Three seconds of `DistanceFrame`s every 40 ms at 1.5 m, level Yellow.
fn replay() -> Feed {
    let db = db();
    let frame = ViewFrames::find(&db).unwrap_or_else(|e| panic!("{e}"));
    let entries = (0..75).map(|i| {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&1500u32.to_le_bytes());
        data[4] = 1;
        let entry = Entry {
            timestamp: 100.0 + f64::from(i) * 0.04,
            channel: "can0".into(),
            frame: Frame::classic(0x100, false, &data),
        };
        Ok((crate::log::At::Line(i as usize + 1), entry))
    });
    Feed::Replay(Replay::new(&frame, entries, "test.log"), "test.log".into())
}

struct Running {
    addr: SocketAddr,
    stop: Stop,
    server: JoinHandle<Result<(), String>>,
}

impl Running {
    fn start(feed: Feed) -> Self {
        let config = db().by_name("ThresholdConfig").cloned();
        let view = View::bind("127.0.0.1:0", Arc::new(Mutex::new(feed)), config)
            .unwrap_or_else(|e| panic!("{e}"));
        let addr = view.addr().unwrap_or_else(|e| panic!("{e}"));
        let stop = view.stopper();
        let server = std::thread::spawn(move || view.run());
        Self { addr, stop, server }
    }

    /// One request; the status and the body.
    fn ask(&self, method: &str, path: &str, json: Option<&str>) -> (u16, String) {
        let mut s = TcpStream::connect(self.addr).unwrap_or_else(|e| panic!("{e}"));
        let body = json.unwrap_or("");
        let kind = if json.is_some() {
            "Content-Type: application/json\r\n"
        } else {
            ""
        };
        let head = format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n{kind}Content-Length: {}\r\n\r\n",
            body.len()
        );
        s.write_all(head.as_bytes())
            .unwrap_or_else(|e| panic!("{e}"));
        s.write_all(body.as_bytes())
            .unwrap_or_else(|e| panic!("{e}"));
        let mut reply = String::new();
        s.read_to_string(&mut reply)
            .unwrap_or_else(|e| panic!("{e}"));
        let status = reply
            .get(9..12)
            .and_then(|c| c.parse().ok())
            .unwrap_or_else(|| panic!("no status in {reply:?}"));
        let body = reply.split_once("\r\n\r\n").map_or("", |(_, b)| b);
        (status, body.to_string())
    }

    fn state(&self) -> serde_json::Value {
        let (status, body) = self.ask("GET", "/state", None);
        assert_eq!(status, 200, "{body}");
        serde_json::from_str(&body).unwrap_or_else(|e| panic!("{e}: {body}"))
    }

    fn stop(self) {
        self.stop.stop();
        match self.server.join() {
            Ok(result) => assert_eq!(result, Ok(())),
            Err(_) => panic!("the server panicked"),
        }
    }
}

/// An event stream's socket, after its first event.
fn stream(addr: SocketAddr) -> (u16, TcpStream) {
    let mut s = TcpStream::connect(addr).unwrap_or_else(|e| panic!("{e}"));
    s.write_all(b"GET /events HTTP/1.1\r\nHost: localhost\r\n\r\n")
        .unwrap_or_else(|e| panic!("{e}"));
    let mut seen = Vec::new();
    let mut buf = [0u8; 4096];
    while !String::from_utf8_lossy(&seen).contains("data:")
        && !String::from_utf8_lossy(&seen).contains("too many")
    {
        let n = s.read(&mut buf).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            n > 0,
            "the stream ended: {}",
            String::from_utf8_lossy(&seen)
        );
        seen.extend_from_slice(&buf[..n]);
    }
    let text = String::from_utf8_lossy(&seen);
    let status = text.get(9..12).and_then(|c| c.parse().ok()).unwrap_or(0);
    (status, s)
}

fn until(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < Duration::from_secs(10), "{what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn the_page_is_served_from_the_binary() {
    let view = Running::start(replay());
    let (status, page) = view.ask("GET", "/", None);
    assert_eq!(status, 200);
    for hook in [
        "id=\"top-obstacle\"",
        "id=\"led-red\"",
        "id=\"readout\"",
        "/view.js",
    ] {
        assert!(page.contains(hook), "the page has no {hook}");
    }
    assert_eq!(view.ask("GET", "/view.js", None), (200, SCRIPT.to_string()));
    assert_eq!(view.ask("GET", "/view.css", None), (200, STYLE.to_string()));
    assert_eq!(view.ask("GET", "/nothing", None).0, 404);
    assert_eq!(view.ask("POST", "/state", Some("{}")).0, 405);
    view.stop();
}

#[test]
fn controls_move_the_replay_and_bad_ones_are_refused_with_a_reason() {
    let view = Running::start(replay());
    let state = view.state();
    assert_eq!(state["source"], "replay");
    assert_eq!(state["clock"]["playing"], false);
    assert_eq!(state["shown"]["status"], "Live");

    let seek = view.ask("POST", "/control", Some(r#"{"seek": 1.5, "speed": 2}"#));
    assert_eq!(seek, (200, "ok".to_string()));
    let state = view.state();
    assert_eq!(state["clock"]["position"], 1.5);
    assert_eq!(state["clock"]["speed"], 2.0);
    assert_eq!(state["shown"]["sample"]["reading"]["mm"], 1500);
    assert_eq!(state["shown"]["yellow"], true);

    // Refused, each with its reason; nothing changes.
    let (status, why) = view.ask("POST", "/control", Some(r#"{"speed": 0}"#));
    assert_eq!(
        (status, why.as_str()),
        (409, "speed 0 is not between 0.05 and 1000")
    );
    assert_eq!(
        view.ask("POST", "/control", Some(r#"{"rewind": true}"#)).0,
        422
    );
    assert_eq!(view.ask("POST", "/control", Some("{seek")).0, 400);
    assert_eq!(view.ask("POST", "/control", None).0, 415);
    let long = format!(r#"{{"seek": 1{}}}"#, "0".repeat(BODY_MAX));
    assert_eq!(view.ask("POST", "/control", Some(&long)).0, 413);
    assert_eq!(view.state()["clock"]["speed"], 2.0);

    // A replay has no bus to send to.
    let (status, why) = view.ask(
        "POST",
        "/send",
        Some(r#"{"red_below_mm": 500, "yellow_below_mm": 900}"#),
    );
    assert_eq!(
        (status, why.as_str()),
        (409, "a replayed log has no bus to send to")
    );

    // Playing moves the clock by the time that passes, at the speed set.
    assert_eq!(
        view.ask("POST", "/control", Some(r#"{"play": true}"#)).0,
        200
    );
    until("the replay plays to its end", || {
        view.state()["clock"]["playing"] == false
    });
    let end = view.state();
    assert_eq!(end["clock"]["position"], end["clock"]["duration"]);
    view.stop();
}

#[test]
fn the_sender_panel_puts_threshold_config_on_a_live_bus() {
    let sent: Arc<Mutex<Vec<Frame>>> = Arc::default();
    let bus = Arc::clone(&sent);
    let live = Live::new(
        "simulation",
        "test bus",
        Some(Box::new(move |frame: &Frame| {
            bus.lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push(frame.clone());
            Ok(())
        })),
        false,
    );
    let view = Running::start(Feed::Live(live));
    assert_eq!(view.state()["can_send"], true);
    // A live bus has no clock to set.
    assert_eq!(
        view.ask("POST", "/control", Some(r#"{"play": true}"#)).0,
        409
    );

    let ok = view.ask(
        "POST",
        "/send",
        Some(r#"{"red_below_mm": 500, "yellow_below_mm": 900}"#),
    );
    assert_eq!(ok, (200, "ok".to_string()));
    // The ECU's rule, and the DBC's 16-bit range: refused before the bus.
    for (body, why) in [
        (
            r#"{"red_below_mm": 0, "yellow_below_mm": 900}"#,
            "red below 0 mm would never be red",
        ),
        (
            r#"{"red_below_mm": 900, "yellow_below_mm": 900}"#,
            "red must be below yellow",
        ),
    ] {
        assert_eq!(
            view.ask("POST", "/send", Some(body)),
            (422, why.to_string())
        );
    }
    let (status, why) = view.ask(
        "POST",
        "/send",
        Some(r#"{"red_below_mm": 500, "yellow_below_mm": 70000}"#),
    );
    assert_eq!(status, 422);
    assert!(why.contains("YellowBelow"), "{why}");
    assert_eq!(
        view.state()["thresholds"]["red_below_mm"],
        500,
        "drawn once sent"
    );
    let sent = sent.lock().unwrap_or_else(PoisonError::into_inner).clone();
    // RedBelow 500 = 0x01F4 and YellowBelow 900 = 0x0384, little-endian, id 0x200.
    assert_eq!(
        sent,
        vec![Frame::classic(0x200, false, &[0xF4, 0x01, 0x84, 0x03])]
    );
    view.stop();
}

/// A raw request; the status.
fn raw(addr: SocketAddr, request: &str) -> u16 {
    let mut s = TcpStream::connect(addr).unwrap_or_else(|e| panic!("{e}"));
    s.write_all(request.as_bytes())
        .unwrap_or_else(|e| panic!("{e}"));
    let mut reply = String::new();
    s.read_to_string(&mut reply)
        .unwrap_or_else(|e| panic!("{e}"));
    reply.get(9..12).and_then(|c| c.parse().ok()).unwrap_or(0)
}

#[test]
fn other_sites_and_other_names_are_refused() {
    let view = Running::start(replay());
    let get = |host: &str| {
        raw(
            view.addr,
            &format!("GET /state HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"),
        )
    };
    for host in ["127.0.0.1", "127.0.0.1:8080", "localhost:1", "[::1]:8080"] {
        assert_eq!(get(host), 200, "{host}");
    }
    // A rebound name, or none.
    for host in [
        "evil.example",
        "evil.example:8080",
        "127.0.0.1.evil.example",
        "",
    ] {
        assert_eq!(get(host), 403, "{host}");
    }
    let post = |origin: &str| {
        let body = r#"{"play": true}"#;
        raw(
            view.addr,
            &format!(
                "POST /control HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nOrigin: {origin}\r\n\
                 Connection: close\r\nContent-Type: application/json\r\n\
                 Content-Length: {}\r\n\r\n{body}",
                body.len()
            ),
        )
    };
    assert_eq!(post("http://evil.example"), 403);
    assert_eq!(view.state()["clock"]["playing"], false, "nothing changed");
    assert_eq!(post("http://127.0.0.1:8080"), 200, "the page itself");
    view.stop();
}

#[test]
fn event_streams_are_bounded_and_let_go_when_their_clients_leave() {
    let view = Running::start(replay());
    let mut streams: Vec<TcpStream> = (0..MAX_STREAMS)
        .map(|_| {
            let (status, s) = stream(view.addr);
            assert_eq!(status, 200);
            s
        })
        .collect();
    let (status, _refused) = stream(view.addr);
    assert_eq!(status, 503);
    assert_eq!(view.state()["streams"], MAX_STREAMS);
    // Ten clients leave mid-stream; the server lets go of them and takes new ones.
    streams.truncate(MAX_STREAMS - 10);
    until("the server counts the streams left", || {
        view.state()["streams"] == MAX_STREAMS - 10
    });
    let (status, _again) = stream(view.addr);
    assert_eq!(status, 200);
    // Stopping ends every stream and then the server.
    view.stop();
}
