//! The ECU configuration (paper §3.2, ARCHITECTURE §1). The basic software's tables (the
//! OS's tasks, alarms, resources and ISRs; Com's I-PDUs and signals; PduR's routes;
//! CanIf's PDUs; the CAN controller's bit rate) are generated from the ECU's description,
//! `firmware/ecu.arxml`, into [`crate::generated`] (`cargo xtask generate`, the paper's
//! step 3); this module builds the kernel's, Com's, CanIf's and PduR's checked tables
//! from them and holds what the description does not carry yet (the FlexCAN message
//! buffers, CanSM's timing, WdgM's supervision, the sensor's timing). A rule broken here or
//! in the generated tables is a build error naming the table entry.
//!
//! The ECU's task set, as the description configures it:
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
use cw_core::can::Hrh;
use cw_core::cansm::{CanSmConfig, CanSmTimesMs};
use cw_core::os::{
    AlarmAction, AlarmAutostart, ConformanceClass, EventMask, OsConfig, OsDescription, Status,
    TaskId, TaskKind,
};
use cw_core::wdgm::AliveSupervision;

pub use crate::generated::{can, canif, com, os, pdur};

/// Task periods in ms (0: not periodic), indexed by task: the cycles of the alarms on the
/// system counter, which ticks every millisecond.
pub const PERIOD_MS: [u32; os::TASKS] = os::PERIOD_TICKS;

/// The longest time a UART ranging module takes between two frames, ms (A02YYUW in its
/// "processed" output mode: 100 to 300 ms).
pub const SENSOR_FRAME_PERIOD_MAX_MS: u32 = 300;

/// Samples of `OsSonarTask` without a good frame after which a UART ranging module is
/// silent (its samples invalid): the first sample past the module's longest period.
pub const SENSOR_SILENT_AFTER_SAMPLES: u8 = {
    let samples = SENSOR_FRAME_PERIOD_MAX_MS / PERIOD_MS[os::OS_SONAR_TASK.0 as usize] + 1;
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

/// The OS as described, or with the paper's task structure where [`EXTENDED_TASKS`]:
/// every task an autostarted cyclic alarm activates becomes an extended task started with
/// the OS, and its alarm sets [`EV_PERIOD`] on it instead (conformance class ECC1).
const fn structure(
    d: OsDescription<{ os::TASKS }, { os::COUNTERS }, { os::ALARMS }, { os::ISRS }>,
) -> OsDescription<{ os::TASKS }, { os::COUNTERS }, { os::ALARMS }, { os::ISRS }> {
    if !EXTENDED_TASKS {
        return d;
    }
    let mut d = d;
    let mut a = 0;
    while a < os::ALARMS {
        let cyclic =
            matches!(d.alarms[a].autostart, AlarmAutostart::Relative { cycle, .. } if cycle > 0);
        if let (AlarmAction::ActivateTask(task), true) = (d.alarms[a].action, cyclic) {
            d.alarms[a].action = AlarmAction::SetEvent(task, EV_PERIOD);
            let t = task.0 as usize;
            d.tasks[t].kind = TaskKind::Extended;
            d.tasks[t] = d.tasks[t].autostart();
        }
        a += 1;
    }
    d.class(ConformanceClass::Ecc1)
}

/// The OS's status: as the description sets it (`OsStatus`: extended, every check OSEK
/// defines, errors to `ErrorHook`), or standard with the `standard-status` feature. Extended status costs the ECU's paths
/// about 5 instructions per `GetResource` (the caller's priority against the ceiling) and
/// 88 bytes of the production image (docs/src/os.md, "Standard and extended status").
pub const STATUS: Status = if cfg!(feature = "standard-status") {
    Status::Standard
} else {
    os::DESCRIPTION.status
};

/// The OS: the generated description ([`os::DESCRIPTION`]), in its structure
/// (the paper's where [`EXTENDED_TASKS`]) and status ([`STATUS`]).
pub static OS: os::Config = match OsConfig::new(structure(os::DESCRIPTION).status(STATUS)) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

cw_core::static_tables!(
    /// [`OS`] as a build-time constant: the kernel's table lookups fold away.
    pub OsTables: os::Config = OS
);

/// The OS kernel type for [`OS`], with the ECU's hooks.
pub type Kernel = cw_core::os::Os<
    { os::TASKS },
    { os::RESOURCES },
    { os::COUNTERS },
    { os::ALARMS },
    { os::ISRS },
    { os::QUEUE },
    OsTables,
    crate::ecu::EcuHooks,
>;

/// The kernel for [`OS`], before `StartOS`.
///
/// # Errors
/// [`cw_core::os::ConfigError`] if the kernel's queue capacity does not match the
/// configuration (a build-configuration mistake, reported rather than panicking).
pub fn kernel() -> Result<Kernel, cw_core::os::ConfigError> {
    Kernel::new(OsTables)
}

/// The ECU's FlexCAN receive buffers (CanIf's hardware receive objects): the threshold
/// frame into HRH 0 through its exact filter, and, like a controller with an open filter,
/// every other frame too (standard and extended), so CanIf's own checks (unknown id, DLC)
/// see every frame.
pub const CAN_FILTERS: [RxFilter; 3] = [
    RxFilter::exact(canif::THRESHOLD_CONFIG_ID, Hrh(0)),
    RxFilter::any(Hrh(0), false),
    RxFilter::any(Hrh(0), true),
];

/// The ECU's FlexCAN transmit buffers: one for its one HTH.
pub const CAN_TX_BUFFERS: [u8; 1] = [1];

// The message buffers above are the board's, not the description's: they serve one HTH
// and one HRH, which every L-PDU of the description must use.
const _: () = {
    let mut k = 0;
    while k < canif::TX {
        assert!(
            CANIF_ON_BUFFERS.tx()[k].hth.0 == 0,
            "a CanIf TX PDU on an HTH the FlexCAN buffers do not serve"
        );
        k += 1;
    }
    let mut k = 0;
    while k < canif::RX {
        assert!(
            CANIF_ON_BUFFERS.rx()[k].hrh.0 == 0,
            "a CanIf RX PDU on an HRH the FlexCAN filters do not serve"
        );
        k += 1;
    }
};
const CANIF_ON_BUFFERS: canif::Config = canif::CONFIG;

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

/// CanIf: the generated tables ([`canif::CONFIG`]).
pub static CANIF: canif::Config = canif::CONFIG;

cw_core::static_tables!(
    /// [`CANIF`] as a build-time constant: CanIf's lookups fold away.
    pub CanIfTables: canif::Config = CANIF
);

/// The ECU's CanIf.
pub type EcuCanIf = cw_core::canif::CanIf<{ canif::TX }, { canif::RX }, CanIfTables>;

/// The Com main functions run in `OsBswServiceTask`, every 10 ms.
pub const BSW_PERIOD_MS: u32 = com::MAIN_PERIOD_MS;
const _: () = assert!(
    PERIOD_MS[os::OS_BSW_SERVICE_TASK.0 as usize] == BSW_PERIOD_MS,
    "Com's main functions run once per OsBswServiceTask job"
);

/// Com: the generated tables ([`com::CONFIG`]).
pub static COM: com::Config = com::CONFIG;

cw_core::static_tables!(
    /// [`COM`] as a build-time constant: signal layouts, transfer properties and timing
    /// fold into the code that uses them.
    pub ComTables: com::Config = COM
);

/// The ECU's Com.
pub type EcuCom = cw_core::com::ipdu::Com<
    { com::PDU_BYTES },
    { com::TX },
    { com::RX },
    { com::SIGNALS },
    ComTables,
>;

/// PduR: the generated routing paths ([`pdur::CONFIG`]).
pub static PDUR: pdur::Config = pdur::CONFIG;

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
pub const SUPERVISED: [TaskId; 3] = [
    os::OS_LED_TASK,
    os::OS_OBSTACLE_DETECTION_TASK,
    os::OS_SONAR_TASK,
];

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
    AliveSupervision::new("OsLEDTask", reference_cycle(os::OS_LED_TASK), 1),
    AliveSupervision::new(
        "OsObstacleDetectionTask",
        reference_cycle(os::OS_OBSTACLE_DETECTION_TASK),
        1,
    ),
    AliveSupervision::new("OsSonarTask", reference_cycle(os::OS_SONAR_TASK), 1),
];

/// Main functions an expired supervision still triggers the watchdog: none. The reset
/// follows the expiry by the watchdog's timeout.
pub const WDGM_EXPIRED_TOLERANCE: u16 = 0;

/// The watchdog's timeout, ms: WdgM triggers it every 10 ms (each `OsBswServiceTask`
/// job), so five periods without a trigger reset the ECU.
pub const WATCHDOG_TIMEOUT_MS: u16 = 50;
