//! The kernel state and the OSEK services. See the module documentation of [`crate::os`]
//! for the rules and the choices made where the standards leave room.
//!
//! Representation:
//! - activation records live in a [`ReadyQueue`] (O(1) push, pop and highest-priority
//!   lookup); the running task's record is out of the queue while it runs;
//! - each task's held resources form a LIFO stack threaded through the resources
//!   (`res_top[task]` and `ResState::next`), so `ReleaseResource` out of order is detected in
//!   O(1);
//! - each counter keeps its armed alarms in a delta list: an alarm's delta is the number of
//!   ticks after its predecessor's expiry. A tick with nothing due decrements one number and
//!   compares it: O(1) whatever the number of alarms.

use super::config::{cycle_ok, AlarmAction, AlarmAutostart, ConfigError, OsConfig, TaskKind};
use super::queue::ReadyQueue;
use super::{
    AlarmId, CounterId, EventMask, OsError, ResourceId, TaskId, TaskState, TickType, RES_SCHEDULER,
};
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

/// What one counter tick did besides moving alarms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TickReport {
    /// Alarm callbacks that expired, one bit per callback id; the board runs them now.
    pub callbacks: u32,
    /// Alarm actions that failed (e.g. `E_OS_LIMIT` activating a task already at its limit).
    pub failed_actions: u8,
    /// The last such failure.
    pub last_failure: Option<OsError>,
}

impl TickReport {
    fn record(&mut self, result: Result<(), OsError>) {
        if let Err(e) = result {
            self.failed_actions = self.failed_actions.saturating_add(1);
            self.last_failure = Some(e);
        }
    }
}

/// One resource's dynamic state: its holder, the holder's priority before taking it, and
/// the next resource down the holder's stack.
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

/// Who is calling a service.
#[derive(Clone, Copy)]
enum Caller {
    Task(usize),
    /// Interrupt level, or no task running.
    Isr,
}

/// The configuration, compared by identity: two kernels are equal only if they run the same
/// configuration object, and hashing the state need not hash the tables.
#[derive(Clone, Copy)]
struct CfgRef<const T: usize, const R: usize, const C: usize, const A: usize, K>(K);

impl<const T: usize, const R: usize, const C: usize, const A: usize, K> CfgRef<T, R, C, A, K>
where
    K: Tables<OsConfig<T, R, C, A>>,
{
    #[inline(always)]
    fn get(self) -> &'static OsConfig<T, R, C, A> {
        self.0.tables()
    }
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, K> PartialEq
    for CfgRef<T, R, C, A, K>
where
    K: Tables<OsConfig<T, R, C, A>>,
{
    fn eq(&self, other: &Self) -> bool {
        core::ptr::eq(self.get(), other.get())
    }
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, K> Eq for CfgRef<T, R, C, A, K> where
    K: Tables<OsConfig<T, R, C, A>>
{
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, K> Hash
    for CfgRef<T, R, C, A, K>
{
    fn hash<H: Hasher>(&self, _state: &mut H) {}
}
impl<const T: usize, const R: usize, const C: usize, const A: usize, K> core::fmt::Debug
    for CfgRef<T, R, C, A, K>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("OsConfig")
    }
}

/// The OSEK kernel state for a configuration of `T` tasks, `R` resources, `C` counters and
/// `A` alarms, with `Q` ready-queue entries (the sum of all tasks' activations).
///
/// `K` is where the configuration comes from ([`Tables`]): a `&'static OsConfig`, or a
/// zero-sized type that makes it a build-time constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Os<
    const T: usize,
    const R: usize,
    const C: usize,
    const A: usize,
    const Q: usize,
    K = &'static OsConfig<T, R, C, A>,
> where
    K: Tables<OsConfig<T, R, C, A>>,
{
    cfg: CfgRef<T, R, C, A, K>,
    ready: ReadyQueue<Q>,
    running: u8,
    running_prio: u8,
    /// Cached scheduling threshold: a ready priority at or above it preempts. 0 when idle,
    /// the running priority + 1 when a task runs, `u8::MAX` at interrupt level (nothing
    /// preempts there). Derived from `running`, `running_prio` and `isr_depth` by
    /// `sync_threshold` after every change to them, so the hot paths decide with one
    /// comparison.
    preempt_at: u8,
    isr_depth: u8,
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
    alarm_delta: [u64; A],
    alarm_next: [u8; A],
    alarm_cycle: [TickType; A],
}

impl<const T: usize, const R: usize, const C: usize, const A: usize, const Q: usize, K>
    Os<T, R, C, A, Q, K>
where
    K: Tables<OsConfig<T, R, C, A>>,
{
    /// A kernel for `cfg`, before `StartOS`: no task is active, no alarm armed.
    ///
    /// # Errors
    /// [`ConfigError::QueueCapacity`] unless `Q` equals the configuration's total
    /// activations (and is at most 255).
    pub fn new(tables: K) -> Result<Self, ConfigError> {
        let cfg = tables.tables();
        if Q != cfg.total_activations || Q > 255 {
            return Err(ConfigError::QueueCapacity {
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
            preempt_at: 0,
            isr_depth: 0,
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
        })
    }

    /// `StartOS`: activates the autostart tasks (in table order), arms the autostart alarms,
    /// and dispatches the highest-priority task.
    ///
    /// # Errors
    /// `E_OS_STATE` if called again after tasks or alarms are already active.
    pub fn start(&mut self) -> Result<(), OsError> {
        if self.running != NONE || self.ready.bitmap() != 0 || self.alarm_active.iter().any(|a| *a)
        {
            return Err(OsError::State);
        }
        let cfg = self.cfg.get();
        for t in 0..T {
            if cfg.tasks[t].autostart {
                self.activate(t)?;
            }
        }
        for a in 0..A {
            let alarm = &cfg.alarms[a];
            let c = alarm.counter.0 as usize;
            match alarm.autostart {
                AlarmAutostart::Off => {}
                AlarmAutostart::Relative { increment, cycle } => {
                    self.arm(a, c, u64::from(increment), cycle);
                }
                AlarmAutostart::Absolute { start, cycle } => {
                    let delay = self.abs_delay(c, start);
                    self.arm(a, c, delay, cycle);
                }
            }
        }
        self.reschedule();
        Ok(())
    }

    // ---- inspection ---------------------------------------------------------------------

    /// The configuration.
    #[inline(always)]
    pub fn config(&self) -> &'static OsConfig<T, R, C, A> {
        self.cfg.get()
    }

    /// The task the kernel has chosen to run (OSEK `GetTaskID` at task level).
    #[inline]
    pub const fn running(&self) -> Option<TaskId> {
        if self.running == NONE {
            None
        } else {
            Some(TaskId(self.running))
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

    /// Highest priority with a ready (not running) activation.
    pub fn highest_ready(&self) -> Option<u8> {
        self.ready.highest()
    }

    /// Bitmap of priorities with ready activations (bit `p` for priority `p`).
    pub fn ready_bitmap(&self) -> u64 {
        self.ready.bitmap()
    }

    /// The ready activations at `prio`, oldest first.
    pub fn ready_at(&self, prio: u8) -> impl Iterator<Item = TaskId> + Clone + '_ {
        self.ready.iter(prio).map(TaskId)
    }

    /// Pending activations of a task, including the running or waiting one (0 if the id is
    /// invalid).
    pub fn activation_count(&self, task: TaskId) -> u8 {
        self.activations.get(task.0 as usize).copied().unwrap_or(0)
    }

    /// The priority a task resumes at if preempted now, or starts at if not yet started.
    pub fn saved_priority(&self, task: TaskId) -> Option<u8> {
        self.saved_prio.get(task.0 as usize).copied()
    }

    /// Whether the task's current activation has begun executing (and so resumes rather
    /// than starts when dispatched).
    pub fn is_started(&self, task: TaskId) -> bool {
        self.started.get(task.0 as usize).copied().unwrap_or(false)
    }

    /// The events a waiting task waits for (0 unless waiting).
    pub fn wait_mask(&self, task: TaskId) -> EventMask {
        self.wait_mask.get(task.0 as usize).copied().unwrap_or(0)
    }

    /// Nesting depth of interrupt level (0: task level).
    pub const fn isr_depth(&self) -> u8 {
        self.isr_depth
    }

    /// The holder of a resource, or `None` if free or the id is invalid.
    pub fn resource_owner(&self, res: ResourceId) -> Option<TaskId> {
        let state = self.res_state(res).ok()?;
        (state.owner != NONE).then_some(TaskId(state.owner))
    }

    /// The resources a task holds, most recently taken first.
    pub fn held_resources(&self, task: TaskId) -> impl Iterator<Item = ResourceId> + '_ {
        let mut top = self.res_top.get(task.0 as usize).copied().unwrap_or(NO_RES);
        core::iter::from_fn(move || {
            let id = ResourceId(top);
            let state = self.res_state(id).ok()?;
            top = state.next;
            Some(id)
        })
    }

    /// The ceiling of a resource.
    pub fn ceiling(&self, res: ResourceId) -> Option<u8> {
        if res == RES_SCHEDULER {
            Some(self.cfg.get().scheduler_ceiling)
        } else {
            self.cfg.get().resource_ceiling(res.0 as usize)
        }
    }

    /// The priority a task runs at when holding no resource: its own, or the
    /// `RES_SCHEDULER` ceiling for a non-preemptive task (its internal resource).
    pub fn dispatch_priority(&self, task: TaskId) -> Option<u8> {
        let t = task.0 as usize;
        (t < T).then(|| self.internal_prio(t))
    }

    /// A counter's current value.
    pub fn counter_value(&self, counter: CounterId) -> Option<TickType> {
        self.counter_value.get(counter.0 as usize).copied()
    }

    // ---- helpers ------------------------------------------------------------------------

    #[inline(always)]
    fn task_index(id: TaskId) -> Result<usize, OsError> {
        let t = id.0 as usize;
        if t < T {
            Ok(t)
        } else {
            Err(OsError::Id)
        }
    }

    #[inline(always)]
    fn caller(&self) -> Caller {
        if self.isr_depth == 0 && (self.running as usize) < T {
            Caller::Task(self.running as usize)
        } else {
            Caller::Isr
        }
    }

    #[inline(always)]
    fn task_caller(&self) -> Result<usize, OsError> {
        match self.caller() {
            Caller::Task(t) => Ok(t),
            Caller::Isr => Err(OsError::CallLevel),
        }
    }

    #[inline(always)]
    fn base_prio(&self, t: usize) -> u8 {
        self.cfg.get().priority[t]
    }

    #[inline(always)]
    fn internal_prio(&self, t: usize) -> u8 {
        self.cfg.get().dispatch_priority[t]
    }

    #[inline(always)]
    fn is_extended(&self, t: usize) -> bool {
        matches!(self.cfg.get().tasks[t].kind, TaskKind::Extended)
    }

    fn res_state(&self, id: ResourceId) -> Result<&ResState, OsError> {
        if id == RES_SCHEDULER {
            Ok(&self.sched_res)
        } else {
            self.res.get(id.0 as usize).ok_or(OsError::Id)
        }
    }

    fn res_state_mut(&mut self, id: ResourceId) -> Result<&mut ResState, OsError> {
        if id == RES_SCHEDULER {
            Ok(&mut self.sched_res)
        } else {
            self.res.get_mut(id.0 as usize).ok_or(OsError::Id)
        }
    }

    /// Records one more activation of `t` (OSEK: suspended -> ready, or a queued request).
    /// Returns the task's priority, which the caller needs for its scheduling decision.
    #[inline(always)]
    fn activate(&mut self, t: usize) -> Result<u8, OsError> {
        let cfg = self.cfg.get();
        let (count, max, prio) = (self.activations[t], cfg.max_activations[t], cfg.priority[t]);
        if count >= max {
            return Err(OsError::Limit);
        }
        self.ready
            .push_back(prio, t as u8)
            .map_err(|_| OsError::Limit)?;
        self.activations[t] = count + 1;
        Ok(prio)
    }

    /// The rescheduling point: keeps the running task unless a strictly higher priority is
    /// ready; then the running task becomes the oldest of its current priority.
    #[inline(always)]
    fn reschedule(&mut self) {
        self.sync_threshold();
        let Some(top) = self.ready.highest() else {
            return;
        };
        if top >= self.preempt_at {
            self.switch_to(top);
        }
    }

    /// The value `preempt_at` must hold.
    #[inline(always)]
    const fn threshold(&self) -> u8 {
        if self.isr_depth != 0 {
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

    /// Preempts the running task (if any) and dispatches the oldest task of `top`. Kept out
    /// of line: the common decision "keep running" must not pay for it.
    #[inline(never)]
    fn switch_to(&mut self, top: u8) {
        if self.running != NONE {
            let r = self.running as usize;
            self.saved_prio[r] = self.running_prio;
            // The running task's own record returns to the pool, so there is room for it.
            let _ = self.ready.push_front(self.running_prio, r as u8);
            self.running = NONE;
        }
        self.dispatch(top);
        self.sync_threshold();
        debug_assert!(super::spec::kernel_invariants(self));
    }

    #[inline(always)]
    fn dispatch(&mut self, top: u8) {
        let Some(t) = self.ready.pop_front(top) else {
            return;
        };
        let ti = t as usize;
        self.running = t;
        let internal = self.internal_prio(ti);
        self.running_prio = if self.started[ti] {
            // Resuming: keep the ceiling it was preempted at.
            if self.saved_prio[ti] > internal {
                self.saved_prio[ti]
            } else {
                internal
            }
        } else {
            self.started[ti] = true;
            internal
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

    // ---- task management (OSEK §13.2) ---------------------------------------------------

    /// `ActivateTask`: one more activation of `task`; it preempts the caller if it has a
    /// higher priority (at task level).
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_LIMIT` the task already has `max_activations`.
    #[inline]
    pub fn activate_task(&mut self, task: TaskId) -> Result<(), OsError> {
        let t = Self::task_index(task)?;
        let prio = self.activate(t)?;
        // The running task was a highest-priority one before the call (the invariant), so the
        // only entry that can outrank it now is the one just queued: compare with that
        // priority instead of searching the bitmap.
        debug_assert_eq!(self.preempt_at, self.threshold());
        if prio >= self.preempt_at {
            self.switch_to(prio);
        }
        Ok(())
    }

    /// `TerminateTask`: ends the calling task. On success the board must stop executing it.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_RESOURCE` the task holds a resource.
    pub fn terminate_task(&mut self) -> Result<(), OsError> {
        let t = self.task_caller()?;
        if self.res_top[t] != NO_RES {
            return Err(OsError::Resource);
        }
        self.finish(t);
        self.reschedule();
        Ok(())
    }

    /// `ChainTask`: ends the calling task and activates `task` (itself included, which
    /// re-queues it as the newest of its priority).
    ///
    /// # Errors
    /// `E_OS_CALLEVEL`, `E_OS_RESOURCE` as for `TerminateTask`; `E_OS_ID` invalid task;
    /// `E_OS_LIMIT` the successor is at its activation limit (the caller keeps running).
    pub fn chain_task(&mut self, task: TaskId) -> Result<(), OsError> {
        let t = self.task_caller()?;
        if self.res_top[t] != NO_RES {
            return Err(OsError::Resource);
        }
        let n = Self::task_index(task)?;
        if n != t && self.activations[n] >= self.cfg.get().max_activations[n] {
            return Err(OsError::Limit);
        }
        self.finish(t);
        self.activate(n)?;
        self.reschedule();
        Ok(())
    }

    /// `Schedule`: lets higher-priority ready tasks run; for a non-preemptive task this is
    /// the point where it may be preempted.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_RESOURCE` the task holds a resource.
    pub fn schedule(&mut self) -> Result<(), OsError> {
        let t = self.task_caller()?;
        if self.res_top[t] != NO_RES {
            return Err(OsError::Resource);
        }
        // Release the internal resource (non-preemption) for the decision, then take it back
        // if the task keeps the processor.
        self.running_prio = self.base_prio(t);
        self.reschedule();
        if self.running as usize == t {
            self.running_prio = self.internal_prio(t);
            self.sync_threshold();
        }
        Ok(())
    }

    /// `GetTaskID`: the running task (at interrupt level: the interrupted one), if any.
    pub const fn get_task_id(&self) -> Option<TaskId> {
        self.running()
    }

    /// `GetTaskState`.
    ///
    /// # Errors
    /// `E_OS_ID` invalid task.
    pub fn get_task_state(&self, task: TaskId) -> Result<TaskState, OsError> {
        let t = Self::task_index(task)?;
        Ok(if self.running as usize == t {
            TaskState::Running
        } else if self.waiting[t] {
            TaskState::Waiting
        } else if self.activations[t] > 0 {
            TaskState::Ready
        } else {
            TaskState::Suspended
        })
    }

    // ---- events (OSEK §13.5) ------------------------------------------------------------

    fn set_event_inner(&mut self, t: usize, mask: EventMask) -> Result<(), OsError> {
        if !self.is_extended(t) {
            return Err(OsError::Access);
        }
        if self.activations[t] == 0 {
            return Err(OsError::State);
        }
        self.events[t] |= mask;
        if self.waiting[t] && self.events[t] & self.wait_mask[t] != 0 {
            self.waiting[t] = false;
            self.wait_mask[t] = 0;
            self.saved_prio[t] = self.base_prio(t);
            self.ready
                .push_back(self.base_prio(t), t as u8)
                .map_err(|_| OsError::Limit)?;
        }
        Ok(())
    }

    /// `SetEvent`: sets events of an extended task; a task waiting for any of them becomes
    /// ready (the newest of its priority).
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_ACCESS` not an extended task; `E_OS_STATE` the task is
    /// suspended.
    pub fn set_event(&mut self, task: TaskId, mask: EventMask) -> Result<(), OsError> {
        let t = Self::task_index(task)?;
        self.set_event_inner(t, mask)?;
        self.reschedule();
        Ok(())
    }

    /// `ClearEvent`: clears events of the calling extended task.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_ACCESS` the caller is a basic task.
    pub fn clear_event(&mut self, mask: EventMask) -> Result<(), OsError> {
        let t = self.task_caller()?;
        if !self.is_extended(t) {
            return Err(OsError::Access);
        }
        self.events[t] &= !mask;
        Ok(())
    }

    /// `GetEvent`: the events set for an extended task.
    ///
    /// # Errors
    /// `E_OS_ID` invalid task; `E_OS_ACCESS` not an extended task; `E_OS_STATE` suspended.
    pub fn get_event(&self, task: TaskId) -> Result<EventMask, OsError> {
        let t = Self::task_index(task)?;
        if !self.is_extended(t) {
            return Err(OsError::Access);
        }
        if self.activations[t] == 0 {
            return Err(OsError::State);
        }
        Ok(self.events[t])
    }

    /// `WaitEvent`: the calling extended task waits until one of `mask` is set; returns at
    /// once if one already is.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` not called by a task; `E_OS_ACCESS` basic task; `E_OS_RESOURCE` the
    /// task holds a resource.
    pub fn wait_event(&mut self, mask: EventMask) -> Result<(), OsError> {
        let t = self.task_caller()?;
        if !self.is_extended(t) {
            return Err(OsError::Access);
        }
        if self.res_top[t] != NO_RES {
            return Err(OsError::Resource);
        }
        if self.events[t] & mask != 0 {
            return Ok(());
        }
        self.waiting[t] = true;
        self.wait_mask[t] = mask;
        self.saved_prio[t] = self.base_prio(t);
        self.running = NONE;
        self.running_prio = 0;
        self.reschedule();
        Ok(())
    }

    // ---- resources (OSEK §13.4) ---------------------------------------------------------

    /// The checks `GetResource` and `ReleaseResource` share: `E_OS_ID` for an unknown
    /// resource, `E_OS_ACCESS` when the caller's static priority is above the ceiling (an
    /// ISR's always is). Returns the calling task and the ceiling.
    fn resource_caller(&self, res: ResourceId) -> Result<(usize, u8), OsError> {
        let ceiling = self.ceiling(res).ok_or(OsError::Id)?;
        match self.caller() {
            Caller::Task(t) if self.base_prio(t) <= ceiling => Ok((t, ceiling)),
            _ => Err(OsError::Access),
        }
    }

    /// `GetResource`: takes a resource, raising the caller to its ceiling.
    ///
    /// # Errors
    /// `E_OS_ID` invalid resource; `E_OS_ACCESS` the resource is occupied, or the caller's
    /// static priority is above its ceiling (always so at interrupt level).
    pub fn get_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        let (t, ceiling) = self.resource_caller(res)?;
        let running_prio = self.running_prio;
        let top = self.res_top[t];
        let state = self.res_state_mut(res)?;
        if state.owner != NONE {
            return Err(OsError::Access);
        }
        *state = ResState {
            owner: t as u8,
            prev_prio: running_prio,
            next: top,
        };
        self.res_top[t] = res.0;
        if ceiling > self.running_prio {
            self.running_prio = ceiling;
            self.sync_threshold();
        }
        Ok(())
    }

    /// `ReleaseResource`: releases the most recently taken resource and restores the
    /// priority the caller had before taking it.
    ///
    /// # Errors
    /// `E_OS_ID` invalid resource; `E_OS_ACCESS` the caller's static priority is above the
    /// ceiling (always so at interrupt level); `E_OS_NOFUNC` the caller does not hold it, or
    /// another resource must be released first.
    pub fn release_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        let (t, _) = self.resource_caller(res)?;
        if self.res_top[t] != res.0 {
            return Err(OsError::NoFunc);
        }
        let state = self.res_state_mut(res)?;
        let released = *state;
        *state = FREE_RES;
        self.res_top[t] = released.next;
        self.running_prio = released.prev_prio;
        self.reschedule();
        Ok(())
    }

    // ---- interrupt level ----------------------------------------------------------------

    /// Enters a category-2 ISR: rescheduling is deferred until the outermost ISR exits.
    ///
    /// # Errors
    /// `E_OS_LIMIT` beyond 255 nesting levels.
    pub fn enter_isr(&mut self) -> Result<(), OsError> {
        self.isr_depth = self.isr_depth.checked_add(1).ok_or(OsError::Limit)?;
        self.sync_threshold();
        Ok(())
    }

    /// Leaves a category-2 ISR; leaving the outermost one is a rescheduling point.
    ///
    /// # Errors
    /// `E_OS_CALLEVEL` when not at interrupt level.
    pub fn exit_isr(&mut self) -> Result<(), OsError> {
        self.isr_depth = self.isr_depth.checked_sub(1).ok_or(OsError::CallLevel)?;
        self.reschedule();
        Ok(())
    }

    // ---- counters and alarms (OSEK §13.6, AUTOSAR IncrementCounter) ---------------------

    fn alarm_index(id: AlarmId) -> Result<usize, OsError> {
        let a = id.0 as usize;
        if a < A {
            Ok(a)
        } else {
            Err(OsError::Id)
        }
    }

    fn alarm_counter(&self, a: usize) -> usize {
        self.cfg.get().alarms[a].counter.0 as usize
    }

    /// Ticks from now until the counter of `c` next shows `start` (a full revolution if it
    /// shows it now).
    fn abs_delay(&self, c: usize, start: TickType) -> u64 {
        let modulus = u64::from(self.cfg.get().counters[c].max_allowed_value) + 1;
        let now = u64::from(self.counter_value[c]);
        let delay = (u64::from(start) + modulus - now) % modulus;
        if delay == 0 {
            modulus
        } else {
            delay
        }
    }

    /// Inserts alarm `a` into counter `c`'s delta list, `delay >= 1` ticks from now, after
    /// any alarm due at the same tick.
    fn arm(&mut self, a: usize, c: usize, delay: u64, cycle: TickType) {
        let mut prev = NONE;
        let mut node = self.counter_head[c];
        let mut rest = delay;
        while (node as usize) < A && rest >= self.alarm_delta[node as usize] {
            rest -= self.alarm_delta[node as usize];
            prev = node;
            node = self.alarm_next[node as usize];
        }
        self.alarm_delta[a] = rest;
        self.alarm_next[a] = node;
        if (prev as usize) < A {
            self.alarm_next[prev as usize] = a as u8;
        } else {
            self.counter_head[c] = a as u8;
        }
        if (node as usize) < A {
            self.alarm_delta[node as usize] -= rest;
        }
        self.alarm_active[a] = true;
        self.alarm_cycle[a] = cycle;
    }

    /// Removes armed alarm `a` from its counter's delta list.
    fn disarm(&mut self, a: usize) {
        let c = self.alarm_counter(a);
        let next = self.alarm_next[a];
        if (next as usize) < A {
            self.alarm_delta[next as usize] += self.alarm_delta[a];
        }
        if self.counter_head[c] as usize == a {
            self.counter_head[c] = next;
        } else {
            let mut node = self.counter_head[c];
            while (node as usize) < A {
                if self.alarm_next[node as usize] as usize == a {
                    self.alarm_next[node as usize] = next;
                    break;
                }
                node = self.alarm_next[node as usize];
            }
        }
        self.alarm_active[a] = false;
        self.alarm_delta[a] = 0;
        self.alarm_next[a] = NONE;
        self.alarm_cycle[a] = 0;
    }

    /// `GetAlarmBase`.
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm.
    pub fn get_alarm_base(&self, alarm: AlarmId) -> Result<AlarmBase, OsError> {
        let a = Self::alarm_index(alarm)?;
        let k = &self.cfg.get().counters[self.alarm_counter(a)];
        Ok(AlarmBase {
            max_allowed_value: k.max_allowed_value,
            ticks_per_base: k.ticks_per_base,
            min_cycle: k.min_cycle,
        })
    }

    /// `GetAlarm`: ticks left before the alarm expires.
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm; `E_OS_NOFUNC` the alarm is not armed.
    pub fn get_alarm(&self, alarm: AlarmId) -> Result<u64, OsError> {
        let a = Self::alarm_index(alarm)?;
        if !self.alarm_active[a] {
            return Err(OsError::NoFunc);
        }
        let mut node = self.counter_head[self.alarm_counter(a)];
        let mut ticks = 0u64;
        while (node as usize) < A {
            ticks += self.alarm_delta[node as usize];
            if node as usize == a {
                break;
            }
            node = self.alarm_next[node as usize];
        }
        Ok(ticks)
    }

    /// The checks `SetRelAlarm` and `SetAbsAlarm` share: `E_OS_ID` for an unknown alarm,
    /// `E_OS_STATE` for an armed one. Returns the alarm and its counter.
    fn unarmed_alarm(&self, alarm: AlarmId) -> Result<(usize, usize), OsError> {
        let a = Self::alarm_index(alarm)?;
        if self.alarm_active[a] {
            return Err(OsError::State);
        }
        Ok((a, self.alarm_counter(a)))
    }

    /// `SetRelAlarm`: arms the alarm `increment` ticks from now, then every `cycle` ticks
    /// (0: once).
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm; `E_OS_STATE` already armed; `E_OS_VALUE` increment not in
    /// `1 ..= maxallowedvalue`, or cycle neither 0 nor in `mincycle ..= maxallowedvalue`.
    pub fn set_rel_alarm(
        &mut self,
        alarm: AlarmId,
        increment: TickType,
        cycle: TickType,
    ) -> Result<(), OsError> {
        let (a, c) = self.unarmed_alarm(alarm)?;
        let k = &self.cfg.get().counters[c];
        if increment == 0 || increment > k.max_allowed_value || !cycle_ok(k, cycle) {
            return Err(OsError::Value);
        }
        self.arm(a, c, u64::from(increment), cycle);
        Ok(())
    }

    /// `SetAbsAlarm`: arms the alarm to expire when the counter next reaches `start`, then
    /// every `cycle` ticks (0: once).
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm; `E_OS_STATE` already armed; `E_OS_VALUE` start above
    /// `maxallowedvalue`, or cycle neither 0 nor in `mincycle ..= maxallowedvalue`.
    pub fn set_abs_alarm(
        &mut self,
        alarm: AlarmId,
        start: TickType,
        cycle: TickType,
    ) -> Result<(), OsError> {
        let (a, c) = self.unarmed_alarm(alarm)?;
        let k = &self.cfg.get().counters[c];
        if start > k.max_allowed_value || !cycle_ok(k, cycle) {
            return Err(OsError::Value);
        }
        let delay = self.abs_delay(c, start);
        self.arm(a, c, delay, cycle);
        Ok(())
    }

    /// `CancelAlarm`.
    ///
    /// # Errors
    /// `E_OS_ID` invalid alarm; `E_OS_NOFUNC` the alarm is not armed.
    pub fn cancel_alarm(&mut self, alarm: AlarmId) -> Result<(), OsError> {
        let a = Self::alarm_index(alarm)?;
        if !self.alarm_active[a] {
            return Err(OsError::NoFunc);
        }
        self.disarm(a);
        Ok(())
    }

    /// `IncrementCounter`: advances a counter by one tick and runs the actions of the alarms
    /// that expire. At task level this is a rescheduling point.
    ///
    /// # Errors
    /// `E_OS_ID` invalid counter.
    #[inline]
    pub fn increment_counter(&mut self, counter: CounterId) -> Result<TickReport, OsError> {
        let c = counter.0 as usize;
        if c >= C {
            return Err(OsError::Id);
        }
        let max = self.cfg.get().counters[c].max_allowed_value;
        let value = self.counter_value[c];
        self.counter_value[c] = if value >= max { 0 } else { value + 1 };
        let head = self.counter_head[c] as usize;
        if head >= A {
            return Ok(TickReport::default());
        }
        // The head's delta is at least 1 between ticks.
        self.alarm_delta[head] = self.alarm_delta[head].saturating_sub(1);
        if self.alarm_delta[head] != 0 {
            return Ok(TickReport::default());
        }
        let report = self.expire(c);
        self.reschedule();
        Ok(report)
    }

    /// Pops and runs every alarm of counter `c` that is due now.
    #[inline(never)]
    fn expire(&mut self, c: usize) -> TickReport {
        let mut report = TickReport::default();
        loop {
            let a = self.counter_head[c] as usize;
            if a >= A || self.alarm_delta[a] != 0 {
                break;
            }
            let cycle = self.alarm_cycle[a];
            self.counter_head[c] = self.alarm_next[a];
            self.alarm_next[a] = NONE;
            self.alarm_active[a] = false;
            self.alarm_cycle[a] = 0;
            if cycle != 0 {
                self.arm(a, c, u64::from(cycle), cycle);
            }
            match self.cfg.get().alarms[a].action {
                AlarmAction::ActivateTask(task) => {
                    let result = Self::task_index(task).and_then(|t| self.activate(t).map(|_| ()));
                    report.record(result);
                }
                AlarmAction::SetEvent(task, mask) => {
                    let result = Self::task_index(task).and_then(|t| self.set_event_inner(t, mask));
                    report.record(result);
                }
                AlarmAction::Callback(id) => report.callbacks |= 1u32 << (id & 31),
            }
        }
        report
    }

    /// Whether an alarm is armed.
    pub fn alarm_armed(&self, alarm: AlarmId) -> bool {
        self.alarm_active
            .get(alarm.0 as usize)
            .copied()
            .unwrap_or(false)
    }

    /// Number of ready-queue records of `task` (activations not running or waiting).
    pub fn queued_records(&self, task: TaskId) -> usize {
        let mut levels = self.ready.bitmap();
        let mut n = 0;
        while levels != 0 {
            let p = levels.trailing_zeros() as u8;
            n += self.ready.iter(p).filter(|t| *t == task.0).count();
            levels &= levels - 1;
        }
        n
    }

    /// Whether a task is blocked in `WaitEvent`.
    pub fn is_waiting(&self, task: TaskId) -> bool {
        self.waiting.get(task.0 as usize).copied().unwrap_or(false)
    }

    /// Events set for a task (whatever its kind or state; 0 for an invalid id).
    pub fn events(&self, task: TaskId) -> EventMask {
        self.events.get(task.0 as usize).copied().unwrap_or(0)
    }
}
