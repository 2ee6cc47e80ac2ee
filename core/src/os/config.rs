//! Static OS configuration (the OIL/ARXML part of an OSEK system) and its validation.
//!
//! A configuration is built once, in a `const`, by [`OsConfig::new`]; every rule below is
//! checked there, so an impossible configuration fails the build (see [`OsConfig::new`]).
//! Derived values (resource ceilings, the `RES_SCHEDULER` ceiling, the activation-queue
//! size) are computed from the tables, never written by hand.

use super::{CounterId, EventMask, TaskId, TickType};

/// Highest task priority (priorities are `0 ..= MAX_PRIORITY`, higher runs first).
pub const MAX_PRIORITY: u8 = 63;
/// Most tasks one configuration may hold.
pub const MAX_TASKS: usize = 64;
/// Most user resources one configuration may hold (besides `RES_SCHEDULER`).
pub const MAX_RESOURCES: usize = 32;
/// Most alarm callbacks (callback ids are `0 .. MAX_CALLBACKS`).
pub const MAX_CALLBACKS: u8 = 32;
/// Most alarms or counters one configuration may hold.
pub const MAX_ALARMS: usize = 64;

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
    /// Activated by `StartOS`.
    pub autostart: bool,
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
            autostart: false,
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

    /// The same task, started by `StartOS`.
    pub const fn autostart(self) -> Self {
        Self {
            autostart: true,
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
    /// Run alarm callback `id`; the board runs it (reported in the `TickReport`).
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
}

/// A configuration rule that was broken. Indices name the offending table entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfigError {
    /// More tasks, resources, counters or alarms than the kernel supports.
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
    /// callback id of [`MAX_CALLBACKS`] or more.
    AlarmAction {
        /// Alarm index.
        alarm: u8,
    },
    /// An autostart alarm's increment, start or cycle is outside the counter's limits.
    AlarmAutostart {
        /// Alarm index.
        alarm: u8,
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
            Self::TooManyObjects => "more tasks, resources, counters or alarms than the kernel supports",
            Self::TaskPriority { .. } => "a task priority is above MAX_PRIORITY (63)",
            Self::TaskActivations { .. } => "a task has zero activations",
            Self::ExtendedActivations { .. } => "an extended task has more than one activation",
            Self::TaskResource { .. } => "a task uses a resource that is not configured",
            Self::CounterLimits { .. } => "a counter has inconsistent limits",
            Self::AlarmCounter { .. } => "an alarm is driven by a counter that is not configured",
            Self::AlarmAction { .. } => "an alarm action names a missing task, an event of a basic task, or a callback id above 31",
            Self::AlarmAutostart { .. } => "an autostart alarm's increment, start or cycle is outside its counter's limits",
            Self::QueueCapacity { .. } => "the ready-queue capacity differs from what the tasks' activations need (at most 255)",
        }
    }
}

/// A validated configuration: `T` tasks, `R` user resources, `C` counters, `A` alarms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OsConfig<const T: usize, const R: usize, const C: usize, const A: usize> {
    pub(crate) tasks: [TaskConfig; T],
    pub(crate) counters: [CounterConfig; C],
    pub(crate) alarms: [AlarmConfig; A],
    /// Derived: the ceiling of each user resource.
    pub(crate) ceilings: [u8; R],
    /// Derived: the ceiling of `RES_SCHEDULER` (the highest task priority).
    pub(crate) scheduler_ceiling: u8,
    /// Derived: the sum of all tasks' activations (the ready-queue entries ever needed).
    pub(crate) total_activations: usize,
    /// Derived, per task, for the hot paths: static priority.
    pub(crate) priority: [u8; T],
    /// Derived, per task: activation limit.
    pub(crate) max_activations: [u8; T],
    /// Derived, per task: the priority it runs at holding no resource (its own, or the
    /// `RES_SCHEDULER` ceiling when non-preemptive).
    pub(crate) dispatch_priority: [u8; T],
}

/// Whether a cycle is admissible for a counter: 0 (single shot) or within
/// `min_cycle ..= max_allowed_value`.
pub(crate) const fn cycle_ok(counter: &CounterConfig, cycle: TickType) -> bool {
    cycle == 0 || (cycle >= counter.min_cycle && cycle <= counter.max_allowed_value)
}

impl<const T: usize, const R: usize, const C: usize, const A: usize> OsConfig<T, R, C, A> {
    /// Validates the tables and derives the ceilings. Use it in a `const` so that a broken
    /// rule stops the build:
    ///
    /// ```
    /// use cw_core::os::{OsConfig, TaskConfig};
    /// const CFG: OsConfig<2, 1, 0, 0> = match OsConfig::new(
    ///     [TaskConfig::basic("Low", 1).uses(0b1), TaskConfig::basic("High", 5).uses(0b1)],
    ///     [],
    ///     [],
    /// ) {
    ///     Ok(cfg) => cfg,
    ///     Err(e) => panic!("{}", e.describe()),
    /// };
    /// assert_eq!(CFG.resource_ceiling(0), Some(5));
    /// ```
    ///
    /// # Errors
    /// The first [`ConfigError`] found, naming the table entry.
    pub const fn new(
        tasks: [TaskConfig; T],
        counters: [CounterConfig; C],
        alarms: [AlarmConfig; A],
    ) -> Result<Self, ConfigError> {
        if T > MAX_TASKS || R > MAX_RESOURCES || C > MAX_ALARMS || A > MAX_ALARMS {
            return Err(ConfigError::TooManyObjects);
        }
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
            if matches!(task.kind, TaskKind::Extended) && task.max_activations != 1 {
                return Err(ConfigError::ExtendedActivations { task: id });
            }
            if R < 32 && task.resources >> R != 0 {
                return Err(ConfigError::TaskResource { task: id });
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
            let k = &counters[c];
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
        let mut a = 0;
        while a < A {
            let alarm = &alarms[a];
            let id = a as u8;
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
            let k = &counters[alarm.counter.0 as usize];
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
            a += 1;
        }
        Ok(Self {
            tasks,
            counters,
            alarms,
            ceilings,
            scheduler_ceiling,
            total_activations,
            priority,
            max_activations,
            dispatch_priority,
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

    /// The derived ceiling of user resource `index`.
    pub const fn resource_ceiling(&self, index: usize) -> Option<u8> {
        if index < R {
            Some(self.ceilings[index])
        } else {
            None
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
}
