//! What the view shows, from the frames alone: each `DistanceFrame`, decoded with the DBC,
//! becomes a [`Sample`]; [`shown`] turns the newest sample and the time now into the
//! picture (the obstacle's distance, the LEDs, the status). A [`Replay`] is a log's samples
//! under a clock that plays, pauses, changes speed and seeks.
//!
//! The rules the page follows:
//! - no `DistanceFrame` for [`NO_SIGNAL_AFTER_US`] (200 ms, five of the ECU's 40 ms periods):
//!   **no signal**, whatever the last frame said, never a stale picture;
//! - a distance the ECU marks invalid (the DBC's `Invalid`) or the level `Fault`: **fault**,
//!   both LEDs blinking as the board blinks them;
//! - otherwise the LEDs are those the `WarningLevel` signal names (red for `Red`, yellow
//!   for `Yellow`, none for `Off`), never computed from the distance.

use crate::codec::{self, Decoded, Physical, Raw};
use crate::dbc::{Database, MessageDef};
use crate::log::{At, Entry, LineError};
use serde::Serialize;

/// Without a `DistanceFrame` for this long (microseconds), the view shows "no signal".
pub const NO_SIGNAL_AFTER_US: u32 = 200_000;

/// Whether a sample stamped `t` is current at `now` (seconds): its age, rounded to the
/// microsecond (a log's resolution), is below [`NO_SIGNAL_AFTER_US`]. Rounding keeps 200 ms
/// after a frame at 10.0 s "no signal" although `10.2 - 10.0` is a little less than 0.2 in
/// binary.
pub fn is_current(t: f64, now: f64) -> bool {
    ((now - t) * 1e6).round() < f64::from(NO_SIGNAL_AFTER_US)
}

/// The distance a frame reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", content = "mm")]
pub enum Reading {
    /// A measured distance, millimetres.
    Distance(u32),
    /// Nothing within the sensor's range.
    NothingInRange,
    /// No valid measurement (a sensor fault).
    Invalid,
}

/// The warning level a frame reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Level {
    /// No warning: both LEDs off.
    Off,
    /// Yellow LED.
    Yellow,
    /// Red LED.
    Red,
    /// Fault: both LEDs blink.
    Fault,
}

/// One `DistanceFrame`, decoded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// The frame's time stamp, seconds.
    pub t: f64,
    /// Its distance.
    pub reading: Reading,
    /// Its warning level.
    pub level: Level,
}

/// The warning thresholds the page draws: those of the newest `ThresholdConfig` on the bus
/// that the ECU would take, or the paper's before any.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Thresholds {
    /// When the frame that carried them was seen (none: the paper's, no frame yet).
    pub t: Option<f64>,
    /// Red below this distance, millimetres.
    pub red_below_mm: u32,
    /// Yellow below this distance, millimetres.
    pub yellow_below_mm: u32,
}

impl Thresholds {
    /// The paper's: red below 1.0 m, yellow below 2.0 m (what the ECU starts with).
    pub const PAPER: Self = Self {
        t: None,
        red_below_mm: 1000,
        yellow_below_mm: 2000,
    };
}

/// Where the view's frames are in the DBC: `DistanceFrame`, and `ThresholdConfig` when the
/// DBC has it, with the names they give their signals and values.
#[derive(Debug, Clone, Copy)]
pub struct ViewFrames<'a> {
    message: &'a MessageDef,
    config: Option<&'a MessageDef>,
}

impl<'a> ViewFrames<'a> {
    /// The DBC's `DistanceFrame`, with its `Distance` and `WarningLevel` signals, and its
    /// `ThresholdConfig` when it has one with `RedBelow` and `YellowBelow`.
    ///
    /// # Errors
    /// A DBC without a `DistanceFrame` and its two signals.
    pub fn find(db: &'a Database) -> Result<Self, String> {
        let message = db
            .by_name("DistanceFrame")
            .ok_or("the DBC has no message `DistanceFrame`")?;
        for name in ["Distance", "WarningLevel"] {
            if !message.signals.iter().any(|s| s.name == name) {
                return Err(format!("`DistanceFrame` has no signal `{name}`"));
            }
        }
        let config = db.by_name("ThresholdConfig").filter(|m| {
            ["RedBelow", "YellowBelow"]
                .iter()
                .all(|name| m.signals.iter().any(|s| s.name == *name))
        });
        Ok(Self { message, config })
    }

    /// The thresholds a `ThresholdConfig` entry carries, when the ECU would take them
    /// (red above 0 and below yellow, its own rule); `None` for any other frame, and for
    /// one that does not decode or that the ECU refuses.
    pub fn thresholds(&self, entry: &Entry) -> Option<Thresholds> {
        let config = self.config.filter(|m| carries(m, &entry.frame))?;
        let signals = codec::decode(config, &entry.frame.data).ok()?;
        let value = |name: &str| match signals.iter().find(|d| d.signal.name == name)?.physical {
            Physical::Int(v) => u32::try_from(v).ok(),
            Physical::Float(_) => None,
        };
        let (red, yellow) = (value("RedBelow")?, value("YellowBelow")?);
        cw_core::warning::Thresholds::new(red, yellow).ok()?;
        Some(Thresholds {
            t: Some(entry.timestamp),
            red_below_mm: red,
            yellow_below_mm: yellow,
        })
    }

    /// The sample an entry carries: `None` for any other frame.
    ///
    /// # Errors
    /// A `DistanceFrame` that does not decode, or whose level the DBC does not name.
    pub fn sample(&self, entry: &Entry) -> Option<Result<Sample, String>> {
        let frame = &entry.frame;
        if !carries(self.message, frame) {
            return None;
        }
        Some(
            codec::decode(self.message, &frame.data)
                .map_err(|e| e.to_string())
                .and_then(|signals| sample_of(entry.timestamp, &signals)),
        )
    }
}

/// Whether `frame` is one of `message`'s (a data frame with its id).
fn carries(message: &MessageDef, frame: &crate::frame::Frame) -> bool {
    frame.is_data() && frame.id == message.id && frame.extended == message.extended
}

fn sample_of(t: f64, signals: &[Decoded<'_>]) -> Result<Sample, String> {
    let signal = |name: &str| signals.iter().find(|d| d.signal.name == name);
    let distance = signal("Distance").ok_or("no `Distance` in the frame")?;
    let reading = match (distance.choice, distance.physical) {
        (Some("Invalid"), _) => Reading::Invalid,
        (Some("NothingInRange"), _) => Reading::NothingInRange,
        (_, Physical::Int(mm)) => u32::try_from(mm)
            .map(Reading::Distance)
            .map_err(|_| format!("distance {mm} mm is out of range"))?,
        (_, Physical::Float(mm)) => return Err(format!("distance {mm} mm is not whole")),
    };
    let level = signal("WarningLevel").ok_or("no `WarningLevel` in the frame")?;
    let level = match level.choice {
        Some("Off") => Level::Off,
        Some("Yellow") => Level::Yellow,
        Some("Red") => Level::Red,
        Some("Fault") => Level::Fault,
        _ => {
            let raw = match level.raw {
                Raw::Int(v) => v.to_string(),
                Raw::Float(v) => v.to_string(),
            };
            return Err(format!("warning level {raw} is not one the DBC names"));
        }
    };
    Ok(Sample { t, reading, level })
}

/// What the page shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Status {
    /// No frame yet, or none for [`NO_SIGNAL_AFTER_US`].
    NoSignal,
    /// The ECU reports a fault: both LEDs blink.
    Fault,
    /// A current reading.
    Live,
}

/// The picture at one moment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Shown {
    /// What the page says.
    pub status: Status,
    /// The newest sample, when it is current (not when there is no signal).
    pub sample: Option<Sample>,
    /// The red LED is lit (steadily, or blinking on a fault).
    pub red: bool,
    /// The yellow LED is lit (steadily, or blinking on a fault).
    pub yellow: bool,
    /// The LEDs blink (a fault).
    pub blinking: bool,
}

/// The picture at time `now` (seconds, the frames' clock), given the newest sample at or
/// before it.
pub fn shown(newest: Option<&Sample>, now: f64) -> Shown {
    let current = newest.filter(|s| is_current(s.t, now));
    let Some(sample) = current else {
        return Shown {
            status: Status::NoSignal,
            sample: None,
            red: false,
            yellow: false,
            blinking: false,
        };
    };
    let fault = sample.level == Level::Fault || sample.reading == Reading::Invalid;
    Shown {
        status: if fault { Status::Fault } else { Status::Live },
        sample: Some(*sample),
        red: fault || sample.level == Level::Red,
        yellow: fault || sample.level == Level::Yellow,
        blinking: fault,
    }
}

/// A log's samples under a clock: position is seconds since the earliest entry.
#[derive(Debug, Clone)]
pub struct Replay {
    samples: Vec<Sample>,
    configs: Vec<Thresholds>,
    start: f64,
    duration: f64,
    position: f64,
    speed: f64,
    playing: bool,
    bad: Vec<String>,
}

/// The slowest and fastest replay speeds.
pub const SPEEDS: (f64, f64) = (0.05, 1000.0);

impl Replay {
    /// The samples of `entries` (a log read with [`crate::log::open`], named `name`),
    /// paused at the start. Bad lines and frames are kept as messages naming them
    /// ([`Replay::bad`]); the rest plays.
    pub fn new(
        frame: &ViewFrames<'_>,
        entries: impl IntoIterator<Item = Result<(At, Entry), LineError>>,
        name: &str,
    ) -> Self {
        let mut samples: Vec<Sample> = Vec::new();
        let mut configs: Vec<Thresholds> = Vec::new();
        let mut bad = Vec::new();
        let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
        for entry in entries {
            let (at, entry) = match entry {
                Ok(e) => e,
                Err(e) => {
                    bad.push(format!("{name}:{e}"));
                    continue;
                }
            };
            first = first.min(entry.timestamp);
            last = last.max(entry.timestamp);
            if let Some(c) = frame.thresholds(&entry) {
                let at = configs.partition_point(|p| p.t <= c.t);
                configs.insert(at, c);
            }
            match frame.sample(&entry) {
                None => {}
                Some(Err(e)) => bad.push(format!("{name}:{at}: {e}")),
                // A frame stamped before the one already read goes where its time puts it.
                Some(Ok(s)) => {
                    let at = samples.partition_point(|p| p.t <= s.t);
                    samples.insert(at, s);
                }
            }
        }
        // No entry at all: an empty log of no duration.
        let start = if first.is_finite() { first } else { 0.0 };
        Self {
            samples,
            configs,
            start,
            duration: (last - start).max(0.0),
            position: 0.0,
            speed: 1.0,
            playing: false,
            bad,
        }
    }

    /// Seconds from the earliest entry to the latest.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Seconds since the earliest entry.
    pub fn position(&self) -> f64 {
        self.position
    }

    /// Log seconds per wall-clock second.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Whether the clock runs.
    pub fn playing(&self) -> bool {
        self.playing
    }

    /// The bad lines and frames, each named.
    pub fn bad(&self) -> &[String] {
        &self.bad
    }

    /// Every sample, oldest first.
    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }

    /// Starts or stops the clock; playing from the end starts again.
    pub fn set_playing(&mut self, playing: bool) {
        if playing && self.position >= self.duration {
            self.position = 0.0;
        }
        self.playing = playing;
    }

    /// Sets the speed, within [`SPEEDS`]; anything else (NaN) is refused.
    ///
    /// # Errors
    /// A speed outside [`SPEEDS`].
    pub fn set_speed(&mut self, speed: f64) -> Result<(), String> {
        if (SPEEDS.0..=SPEEDS.1).contains(&speed) {
            self.speed = speed;
            Ok(())
        } else {
            Err(format!(
                "speed {speed} is not between {} and {}",
                SPEEDS.0, SPEEDS.1
            ))
        }
    }

    /// Moves to `position` seconds, within the log.
    pub fn seek(&mut self, position: f64) {
        self.position = if position.is_nan() {
            self.position
        } else {
            position.clamp(0.0, self.duration)
        };
    }

    /// Lets `wall` seconds pass: the clock moves `wall * speed` when playing, and stops at
    /// the end.
    pub fn advance(&mut self, wall: f64) {
        if !self.playing || wall.is_nan() || wall <= 0.0 {
            return;
        }
        self.position = (self.position + wall * self.speed).min(self.duration);
        if self.position >= self.duration {
            self.playing = false;
        }
    }

    /// The frames' time now.
    pub fn now(&self) -> f64 {
        self.start + self.position
    }

    /// The newest sample at or before now.
    pub fn newest(&self) -> Option<&Sample> {
        let now = self.now();
        let n = self.samples.partition_point(|s| s.t <= now);
        n.checked_sub(1).and_then(|i| self.samples.get(i))
    }

    /// The picture now.
    pub fn shown(&self) -> Shown {
        shown(self.newest(), self.now())
    }

    /// The thresholds of the newest `ThresholdConfig` at or before now, or the paper's.
    pub fn thresholds(&self) -> Thresholds {
        let now = Some(self.now());
        let n = self.configs.partition_point(|c| c.t <= now);
        n.checked_sub(1)
            .and_then(|i| self.configs.get(i))
            .copied()
            .unwrap_or(Thresholds::PAPER)
    }

    /// The samples of the last `seconds` up to now, oldest first (the chart's window).
    pub fn window(&self, seconds: f64) -> &[Sample] {
        let now = self.now();
        let end = self.samples.partition_point(|s| s.t <= now);
        let begin = self.samples.partition_point(|s| s.t < now - seconds);
        self.samples.get(begin.min(end)..end).unwrap_or(&[])
    }
}

#[cfg(test)]
mod tests;
