//! The ECU configuration: every static table of the paper's collision-warning ECU in one
//! place (paper §3.2, ARCHITECTURE §1). A rule broken here is a build error naming the
//! table entry.
//!
//! | task | priority | activation | runnables |
//! |---|---|---|---|
//! | `OsStartupTask` | 7, non-preemptive | autostart, once | EcuM start-up two, ModeManagerInit |
//! | `OsLEDTask` | 6 | every 10 ms | LEDActuator (YellowLED, RedLED) |
//! | `OsBswServiceTask` | 5 | every 10 ms | Com, CanSM, EcuM/BswM main functions |
//! | `OsObstacleDetectionTask` | 4 | every 20 ms | ObstacleDetection |
//! | `OsComTask` | 3 | data received on SonarRecv | CanTranslate |
//! | `OsSonarTask` | 2 | every 40 ms | UltraSonic |
//!
//! `OsComTask` sits just above the sonar task: the sample the sonar task writes leaves as a
//! CAN frame as soon as the sonar task's write completes, and the periodic tasks, which
//! keep the LEDs in time, still outrank it.
//!
//! | ISR | category | priority | does |
//! |---|---|---|---|
//! | `SysTickIsr` | 2 | 2 | advances the 1 ms system counter; due alarms activate tasks |
//! | `CanIsr` | 2 | 1 | takes the CAN controller's events into CanIf (receptions, confirmations, bus-off) |
//! | `SensorRxIsr` | 1 | 3 | takes the UART ranging module's bytes off its UART into the driver's buffer (boards with that sensor; no OS service, no shared state but the buffer's atomics) |
//!
//! | resource | guards | taken by | ceiling |
//! |---|---|---|---|
//! | `RES_COM` | the Com stack: EcuM, BswM, CanSM, Com, PduR, CanIf and the CAN controller | `OsStartupTask`, `OsBswServiceTask`, `OsObstacleDetectionTask`, `OsComTask`, `CanIsr` | `CanIsr`'s level: a task holding it masks `CanIsr` |
//! | `RES_RTE` | the RTE's buffers (SonarData, LedRequest, mode requests) | `OsLEDTask`, `OsBswServiceTask`, `OsObstacleDetectionTask`, `OsComTask`, `OsSonarTask` | 6 (`OsLEDTask`) |
//! | `RES_LEDS` | the LED pins | `OsLEDTask`, `OsBswServiceTask` (EcuM's safe state) | 6 (`OsLEDTask`) |
//!
//! WdgM supervises `OsLEDTask`, `OsObstacleDetectionTask` and `OsSonarTask` (one alive
//! indication per job, exactly one per period); its main function runs in
//! `OsBswServiceTask` and triggers the watchdog (50 ms timeout) while every supervision
//! holds. A failed supervision puts the LEDs in their safe state (dark) and stops the
//! trigger: the watchdog resets the ECU.
//!
//! The kernel's own data is guarded by the kernel lock (every interrupt the OS serves
//! masked for the length of one service call; the category-1 `SensorRxIsr` above it is
//! not); `SysTickIsr` takes no resource. The ceilings are derived
//! by `OsConfig::new` from the `uses` declarations below, never written by hand.
//!
//! With the feature `extended-tasks` (the measuring image only, for the evaluation), the
//! four periodic tasks have the paper's structure instead: extended tasks, started with the
//! OS, each waiting for the event [`EV_PERIOD`] its alarm sets, in conformance class ECC1.
//!
//! The OS runs in conformance class BCC1 (basic tasks, one activation each, one task per
//! priority: the paper's task set needs no more), with extended status (every misuse is
//! refused and reported to `ErrorHook`, which the ECU counts; the call-level check is one
//! test of a cached mask, so the fast paths cost the same as in standard status: see the
//! book's instruction counts, `docs/src/performance.md`), and AUTOSAR's behaviour where OSEK and AUTOSAR differ (the
//! paper's stack is an AUTOSAR one).

use cw_bsp::chip::flexcan::driver::INIT_POLLS;
use cw_bsp::chip::flexcan::{ClockSource, FlexcanConfig, RxFilter};
use cw_core::can::{CanId, Hrh, Hth};
use cw_core::canif::{CanIfConfig, RxPduConfig, TxPduConfig, TxPduId};
use cw_core::cansm::{CanSmConfig, CanSmTimesMs};
use cw_core::com::ipdu::{
    ComConfig, RxIpduConfig, RxIpduId, SignalConfig, SignalDirection, SignalId, TransferProperty,
    TxIpduConfig, TxIpduId, TxMode,
};
use cw_core::com::signal::{ByteOrder, Signedness};
use cw_core::os::{
    AlarmAction, AlarmConfig, ConformanceClass, CounterConfig, CounterId, Dialect, EventMask,
    HookSet, IsrConfig, IsrId, OsConfig, OsDescription, ResourceId, Status, TaskConfig, TaskId,
};
use cw_core::pdur::{PduRConfig, RxRoute};
use cw_core::wdgm::AliveSupervision;

/// `OsStartupTask`.
pub const STARTUP_TASK: TaskId = TaskId(0);
/// `OsLEDTask`.
pub const LED_TASK: TaskId = TaskId(1);
/// `OsBswServiceTask`.
pub const BSW_TASK: TaskId = TaskId(2);
/// `OsObstacleDetectionTask`.
pub const OBSTACLE_TASK: TaskId = TaskId(3);
/// `OsComTask`.
pub const COM_TASK: TaskId = TaskId(4);
/// `OsSonarTask`.
pub const SONAR_TASK: TaskId = TaskId(5);
/// `RES_COM`: the Com stack and the CAN controller.
pub const RES_COM: ResourceId = ResourceId(0);
/// `RES_RTE`: the RTE's buffers.
pub const RES_RTE: ResourceId = ResourceId(1);
/// `RES_LEDS`: the LED pins.
pub const RES_LEDS: ResourceId = ResourceId(2);
const USES_COM: u32 = 1 << RES_COM.0;
const USES_RTE: u32 = 1 << RES_RTE.0;
const USES_LEDS: u32 = 1 << RES_LEDS.0;

/// The 1 ms system counter.
pub const SYSTEM_COUNTER: CounterId = CounterId(0);
/// The system timer's interrupt (SysTick on a Cortex-M): drives [`SYSTEM_COUNTER`].
pub const SYSTICK_ISR: IsrId = IsrId(0);
/// The CAN controller's interrupt.
pub const CAN_ISR: IsrId = IsrId(1);
/// The UART ranging module's receive interrupt (category 1: above every category-2 ISR,
/// so that `SuspendOSInterrupts` leaves it running and no byte at 9600 baud waits for an
/// OS job).
pub const SENSOR_RX_ISR: IsrId = IsrId(2);

/// Task periods in ms (0: not periodic), indexed by task.
pub const PERIOD_MS: [u32; 6] = [0, 10, 10, 20, 0, 40];

/// The longest time a UART ranging module takes between two frames, ms (A02YYUW in its
/// "processed" output mode: 100 to 300 ms).
pub const SENSOR_FRAME_PERIOD_MAX_MS: u32 = 300;

/// Samples of `OsSonarTask` without a good frame after which a UART ranging module is
/// silent (its samples invalid): the first sample past the module's longest period.
pub const SENSOR_SILENT_AFTER_SAMPLES: u8 = {
    let samples = SENSOR_FRAME_PERIOD_MAX_MS / PERIOD_MS[SONAR_TASK.0 as usize] + 1;
    assert!(samples <= u8::MAX as u32);
    samples as u8
};

/// Whether the periodic tasks have the paper's structure (feature `extended-tasks`):
/// extended tasks that wait for [`EV_PERIOD`], which their alarms set, instead of basic
/// tasks their alarms activate.
pub const EXTENDED_TASKS: bool = cfg!(feature = "extended-tasks");

/// The event a periodic task's alarm sets where the tasks are extended
/// ([`EXTENDED_TASKS`]).
pub const EV_PERIOD: EventMask = 1;

/// A periodic task: basic, or extended and started with the OS ([`EXTENDED_TASKS`]).
const fn periodic(name: &'static str, priority: u8) -> TaskConfig {
    if EXTENDED_TASKS {
        TaskConfig::extended(name, priority).autostart()
    } else {
        TaskConfig::basic(name, priority)
    }
}

/// A periodic task's alarm: it activates the task, or sets [`EV_PERIOD`] on it where the
/// tasks are extended.
const fn cyclic(name: &'static str, task: TaskId, period_ms: u32) -> AlarmConfig {
    let action = if EXTENDED_TASKS {
        AlarmAction::SetEvent(task, EV_PERIOD)
    } else {
        AlarmAction::ActivateTask(task)
    };
    AlarmConfig::new(name, SYSTEM_COUNTER, action).relative(period_ms, period_ms)
}

/// The OS's status: extended (every check OSEK defines, errors to `ErrorHook`), or
/// standard with the `standard-status` feature. Extended status costs the ECU's paths
/// about 5 instructions per `GetResource` (the caller's priority against the ceiling) and
/// 88 bytes of the production image (docs/src/os.md, "Standard and extended status").
pub const STATUS: Status = if cfg!(feature = "standard-status") {
    Status::Standard
} else {
    Status::Extended
};

/// The OS: six tasks, three resources, four cyclic alarms on a 1 ms counter, two
/// category-2 ISRs and one of category 1.
pub static OS: OsConfig<6, 3, 1, 4, 3> = match OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("OsStartupTask", 7)
                .non_preemptive()
                .autostart()
                .uses(USES_COM),
            periodic("OsLEDTask", 6).uses(USES_RTE | USES_LEDS),
            periodic("OsBswServiceTask", 5).uses(USES_COM | USES_RTE | USES_LEDS),
            periodic("OsObstacleDetectionTask", 4).uses(USES_COM | USES_RTE),
            TaskConfig::basic("OsComTask", 3).uses(USES_COM | USES_RTE),
            periodic("OsSonarTask", 2).uses(USES_RTE),
        ],
        [CounterConfig {
            max_allowed_value: 0xFFFF,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        [
            cyclic("LedAlarm", LED_TASK, 10),
            cyclic("BswAlarm", BSW_TASK, 10),
            cyclic("ObstacleAlarm", OBSTACLE_TASK, 20),
            cyclic("SonarAlarm", SONAR_TASK, 40),
        ],
        [
            IsrConfig::cat2("SysTickIsr", 2),
            IsrConfig::cat2("CanIsr", 1).uses(USES_COM),
            IsrConfig::cat1("SensorRxIsr", 3),
        ],
    )
    .class(if EXTENDED_TASKS {
        ConformanceClass::Ecc1
    } else {
        ConformanceClass::Bcc1
    })
    .status(STATUS)
    .dialect(Dialect::Autosar)
    .hooks(HookSet {
        error: true,
        shutdown: true,
        ..HookSet::NONE
    }),
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

cw_core::static_tables!(
    /// [`OS`] as a build-time constant: the kernel's table lookups fold away.
    pub OsTables: OsConfig<6, 3, 1, 4, 3> = OS
);

/// The OS kernel type for [`OS`], with the ECU's hooks.
pub type Kernel = cw_core::os::Os<6, 3, 1, 4, 3, 6, OsTables, crate::ecu::EcuHooks>;

/// The kernel for [`OS`], before `StartOS`.
///
/// # Errors
/// [`cw_core::os::ConfigError`] if the kernel's queue capacity does not match the
/// configuration (a build-configuration mistake, reported rather than panicking).
pub fn kernel() -> Result<Kernel, cw_core::os::ConfigError> {
    Kernel::new(OsTables)
}

const fn std_id(raw: u16) -> CanId {
    match CanId::standard(raw) {
        Some(id) => id,
        None => panic!("CAN id above 0x7FF"),
    }
}

/// CAN id of the distance frame (DBC `DistanceFrame`).
pub const DISTANCE_FRAME_ID: CanId = std_id(0x100);
/// CAN id of the threshold configuration frame (DBC `ThresholdConfig`).
pub const THRESHOLD_FRAME_ID: CanId = std_id(0x200);

/// The ECU's FlexCAN receive buffers (CanIf's hardware receive objects): the threshold
/// frame into HRH 0 through its exact filter, and, like a controller with an open filter,
/// every other frame too (standard and extended), so CanIf's own checks (unknown id, DLC)
/// see every frame.
pub const CAN_FILTERS: [RxFilter; 3] = [
    RxFilter::exact(THRESHOLD_FRAME_ID, Hrh(0)),
    RxFilter::any(Hrh(0), false),
    RxFilter::any(Hrh(0), true),
];

/// The ECU's FlexCAN transmit buffers: one for its one HTH.
pub const CAN_TX_BUFFERS: [u8; 1] = [1];

/// The ECU's FlexCAN controller on the protocol clock `clock_hz` from `clock_source`: 32
/// message buffers, the receive filters [`CAN_FILTERS`] and transmit buffers
/// [`CAN_TX_BUFFERS`], and the driver's bound on each acknowledge it waits for.
pub const fn flexcan(clock_source: ClockSource, clock_hz: u32) -> FlexcanConfig<'static> {
    FlexcanConfig {
        clock_source,
        clock_hz,
        mailboxes: 32,
        rx: &CAN_FILTERS,
        tx: &CAN_TX_BUFFERS,
        init_polls: INIT_POLLS,
    }
}

/// CanIf: one TX L-PDU (the distance frame), one RX L-PDU (thresholds from the PC).
pub static CANIF: CanIfConfig<1, 1> = match CanIfConfig::new(
    [TxPduConfig {
        name: "DistanceFrame",
        id: DISTANCE_FRAME_ID,
        dlc: 8,
        hth: Hth(0),
    }],
    [RxPduConfig {
        name: "ThresholdConfig",
        id: THRESHOLD_FRAME_ID,
        dlc: 4,
        hrh: Hrh(0),
    }],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

cw_core::static_tables!(
    /// [`CANIF`] as a build-time constant: CanIf's lookups fold away.
    pub CanIfTables: CanIfConfig<1, 1> = CANIF
);

/// The ECU's CanIf.
pub type EcuCanIf = cw_core::canif::CanIf<1, 1, CanIfTables>;

/// Com TX I-PDU of the distance frame.
pub const DISTANCE_IPDU: TxIpduId = TxIpduId(0);
/// Com RX I-PDU of the threshold frame.
pub const THRESHOLD_IPDU: RxIpduId = RxIpduId(0);
/// Com signal: the distance, mm (DBC `Distance`, 0|32@1+).
pub const SIG_DISTANCE: SignalId = SignalId(0);
/// Com signal: the warning level (DBC `WarningLevel`, 32|8@1+).
pub const SIG_WARNING_LEVEL: SignalId = SignalId(1);
/// Com signal: red threshold, mm (DBC `RedBelow`).
pub const SIG_RED_BELOW: SignalId = SignalId(2);
/// Com signal: yellow threshold, mm (DBC `YellowBelow`).
pub const SIG_YELLOW_BELOW: SignalId = SignalId(3);
/// The distance's invalidation value: all 32 bits set.
pub const DISTANCE_INVALID: u64 = 0xFFFF_FFFF;

/// The Com main functions run in `OsBswServiceTask`, every 10 ms.
pub const BSW_PERIOD_MS: u32 = 10;

/// The CAN controller (`CanControllerBaudrateConfig`): 500 kbit/s, the paper's bus, sampled
/// at 87.5 % (CiA 301's recommendation).
pub const CAN_CONTROLLER: cw_core::can::ControllerConfig = cw_core::can::ControllerConfig {
    bitrate: 500_000,
    sample_permille: 875,
};

/// Com: the distance frame is sent directly, once per sonar sample (the distance
/// triggers, the level travels with it); the thresholds arrive from the PC.
pub static COM: ComConfig<8, 1, 1, 4> = match ComConfig::new(
    BSW_PERIOD_MS,
    [TxIpduConfig {
        name: "DistanceFrame",
        len: 8,
        mode: TxMode::Direct {
            repetitions: 0,
            repetition_period_ms: 0,
        },
        mdt_ms: 0,
    }],
    [RxIpduConfig {
        name: "ThresholdConfig",
        len: 4,
        deadline_ms: 0,
    }],
    [
        SignalConfig {
            name: "Distance",
            direction: SignalDirection::Tx(DISTANCE_IPDU, TransferProperty::Triggered),
            layout: cw_core::signal_layout!(8; 0, 32, ByteOrder::Intel, Signedness::Unsigned),
            init: DISTANCE_INVALID,
            invalid: Some(DISTANCE_INVALID),
            update_bit: None,
        },
        SignalConfig {
            name: "WarningLevel",
            direction: SignalDirection::Tx(DISTANCE_IPDU, TransferProperty::Pending),
            layout: cw_core::signal_layout!(8; 32, 8, ByteOrder::Intel, Signedness::Unsigned),
            init: 3,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "RedBelow",
            direction: SignalDirection::Rx(THRESHOLD_IPDU),
            layout: cw_core::signal_layout!(8; 0, 16, ByteOrder::Intel, Signedness::Unsigned),
            init: 1000,
            invalid: None,
            update_bit: None,
        },
        SignalConfig {
            name: "YellowBelow",
            direction: SignalDirection::Rx(THRESHOLD_IPDU),
            layout: cw_core::signal_layout!(8; 16, 16, ByteOrder::Intel, Signedness::Unsigned),
            init: 2000,
            invalid: None,
            update_bit: None,
        },
    ],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

cw_core::static_tables!(
    /// [`COM`] as a build-time constant: signal layouts, transfer properties and timing
    /// fold into the code that uses them.
    pub ComTables: ComConfig<8, 1, 1, 4> = COM
);

/// The ECU's Com.
pub type EcuCom = cw_core::com::ipdu::Com<8, 1, 1, 4, ComTables>;

/// PduR: the distance I-PDU onto CanIf PDU 0; CanIf RX PDU 0 onto the threshold I-PDU.
pub static PDUR: PduRConfig<1, 1, 1, 1> =
    match PduRConfig::new([TxPduId(0)], [RxRoute::One(THRESHOLD_IPDU)]) {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    };

/// CanSM: two fast recoveries after 10 ms, then 1 s; 100 ms on the bus ensures recovery.
/// A controller mode change not indicated within 10 ms is asked for again, three times.
pub const CANSM: CanSmConfig = match CanSmConfig::from_ms(
    BSW_PERIOD_MS,
    CanSmTimesMs {
        fast_retries: 2,
        fast: 10,
        slow: 1000,
        tx_ensured: 100,
        mode_request: 10,
        mode_request_repeats: 3,
    },
) {
    Ok(cfg) => cfg,
    Err(_) => panic!("CanSM timing is not a whole number of BSW periods"),
};

/// The tasks WdgM supervises, in the order of [`ALIVE`]: the periodic tasks but
/// `OsBswServiceTask`, which runs WdgM's main function (if it stalls, the watchdog is no
/// longer triggered at all).
pub const SUPERVISED: [TaskId; 3] = [LED_TASK, OBSTACLE_TASK, SONAR_TASK];

/// Main functions of WdgM (one per `OsBswServiceTask` job) in one period of `task`.
const fn reference_cycle(task: TaskId) -> u16 {
    let cycle = PERIOD_MS[task.0 as usize] / BSW_PERIOD_MS;
    assert!(
        cycle >= 1 && cycle * BSW_PERIOD_MS == PERIOD_MS[task.0 as usize],
        "a supervised task's period is a whole number of WdgM main functions"
    );
    cycle as u16
}

/// WdgM's alive supervision: each supervised task reports one alive indication per job,
/// and exactly one is expected per period (no margin, no failed cycle tolerated). A job
/// that does not come, or comes twice, is a failure.
pub static ALIVE: [AliveSupervision; 3] = [
    AliveSupervision::new("OsLEDTask", reference_cycle(LED_TASK), 1),
    AliveSupervision::new("OsObstacleDetectionTask", reference_cycle(OBSTACLE_TASK), 1),
    AliveSupervision::new("OsSonarTask", reference_cycle(SONAR_TASK), 1),
];

/// Main functions an expired supervision still triggers the watchdog: none. The reset
/// follows the expiry by the watchdog's timeout.
pub const WDGM_EXPIRED_TOLERANCE: u16 = 0;

/// The watchdog's timeout, ms: WdgM triggers it every 10 ms (each `OsBswServiceTask`
/// job), so five periods without a trigger reset the ECU.
pub const WATCHDOG_TIMEOUT_MS: u16 = 50;
