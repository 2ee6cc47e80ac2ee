//! The paper's software components (§3.2.1), as plain state machines: each runnable takes
//! its inputs and returns its outputs; the RTE ([`crate::rte`]) moves the data between them.
//!
//! - UltraSonic (40 ms): the sensor's sample (IoHwAb) -> measurement; holds the last valid value through up to
//!   [`FAULT_AFTER_SAMPLES`]` - 1` bad samples, then reports the measurement invalid.
//! - ObstacleDetection (20 ms): measurement -> warning level with the configured thresholds
//!   (the PC may change them over CAN; an invalid pair is refused and counted).
//! - LEDActuator (10 ms), prototypes RedLED and YellowLED: level -> pin; on Fault both
//!   blink at [`BLINK_HALF_PERIOD_MS`].
//! - CanTranslate (on data received): measurement and level -> the CAN signals.
//! - ModeManager (10 ms, in `OsBswServiceTask`): the ignition and communication-enable
//!   inputs -> BswM mode requests, on their edges.

use cw_core::ecum::BswMRequest;
use cw_core::sonar::SonarConfig;
use cw_core::warning::{Measurement, Thresholds, WarningLevel};

use crate::rte::{
    CanTranslatePorts, CanTranslateRunnables, ObstacleDetectionPorts, ObstacleDetectionRunnables,
};

/// Consecutive bad samples after which the measurement is reported invalid (3 x 40 ms).
pub const FAULT_AFTER_SAMPLES: u8 = 3;
/// Half period of the fault blinking, ms (2 Hz).
pub const BLINK_HALF_PERIOD_MS: u32 = 250;
/// The distance signal's value for "nothing within range" (DBC `VAL_`).
pub const DISTANCE_NOTHING_IN_RANGE: u64 = 0xFFFF_FFFE;

/// UltraSonic: the sensor's sample to the measurement published, with a short hold over
/// bad samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UltraSonic {
    sensor: SonarConfig,
    bad_in_a_row: u8,
    last_good: Option<Measurement>,
}

impl UltraSonic {
    /// A sensor SWC with its parameters.
    pub const fn new(sensor: SonarConfig) -> Self {
        Self {
            sensor,
            bad_in_a_row: 0,
            last_good: None,
        }
    }

    /// The sensor's parameters.
    pub const fn sensor(&self) -> &SonarConfig {
        &self.sensor
    }

    /// The runnable: one sample in (IoHwAb's, with [`Self::sensor`]'s parameters), the
    /// measurement to publish out.
    pub fn run(&mut self, sample: Measurement) -> Measurement {
        match sample {
            Measurement::Invalid => {
                self.bad_in_a_row = self.bad_in_a_row.saturating_add(1);
                match self.last_good {
                    Some(good) if self.bad_in_a_row < FAULT_AFTER_SAMPLES => good,
                    _ => Measurement::Invalid,
                }
            }
            good => {
                self.bad_in_a_row = 0;
                self.last_good = Some(good);
                good
            }
        }
    }
}

/// ObstacleDetection: the warning level for the newest measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObstacleDetection {
    thresholds: Thresholds,
    refused_thresholds: u32,
}

impl Default for ObstacleDetection {
    fn default() -> Self {
        Self::new()
    }
}

impl ObstacleDetection {
    /// With the paper's thresholds (red below 1.0 m, yellow below 2.0 m).
    pub const fn new() -> Self {
        Self {
            thresholds: Thresholds::PAPER,
            refused_thresholds: 0,
        }
    }

    /// The thresholds in use.
    pub const fn thresholds(&self) -> Thresholds {
        self.thresholds
    }

    /// Threshold pairs refused so far.
    pub const fn refused_thresholds(&self) -> u32 {
        self.refused_thresholds
    }

    /// Takes a threshold pair received from the PC; an invalid pair is refused and the old
    /// thresholds stay.
    pub fn configure(&mut self, red_below_mm: u32, yellow_below_mm: u32) {
        match Thresholds::new(red_below_mm, yellow_below_mm) {
            Ok(t) => self.thresholds = t,
            Err(_) => self.refused_thresholds = self.refused_thresholds.saturating_add(1),
        }
    }

    /// The runnable.
    pub const fn run(&self, measurement: Measurement) -> WarningLevel {
        self.thresholds.level(measurement)
    }
}

impl ObstacleDetectionRunnables for ObstacleDetection {
    /// The newest measurement's level to the LEDs and CanTranslate.
    fn obstacle_detection_runnable(&mut self, ports: &mut impl ObstacleDetectionPorts) {
        let level = self.run(ports.read_sonar_data());
        ports.write_led_request(level);
    }
}

/// Which LED an LEDActuator prototype drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LedColor {
    /// The red LED (obstacle closer than the red threshold).
    Red,
    /// The yellow LED.
    Yellow,
}

/// LEDActuator, one prototype per LED.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LedActuator {
    color: LedColor,
}

impl LedActuator {
    /// The prototype for one LED.
    pub const fn new(color: LedColor) -> Self {
        Self { color }
    }

    /// The runnable: whether the LED is lit at `now_ms` for `level`.
    pub const fn run(&self, level: WarningLevel, now_ms: u64) -> bool {
        match (level, self.color) {
            (WarningLevel::Red, LedColor::Red) | (WarningLevel::Yellow, LedColor::Yellow) => true,
            (WarningLevel::Fault, _) => {
                cw_core::time::rem_u64(now_ms, 2 * BLINK_HALF_PERIOD_MS as u16)
                    < BLINK_HALF_PERIOD_MS
            }
            _ => false,
        }
    }
}

/// CanTranslate, started by a new measurement: its runnable leaves the CAN signals' raw
/// values for the job to hand to Com once it has left the RTE ([`can_translate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CanTranslate {
    /// The signals the runnable made (distance, level), not yet sent.
    pub signals: Option<(Option<u64>, u64)>,
}

impl CanTranslateRunnables for CanTranslate {
    /// The new measurement and the newest level, as the CAN signals' values.
    fn can_translate_runnable(&mut self, ports: &mut impl CanTranslatePorts) {
        if let Ok(measurement) = ports.take_sonar_recv() {
            self.signals = Some(can_translate(measurement, ports.read_led_request()));
        }
    }
}

/// CanTranslate: the raw CAN signal values for a measurement and level. `None` for the
/// distance means "send the invalidation value" (`Com_InvalidateSignal`).
pub const fn can_translate(measurement: Measurement, level: WarningLevel) -> (Option<u64>, u64) {
    let distance = match measurement {
        Measurement::Distance { distance_mm } => Some(distance_mm as u64),
        Measurement::NothingInRange => Some(DISTANCE_NOTHING_IN_RANGE),
        Measurement::Invalid => None,
    };
    (distance, level as u64)
}

/// ModeManager: the mode inputs (Dio, sampled every 10 ms) to BswM mode requests, on
/// their edges: ignition off asks for post-run (and so for the shutdown), the
/// communication-enable line low and high again asks to stop and restart communication.
/// Both inputs are on at power-on (ModeManagerInit has asked for the run mode). A pin
/// that cannot be read keeps its last level. When both change within one sample the
/// ignition goes first: a run-down is never overtaken by a restart of communication,
/// which BswM then refuses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModeManager {
    ignition: bool,
    com_enable: bool,
}

impl Default for ModeManager {
    fn default() -> Self {
        Self::new()
    }
}

impl ModeManager {
    /// Both inputs on.
    pub const fn new() -> Self {
        Self {
            ignition: true,
            com_enable: true,
        }
    }

    /// The runnable: the inputs now (`None`: unreadable), the requests their edges make,
    /// in order.
    pub fn run(
        &mut self,
        ignition: Option<bool>,
        com_enable: Option<bool>,
    ) -> [Option<BswMRequest>; 2] {
        let ignition = ignition.unwrap_or(self.ignition);
        let com_enable = com_enable.unwrap_or(self.com_enable);
        let run_down = (self.ignition && !ignition).then_some(BswMRequest::EcuPostRun);
        let com = (com_enable != self.com_enable).then_some(if com_enable {
            BswMRequest::CommunicationOn
        } else {
            BswMRequest::CommunicationOff
        });
        self.ignition = ignition;
        self.com_enable = com_enable;
        [run_down, com]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ultrasonic_holds_then_faults_then_recovers() {
        let mut swc = UltraSonic::new(SonarConfig::HC_SR04);
        let good = swc.run(Measurement::Distance { distance_mm: 1000 });
        assert_eq!(good, Measurement::Distance { distance_mm: 1000 });
        assert_eq!(
            swc.run(Measurement::Invalid),
            good,
            "one bad sample is held"
        );
        assert_eq!(swc.run(Measurement::Invalid), good, "two are held");
        assert_eq!(
            swc.run(Measurement::Invalid),
            Measurement::Invalid,
            "the third is a fault"
        );
        assert_eq!(
            swc.run(Measurement::NothingInRange),
            Measurement::NothingInRange
        );
        let mut fresh = UltraSonic::new(SonarConfig::HC_SR04);
        assert_eq!(
            fresh.run(Measurement::Invalid),
            Measurement::Invalid,
            "nothing to hold yet"
        );
    }

    #[test]
    fn obstacle_detection_levels_and_thresholds() {
        let mut od = ObstacleDetection::new();
        let at = |mm| Measurement::Distance { distance_mm: mm };
        assert_eq!(od.run(at(999)), WarningLevel::Red);
        assert_eq!(od.run(at(1000)), WarningLevel::Yellow);
        assert_eq!(od.run(at(2000)), WarningLevel::Off);
        assert_eq!(od.run(Measurement::Invalid), WarningLevel::Fault);
        od.configure(3000, 2000);
        assert_eq!(od.refused_thresholds(), 1);
        assert_eq!(od.thresholds(), Thresholds::PAPER);
        od.configure(500, 800);
        assert_eq!(od.run(at(600)), WarningLevel::Yellow);
    }

    #[test]
    fn leds_follow_the_level_and_blink_on_fault() {
        let red = LedActuator::new(LedColor::Red);
        let yellow = LedActuator::new(LedColor::Yellow);
        assert!(red.run(WarningLevel::Red, 0) && !yellow.run(WarningLevel::Red, 0));
        assert!(!red.run(WarningLevel::Yellow, 0) && yellow.run(WarningLevel::Yellow, 0));
        assert!(!red.run(WarningLevel::Off, 0) && !yellow.run(WarningLevel::Off, 0));
        let lit: [bool; 4] = [0, 250, 500, 750].map(|t| red.run(WarningLevel::Fault, t));
        assert_eq!(lit, [true, false, true, false]);
        assert_eq!(
            yellow.run(WarningLevel::Fault, 260),
            red.run(WarningLevel::Fault, 260)
        );
    }

    #[test]
    fn can_translate_maps_every_measurement() {
        let d = Measurement::Distance { distance_mm: 1500 };
        assert_eq!(can_translate(d, WarningLevel::Yellow), (Some(1500), 1));
        assert_eq!(
            can_translate(Measurement::NothingInRange, WarningLevel::Off),
            (Some(0xFFFF_FFFE), 0)
        );
        assert_eq!(
            can_translate(Measurement::Invalid, WarningLevel::Fault),
            (None, 3)
        );
    }

    #[test]
    fn mode_manager_requests_on_edges_ignition_first() {
        let mut mm = ModeManager::new();
        assert_eq!(mm.run(Some(true), Some(true)), [None, None]);
        assert_eq!(
            mm.run(Some(true), Some(false)),
            [None, Some(BswMRequest::CommunicationOff)]
        );
        assert_eq!(
            mm.run(Some(true), None),
            [None, None],
            "unreadable: unchanged"
        );
        assert_eq!(
            mm.run(Some(false), Some(true)),
            [
                Some(BswMRequest::EcuPostRun),
                Some(BswMRequest::CommunicationOn)
            ]
        );
        assert_eq!(mm.run(Some(true), Some(true)), [None, None]);
    }
}
