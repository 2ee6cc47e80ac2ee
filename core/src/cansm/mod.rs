//! CAN State Manager (AUTOSAR SWS CanSM) with the communication requests of ComM.
//!
//! CanSM owns the network's communication mode and recovers from bus-off:
//! - ComM asks for full or no communication ([`ComMode`]); CanSM starts or stops the
//!   controller and sets the CanIf PDU mode accordingly.
//! - On bus-off (`CanSM_ControllerBusOff`) transmission stops at once; after the recovery
//!   time the controller is restarted. The first [`CanSmConfig::fast_retries`] recoveries wait
//!   `fast_ms` (`CanSMBorTimeL1`), later ones `slow_ms` (`CanSMBorTimeL2`). A recovery
//!   counts as successful once `tx_ensured_ms` (`CanSMBorTimeTxEnsured`) pass without a new
//!   bus-off; then the counter returns to zero and the next bus-off is fast again.
//!
//! CanSM is pure: [`CanSm::request`], [`CanSm::controller_bus_off`] and
//! [`CanSm::main_function`] return the [`Actions`] the caller applies to CanIf and the
//! driver. Times are in main-function cycles (the configuration converts milliseconds).

use crate::can::{CanDriver, ControllerMode};
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
    /// Full communication; `since_restart` counts cycles since the last bus-off restart
    /// (`None` once the transmission is ensured).
    FullCommunication {
        /// Cycles since the restart after a bus-off, until the transmission is ensured.
        since_restart: Option<u32>,
    },
    /// Off the bus (after a bus-off, or a start the controller refused), waiting
    /// `remaining` cycles before restarting the controller.
    BusOff {
        /// Cycles left before the restart.
        remaining: u32,
    },
}

/// What the caller must do to CanIf and the controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Actions {
    /// Set the controller to this mode (through CanIf).
    pub controller: Option<ControllerMode>,
    /// Set the CanIf PDU channel to this mode.
    pub pdu: Option<PduMode>,
    /// Tell ComM the network changed communication mode.
    pub indicate: Option<ComMode>,
}

/// Recovery timing, in main-function cycles.
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
}

/// A timing that would never restart or never settle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanSmConfigError;

impl CanSmConfig {
    /// Builds the timing from milliseconds and the main-function period.
    ///
    /// # Errors
    /// [`CanSmConfigError`] if a time is zero or not a whole number of periods.
    pub const fn from_ms(
        main_period_ms: u32,
        fast_retries: u8,
        fast_ms: u32,
        slow_ms: u32,
        tx_ensured_ms: u32,
    ) -> Result<Self, CanSmConfigError> {
        if main_period_ms == 0
            || fast_ms == 0
            || slow_ms == 0
            || tx_ensured_ms == 0
            || fast_ms % main_period_ms != 0
            || slow_ms % main_period_ms != 0
            || tx_ensured_ms % main_period_ms != 0
        {
            return Err(CanSmConfigError);
        }
        Ok(Self {
            fast_retries,
            fast_cycles: fast_ms / main_period_ms,
            slow_cycles: slow_ms / main_period_ms,
            tx_ensured_cycles: tx_ensured_ms / main_period_ms,
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

    /// The communication mode the network is in, as ComM sees it.
    pub const fn current_mode(&self) -> ComMode {
        match self.state {
            CanSmState::NoCommunication | CanSmState::BusOff { .. } => ComMode::No,
            CanSmState::FullCommunication { .. } => ComMode::Full,
        }
    }

    /// `CanSM_RequestComMode`, called by ComM.
    pub fn request(&mut self, mode: ComMode) -> Actions {
        self.requested = mode;
        match (mode, self.state) {
            (ComMode::Full, CanSmState::NoCommunication) => {
                self.state = CanSmState::FullCommunication {
                    since_restart: None,
                };
                Actions {
                    controller: Some(ControllerMode::Started),
                    pdu: Some(PduMode::Online),
                    indicate: Some(ComMode::Full),
                }
            }
            (ComMode::No, CanSmState::FullCommunication { .. } | CanSmState::BusOff { .. }) => {
                self.state = CanSmState::NoCommunication;
                Actions {
                    controller: Some(ControllerMode::Stopped),
                    pdu: Some(PduMode::Offline),
                    indicate: Some(ComMode::No),
                }
            }
            // Already there, or a full request during recovery (it completes by itself).
            _ => Actions::default(),
        }
    }

    /// `CanSM_ControllerBusOff`: transmission stops; the restart waits the fast or the
    /// slow recovery time.
    pub fn controller_bus_off(&mut self) -> Actions {
        if self.state == CanSmState::NoCommunication {
            return Actions::default();
        }
        self.total = self.total.saturating_add(1);
        let wait = if self.consecutive < self.cfg.fast_retries {
            self.cfg.fast_cycles
        } else {
            self.cfg.slow_cycles
        };
        self.consecutive = self.consecutive.saturating_add(1);
        let was_full = matches!(self.state, CanSmState::FullCommunication { .. });
        self.state = CanSmState::BusOff { remaining: wait };
        Actions {
            controller: None,
            pdu: Some(PduMode::TxOffline),
            indicate: was_full.then_some(ComMode::No),
        }
    }

    /// The controller refused to start (`CanIf_SetControllerMode` failed): CanSM stays off
    /// the bus and asks again after the fast recovery time, as after a bus-off, without
    /// counting a bus-off. The channel stays closed for transmission meanwhile.
    pub fn start_refused(&mut self) -> Actions {
        let was_full = matches!(self.state, CanSmState::FullCommunication { .. });
        self.state = CanSmState::BusOff {
            remaining: self.cfg.fast_cycles,
        };
        Actions {
            controller: None,
            pdu: Some(PduMode::TxOffline),
            indicate: was_full.then_some(ComMode::No),
        }
    }

    /// `CanSM_MainFunction`: one period passed.
    pub fn main_function(&mut self) -> Actions {
        match self.state {
            CanSmState::BusOff { remaining } if remaining > 1 => {
                self.state = CanSmState::BusOff {
                    remaining: remaining - 1,
                };
                Actions::default()
            }
            CanSmState::BusOff { .. } => {
                self.state = CanSmState::FullCommunication {
                    since_restart: Some(0),
                };
                Actions {
                    controller: Some(ControllerMode::Started),
                    pdu: Some(PduMode::Online),
                    indicate: Some(ComMode::Full),
                }
            }
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
            _ => Actions::default(),
        }
    }
}

/// Carries out CanSM's [`Actions`] on CanIf and the controller. A controller that refuses
/// to start is reported back to CanSM ([`CanSm::start_refused`]), so the channel never goes
/// online on a stopped controller; a refused stop still takes the channel offline.
pub fn apply<D: CanDriver, const TX: usize, const RX: usize, K: Tables<CanIfConfig<TX, RX>>>(
    cansm: &mut CanSm,
    canif: &mut CanIf<TX, RX, K>,
    driver: &mut D,
    actions: Actions,
) {
    if let Some(mode) = actions.controller {
        let refused = canif.set_controller_mode(driver, mode).is_err();
        if refused && mode == ControllerMode::Started {
            let retry = cansm.start_refused();
            if let Some(pdu) = retry.pdu {
                canif.set_pdu_mode(pdu);
            }
            return;
        }
    }
    if let Some(pdu) = actions.pdu {
        canif.set_pdu_mode(pdu);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;

    const CFG: CanSmConfig = match CanSmConfig::from_ms(10, 2, 20, 100, 50) {
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

    #[test]
    fn full_and_no_communication_requests() {
        let mut sm = CanSm::new(CFG);
        assert_eq!(sm.current_mode(), ComMode::No);
        let a = sm.request(ComMode::Full);
        assert_eq!(a.controller, Some(ControllerMode::Started));
        assert_eq!(a.pdu, Some(PduMode::Online));
        assert_eq!(
            sm.request(ComMode::Full),
            Actions::default(),
            "already full"
        );
        let a = sm.request(ComMode::No);
        assert_eq!(
            (a.controller, a.pdu),
            (Some(ControllerMode::Stopped), Some(PduMode::Offline))
        );
        assert_eq!(
            sm.controller_bus_off(),
            Actions::default(),
            "bus-off while off-line is ignored"
        );
    }

    #[test]
    fn bus_off_recovers_fast_then_slow_then_fast_again_once_ensured() {
        let mut sm = CanSm::new(CFG);
        sm.request(ComMode::Full);
        // Two fast recoveries (20 ms = 2 cycles), then slow ones (100 ms = 10 cycles).
        for expected in [2, 2, 10, 10] {
            let a = sm.controller_bus_off();
            assert_eq!(a.pdu, Some(PduMode::TxOffline));
            assert_eq!(sm.current_mode(), ComMode::No);
            assert_eq!(cycles_until_restart(&mut sm), expected);
            assert_eq!(sm.current_mode(), ComMode::Full);
        }
        assert_eq!(sm.bus_off_total(), 4);
        assert_eq!(sm.bus_off_consecutive(), 4);
        // 50 ms (5 cycles) without bus-off: the recovery is ensured, the counter resets.
        for _ in 0..5 {
            sm.main_function();
        }
        assert_eq!(
            sm.state(),
            CanSmState::FullCommunication {
                since_restart: None
            }
        );
        assert_eq!(sm.bus_off_consecutive(), 0);
        sm.controller_bus_off();
        assert_eq!(cycles_until_restart(&mut sm), 2, "fast again");
    }

    #[test]
    fn no_communication_during_recovery_wins() {
        let mut sm = CanSm::new(CFG);
        sm.request(ComMode::Full);
        sm.controller_bus_off();
        let a = sm.request(ComMode::No);
        assert_eq!(a.controller, Some(ControllerMode::Stopped));
        for _ in 0..20 {
            assert_eq!(sm.main_function(), Actions::default());
        }
        assert_eq!(sm.state(), CanSmState::NoCommunication);
        assert_eq!(
            CanSmConfig::from_ms(10, 1, 15, 100, 50),
            Err(CanSmConfigError)
        );
    }

    /// Any sequence of requests, bus-offs and periods: the controller is never started while
    /// no communication is requested, and every bus-off in full communication leads to a
    /// restart within the slow recovery time.
    #[test]
    fn any_event_sequence_keeps_the_recovery_promises() {
        bolero::check!()
            .with_type::<std::vec::Vec<u8>>()
            .for_each(|events| {
                let mut sm = CanSm::new(CFG);
                // Main-function periods spent off the bus since the last bus-off.
                let mut periods_off = 0u32;
                for e in events.iter().take(300) {
                    let actions = match e % 4 {
                        0 => sm.request(ComMode::Full),
                        1 if e % 32 == 1 => sm.request(ComMode::No),
                        2 => sm.controller_bus_off(),
                        _ => sm.main_function(),
                    };
                    if actions.controller == Some(ControllerMode::Started) {
                        assert_eq!(sm.requested, ComMode::Full);
                    }
                    match sm.state() {
                        CanSmState::BusOff { remaining } => {
                            assert!(remaining <= CFG.slow_cycles);
                            if e % 4 == 2 {
                                periods_off = 0;
                            } else if e % 4 == 3 {
                                periods_off += 1;
                            }
                            assert!(
                                periods_off < CFG.slow_cycles,
                                "still off after {periods_off} periods"
                            );
                        }
                        _ => periods_off = 0,
                    }
                }
            });
    }
}
