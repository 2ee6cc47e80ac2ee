//! Where the view's frames come from, and what the page is sent: a [`Feed`] is a replayed
//! log (a [`Replay`] under its clock) or a live bus ([`Live`]: the frames a source thread
//! pushes, with the time now on their clock). Either gives a [`Snapshot`], the one JSON
//! object the page draws from.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

#[cfg(test)]
use super::state::Status;
use super::state::{self, Level, Reading, Replay, Sample, Shown, Thresholds};
use crate::frame::Frame;

/// The chart's window: the last 10 s of frames.
pub const CHART_SECONDS: f64 = 10.0;

/// The most points the chart is sent (250: 10 s of the ECU's 40 ms frames); a denser
/// window is thinned evenly.
pub const CHART_POINTS: usize = 250;

/// The most bad lines a snapshot names (the newest); the count covers them all.
pub const BAD_SHOWN: usize = 5;

/// The most bad lines a live feed keeps (the newest); the count covers them all.
const BAD_KEPT: usize = 64;

/// The feed, shared by the server's tasks and a live source's thread.
pub type Shared = std::sync::Arc<std::sync::Mutex<Feed>>;

/// A frame for the bus, from the page's sender panel.
pub type Sender = Box<dyn FnMut(&Frame) -> Result<(), String> + Send>;

/// A live bus: the newest frames, and the time now on their clock.
pub struct Live {
    kind: &'static str,
    name: String,
    recent: VecDeque<Sample>,
    now: f64,
    bad: VecDeque<String>,
    bad_count: usize,
    send: Option<Sender>,
    wall_clock: bool,
    origin: Option<f64>,
    thresholds: Thresholds,
}

impl Live {
    /// A live feed of `kind` (`"slcan"`, `"simulation"`) named `name`, with `send` the way
    /// to the bus for the sender panel (none: the panel is off). With `wall_clock`, the
    /// frames are stamped by this PC's clock (an adapter's, as python-can stamps them), and
    /// the time now is that clock's; without, the source sets it ([`Live::set_now`]).
    pub fn new(kind: &'static str, name: &str, send: Option<Sender>, wall_clock: bool) -> Self {
        Self {
            kind,
            name: name.to_string(),
            recent: VecDeque::new(),
            now: f64::NEG_INFINITY,
            bad: VecDeque::new(),
            bad_count: 0,
            send,
            wall_clock,
            origin: None,
            thresholds: Thresholds::PAPER,
        }
    }

    /// The frames' time that the page counts from (a simulation's start); without one, the
    /// page shows a frame's time of day.
    #[must_use]
    pub fn with_origin(mut self, origin: f64) -> Self {
        self.origin = Some(origin);
        self
    }

    /// A frame arrived. Samples older than the chart's window are let go, so a live feed
    /// holds at most [`CHART_SECONDS`] of frames however long it runs; a sample stamped
    /// before the newest goes where its time puts it.
    pub fn push(&mut self, sample: Sample) {
        let at = self.recent.partition_point(|p| p.t <= sample.t);
        self.recent.insert(at, sample);
        self.now = self.now.max(sample.t);
        self.forget();
    }

    /// A `ThresholdConfig` the ECU would take was on the bus: the newest one is drawn.
    pub fn configure(&mut self, thresholds: Thresholds) {
        if thresholds.t >= self.thresholds.t {
            self.thresholds = thresholds;
        }
    }

    /// A bad line or frame, named.
    pub fn bad(&mut self, what: String) {
        self.bad_count += 1;
        if self.bad.len() == BAD_KEPT {
            self.bad.pop_front();
        }
        self.bad.push_back(what);
    }

    /// The time now on the frames' clock (it never goes back).
    pub fn set_now(&mut self, now: f64) {
        if now.is_finite() {
            self.now = self.now.max(now);
            self.forget();
        }
    }

    fn forget(&mut self) {
        while self
            .recent
            .front()
            .is_some_and(|s| s.t < self.now - CHART_SECONDS)
        {
            self.recent.pop_front();
        }
    }
}

/// Why a frame did not go on the bus.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SendError {
    /// The feed has no bus to send to (a replay, a read-only bus, an ended simulation).
    NoBus(String),
    /// The bus failed to take the frame (the adapter's connection).
    Bus(String),
}

/// What the page asks of a replay; absent fields are left as they are.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Control {
    /// Play or pause.
    pub play: Option<bool>,
    /// Log seconds per second.
    pub speed: Option<f64>,
    /// Seconds since the log's first entry.
    pub seek: Option<f64>,
}

/// The view's frames.
pub enum Feed {
    /// A log, replayed (named).
    Replay(Replay, String),
    /// A live bus.
    Live(Live),
}

/// A replay's clock, as the page shows it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Clock {
    /// The frames' time at the log's first entry.
    pub start: f64,
    /// Seconds since then.
    pub position: f64,
    /// The log's length, seconds.
    pub duration: f64,
    /// Log seconds per second.
    pub speed: f64,
    /// Whether the clock runs.
    pub playing: bool,
}

/// One chart point: seconds before now, the distance in millimetres (none for nothing in
/// range or invalid), and the level (0 off, 1 yellow, 2 red, 3 fault).
pub type Point = (f64, Option<u32>, u8);

/// Everything the page draws, at one moment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Snapshot {
    /// `replay`, `slcan` or `simulation`.
    pub source: &'static str,
    /// The log's file or the bus's name.
    pub name: String,
    /// The time now on the frames' clock, seconds.
    pub now: f64,
    /// The frames' time the page counts from (a replay's first entry, a simulation's
    /// start); none: the page shows the time of day.
    pub origin: Option<f64>,
    /// The replay's clock (none for a live bus).
    pub clock: Option<Clock>,
    /// The picture.
    pub shown: Shown,
    /// The thresholds the chart draws.
    pub thresholds: Thresholds,
    /// The chart's points, oldest first, over the last [`CHART_SECONDS`].
    pub chart: Vec<Point>,
    /// How many lines or frames were bad.
    pub bad_count: usize,
    /// The newest of them (at most [`BAD_SHOWN`]), named `FILE:LINE: why`.
    pub bad: Vec<String>,
    /// Whether the sender panel reaches a bus.
    pub can_send: bool,
    /// How many event streams the server is sending (set by the server).
    pub streams: usize,
}

fn level_code(level: Level) -> u8 {
    match level {
        Level::Off => 0,
        Level::Yellow => 1,
        Level::Red => 2,
        Level::Fault => 3,
    }
}

/// The chart's points for `window` (oldest first) at `now`, thinned to [`CHART_POINTS`].
pub fn chart<'a>(window: impl ExactSizeIterator<Item = &'a Sample>, now: f64) -> Vec<Point> {
    let stride = window.len().div_ceil(CHART_POINTS).max(1);
    window
        .step_by(stride)
        .map(|s| {
            let mm = match s.reading {
                Reading::Distance(mm) => Some(mm),
                Reading::NothingInRange | Reading::Invalid => None,
            };
            // Microseconds, as a log stamps them.
            let ago = ((now - s.t) * 1e6).round() / 1e6;
            (ago, mm, level_code(s.level))
        })
        .collect()
}

fn newest_bad<'a>(bad: impl DoubleEndedIterator<Item = &'a String>) -> Vec<String> {
    let mut shown: Vec<String> = bad.rev().take(BAD_SHOWN).cloned().collect();
    shown.reverse();
    shown
}

impl Feed {
    /// Lets `wall` seconds pass: a replay's clock moves; a live bus stamped by this PC's
    /// clock reads it.
    pub fn tick(&mut self, wall: f64) {
        match self {
            Self::Replay(replay, _) => replay.advance(wall),
            Self::Live(live) if live.wall_clock => {
                let now = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0.0, |d| d.as_secs_f64());
                live.set_now(now);
            }
            Self::Live(_) => {}
        }
    }

    /// What the page draws now.
    pub fn snapshot(&self) -> Snapshot {
        match self {
            Self::Replay(replay, name) => Snapshot {
                source: "replay",
                name: name.clone(),
                now: replay.now(),
                origin: Some(replay.now() - replay.position()),
                clock: Some(Clock {
                    start: replay.now() - replay.position(),
                    position: replay.position(),
                    duration: replay.duration(),
                    speed: replay.speed(),
                    playing: replay.playing(),
                }),
                shown: replay.shown(),
                thresholds: replay.thresholds(),
                chart: chart(replay.window(CHART_SECONDS).iter(), replay.now()),
                bad_count: replay.bad().len(),
                bad: newest_bad(replay.bad().iter()),
                can_send: false,
                streams: 0,
            },
            Self::Live(live) => {
                let newest = live.recent.iter().rev().find(|s| s.t <= live.now);
                Snapshot {
                    source: live.kind,
                    name: live.name.clone(),
                    now: live.now,
                    origin: live.origin,
                    clock: None,
                    shown: state::shown(newest, live.now),
                    thresholds: live.thresholds,
                    chart: chart(
                        live.recent
                            .iter()
                            .filter(|s| s.t <= live.now)
                            .collect::<Vec<_>>()
                            .into_iter(),
                        live.now,
                    ),
                    bad_count: live.bad_count,
                    bad: newest_bad(live.bad.iter()),
                    can_send: live.send.is_some(),
                    streams: 0,
                }
            }
        }
    }

    /// Plays, pauses, sets the speed or seeks a replay.
    ///
    /// # Errors
    /// A live bus (it has no clock to set), or a speed out of range; nothing is changed
    /// then.
    pub fn control(&mut self, control: Control) -> Result<(), String> {
        let Self::Replay(replay, _) = self else {
            return Err("a live bus cannot be paused, sped up or seeked".into());
        };
        if let Some(speed) = control.speed {
            replay.set_speed(speed)?;
        }
        if let Some(position) = control.seek {
            replay.seek(position);
        }
        if let Some(play) = control.play {
            replay.set_playing(play);
        }
        Ok(())
    }

    /// Puts `frame`, which carries `thresholds`, on the bus; the chart draws them from
    /// then on (an adapter does not hand back the frames it sends).
    ///
    /// # Errors
    /// [`SendError::NoBus`] for a replay or a feed with no way to send;
    /// [`SendError::Bus`] when the bus fails to take it.
    pub fn send(&mut self, frame: &Frame, thresholds: Thresholds) -> Result<(), SendError> {
        match self {
            Self::Replay(..) => Err(SendError::NoBus(
                "a replayed log has no bus to send to".into(),
            )),
            Self::Live(live) => {
                let send = live
                    .send
                    .as_mut()
                    .ok_or_else(|| SendError::NoBus("this bus is read only".into()))?;
                send(frame).map_err(SendError::Bus)?;
                live.configure(Thresholds {
                    t: Some(live.now),
                    ..thresholds
                });
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests;
