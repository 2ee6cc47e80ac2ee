use super::*;

fn sample(t: f64, mm: u32, level: Level) -> Sample {
    Sample {
        t,
        reading: Reading::Distance(mm),
        level,
    }
}

#[test]
fn a_live_bus_keeps_the_charts_window_only() {
    let mut live = Live::new("slcan", "socket://x", None, false);
    for i in 0..1000 {
        live.push(sample(f64::from(i) * 0.04, 1000 + i, Level::Yellow));
    }
    // 39.96 s now: the window holds 10 s of 40 ms frames.
    assert!(live.recent.len() <= 251, "{}", live.recent.len());
    assert!(live.recent.iter().all(|s| s.t >= live.now - CHART_SECONDS));
    let feed = Feed::Live(live);
    let snap = feed.snapshot();
    assert_eq!(snap.shown.status, Status::Live);
    assert_eq!(
        snap.shown.sample.map(|s| s.reading),
        Some(Reading::Distance(1999))
    );
    assert!(snap.chart.len() <= CHART_POINTS);
    assert_eq!(snap.chart.last(), Some(&(0.0, Some(1999), 1)));
    assert!(!snap.can_send);
}

#[test]
fn a_silent_live_bus_shows_no_signal_and_forgets_its_frames() {
    let mut live = Live::new("simulation", "sim", None, false);
    live.push(sample(5.0, 800, Level::Red));
    live.set_now(5.199_999);
    assert_eq!(Feed::Live(live).snapshot().shown.status, Status::Live);
    let mut live = Live::new("simulation", "sim", None, false);
    live.push(sample(5.0, 800, Level::Red));
    live.set_now(5.2);
    live.set_now(1.0);
    live.set_now(f64::NAN);
    assert_eq!(live.now, 5.2, "the clock never goes back");
    let snap = Feed::Live(live).snapshot();
    assert_eq!(
        (snap.shown.status, snap.shown.red),
        (Status::NoSignal, false)
    );
    let mut live = Live::new("simulation", "sim", None, false);
    live.push(sample(5.0, 800, Level::Red));
    live.set_now(15.0 + 1e-9);
    assert!(live.recent.is_empty());
}

#[test]
fn bad_lines_are_counted_all_and_the_newest_named() {
    let mut live = Live::new("slcan", "socket://x", None, false);
    for i in 0..100 {
        live.bad(format!("socket://x:{i}: bad"));
    }
    assert_eq!(live.bad.len(), BAD_KEPT);
    let snap = Feed::Live(live).snapshot();
    assert_eq!(snap.bad_count, 100);
    let named: Vec<String> = (95..100).map(|i| format!("socket://x:{i}: bad")).collect();
    assert_eq!(snap.bad, named);
}

#[test]
fn a_dense_window_is_thinned_evenly() {
    let samples: Vec<Sample> = (0..1000)
        .map(|i| sample(f64::from(i) * 0.01, 1000, Level::Off))
        .collect();
    let points = chart(samples.iter(), 9.99);
    assert_eq!(points.len(), 250);
    assert_eq!(points.first().map(|p| p.0), Some(9.99));
    assert!(points
        .windows(2)
        .all(|w| (w[0].0 - w[1].0 - 0.04).abs() < 1e-9));
    let special = [
        Sample {
            t: 1.0,
            reading: Reading::Invalid,
            level: Level::Fault,
        },
        Sample {
            t: 1.0,
            reading: Reading::NothingInRange,
            level: Level::Off,
        },
    ];
    assert_eq!(
        chart(special.iter(), 1.5),
        vec![(0.5, None, 3), (0.5, None, 0)]
    );
}

#[test]
fn a_replay_refuses_to_send_and_a_live_bus_to_seek() {
    let mut live = Feed::Live(Live::new("slcan", "x", None, true));
    let frame = Frame::classic(0x200, false, &[1, 2, 3, 4]);
    assert_eq!(
        live.send(&frame, Thresholds::PAPER),
        Err(SendError::NoBus("this bus is read only".into()))
    );
    assert!(live.control(Control::default()).is_err());
    // Stamped by this PC's clock: the time now is the clock's.
    live.tick(0.01);
    assert!(live.snapshot().now > 1.7e9);
}

/// One thing that happens to a live bus.
#[derive(Debug, Clone, Copy, bolero::TypeGenerator)]
enum Event {
    Frame { ms: u32, mm: u16, level: u8 },
    Now(u32),
    Bad,
}

/// Any frames, in any order, any clock and bad lines: a live bus holds at most the chart's
/// window behind the newest time, the picture is the rules' for the newest frame at or
/// before now, the chart is at most [`CHART_POINTS`] points within the window.
#[test]
fn any_live_bus_keeps_its_window_and_shows_what_the_rules_say() {
    bolero::check!()
        .with_type::<Vec<Event>>()
        .for_each(|events| {
            let mut live = Live::new("slcan", "any", None, false);
            let mut all: Vec<Sample> = Vec::new();
            let mut bad = 0;
            for event in events.iter().take(400) {
                match *event {
                    Event::Frame { ms, mm, level } => {
                        let level = [Level::Off, Level::Yellow, Level::Red, Level::Fault]
                            [usize::from(level % 4)];
                        let s = sample(f64::from(ms) / 1000.0, u32::from(mm), level);
                        all.push(s);
                        live.push(s);
                    }
                    Event::Now(ms) => live.set_now(f64::from(ms) / 1000.0),
                    Event::Bad => {
                        bad += 1;
                        live.bad(format!("any:{bad}: bad"));
                    }
                }
                let now = live.now;
                assert!(live.recent.iter().all(|s| s.t >= now - CHART_SECONDS));
                assert!(live
                    .recent
                    .iter()
                    .zip(live.recent.iter().skip(1))
                    .all(|(a, b)| a.t <= b.t));
                assert!(live.bad.len() <= BAD_KEPT);
            }
            let now = live.now;
            let feed = Feed::Live(live);
            let snap = feed.snapshot();
            assert_eq!(snap.bad_count, bad);
            assert!(snap.bad.len() <= BAD_SHOWN);
            assert!(snap.chart.len() <= CHART_POINTS);
            assert!(snap
                .chart
                .iter()
                .all(|p| (0.0..=CHART_SECONDS + 1e-6).contains(&p.0)));
            // The reference: the newest frame at or before now, of all ever pushed.
            let newest = all
                .iter()
                .filter(|s| s.t <= now)
                .fold(None::<&Sample>, |best, s| match best {
                    Some(b) if b.t > s.t => Some(b),
                    _ => Some(s),
                });
            let expected = state::shown(newest, now);
            assert_eq!(snap.shown.status, expected.status);
            assert_eq!(
                (snap.shown.red, snap.shown.yellow),
                (expected.red, expected.yellow)
            );
            assert_eq!(snap.shown.sample.map(|s| s.t), expected.sample.map(|s| s.t));
        });
}

#[test]
fn a_live_bus_draws_the_newest_thresholds() {
    let mut live = Live::new("slcan", "x", None, false);
    let th = |t: f64, red: u32| Thresholds {
        t: Some(t),
        red_below_mm: red,
        yellow_below_mm: 3000,
    };
    assert_eq!(
        Feed::Live(Live::new("slcan", "x", None, false))
            .snapshot()
            .thresholds,
        Thresholds::PAPER
    );
    live.configure(th(2.0, 700));
    live.configure(th(1.0, 600));
    assert_eq!(
        Feed::Live(live).snapshot().thresholds,
        th(2.0, 700),
        "an older frame does not win"
    );
}
