//! Scenarios: how the obstacle moves and what goes wrong, over virtual time.
//!
//! A scenario is a small text file, one command per line, `#` starts a comment:
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
//! shutdown 9000            # at_ms: ignition off; EcuM post-run, then the ECU shuts down
//! ```
//!
//! `hold` and `ramp` follow each other in time; the other commands are placed by their own
//! times. The scenario lasts as long as its movements (at least until its last event).

use super::cantool::parse_frame;
use cw_core::can::CanFrame;

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

/// One segment of obstacle movement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// Start time, ms.
    pub start_ms: u64,
    /// Duration, ms.
    pub duration_ms: u64,
    /// Distance at the start, mm.
    pub from_mm: u32,
    /// Distance at the end, mm (equal to `from_mm` for a hold).
    pub to_mm: u32,
}

/// A parsed scenario.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scenario {
    /// Movements, back to back from 0.
    pub segments: Vec<Segment>,
    /// Sensor noise.
    pub noise: NoiseSpec,
    /// Random echo loss, parts per million.
    pub dropout_ppm: u32,
    /// Windows without echo: (start_ms, duration_ms).
    pub dropouts: Vec<(u64, u64)>,
    /// CAN error bursts: (at_ms, count).
    pub can_errors: Vec<(u64, u32)>,
    /// Tester frames: (at_ms, frame).
    pub frames: Vec<(u64, CanFrame)>,
    /// Windows without network communication (ComM no-communication via BswM):
    /// (start_ms, duration_ms).
    pub no_communication: Vec<(u64, u64)>,
    /// Ignition off, ms.
    pub shutdown_at_ms: Option<u64>,
}

/// A scenario line that could not be read, with its line number (from 1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScenarioError {
    /// The line.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for ScenarioError {}

impl Scenario {
    /// The paper's Figure 7: 0.5, 1.0, 1.5, 2.0 and 2.5 m, 3 s each.
    pub fn figure7() -> Self {
        let mut s = Self::empty();
        for mm in [500, 1000, 1500, 2000, 2500] {
            s.push(mm, mm, 3000);
        }
        s
    }

    fn empty() -> Self {
        Self {
            segments: Vec::new(),
            noise: NoiseSpec::Off,
            dropout_ppm: 0,
            dropouts: Vec::new(),
            can_errors: Vec::new(),
            frames: Vec::new(),
            no_communication: Vec::new(),
            shutdown_at_ms: None,
        }
    }

    fn push(&mut self, from_mm: u32, to_mm: u32, duration_ms: u64) {
        let start_ms = self
            .segments
            .last()
            .map_or(0, |s| s.start_ms + s.duration_ms);
        self.segments.push(Segment {
            start_ms,
            duration_ms,
            from_mm,
            to_mm,
        });
    }

    /// Reads a scenario.
    ///
    /// # Errors
    /// The first malformed line, with its number and what is wrong.
    pub fn parse(text: &str) -> Result<Self, ScenarioError> {
        let mut s = Self::empty();
        for (index, raw) in text.lines().enumerate() {
            let line = index + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            // A frame's `id#data` contains '#': re-read that command from the raw line.
            let content = if raw.trim_start().starts_with("frame") {
                raw.trim()
            } else {
                content
            };
            if content.is_empty() {
                continue;
            }
            let err = |message: String| ScenarioError { line, message };
            let words: Vec<&str> = content.split_whitespace().collect();
            let num = |i: usize, what: &str| -> Result<u64, ScenarioError> {
                let word = words
                    .get(i)
                    .ok_or_else(|| err(format!("`{}` needs {what}", words[0])))?;
                word.parse::<u64>()
                    .map_err(|_| err(format!("`{word}` is not a whole number ({what})")))
            };
            let mm = |i: usize, what: &str| -> Result<u32, ScenarioError> {
                let v = num(i, what)?;
                u32::try_from(v).map_err(|_| err(format!("{v} mm is too large")))
            };
            let arity = |n: usize| -> Result<(), ScenarioError> {
                if words.len() == n + 1 {
                    Ok(())
                } else {
                    Err(err(format!(
                        "`{}` takes {n} value(s), found {}",
                        words[0],
                        words.len() - 1
                    )))
                }
            };
            match words[0] {
                "hold" => {
                    arity(2)?;
                    let d = mm(1, "a distance in mm")?;
                    s.push(d, d, num(2, "a duration in ms")?);
                }
                "ramp" => {
                    arity(3)?;
                    s.push(
                        mm(1, "a start distance in mm")?,
                        mm(2, "an end distance in mm")?,
                        num(3, "a duration in ms")?,
                    );
                }
                "noise" => match words.get(1).copied() {
                    Some("off") => s.noise = NoiseSpec::Off,
                    Some("uniform") => {
                        arity(2)?;
                        s.noise = NoiseSpec::Uniform(mm(2, "an amplitude in mm")?);
                    }
                    Some("gaussian") => {
                        arity(2)?;
                        s.noise = NoiseSpec::Gaussian(mm(2, "a sigma in mm")?);
                    }
                    _ => {
                        return Err(err(
                            "`noise` takes `off`, `uniform MM` or `gaussian MM`".into()
                        ))
                    }
                },
                "dropout" => {
                    arity(2)?;
                    s.dropouts
                        .push((num(1, "a start in ms")?, num(2, "a duration in ms")?));
                }
                "dropout-rate" => {
                    arity(1)?;
                    let ppm = num(1, "parts per million")?;
                    s.dropout_ppm = u32::try_from(ppm)
                        .ok()
                        .filter(|p| *p <= 1_000_000)
                        .ok_or_else(|| err(format!("{ppm} ppm is above 1000000")))?;
                }
                "can-errors" => {
                    arity(2)?;
                    let count = num(2, "a count")?;
                    let count = u32::try_from(count)
                        .map_err(|_| err(format!("{count} errors is too many")))?;
                    s.can_errors.push((num(1, "a time in ms")?, count));
                }
                "frame" => {
                    arity(2)?;
                    let frame = parse_frame(words[2]).map_err(err)?;
                    s.frames.push((num(1, "a time in ms")?, frame));
                }
                "no-communication" => {
                    arity(2)?;
                    s.no_communication
                        .push((num(1, "a start in ms")?, num(2, "a duration in ms")?));
                }
                "shutdown" => {
                    arity(1)?;
                    if s.shutdown_at_ms.is_some() {
                        return Err(err("the ECU shuts down only once".into()));
                    }
                    s.shutdown_at_ms = Some(num(1, "a time in ms")?);
                }
                other => return Err(err(format!("unknown command `{other}`"))),
            }
        }
        if s.segments.is_empty() {
            return Err(ScenarioError {
                line: 0,
                message: "the scenario moves no obstacle: add at least one `hold` or `ramp`".into(),
            });
        }
        Ok(s)
    }

    /// How long the scenario runs, ms: its movements, or its last event if later.
    pub fn duration_ms(&self) -> u64 {
        let moves = self
            .segments
            .last()
            .map_or(0, |s| s.start_ms + s.duration_ms);
        let events = self
            .dropouts
            .iter()
            .map(|(t, d)| t + d)
            .chain(self.can_errors.iter().map(|(t, _)| *t))
            .chain(self.frames.iter().map(|(t, _)| *t))
            .chain(self.no_communication.iter().map(|(t, d)| t + d))
            .chain(self.shutdown_at_ms)
            .max()
            .unwrap_or(0);
        moves.max(events)
    }

    /// The true distance at `t_ms` (the last segment's end distance after the movements).
    pub fn distance_at(&self, t_ms: u64) -> u32 {
        for s in &self.segments {
            if t_ms < s.start_ms + s.duration_ms {
                let into = t_ms.saturating_sub(s.start_ms);
                let span = i64::from(s.to_mm) - i64::from(s.from_mm);
                let d = i64::from(s.from_mm) + span * into as i64 / s.duration_ms.max(1) as i64;
                return u32::try_from(d).unwrap_or(0);
            }
        }
        self.segments.last().map_or(0, |s| s.to_mm)
    }

    /// Whether the sensor is in a forced dropout at `t_ms`.
    pub fn in_dropout(&self, t_ms: u64) -> bool {
        self.dropouts
            .iter()
            .any(|(start, len)| (*start..start + len).contains(&t_ms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_command_and_places_movements_back_to_back() {
        let text =
            "# demo\nhold 500 1000\nramp 500 1500 1000 # up\nnoise uniform 20\ndropout 300 200\n\
                    dropout-rate 1000\ncan-errors 1500 40\nframe 1800 200#E8030000\n\
                    no-communication 1200 300\nshutdown 1900\n";
        let s = Scenario::parse(text).expect("valid scenario");
        assert_eq!(s.segments.len(), 2);
        assert_eq!(s.segments[1].start_ms, 1000);
        assert_eq!(s.distance_at(0), 500);
        assert_eq!(s.distance_at(1500), 1000, "half-way up the ramp");
        assert_eq!(
            s.distance_at(5000),
            1500,
            "after the end: the last distance"
        );
        assert_eq!(s.noise, NoiseSpec::Uniform(20));
        assert!(s.in_dropout(300) && s.in_dropout(499) && !s.in_dropout(500));
        assert_eq!(s.can_errors, [(1500, 40)]);
        assert_eq!(s.frames[0].1.bytes(), &[0xE8, 0x03, 0, 0]);
        assert_eq!(s.no_communication, [(1200, 300)]);
        assert_eq!(s.shutdown_at_ms, Some(1900));
        assert_eq!(s.duration_ms(), 2000);
    }

    #[test]
    fn malformed_lines_name_the_line_and_the_problem() {
        let cases = [
            ("hold 500", "line 1: `hold` takes 2 value(s), found 1"),
            (
                "hold 500 abc",
                "line 1: `abc` is not a whole number (a duration in ms)",
            ),
            ("\nteleport 3", "line 2: unknown command `teleport`"),
            (
                "hold 1 1\nframe 5 800#00",
                "line 2: CAN id 800 is out of range",
            ),
            (
                "hold 1 1\nframe 5 100#000",
                "line 2: `000` has an odd number of hex digits",
            ),
            (
                "hold 1 1\nframe 5 100#000000000000000000",
                "line 2: 9 data bytes; a CAN frame holds at most 8",
            ),
            (
                "shutdown 5\nshutdown 6",
                "line 2: the ECU shuts down only once",
            ),
            (
                "noise pink 3",
                "line 1: `noise` takes `off`, `uniform MM` or `gaussian MM`",
            ),
            (
                "# nothing",
                "line 0: the scenario moves no obstacle: add at least one `hold` or `ramp`",
            ),
        ];
        for (text, expected) in cases {
            let e = Scenario::parse(text).expect_err(text);
            assert_eq!(e.to_string(), expected);
        }
    }

    #[test]
    fn figure7_is_five_three_second_holds() {
        let s = Scenario::figure7();
        assert_eq!(s.duration_ms(), 15_000);
        assert_eq!(
            [0, 3000, 6000, 9000, 12000].map(|t| s.distance_at(t)),
            [500, 1000, 1500, 2000, 2500]
        );
    }
}
