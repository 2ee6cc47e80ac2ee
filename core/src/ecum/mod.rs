//! ECU State Manager and BSW Mode Manager (AUTOSAR SWS EcuM, fixed variant, and SWS BswM),
//! as the paper's ECU uses them (paper §3.2.3): `OsStartupTask` calls `EcuM_StartupTwo`,
//! which initialises the BSW; the `ModeManagerInit` SWC then asks BswM for the run mode,
//! whose action list requests full communication from ComM and RUN from EcuM.
//!
//! [`EcuM`] is a state machine that says *what* to initialise, in which order, and when
//! the ECU may run or must shut down; the firmware does the initialising. Wrong-order calls
//! are refused with [`EcuMError`], never half-done.

use crate::can::CanDriver;
use crate::canif::{CanIf, CanIfConfig};
use crate::cansm::{apply, CanSm, ComMode};
use crate::tables::Tables;

/// A BSW module the start-up initialises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Module {
    /// Microcontroller driver (clocks).
    Mcu,
    /// Port driver (pin functions).
    Port,
    /// Digital I/O driver.
    Dio,
    /// General-purpose timer driver (the sonar echo timing).
    Gpt,
    /// CAN driver.
    Can,
    /// CAN interface.
    CanIf,
    /// CAN state manager.
    CanSm,
    /// PDU router.
    PduR,
    /// Communication services.
    Com,
    /// Communication manager.
    ComM,
    /// BSW mode manager.
    BswM,
    /// I/O hardware abstraction.
    IoHwAb,
}

/// `EcuM_Init` (start-up one, before the OS): drivers needed to start the OS.
pub const STARTUP_ONE: [Module; 4] = [Module::Mcu, Module::Port, Module::Dio, Module::Gpt];
/// `EcuM_StartupTwo` (in `OsStartupTask`): the rest of the BSW, lower layers first.
pub const STARTUP_TWO: [Module; 8] = [
    Module::Can,
    Module::CanIf,
    Module::CanSm,
    Module::PduR,
    Module::Com,
    Module::ComM,
    Module::BswM,
    Module::IoHwAb,
];

/// EcuM states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EcuMState {
    /// Power on, nothing initialised.
    Off,
    /// Start-up one done; the OS may start.
    StartupOneDone,
    /// Start-up two done: the BSW is initialised, waiting for a RUN request.
    StartupTwoDone,
    /// Running: at least one user requests RUN.
    Run,
    /// No user requests RUN any more: post-run, then shutdown.
    PostRun,
    /// Shut down (communication stopped; the OS may shut down).
    Shutdown,
}

/// A service called out of order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EcuMError {
    /// The call does not fit the current state.
    WrongState(EcuMState),
    /// The user id is 32 or above.
    UnknownUser,
}

/// Requests the mode-manager SWC sends to BswM.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BswMRequest {
    /// Bring the ECU into its run mode (`ModeManagerInit` at start).
    EcuRun,
    /// Leave the run mode (ignition off): communication stops, then post-run and shutdown.
    EcuPostRun,
    /// Stop communicating on the network while running (e.g. a diagnostic communication
    /// control): the ECU keeps working locally.
    CommunicationOff,
    /// Communicate again after [`BswMRequest::CommunicationOff`].
    CommunicationOn,
}

/// One action of a BswM action list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BswMAction {
    /// `ComM_RequestComMode(user, COMM_FULL_COMMUNICATION)`.
    ComMFullCommunication,
    /// `ComM_RequestComMode(user, COMM_NO_COMMUNICATION)`.
    ComMNoCommunication,
    /// `EcuM_RequestRUN(user)`.
    EcuMRequestRun,
    /// `EcuM_ReleaseRUN(user)`.
    EcuMReleaseRun,
}

/// BswM's rule for a request: the actions to carry out, in order.
pub const fn bswm_actions(request: BswMRequest) -> &'static [BswMAction] {
    match request {
        BswMRequest::EcuRun => &[
            BswMAction::ComMFullCommunication,
            BswMAction::EcuMRequestRun,
        ],
        BswMRequest::EcuPostRun => &[BswMAction::ComMNoCommunication, BswMAction::EcuMReleaseRun],
        BswMRequest::CommunicationOff => &[BswMAction::ComMNoCommunication],
        BswMRequest::CommunicationOn => &[BswMAction::ComMFullCommunication],
    }
}

/// A BswM request whose rule condition does not hold now; nothing was done.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RequestRefused(pub EcuMState);

/// BswM: carries out the action list of `request` on EcuM and, through ComM, on CanSM,
/// CanIf and the controller. Rule conditions: every request needs the BSW started and not
/// shut down, and [`BswMRequest::CommunicationOn`] needs RUN (communication never restarts
/// during post-run).
///
/// # Errors
/// [`RequestRefused`] with the EcuM state when the rule's condition does not hold.
pub fn bswm_execute<D, const TX: usize, const RX: usize, K>(
    request: BswMRequest,
    ecum: &mut EcuM,
    cansm: &mut CanSm,
    canif: &mut CanIf<TX, RX, K>,
    driver: &mut D,
) -> Result<(), RequestRefused>
where
    D: CanDriver,
    K: Tables<CanIfConfig<TX, RX>>,
{
    let state = ecum.state();
    let allowed = match request {
        BswMRequest::EcuRun => matches!(state, EcuMState::StartupTwoDone | EcuMState::Run),
        BswMRequest::CommunicationOn => state == EcuMState::Run,
        BswMRequest::EcuPostRun | BswMRequest::CommunicationOff => {
            matches!(state, EcuMState::Run | EcuMState::PostRun)
        }
    };
    if !allowed {
        return Err(RequestRefused(state));
    }
    for action in bswm_actions(request) {
        match action {
            BswMAction::ComMFullCommunication => {
                let actions = cansm.request(ComMode::Full);
                apply(cansm, canif, driver, actions);
            }
            BswMAction::ComMNoCommunication => {
                let actions = cansm.request(ComMode::No);
                apply(cansm, canif, driver, actions);
            }
            // The state was checked above: these cannot fail here.
            BswMAction::EcuMRequestRun => {
                let _ = ecum.request_run(0);
            }
            BswMAction::EcuMReleaseRun => {
                let _ = ecum.release_run(0);
            }
        }
    }
    Ok(())
}

/// The EcuM state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EcuM {
    state: EcuMState,
    /// Users requesting RUN, one bit each.
    run_requests: u32,
}

impl Default for EcuM {
    fn default() -> Self {
        Self::new()
    }
}

impl EcuM {
    /// EcuM at power-on.
    pub const fn new() -> Self {
        Self {
            state: EcuMState::Off,
            run_requests: 0,
        }
    }

    /// The current state.
    pub const fn state(&self) -> EcuMState {
        self.state
    }

    fn require_state(&self, state: EcuMState) -> Result<(), EcuMError> {
        if self.state == state {
            Ok(())
        } else {
            Err(EcuMError::WrongState(self.state))
        }
    }

    /// `EcuM_Init`: the modules to initialise before starting the OS, in order.
    ///
    /// # Errors
    /// [`EcuMError::WrongState`] unless off.
    pub fn init(&mut self) -> Result<&'static [Module], EcuMError> {
        self.require_state(EcuMState::Off)?;
        self.state = EcuMState::StartupOneDone;
        Ok(&STARTUP_ONE)
    }

    /// `EcuM_StartupTwo`: the BSW modules to initialise in `OsStartupTask`, in order.
    ///
    /// # Errors
    /// [`EcuMError::WrongState`] unless start-up one is done.
    pub fn startup_two(&mut self) -> Result<&'static [Module], EcuMError> {
        self.require_state(EcuMState::StartupOneDone)?;
        self.state = EcuMState::StartupTwoDone;
        Ok(&STARTUP_TWO)
    }

    fn user_bit(user: u8) -> Result<u32, EcuMError> {
        1u32.checked_shl(u32::from(user))
            .ok_or(EcuMError::UnknownUser)
    }

    /// `EcuM_RequestRUN`.
    ///
    /// # Errors
    /// [`EcuMError::WrongState`] before start-up two or after post-run began;
    /// [`EcuMError::UnknownUser`].
    pub fn request_run(&mut self, user: u8) -> Result<(), EcuMError> {
        let bit = Self::user_bit(user)?;
        match self.state {
            EcuMState::StartupTwoDone | EcuMState::Run => {
                self.run_requests |= bit;
                self.state = EcuMState::Run;
                Ok(())
            }
            other => Err(EcuMError::WrongState(other)),
        }
    }

    /// `EcuM_ReleaseRUN`: when the last user releases, the ECU enters post-run.
    ///
    /// # Errors
    /// [`EcuMError::WrongState`] unless running; [`EcuMError::UnknownUser`].
    pub fn release_run(&mut self, user: u8) -> Result<(), EcuMError> {
        let bit = Self::user_bit(user)?;
        self.require_state(EcuMState::Run)?;
        self.run_requests &= !bit;
        if self.run_requests == 0 {
            self.state = EcuMState::PostRun;
        }
        Ok(())
    }

    /// `EcuM_MainFunction`: in post-run, the ECU shuts down now. Returns whether it did, so
    /// that the caller puts the outputs in their safe state and stops the OS.
    pub fn main_function(&mut self) -> bool {
        self.shutdown().is_ok()
    }

    /// Ends post-run: the ECU shuts down.
    ///
    /// # Errors
    /// [`EcuMError::WrongState`] unless in post-run.
    pub fn shutdown(&mut self) -> Result<(), EcuMError> {
        self.require_state(EcuMState::PostRun)?;
        self.state = EcuMState::Shutdown;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_start_up_run_and_shutdown() {
        let mut ecum = EcuM::new();
        assert_eq!(
            ecum.startup_two(),
            Err(EcuMError::WrongState(EcuMState::Off))
        );
        assert_eq!(ecum.init(), Ok(&STARTUP_ONE[..]));
        assert_eq!(
            ecum.request_run(0),
            Err(EcuMError::WrongState(EcuMState::StartupOneDone))
        );
        let two = ecum.startup_two();
        assert_eq!(two.map(|m| m.first().copied()), Ok(Some(Module::Can)));
        // Lower layers are initialised before the layers that use them.
        let order = |m| STARTUP_TWO.iter().position(|x| *x == m);
        assert!(order(Module::CanIf) < order(Module::CanSm));
        assert!(order(Module::PduR) < order(Module::Com));
        assert!(order(Module::Com) < order(Module::ComM));
        // ModeManagerInit -> BswM: full communication, then RUN.
        assert_eq!(
            bswm_actions(BswMRequest::EcuRun),
            &[
                BswMAction::ComMFullCommunication,
                BswMAction::EcuMRequestRun
            ]
        );
        assert_eq!(ecum.request_run(0), Ok(()));
        assert_eq!(ecum.request_run(3), Ok(()));
        assert_eq!(ecum.request_run(32), Err(EcuMError::UnknownUser));
        assert_eq!(ecum.release_run(0), Ok(()));
        assert_eq!(ecum.state(), EcuMState::Run, "user 3 still requests RUN");
        assert_eq!(ecum.shutdown(), Err(EcuMError::WrongState(EcuMState::Run)));
        assert_eq!(ecum.release_run(3), Ok(()));
        assert_eq!(ecum.state(), EcuMState::PostRun);
        assert_eq!(
            ecum.request_run(0),
            Err(EcuMError::WrongState(EcuMState::PostRun))
        );
        assert_eq!(ecum.shutdown(), Ok(()));
        assert_eq!(ecum.init(), Err(EcuMError::WrongState(EcuMState::Shutdown)));
    }
}
