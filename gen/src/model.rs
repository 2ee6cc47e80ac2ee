//! The ECU's description as the generator sees it: the basic software's configuration
//! values (paper §3.1, step 2), one plain Rust value per ECUC container, each with the
//! ARXML path it was read from so that every error and every generated line can name it.
//!
//! Items refer to each other by short name (a task's resources, an alarm's task); the
//! reader resolves ARXML references to these names and [`crate::validate`] checks that
//! each one names an item that exists.

/// Where an item came from: its ARXML path (`/CwEcu/EcucValues/Os/OsLEDTask`).
pub type Path = String;

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Ecu {
    /// `Os`.
    pub os: Os,
    /// `EcuC`'s global PDUs, which Com, PduR and CanIf refer to.
    pub pdus: Vec<Pdu>,
    /// `Com`.
    pub com: Com,
    /// `PduR`'s routing paths.
    pub routes: Vec<Route>,
    /// `CanIf`.
    pub canif: CanIf,
    /// `Can`: the controller.
    pub can: CanController,
}

/// OSEK/AUTOSAR status (`OsStatus`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Status {
    /// `STANDARD`.
    Standard,
    /// `EXTENDED`.
    #[default]
    Extended,
}

/// The OS's hooks (`OsHooks`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Hooks {
    /// `OsErrorHook`.
    pub error: bool,
    /// `OsShutdownHook`.
    pub shutdown: bool,
    /// `OsStartupHook`.
    pub startup: bool,
    /// `OsPreTaskHook`.
    pub pre_task: bool,
    /// `OsPostTaskHook`.
    pub post_task: bool,
}

/// `Os`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Os {
    /// The module's path.
    pub path: Path,
    /// `OsOS/OsStatus`.
    pub status: Status,
    /// `OsOS/OsHooks`.
    pub hooks: Hooks,
    /// `OsTask`, in ARXML order: a task's id is its index.
    pub tasks: Vec<Task>,
    /// `OsEvent`.
    pub events: Vec<Event>,
    /// `OsResource`: a resource's id is its index.
    pub resources: Vec<Named>,
    /// `OsCounter`.
    pub counters: Vec<Counter>,
    /// `OsAlarm`.
    pub alarms: Vec<Alarm>,
    /// `OsIsr`: an ISR's id is its index.
    pub isrs: Vec<Isr>,
}

/// An item with only a name.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Named {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
}

/// `OsTask`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Task {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `OsTaskPriority` (higher runs first).
    pub priority: u64,
    /// `OsTaskSchedule`: `FULL` (true) or `NON`.
    pub preemptive: bool,
    /// `OsTaskActivation`.
    pub activations: u64,
    /// An `OsTaskAutostart` container is present.
    pub autostart: bool,
    /// `OsTaskResourceRef`s, by name.
    pub resources: Vec<String>,
    /// `OsTaskEventRef`s, by name: a task with events is extended.
    pub events: Vec<String>,
    /// `OsTaskTimingProtection`.
    pub timing: Option<Timing>,
}

/// `OsTaskTimingProtection` or `OsIsrTimingProtection`: what the task set's response-time
/// analysis takes from the description ([`crate::timing`]). The kernel does not enforce
/// it (it has no timing protection); the evaluation holds the image's measured jobs to it.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Timing {
    /// The container's ARXML path.
    pub path: Path,
    /// `OsTaskExecutionBudget` / `OsIsrExecutionBudget`: the longest one job or one run
    /// of the ISR takes alone, µs.
    pub budget_us: Option<u64>,
    /// `OsTaskTimeFrame` / `OsIsrTimeFrame`: the shortest time between two releases, µs.
    pub time_frame_us: Option<u64>,
}

/// `OsEvent`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Event {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `OsEventMask`.
    pub mask: u64,
}

/// `OsCounter`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Counter {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `OsCounterMaxAllowedValue`.
    pub max_allowed_value: u64,
    /// `OsCounterTicksPerBase`.
    pub ticks_per_base: u64,
    /// `OsCounterMinCycle`.
    pub min_cycle: u64,
}

/// What an alarm does when it expires (`OsAlarmAction`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AlarmAction {
    /// `OsAlarmActivateTask`: the task, by name.
    ActivateTask(String),
    /// `OsAlarmSetEvent`: the task and the event, by name.
    SetEvent(String, String),
}

/// `OsAlarm`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Alarm {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `OsAlarmCounterRef`, by name.
    pub counter: String,
    /// `OsAlarmAction`.
    pub action: AlarmAction,
    /// `OsAlarmAutostart`: `OsAlarmAlarmTime` and `OsAlarmCycleTime`, relative.
    pub autostart: Option<(u64, u64)>,
}

/// `OsIsr`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Isr {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `OsIsrCategory`: 1 or 2.
    pub category: u64,
    /// The interrupt's priority (a vendor parameter: AUTOSAR leaves it to the port).
    pub priority: u64,
    /// `OsIsrResourceRef`s, by name.
    pub resources: Vec<String>,
    /// `OsIsrTimingProtection`.
    pub timing: Option<Timing>,
}

/// `EcucPduCollection/Pdu`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Pdu {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `PduLength`, bytes.
    pub length: u64,
}

/// `Com`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Com {
    /// The module's path.
    pub path: Path,
    /// The period of Com's main functions, ms (`ComTimeBase/ComTxTimeBase`, which
    /// `ComRxTimeBase` must equal: both run in one task).
    pub main_period_ms: u64,
    /// `ComIPdu`.
    pub ipdus: Vec<IPdu>,
    /// `ComSignal`.
    pub signals: Vec<Signal>,
}

/// `ComIPduDirection` and what goes with it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Direction {
    /// `SEND`, with `ComTxIPdu`.
    Send(TxIPdu),
    /// `RECEIVE`, with its deadline (`ComRxDataTimeoutAction` per signal group aside: the
    /// I-PDU's first signal's `ComTimeout`, ms; 0 none).
    Receive {
        /// Deadline, ms (0: not monitored).
        deadline_ms: u64,
    },
}

/// `ComTxModeMode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TxModeMode {
    /// `NONE`.
    None,
    /// `PERIODIC`.
    Periodic,
    /// `DIRECT`.
    Direct,
    /// `MIXED`.
    Mixed,
}

/// `ComTxIPdu` with its `ComTxModeTrue/ComTxMode`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TxIPdu {
    /// `ComTxModeMode`.
    pub mode: TxModeMode,
    /// `ComTxModeTimePeriod`, ms.
    pub period_ms: u64,
    /// `ComTxModeTimeOffset`, ms.
    pub offset_ms: u64,
    /// `ComTxModeNumberOfRepetitions`.
    pub repetitions: u64,
    /// `ComTxModeRepetitionPeriod`, ms.
    pub repetition_period_ms: u64,
    /// `ComMinimumDelayTime`, ms.
    pub mdt_ms: u64,
}

/// `ComIPdu`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IPdu {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `ComPduIdRef`: the global PDU, by name.
    pub pdu: String,
    /// Send or receive.
    pub direction: Direction,
    /// `ComIPduSignalRef`s, by name.
    pub signals: Vec<String>,
}

/// `ComSignalEndianness`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endianness {
    /// `LITTLE_ENDIAN` (Intel).
    Little,
    /// `BIG_ENDIAN` (Motorola).
    Big,
}

/// `ComTransferProperty`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transfer {
    /// `PENDING`.
    Pending,
    /// `TRIGGERED`.
    Triggered,
    /// `TRIGGERED_ON_CHANGE`.
    TriggeredOnChange,
    /// `TRIGGERED_WITHOUT_REPETITION`.
    TriggeredWithoutRepetition,
    /// `TRIGGERED_ON_CHANGE_WITHOUT_REPETITION`.
    TriggeredOnChangeWithoutRepetition,
}

/// `ComSignal`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Signal {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `ComBitPosition`.
    pub bit_position: u64,
    /// `ComBitSize`.
    pub bit_size: u64,
    /// `ComSignalEndianness`.
    pub endianness: Endianness,
    /// `ComSignalType`: `SINT*` (true) or `UINT*`/`BOOLEAN`.
    pub signed: bool,
    /// `ComSignalType`'s width in bits: 1 (`BOOLEAN`), 8, 16, 32 or 64.
    pub type_bits: u64,
    /// `ComSignalInitValue`.
    pub init: u64,
    /// `ComSignalDataInvalidValue`.
    pub invalid: Option<u64>,
    /// `ComTransferProperty` (sent signals; `PENDING` where it is not given).
    pub transfer: Option<Transfer>,
    /// `ComUpdateBitPosition`.
    pub update_bit: Option<u64>,
}

/// `PduRRoutingPath`: one source PDU to one destination or more.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Route {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `PduRSrcPdu/PduRSrcPduRef`, by name.
    pub src: String,
    /// Every `PduRDestPdu/PduRDestPduRef`, by name.
    pub dests: Vec<String>,
}

/// `CanIf`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CanIf {
    /// The module's path.
    pub path: Path,
    /// `CanIfTxPduCfg`.
    pub tx: Vec<LPdu>,
    /// `CanIfRxPduCfg`.
    pub rx: Vec<LPdu>,
}

/// A CanIf L-PDU (`CanIfTxPduCfg` or `CanIfRxPduCfg`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LPdu {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `CanIfTxPduCanId` / `CanIfRxPduCanId`.
    pub can_id: u64,
    /// `..CanIdType` is `EXTENDED_CAN` (29 bits).
    pub extended: bool,
    /// `CanIfRxPduDataLength` (`CanIfRxPduDlc` before R4.3), or for a sent PDU the
    /// vendor parameter `CanIfTxPduDlc`; `None`: the global PDU's length.
    pub dlc: Option<u64>,
    /// `CanIfTxPduRef` / `CanIfRxPduRef`: the global PDU, by name.
    pub pdu: String,
    /// The hardware object: `CanIfTxPduBufferRef`'s HTH or `CanIfRxPduHrhIdRef`'s HRH, by
    /// its index among the CanIf's HTHs or HRHs.
    pub hoh: u64,
}

/// `Can/CanConfigSet/CanController` with its baud rate configuration.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CanController {
    /// ARXML path.
    pub path: Path,
    /// Short name.
    pub name: String,
    /// `CanControllerBaudRate`, kbit/s.
    pub baud_kbps: u64,
    /// `CanControllerPropSeg`, time quanta.
    pub prop_seg: u64,
    /// `CanControllerSeg1`, time quanta.
    pub seg1: u64,
    /// `CanControllerSeg2`, time quanta.
    pub seg2: u64,
}

impl CanController {
    /// The sample point in per mille of the bit: the synchronisation quantum, the
    /// propagation and phase 1 segments over the whole bit, rounded down (`None` where the
    /// segments overflow).
    pub fn sample_permille(&self) -> Option<u64> {
        let before = self.prop_seg.checked_add(self.seg1)?.checked_add(1)?;
        before
            .checked_mul(1000)?
            .checked_div(before.checked_add(self.seg2)?)
    }
}
