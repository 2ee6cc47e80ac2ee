//! The ECU: the paper's tasks and ISRs, the BSW (EcuM/BswM, ComM/CanSM, Com, PduR, CanIf)
//! and the SWCs connected through the RTE, on any board and OS port.
//!
//! Execution model: the kernel decides who runs; the port (`cw_bsp::port::Port`) carries
//! it out. On a microcontroller the port switches stacks (PendSV) and interrupts arrive
//! at any instruction; in the host simulation a preempting task runs as a nested call
//! (`Ecu::dispatch`) and interrupts come between jobs. The task bodies and ISRs below
//! are the same for both.
//!
//! Because tasks and ISRs preempt each other, the ECU's state is split by who uses it:
//!
//! | state | guarded by | used by |
//! |---|---|---|
//! | kernel | kernel lock (one service call) | everyone |
//! | [`ComStack`]: EcuM, BswM, CanSM, Com, PduR, CanIf, CAN controller | OSEK resource `RES_COM` (ceiling: `CanIsr`) | startup, BSW, obstacle and Com tasks, `CanIsr` |
//! | [`Rte`] buffers | `RES_RTE` (ceiling: `OsLEDTask`) | LED, BSW, obstacle, Com and sonar tasks |
//! | [`Leds`] | `RES_LEDS` (ceiling: `OsLEDTask`) | LED task, BSW task (safe state at shutdown) |
//! | UltraSonic, the sensor's pins | `OsSonarTask` alone | |
//! | ObstacleDetection | `OsObstacleDetectionTask` alone | |
//!
//! Hooks ([`EcuHooks`]): `ErrorHook` counts every error a kernel service returned (none is
//! expected); `ShutdownHook` records the status `ShutdownOS` was given. EcuM's shutdown
//! calls `ShutdownOS`: from then on no task, ISR or alarm runs.

use cw_bsp::port::{Port, Resource, TaskLocal, TickPath};
use cw_core::canif::{CanIf, RxDropped, TxPduId};
use cw_core::cansm::{self, CanSm};
use cw_core::com::ipdu::Com;
use cw_core::com::signal::SignalValue;
use cw_core::ecum::{bswm_execute, BswMRequest, EcuM};
use cw_core::os::{Hooks, IsrId, OsError, ServiceId, StatusType, TaskId, E_OK, OSDEFAULTAPPMODE};
use cw_core::sonar::SonarConfig;
use cw_core::warning::{Measurement, WarningLevel};

use crate::board::{
    Board, BoardParts, CanEvents, CanInterrupt, DistanceSensor, Leds, ModeInputs, PortDriver,
    TaskFaults,
};
use crate::config::{self, Kernel};
use crate::iohwab;
use crate::rte::{
    tasks, BswmPorts, LedActuatorPorts, LedActuatorRunnables, ModeManagerPorts,
    ModeManagerRunnables, Released, Rte, UltraSonicPorts, UltraSonicRunnables,
};
use crate::swc::{CanTranslate, LedActuator, LedColor, ModeManager, ObstacleDetection, UltraSonic};
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use cw_core::wdgm::{Failure, Status, WdgDriver, WdgM};

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
    /// ISR entries or returns the kernel refused (the port took an interrupt the mask
    /// held, or returned from one not active): these calls have no `ErrorHook`.
    pub port_errors: u32,
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

/// The spans of the ECU's own paths that a port can measure (`Port::span`): the
/// instruction counts of the Cortex-M4 figures in the book (`docs/src/performance.md`).
pub mod span {
    /// From the sonar task's `ActivateTask(OsComTask)` call to `OsComTask`'s first line
    /// (the kernel service, the port's task switch, the job's entry).
    pub const ACTIVATE_TO_FIRST_LINE: usize = 0;
    /// `OsComTask`'s send: `GetResource(RES_COM)`, Com_SendSignal of both signals, PduR,
    /// CanIf, the controller's write (the SLCAN line into the mailbox and the UART's first
    /// characters), `ReleaseResource`.
    pub const COM_SEND: usize = 1;
    /// `CanIsr`: from its first line through the kernel's ISR entry, the events into CanIf
    /// (a TX confirmation, or a reception up to the signal in Com), to the ISR's return
    /// to the kernel.
    pub const CAN_ISR: usize = 2;
    /// `SysTickIsr` on a tick the kernel's fast path takes: no alarm expires.
    pub const TICK_NOTHING_DUE: usize = 3;
    /// `SysTickIsr` on a tick the kernel runs whole: alarms expire and activate tasks
    /// (or, rarely, a tick the fast path declines for another reason: nested in an ISR).
    pub const TICK_ALARMS_DUE: usize = 4;
    /// Span 5 is the board's (the CAN driver's write, inside [`COM_SEND`]).
    pub const DRIVER_WRITE: usize = 5;
    /// Inside `CanIsr`, a received frame from CanIf's checks through PduR to the signals
    /// stored in Com (the RX indication path; `CAN_ISR` spans the whole ISR).
    pub const RX_TO_COM: usize = 6;
    /// The port's calibration of its own measuring.
    pub const CALIBRATION: usize = 7;
    /// The FlexCAN driver's `Can_Write` into a message buffer (ERR005829's two writes
    /// included), against FlexCAN's register map in RAM (the measuring images only).
    pub const FLEXCAN_WRITE: usize = 8;
    /// The FlexCAN driver's interrupt work for a transmitted frame: the flag found, the
    /// buffer's code read, the flag cleared, the confirmation handed out.
    pub const FLEXCAN_TX_CONFIRMATION: usize = 9;
    /// The FlexCAN driver's interrupt work for a received frame: the flag found, the
    /// buffer read under its lock, the flag cleared, the timer read, the frame handed out.
    pub const FLEXCAN_RX: usize = 10;
    /// The FlexCAN spans' names.
    pub const FLEXCAN_NAMES: [(usize, &str); 3] = [
        (
            FLEXCAN_WRITE,
            "FlexCAN driver: Can_Write into a message buffer",
        ),
        (
            FLEXCAN_TX_CONFIRMATION,
            "FlexCAN driver: a transmit flag to its confirmation",
        ),
        (FLEXCAN_RX, "FlexCAN driver: a receive flag to its frame"),
    ];
    /// `GetResource` and `ReleaseResource` of `RES_RTE` in `OsLEDTask`, with the generated
    /// task body between them (both LED runnables: a load of the LED request and a compare
    /// each): the lock pair as the application takes it (`Resource::lock`).
    pub const LOCK_PAIR: usize = 11;
    /// The calibration's second span, inside or across [`CALIBRATION`] (the cost of a
    /// span's marks as a span around them sees it).
    pub const CALIBRATION_INNER: usize = 12;
    /// Each probe of the communication stack's layers (`crate::stack_probe`), one after
    /// the other before the OS starts (the measuring images only).
    pub const STACK_PROBE: usize = 13;
    /// The spans named apart from [`NAMES`] (numbered after the board's).
    pub const MORE_NAMES: [(usize, &str); 1] = [(
        LOCK_PAIR,
        "a lock pair (RES_RTE in OsLEDTask, both LED runnables inside)",
    )];
    /// The spans that are ISRs (bit per span): the trace takes their time off the spans
    /// and jobs they interrupt.
    pub const ISR_SPANS: u32 = 1 << CAN_ISR | 1 << TICK_NOTHING_DUE | 1 << TICK_ALARMS_DUE;
    /// The names, by number.
    pub const NAMES: [&str; 7] = [
        "ActivateTask(OsComTask) to its first line",
        "OsComTask send (Com, PduR, CanIf, controller, RES_COM)",
        "CanIsr (entry to return)",
        "SysTickIsr, nothing due",
        "SysTickIsr, alarms due",
        "the CAN driver's write (inside the send)",
        "a received frame, CanIf to the signal in Com (inside CanIsr)",
    ];
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
    /// Controller mode changes reported after the request (a stop asked for during a
    /// frame on the wire completes at the frame's end).
    pub mode_indications: u32,
}

/// The Com stack and the CAN controller it drives (`RES_COM`).
pub struct ComStack<C> {
    /// EcuM (BswM's rules act on it).
    pub ecum: EcuM,
    /// CanIf.
    pub canif: config::EcuCanIf,
    /// CanSM.
    pub cansm: CanSm,
    /// Com.
    pub com: config::EcuCom,
    /// The CAN controller.
    pub can: C,
    frames: FrameCounts,
    rx_dropped: u32,
    mode_requests_refused: u32,
    mode_indications: u32,
    /// `Can_Init` refused the controller's configuration: CanSM's starts will be refused
    /// too, and it retries as after a bus-off.
    pub can_init_refused: bool,
}

impl<C: cw_core::can::CanDriver + CanEvents> ComStack<C> {
    fn new(can: C) -> Self {
        Self {
            ecum: EcuM::new(),
            canif: CanIf::new(config::CanIfTables),
            cansm: CanSm::new(config::CANSM),
            com: Com::new(config::ComTables),
            can,
            frames: FrameCounts::default(),
            rx_dropped: 0,
            mode_requests_refused: 0,
            mode_indications: 0,
            can_init_refused: false,
        }
    }

    /// BswM's main function for one request; a request whose rule does not hold now (e.g.
    /// communication on during post-run) is refused and counted.
    fn bswm(&mut self, request: BswMRequest) {
        let done = bswm_execute(
            request,
            &mut self.ecum,
            &mut self.cansm,
            &mut self.canif,
            &mut self.can,
        );
        if done.is_err() {
            self.mode_requests_refused = self.mode_requests_refused.saturating_add(1);
        }
    }

    /// The BSW main functions of `OsBswServiceTask`; whether EcuM asks to shut down.
    fn main_functions(&mut self) -> bool {
        self.com.main_function_rx(|_timed_out| {});
        let (canif, can, frames) = (&mut self.canif, &mut self.can, &mut self.frames);
        self.com
            .main_function_tx(|ipdu, sdu| frames.transmit(canif, can, ipdu, sdu));
        let actions = self.cansm.main_function();
        cansm::apply(&mut self.cansm, &mut self.canif, &mut self.can, actions);
        self.ecum.main_function()
    }

    /// CanTranslate's signals through Com, PduR and CanIf to the controller.
    #[inline(never)]
    fn send(&mut self, distance: Option<u64>, level: u64) {
        let (canif, can, frames) = (&mut self.canif, &mut self.can, &mut self.frames);
        let mut transmit = |ipdu, sdu: &[u8]| frames.transmit(canif, can, ipdu, sdu);
        let _ = self.com.send_signal(
            config::com::WARNING_LEVEL,
            SignalValue::Unsigned(level),
            &mut transmit,
        );
        let _ = match distance {
            Some(mm) => self.com.send_signal(
                config::com::DISTANCE,
                SignalValue::Unsigned(mm),
                &mut transmit,
            ),
            None => self
                .com
                .invalidate_signal(config::com::DISTANCE, &mut transmit),
        };
    }

    /// One controller event, inside `CanIsr`.
    fn can_event(&mut self, event: CanInterrupt) {
        match event {
            CanInterrupt::TxConfirmation(pdu) => {
                if let Some(TxPduId(p)) = self.canif.tx_confirmation(&mut self.can, pdu) {
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
                    self.rx_dropped = self.rx_dropped.saturating_add(1);
                }
            },
            CanInterrupt::BusOff => cansm::bus_off(&mut self.cansm, &mut self.canif, &mut self.can),
            CanInterrupt::ModeIndication(mode) => {
                self.mode_indications = self.mode_indications.saturating_add(1);
                cansm::mode_indication(&mut self.cansm, &mut self.canif, &mut self.can, mode);
            }
        }
    }
}

/// Distance frames handed to CanIf and refused by it.
#[derive(Default)]
struct FrameCounts {
    requested: u32,
    refused: u32,
}

impl FrameCounts {
    /// Com's transmit request through PduR to CanIf and the controller, counted.
    fn transmit<C: cw_core::can::CanDriver>(
        &mut self,
        canif: &mut config::EcuCanIf,
        can: &mut C,
        ipdu: cw_core::com::ipdu::TxIpduId,
        sdu: &[u8],
    ) -> bool {
        let sent = config::PDUR.com_transmit(canif, can, ipdu, sdu).is_ok();
        if sent {
            self.requested = self.requested.saturating_add(1);
        } else {
            self.refused = self.refused.saturating_add(1);
        }
        sent
    }
}

/// The LED pins (`RES_LEDS`).
pub struct LedOutputs<B: Board> {
    pins: Leds<B>,
    pin_faults: u32,
}

impl<B: Board> LedOutputs<B> {
    fn set(&mut self, color: LedColor, lit: bool) {
        if iohwab::set_led(&mut self.pins, color, lit).is_err() {
            self.pin_faults = self.pin_faults.saturating_add(1);
        }
    }
}

/// `OsSonarTask`'s own state.
struct SonarPart<B: Board> {
    io: B::Sensor,
    swc: UltraSonic,
    /// The sensor's sample of this job, taken before the RTE is locked (a long read).
    sample: Measurement,
    last: Measurement,
}

/// UltraSonic as its task runs it: the job's sample to the measurement published.
impl<B: Board> UltraSonicRunnables for SonarPart<B> {
    fn ultra_sonic_runnable(&mut self, ports: &mut impl UltraSonicPorts) {
        self.last = self.swc.run(self.sample);
        ports.write_sonar_data(self.last);
    }
}

/// One LEDActuator prototype in one `OsLEDTask` job: its level to whether its LED is lit
/// now (dark in the safe state), for the job to write to the pin after the RTE.
struct LedJob {
    swc: LedActuator,
    now_ms: u64,
    safe: bool,
    lit: bool,
}

impl LedActuatorRunnables for LedJob {
    fn led_actuator_runnable(&mut self, ports: &mut impl LedActuatorPorts) {
        let level = ports.read_led_request();
        // WdgM's supervision expired: dark until the watchdog's reset.
        self.lit = !self.safe && self.swc.run(level, self.now_ms);
    }
}

/// `OsObstacleDetectionTask`'s own state.
/// `OsBswServiceTask`'s own state: the mode inputs and ModeManager.
struct ModePart<B: Board> {
    inputs: ModeInputs<B>,
    swc: ModeManager,
    /// Requests the RTE's queue had no room for.
    refused: u32,
}

/// ModeManager as its task runs it: the inputs' edges (read through IoHwAb) as mode
/// requests to BswM.
impl<B: Board> ModeManagerRunnables for ModePart<B> {
    fn mode_manager_runnable(&mut self, ports: &mut impl ModeManagerPorts) {
        let ignition = iohwab::read_input(&mut self.inputs.ignition);
        let com_enable = iohwab::read_input(&mut self.inputs.com_enable);
        for request in self.swc.run(ignition, com_enable).into_iter().flatten() {
            if ports.send_mode_request(request).is_err() {
                self.refused = self.refused.saturating_add(1);
            }
        }
    }
}

/// WdgM and the watchdog it triggers (`OsBswServiceTask`'s, and `Ecu::init`'s before the
/// OS runs).
struct WdgPart<B: Board> {
    wdgm: WdgM<3>,
    driver: B::Watchdog,
}

struct ObstaclePart {
    swc: ObstacleDetection,
    /// The last threshold pair received from the PC and applied (raw), to apply each once.
    applied: (u64, u64),
}

/// The whole ECU on a port `P` and a board `B`.
pub struct Ecu<P, B: Board> {
    port: P,
    com: Resource<
        ComStack<B::Can>,
        { config::os::RES_COM.0 },
        { config::OS.isr_shared(config::os::RES_COM) },
    >,
    rte: Resource<Rte, { config::os::RES_RTE.0 }, { config::OS.isr_shared(config::os::RES_RTE) }>,
    leds: Resource<
        LedOutputs<B>,
        { config::os::RES_LEDS.0 },
        { config::OS.isr_shared(config::os::RES_LEDS) },
    >,
    sonar: TaskLocal<SonarPart<B>>,
    obstacle: TaskLocal<ObstaclePart>,
    modes: TaskLocal<ModePart<B>>,
    wdg: TaskLocal<WdgPart<B>>,
    /// Alive indications of the supervised tasks since WdgM's last main function, each
    /// incremented by its task alone and taken (swapped to 0) by the main function.
    alive: [AtomicU32; 3],
    /// WdgM's supervision expired: the LEDs stay in their safe state until the reset.
    safe_state: AtomicBool,
    /// The faults the board injects into the tasks.
    faults: B::Faults,
    /// The Port driver, until `Port_Init`.
    port_driver: Option<B::Port>,
}

impl<P: Port<Kernel = Kernel>, B: Board> Ecu<P, B> {
    /// The ECU before power-on, on the port `port` (which holds the kernel) and the board's
    /// parts.
    pub fn new(port: P, parts: BoardParts<B>, sensor: SonarConfig) -> Self {
        Self {
            port,
            com: Resource::new(ComStack::new(parts.can)),
            rte: Resource::new(Rte::new()),
            leds: Resource::new(LedOutputs {
                pins: parts.leds,
                pin_faults: 0,
            }),
            sonar: TaskLocal::new(SonarPart {
                io: parts.sonar,
                swc: UltraSonic::new(sensor),
                sample: Measurement::Invalid,
                last: Measurement::Invalid,
            }),
            modes: TaskLocal::new(ModePart {
                inputs: parts.modes,
                swc: ModeManager::new(),
                refused: 0,
            }),
            obstacle: TaskLocal::new(ObstaclePart {
                swc: ObstacleDetection::new(),
                applied: (1000, 2000),
            }),
            wdg: TaskLocal::new(WdgPart {
                wdgm: WdgM::new(&config::ALIVE, config::WDGM_EXPIRED_TOLERANCE),
                driver: parts.watchdog,
            }),
            alive: [AtomicU32::new(0), AtomicU32::new(0), AtomicU32::new(0)],
            safe_state: AtomicBool::new(false),
            faults: parts.faults,
            port_driver: Some(parts.port),
        }
    }

    /// The OS port (with the kernel).
    pub const fn port(&self) -> &P {
        &self.port
    }

    /// The Com stack, the CAN controller included (for inspection while the ECU does not
    /// run).
    pub fn com_stack(&mut self) -> &mut ComStack<B::Can> {
        self.com.get_mut()
    }

    /// The CanIf state (drop counters, modes).
    pub fn canif(&mut self) -> &config::EcuCanIf {
        &self.com.get_mut().canif
    }

    /// The CanSM state (bus-off counters).
    pub fn cansm(&mut self) -> &CanSm {
        &self.com.get_mut().cansm
    }

    /// The EcuM state.
    pub fn ecum(&mut self) -> &EcuM {
        &self.com.get_mut().ecum
    }

    /// Runs `f` with the sensor's driver, unless `OsSonarTask` has a job under way (then
    /// `None`): for a board's report of what its sensor counted.
    pub fn with_sensor<R>(&self, f: impl FnOnce(&mut B::Sensor) -> R) -> Option<R> {
        self.sonar.with(|part| f(&mut part.io))
    }

    /// The newest measurement UltraSonic published.
    pub fn measurement(&mut self) -> Measurement {
        self.sonar.get_mut().last
    }

    /// The level ObstacleDetection decided last (as the LEDs read it).
    pub fn level(&mut self) -> WarningLevel {
        self.rte.get_mut().peek_obstacle_detection_led_request()
    }

    /// WdgM's global status and the failure that expired it, unless `OsBswServiceTask` has
    /// a job under way (then `None`).
    pub fn supervision(&self) -> Option<(Status, Option<Failure>)> {
        self.wdg
            .with(|part| (part.wdgm.global_status(), part.wdgm.failure()))
    }

    /// The warning thresholds in use.
    pub fn thresholds(&mut self) -> cw_core::warning::Thresholds {
        self.obstacle.get_mut().swc.thresholds()
    }

    /// The hooks' record (errors, shutdown status).
    pub fn hooks(&self) -> EcuHooks {
        self.port.inspect(|os| *os.hooks())
    }

    /// Run counters.
    pub fn stats(&mut self) -> EcuStats {
        let hooks = self.hooks();
        let pin_faults = self.leds.get_mut().pin_faults;
        let com = self.com.get_mut();
        EcuStats {
            frames_requested: com.frames.requested,
            frames_refused: com.frames.refused,
            rx_dropped: com.rx_dropped,
            os_errors: hooks.errors.saturating_add(hooks.port_errors),
            pin_faults,
            mode_requests_refused: com.mode_requests_refused,
            mode_indications: com.mode_indications,
        }
    }

    /// Mode requests of ModeManager that found the RTE's queue full (not stored).
    pub fn mode_requests_dropped(&self) -> u32 {
        self.modes.with(|part| part.refused).unwrap_or(0)
    }

    /// Whether the ECU has shut down (`ShutdownOS` ran: it no longer runs).
    pub fn is_off(&self) -> bool {
        self.port.inspect(|os| os.is_shut_down())
    }

    /// Power-on, start-up one: `EcuM_Init`, then `Port_Init` (every pin to its direction,
    /// outputs low). The OS starts next ([`Ecu::start_os`]).
    pub fn init(&mut self) {
        if self.com.get_mut().ecum.init().is_err() {
            return;
        }
        if let Some(mut port) = self.port_driver.take() {
            port.port_init();
        }
        // Can_Init: the controller at the configured bitrate, stopped until CanSM starts it.
        let stack = self.com.get_mut();
        stack.can_init_refused =
            cw_core::can::CanDriver::init(&mut stack.can, &config::can::CONTROLLER).is_err();
        // Wdg_Init: the watchdog runs from here on; WdgM's first main function (the first
        // `OsBswServiceTask` job, 10 ms after StartOS) triggers it well within its timeout.
        self.wdg
            .get_mut()
            .driver
            .set_trigger_condition(config::WATCHDOG_TIMEOUT_MS);
    }

    /// `StartOS`, which activates `OsStartupTask`.
    pub fn start_os(&self) {
        self.port.kernel(|os| {
            if os.start_os(OSDEFAULTAPPMODE).is_err() {
                os.hooks_mut().port_errors = os.hooks_mut().port_errors.saturating_add(1);
            }
        });
        self.dispatch();
    }

    /// A kernel call from a task or ISR body: the port carries out the kernel's choice
    /// (host port: here, by running the preempting tasks).
    fn os<R>(&self, f: impl FnOnce(&mut Kernel) -> R) -> R {
        let result = self.port.kernel(f);
        self.dispatch();
        result
    }

    /// Where the caller runs preempting tasks itself (host port): runs every task the
    /// kernel chooses above the job on top of the stack, until that job is chosen again.
    fn dispatch(&self) {
        if !P::NESTED {
            return;
        }
        loop {
            let next = self.port.inspect(|os| {
                if os.is_shut_down() {
                    None
                } else {
                    os.running()
                }
            });
            match next {
                Some(task) if Some(task) != self.port.current_job() => self.run_job(task),
                _ => return,
            }
        }
    }

    /// One job of `task`: its body, then `TerminateTask`. The Cortex-M port's task entry
    /// and the host port's dispatch call it. Where the periodic tasks are extended
    /// ([`config::EXTENDED_TASKS`], the paper's structure), each of them never ends: it
    /// waits for its alarm's event, clears it, runs one job, and waits again.
    pub fn run_job(&self, task: TaskId) {
        if config::EXTENDED_TASKS && config::PERIOD_MS.get(usize::from(task.0)) > Some(&0) {
            // A refused wait (the OS shut down, or a call from the wrong level) ends the loop,
            // and the task's TerminateTask below reports it.
            while self
                .port
                .kernel(|os| os.wait_event(config::EV_PERIOD))
                .is_ok()
            {
                let _ = self.port.kernel(|os| os.clear_event(config::EV_PERIOD));
                if !self.job(task) {
                    return;
                }
            }
        } else if !self.job(task) {
            return;
        }
        // After ShutdownOS inside the body the OS is gone and nothing terminates; an
        // error here reaches ErrorHook, which counts it.
        let _ = self.port.end_job(|os| {
            if os.is_shut_down() {
                Err(OsError::State)
            } else {
                os.terminate_task()
            }
        });
    }

    /// One job's body between its marks, and its alive indication; `false` where the board
    /// made it hang (it never ends: no `TerminateTask` follows).
    fn job(&self, task: TaskId) -> bool {
        if task == config::os::OS_COM_TASK {
            self.port.span(span::ACTIVATE_TO_FIRST_LINE, false);
        }
        self.port.job_started(task);
        if <B::Faults as TaskFaults>::INJECTS && self.faults.hangs(task, || self.port.now_ms()) {
            // A fault the board injects: the job hangs here, never ending (the port keeps
            // it running at its priority); it reports no alive indication.
            self.port.hang();
            return false;
        }
        match task {
            config::os::OS_STARTUP_TASK => self.startup_task(),
            config::os::OS_LED_TASK => self.led_task(),
            config::os::OS_BSW_SERVICE_TASK => self.bsw_task(),
            config::os::OS_OBSTACLE_DETECTION_TASK => self.obstacle_task(),
            config::os::OS_COM_TASK => self.com_task(),
            config::os::OS_SONAR_TASK => self.sonar_task(),
            _ => {}
        }
        // WdgM's alive indication: the supervised task's job has run.
        if let Some(alive) = config::SUPERVISED
            .iter()
            .position(|&t| t == task)
            .and_then(|i| self.alive.get(i))
        {
            alive.fetch_add(1, Ordering::Relaxed);
        }
        // The job's last line (where the port switches stacks, the TerminateTask after it
        // never returns).
        self.port.job_finished(task);
        true
    }

    /// Runs an ISR as the port does: the kernel is told of its entry, `body` runs, the
    /// kernel is told of its return (a rescheduling point).
    fn isr(&self, isr: IsrId, span: usize, body: impl FnOnce(&Self)) {
        self.port.span(span, true);
        self.isr_spanned(isr, span, body);
    }

    /// [`Ecu::isr`] with its span already started; ends it.
    fn isr_spanned(&self, isr: IsrId, span: usize, body: impl FnOnce(&Self)) {
        if self.port.kernel(|os| Self::isr_entry(os, isr)).is_err() {
            // The body does not run, so nothing clears the source: the port quiets the
            // line (a level-triggered one would be taken again at once).
            self.port.isr_refused(isr);
            self.port.span(span, false);
            return;
        }
        self.port.isr_entered(isr);
        body(self);
        let left = self.port.kernel(Self::isr_return);
        self.port.span(span, false);
        if left.is_ok() {
            self.dispatch();
        }
    }

    /// The kernel is told of ISR `isr`'s entry (refused once the OS is shut down); a
    /// refusal is counted as the port's error.
    fn isr_entry(os: &mut Kernel, isr: IsrId) -> Result<(), OsError> {
        if os.is_shut_down() {
            return Err(OsError::State);
        }
        let entered = os.enter_isr(isr);
        Self::count_port_error(os, entered)
    }

    /// The kernel is told the innermost ISR returns, as [`Ecu::isr_entry`] its entry.
    fn isr_return(os: &mut Kernel) -> Result<(), OsError> {
        if os.is_shut_down() {
            return Err(OsError::State);
        }
        let left = os.exit_isr();
        Self::count_port_error(os, left)
    }

    fn count_port_error(os: &mut Kernel, result: Result<(), OsError>) -> Result<(), OsError> {
        if result.is_err() {
            os.hooks_mut().port_errors = os.hooks_mut().port_errors.saturating_add(1);
        }
        result
    }

    /// `SysTickIsr`, every 1 ms: the system counter advances and due alarms activate tasks.
    /// An alarm that cannot activate its task (a period overrun, which the paper's Table 1
    /// would show as a missed period) reaches `ErrorHook`. One kernel call: the kernel's
    /// fast path where nothing is due, its fast path where the due alarms only activate
    /// tasks that may be activated, else the ISR's entry, `IncrementCounter` and its
    /// return under the same kernel lock (`Port::tick_isr`).
    pub fn tick(&self) {
        // One span from the ISR's first line, filed by the path the kernel took (so that
        // telling the two apart costs the tick nothing).
        self.port.span(span::TICK_NOTHING_DUE, true);
        let whole =
            self.port
                .tick_isr(config::os::SYS_TICK_ISR, config::os::SYSTEM_COUNTER, |os| {
                    // (The outer result: the entry; the inner one: the return.)
                    Self::isr_entry(os, config::os::SYS_TICK_ISR)?;
                    let _ = os.increment_counter(config::os::SYSTEM_COUNTER);
                    Ok::<_, OsError>(Self::isr_return(os))
                });
        // (The trace's mark of the ISR's entry comes after the span: it is the measuring's,
        // not the tick's.)
        match whole {
            TickPath::NothingDue => {
                self.port.span(span::TICK_NOTHING_DUE, false);
                self.port.isr_entered(config::os::SYS_TICK_ISR);
            }
            TickPath::Whole(Err(_)) => {
                self.port
                    .span_end_as(span::TICK_NOTHING_DUE, span::TICK_ALARMS_DUE);
                self.port.isr_refused(config::os::SYS_TICK_ISR);
            }
            TickPath::AlarmsDue => {
                self.port
                    .span_end_as(span::TICK_NOTHING_DUE, span::TICK_ALARMS_DUE);
                self.port.isr_entered(config::os::SYS_TICK_ISR);
                self.dispatch();
            }
            TickPath::Whole(Ok(left)) => {
                self.port
                    .span_end_as(span::TICK_NOTHING_DUE, span::TICK_ALARMS_DUE);
                self.port.isr_entered(config::os::SYS_TICK_ISR);
                if left.is_ok() {
                    self.dispatch();
                }
            }
        }
    }

    /// `ticks` OS ticks at once where the kernel's tick fast path would take each one by
    /// one (nothing due at any of them): `true` when taken, `false` (nothing changed) when
    /// the caller must run them one by one. For a simulation in virtual time.
    pub fn quiet_ticks(&self, ticks: u64) -> bool {
        self.port.kernel(|os| {
            os.try_ticks(config::os::SYS_TICK_ISR, config::os::SYSTEM_COUNTER, ticks)
                .is_some()
        })
    }

    /// The OS ticks until the next alarm of the system counter is due (`u64::MAX`: none
    /// armed).
    pub fn ticks_to_expiry(&self) -> u64 {
        self.port
            .inspect(|os| os.ticks_to_expiry(config::os::SYSTEM_COUNTER).unwrap_or(0))
    }

    /// `CanIsr`: the CAN controller's pending events, in order, into CanIf and upwards.
    /// Out of line, as an ISR's body is (`ISR(CanIsr)`).
    #[inline(never)]
    pub fn can_isr(&self) {
        self.isr(config::os::CAN_ISR, span::CAN_ISR, |ecu| {
            let _ = ecu.com.lock(&ecu.port, |stack| {
                while let Some(event) = stack.can.take_event() {
                    let rx = matches!(event, CanInterrupt::Received(..));
                    if rx {
                        ecu.port.span(span::RX_TO_COM, true);
                    }
                    stack.can_event(event);
                    if rx {
                        ecu.port.span(span::RX_TO_COM, false);
                    }
                }
            });
        });
    }

    /// `OsStartupTask`: `EcuM_StartupTwo`, then the ModeManagerInit runnable asks BswM for
    /// the run mode.
    fn startup_task(&self) {
        // Start-up two: Can, CanIf, CanSM, PduR, Com, ComM, BswM, IoHwAb. Each is already in
        // its initial state (constructed in `new`); the order is EcuM's to keep.
        let _ = self.com.lock(&self.port, |stack| {
            if stack.ecum.startup_two().is_ok() {
                stack.bswm(BswMRequest::EcuRun);
            }
        });
    }

    /// `OsLEDTask`: LEDActuator, prototypes RedLED and YellowLED (the generated body runs
    /// both, each with its context), then their pins.
    fn led_task(&self) {
        let now_ms = self.port.now_ms();
        let safe = self.safe_state.load(Ordering::Relaxed);
        // The prototypes hold no state: each job makes its own.
        let mut red = LedJob {
            swc: LedActuator::new(LedColor::Red),
            now_ms,
            safe,
            lit: false,
        };
        let mut yellow = LedJob {
            swc: LedActuator::new(LedColor::Yellow),
            now_ms,
            safe,
            lit: false,
        };
        self.port.span(span::LOCK_PAIR, true);
        let ran = self.rte.lock(&self.port, |rte| {
            tasks::os_led_task(rte, &mut red, &mut yellow)
        });
        self.port.span(span::LOCK_PAIR, false);
        let Ok(released) = ran else {
            return;
        };
        let _ = self.leds.lock(&self.port, |leds| {
            leds.set(LedColor::Red, red.lit);
            leds.set(LedColor::Yellow, yellow.lit);
        });
        self.activate(released);
    }

    /// WdgM's main function, in `OsBswServiceTask`: the supervised tasks' alive
    /// indications since the last one judged; the watchdog triggered while every
    /// supervision holds; on the expiry, the LEDs' safe state (they stay dark until the
    /// watchdog resets the ECU, which no longer being triggered brings).
    fn wdgm_main_function(&self) {
        let indications = self.alive.each_ref().map(|a| a.swap(0, Ordering::Relaxed));
        let verdict = self.wdg.with(|part| {
            let verdict = part.wdgm.main_function(&indications);
            if verdict.trigger {
                part.driver
                    .set_trigger_condition(config::WATCHDOG_TIMEOUT_MS);
            }
            verdict
        });
        if verdict.is_some_and(|v| v.expired_now) {
            self.safe_state.store(true, Ordering::Relaxed);
            let _ = self.leds.lock(&self.port, |leds| {
                leds.set(LedColor::Red, false);
                leds.set(LedColor::Yellow, false);
            });
        }
    }

    /// `OsBswServiceTask`: the BSW main functions; in EcuM's post-run the outputs go to
    /// their safe state (LEDs off) and the ECU shuts down (`ShutdownOS(E_OK)`: no more
    /// ticks, tasks or interrupts).
    fn bsw_task(&self) {
        // ModeManager (the generated body), then BswM's side: the requests it takes in its
        // main function below.
        let mut requests = [None; 4];
        let released = self.rte.lock(&self.port, |rte| {
            let released = self
                .modes
                .with(|part| tasks::os_bsw_service_task(rte, part));
            for slot in &mut requests {
                *slot = rte.bswm().receive_mode_request().ok();
            }
            released
        });
        if let Ok(Some(released)) = released {
            self.activate(released);
        }
        let shut_down = self.com.lock(&self.port, |stack| {
            for request in requests.into_iter().flatten() {
                stack.bswm(request);
            }
            stack.main_functions()
        });
        self.wdgm_main_function();
        if shut_down != Ok(true) {
            return;
        }
        let _ = self.leds.lock(&self.port, |leds| {
            leds.set(LedColor::Red, false);
            leds.set(LedColor::Yellow, false);
        });
        // No task triggers the watchdog after ShutdownOS: EcuM switches it off first.
        let _ = self.wdg.with(|part| part.driver.off());
        let _ = self.os(|os| os.shutdown_os(E_OK));
    }

    /// `OsObstacleDetectionTask`: ObstacleDetection (and the thresholds from the PC).
    fn obstacle_task(&self) {
        let thresholds = self.com.lock(&self.port, |stack| {
            (
                stack.com.receive_signal(config::com::RED_BELOW),
                stack.com.receive_signal(config::com::YELLOW_BELOW),
            )
        });
        let released = self.obstacle.with(|part| {
            if let Ok((Ok(SignalValue::Unsigned(r)), Ok(SignalValue::Unsigned(y)))) = thresholds {
                if (r, y) != part.applied {
                    part.applied = (r, y);
                    part.swc.configure(r as u32, y as u32);
                }
            }
            self.rte.lock(&self.port, |rte| {
                tasks::os_obstacle_detection_task(rte, &mut part.swc)
            })
        });
        if let Some(Ok(released)) = released {
            self.activate(released);
        }
    }

    /// `OsSonarTask`: UltraSonic; its write to SonarRecv activates `OsComTask`, which
    /// preempts it at once.
    fn sonar_task(&self) {
        let released = self.sonar.with(|part| {
            part.sample = part.io.sample(part.swc.sensor());
            self.rte
                .lock(&self.port, |rte| tasks::os_sonar_task(rte, part))
        });
        if let Some(Ok(released)) = released {
            self.activate(released);
        }
    }

    /// The tasks whose data-received events a job's writes fired (the generated RTE's
    /// mapping), activated once the job has left the RTE; the first of them preempts at
    /// once. An error here reaches ErrorHook, which counts it.
    #[inline(always)]
    fn activate(&self, released: Released) {
        // A body that can fire no event returns this constant: no code for it.
        if released != Released::NONE {
            self.activate_tasks(released);
        }
    }

    /// [`Self::activate`]'s work: the tasks activated (the generated code tests each
    /// task's bit and activates its constant task), the first preempting at once.
    fn activate_tasks(&self, released: Released) {
        // The span ends at the first activated task's first line.
        self.port.span(span::ACTIVATE_TO_FIRST_LINE, true);
        released.activate(|task| {
            let _ = self.port.activate_task(task);
        });
        self.dispatch();
    }

    /// `OsComTask`: CanTranslate, then its signals to Com. Out of line, as a task body is
    /// (`TASK(OsComTask)`): the job's instructions are measured on this symbol on the host
    /// (callgrind), as the image's trace measures them between the job's marks.
    #[inline(never)]
    fn com_task(&self) {
        let mut swc = CanTranslate::default();
        let released = self
            .rte
            .lock(&self.port, |rte| tasks::os_com_task(rte, &mut swc));
        if let Some((distance, level)) = swc.signals {
            self.port.span(span::COM_SEND, true);
            let _ = self
                .com
                .lock(&self.port, |stack| stack.send(distance, level));
            self.port.span(span::COM_SEND, false);
        }
        if let Ok(released) = released {
            self.activate(released);
        }
    }
}
