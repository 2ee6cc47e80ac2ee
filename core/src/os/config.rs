//! Static OS configuration (the OIL/ARXML part of an OSEK system) and its validation.
//!
//! A configuration is described once, in a `const`, by an [`OsDescription`] (the OS
//! object's attributes and the tables of tasks, counters, alarms and ISRs) and validated
//! by [`OsConfig::new`]; every rule below is checked there, so an impossible configuration
//! fails the build with an error naming the offending entries. Derived values (resource
//! ceilings at task and interrupt level, the `RES_SCHEDULER` ceiling, the activation-queue
//! size, the call-level masks) are computed from the tables, never written by hand.
//!
//! # Priorities
//! Tasks have priorities `0 ..= MAX_PRIORITY` (63), ISRs `0 ..= MAX_ISR_PRIORITY` (63),
//! higher runs first. Every ISR lies above every task: the kernel keeps one processor
//! priority in which task priority `p` is `p` and ISR priority `p` is
//! [`ISR_LEVEL_BASE`]` + p`, so a resource shared with an ISR has a ceiling at interrupt
//! level and a task holding it masks that ISR.

use super::callevel::{denied_table, Context};
use super::{CounterId, EventMask, TaskId, TickType};

/// Highest task priority (priorities are `0 ..= MAX_PRIORITY`, higher runs first).
pub const MAX_PRIORITY: u8 = 63;
/// Highest ISR priority (ISR priorities are `0 ..= MAX_ISR_PRIORITY`, all above tasks).
pub const MAX_ISR_PRIORITY: u8 = 63;
/// The processor priority of ISR priority 0: one above the highest task priority.
pub const ISR_LEVEL_BASE: u8 = MAX_PRIORITY + 1;
/// Most tasks one configuration may hold.
pub const MAX_TASKS: usize = 64;
/// Most user resources one configuration may hold (besides `RES_SCHEDULER`).
pub const MAX_RESOURCES: usize = 32;
/// Resources below this one may be locked outside the kernel: the kernel's answer
/// ([`lock_free_bit`]) has one bit for each kind of such a lock, in its low 24 bits (a
/// port keeps the lock itself in the same word, in the 8 bits above).
pub const LOCK_FREE_RESOURCES: u8 = 12;

/// The bit of the kernel's answer to which resources the running task may lock outside
/// the kernel ([`Os::lock_free_resources`](crate::os::Os::lock_free_resources)) that names
/// resource `res`: bit `res` where no ISR shares it (its ceiling at a task's level: the
/// lock masks no interrupt), bit `12 + res` where one does (`masks_isrs`: the lock masks
/// the ISRs up to the ceiling). So a port that tests a constant resource's first bit
/// knows, without a table, that the lock masks nothing. 0 from [`LOCK_FREE_RESOURCES`] on:
/// the answer never names those.
pub const fn lock_free_bit(res: super::ResourceId, masks_isrs: bool) -> u32 {
    if res.0 >= LOCK_FREE_RESOURCES {
        return 0;
    }
    let shift = if masks_isrs { LOCK_FREE_RESOURCES } else { 0 };
    1 << (res.0 + shift)
}

/// Most alarm callbacks (callback ids are `0 .. MAX_CALLBACKS`).
pub const MAX_CALLBACKS: u8 = 32;
/// Most alarms or counters one configuration may hold.
pub const MAX_ALARMS: usize = 64;
/// Most ISRs one configuration may hold.
pub const MAX_ISRS: usize = 64;
/// Most application modes (`AppModeType` values `0 .. MAX_APP_MODES`).
pub const MAX_APP_MODES: u8 = 32;

/// Basic tasks run to completion; extended tasks may wait for events.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TaskKind {
    /// No `WaitEvent`; may be activated several times (BCC2/ECC2).
    Basic,
    /// May `WaitEvent`; one activation at a time.
    Extended,
}

/// Whether higher-priority tasks may preempt this one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preemption {
    /// Preempted as soon as a higher-priority task is ready.
    Full,
    /// Runs until it terminates, waits or calls `Schedule` (only ISRs interrupt it).
    Non,
}

/// One task of the configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TaskConfig {
    /// Name, for messages and traces.
    pub name: &'static str,
    /// Static priority, `0 ..= MAX_PRIORITY`; higher runs first.
    pub priority: u8,
    /// Most pending activations (1 for extended tasks).
    pub max_activations: u8,
    /// Basic or extended.
    pub kind: TaskKind,
    /// Fully or non-preemptive.
    pub preemption: Preemption,
    /// The application modes in which `StartOS` activates the task, one bit per mode
    /// (bit 0: `OSDEFAULTAPPMODE`).
    pub autostart_modes: u32,
    /// The user resources this task may take, one bit per resource index. Ceilings are
    /// derived from this.
    pub resources: u32,
}

impl TaskConfig {
    /// A fully preemptive basic task with one activation, no resources, no autostart.
    pub const fn basic(name: &'static str, priority: u8) -> Self {
        Self {
            name,
            priority,
            max_activations: 1,
            kind: TaskKind::Basic,
            preemption: Preemption::Full,
            autostart_modes: 0,
            resources: 0,
        }
    }

    /// A fully preemptive extended task, no resources, no autostart.
    pub const fn extended(name: &'static str, priority: u8) -> Self {
        Self {
            kind: TaskKind::Extended,
            ..Self::basic(name, priority)
        }
    }

    /// The same task with `n` activations.
    pub const fn activations(self, n: u8) -> Self {
        Self {
            max_activations: n,
            ..self
        }
    }

    /// The same task, non-preemptive.
    pub const fn non_preemptive(self) -> Self {
        Self {
            preemption: Preemption::Non,
            ..self
        }
    }

    /// The same task, activated by `StartOS(OSDEFAULTAPPMODE)`.
    pub const fn autostart(self) -> Self {
        self.autostart_in(1)
    }

    /// The same task, activated by `StartOS` in the application modes of `modes` (one bit
    /// per mode).
    pub const fn autostart_in(self, modes: u32) -> Self {
        Self {
            autostart_modes: modes,
            ..self
        }
    }

    /// The same task, allowed to take the resources in `mask`.
    pub const fn uses(self, mask: u32) -> Self {
        Self {
            resources: mask,
            ..self
        }
    }
}

/// One counter (OSEK `COUNTER` object).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CounterConfig {
    /// Largest counter value; it wraps to 0 after it.
    pub max_allowed_value: TickType,
    /// Ticks per base unit (informational, reported by `GetAlarmBase`).
    pub ticks_per_base: TickType,
    /// Smallest admitted cycle of a cyclic alarm.
    pub min_cycle: TickType,
}

/// What an alarm does when it expires.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AlarmAction {
    /// `ActivateTask(task)`.
    ActivateTask(TaskId),
    /// `SetEvent(task, mask)`; the task must be extended.
    SetEvent(TaskId, EventMask),
    /// The alarm callback `id` (`ALARMCALLBACK`), run by the kernel through
    /// [`Hooks::alarm_callback`](super::Hooks::alarm_callback).
    Callback(u8),
}

/// How `StartOS` arms an alarm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AlarmAutostart {
    /// Not armed at start.
    Off,
    /// Armed as by `SetRelAlarm(increment, cycle)`.
    Relative {
        /// Ticks to the first expiry.
        increment: TickType,
        /// Period afterwards (0: single shot).
        cycle: TickType,
    },
    /// Armed as by `SetAbsAlarm(start, cycle)`.
    Absolute {
        /// Counter value of the first expiry.
        start: TickType,
        /// Period afterwards (0: single shot).
        cycle: TickType,
    },
}

/// One alarm (OSEK `ALARM` object).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AlarmConfig {
    /// Name, for messages and traces.
    pub name: &'static str,
    /// The counter that drives it.
    pub counter: CounterId,
    /// What it does on expiry.
    pub action: AlarmAction,
    /// Whether `StartOS` arms it.
    pub autostart: AlarmAutostart,
    /// The application modes in which `StartOS` arms it, one bit per mode.
    pub autostart_modes: u32,
}

impl AlarmConfig {
    /// An alarm `StartOS` does not arm.
    pub const fn new(name: &'static str, counter: CounterId, action: AlarmAction) -> Self {
        Self {
            name,
            counter,
            action,
            autostart: AlarmAutostart::Off,
            autostart_modes: 1,
        }
    }

    /// The same alarm, armed by `StartOS(OSDEFAULTAPPMODE)` as by `SetRelAlarm(increment,
    /// cycle)`.
    pub const fn relative(self, increment: TickType, cycle: TickType) -> Self {
        Self {
            autostart: AlarmAutostart::Relative { increment, cycle },
            ..self
        }
    }

    /// The same alarm, armed by `StartOS(OSDEFAULTAPPMODE)` as by `SetAbsAlarm(start,
    /// cycle)`.
    pub const fn absolute(self, start: TickType, cycle: TickType) -> Self {
        Self {
            autostart: AlarmAutostart::Absolute { start, cycle },
            ..self
        }
    }

    /// The same alarm, armed at start in the application modes of `modes` instead.
    pub const fn in_modes(self, modes: u32) -> Self {
        Self {
            autostart_modes: modes,
            ..self
        }
    }
}

/// ISR category (OSEK §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IsrCategory {
    /// Category 1: runs outside the OS, may call only the interrupt services. Its
    /// priority lies above every category-2 ISR, so that `SuspendOSInterrupts` is one mask.
    One,
    /// Category 2: runs under the OS; rescheduling waits until the last ISR returns.
    Two,
}

/// One interrupt service routine (OSEK/AUTOSAR `ISR` object).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IsrConfig {
    /// Name, for messages and traces.
    pub name: &'static str,
    /// Category 1 or 2.
    pub category: IsrCategory,
    /// Interrupt priority, `0 ..= MAX_ISR_PRIORITY`; higher interrupts lower. Every ISR lies
    /// above every task.
    pub priority: u8,
    /// The user resources this ISR may take (category 2 only), one bit per index.
    pub resources: u32,
}

impl IsrConfig {
    /// A category-2 ISR with no resources.
    pub const fn cat2(name: &'static str, priority: u8) -> Self {
        Self {
            name,
            category: IsrCategory::Two,
            priority,
            resources: 0,
        }
    }

    /// A category-1 ISR.
    pub const fn cat1(name: &'static str, priority: u8) -> Self {
        Self {
            category: IsrCategory::One,
            ..Self::cat2(name, priority)
        }
    }

    /// The same ISR, allowed to take the resources in `mask`.
    pub const fn uses(self, mask: u32) -> Self {
        Self {
            resources: mask,
            ..self
        }
    }
}

/// OSEK conformance class (§3.2): what the application may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConformanceClass {
    /// Basic tasks only, one activation each, one task per priority.
    Bcc1,
    /// Basic tasks, multiple activations, several tasks per priority.
    Bcc2,
    /// Basic and extended tasks, one activation each, one task per priority.
    Ecc1,
    /// Basic and extended tasks, multiple activations of basic tasks, several tasks per
    /// priority.
    Ecc2,
}

impl ConformanceClass {
    /// The class's name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Bcc1 => "BCC1",
            Self::Bcc2 => "BCC2",
            Self::Ecc1 => "ECC1",
            Self::Ecc2 => "ECC2",
        }
    }

    const fn extended_tasks(self) -> bool {
        matches!(self, Self::Ecc1 | Self::Ecc2)
    }

    const fn multiple(self) -> bool {
        matches!(self, Self::Bcc2 | Self::Ecc2)
    }
}

/// OSEK status level (`STATUS = STANDARD | EXTENDED`).
///
/// Extended status makes every plausibility check the standard lists. Standard status
/// leaves out the ones whose failure cannot corrupt the kernel: a caller whose priority is
/// above a resource's ceiling (`E_OS_ACCESS` of `GetResource`/`ReleaseResource`), alarm
/// values out of range (`E_OS_VALUE`, except AUTOSAR's increment 0), and events of a basic
/// task (`E_OS_ACCESS` of `SetEvent`, `ClearEvent`, `GetEvent`); such a call is then carried
/// out. The checks that keep the kernel consistent (invalid identifiers, call levels,
/// resources held or released out of order, events of a suspended task, calls with
/// interrupts disabled) stay in both: where OSEK leaves standard status undefined, this
/// kernel refuses the call and returns the extended code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// Standard status.
    Standard,
    /// Extended status.
    Extended,
}

/// Which standard decides where OSEK OS 2.2.3 and AUTOSAR OS differ (see [`crate::os`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dialect {
    /// OSEK OS 2.2.3.
    Osek,
    /// AUTOSAR OS (scalability class 1).
    Autosar,
}

/// Which hook routines the application has (OIL `STARTUPHOOK = TRUE` ...). The bodies are
/// the application's [`Hooks`](super::Hooks) implementation; the kernel calls only the
/// ones enabled here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HookSet {
    /// `StartupHook`.
    pub startup: bool,
    /// `ShutdownHook`.
    pub shutdown: bool,
    /// `PreTaskHook`.
    pub pre_task: bool,
    /// `PostTaskHook`.
    pub post_task: bool,
    /// `ErrorHook`.
    pub error: bool,
}

impl HookSet {
    /// No hooks.
    pub const NONE: Self = Self {
        startup: false,
        shutdown: false,
        pre_task: false,
        post_task: false,
        error: false,
    };
    /// All five hooks.
    pub const ALL: Self = Self {
        startup: true,
        shutdown: true,
        pre_task: true,
        post_task: true,
        error: true,
    };
}

/// The description of an OS: the attributes of the OIL `OS` object and the tables of
/// tasks, counters, alarms and ISRs. [`OsDescription::new`] gives the defaults (ECC2,
/// extended status, OSEK, no hooks, one application mode); the builder methods change them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OsDescription<const T: usize, const C: usize, const A: usize, const I: usize> {
    /// The conformance class the application declares.
    pub class: ConformanceClass,
    /// Standard or extended status.
    pub status: Status,
    /// OSEK or AUTOSAR behaviour where they differ.
    pub dialect: Dialect,
    /// The hooks the application has.
    pub hooks: HookSet,
    /// Number of application modes (`1 ..= MAX_APP_MODES`); mode 0 is `OSDEFAULTAPPMODE`.
    pub app_modes: u8,
    /// The tasks; a task's id is its index.
    pub tasks: [TaskConfig; T],
    /// The counters.
    pub counters: [CounterConfig; C],
    /// The alarms.
    pub alarms: [AlarmConfig; A],
    /// The ISRs; an ISR's id is its index.
    pub isrs: [IsrConfig; I],
}

impl<const T: usize, const C: usize, const A: usize, const I: usize> OsDescription<T, C, A, I> {
    /// The tables, with ECC2, extended status, the OSEK dialect, no hooks and one
    /// application mode.
    pub const fn new(
        tasks: [TaskConfig; T],
        counters: [CounterConfig; C],
        alarms: [AlarmConfig; A],
        isrs: [IsrConfig; I],
    ) -> Self {
        Self {
            class: ConformanceClass::Ecc2,
            status: Status::Extended,
            dialect: Dialect::Osek,
            hooks: HookSet::NONE,
            app_modes: 1,
            tasks,
            counters,
            alarms,
            isrs,
        }
    }

    /// The same, declaring conformance class `class`.
    pub const fn class(self, class: ConformanceClass) -> Self {
        Self { class, ..self }
    }

    /// The same, in status `status`.
    pub const fn status(self, status: Status) -> Self {
        Self { status, ..self }
    }

    /// The same, in dialect `dialect`.
    pub const fn dialect(self, dialect: Dialect) -> Self {
        Self { dialect, ..self }
    }

    /// The same, with the hooks `hooks`.
    pub const fn hooks(self, hooks: HookSet) -> Self {
        Self { hooks, ..self }
    }

    /// The same, with `n` application modes.
    pub const fn app_modes(self, n: u8) -> Self {
        Self {
            app_modes: n,
            ..self
        }
    }
}

/// A configuration rule that was broken. Indices name the offending table entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfigError {
    /// More tasks, resources, counters, alarms or ISRs than the kernel supports.
    TooManyObjects,
    /// A task's priority is above [`MAX_PRIORITY`].
    TaskPriority {
        /// Task index.
        task: u8,
    },
    /// A task has zero activations.
    TaskActivations {
        /// Task index.
        task: u8,
    },
    /// An extended task with more than one activation (OSEK allows one).
    ExtendedActivations {
        /// Task index.
        task: u8,
    },
    /// A task declares a resource index that does not exist.
    TaskResource {
        /// Task index.
        task: u8,
    },
    /// An extended task in a basic conformance class (BCC1, BCC2).
    ClassExtendedTask {
        /// Task index.
        task: u8,
    },
    /// Multiple activations in a class that allows one (BCC1, ECC1).
    ClassMultipleActivations {
        /// Task index.
        task: u8,
    },
    /// Two tasks at one priority in a class that allows one per priority (BCC1, ECC1).
    ClassSharedPriority {
        /// The later task.
        task: u8,
        /// The earlier task at the same priority.
        other: u8,
    },
    /// The number of application modes is 0 or above [`MAX_APP_MODES`].
    AppModes,
    /// A task autostarts in an application mode that does not exist.
    TaskAppMode {
        /// Task index.
        task: u8,
    },
    /// An alarm autostarts in an application mode that does not exist.
    AlarmAppMode {
        /// Alarm index.
        alarm: u8,
    },
    /// A counter's limits are inconsistent (`max_allowed_value` 0 or `u32::MAX`,
    /// `ticks_per_base` 0, `min_cycle` not in `1 ..= max_allowed_value`).
    CounterLimits {
        /// Counter index.
        counter: u8,
    },
    /// An alarm names a counter that does not exist.
    AlarmCounter {
        /// Alarm index.
        alarm: u8,
    },
    /// An alarm's action names a missing task, sets an event of a basic task, or uses a
    /// callback id of `MAX_CALLBACKS` (32) or more.
    AlarmAction {
        /// Alarm index.
        alarm: u8,
    },
    /// An autostart alarm's increment, start or cycle is outside the counter's limits.
    AlarmAutostart {
        /// Alarm index.
        alarm: u8,
    },
    /// An ISR's priority is above [`MAX_ISR_PRIORITY`].
    IsrPriority {
        /// ISR index.
        isr: u8,
    },
    /// An ISR declares a resource index that does not exist.
    IsrResource {
        /// ISR index.
        isr: u8,
    },
    /// A category-1 ISR declares resources (it may call no resource service).
    Cat1Resource {
        /// ISR index.
        isr: u8,
    },
    /// A category-1 ISR whose priority is not above every category-2 ISR.
    Cat1BelowCat2 {
        /// The category-1 ISR.
        cat1: u8,
        /// A category-2 ISR at or above it.
        cat2: u8,
    },
    /// The kernel's ready-queue capacity `Q` is below the sum of all activations, or above
    /// 255.
    QueueCapacity {
        /// Entries the configuration needs.
        needed: usize,
    },
}

impl ConfigError {
    /// A sentence describing the broken rule.
    pub const fn describe(&self) -> &'static str {
        match self {
            Self::TooManyObjects => "more tasks, resources, counters, alarms or ISRs than the kernel supports",
            Self::TaskPriority { .. } => "a task priority is above MAX_PRIORITY (63)",
            Self::TaskActivations { .. } => "a task has zero activations",
            Self::ExtendedActivations { .. } => "an extended task has more than one activation",
            Self::TaskResource { .. } => "a task uses a resource that is not configured",
            Self::ClassExtendedTask { .. } => "an extended task in conformance class BCC1 or BCC2 (declare ECC1 or ECC2)",
            Self::ClassMultipleActivations { .. } => "a task with multiple activations in conformance class BCC1 or ECC1 (declare BCC2 or ECC2)",
            Self::ClassSharedPriority { .. } => "two tasks share a priority in conformance class BCC1 or ECC1 (declare BCC2 or ECC2)",
            Self::AppModes => "the number of application modes is not within 1 ..= 32",
            Self::TaskAppMode { .. } => "a task autostarts in an application mode that is not configured",
            Self::AlarmAppMode { .. } => "an alarm autostarts in an application mode that is not configured",
            Self::CounterLimits { .. } => "a counter has inconsistent limits",
            Self::AlarmCounter { .. } => "an alarm is driven by a counter that is not configured",
            Self::AlarmAction { .. } => "an alarm action names a missing task, an event of a basic task, or a callback id above 31",
            Self::AlarmAutostart { .. } => "an autostart alarm's increment, start or cycle is outside its counter's limits",
            Self::IsrPriority { .. } => "an ISR priority is above MAX_ISR_PRIORITY (63)",
            Self::IsrResource { .. } => "an ISR uses a resource that is not configured",
            Self::Cat1Resource { .. } => "a category-1 ISR declares resources (it may call no resource service)",
            Self::Cat1BelowCat2 { .. } => "a category-1 ISR is not above every category-2 ISR (SuspendOSInterrupts must be one mask)",
            Self::QueueCapacity { .. } => "the ready-queue capacity differs from what the tasks' activations need (at most 255)",
        }
    }
}

/// A validated configuration: `T` tasks, `R` user resources, `C` counters, `A` alarms, `I`
/// ISRs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OsConfig<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize>
{
    pub(crate) class: ConformanceClass,
    pub(crate) status: Status,
    pub(crate) dialect: Dialect,
    pub(crate) hooks: HookSet,
    pub(crate) app_modes: u8,
    pub(crate) tasks: [TaskConfig; T],
    pub(crate) counters: [CounterConfig; C],
    pub(crate) alarms: [AlarmConfig; A],
    pub(crate) isrs: [IsrConfig; I],
    /// Derived: the ceiling of each user resource (a processor priority: at interrupt level
    /// when an ISR uses it).
    pub(crate) ceilings: [u8; R],
    /// Derived: the ceiling of `RES_SCHEDULER` (the highest task priority).
    pub(crate) scheduler_ceiling: u8,
    /// Derived: every alarm's action is `ActivateTask`. With tables that are constants
    /// (`static_tables!`) the kernel's image then holds no code for the other actions.
    pub(crate) task_alarms_only: bool,
    /// Derived, per task: the user resources it declares, one bit each (the first 32);
    /// none for a task that is not fully preemptive (it runs at `RES_SCHEDULER`'s
    /// ceiling).
    pub(crate) lock_free_resources: [u32; T],
    /// Derived: the sum of all tasks' activations (the ready-queue entries ever needed).
    pub(crate) total_activations: usize,
    /// Derived, per task, for the hot paths: static priority.
    pub(crate) priority: [u8; T],
    /// Derived, per task: activation limit.
    pub(crate) max_activations: [u8; T],
    /// Derived, per task: the priority it runs at holding no resource (its own, or the
    /// `RES_SCHEDULER` ceiling when non-preemptive).
    pub(crate) dispatch_priority: [u8; T],
    /// Derived, per ISR: its processor priority (`ISR_LEVEL_BASE + priority`).
    pub(crate) isr_level: [u8; I],
    /// Derived: the processor priority `SuspendOSInterrupts` raises to (the highest
    /// category-2 ISR's), 0 with no category-2 ISR.
    pub(crate) os_level: u8,
    /// Derived: the services refused in each [`Context`] (the call-level table).
    pub(crate) denied: [u64; Context::COUNT],
    /// Derived: the processor priority below which each [`Context`] holds interrupts by
    /// itself: every one outside the OS and in the start-up and shutdown hooks, the
    /// category-2 ones in the other hooks and alarm callbacks, none elsewhere.
    pub(crate) context_gate: [u8; Context::COUNT],
}

/// The interrupt gate of each context (see `OsConfig::context_gate`).
const fn context_gates(os_level: u8) -> [u8; Context::COUNT] {
    let mut gates = [0u8; Context::COUNT];
    let mut i = 0;
    while i < Context::COUNT {
        gates[i] = match Context::ALL[i] {
            Context::BeforeStart
            | Context::StartupHook
            | Context::ShutdownHook
            | Context::ShutDown => u8::MAX,
            Context::ErrorHook
            | Context::PreTaskHook
            | Context::PostTaskHook
            | Context::AlarmCallback => os_level,
            Context::Idle | Context::Task | Context::Isr1 | Context::Isr2 => 0,
        };
        i += 1;
    }
    gates
}

/// Whether a cycle is admissible for a counter: 0 (single shot) or within
/// `min_cycle ..= max_allowed_value`.
pub(crate) const fn cycle_ok(counter: &CounterConfig, cycle: TickType) -> bool {
    cycle == 0 || (cycle >= counter.min_cycle && cycle <= counter.max_allowed_value)
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize>
    OsConfig<T, R, C, A, I>
{
    /// Validates the description and derives the ceilings. Use it in a `const` so that a
    /// broken rule stops the build:
    ///
    /// ```
    /// use cw_core::os::{ConformanceClass, IsrConfig, OsConfig, OsDescription, TaskConfig};
    /// const CFG: OsConfig<2, 2, 0, 0, 1> = match OsConfig::new(
    ///     OsDescription::new(
    ///         [TaskConfig::basic("Low", 1).uses(0b11), TaskConfig::basic("High", 5).uses(0b01)],
    ///         [],
    ///         [],
    ///         [IsrConfig::cat2("CanRx", 3).uses(0b10)],
    ///     )
    ///     .class(ConformanceClass::Bcc1),
    /// ) {
    ///     Ok(cfg) => cfg,
    ///     Err(e) => panic!("{}", e.describe()),
    /// };
    /// assert_eq!(CFG.resource_ceiling(0), Some(5));
    /// // Resource 1 is shared with an ISR: its ceiling lies at interrupt level.
    /// assert_eq!(CFG.resource_ceiling(1), Some(64 + 3));
    /// ```
    ///
    /// # Errors
    /// The first [`ConfigError`] found, naming the table entries.
    pub const fn new(d: OsDescription<T, C, A, I>) -> Result<Self, ConfigError> {
        if T > MAX_TASKS || R > MAX_RESOURCES || C > MAX_ALARMS || A > MAX_ALARMS || I > MAX_ISRS {
            return Err(ConfigError::TooManyObjects);
        }
        if d.app_modes == 0 || d.app_modes > MAX_APP_MODES {
            return Err(ConfigError::AppModes);
        }
        let modes_mask: u32 = if d.app_modes >= 32 {
            u32::MAX
        } else {
            (1u32 << d.app_modes) - 1
        };
        let tasks = &d.tasks;
        let mut ceilings = [0u8; R];
        let mut scheduler_ceiling = 0u8;
        let mut total_activations = 0usize;
        let mut t = 0;
        while t < T {
            let task = &tasks[t];
            let id = t as u8;
            if task.priority > MAX_PRIORITY {
                return Err(ConfigError::TaskPriority { task: id });
            }
            if task.max_activations == 0 {
                return Err(ConfigError::TaskActivations { task: id });
            }
            let extended = matches!(task.kind, TaskKind::Extended);
            if extended && task.max_activations != 1 {
                return Err(ConfigError::ExtendedActivations { task: id });
            }
            if R < 32 && task.resources >> R != 0 {
                return Err(ConfigError::TaskResource { task: id });
            }
            if task.autostart_modes & !modes_mask != 0 {
                return Err(ConfigError::TaskAppMode { task: id });
            }
            if extended && !d.class.extended_tasks() {
                return Err(ConfigError::ClassExtendedTask { task: id });
            }
            if task.max_activations > 1 && !d.class.multiple() {
                return Err(ConfigError::ClassMultipleActivations { task: id });
            }
            if !d.class.multiple() {
                let mut u = 0;
                while u < t {
                    if tasks[u].priority == task.priority {
                        return Err(ConfigError::ClassSharedPriority {
                            task: id,
                            other: u as u8,
                        });
                    }
                    u += 1;
                }
            }
            total_activations += task.max_activations as usize;
            if task.priority > scheduler_ceiling {
                scheduler_ceiling = task.priority;
            }
            let mut r = 0;
            while r < R {
                if task.resources & (1 << r) != 0 && task.priority > ceilings[r] {
                    ceilings[r] = task.priority;
                }
                r += 1;
            }
            t += 1;
        }
        let mut isr_level = [0u8; I];
        let mut os_level = 0u8;
        let mut i = 0;
        while i < I {
            let isr = &d.isrs[i];
            let id = i as u8;
            if isr.priority > MAX_ISR_PRIORITY {
                return Err(ConfigError::IsrPriority { isr: id });
            }
            if R < 32 && isr.resources >> R != 0 {
                return Err(ConfigError::IsrResource { isr: id });
            }
            let level = ISR_LEVEL_BASE + isr.priority;
            isr_level[i] = level;
            match isr.category {
                IsrCategory::One => {
                    if isr.resources != 0 {
                        return Err(ConfigError::Cat1Resource { isr: id });
                    }
                }
                IsrCategory::Two => {
                    if level > os_level {
                        os_level = level;
                    }
                    let mut r = 0;
                    while r < R {
                        if isr.resources & (1 << r) != 0 && level > ceilings[r] {
                            ceilings[r] = level;
                        }
                        r += 1;
                    }
                }
            }
            i += 1;
        }
        let mut lock_free_resources = [0u32; T];
        let mut t = 0;
        while t < T {
            let mut r = 0;
            // (`R` is at most 32, `MAX_RESOURCES`: checked above.)
            while r < R {
                if d.tasks[t].resources & (1 << r) != 0
                    && matches!(d.tasks[t].preemption, Preemption::Full)
                {
                    lock_free_resources[t] |=
                        lock_free_bit(super::ResourceId(r as u8), ceilings[r] >= ISR_LEVEL_BASE);
                }
                r += 1;
            }
            t += 1;
        }
        // Category 1 above every category 2: then `SuspendOSInterrupts` is one mask at the
        // highest category-2 level, which leaves every category-1 ISR free.
        let mut i = 0;
        while i < I {
            if matches!(d.isrs[i].category, IsrCategory::One) {
                let mut j = 0;
                while j < I {
                    if matches!(d.isrs[j].category, IsrCategory::Two)
                        && d.isrs[j].priority >= d.isrs[i].priority
                    {
                        return Err(ConfigError::Cat1BelowCat2 {
                            cat1: i as u8,
                            cat2: j as u8,
                        });
                    }
                    j += 1;
                }
            }
            i += 1;
        }
        let mut priority = [0u8; T];
        let mut max_activations = [0u8; T];
        let mut dispatch_priority = [0u8; T];
        let mut t = 0;
        while t < T {
            priority[t] = tasks[t].priority;
            max_activations[t] = tasks[t].max_activations;
            dispatch_priority[t] = match tasks[t].preemption {
                Preemption::Full => tasks[t].priority,
                Preemption::Non => scheduler_ceiling,
            };
            t += 1;
        }
        let mut c = 0;
        while c < C {
            let k = &d.counters[c];
            if k.max_allowed_value == 0
                || k.max_allowed_value == TickType::MAX
                || k.ticks_per_base == 0
                || k.min_cycle == 0
                || k.min_cycle > k.max_allowed_value
            {
                return Err(ConfigError::CounterLimits { counter: c as u8 });
            }
            c += 1;
        }
        let mut task_alarms_only = true;
        let mut a = 0;
        while a < A {
            let alarm = &d.alarms[a];
            let id = a as u8;
            if !matches!(alarm.action, AlarmAction::ActivateTask(_)) {
                task_alarms_only = false;
            }
            if alarm.counter.0 as usize >= C {
                return Err(ConfigError::AlarmCounter { alarm: id });
            }
            let action_ok = match alarm.action {
                AlarmAction::ActivateTask(task) => (task.0 as usize) < T,
                AlarmAction::SetEvent(task, _) => {
                    (task.0 as usize) < T
                        && matches!(tasks[task.0 as usize].kind, TaskKind::Extended)
                }
                AlarmAction::Callback(cb) => cb < MAX_CALLBACKS,
            };
            if !action_ok {
                return Err(ConfigError::AlarmAction { alarm: id });
            }
            let k = &d.counters[alarm.counter.0 as usize];
            let autostart_ok = match alarm.autostart {
                AlarmAutostart::Off => true,
                AlarmAutostart::Relative { increment, cycle } => {
                    increment >= 1 && increment <= k.max_allowed_value && cycle_ok(k, cycle)
                }
                AlarmAutostart::Absolute { start, cycle } => {
                    start <= k.max_allowed_value && cycle_ok(k, cycle)
                }
            };
            if !autostart_ok {
                return Err(ConfigError::AlarmAutostart { alarm: id });
            }
            if !matches!(alarm.autostart, AlarmAutostart::Off)
                && alarm.autostart_modes & !modes_mask != 0
            {
                return Err(ConfigError::AlarmAppMode { alarm: id });
            }
            a += 1;
        }
        Ok(Self {
            class: d.class,
            status: d.status,
            dialect: d.dialect,
            hooks: d.hooks,
            app_modes: d.app_modes,
            tasks: d.tasks,
            counters: d.counters,
            alarms: d.alarms,
            isrs: d.isrs,
            ceilings,
            scheduler_ceiling,
            lock_free_resources,
            task_alarms_only,
            total_activations,
            priority,
            max_activations,
            dispatch_priority,
            isr_level,
            os_level,
            denied: denied_table(d.dialect),
            context_gate: context_gates(os_level),
        })
    }

    /// The task table.
    pub const fn tasks(&self) -> &[TaskConfig; T] {
        &self.tasks
    }

    /// The counter table.
    pub const fn counters(&self) -> &[CounterConfig; C] {
        &self.counters
    }

    /// The alarm table.
    pub const fn alarms(&self) -> &[AlarmConfig; A] {
        &self.alarms
    }

    /// The ISR table.
    pub const fn isrs(&self) -> &[IsrConfig; I] {
        &self.isrs
    }

    /// The declared conformance class.
    pub const fn class(&self) -> ConformanceClass {
        self.class
    }

    /// Standard or extended status.
    pub const fn status(&self) -> Status {
        self.status
    }

    /// OSEK or AUTOSAR behaviour.
    pub const fn dialect(&self) -> Dialect {
        self.dialect
    }

    /// The enabled hooks.
    pub const fn hooks(&self) -> HookSet {
        self.hooks
    }

    /// Number of application modes.
    pub const fn app_modes(&self) -> u8 {
        self.app_modes
    }

    /// The derived ceiling of user resource `index` (a processor priority: above
    /// [`MAX_PRIORITY`] when an ISR uses the resource).
    pub const fn resource_ceiling(&self, index: usize) -> Option<u8> {
        if index < R {
            Some(self.ceilings[index])
        } else {
            None
        }
    }

    /// Whether an ISR shares user resource `res` (its ceiling at interrupt level): the
    /// kind of its lock outside the kernel ([`lock_free_bit`]). A `const fn`, so that the
    /// data a resource guards can carry it in its type, read from the configuration when
    /// the image is built. `false` for an unknown resource.
    pub const fn isr_shared(&self, res: super::ResourceId) -> bool {
        match self.resource_ceiling(res.0 as usize) {
            Some(ceiling) => ceiling >= ISR_LEVEL_BASE,
            None => false,
        }
    }

    /// The user resources task `index` declares, one bit each ([`lock_free_bit`]: the
    /// first [`LOCK_FREE_RESOURCES`], those an ISR shares too, a ceiling at interrupt
    /// level, in the second twelve bits); none for a task that is not fully preemptive, or an
    /// unknown index. What a port may let the task lock outside the kernel
    /// ([`Os::lock_free_resources`](crate::os::Os::lock_free_resources)), masking the ISRs
    /// at or below the ceiling itself where an ISR shares the resource.
    pub const fn lock_free_resources(&self, index: usize) -> u32 {
        if index < T {
            self.lock_free_resources[index]
        } else {
            0
        }
    }

    /// The ceiling of `RES_SCHEDULER`: the highest task priority.
    pub const fn scheduler_ceiling(&self) -> u8 {
        self.scheduler_ceiling
    }

    /// The number of ready-queue entries the configuration can need at once.
    pub const fn total_activations(&self) -> usize {
        self.total_activations
    }

    /// The processor priority of ISR `index` ([`ISR_LEVEL_BASE`] + its priority).
    pub const fn isr_level(&self, index: usize) -> Option<u8> {
        if index < I {
            Some(self.isr_level[index])
        } else {
            None
        }
    }

    /// The processor priority `SuspendOSInterrupts` masks up to: the highest category-2
    /// ISR's (0 when there is none).
    pub const fn os_interrupt_level(&self) -> u8 {
        self.os_level
    }
}
