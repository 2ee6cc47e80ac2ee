use std::io::{Read, Write};

use super::*;
use crate::view::state::{Level, Reading, Status};

const ECU_DBC: &[u8] = include_bytes!("../../../../firmware/ecu.dbc");

fn db() -> Database {
    Database::from_bytes(ECU_DBC).unwrap_or_else(|e| panic!("ecu.dbc: {e}"))
}

fn until(feed: &Shared, what: &str, mut done: impl FnMut(&super::super::feed::Snapshot) -> bool) {
    let start = Instant::now();
    loop {
        // As the server's clock does.
        let snap = {
            let mut feed = feed.lock().unwrap_or_else(PoisonError::into_inner);
            feed.tick(0.01);
            feed.snapshot()
        };
        if done(&snap) {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "{what}: {snap:?}"
        );
        thread::sleep(Duration::from_millis(10));
    }
}

fn send(feed: &Shared, frame: &Frame) -> Result<(), crate::view::feed::SendError> {
    let thresholds = crate::view::state::Thresholds {
        t: None,
        red_below_mm: 500,
        yellow_below_mm: 1000,
    };
    feed.lock()
        .unwrap_or_else(PoisonError::into_inner)
        .send(frame, thresholds)
}

/// RedBelow 500 mm, YellowBelow 1000 mm.
fn config() -> Frame {
    Frame::classic(0x200, false, &[0xF4, 0x01, 0xE8, 0x03])
}

#[test]
fn the_simulation_runs_live_and_takes_the_pcs_thresholds() {
    let scenario = Scenario::parse("hold 800 60000").unwrap_or_else(|e| panic!("{e}"));
    let feed = simulation(&db(), scenario, 1, "hold 800").unwrap_or_else(|e| panic!("{e}"));
    until(&feed, "800 mm, red", |s| {
        s.shown.status == Status::Live
            && s.shown.sample.map(|x| (x.reading, x.level))
                == Some((Reading::Distance(800), Level::Red))
    });
    assert!(s_can_send(&feed));
    assert_eq!(send(&feed, &config()), Ok(()));
    until(&feed, "800 mm is yellow below 1000 mm", |s| {
        s.shown.sample.map(|x| x.level) == Some(Level::Yellow) && s.shown.yellow && !s.shown.red
    });
    // The PC's frame was on the bus: the chart draws its thresholds.
    let drawn = feed
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .snapshot()
        .thresholds;
    assert_eq!((drawn.red_below_mm, drawn.yellow_below_mm), (500, 1000));
    assert!(drawn.t.is_some());
    let fd = Frame {
        kind: crate::frame::FrameKind::Fd {
            brs: false,
            esi: false,
        },
        ..config()
    };
    assert!(send(&feed, &fd).is_err());
}

fn s_can_send(feed: &Shared) -> bool {
    feed.lock()
        .unwrap_or_else(PoisonError::into_inner)
        .snapshot()
        .can_send
}

#[test]
fn an_slcan_adapter_feeds_the_view_and_takes_the_panels_frames() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap_or_else(|e| panic!("{e}"));
    let addr = listener.local_addr().unwrap_or_else(|e| panic!("{e}"));
    let adapter = thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap_or_else(|e| panic!("{e}"));
        s.set_read_timeout(Some(Duration::from_millis(20)))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut got = Vec::new();
        let mut buf = [0u8; 256];
        // 800 mm, Red, every 20 ms, and one line that is no frame; until the panel's
        // ThresholdConfig arrives.
        s.write_all(b"t8001AA\r").unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..500 {
            if s.write_all(b"t10082003000002000000\r").is_err() {
                break;
            }
            if let Ok(n) = s.read(&mut buf) {
                got.extend_from_slice(buf.get(..n).unwrap_or(&[]));
            }
            if got.ends_with(b"t2004F401E803\r") {
                break;
            }
        }
        got
    });
    let url = format!("socket://{addr}");
    let feed = slcan(&db(), &url, 0, None).unwrap_or_else(|e| panic!("{e}"));
    until(&feed, "800 mm, red, one bad line", |s| {
        s.source == "slcan"
            && s.shown.status == Status::Live
            && s.shown.sample.map(|x| x.reading) == Some(Reading::Distance(800))
            && s.bad_count == 1
    });
    assert_eq!(send(&feed, &config()), Ok(()));
    let got = adapter
        .join()
        .unwrap_or_else(|_| panic!("the fake adapter failed"));
    assert!(got.starts_with(b"C\rO\r"), "{got:?}");
    assert!(got.ends_with(b"t2004F401E803\r"), "{got:?}");
    // The adapter is gone: a bad line says so, and without frames the view shows no
    // signal within 200 ms of the last.
    until(&feed, "the stream's end named, no signal", |s| {
        s.shown.status == Status::NoSignal
            && s.bad
                .last()
                .is_some_and(|b| b.ends_with("the adapter's stream ended"))
    });
}
