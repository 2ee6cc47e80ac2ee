//! The ECU: the OSEK kernel executing the paper's tasks, the BSW (EcuM/BswM, ComM/CanSM,
//! Com, PduR, CanIf) and the SWCs connected through the RTE, on any [`Board`].
//!
//! Execution model: the kernel decides who runs; [`Ecu::dispatch`] executes it. Tasks are
//! basic and run to completion, so a task that another one preempts (the sonar task
//! activating `OsComTask`) is simply suspended on the Rust stack while the higher one runs,
//! exactly as a single-stack OSEK kernel does. The timer and CAN interrupts are the
//! configuration's category-2 ISRs `SysTickIsr` and `CanIsr` ([`Ecu::tick`],
//! [`Ecu::can_isr`]): the board's interrupt controller takes them when the kernel's
//! interrupt mask admits them, the kernel is told of their entry and return, and
//! rescheduling happens when they return. The board applies the kernel's interrupt mask
//! ([`cw_core::os::InterruptControl`]) after every kernel call that can change it other
//! than an ISR's own entry and return, whose masking the interrupt controller does by
//! itself: here, `StartOS` and `ShutdownOS` (the ECU's tasks take no interrupt lock and
//! no resource shared with an ISR).
//!
//! Hooks ([`EcuHooks`]): `ErrorHook` counts every error a kernel service returned (none is
//! expected); `ShutdownHook` records the status `ShutdownOS` was given. EcuM's shutdown
//! calls `ShutdownOS`: from then on no task, ISR or alarm runs.

use cw_core::canif::{CanIf, RxDropped, TxPduId};
use cw_core::cansm::{self, Actions, CanSm};
use cw_core::com::ipdu::Com;
use cw_core::com::signal::SignalValue;
use cw_core::ecum::{bswm_execute, BswMRequest, EcuM};
use cw_core::os::{
    Hooks, InterruptControl, IsrId, OsError, ServiceId, StatusType, TaskId, E_OK, OSDEFAULTAPPMODE,
};
use cw_core::rte::RteError;
use cw_core::sonar::SonarConfig;
use cw_core::warning::{Measurement, WarningLevel};

use crate::board::Board;
use crate::config::{self, Kernel};
use crate::iohwab;
use crate::rte::Rte;
use crate::swc::{can_translate, LedActuator, LedColor, ObstacleDetection, UltraSonic};

/// A CAN controller event, delivered by the board's CAN interrupt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CanInterrupt {
    /// The frame of this CanIf PDU handle was sent.
    TxConfirmation(u16),
    /// A frame arrived in this receive mailbox.
    Received(cw_core::can::Hrh, cw_core::can::CanFrame),
    /// The controller went bus-off.
    BusOff,
}

/// The ECU's hook routines and their data (the OS configuration enables `ErrorHook` and
/// `ShutdownHook`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct EcuHooks {
    /// Errors reported to `ErrorHook`: services that returned one, alarm actions that
    /// failed (a period overrun would show here), tasks and ISRs that ended badly.
    pub errors: u32,
    /// The last error: the service and its status.
    pub last_error: Option<(ServiceId, OsError)>,
    /// The status `ShutdownOS` was given, once it ran.
    pub shutdown: Option<StatusType>,
}

impl Hooks<Kernel> for EcuHooks {
    fn error_hook(os: &mut Kernel, error: OsError) {
        let service = os.error_service_id();
        let hooks = os.hooks_mut();
        hooks.errors = hooks.errors.saturating_add(1);
        hooks.last_error = service.map(|s| (s, error));
    }

    fn shutdown_hook(os: &mut Kernel, error: StatusType) {
        os.hooks_mut().shutdown = Some(error);
    }
}

/// Counters an engineer looks at after a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EcuStats {
    /// Distance frames handed to CanIf (sent or buffered).
    pub frames_requested: u32,
    /// Distance frames CanIf refused (controller stopped or off-line, e.g. during bus-off).
    pub frames_refused: u32,
    /// Received frames dropped by CanIf (unknown id, wrong DLC, wrong mailbox, off-line).
    pub rx_dropped: u32,
    /// Kernel errors (none expected): those `ErrorHook` saw, and ISR entries or returns the
    /// kernel refused.
    pub os_errors: u32,
    /// LED writes a Dio channel refused.
    pub pin_faults: u32,
    /// Mode requests BswM refused (their rule's condition did not hold).
    pub mode_requests_refused: u32,
}

/// The whole ECU except the board.
pub struct Ecu {
    os: Kernel,
    ecum: EcuM,
    canif: config::EcuCanIf,
    cansm: CanSm,
    com: config::EcuCom,
    rte: Rte,
    ultrasonic: UltraSonic,
    obstacle: ObstacleDetection,
    red: LedActuator,
    yellow: LedActuator,
    /// The last threshold pair received from the PC and applied (raw), to apply each once.
    applied_thresholds: (u64, u64),
    last_measurement: Measurement,
    stats: EcuStats,
    /// ISR entries or returns the kernel refused (the board took an interrupt the mask
    /// held, or returned from one not active).
    port_errors: u32,
}

impl Ecu {
    /// The ECU before power-on.
    ///
    /// # Errors
    /// [`cw_core::os::ConfigError`] if the kernel's queue capacity does not match the
    /// configuration (a build-configuration mistake, reported rather than panicking).
    pub fn new(sensor: SonarConfig) -> Result<Self, cw_core::os::ConfigError> {
        Ok(Self {
            os: Kernel::new(config::OsTables)?,
            ecum: EcuM::new(),
            canif: CanIf::new(config::CanIfTables),
            cansm: CanSm::new(config::CANSM),
            com: Com::new(config::ComTables),
            rte: Rte::new(),
            ultrasonic: UltraSonic::new(sensor),
            obstacle: ObstacleDetection::new(),
            red: LedActuator::new(LedColor::Red),
            yellow: LedActuator::new(LedColor::Yellow),
            applied_thresholds: (1000, 2000),
            last_measurement: Measurement::Invalid,
            stats: EcuStats::default(),
            port_errors: 0,
        })
    }

    /// The kernel (for inspection).
    pub const fn os(&self) -> &Kernel {
        &self.os
    }

    /// The CanIf state (drop counters, modes).
    pub const fn canif(&self) -> &config::EcuCanIf {
        &self.canif
    }

    /// The CanSM state (bus-off counters).
    pub const fn cansm(&self) -> &CanSm {
        &self.cansm
    }

    /// The EcuM state.
    pub const fn ecum(&self) -> &EcuM {
        &self.ecum
    }

    /// The newest measurement UltraSonic published.
    pub const fn measurement(&self) -> Measurement {
        self.last_measurement
    }

    /// The level ObstacleDetection decided last.
    pub fn level(&self) -> WarningLevel {
        self.rte.led_request.read()
    }

    /// The warning thresholds in use.
    pub const fn thresholds(&self) -> cw_core::warning::Thresholds {
        self.obstacle.thresholds()
    }

    /// Run counters.
    pub fn stats(&self) -> EcuStats {
        EcuStats {
            os_errors: self.os.hooks().errors.saturating_add(self.port_errors),
            ..self.stats
        }
    }

    /// A kernel call the board makes as the port (ISR entry and return, `StartOS`): these
    /// have no `ErrorHook`, so their refusals are counted here.
    fn port_result(&mut self, result: Result<(), OsError>) {
        if result.is_err() {
            self.port_errors = self.port_errors.saturating_add(1);
        }
    }

    /// A mode request to BswM (from the mode-management SWC: ignition off, or a
    /// communication control), carried out by BswM's main function in the next
    /// `OsBswServiceTask`.
    ///
    /// # Errors
    /// [`RteError::Limit`] when four requests are already waiting; this one is not stored.
    pub fn request_mode(&mut self, request: BswMRequest) -> Result<(), RteError> {
        self.rte.mode_requests.send(request).map(|_| ())
    }

    /// Whether the ECU has shut down (`ShutdownOS` ran: it no longer runs).
    pub fn is_off(&self) -> bool {
        self.os.is_shut_down()
    }

    /// The hooks' record (errors, shutdown status).
    pub fn hooks(&self) -> &EcuHooks {
        self.os.hooks()
    }

    /// Power-on: `EcuM_Init` (start-up one), then `StartOS`, which runs `OsStartupTask`.
    pub fn start<B: Board>(&mut self, board: &mut B) {
        if self.ecum.init().is_err() {
            return;
        }
        // Start-up one: Mcu, Port (every pin to its direction, outputs low), Dio, Gpt.
        board.port_init();
        let started = self.os.start_os(OSDEFAULTAPPMODE);
        self.port_result(started);
        board.irq().apply_mask(self.os.interrupt_mask());
        self.dispatch(board);
    }

    /// Runs an ISR as the port does: the kernel is told of its entry, `body` runs, the
    /// kernel is told of its return (a rescheduling point), and the tasks it made ready run.
    fn isr<B: Board>(&mut self, board: &mut B, isr: IsrId, body: impl FnOnce(&mut Self, &mut B)) {
        if self.is_off() {
            return;
        }
        let entered = self.os.enter_isr(isr);
        self.port_result(entered);
        if entered.is_err() {
            return;
        }
        body(self, board);
        if self.is_off() {
            return;
        }
        let left = self.os.exit_isr();
        self.port_result(left);
        self.dispatch(board);
    }

    /// `SysTickIsr`, every 1 ms: the system counter advances and due alarms activate tasks,
    /// which then run. An alarm that cannot activate its task (a period overrun, which the
    /// paper's Table 1 would show as a missed period) reaches `ErrorHook`.
    pub fn tick<B: Board>(&mut self, board: &mut B) {
        self.isr(board, config::SYSTICK_ISR, |ecu, _| {
            let _ = ecu.os.increment_counter(config::SYSTEM_COUNTER);
        });
    }

    /// `CanIsr`: the CAN controller's pending events, in order, into CanIf and upwards.
    pub fn can_isr<B: Board>(
        &mut self,
        board: &mut B,
        events: impl IntoIterator<Item = CanInterrupt>,
    ) {
        self.isr(board, config::CAN_ISR, |ecu, board| {
            for event in events {
                ecu.can_event(board, event);
            }
        });
    }

    /// One controller event, inside `CanIsr`.
    fn can_event<B: Board>(&mut self, board: &mut B, event: CanInterrupt) {
        match event {
            CanInterrupt::TxConfirmation(pdu) => {
                if let Some(TxPduId(p)) = self.canif.tx_confirmation(board.can(), pdu) {
                    let _ = config::PDUR.canif_tx_confirmation(TxPduId(p));
                }
            }
            CanInterrupt::Received(hrh, frame) => match self.canif.rx_indication(hrh, &frame) {
                Ok(pdu) => {
                    config::PDUR.canif_rx_indication(&mut self.com, pdu, frame.bytes());
                }
                Err(
                    RxDropped::Offline
                    | RxDropped::UnknownId
                    | RxDropped::WrongHrh
                    | RxDropped::WrongDlc,
                ) => {
                    self.stats.rx_dropped = self.stats.rx_dropped.saturating_add(1);
                }
            },
            CanInterrupt::BusOff => {
                self.canif.controller_bus_off();
                let actions = self.cansm.controller_bus_off();
                self.apply(board, actions);
            }
        }
    }

    /// Runs tasks while the kernel has one to run that is not already on the stack.
    fn dispatch<B: Board>(&mut self, board: &mut B) {
        while let Some(task) = self.os.running() {
            if self.is_off() {
                return;
            }
            self.run_task(board, task);
        }
    }

    /// Runs the task the kernel just chose until the current one (`me`) is chosen again:
    /// the nested execution of a preempting task.
    fn run_preempting<B: Board>(&mut self, board: &mut B, me: TaskId) {
        while let Some(task) = self.os.running() {
            if task == me || self.is_off() {
                return;
            }
            self.run_task(board, task);
        }
    }

    fn run_task<B: Board>(&mut self, board: &mut B, task: TaskId) {
        board.task_started(task);
        match task {
            config::STARTUP_TASK => self.startup_task(board),
            config::LED_TASK => self.led_task(board),
            config::BSW_TASK => self.bsw_task(board),
            config::OBSTACLE_TASK => self.obstacle_task(),
            config::COM_TASK => self.com_task(board),
            config::SONAR_TASK => self.sonar_task(board),
            _ => {}
        }
        if self.is_off() {
            // The ECU shut down inside this task: the OS is gone, nothing terminates.
            return;
        }
        // An error here reaches ErrorHook, which counts it.
        let _ = self.os.terminate_task();
    }

    /// `OsStartupTask`: `EcuM_StartupTwo`, then the ModeManagerInit runnable asks BswM for
    /// the run mode.
    fn startup_task<B: Board>(&mut self, board: &mut B) {
        // Start-up two: Can, CanIf, CanSM, PduR, Com, ComM, BswM, IoHwAb. Each is already in
        // its initial state (constructed in `new`); the order is EcuM's to keep.
        if self.ecum.startup_two().is_err() {
            return;
        }
        self.bswm(board, BswMRequest::EcuRun);
    }

    /// EcuM's main function: in post-run, the outputs go to their safe state (LEDs off)
    /// and the ECU shuts down (`ShutdownOS(E_OK)`: no more ticks, tasks or interrupts).
    fn ecum_main_function<B: Board>(&mut self, board: &mut B) {
        if !self.ecum.main_function() {
            return;
        }
        for color in [LedColor::Red, LedColor::Yellow] {
            if iohwab::set_led(board, color, false).is_err() {
                self.stats.pin_faults = self.stats.pin_faults.saturating_add(1);
            }
        }
        let _ = self.os.shutdown_os(E_OK);
        board.irq().apply_mask(self.os.interrupt_mask());
    }

    /// BswM's main function for one request; a request whose rule does not hold now (e.g.
    /// communication on during post-run) is refused and counted.
    fn bswm<B: Board>(&mut self, board: &mut B, request: BswMRequest) {
        let done = bswm_execute(
            request,
            &mut self.ecum,
            &mut self.cansm,
            &mut self.canif,
            board.can(),
        );
        if done.is_err() {
            self.stats.mode_requests_refused = self.stats.mode_requests_refused.saturating_add(1);
        }
    }

    /// Carries out CanSM's decisions on CanIf and the controller.
    fn apply<B: Board>(&mut self, board: &mut B, actions: Actions) {
        cansm::apply(&mut self.cansm, &mut self.canif, board.can(), actions);
    }

    /// `OsLEDTask`: LEDActuator, prototypes RedLED and YellowLED.
    fn led_task<B: Board>(&mut self, board: &mut B) {
        let level = self.rte.led_request.read();
        let now_ms = board.now_ms();
        for (swc, color) in [(self.red, LedColor::Red), (self.yellow, LedColor::Yellow)] {
            if iohwab::set_led(board, color, swc.run(level, now_ms)).is_err() {
                self.stats.pin_faults = self.stats.pin_faults.saturating_add(1);
            }
        }
    }

    /// `OsBswServiceTask`: the BSW main functions.
    fn bsw_task<B: Board>(&mut self, board: &mut B) {
        while let Ok(request) = self.rte.mode_requests.receive() {
            self.bswm(board, request);
        }
        self.com.main_function_rx(|_timed_out| {});
        let (canif, stats) = (&mut self.canif, &mut self.stats);
        self.com.main_function_tx(|ipdu, sdu| {
            let sent = config::PDUR
                .com_transmit(canif, board.can(), ipdu, sdu)
                .is_ok();
            count_frame(stats, sent);
            sent
        });
        let actions = self.cansm.main_function();
        self.apply(board, actions);
        self.ecum_main_function(board);
    }

    /// `OsObstacleDetectionTask`: ObstacleDetection (and the thresholds from the PC).
    fn obstacle_task(&mut self) {
        let red = self.com.receive_signal(config::SIG_RED_BELOW);
        let yellow = self.com.receive_signal(config::SIG_YELLOW_BELOW);
        if let (Ok(SignalValue::Unsigned(r)), Ok(SignalValue::Unsigned(y))) = (red, yellow) {
            if (r, y) != self.applied_thresholds {
                self.applied_thresholds = (r, y);
                self.obstacle.configure(r as u32, y as u32);
            }
        }
        let level = self.obstacle.run(self.rte.sonar_to_obstacle.read());
        let _ = self.rte.led_request.write(level);
    }

    /// `OsSonarTask`: UltraSonic; its write to SonarRecv activates `OsComTask`.
    fn sonar_task<B: Board>(&mut self, board: &mut B) {
        let echo = iohwab::measure_echo(board, self.ultrasonic.sensor().echo_timeout_us());
        let measurement = self.ultrasonic.run(echo);
        self.last_measurement = measurement;
        let _ = self.rte.sonar_to_obstacle.write(measurement);
        if self.rte.sonar_to_can.write(measurement).0 {
            // An error here reaches ErrorHook, which counts it.
            let _ = self.os.activate_task(config::COM_TASK);
            self.run_preempting(board, config::SONAR_TASK);
        }
    }

    /// `OsComTask`: CanTranslate.
    fn com_task<B: Board>(&mut self, board: &mut B) {
        let Ok(measurement) = self.rte.sonar_to_can.take() else {
            return;
        };
        let (distance, level) = can_translate(measurement, self.rte.led_request.read());
        let (canif, stats) = (&mut self.canif, &mut self.stats);
        let mut transmit = |ipdu, sdu: &[u8]| {
            let sent = config::PDUR
                .com_transmit(canif, board.can(), ipdu, sdu)
                .is_ok();
            count_frame(stats, sent);
            sent
        };
        let _ = self.com.send_signal(
            config::SIG_WARNING_LEVEL,
            SignalValue::Unsigned(level),
            &mut transmit,
        );
        let _ = match distance {
            Some(mm) => self.com.send_signal(
                config::SIG_DISTANCE,
                SignalValue::Unsigned(mm),
                &mut transmit,
            ),
            None => self
                .com
                .invalidate_signal(config::SIG_DISTANCE, &mut transmit),
        };
    }
}

fn count_frame(stats: &mut EcuStats, sent: bool) {
    if sent {
        stats.frames_requested = stats.frames_requested.saturating_add(1);
    } else {
        stats.frames_refused = stats.frames_refused.saturating_add(1);
    }
}
