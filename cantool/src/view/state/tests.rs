use super::*;
use crate::frame::Frame;
use crate::log::CandumpReader;

const ECU_DBC: &[u8] = include_bytes!("../../../../firmware/ecu.dbc");

fn db() -> Database {
    match Database::from_bytes(ECU_DBC) {
        Ok(db) => db,
        Err(e) => panic!("ecu.dbc: {e}"),
    }
}

/// A `DistanceFrame` entry: distance (mm, or the DBC's special values) and raw level.
fn entry(t: f64, distance: u32, level: u8) -> Entry {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&distance.to_le_bytes());
    data[4] = level;
    Entry {
        timestamp: t,
        channel: "can0".into(),
        frame: Frame::classic(0x100, false, &data),
    }
}

fn sample(db: &Database, e: &Entry) -> Result<Sample, String> {
    let Ok(frame) = ViewFrames::find(db) else {
        panic!("ecu.dbc has a DistanceFrame")
    };
    match frame.sample(e) {
        Some(s) => s,
        None => panic!("{e:?} is a DistanceFrame"),
    }
}

#[test]
fn distance_frames_decode_with_the_dbcs_names() {
    let db = db();
    let cases = [
        (999, 2, Reading::Distance(999), Level::Red),
        (1500, 1, Reading::Distance(1500), Level::Yellow),
        (2500, 0, Reading::Distance(2500), Level::Off),
        (u32::MAX, 3, Reading::Invalid, Level::Fault),
        (u32::MAX - 1, 0, Reading::NothingInRange, Level::Off),
    ];
    for (mm, level, reading, expected) in cases {
        assert_eq!(
            sample(&db, &entry(1.0, mm, level)),
            Ok(Sample {
                t: 1.0,
                reading,
                level: expected
            })
        );
    }
    // A level the DBC does not name is an error, not a guess.
    assert_eq!(
        sample(&db, &entry(1.0, 500, 7)),
        Err("warning level 7 is not one the DBC names".into())
    );
    // Other frames are not the view's.
    let Ok(frame) = ViewFrames::find(&db) else {
        panic!("ecu.dbc has a DistanceFrame")
    };
    let other = Entry {
        frame: Frame::classic(0x200, false, &[0xF4, 1, 0xE8, 3]),
        ..entry(1.0, 0, 0)
    };
    assert_eq!(frame.sample(&other), None);
    // A DistanceFrame too short for its message is refused by the codec.
    let short = Entry {
        frame: Frame::classic(0x100, false, &[1, 2]),
        ..entry(1.0, 0, 0)
    };
    assert!(matches!(frame.sample(&short), Some(Err(_))));
}

#[test]
fn a_dbc_without_the_frame_or_its_signals_is_refused() {
    let Ok(other) = Database::from_bytes(
        b"VERSION \"\"\nNS_ :\nBS_:\nBU_: A\nBO_ 1 M: 1 A\n SG_ S : 0|8@1+ (1,0) [0|255] \"\" A\n",
    ) else {
        panic!("a valid DBC")
    };
    assert_eq!(
        ViewFrames::find(&other).map(|_| ()),
        Err("the DBC has no message `DistanceFrame`".into())
    );
    let Ok(renamed) = Database::from_bytes(
        b"VERSION \"\"\nNS_ :\nBS_:\nBU_: A\nBO_ 256 DistanceFrame: 8 A\n SG_ Dist : 0|32@1+ (1,0) [0|0] \"\" A\n SG_ WarningLevel : 32|8@1+ (1,0) [0|3] \"\" A\n",
    ) else {
        panic!("a valid DBC")
    };
    assert_eq!(
        ViewFrames::find(&renamed).map(|_| ()),
        Err("`DistanceFrame` has no signal `Distance`".into())
    );
}

#[test]
fn no_frame_for_200_ms_is_no_signal_whatever_the_last_one_said() {
    let red = Sample {
        t: 10.0,
        reading: Reading::Distance(500),
        level: Level::Red,
    };
    assert_eq!(shown(None, 10.0).status, Status::NoSignal);
    let live = shown(Some(&red), 10.199);
    assert_eq!(
        (live.status, live.red, live.yellow),
        (Status::Live, true, false)
    );
    let stale = shown(Some(&red), 10.2);
    assert_eq!(
        stale,
        Shown {
            status: Status::NoSignal,
            sample: None,
            red: false,
            yellow: false,
            blinking: false
        }
    );
}

#[test]
fn a_fault_blinks_both_leds_and_the_level_alone_lights_them() {
    let at = |reading, level| {
        shown(
            Some(&Sample {
                t: 0.0,
                reading,
                level,
            }),
            0.05,
        )
    };
    let fault = at(Reading::Invalid, Level::Fault);
    assert_eq!(
        (fault.status, fault.red, fault.yellow, fault.blinking),
        (Status::Fault, true, true, true)
    );
    // An invalid distance is a fault even if the level (wrongly) says otherwise.
    assert_eq!(at(Reading::Invalid, Level::Off).status, Status::Fault);
    // The LEDs are what the frame's level names, not what the distance would give.
    let off_at_500 = at(Reading::Distance(500), Level::Off);
    assert_eq!((off_at_500.red, off_at_500.yellow), (false, false));
    let yellow = at(Reading::Distance(2500), Level::Yellow);
    assert_eq!(
        (yellow.red, yellow.yellow, yellow.blinking),
        (false, true, false)
    );
    let nothing = at(Reading::NothingInRange, Level::Off);
    assert_eq!(nothing.status, Status::Live);
}

fn replay_of(log: &str) -> Replay {
    let db = db();
    let Ok(frame) = ViewFrames::find(&db) else {
        panic!("ecu.dbc has a DistanceFrame")
    };
    let mut reader = CandumpReader::new(log.as_bytes());
    let entries = std::iter::from_fn(move || {
        reader
            .next()
            .map(|x| x.map(|e| (At::Line(reader.line()), e)))
    });
    Replay::new(&frame, entries, "t.log")
}

#[test]
fn a_replay_names_bad_lines_and_frames_and_plays_the_rest_in_time_order() {
    let replay = replay_of(
        "(100.000000) can0 100#E803000001000000\n\
         (100.040000) can0 garbage\n\
         (100.080000) can0 100#F401000007000000\n\
         (100.200000) can0 100#F401000002000000\n\
         (100.120000) can0 100#D007000000000000\n\
         (101.000000) can0 200#F401E803\n",
    );
    assert_eq!(replay.bad().len(), 2, "{:?}", replay.bad());
    assert!(
        replay.bad()[0].starts_with("t.log:2: "),
        "{:?}",
        replay.bad()
    );
    assert_eq!(
        replay.bad()[1],
        "t.log:3: warning level 7 is not one the DBC names"
    );
    let ms: Vec<i64> = replay
        .samples()
        .iter()
        .map(|s| (s.t * 1000.0).round() as i64)
        .collect();
    assert_eq!(ms, [100_000, 100_120, 100_200]);
    assert!((replay.duration() - 1.0).abs() < 1e-9);
    assert!(!replay.playing());
    assert_eq!(
        replay.shown().sample.map(|s| s.reading),
        Some(Reading::Distance(1000))
    );
}

#[test]
fn the_clock_plays_at_its_speed_seeks_within_the_log_and_stops_at_the_end() {
    let mut replay = replay_of(
        "(0.000000) can0 100#E803000001000000\n\
         (1.000000) can0 100#F401000002000000\n\
         (1.100000) can0 100#F401000002000000\n\
         (4.000000) can0 100#FFFFFFFF03000000\n",
    );
    replay.advance(1.0);
    assert_eq!(replay.position(), 0.0, "paused: the clock does not move");
    replay.set_playing(true);
    assert_eq!(replay.set_speed(2.0), Ok(()));
    replay.advance(0.5);
    assert_eq!(replay.position(), 1.0);
    assert_eq!(replay.shown().status, Status::Live);
    assert_eq!(replay.shown().sample.map(|s| s.level), Some(Level::Red));
    replay.advance(0.5);
    // 2.0 s: the last frame was at 1.1 s.
    assert_eq!(replay.shown().status, Status::NoSignal);
    assert_eq!(replay.window(0.5).len(), 0);
    assert_eq!(replay.window(1.5).len(), 2);
    replay.advance(10.0);
    assert_eq!((replay.position(), replay.playing()), (4.0, false));
    assert_eq!(replay.shown().status, Status::Fault);
    replay.set_playing(true);
    assert_eq!(replay.position(), 0.0, "playing from the end starts again");
    for bad in [0.0, -1.0, f64::NAN, 1001.0] {
        assert!(replay.set_speed(bad).is_err(), "{bad}");
    }
    assert_eq!(replay.speed(), 2.0);
    replay.seek(-5.0);
    assert_eq!(replay.position(), 0.0);
    replay.seek(99.0);
    assert_eq!(replay.position(), 4.0);
    replay.seek(f64::NAN);
    assert_eq!(replay.position(), 4.0);
}

/// One operation on a replay.
#[derive(Debug, Clone, Copy, bolero::TypeGenerator)]
enum Op {
    Advance(u16),
    Seek(i32),
    Speed(u8),
    Play(bool),
}

/// Any log of `DistanceFrame`s (any times, in any order, any distance and level byte)
/// under any operations: the clock stays within the log, the newest sample is the last one
/// at or before the clock, and the picture follows the rules (no signal after 200 ms,
/// fault, LEDs from the level).
#[test]
fn any_replay_under_any_operations_shows_what_the_rules_say() {
    let db = db();
    let Ok(frame) = ViewFrames::find(&db) else {
        panic!("ecu.dbc has a DistanceFrame")
    };
    bolero::check!()
        .with_type::<(Vec<(u16, u32, u8)>, Vec<Op>)>()
        .for_each(|(frames, ops)| {
            let entries = frames.iter().enumerate().map(|(i, &(ms, mm, level))| {
                Ok((
                    At::Line(i + 1),
                    entry(f64::from(ms) / 1000.0, mm, level % 5),
                ))
            });
            let mut replay = Replay::new(&frame, entries, "any");
            let named = frames.iter().filter(|f| f.2 % 5 <= 3).count();
            assert_eq!(replay.samples().len(), named);
            assert_eq!(replay.bad().len(), frames.len() - named);
            for op in ops.iter().take(32) {
                match *op {
                    Op::Advance(ms) => replay.advance(f64::from(ms) / 1000.0),
                    Op::Seek(ms) => replay.seek(f64::from(ms) / 1000.0),
                    Op::Speed(s) => {
                        let _ = replay.set_speed(f64::from(s) / 10.0);
                    }
                    Op::Play(p) => replay.set_playing(p),
                }
                assert!((0.0..=replay.duration()).contains(&replay.position()));
                let now = replay.now();
                let reference = replay.samples().iter().rev().find(|s| s.t <= now);
                assert_eq!(replay.newest(), reference);
                let shown = replay.shown();
                match reference.filter(|s| ((now - s.t) * 1e6).round() < 200_000.0) {
                    None => assert_eq!(shown.status, Status::NoSignal),
                    Some(s) => {
                        let fault = s.level == Level::Fault || s.reading == Reading::Invalid;
                        assert_eq!(shown.blinking, fault);
                        assert_eq!(shown.red, fault || s.level == Level::Red);
                        assert_eq!(shown.yellow, fault || s.level == Level::Yellow);
                    }
                }
                assert!(replay
                    .window(1.0)
                    .iter()
                    .all(|s| s.t <= now && s.t >= now - 1.0));
            }
        });
}

#[test]
fn the_chart_draws_the_newest_thresholds_the_ecu_would_take() {
    // 200#: RedBelow, YellowBelow, little-endian. 500/1000 at 1 s, 900/900 (refused by
    // the ECU's rule) at 2 s, 0/700 (refused) at 3 s, 1500/2500 stamped 0.5 s but read last.
    let mut replay = replay_of(
        "(0.000000) can0 100#E803000001000000\n\
         (1.000000) can0 200#F401E803\n\
         (2.000000) can0 200#84038403\n\
         (3.000000) can0 200#0000BC02\n\
         (4.000000) can0 100#E803000001000000\n\
         (0.500000) can0 200#DC05C409\n",
    );
    let at = |replay: &mut Replay, t: f64| {
        replay.seek(t);
        let th = replay.thresholds();
        (th.red_below_mm, th.yellow_below_mm, th.t)
    };
    assert_eq!(replay.thresholds(), Thresholds::PAPER);
    assert_eq!(at(&mut replay, 0.7), (1500, 2500, Some(0.5)));
    assert_eq!(at(&mut replay, 1.0), (500, 1000, Some(1.0)));
    assert_eq!(
        at(&mut replay, 3.5),
        (500, 1000, Some(1.0)),
        "refused ones are not drawn"
    );
    assert!(
        replay.bad().is_empty(),
        "a refused configuration is no bad frame"
    );
}
