//! The RTE of this ECU: the interfaces and the connections between the SWCs (paper
//! Figure 4). Each connection is a typed port from `cw_core::rte`; the task bodies in
//! [`crate::ecu`] call the runnables with exactly these ports, so a missing or mistyped
//! connection does not compile.

use cw_core::rte::{LastIsBest, Queued, SenderReceiverInterface};
use cw_core::warning::{Measurement, WarningLevel};

/// `SonarDataInterface`: the distance measured by UltraSonic, with its validity (the paper
/// carries a 4-byte unsigned distance; the validity makes a fault explicit instead of a
/// magic number).
pub struct SonarDataInterface;
impl SenderReceiverInterface for SonarDataInterface {
    type Data = Measurement;
    const NAME: &'static str = "SonarDataInterface";
}

/// `LedRequestInterface`: the warning ObstacleDetection asks the LEDs to show.
pub struct LedRequestInterface;
impl SenderReceiverInterface for LedRequestInterface {
    type Data = WarningLevel;
    const NAME: &'static str = "LedRequestInterface";
}

/// `ModeRequestInterface`: what the mode-management SWC asks BswM for (queued: every
/// request is carried out once, in order).
pub struct ModeRequestInterface;
impl SenderReceiverInterface for ModeRequestInterface {
    type Data = cw_core::ecum::BswMRequest;
    const NAME: &'static str = "ModeRequestInterface";
}

/// All connections of the ECU.
pub struct Rte {
    /// UltraSonic.SonarData -> ObstacleDetection.SonarData (read every 20 ms).
    pub sonar_to_obstacle: LastIsBest<SonarDataInterface>,
    /// UltraSonic.SonarData -> CanTranslate.SonarRecv, with a data-received event that
    /// activates `OsComTask`.
    pub sonar_to_can: LastIsBest<SonarDataInterface>,
    /// ObstacleDetection.LedRequest -> LEDActuator (both prototypes) and CanTranslate.
    pub led_request: LastIsBest<LedRequestInterface>,
    /// Mode management -> BswM (ignition off, communication control), queued, handled by
    /// BswM's main function in `OsBswServiceTask`.
    pub mode_requests: Queued<ModeRequestInterface, 4>,
}

impl Rte {
    /// Connections before any write: no measurement yet (invalid), level Fault until the
    /// first decision, so nothing is shown as safe before it is known.
    pub const fn new() -> Self {
        Self {
            sonar_to_obstacle: LastIsBest::new(Measurement::Invalid, false),
            sonar_to_can: LastIsBest::new(Measurement::Invalid, true),
            led_request: LastIsBest::new(WarningLevel::Fault, false),
            mode_requests: Queued::new(),
        }
    }
}

impl Default for Rte {
    fn default() -> Self {
        Self::new()
    }
}
