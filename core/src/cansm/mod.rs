//! CAN State Manager (AUTOSAR SWS CanSM), reduced to one network: the communication mode
//! requests of ComM.
//!
//! CanSM owns the network's communication mode and recovers from bus-off:
//! - ComM asks for full or no communication ([`ComMode`]); CanSM starts or stops the
//!   controller and sets the CanIf PDU mode accordingly.
//! - A controller mode change completes when the controller indicates it
//!   (`CanSM_ControllerModeIndication`), at once or later: a FlexCAN stops only once the
//!   frame on the wire has ended. The channel goes online only after the start is
//!   indicated, and goes offline before the stop is asked for. A request not indicated
//!   within `mode_request_cycles` (`CanSMModeRequestRepetitionTime`) is asked again, up to
//!   `mode_request_repeats` times (`CanSMModeRequestRepetitionMax`); then it has timed out
//!   (`CANSM_E_MODE_REQUEST_TIMEOUT`, counted): a start is retried after the fast recovery
//!   time, a stop is taken as done (the channel is already offline).
//! - On bus-off (`CanSM_ControllerBusOff`) transmission stops at once; after the recovery
//!   time the controller is restarted. The first [`CanSmConfig::fast_retries`] recoveries
//!   wait `fast_ms` (`CanSMBorTimeL1`), later ones `slow_ms` (`CanSMBorTimeL2`). A recovery
//!   counts as successful once `tx_ensured_ms` (`CanSMBorTimeTxEnsured`) pass without a new
//!   bus-off; then the counter returns to zero and the next bus-off is fast again.
//!
//! CanSM is pure: [`CanSm::request`], [`CanSm::controller_mode_indication`],
//! [`CanSm::controller_bus_off`] and [`CanSm::main_function`] return the [`Actions`] the
//! caller applies to CanIf and the driver ([`apply`], [`mode_indication`], [`bus_off`] do
//! it). Times are in main-function cycles (the configuration converts milliseconds).

use crate::can::{CanDriver, ControllerMode, ModeChange};
use crate::canif::{CanIf, CanIfConfig, PduMode};
use crate::tables::Tables;

/// A communication mode requested by ComM.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ComMode {
    /// No communication: controller stopped, channel offline.
    No,
    /// Full communication: controller started, channel online.
    Full,
}

/// The CanSM state of the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CanSmState {
    /// No communication.
    NoCommunication,
    /// The controller was asked to start; the channel opens when it indicates it started.
    StartRequested {
        /// Cycles since the start was first asked for.
        waited: u32,
        /// A restart after a bus-off (recovery is ensured only after a while on the bus).
        after_bus_off: bool,
    },
    /// Full communication; `since_restart` counts cycles since the last bus-off restart
    /// (`None` once the transmission is ensured).
    FullCommunication {
        /// Cycles since the restart after a bus-off, until the transmission is ensured.
        since_restart: Option<u32>,
    },
    /// The channel is offline and the controller was asked to stop; no communication
    /// once it indicates it stopped.
    StopRequested {
        /// Cycles since the stop was first asked for.
        waited: u32,
    },
    /// Off the bus (after a bus-off, or a start the controller refused or never
    /// indicated), waiting `remaining` cycles before restarting the controller.
    BusOff {
        /// Cycles left before the restart.
        remaining: u32,
    },
}

/// What the caller must do to CanIf and the controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Actions {
    /// Set the CanIf PDU channel to this mode (before the controller's mode is asked).
    pub pdu: Option<PduMode>,
    /// Ask for this controller mode (through CanIf).
    pub controller: Option<ControllerMode>,
    /// Tell ComM the network changed communication mode.
    pub indicate: Option<ComMode>,
}

/// Recovery and mode request timing, in main-function cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanSmConfig {
    /// Recoveries that use the fast wait before switching to the slow one.
    pub fast_retries: u8,
    /// Fast wait before a restart, cycles (`CanSMBorTimeL1`).
    pub fast_cycles: u32,
    /// Slow wait before a restart, cycles (`CanSMBorTimeL2`).
    pub slow_cycles: u32,
    /// Cycles without bus-off after which a recovery counts as successful.
    pub tx_ensured_cycles: u32,
    /// Cycles a controller mode request waits for its indication before it is made again
    /// (`CanSMModeRequestRepetitionTime`).
    pub mode_request_cycles: u32,
    /// Times a mode request is made again before it has timed out
    /// (`CanSMModeRequestRepetitionMax`).
    pub mode_request_repeats: u8,
    /// Derived: cycles after which a request made and repeated without indication has
    /// timed out (`mode_request_cycles x (mode_request_repeats + 1)`).
    pub mode_request_timeout_cycles: u32,
}

/// CanSM's times in milliseconds, as a configuration tool gives them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanSmTimesMs {
    /// Recoveries that use the fast wait (`CanSMBorCounterL1ToL2`).
    pub fast_retries: u8,
    /// `CanSMBorTimeL1`.
    pub fast: u32,
    /// `CanSMBorTimeL2`.
    pub slow: u32,
    /// `CanSMBorTimeTxEnsured`.
    pub tx_ensured: u32,
    /// `CanSMModeRequestRepetitionTime`.
    pub mode_request: u32,
    /// `CanSMModeRequestRepetitionMax`.
    pub mode_request_repeats: u8,
}

/// A timing that would never restart, never settle or never repeat a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanSmConfigError;

/// `ms` in whole periods of `period`, or `None` when zero or not whole.
const fn cycles(ms: u32, period: u32) -> Option<u32> {
    if ms == 0 || ms % period != 0 {
        None
    } else {
        Some(ms / period)
    }
}

impl CanSmConfig {
    /// Builds the timing from milliseconds and the main-function period.
    ///
    /// # Errors
    /// [`CanSmConfigError`] if a time is zero or not a whole number of periods.
    pub const fn from_ms(
        main_period_ms: u32,
        times: CanSmTimesMs,
    ) -> Result<Self, CanSmConfigError> {
        if main_period_ms == 0 {
            return Err(CanSmConfigError);
        }
        let (Some(fast_cycles), Some(slow_cycles), Some(tx_ensured_cycles), Some(mode_cycles)) = (
            cycles(times.fast, main_period_ms),
            cycles(times.slow, main_period_ms),
            cycles(times.tx_ensured, main_period_ms),
            cycles(times.mode_request, main_period_ms),
        ) else {
            return Err(CanSmConfigError);
        };
        Ok(Self {
            fast_retries: times.fast_retries,
            fast_cycles,
            slow_cycles,
            tx_ensured_cycles,
            mode_request_cycles: mode_cycles,
            mode_request_repeats: times.mode_request_repeats,
            mode_request_timeout_cycles: mode_cycles
                .saturating_mul(times.mode_request_repeats as u32 + 1),
        })
    }
}

/// CanSM for one network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanSm {
    cfg: CanSmConfig,
    state: CanSmState,
    requested: ComMode,
    /// Consecutive bus-offs without an ensured transmission in between.
    consecutive: u8,
    /// Every bus-off since start.
    total: u32,
    /// Mode requests that timed out since start.
    timeouts: u32,
}

impl CanSm {
    /// CanSM after `CanSM_Init`: no communication.
    pub const fn new(cfg: CanSmConfig) -> Self {
        Self {
            cfg,
            state: CanSmState::NoCommunication,
            requested: ComMode::No,
            consecutive: 0,
            total: 0,
            timeouts: 0,
        }
    }

    /// The current state.
    pub const fn state(&self) -> CanSmState {
        self.state
    }

    /// Bus-offs since start.
    pub const fn bus_off_total(&self) -> u32 {
        self.total
    }

    /// Consecutive bus-offs not yet followed by an ensured transmission.
    pub const fn bus_off_consecutive(&self) -> u8 {
        self.consecutive
    }

    /// Controller mode requests that were never indicated, however often repeated
    /// (`CANSM_E_MODE_REQUEST_TIMEOUT`), since start.
    pub const fn mode_request_timeouts(&self) -> u32 {
        self.timeouts
    }

    /// The communication mode the network is in, as ComM sees it.
    pub const fn current_mode(&self) -> ComMode {
        match self.state {
            CanSmState::FullCommunication { .. } => ComMode::Full,
            _ => ComMode::No,
        }
    }

    /// Moves to `state`; the actions say to ComM whether that changed its mode.
    fn go(
        &mut self,
        state: CanSmState,
        pdu: Option<PduMode>,
        controller: Option<ControllerMode>,
    ) -> Actions {
        let before = self.current_mode();
        self.state = state;
        let after = self.current_mode();
        Actions {
            pdu,
            controller,
            indicate: (after != before).then_some(after),
        }
    }

    fn request_start(&mut self, after_bus_off: bool) -> Actions {
        let state = CanSmState::StartRequested {
            waited: 0,
            after_bus_off,
        };
        self.go(state, None, Some(ControllerMode::Started))
    }

    fn request_stop(&mut self) -> Actions {
        let state = CanSmState::StopRequested { waited: 0 };
        self.go(state, Some(PduMode::Offline), Some(ControllerMode::Stopped))
    }

    /// `CanSM_RequestComMode`, called by ComM.
    pub fn request(&mut self, mode: ComMode) -> Actions {
        self.requested = mode;
        match (mode, self.state) {
            (ComMode::Full, CanSmState::NoCommunication) => self.request_start(false),
            (ComMode::No, CanSmState::NoCommunication | CanSmState::StopRequested { .. }) => {
                Actions::default()
            }
            (ComMode::No, _) => self.request_stop(),
            // Already there or on the way: a full request during a stop is taken up when
            // the stop is indicated, during a recovery it completes by itself.
            (ComMode::Full, _) => Actions::default(),
        }
    }

    /// `CanSM_ControllerModeIndication`: the controller reached `mode`. An indication
    /// nobody waits for (a start indicated after a bus-off, a late one after a timeout)
    /// changes nothing.
    pub fn controller_mode_indication(&mut self, mode: ControllerMode) -> Actions {
        match (self.state, mode) {
            (CanSmState::StartRequested { after_bus_off, .. }, ControllerMode::Started) => {
                let since_restart = after_bus_off.then_some(0);
                self.go(
                    CanSmState::FullCommunication { since_restart },
                    Some(PduMode::Online),
                    None,
                )
            }
            (CanSmState::StopRequested { .. }, ControllerMode::Stopped) => self.stopped(),
            _ => Actions::default(),
        }
    }

    /// The stop is done: no communication, or a new start if ComM asked for it meanwhile.
    fn stopped(&mut self) -> Actions {
        match self.requested {
            ComMode::Full => self.request_start(false),
            ComMode::No => self.go(CanSmState::NoCommunication, None, None),
        }
    }

    /// `CanSM_ControllerBusOff`: transmission stops; the restart waits the fast or the
    /// slow recovery time. Ignored without communication or on the way there.
    pub fn controller_bus_off(&mut self) -> Actions {
        if matches!(
            self.state,
            CanSmState::NoCommunication | CanSmState::StopRequested { .. }
        ) {
            return Actions::default();
        }
        self.total = self.total.saturating_add(1);
        let wait = if self.consecutive < self.cfg.fast_retries {
            self.cfg.fast_cycles
        } else {
            self.cfg.slow_cycles
        };
        self.consecutive = self.consecutive.saturating_add(1);
        self.go(
            CanSmState::BusOff { remaining: wait },
            Some(PduMode::TxOffline),
            None,
        )
    }

    /// The controller refused `mode` (`CanIf_SetControllerMode` failed). A refused start
    /// keeps CanSM off the bus: it asks again after the fast recovery time, as after a
    /// bus-off, without counting a bus-off. A refused stop is asked again after the
    /// repetition time (the channel is offline already).
    pub fn mode_refused(&mut self, mode: ControllerMode) -> Actions {
        match (self.state, mode) {
            (CanSmState::StartRequested { .. }, ControllerMode::Started) => self.go(
                CanSmState::BusOff {
                    remaining: self.cfg.fast_cycles,
                },
                Some(PduMode::TxOffline),
                None,
            ),
            _ => Actions::default(),
        }
    }

    /// `CanSM_MainFunction`: one period passed. (Out of line: the BSW task's job is the
    /// only caller, and the image's flash is what it saves.)
    #[inline(never)]
    pub fn main_function(&mut self) -> Actions {
        match self.state {
            CanSmState::BusOff { remaining } if remaining > 1 => {
                self.state = CanSmState::BusOff {
                    remaining: remaining - 1,
                };
                Actions::default()
            }
            CanSmState::BusOff { .. } => self.request_start(true),
            CanSmState::FullCommunication {
                since_restart: Some(n),
            } => {
                let n = n + 1;
                self.state = if n >= self.cfg.tx_ensured_cycles {
                    self.consecutive = 0;
                    CanSmState::FullCommunication {
                        since_restart: None,
                    }
                } else {
                    CanSmState::FullCommunication {
                        since_restart: Some(n),
                    }
                };
                Actions::default()
            }
            CanSmState::StartRequested {
                waited,
                after_bus_off,
            } => {
                let waited = waited + 1;
                if self.timed_out(waited) {
                    // Never indicated: off the bus, and a new start after the fast wait.
                    return self.mode_refused(ControllerMode::Started);
                }
                self.state = CanSmState::StartRequested {
                    waited,
                    after_bus_off,
                };
                self.ask_again(waited, ControllerMode::Started)
            }
            CanSmState::StopRequested { waited } => {
                let waited = waited + 1;
                if self.timed_out(waited) {
                    // Never indicated: taken as stopped (the channel has been offline
                    // since the request).
                    return self.stopped();
                }
                self.state = CanSmState::StopRequested { waited };
                self.ask_again(waited, ControllerMode::Stopped)
            }
            _ => Actions::default(),
        }
    }

    /// Whether a request waiting `waited` cycles for its indication has timed out
    /// (counted).
    fn timed_out(&mut self, waited: u32) -> bool {
        let out = waited >= self.cfg.mode_request_timeout_cycles;
        if out {
            self.timeouts = self.timeouts.saturating_add(1);
        }
        out
    }

    /// The request for `mode` again, every repetition time.
    fn ask_again(&self, waited: u32, mode: ControllerMode) -> Actions {
        Actions {
            controller: (waited % self.cfg.mode_request_cycles.max(1) == 0).then_some(mode),
            ..Actions::default()
        }
    }
}

/// The most controller requests one call of [`apply`] makes: a stop the controller
/// reaches at once, then the start ComM asked for meanwhile.
const MAX_REQUESTS: usize = 2;

/// Carries out CanSM's [`Actions`] on CanIf and the controller: the PDU mode first, then
/// the controller mode. A mode the controller reaches at once is indicated to CanSM
/// straight away (and its actions carried out); a pending one when the controller reports
/// it ([`mode_indication`]). A refused mode goes back to CanSM ([`CanSm::mode_refused`]),
/// so the channel never goes online on a stopped controller.
pub fn apply<D: CanDriver, const TX: usize, const RX: usize, K: Tables<CanIfConfig<TX, RX>>>(
    cansm: &mut CanSm,
    canif: &mut CanIf<TX, RX, K>,
    driver: &mut D,
    actions: Actions,
) {
    let mut actions = actions;
    for _ in 0..=MAX_REQUESTS {
        if let Some(pdu) = actions.pdu {
            canif.set_pdu_mode(pdu);
        }
        let Some(mode) = actions.controller else {
            return;
        };
        actions = match canif.set_controller_mode(driver, mode) {
            Ok(ModeChange::Reached) => cansm.controller_mode_indication(mode),
            Ok(ModeChange::Pending) => return,
            Err(_) => cansm.mode_refused(mode),
        };
    }
}

/// `CanIf_ControllerModeIndication` from the driver, passed on to CanSM
/// (`CanSM_ControllerModeIndication`), and CanSM's actions carried out.
pub fn mode_indication<
    D: CanDriver,
    const TX: usize,
    const RX: usize,
    K: Tables<CanIfConfig<TX, RX>>,
>(
    cansm: &mut CanSm,
    canif: &mut CanIf<TX, RX, K>,
    driver: &mut D,
    mode: ControllerMode,
) {
    canif.controller_mode_indication(mode);
    let actions = cansm.controller_mode_indication(mode);
    apply(cansm, canif, driver, actions);
}

/// `CanIf_ControllerBusOff` from the driver, passed on to CanSM (`CanSM_ControllerBusOff`),
/// and CanSM's actions carried out.
pub fn bus_off<D: CanDriver, const TX: usize, const RX: usize, K: Tables<CanIfConfig<TX, RX>>>(
    cansm: &mut CanSm,
    canif: &mut CanIf<TX, RX, K>,
    driver: &mut D,
) {
    canif.controller_bus_off();
    let actions = cansm.controller_bus_off();
    apply(cansm, canif, driver, actions);
}

/// CanSM's promises as a predicate over any run, for the tests, the fuzz target
/// `cansm_modes` and the Kani proof.
pub mod spec {
    use super::{Actions, CanSm, CanSmConfig, CanSmState, ComMode, ControllerMode, PduMode};

    /// The event byte `e` asks for one of: a ComM request (full or, more rarely, none), a
    /// bus-off, a start or stop indication, a refused start or stop (rarely), or a
    /// main-function period.
    fn step(sm: &mut CanSm, e: u8) -> Actions {
        match e % 8 {
            0 => sm.request(ComMode::Full),
            1 if e % 32 == 1 => sm.request(ComMode::No),
            2 => sm.controller_bus_off(),
            4 => sm.controller_mode_indication(ControllerMode::Started),
            5 => sm.controller_mode_indication(ControllerMode::Stopped),
            6 if e % 64 == 6 => sm.mode_refused(ControllerMode::Started),
            7 if e % 64 == 7 => sm.mode_refused(ControllerMode::Stopped),
            _ => sm.main_function(),
        }
    }

    /// Runs CanSM on `cfg` through `events` (each byte one event: a ComM request, a
    /// bus-off, an indication, a refusal or a period) and checks after each: the
    /// controller is asked to start only while full communication is requested; the
    /// channel opens only in full communication; ComM is told exactly the changes of the
    /// mode it sees; a bus-off wait never exceeds the slow recovery time, nor does the
    /// time off the bus since the last bus-off; no mode request waits for its indication
    /// past its repetitions.
    pub fn events_keep_the_promises(cfg: CanSmConfig, events: &[u8]) -> bool {
        let mut sm = CanSm::new(cfg);
        // Main-function periods spent off the bus since the last bus-off.
        let mut periods_off = 0u32;
        for &e in events {
            let before = sm.current_mode();
            let actions = step(&mut sm, e);
            let after = sm.current_mode();
            let told = actions.indicate == (after != before).then_some(after);
            let start_wanted = actions.controller != Some(ControllerMode::Started)
                || sm.requested == ComMode::Full;
            let online_in_full = actions.pdu != Some(PduMode::Online) || after == ComMode::Full;
            if !(told && start_wanted && online_in_full) {
                return false;
            }
            match sm.state() {
                CanSmState::BusOff { remaining } => {
                    if e % 8 == 2 {
                        periods_off = 0;
                    } else if e % 8 == 3 {
                        periods_off += 1;
                    }
                    if remaining > cfg.slow_cycles || periods_off >= cfg.slow_cycles {
                        return false;
                    }
                }
                CanSmState::StartRequested { waited, .. }
                | CanSmState::StopRequested { waited } => {
                    if waited >= cfg.mode_request_timeout_cycles {
                        return false;
                    }
                    periods_off = 0;
                }
                CanSmState::NoCommunication | CanSmState::FullCommunication { .. } => {
                    periods_off = 0;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;

    const CFG: CanSmConfig = match CanSmConfig::from_ms(
        10,
        CanSmTimesMs {
            fast_retries: 2,
            fast: 20,
            slow: 100,
            tx_ensured: 50,
            mode_request: 30,
            mode_request_repeats: 2,
        },
    ) {
        Ok(c) => c,
        Err(_) => panic!("bad CanSM timing"),
    };

    fn cycles_until_restart(sm: &mut CanSm) -> u32 {
        let mut n = 0;
        loop {
            n += 1;
            if sm.main_function().controller == Some(ControllerMode::Started) {
                return n;
            }
            assert!(n < 1000, "never restarted");
        }
    }

    /// Full communication through a controller that starts at once.
    fn full() -> CanSm {
        let mut sm = CanSm::new(CFG);
        sm.request(ComMode::Full);
        sm.controller_mode_indication(ControllerMode::Started);
        assert_eq!(sm.current_mode(), ComMode::Full);
        sm
    }

    #[test]
    fn full_and_no_communication_requests_complete_at_their_indications() {
        let mut sm = CanSm::new(CFG);
        assert_eq!(sm.current_mode(), ComMode::No);
        let a = sm.request(ComMode::Full);
        assert_eq!(
            a,
            Actions {
                pdu: None,
                controller: Some(ControllerMode::Started),
                indicate: None
            },
            "the channel stays closed until the start is indicated"
        );
        assert_eq!(sm.current_mode(), ComMode::No);
        assert_eq!(
            sm.controller_mode_indication(ControllerMode::Stopped),
            Actions::default(),
            "not the mode asked for"
        );
        let a = sm.controller_mode_indication(ControllerMode::Started);
        assert_eq!(
            (a.pdu, a.controller, a.indicate),
            (Some(PduMode::Online), None, Some(ComMode::Full))
        );
        assert_eq!(
            sm.state(),
            CanSmState::FullCommunication {
                since_restart: None
            }
        );
        assert_eq!(
            sm.request(ComMode::Full),
            Actions::default(),
            "already full"
        );
        let a = sm.request(ComMode::No);
        assert_eq!(
            (a.pdu, a.controller, a.indicate),
            (
                Some(PduMode::Offline),
                Some(ControllerMode::Stopped),
                Some(ComMode::No)
            ),
            "offline before the stop is asked for"
        );
        assert_eq!(sm.request(ComMode::No), Actions::default(), "on the way");
        assert_eq!(
            sm.controller_bus_off(),
            Actions::default(),
            "bus-off while stopping is ignored"
        );
        assert_eq!(
            sm.controller_mode_indication(ControllerMode::Stopped),
            Actions::default()
        );
        assert_eq!(sm.state(), CanSmState::NoCommunication);
        assert_eq!(
            sm.controller_bus_off(),
            Actions::default(),
            "bus-off while off-line is ignored"
        );
        assert_eq!(sm.bus_off_total(), 0);
        assert_eq!(sm.request(ComMode::No), Actions::default());
    }

    #[test]
    fn bus_off_recovers_fast_then_slow_then_fast_again_once_ensured() {
        let mut sm = full();
        // Two fast recoveries (20 ms = 2 cycles), then slow ones (100 ms = 10 cycles).
        for expected in [2, 2, 10, 10] {
            let a = sm.controller_bus_off();
            assert_eq!(a.pdu, Some(PduMode::TxOffline));
            assert_eq!(a.indicate, Some(ComMode::No));
            assert_eq!(sm.current_mode(), ComMode::No);
            assert_eq!(cycles_until_restart(&mut sm), expected);
            assert_eq!(
                sm.current_mode(),
                ComMode::No,
                "until the start is indicated"
            );
            let a = sm.controller_mode_indication(ControllerMode::Started);
            assert_eq!(a.pdu, Some(PduMode::Online));
            assert_eq!(
                sm.state(),
                CanSmState::FullCommunication {
                    since_restart: Some(0)
                }
            );
        }
        assert_eq!(sm.bus_off_total(), 4);
        assert_eq!(sm.bus_off_consecutive(), 4);
        // 50 ms (5 cycles) without bus-off: the recovery is ensured, the counter resets;
        // not before.
        for _ in 0..4 {
            sm.main_function();
        }
        assert_eq!(
            sm.state(),
            CanSmState::FullCommunication {
                since_restart: Some(4)
            }
        );
        assert_eq!(sm.bus_off_consecutive(), 4);
        sm.main_function();
        assert_eq!(
            sm.state(),
            CanSmState::FullCommunication {
                since_restart: None
            }
        );
        assert_eq!(sm.bus_off_consecutive(), 0);
        sm.controller_bus_off();
        assert_eq!(cycles_until_restart(&mut sm), 2, "fast again");
        // A bus-off before the restart is indicated: off the bus again, counted.
        assert_eq!(sm.controller_bus_off().pdu, Some(PduMode::TxOffline));
        assert_eq!(sm.bus_off_total(), 6);
        assert_eq!(
            sm.controller_mode_indication(ControllerMode::Started),
            Actions::default(),
            "a start indicated during the wait changes nothing"
        );
        assert!(matches!(sm.state(), CanSmState::BusOff { .. }));
    }

    #[test]
    fn no_communication_during_recovery_wins() {
        let mut sm = full();
        sm.controller_bus_off();
        let a = sm.request(ComMode::No);
        assert_eq!(a.controller, Some(ControllerMode::Stopped));
        assert_eq!(a.indicate, None, "already without communication");
        sm.controller_mode_indication(ControllerMode::Stopped);
        for _ in 0..20 {
            assert_eq!(sm.main_function(), Actions::default());
        }
        assert_eq!(sm.state(), CanSmState::NoCommunication);
    }

    #[test]
    fn times_must_be_whole_periods() {
        let times = CanSmTimesMs {
            fast_retries: 1,
            fast: 10,
            slow: 100,
            tx_ensured: 50,
            mode_request: 10,
            mode_request_repeats: 1,
        };
        assert!(CanSmConfig::from_ms(10, times).is_ok());
        for broken in [
            CanSmTimesMs { fast: 15, ..times },
            CanSmTimesMs { slow: 0, ..times },
            CanSmTimesMs {
                tx_ensured: 55,
                ..times
            },
            CanSmTimesMs {
                mode_request: 0,
                ..times
            },
        ] {
            assert_eq!(CanSmConfig::from_ms(10, broken), Err(CanSmConfigError));
        }
        assert_eq!(CanSmConfig::from_ms(0, times), Err(CanSmConfigError));
    }

    /// A start never indicated is asked again every 30 ms (3 cycles), twice, then has timed
    /// out: off the bus, a new start after the fast wait. A stop never indicated is taken
    /// as done after as long.
    #[test]
    fn a_mode_request_never_indicated_is_repeated_then_times_out() {
        let mut sm = CanSm::new(CFG);
        sm.request(ComMode::Full);
        let mut repeats = std::vec::Vec::new();
        for cycle in 1..=9 {
            let a = sm.main_function();
            if a.controller.is_some() {
                repeats.push((cycle, a.controller));
            }
            if cycle < 9 {
                assert!(matches!(sm.state(), CanSmState::StartRequested { .. }));
            }
        }
        let started = Some(ControllerMode::Started);
        assert_eq!(repeats, [(3, started), (6, started)]);
        assert_eq!(
            sm.state(),
            CanSmState::BusOff {
                remaining: CFG.fast_cycles
            }
        );
        assert_eq!(sm.mode_request_timeouts(), 1);
        assert_eq!(sm.bus_off_total(), 0, "not a bus-off");
        assert_eq!(cycles_until_restart(&mut sm), 2);
        sm.controller_mode_indication(ControllerMode::Started);
        assert_eq!(sm.current_mode(), ComMode::Full);

        sm.request(ComMode::No);
        let mut repeats = 0;
        for _ in 1..=9 {
            if sm.main_function().controller == Some(ControllerMode::Stopped) {
                repeats += 1;
            }
        }
        assert_eq!(repeats, 2);
        assert_eq!(sm.state(), CanSmState::NoCommunication);
        assert_eq!(sm.mode_request_timeouts(), 2);
    }

    #[test]
    fn refused_modes_keep_the_channel_closed() {
        let mut sm = CanSm::new(CFG);
        sm.request(ComMode::Full);
        let a = sm.mode_refused(ControllerMode::Started);
        assert_eq!(a.pdu, Some(PduMode::TxOffline));
        assert_eq!(
            sm.state(),
            CanSmState::BusOff {
                remaining: CFG.fast_cycles
            }
        );
        assert_eq!(cycles_until_restart(&mut sm), 2);
        sm.controller_mode_indication(ControllerMode::Started);
        sm.request(ComMode::No);
        assert_eq!(
            sm.mode_refused(ControllerMode::Stopped),
            Actions::default(),
            "asked again after the repetition time"
        );
        assert!(matches!(sm.state(), CanSmState::StopRequested { .. }));
    }

    /// ComM asks for full communication again while the controller is still stopping:
    /// the start follows the stop's indication.
    #[test]
    fn a_full_request_during_a_stop_starts_after_it() {
        let mut sm = full();
        sm.request(ComMode::No);
        assert_eq!(sm.request(ComMode::Full), Actions::default());
        let a = sm.controller_mode_indication(ControllerMode::Stopped);
        assert_eq!(a.controller, Some(ControllerMode::Started));
        assert_eq!(
            sm.state(),
            CanSmState::StartRequested {
                waited: 0,
                after_bus_off: false
            }
        );
    }

    /// A controller for `apply`: reaches modes at once or later, may refuse to start.
    #[derive(Default)]
    struct Controller {
        mode: Option<ControllerMode>,
        asked: std::vec::Vec<ControllerMode>,
        slow: bool,
        refuses_start: bool,
    }

    impl CanDriver for Controller {
        fn init(
            &mut self,
            _: &crate::can::ControllerConfig,
        ) -> Result<(), crate::can::InitRefused> {
            Ok(())
        }
        fn write(
            &mut self,
            _: crate::can::Hth,
            _: u16,
            _: &crate::can::CanFrame,
        ) -> Result<(), crate::can::CanBusy> {
            Ok(())
        }
        fn set_controller_mode(
            &mut self,
            mode: ControllerMode,
        ) -> Result<ModeChange, crate::can::ModeRefused> {
            self.asked.push(mode);
            if mode == ControllerMode::Started && self.refuses_start {
                return Err(crate::can::ModeRefused);
            }
            if self.slow {
                return Ok(ModeChange::Pending);
            }
            self.mode = Some(mode);
            Ok(ModeChange::Reached)
        }
        fn error_counters(&self) -> crate::can::ErrorCounters {
            crate::can::ErrorCounters::ACTIVE
        }
        fn abort(&mut self, _: crate::can::Hth) {}
    }

    static NO_PDUS: CanIfConfig<0, 0> = match CanIfConfig::new([], []) {
        Ok(c) => c,
        Err(_) => panic!("empty CanIf tables"),
    };

    /// `apply`, `mode_indication` and `bus_off` carry CanSM's actions out on CanIf and the
    /// controller: the channel opens when the start is reached (at once, or at its
    /// indication), closes before the stop is asked for, stays closed on a refusal; a stop
    /// reached at once is followed by the start ComM asked for meanwhile.
    #[test]
    fn actions_reach_canif_and_the_controller_in_order() {
        let (mut sm, mut canif, mut can) =
            (CanSm::new(CFG), CanIf::new(&NO_PDUS), Controller::default());
        let request = |sm: &mut CanSm, canif: &mut CanIf<0, 0>, can: &mut Controller, m| {
            let actions = sm.request(m);
            apply(sm, canif, can, actions);
        };
        request(&mut sm, &mut canif, &mut can, ComMode::Full);
        assert_eq!(canif.controller_mode(), ControllerMode::Started);
        assert_eq!(canif.pdu_mode(), PduMode::Online);
        assert_eq!(sm.current_mode(), ComMode::Full);

        can.slow = true;
        request(&mut sm, &mut canif, &mut can, ComMode::No);
        assert_eq!(canif.pdu_mode(), PduMode::Offline, "closed before the stop");
        assert_eq!(canif.controller_mode(), ControllerMode::Started, "not yet");
        assert!(matches!(sm.state(), CanSmState::StopRequested { .. }));
        // ComM wants the network back before the stop is reached; the controller is quick
        // again, so the stop's indication leads to a start reached at once.
        request(&mut sm, &mut canif, &mut can, ComMode::Full);
        can.slow = false;
        mode_indication(&mut sm, &mut canif, &mut can, ControllerMode::Stopped);
        assert_eq!(
            can.asked,
            [
                ControllerMode::Started,
                ControllerMode::Stopped,
                ControllerMode::Started
            ]
        );
        assert_eq!(canif.pdu_mode(), PduMode::Online);
        assert_eq!(sm.current_mode(), ComMode::Full);

        bus_off(&mut sm, &mut canif, &mut can);
        assert_eq!(canif.controller_mode(), ControllerMode::Stopped);
        assert_eq!(canif.pdu_mode(), PduMode::TxOffline);
        // The restart is refused: off the bus again, without counting a bus-off.
        can.refuses_start = true;
        for _ in 0..CFG.fast_cycles {
            let actions = sm.main_function();
            apply(&mut sm, &mut canif, &mut can, actions);
        }
        assert_eq!(
            sm.state(),
            CanSmState::BusOff {
                remaining: CFG.fast_cycles
            }
        );
        assert_eq!(canif.pdu_mode(), PduMode::TxOffline);
        assert_eq!(sm.bus_off_total(), 1);
        // Started late: online at the indication, with the recovery to be ensured.
        (can.refuses_start, can.slow) = (false, true);
        for _ in 0..CFG.fast_cycles {
            let actions = sm.main_function();
            apply(&mut sm, &mut canif, &mut can, actions);
        }
        assert_eq!(canif.pdu_mode(), PduMode::TxOffline);
        mode_indication(&mut sm, &mut canif, &mut can, ControllerMode::Started);
        assert_eq!(canif.pdu_mode(), PduMode::Online);
        assert_eq!(
            sm.state(),
            CanSmState::FullCommunication {
                since_restart: Some(0)
            }
        );
    }

    /// Any sequence of requests, indications, refusals, bus-offs and periods keeps
    /// CanSM's promises (`spec::events_keep_the_promises`).
    #[test]
    fn any_event_sequence_keeps_the_recovery_promises() {
        bolero::check!()
            .with_type::<std::vec::Vec<u8>>()
            .for_each(|events| {
                let events = events.get(..300).unwrap_or(events);
                assert!(spec::events_keep_the_promises(CFG, events));
            });
    }

    /// The same for every sequence of 8 events (Kani), or random ones.
    #[test]
    #[cfg_attr(kani, kani::proof, kani::unwind(10))]
    fn every_short_event_sequence_keeps_the_recovery_promises() {
        bolero::check!()
            .with_type::<[u8; 8]>()
            .for_each(|events| assert!(spec::events_keep_the_promises(CFG, events)));
    }

    /// The predicate can fail: with no time to wait for an indication, every request
    /// waits too long.
    #[test]
    fn the_promises_can_be_broken() {
        let waits_too_long = CanSmConfig {
            mode_request_timeout_cycles: 0,
            ..CFG
        };
        assert!(!spec::events_keep_the_promises(waits_too_long, &[0]));
        assert!(spec::events_keep_the_promises(CFG, &[0, 4, 2, 3, 3, 4]));
    }
}
