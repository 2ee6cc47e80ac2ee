//! Scenarios: how the obstacle moves and what goes wrong, over time. The host simulation
//! and the Cortex-M image read the same files with this one parser, into the same
//! fixed-capacity [`Scenario`] (no heap: the image holds one in RAM).
//!
//! A scenario is a small text file, one command per line; a `#` that starts a word starts
//! a comment (a frame's `id#data` keeps its `#`):
//!
//! ```text
//! # The paper's Figure 7: the obstacle held at five distances, 3 s each.
//! hold 500 3000            # distance_mm duration_ms
//! ramp 500 2500 10000      # from_mm to_mm duration_ms (linear)
//! noise uniform 20         # sensor noise from now on: uniform +/- mm, `gaussian` sigma, or `off`
//! dropout 4000 500         # start_ms duration_ms: the sensor gives no echo
//! dropout-rate 10000       # parts per million of echoes lost at random
//! can-errors 6000 40       # at_ms count: the ECU's next `count` transmissions fail
//! frame 7000 200#E8030000  # at_ms id#hex: a tester puts this frame on the bus
//! no-communication 8000 500 # start_ms duration_ms: BswM stops network communication
//! stall OsSonarTask 8500   # task at_ms: the task's jobs hang at their first line from then on
//! shutdown 9000            # at_ms: ignition off; EcuM post-run, then the ECU shuts down
//! ```
//!
//! `hold` and `ramp` follow each other in time; the other commands are placed by their own
//! times. The scenario lasts as long as its movements (at least until its last event).
//! Times are milliseconds from power-on, at most `u32::MAX` (49 days).

use core::fmt;

use crate::can::text::{parse_frame, FrameTextError};
use crate::can::CanFrame;

/// The sensor noise of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoiseSpec {
    /// Exact readings.
    Off,
    /// Uniform within +/- this many mm.
    Uniform(u32),
    /// Approximately Gaussian with this sigma, mm.
    Gaussian(u32),
}

/// One scenario line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `hold MM MS`.
    Hold {
        /// Distance, mm.
        mm: u32,
        /// Duration, ms.
        duration_ms: u32,
    },
    /// `ramp FROM TO MS`.
    Ramp {
        /// Start distance, mm.
        from_mm: u32,
        /// End distance, mm.
        to_mm: u32,
        /// Duration, ms.
        duration_ms: u32,
    },
    /// `noise off|uniform MM|gaussian MM`.
    Noise(NoiseSpec),
    /// `dropout START MS`.
    Dropout(Window),
    /// `dropout-rate PPM`.
    DropoutRate(u32),
    /// `can-errors AT COUNT`.
    CanErrors {
        /// When, ms.
        at_ms: u32,
        /// Transmissions that fail.
        count: u32,
    },
    /// `frame AT ID#DATA`.
    Frame {
        /// When, ms.
        at_ms: u32,
        /// The tester's frame.
        frame: CanFrame,
    },
    /// `no-communication START MS`.
    NoCommunication(Window),
    /// `shutdown AT`.
    Shutdown(u32),
    /// `stall TASK AT`: from `at_ms` on, every job of the task hangs at its first line
    /// (it never returns: the task reports no more alive indications, and every task
    /// below it is starved); the watchdog's supervision must catch it.
    Stall {
        /// The task, by its name in the OS configuration.
        task: TaskName,
        /// When, ms.
        at_ms: u32,
    },
}

/// A task's name on a scenario line, kept by value (up to [`TaskName::MAX`] bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TaskName {
    bytes: [u8; TaskName::MAX],
    len: u8,
}

impl TaskName {
    /// The longest name, bytes.
    pub const MAX: usize = 32;

    /// `name`, if it fits.
    pub fn new(name: &str) -> Option<Self> {
        let mut bytes = [0; Self::MAX];
        bytes
            .get_mut(..name.len())?
            .copy_from_slice(name.as_bytes());
        Some(Self {
            bytes,
            len: name.len() as u8,
        })
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        self.bytes
            .get(..usize::from(self.len))
            .and_then(|b| core::str::from_utf8(b).ok())
            .unwrap_or("")
    }
}

/// A time window, ms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Window {
    /// Start, ms.
    pub start_ms: u32,
    /// Duration, ms.
    pub duration_ms: u32,
}

impl Window {
    /// Whether `t_ms` is in the window.
    pub const fn contains(&self, t_ms: u64) -> bool {
        t_ms >= self.start_ms as u64 && t_ms < self.start_ms as u64 + self.duration_ms as u64
    }

    /// The first ms after the window.
    pub const fn end_ms(&self) -> u64 {
        self.start_ms as u64 + self.duration_ms as u64
    }
}

/// One segment of obstacle movement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Segment {
    /// Start time, ms.
    pub start_ms: u64,
    /// Duration, ms.
    pub duration_ms: u32,
    /// Distance at the start, mm.
    pub from_mm: u32,
    /// Distance at the end, mm (equal to `from_mm` for a hold).
    pub to_mm: u32,
}

impl Segment {
    /// The first ms after the segment.
    pub const fn end_ms(&self) -> u64 {
        self.start_ms + self.duration_ms as u64
    }

    /// The distance `into_ms` after the segment's start (linear).
    pub fn distance_after(&self, into_ms: u64) -> u32 {
        let into = into_ms.min(u64::from(self.duration_ms));
        let duration = u64::from(self.duration_ms.max(1));
        if self.to_mm >= self.from_mm {
            let span = u64::from(self.to_mm - self.from_mm);
            self.from_mm
                .saturating_add(u32::try_from(span * into / duration).unwrap_or(u32::MAX))
        } else {
            let span = u64::from(self.from_mm - self.to_mm);
            self.from_mm
                .saturating_sub(u32::try_from(span * into / duration).unwrap_or(u32::MAX))
        }
    }
}

/// What is wrong with a scenario line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineError<'a> {
    /// The first word is no command.
    Unknown(&'a str),
    /// The command takes `takes` values, the line has `found`.
    Arity {
        /// The command.
        command: &'a str,
        /// Values it takes.
        takes: usize,
        /// Values on the line.
        found: usize,
    },
    /// A value is not a whole number.
    NotANumber {
        /// The word.
        word: &'a str,
        /// What the value is.
        what: &'static str,
    },
    /// A value above `u32::MAX` (ms, mm or a count).
    TooLarge(&'a str),
    /// A dropout rate above one million parts per million.
    RateAbove(u32),
    /// `noise` with neither `off`, `uniform MM` nor `gaussian MM`.
    NoiseForm,
    /// The frame of a `frame` line.
    Frame(FrameTextError<'a>),
    /// A second `shutdown`.
    ShutdownTwice,
    /// A task name longer than [`TaskName::MAX`] bytes.
    NameTooLong(&'a str),
    /// More lines of one kind than the scenario holds.
    Full {
        /// The kind.
        kind: &'static str,
        /// The scenario's capacity per kind.
        capacity: usize,
    },
    /// No `hold` or `ramp` at all (reported on line 0).
    NoMovement,
}

impl fmt::Display for LineError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unknown(word) => write!(f, "unknown command `{word}`"),
            Self::Arity {
                command,
                takes,
                found,
            } => write!(f, "`{command}` takes {takes} value(s), found {found}"),
            Self::NotANumber { word, what } => {
                write!(f, "`{word}` is not a whole number ({what})")
            }
            Self::TooLarge(word) => write!(f, "{word} is too large (at most 4294967295)"),
            Self::RateAbove(ppm) => write!(f, "{ppm} ppm is above 1000000"),
            Self::NoiseForm => write!(f, "`noise` takes `off`, `uniform MM` or `gaussian MM`"),
            Self::Frame(e) => write!(f, "{e}"),
            Self::ShutdownTwice => write!(f, "the ECU shuts down only once"),
            Self::NameTooLong(name) => {
                write!(
                    f,
                    "the task name `{name}` is longer than {} bytes",
                    TaskName::MAX
                )
            }
            Self::Full { kind, capacity } => {
                write!(f, "more than {capacity} `{kind}` lines")
            }
            Self::NoMovement => write!(
                f,
                "the scenario moves no obstacle: add at least one `hold` or `ramp`"
            ),
        }
    }
}

/// A scenario that could not be read: the line (from 1; 0 for the whole file) and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScenarioError<'a> {
    /// The line.
    pub line: usize,
    /// What is wrong.
    pub error: LineError<'a>,
}

impl fmt::Display for ScenarioError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.error)
    }
}

/// The line without its comment: from the first `#` that starts a word.
fn strip_comment(raw: &str) -> &str {
    let mut previous_blank = true;
    for (i, c) in raw.char_indices() {
        if c == '#' && previous_blank {
            return raw.get(..i).unwrap_or("");
        }
        previous_blank = c.is_whitespace();
    }
    raw
}

/// Reads one line: `Ok(None)` for a blank or comment line.
///
/// # Errors
/// What is wrong with the line.
#[inline(never)]
pub fn parse_line(raw: &str) -> Result<Option<Command>, LineError<'_>> {
    let mut words = strip_comment(raw).split_whitespace();
    let Some(command) = words.next() else {
        return Ok(None);
    };
    let mut values: [&str; 3] = [""; 3];
    let mut found = 0;
    for word in words {
        if let Some(slot) = values.get_mut(found) {
            *slot = word;
        }
        found += 1;
    }
    let arity = |takes: usize| {
        if found == takes {
            Ok(())
        } else {
            Err(LineError::Arity {
                command,
                takes,
                found,
            })
        }
    };
    let num = |i: usize, what: &'static str| -> Result<u32, LineError<'_>> {
        let word = values.get(i).copied().unwrap_or("");
        if word.is_empty() || !word.bytes().all(|b| b.is_ascii_digit()) {
            return Err(LineError::NotANumber { word, what });
        }
        word.parse::<u32>().map_err(|_| LineError::TooLarge(word))
    };
    let window = || -> Result<Window, LineError<'_>> {
        arity(2)?;
        Ok(Window {
            start_ms: num(0, "a start in ms")?,
            duration_ms: num(1, "a duration in ms")?,
        })
    };
    let parsed = match command {
        "hold" => {
            arity(2)?;
            Command::Hold {
                mm: num(0, "a distance in mm")?,
                duration_ms: num(1, "a duration in ms")?,
            }
        }
        "ramp" => {
            arity(3)?;
            Command::Ramp {
                from_mm: num(0, "a start distance in mm")?,
                to_mm: num(1, "an end distance in mm")?,
                duration_ms: num(2, "a duration in ms")?,
            }
        }
        "noise" => Command::Noise(match values.first().copied() {
            Some("off") if found == 1 => NoiseSpec::Off,
            Some("uniform") if found == 2 => NoiseSpec::Uniform(num(1, "an amplitude in mm")?),
            Some("gaussian") if found == 2 => NoiseSpec::Gaussian(num(1, "a sigma in mm")?),
            _ => return Err(LineError::NoiseForm),
        }),
        "dropout" => Command::Dropout(window()?),
        "dropout-rate" => {
            arity(1)?;
            let ppm = num(0, "parts per million")?;
            if ppm > 1_000_000 {
                return Err(LineError::RateAbove(ppm));
            }
            Command::DropoutRate(ppm)
        }
        "can-errors" => {
            arity(2)?;
            Command::CanErrors {
                at_ms: num(0, "a time in ms")?,
                count: num(1, "a count")?,
            }
        }
        "frame" => {
            arity(2)?;
            Command::Frame {
                at_ms: num(0, "a time in ms")?,
                frame: parse_frame(values.get(1).copied().unwrap_or(""))
                    .map_err(LineError::Frame)?,
            }
        }
        "no-communication" => Command::NoCommunication(window()?),
        "shutdown" => {
            arity(1)?;
            Command::Shutdown(num(0, "a time in ms")?)
        }
        "stall" => {
            arity(2)?;
            let name = values.first().copied().unwrap_or("");
            Command::Stall {
                task: TaskName::new(name).ok_or(LineError::NameTooLong(name))?,
                at_ms: num(1, "a time in ms")?,
            }
        }
        other => return Err(LineError::Unknown(other)),
    };
    Ok(Some(parsed))
}

impl fmt::Display for Command {
    /// The command as a scenario line (what [`parse_line`] reads back).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Hold { mm, duration_ms } => write!(f, "hold {mm} {duration_ms}"),
            Self::Ramp {
                from_mm,
                to_mm,
                duration_ms,
            } => write!(f, "ramp {from_mm} {to_mm} {duration_ms}"),
            Self::Noise(NoiseSpec::Off) => write!(f, "noise off"),
            Self::Noise(NoiseSpec::Uniform(mm)) => write!(f, "noise uniform {mm}"),
            Self::Noise(NoiseSpec::Gaussian(mm)) => write!(f, "noise gaussian {mm}"),
            Self::Dropout(w) => write!(f, "dropout {} {}", w.start_ms, w.duration_ms),
            Self::DropoutRate(ppm) => write!(f, "dropout-rate {ppm}"),
            Self::CanErrors { at_ms, count } => write!(f, "can-errors {at_ms} {count}"),
            Self::Frame { at_ms, ref frame } => {
                write!(f, "frame {at_ms} ")?;
                crate::can::text::write_frame(frame, f)
            }
            Self::NoCommunication(w) => {
                write!(f, "no-communication {} {}", w.start_ms, w.duration_ms)
            }
            Self::Shutdown(at_ms) => write!(f, "shutdown {at_ms}"),
            Self::Stall { ref task, at_ms } => write!(f, "stall {} {at_ms}", task.as_str()),
        }
    }
}

/// A parsed scenario, holding up to `N` lines of each kind.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scenario<const N: usize> {
    /// Movements, back to back from 0.
    pub segments: heapless::Vec<Segment, N>,
    /// Sensor noise.
    pub noise: NoiseSpec,
    /// Random echo loss, parts per million.
    pub dropout_ppm: u32,
    /// Windows without echo.
    pub dropouts: heapless::Vec<Window, N>,
    /// CAN error bursts: (at_ms, count).
    pub can_errors: heapless::Vec<(u32, u32), N>,
    /// Tester frames: (at_ms, frame).
    pub frames: heapless::Vec<(u32, CanFrame), N>,
    /// Windows without network communication (ComM no-communication via BswM).
    pub no_communication: heapless::Vec<Window, N>,
    /// Ignition off, ms.
    pub shutdown_at_ms: Option<u32>,
    /// Tasks that hang: (from ms, task).
    pub stalls: heapless::Vec<(u32, TaskName), N>,
}

/// Adds `item` to `list`, or names the kind that is full.
fn push<T, const N: usize>(
    list: &mut heapless::Vec<T, N>,
    item: T,
    kind: &'static str,
) -> Result<(), LineError<'static>> {
    list.push(item)
        .map_err(|_| LineError::Full { kind, capacity: N })
}

impl<const N: usize> Scenario<N> {
    /// No movement, no event.
    pub const fn empty() -> Self {
        Self {
            segments: heapless::Vec::new(),
            noise: NoiseSpec::Off,
            dropout_ppm: 0,
            dropouts: heapless::Vec::new(),
            can_errors: heapless::Vec::new(),
            frames: heapless::Vec::new(),
            no_communication: heapless::Vec::new(),
            shutdown_at_ms: None,
            stalls: heapless::Vec::new(),
        }
    }

    /// The paper's Figure 7: 0.5, 1.0, 1.5, 2.0 and 2.5 m, 3 s each
    /// (`scenarios/figure7.txt`; a scenario of fewer than five holds keeps the first `N`).
    pub fn figure7() -> Self {
        let mut s = Self::empty();
        for mm in [500, 1000, 1500, 2000, 2500] {
            let _ = s.add(Command::Hold {
                mm,
                duration_ms: 3000,
            });
        }
        s
    }

    /// Adds one command.
    ///
    /// # Errors
    /// [`LineError::Full`] when its kind is full, [`LineError::ShutdownTwice`].
    #[inline(never)]
    pub fn add(&mut self, command: Command) -> Result<(), LineError<'static>> {
        let mut movement = |from_mm, to_mm, duration_ms| {
            let start_ms = self.segments.last().map_or(0, Segment::end_ms);
            push(
                &mut self.segments,
                Segment {
                    start_ms,
                    duration_ms,
                    from_mm,
                    to_mm,
                },
                "hold`/`ramp",
            )
        };
        match command {
            Command::Hold { mm, duration_ms } => movement(mm, mm, duration_ms),
            Command::Ramp {
                from_mm,
                to_mm,
                duration_ms,
            } => movement(from_mm, to_mm, duration_ms),
            Command::Noise(noise) => {
                self.noise = noise;
                Ok(())
            }
            Command::Dropout(w) => push(&mut self.dropouts, w, "dropout"),
            Command::DropoutRate(ppm) => {
                self.dropout_ppm = ppm;
                Ok(())
            }
            Command::CanErrors { at_ms, count } => {
                push(&mut self.can_errors, (at_ms, count), "can-errors")
            }
            Command::Frame { at_ms, frame } => push(&mut self.frames, (at_ms, frame), "frame"),
            Command::NoCommunication(w) => push(&mut self.no_communication, w, "no-communication"),
            Command::Shutdown(at_ms) => {
                if self.shutdown_at_ms.is_some() {
                    return Err(LineError::ShutdownTwice);
                }
                self.shutdown_at_ms = Some(at_ms);
                Ok(())
            }
            Command::Stall { task, at_ms } => push(&mut self.stalls, (at_ms, task), "stall"),
        }
    }

    /// Reads a scenario.
    ///
    /// # Errors
    /// The first malformed line, with its number and what is wrong; line 0 for a
    /// scenario that moves no obstacle.
    pub fn parse(text: &str) -> Result<Self, ScenarioError<'_>> {
        let mut s = Self::empty();
        for (index, raw) in text.lines().enumerate() {
            let line = index + 1;
            let error = |error| ScenarioError { line, error };
            if let Some(command) = parse_line(raw).map_err(error)? {
                s.add(command).map_err(error)?;
            }
        }
        if s.segments.is_empty() {
            return Err(ScenarioError {
                line: 0,
                error: LineError::NoMovement,
            });
        }
        Ok(s)
    }

    /// How long the scenario runs, ms: its movements, or its last event if later.
    pub fn duration_ms(&self) -> u64 {
        let moves = self.segments.last().map_or(0, Segment::end_ms);
        let events = self
            .dropouts
            .iter()
            .chain(&self.no_communication)
            .map(Window::end_ms)
            .chain(self.can_errors.iter().map(|(t, _)| u64::from(*t)))
            .chain(self.frames.iter().map(|(t, _)| u64::from(*t)))
            .chain(self.shutdown_at_ms.map(u64::from))
            .chain(self.stalls.iter().map(|(t, _)| u64::from(*t)))
            .max()
            .unwrap_or(0);
        moves.max(events)
    }

    /// Whether the task named `task` hangs at `t_ms` (a `stall` line at or before it).
    pub fn stalled(&self, task: &str, t_ms: u64) -> bool {
        self.stalls
            .iter()
            .any(|(at, name)| u64::from(*at) <= t_ms && name.as_str() == task)
    }

    /// The true distance at `t_ms` (the last segment's end distance after the movements).
    pub fn distance_at(&self, t_ms: u64) -> u32 {
        self.segments
            .iter()
            .find(|s| t_ms < s.end_ms())
            .map_or_else(
                || self.segments.last().map_or(0, |s| s.to_mm),
                |s| s.distance_after(t_ms.saturating_sub(s.start_ms)),
            )
    }

    /// Whether the sensor is in a forced dropout at `t_ms`.
    pub fn in_dropout(&self, t_ms: u64) -> bool {
        self.dropouts.iter().any(|w| w.contains(t_ms))
    }

    /// Whether communication is disabled at `t_ms` (inside a `no-communication` window).
    pub fn in_no_communication(&self, t_ms: u64) -> bool {
        self.no_communication.iter().any(|w| w.contains(t_ms))
    }

    /// Whether the ignition is on at `t_ms` (before the `shutdown` time, if any).
    pub fn ignition_on(&self, t_ms: u64) -> bool {
        self.shutdown_at_ms.is_none_or(|at| t_ms < u64::from(at))
    }
}

#[cfg(test)]
mod tests;
