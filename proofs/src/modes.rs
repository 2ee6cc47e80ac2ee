//! Model checking of the ECU's communication modes: EcuM start-up, run, post-run and
//! shutdown; BswM's rules; ComM requests to CanSM; CanSM's bus-off recovery; CanIf's
//! controller and PDU modes; and a CAN controller that may leave the bus, refuse to start,
//! report its mode changes late (a FlexCAN entering freeze mode at the end of a frame) or
//! never.
//!
//! The state is the real `EcuM`, `CanSm` and `CanIf` with the ECU's own configuration
//! (`cw_firmware::config::{CANSM, CANIF}`), plus the controller. Every transition calls the
//! code the firmware calls (`bswm_execute`, `cansm::apply`, `CanSm::main_function`,
//! `cansm::bus_off`, `cansm::mode_indication`, `EcuM::main_function`), under every
//! interleaving of mode requests, main-function periods, bus-offs, late mode indications
//! and controller faults. Bus-offs and timed-out mode requests are bounded (at most
//! [`MAX_BUS_OFFS`] and [`MAX_TIMEOUTS`] per run) so that the space is finite; every
//! recovery path, fast and slow, is still reached.
//!
//! Checked in every state:
//! - the channel is online only on a started controller in full communication, and CanIf
//!   never believes a stopped controller started;
//! - a bus-off wait is never longer than configured, and the slow wait comes only after
//!   the fast retries;
//! - a mode request never waits for its indication longer than its repetitions allow;
//! - a shut-down ECU has stopped communicating;
//! - EcuM only moves forward (Off, start-up one, start-up two, RUN, post-run, shutdown).

use cw_core::can::{CanBusy, CanDriver, CanFrame, ControllerMode, Hth, ModeChange, ModeRefused};
use cw_core::canif::{CanIf, PduMode};
use cw_core::cansm::{self, CanSm, CanSmState, ComMode};
use cw_core::ecum::{bswm_execute, BswMRequest, EcuM, EcuMState};
use cw_firmware::config;
use stateright::{Model, Property};

/// Bus-offs per explored run.
pub const MAX_BUS_OFFS: u32 = 4;

/// Mode requests that time out per explored run.
pub const MAX_TIMEOUTS: u32 = 2;

/// The CAN controller as the model sees it: its mode, whether it refuses to start and
/// whether it reports mode changes late (faults the environment may switch on and off),
/// and the mode it was asked for and has not reached yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Controller {
    /// The mode the hardware is in.
    pub mode: ControllerMode,
    /// Starting is refused while this holds.
    pub refuses_start: bool,
    /// Mode changes are reached later, and indicated then (or never).
    pub slow: bool,
    /// The mode asked for and not yet reached.
    pub pending: Option<ControllerMode>,
}

impl CanDriver for Controller {
    fn init(
        &mut self,
        _config: &cw_core::can::ControllerConfig,
    ) -> Result<(), cw_core::can::InitRefused> {
        self.mode = ControllerMode::Stopped;
        Ok(())
    }

    // The model's controller sends nothing (every write is refused): no error counted,
    // nothing to abort.
    fn error_counters(&self) -> cw_core::can::ErrorCounters {
        cw_core::can::ErrorCounters::ACTIVE
    }

    fn abort(&mut self, _hth: Hth) {}

    fn write(&mut self, _hth: Hth, _pdu: u16, _frame: &CanFrame) -> Result<(), CanBusy> {
        Err(CanBusy)
    }

    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        if mode == ControllerMode::Started && self.refuses_start {
            return Err(ModeRefused);
        }
        if self.slow {
            self.pending = Some(mode);
            return Ok(ModeChange::Pending);
        }
        self.mode = mode;
        self.pending = None;
        Ok(ModeChange::Reached)
    }
}

/// A state: the ECU's mode management and its CAN controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModeState {
    /// EcuM.
    pub ecum: EcuM,
    /// CanSM.
    pub cansm: CanSm,
    /// CanIf.
    pub canif: CanIf<1, 1>,
    /// The controller.
    pub controller: Controller,
    /// A broken transition rule, if any.
    pub violation: Option<&'static str>,
    /// The channel went online at a late start indication.
    pub online_after_late_start: bool,
}

/// One step of the ECU or its environment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModeStep {
    /// Power-on: `EcuM_Init`, `StartOS`, `OsStartupTask` (`EcuM_StartupTwo`, then
    /// ModeManagerInit's request for RUN), as the firmware runs it.
    PowerOn,
    /// A mode request handled by BswM (queued by the mode manager).
    Request(BswMRequest),
    /// One `OsBswServiceTask` period: `CanSM_MainFunction`, then `EcuM_MainFunction`.
    MainFunction,
    /// The controller leaves the bus (only a started controller can).
    BusOff,
    /// The controller reaches the mode it was asked for and indicates it.
    Indicate,
    /// The controller starts refusing, or stops refusing, to start.
    ControllerFault(bool),
    /// The controller starts, or stops, reporting its mode changes late.
    SlowModes(bool),
}

/// The model: the ECU's configuration.
#[derive(Debug, Default)]
pub struct ModeModel;

const REQUESTS: [BswMRequest; 4] = [
    BswMRequest::EcuRun,
    BswMRequest::EcuPostRun,
    BswMRequest::CommunicationOff,
    BswMRequest::CommunicationOn,
];

fn stage(state: EcuMState) -> u8 {
    match state {
        EcuMState::Off => 0,
        EcuMState::StartupOneDone => 1,
        EcuMState::StartupTwoDone => 2,
        EcuMState::Run => 3,
        EcuMState::PostRun => 4,
        EcuMState::Shutdown => 5,
    }
}

/// The safety properties of one state, by name; `None` when all hold.
pub fn broken_rule(s: &ModeState) -> Option<&'static str> {
    let cfg = config::CANSM;
    let started = s.controller.mode == ControllerMode::Started;
    if s.canif.pdu_mode() == PduMode::Online
        && !(started
            && s.canif.controller_mode() == ControllerMode::Started
            && s.cansm.current_mode() == ComMode::Full)
    {
        return Some("the channel is online without a started controller in full communication");
    }
    if s.canif.controller_mode() == ControllerMode::Started && !started {
        return Some("CanIf believes a stopped controller started");
    }
    if let CanSmState::StartRequested { waited, .. } | CanSmState::StopRequested { waited } =
        s.cansm.state()
    {
        if waited >= cfg.mode_request_timeout_cycles {
            return Some("a mode request waits longer than its repetitions allow");
        }
    }
    if let CanSmState::BusOff { remaining } = s.cansm.state() {
        if remaining == 0 || remaining > cfg.fast_cycles.max(cfg.slow_cycles) {
            return Some("a bus-off wait outside the configured times");
        }
        if remaining > cfg.fast_cycles && s.cansm.bus_off_consecutive() <= cfg.fast_retries {
            return Some("a slow bus-off wait before the fast retries are used up");
        }
    }
    if s.ecum.state() == EcuMState::Shutdown
        && (s.cansm.current_mode() != ComMode::No || s.canif.pdu_mode() != PduMode::Offline)
    {
        return Some("the ECU shut down while communicating");
    }
    None
}

impl Model for ModeModel {
    type State = ModeState;
    type Action = ModeStep;

    fn init_states(&self) -> Vec<ModeState> {
        vec![ModeState {
            ecum: EcuM::new(),
            cansm: CanSm::new(config::CANSM),
            canif: CanIf::new(&config::CANIF),
            controller: Controller {
                mode: ControllerMode::Stopped,
                refuses_start: false,
                slow: false,
                pending: None,
            },
            violation: None,
            online_after_late_start: false,
        }]
    }

    fn actions(&self, s: &ModeState, actions: &mut Vec<ModeStep>) {
        if s.violation.is_some() || s.ecum.state() == EcuMState::Shutdown {
            return;
        }
        if s.ecum.state() == EcuMState::Off {
            actions.push(ModeStep::PowerOn);
            return;
        }
        actions.extend(REQUESTS.map(ModeStep::Request));
        actions.push(ModeStep::MainFunction);
        if s.controller.mode == ControllerMode::Started {
            actions.push(ModeStep::BusOff);
        }
        if s.controller.pending.is_some() {
            actions.push(ModeStep::Indicate);
        }
        actions.push(ModeStep::ControllerFault(!s.controller.refuses_start));
        actions.push(ModeStep::SlowModes(!s.controller.slow));
    }

    fn next_state(&self, last: &ModeState, step: ModeStep) -> Option<ModeState> {
        let mut s = *last;
        match step {
            ModeStep::PowerOn => {
                if s.ecum.init().is_err() || s.ecum.startup_two().is_err() {
                    s.violation = Some("start-up refused at power-on");
                } else if bswm_execute(
                    BswMRequest::EcuRun,
                    &mut s.ecum,
                    &mut s.cansm,
                    &mut s.canif,
                    &mut s.controller,
                )
                .is_err()
                {
                    s.violation = Some("BswM refused RUN after start-up");
                }
            }
            ModeStep::Request(request) => {
                let before = s;
                let done = bswm_execute(
                    request,
                    &mut s.ecum,
                    &mut s.cansm,
                    &mut s.canif,
                    &mut s.controller,
                );
                if done.is_err() && s != before {
                    s.violation = Some("a refused BswM request changed something");
                }
            }
            ModeStep::MainFunction => {
                let actions = s.cansm.main_function();
                cansm::apply(&mut s.cansm, &mut s.canif, &mut s.controller, actions);
                s.ecum.main_function();
            }
            ModeStep::BusOff => {
                s.controller.mode = ControllerMode::Stopped;
                cansm::bus_off(&mut s.cansm, &mut s.canif, &mut s.controller);
            }
            ModeStep::Indicate => {
                if let Some(mode) = s.controller.pending.take() {
                    s.controller.mode = mode;
                    let offline = s.canif.pdu_mode() != PduMode::Online;
                    cansm::mode_indication(&mut s.cansm, &mut s.canif, &mut s.controller, mode);
                    s.online_after_late_start |= offline && s.canif.pdu_mode() == PduMode::Online;
                }
            }
            ModeStep::ControllerFault(on) => s.controller.refuses_start = on,
            ModeStep::SlowModes(on) => s.controller.slow = on,
        }
        if stage(s.ecum.state()) < stage(last.ecum.state()) {
            s.violation = Some("EcuM moved backwards");
        }
        Some(s)
    }

    fn within_boundary(&self, s: &ModeState) -> bool {
        s.cansm.bus_off_total() <= MAX_BUS_OFFS && s.cansm.mode_request_timeouts() <= MAX_TIMEOUTS
    }

    fn properties(&self) -> Vec<Property<Self>> {
        vec![
            Property::always("transition rules hold", |_, s: &ModeState| {
                s.violation.is_none()
            }),
            Property::always(
                "online only when started in full communication; bus-off waits as configured; \
                 silent after shutdown",
                |_, s: &ModeState| broken_rule(s).is_none(),
            ),
            // Reachability: the properties above are not vacuous.
            Property::sometimes("full communication", |_, s: &ModeState| {
                s.canif.pdu_mode() == PduMode::Online
            }),
            Property::sometimes("a slow bus-off recovery", |_, s: &ModeState| {
                matches!(s.cansm.state(), CanSmState::BusOff { remaining }
                    if remaining > config::CANSM.fast_cycles)
            }),
            Property::sometimes("back online after a refused start", |_, s: &ModeState| {
                s.canif.pdu_mode() == PduMode::Online
                    && s.cansm.bus_off_total() == 0
                    && matches!(
                        s.cansm.state(),
                        CanSmState::FullCommunication {
                            since_restart: Some(_)
                        }
                    )
            }),
            Property::sometimes("online after a start indicated late", |_, s: &ModeState| {
                s.online_after_late_start
            }),
            Property::sometimes("a mode request timed out", |_, s: &ModeState| {
                s.cansm.mode_request_timeouts() > 0
            }),
            Property::sometimes("shut down", |_, s: &ModeState| {
                s.ecum.state() == EcuMState::Shutdown
            }),
        ]
    }
}
