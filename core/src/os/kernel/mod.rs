//! The kernel state and the machinery every service shares: call-level checks, error
//! reporting to `ErrorHook`, hook calls, and the rescheduling point. The services are in
//! the submodules, one per OSEK chapter. See the module documentation of [`crate::os`] for
//! the rules and the choices made where the standards leave room.
//!
//! Representation:
//! - activation records live in a [`ReadyQueue`] (O(1) push, pop and highest-priority
//!   lookup); the running task's record is out of the queue while it runs;
//! - each owner's held resources (a task's, or an active ISR's) form a LIFO stack threaded
//!   through the resources (`res_top` and `ResState::next`), so `ReleaseResource` out of
//!   order is detected in O(1);
//! - active ISRs form a stack of [`IsrFrame`]s: each records the ISR, its current
//!   processor priority (raised by the ceilings it holds), its resources, and the context
//!   and interrupt locks it interrupted;
//! - `denied` caches the services the current context and interrupt locks refuse, one bit
//!   per [`ServiceId`], so a service's call-level check is one test;
//! - each counter keeps its armed alarms in a delta list: an alarm's delta is the number of
//!   ticks after its predecessor's expiry. A tick with nothing due decrements one number and
//!   compares it: O(1) whatever the number of alarms.

mod alarm;
mod control;
mod event;
mod interrupt;
mod resource;
mod task;

use super::call::ServiceCall;
use super::callevel::{Context, INTERRUPT_SERVICES};
use super::config::{OsConfig, TaskKind};
use super::error::ServiceId;
use super::hooks::{Hooks, NoHooks};
use super::queue::ReadyQueue;
use super::{AppMode, EventMask, OsError, TickType, OSDEFAULTAPPMODE};
use crate::tables::Tables;
use core::hash::{Hash, Hasher};

const NONE: u8 = u8::MAX;
const NO_RES: u8 = 0xFE;

/// `GetAlarmBase` result: the driving counter's constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AlarmBase {
    /// Largest counter value.
    pub max_allowed_value: TickType,
    /// Ticks per base unit.
    pub ticks_per_base: TickType,
    /// Smallest cycle.
    pub min_cycle: TickType,
}

/// Where the OS is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Phase {
    /// Before `StartOS`.
    BeforeStart,
    /// Inside `StartOS`: autostart done, `StartupHook` running, nothing dispatched yet.
    Starting,
    /// Scheduling.
    Running,
    /// Inside `ShutdownOS`: `ShutdownHook` running.
    ShuttingDown,
    /// After `ShutdownOS`: nothing runs any more.
    ShutDown,
}

/// The interrupt locks in force (OSEK §13.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Locks {
    /// `DisableAllInterrupts` is in force (not nestable).
    pub all_disabled: bool,
    /// Nesting depth of `SuspendAllInterrupts`.
    pub suspend_all: u8,
    /// Nesting depth of `SuspendOSInterrupts`.
    pub suspend_os: u8,
}

impl Locks {
    /// Whether any lock is in force.
    #[inline(always)]
    pub const fn any(self) -> bool {
        self.all_disabled || self.suspend_all != 0 || self.suspend_os != 0
    }

    /// Whether every interrupt is held (`DisableAll` or `SuspendAll` in force).
    pub const fn masks_all(self) -> bool {
        self.all_disabled || self.suspend_all != 0
    }
}

/// One resource's dynamic state: its holder (a task index, or `T` + an ISR index), the
/// holder's priority before taking it, and the next resource down the holder's stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct ResState {
    owner: u8,
    prev_prio: u8,
    next: u8,
}

const FREE_RES: ResState = ResState {
    owner: NONE,
    prev_prio: 0,
    next: NO_RES,
};

/// One active ISR.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct IsrFrame {
    /// The ISR's index.
    isr: u8,
    /// Its processor priority now: its own, raised by the ceilings of what it holds.
    level: u8,
    /// The top of its resource stack.
    res_top: u8,
    /// The interrupt locks in force when it was entered (restored when it returns).
    locks: Locks,
    /// The context it interrupted.
    interrupted: Context,
}

pub(crate) const NO_FRAME: IsrFrame = IsrFrame {
    isr: NONE,
    level: 0,
    res_top: NO_RES,
    locks: Locks {
        all_disabled: false,
        suspend_all: 0,
        suspend_os: 0,
    },
    interrupted: Context::Idle,
};

/// The configuration, compared by identity: two kernels are equal only if they run the same
/// configuration object, and hashing the state need not hash the tables.
#[derive(Clone, Copy)]
struct CfgRef<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K>(K);

impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K>
    CfgRef<T, R, C, A, I, K>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
{
    #[inline(always)]
    fn get(self) -> &'static OsConfig<T, R, C, A, I> {
        self.0.tables()
    }
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K> PartialEq
    for CfgRef<T, R, C, A, I, K>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
{
    fn eq(&self, other: &Self) -> bool {
        core::ptr::eq(self.get(), other.get())
    }
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K> Eq
    for CfgRef<T, R, C, A, I, K>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
{
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K> Hash
    for CfgRef<T, R, C, A, I, K>
{
    fn hash<Hs: Hasher>(&self, _state: &mut Hs) {}
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, const I: usize, K>
    core::fmt::Debug for CfgRef<T, R, C, A, I, K>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("OsConfig")
    }
}

/// The OSEK kernel state for a configuration of `T` tasks, `R` resources, `C` counters,
/// `A` alarms and `I` ISRs, with `Q` ready-queue entries (the sum of all tasks'
/// activations).
///
/// `K` is where the configuration comes from ([`Tables`]): a `&'static OsConfig`, or a
/// zero-sized type that makes it a build-time constant. `H` is the application's
/// [`Hooks`] type, whose value (the hooks' data) the kernel holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Os<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const I: usize,
    const Q: usize,
    K = &'static OsConfig<T, R, C, A, I>,
    H = NoHooks,
> where
    K: Tables<OsConfig<T, R, C, A, I>>,
{
    cfg: CfgRef<T, R, C, A, I, K>,
    ready: ReadyQueue<Q>,
    running: u8,
    running_prio: u8,
    /// Cached scheduling threshold: a ready priority at or above it preempts. 0 when idle,
    /// the running priority + 1 when a task runs, `u8::MAX` at interrupt level and outside
    /// the running phase (nothing preempts there). Derived by `sync_threshold` after every
    /// change to what it depends on, so the hot paths decide with one comparison.
    preempt_at: u8,
    /// Cached: the services refused now, one bit per `ServiceId` (the call-level table's
    /// row for `context`, plus every non-interrupt service while a lock is in force).
    /// Derived by `sync_denied` after every change of context or locks.
    denied: u64,
    /// Cached: the processor priority below which no interrupt may be taken whatever runs:
    /// `u8::MAX` outside the running phase and under `DisableAll`/`SuspendAll`, the
    /// highest category-2 level under `SuspendOS` or in a hook, else 0. Derived with
    /// `denied` by `sync_denied`.
    gate: u8,
    /// Cached from `locks`: the services a lock refuses, and the priority it masks up to.
    /// Derived by `set_locks`.
    lock_denied: u64,
    lock_gate: u8,
    context: Context,
    phase: Phase,
    mode: AppMode,
    locks: Locks,
    isr_depth: u8,
    isr_stack: [IsrFrame; I],
    /// The failed call while `ErrorHook` runs (and so `ErrorHook` is never re-entered).
    error_call: Option<ServiceCall>,
    activations: [u8; T],
    started: [bool; T],
    waiting: [bool; T],
    saved_prio: [u8; T],
    events: [EventMask; T],
    wait_mask: [EventMask; T],
    res_top: [u8; T],
    res: [ResState; R],
    sched_res: ResState,
    counter_value: [TickType; C],
    counter_head: [u8; C],
    alarm_active: [bool; A],
    /// Each armed alarm's ticks after the one before it in its counter's list (the
    /// head's: after now). 32 bits: no delay exceeds `u32::MAX` ticks (a counter's
    /// `maxallowedvalue` is below it, and standard status arms at most that far).
    alarm_delta: [TickType; A],
    alarm_next: [u8; A],
    alarm_cycle: [TickType; A],
    hooks: H,
}

impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
        K,
        H,
    > Os<T, R, C, A, I, Q, K, H>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Self>,
{
    /// A kernel for `tables`, before `StartOS`: no task is active, no alarm armed; `hooks`
    /// is the initial value of the hooks' data.
    ///
    /// # Errors
    /// [`ConfigError::QueueCapacity`](super::ConfigError::QueueCapacity) unless `Q` equals
    /// the configuration's total activations (and is at most 255).
    pub fn with_hooks(tables: K, hooks: H) -> Result<Self, super::ConfigError> {
        let cfg = tables.tables();
        if Q != cfg.total_activations || Q > 255 {
            return Err(super::ConfigError::QueueCapacity {
                needed: cfg.total_activations,
            });
        }
        let mut saved_prio = [0u8; T];
        let mut t = 0;
        while t < T {
            saved_prio[t] = cfg.tasks[t].priority;
            t += 1;
        }
        Ok(Self {
            cfg: CfgRef(tables),
            ready: ReadyQueue::new(),
            running: NONE,
            running_prio: 0,
            preempt_at: u8::MAX,
            denied: cfg.denied[Context::BeforeStart as usize],
            gate: u8::MAX,
            lock_denied: 0,
            lock_gate: 0,
            context: Context::BeforeStart,
            phase: Phase::BeforeStart,
            mode: OSDEFAULTAPPMODE,
            locks: Locks::default(),
            isr_depth: 0,
            isr_stack: [NO_FRAME; I],
            error_call: None,
            activations: [0; T],
            started: [false; T],
            waiting: [false; T],
            saved_prio,
            events: [0; T],
            wait_mask: [0; T],
            res_top: [NO_RES; T],
            res: [FREE_RES; R],
            sched_res: FREE_RES,
            counter_value: [0; C],
            counter_head: [NONE; C],
            alarm_active: [false; A],
            alarm_delta: [0; A],
            alarm_next: [NONE; A],
            alarm_cycle: [0; A],
            hooks,
        })
    }

    /// A kernel for `tables` with the default value of the hooks' data.
    ///
    /// # Errors
    /// As [`Os::with_hooks`].
    pub fn new(tables: K) -> Result<Self, super::ConfigError>
    where
        H: Default,
    {
        Self::with_hooks(tables, H::default())
    }

    // ---- inspection (not OSEK services: no call-level check, no ErrorHook) -------------

    /// The configuration.
    #[inline(always)]
    pub fn config(&self) -> &'static OsConfig<T, R, C, A, I> {
        self.cfg.get()
    }

    /// The hooks' data.
    pub const fn hooks(&self) -> &H {
        &self.hooks
    }

    /// The hooks' data, to change (from a hook, or from the application).
    pub fn hooks_mut(&mut self) -> &mut H {
        &mut self.hooks
    }

    /// The task the kernel has chosen to run.
    #[inline]
    pub const fn running(&self) -> Option<super::TaskId> {
        if self.running == NONE {
            None
        } else {
            Some(super::TaskId(self.running))
        }
    }

    /// The running task's current priority (raised by ceilings and non-preemption).
    pub const fn running_priority(&self) -> Option<u8> {
        if self.running == NONE {
            None
        } else {
            Some(self.running_prio)
        }
    }

    /// Where code runs now, as far as the OS knows.
    pub const fn context(&self) -> Context {
        self.context
    }

    /// Where the OS is in its life.
    pub const fn phase(&self) -> Phase {
        self.phase
    }

    /// Whether `ShutdownOS` has run: nothing runs any more.
    pub const fn is_shut_down(&self) -> bool {
        matches!(self.phase, Phase::ShutDown | Phase::ShuttingDown)
    }

    /// The interrupt locks in force.
    pub const fn locks(&self) -> Locks {
        self.locks
    }

    /// The application mode `StartOS` was given.
    pub const fn app_mode(&self) -> AppMode {
        self.mode
    }

    /// The processor priority now: the innermost active ISR's (raised by its ceilings),
    /// else the running task's, else 0.
    #[inline]
    pub fn current_level(&self) -> u8 {
        match self.top_frame() {
            Some(frame) => frame.level,
            // 0 when no task runs: `finish` and `WaitEvent` clear it.
            None => self.running_prio,
        }
    }

    /// Highest priority with a ready (not running) activation.
    pub fn highest_ready(&self) -> Option<u8> {
        self.ready.highest()
    }

    /// Bitmap of priorities with ready activations (bit `p` for priority `p`).
    pub fn ready_bitmap(&self) -> u64 {
        self.ready.bitmap()
    }

    /// The ready activations at `prio`, oldest first.
    pub fn ready_at(&self, prio: u8) -> impl Iterator<Item = super::TaskId> + Clone + '_ {
        self.ready.iter(prio).map(super::TaskId)
    }

    /// Pending activations of a task, including the running or waiting one (0 if the id is
    /// invalid).
    pub fn activation_count(&self, task: super::TaskId) -> u8 {
        self.activations.get(task.0 as usize).copied().unwrap_or(0)
    }

    /// The state of a task (`None` for an invalid id); the inspection behind
    /// `GetTaskState`.
    pub fn task_state(&self, task: super::TaskId) -> Option<super::TaskState> {
        let t = task.0 as usize;
        if t >= T {
            return None;
        }
        Some(if self.running as usize == t {
            super::TaskState::Running
        } else if self.waiting[t] {
            super::TaskState::Waiting
        } else if self.activations[t] > 0 {
            super::TaskState::Ready
        } else {
            super::TaskState::Suspended
        })
    }

    /// The priority a task resumes at if preempted now, or starts at if not yet started.
    pub fn saved_priority(&self, task: super::TaskId) -> Option<u8> {
        self.saved_prio.get(task.0 as usize).copied()
    }

    /// Whether the task's current activation has begun executing (and so resumes rather
    /// than starts when dispatched).
    pub fn is_started(&self, task: super::TaskId) -> bool {
        self.started.get(task.0 as usize).copied().unwrap_or(false)
    }

    /// The events a waiting task waits for (0 unless waiting).
    pub fn wait_mask(&self, task: super::TaskId) -> EventMask {
        self.wait_mask.get(task.0 as usize).copied().unwrap_or(0)
    }

    /// Whether a task is blocked in `WaitEvent`.
    pub fn is_waiting(&self, task: super::TaskId) -> bool {
        self.waiting.get(task.0 as usize).copied().unwrap_or(false)
    }

    /// Events set for a task (whatever its kind or state; 0 for an invalid id).
    pub fn events(&self, task: super::TaskId) -> EventMask {
        self.events.get(task.0 as usize).copied().unwrap_or(0)
    }

    /// Number of ready-queue records of `task` (activations not running or waiting).
    pub fn queued_records(&self, task: super::TaskId) -> usize {
        self.ready
            .levels()
            .map(|p| self.ready.iter(p).filter(|t| *t == task.0).count())
            .sum()
    }

    /// The priority a task runs at when holding no resource: its own, or the
    /// `RES_SCHEDULER` ceiling for a non-preemptive task (its internal resource).
    pub fn dispatch_priority(&self, task: super::TaskId) -> Option<u8> {
        let t = task.0 as usize;
        (t < T).then(|| self.internal_prio(t))
    }

    /// `ErrorHook`'s `OSErrorGetServiceId()`: the service that failed, while `ErrorHook`
    /// runs (`None` elsewhere).
    pub const fn error_service_id(&self) -> Option<ServiceId> {
        match self.error_call {
            Some(call) => Some(call.id()),
            None => None,
        }
    }

    /// `ErrorHook`'s view of the failed call with its parameters (the
    /// `OSError_<Service>_<Param>()` macros), while `ErrorHook` runs.
    pub const fn error_call(&self) -> Option<ServiceCall> {
        self.error_call
    }

    // ---- shared helpers -----------------------------------------------------------------

    #[inline(always)]
    fn cfg(&self) -> &'static OsConfig<T, R, C, A, I> {
        self.cfg.get()
    }

    #[inline(always)]
    fn extended(&self) -> bool {
        matches!(self.cfg().status, super::Status::Extended)
    }

    #[inline(always)]
    fn task_index(id: super::TaskId) -> Result<usize, OsError> {
        let t = id.0 as usize;
        if t < T {
            Ok(t)
        } else {
            Err(OsError::Id)
        }
    }

    /// The running task, for a service only a task may call: the call-level check already
    /// refused every other context, so this only guards the index.
    #[inline(always)]
    fn calling_task(&self) -> Result<usize, OsError> {
        let t = self.running as usize;
        if t < T && matches!(self.context, Context::Task) {
            Ok(t)
        } else {
            Err(OsError::CallLevel)
        }
    }

    #[inline(always)]
    fn base_prio(&self, t: usize) -> u8 {
        // (`t` is a task index: the ready queue and the services hold only those.)
        self.cfg().priority.get(t).copied().unwrap_or(0)
    }

    #[inline(always)]
    fn internal_prio(&self, t: usize) -> u8 {
        self.cfg().dispatch_priority.get(t).copied().unwrap_or(0)
    }

    #[inline(always)]
    fn is_extended_task(&self, t: usize) -> bool {
        matches!(self.cfg().tasks[t].kind, TaskKind::Extended)
    }

    #[inline(always)]
    fn top_frame(&self) -> Option<&IsrFrame> {
        (self.isr_depth as usize)
            .checked_sub(1)
            .and_then(|i| self.isr_stack.get(i))
    }

    // ---- call levels and errors ---------------------------------------------------------

    /// The call-level and interrupt-lock check every service starts with: one test of the
    /// cached mask.
    #[inline(always)]
    fn check(&self, id: ServiceId) -> Result<(), OsError> {
        if self.denied & id.bit() == 0 {
            Ok(())
        } else {
            Err(self.refusal(id))
        }
    }

    /// Why `id` is refused now: not allowed in this context at all, or only because an
    /// interrupt lock is in force.
    #[cold]
    #[inline(never)]
    fn refusal(&self, id: ServiceId) -> OsError {
        if self.cfg().denied[self.context as usize] & id.bit() != 0 {
            OsError::CallLevel
        } else {
            OsError::DisabledInt
        }
    }

    /// Recomputes the cached refusal mask and interrupt gate after a change of context or
    /// phase.
    #[inline(always)]
    fn sync_denied(&mut self) {
        let cfg = self.cfg();
        let context = self.context as usize;
        self.denied = cfg.denied[context] | self.lock_denied;
        self.gate = if matches!(self.phase, Phase::Running) {
            cfg.context_gate[context].max(self.lock_gate)
        } else {
            u8::MAX
        };
    }

    /// Puts `locks` in force, with what they refuse and mask.
    fn set_locks(&mut self, locks: Locks) {
        self.locks = locks;
        self.lock_denied = if locks.any() { !INTERRUPT_SERVICES } else { 0 };
        self.lock_gate = if locks.masks_all() {
            u8::MAX
        } else if locks.suspend_os != 0 {
            self.cfg().os_level
        } else {
            0
        };
        self.sync_denied();
    }

    /// After the running task changed at task level: the context is `Task` or `Idle`.
    #[inline]
    fn sync_task_context(&mut self) {
        if matches!(self.context, Context::Task | Context::Idle) {
            let context = if self.running == NONE {
                Context::Idle
            } else {
                Context::Task
            };
            if context != self.context {
                self.context = context;
                self.sync_denied();
            }
        }
    }

    /// Runs service `id`'s body and reports its error, if any, to `ErrorHook`. The call's
    /// description (`call`) is only built on that path: the fast path must not pay for it.
    #[inline(always)]
    fn service<V>(
        &mut self,
        id: ServiceId,
        call: impl FnOnce() -> ServiceCall,
        body: impl FnOnce(&mut Self) -> Result<V, OsError>,
    ) -> Result<V, OsError> {
        let result = match self.check(id) {
            Ok(()) => body(self),
            Err(e) => Err(e),
        };
        match result {
            Ok(v) => Ok(v),
            Err(e) => Err(self.report_with(call, e)),
        }
    }

    /// The error path of [`Os::service`], out of line: the description of the call is built
    /// here, so the fast path only passes what the closure captured.
    #[cold]
    #[inline(never)]
    fn report_with(&mut self, call: impl FnOnce() -> ServiceCall, error: OsError) -> OsError {
        self.report(call(), error)
    }

    /// `ErrorHook` for the failed `call`, unless it is running already (OSEK: never
    /// recursively) or the OS is not running. Returns `error`.
    #[cold]
    #[inline(never)]
    fn report(&mut self, call: ServiceCall, error: OsError) -> OsError {
        let running = matches!(self.phase, Phase::Running | Phase::Starting);
        if self.cfg().hooks.error && self.error_call.is_none() && running {
            self.error_call = Some(call);
            self.call_hook(Context::ErrorHook, |os| H::error_hook(os, error));
            self.error_call = None;
        }
        error
    }

    /// Runs a hook routine at its call level. Interrupt locks the hook leaves behind are
    /// undone (reported to `ErrorHook` with `E_OS_DISABLEDINT`, unless it was `ErrorHook`).
    fn call_hook(&mut self, context: Context, hook: impl FnOnce(&mut Self)) {
        let (saved_context, saved_locks) = (self.context, self.locks);
        self.context = context;
        self.sync_denied();
        hook(self);
        if self.phase == Phase::ShutDown {
            return;
        }
        let unbalanced = self.locks != saved_locks;
        self.context = saved_context;
        if unbalanced {
            self.set_locks(saved_locks);
        } else {
            self.sync_denied();
        }
        if unbalanced && context != Context::ErrorHook {
            self.report(ServiceCall::HookMissingEnd, OsError::DisabledInt);
        }
    }

    // ---- scheduling ---------------------------------------------------------------------

    /// Records one more activation of `t` (OSEK: suspended -> ready, or a queued request).
    /// Returns the task's priority, which the caller needs for its scheduling decision.
    #[inline(always)]
    fn activate(&mut self, t: usize) -> Result<u8, OsError> {
        let count = self.activation_left(t)?;
        let prio = self.cfg().priority[t];
        self.ready
            .push_back(prio, t as u8)
            .map_err(|_| OsError::Limit)?;
        self.activations[t] = count + 1;
        Ok(prio)
    }

    /// Task `t`'s activations now, if one more is allowed (`E_OS_LIMIT` otherwise).
    #[inline(always)]
    fn activation_left(&self, t: usize) -> Result<u8, OsError> {
        let count = self.activations[t];
        if count >= self.cfg().max_activations[t] {
            return Err(OsError::Limit);
        }
        Ok(count)
    }

    /// The rescheduling point: keeps the running task unless a strictly higher priority is
    /// ready; then the running task becomes the oldest of its current priority.
    #[inline(always)]
    fn reschedule(&mut self) {
        self.sync_threshold();
        self.reschedule_in_sync();
    }

    /// [`Os::reschedule`] where the threshold is in sync already
    /// (`spec::threshold_synced`): a step that changed neither the context nor the running
    /// task's priority, only the ready queue (the tick's fast path where alarms are due).
    /// A switch syncs the threshold and the context itself.
    #[inline(always)]
    pub(super) fn reschedule_in_sync(&mut self) {
        let Some(top) = self.ready.highest() else {
            return;
        };
        if top >= self.preempt_at {
            self.switch_to(top, None);
        }
    }

    /// The preemption threshold the kernel keeps (the priority a task must reach to
    /// preempt), for `spec::threshold_synced`.
    pub(crate) const fn preemption_threshold(&self) -> u8 {
        self.preempt_at
    }

    /// The value `preempt_at` must hold.
    #[inline(always)]
    pub(crate) const fn threshold(&self) -> u8 {
        if self.isr_depth != 0 || !matches!(self.phase, Phase::Running) {
            u8::MAX
        } else if self.running == NONE {
            0
        } else {
            self.running_prio + 1
        }
    }

    #[inline(always)]
    fn sync_threshold(&mut self) {
        self.preempt_at = self.threshold();
    }

    /// Preempts the running task (if any) and dispatches the oldest task of `top` (or
    /// `activated`, below), with `PostTaskHook` and `PreTaskHook` around the switch. Kept
    /// out of line: the common decision "keep running" must not pay for it.
    ///
    /// `activated`: a task `ActivateTask` activated that goes to the processor at once,
    /// without a ready-queue record. That is the same switch where the queue at its
    /// priority is empty (the running task was a highest-priority one, below it) and
    /// nothing runs between the activation and the switch (no `PostTaskHook`): its record
    /// would be queued and taken again at once.
    #[inline(never)]
    fn switch_to(&mut self, top: u8, activated: Option<u8>) {
        if self.running != NONE && !self.post_task_hook() {
            return;
        }
        self.preempt_running();
        match activated {
            Some(t) => self.run(usize::from(t)),
            None => self.dispatch(top),
        }
        self.switched();
    }

    /// The running task (if any) leaves the processor for the head of its priority's
    /// queue (its `PostTaskHook` has run).
    #[inline(always)]
    fn preempt_running(&mut self) {
        if self.running != NONE {
            let r = self.running as usize;
            if let Some(saved) = self.saved_prio.get_mut(r) {
                *saved = self.running_prio;
            }
            // The running task's own record returns to the pool, so there is room for it.
            let _ = self.ready.push_front(self.running_prio, r as u8);
            self.running = NONE;
        }
    }

    /// After a task switch: the threshold and the call level follow the new running task,
    /// then its `PreTaskHook`.
    #[inline(always)]
    fn switched(&mut self) {
        self.sync_threshold();
        self.sync_task_context();
        // Not in Kani builds: there the proofs check every invariant after every step, and
        // this second check inside each dispatch triples the cost of a proof (the book: `docs/src/kani.md`).
        #[cfg(not(kani))]
        debug_assert!(super::spec::kernel_invariants(self));
        self.pre_task_hook();
    }

    /// `PreTaskHook`, if configured, for the task just dispatched.
    fn pre_task_hook(&mut self) {
        if self.running != NONE && self.cfg().hooks.pre_task {
            self.call_hook(Context::PreTaskHook, |os| H::pre_task_hook(os));
        }
    }

    /// `PostTaskHook`, if configured, for the running task about to leave the running
    /// state. Returns `false` when the OS was shut down inside it.
    fn post_task_hook(&mut self) -> bool {
        if self.cfg().hooks.post_task {
            self.call_hook(Context::PostTaskHook, |os| H::post_task_hook(os));
        }
        !self.is_shut_down()
    }

    #[inline(always)]
    fn dispatch(&mut self, top: u8) {
        let Some(t) = self.ready.pop_front(top) else {
            return;
        };
        self.run(t as usize);
    }

    /// Task `ti` becomes the running task: it resumes at the priority it was preempted at,
    /// or starts at its dispatch priority.
    #[inline(always)]
    fn run(&mut self, ti: usize) {
        self.running = ti as u8;
        let internal = self.internal_prio(ti);
        let saved = self.saved_prio.get(ti).copied().unwrap_or(0);
        self.running_prio = match self.started.get_mut(ti) {
            // Resuming: keep the ceiling it was preempted at.
            Some(true) => saved.max(internal),
            Some(started) => {
                *started = true;
                internal
            }
            None => internal,
        };
    }

    /// Ends the running instance of `t`.
    fn finish(&mut self, t: usize) {
        self.activations[t] = self.activations[t].saturating_sub(1);
        if self.activations[t] == 0 {
            // OSEK clears an extended task's events when it is next activated from the
            // suspended state. Events cannot be set while it is suspended (E_OS_STATE), so
            // clearing them here, as it becomes suspended, is the same and keeps the
            // activation path short.
            self.events[t] = 0;
        }
        self.started[t] = false;
        self.saved_prio[t] = self.base_prio(t);
        self.running = NONE;
        self.running_prio = 0;
    }
}
