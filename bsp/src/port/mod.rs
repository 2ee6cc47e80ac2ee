//! The OS port: what lets the same ECU code run with real preemption on a microcontroller
//! and with nested calls in the host simulation.
//!
//! The kernel (`cw_core::os::Os`) keeps the logical state: who runs, who is ready, which
//! resources are held, which interrupts are masked. A port carries its decisions out on a
//! board: it runs kernel services under the kernel lock, applies the kernel's interrupt
//! mask, and switches to the task the kernel chose. Two ports implement [`Port`]:
//!
//! - the host port ([`crate::host::HostPort`]): tasks are nested calls on one stack, and
//!   interrupts are taken between them;
//! - the Cortex-M port (`crate::cortex_m`, built for `thumbv7em` targets only): PendSV switches
//!   stacks, SysTick and the peripherals' interrupts arrive at any instruction.
//!
//! State that several tasks and ISRs share lives in a [`Resource`]: it is reachable only
//! while the caller holds the OSEK resource of that id (`GetResource` succeeded), whose
//! ceiling the configuration derives from the tasks and ISRs that declare it. State that
//! one task alone uses lives in a [`TaskLocal`].

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use cw_core::os::{
    CounterId, Hooks, InterruptMask, IsrConfig, IsrId, Os, OsConfig, OsError, ResourceId,
    TaskConfig, TaskId, TaskState,
};
use cw_core::tables::Tables;

pub(crate) mod lazy;
pub mod preempt;
pub mod trace;

/// The kernel services a port and the [`Resource`] cells rely on.
///
/// # Safety
/// `get_resource` must succeed only if no other task or ISR holds `res` now, and the
/// resource must stay held by the caller until `release_resource` succeeds: [`Resource`]
/// hands out a `&mut` on that promise. `cw_core::os::Os` is the implementation: its
/// `GetResource` refuses an occupied resource with `E_OS_ACCESS` in every status (the
/// conformance suite's `rm` tests and the `ceiling` model check exercise it).
pub unsafe trait OsKernel {
    /// The task the kernel has chosen to run (`None`: idle).
    fn running(&self) -> Option<TaskId>;
    /// The state of a task.
    fn task_state(&self, task: TaskId) -> Option<TaskState>;
    /// The interrupts the kernel holds masked now.
    fn interrupt_mask(&self) -> InterruptMask;
    /// The processor priority at or below which the kernel holds interrupts now
    /// (`u8::MAX`: all); [`OsKernel::interrupt_mask`] is its
    /// [`InterruptMask::at_level`].
    fn masked_level(&self) -> u8;
    /// Whether `ShutdownOS` has run.
    fn is_shut_down(&self) -> bool;
    /// `GetResource`.
    ///
    /// # Errors
    /// As the kernel's service.
    fn get_resource(&mut self, res: ResourceId) -> Result<(), OsError>;
    /// `ReleaseResource`.
    ///
    /// # Errors
    /// As the kernel's service.
    fn release_resource(&mut self, res: ResourceId) -> Result<(), OsError>;
    /// `GetResource`'s fast path ([`Os::try_get_resource`]): the processor priority the
    /// caller runs at now, or `None` with nothing changed (the caller then makes the full
    /// service call).
    fn try_get_resource(&mut self, res: ResourceId) -> Option<u8>;
    /// `ReleaseResource`'s fast path ([`Os::try_release_resource`]), as
    /// [`OsKernel::try_get_resource`].
    fn try_release_resource(&mut self, res: ResourceId) -> Option<u8>;
    /// The resources the running task may lock outside the kernel now, one bit each of
    /// the kind of lock each takes ([`Os::lock_free_resources`],
    /// [`cw_core::os::lock_free_bit`]).
    fn lock_free_resources(&self) -> u32;
    /// The ceiling of a resource, a processor priority ([`Os::ceiling`]): the level a
    /// lock kept outside the kernel masks.
    fn ceiling(&self, res: ResourceId) -> Option<u8>;
    /// [`OsKernel::masked_level`] and [`OsKernel::lock_free_resources`] in one
    /// ([`Os::port_view`]), as the port reads them at the end of every kernel call.
    fn port_view(&self) -> (u8, u32);
    /// `ActivateTask`.
    ///
    /// # Errors
    /// As the kernel's service.
    fn activate_task(&mut self, task: TaskId) -> Result<(), OsError>;
    /// `ActivateTask`'s fast path ([`Os::try_activate_task`]): where the activated task
    /// preempts the running one at task level, the kernel's view after it
    /// ([`OsKernel::port_view`]); `None` with nothing changed (the caller then makes the
    /// full service call).
    fn try_activate_task(&mut self, task: TaskId) -> Option<(u8, u32)>;
    /// The OS tick's fast path ([`Os::try_tick`]): the whole category-2 ISR `isr` whose
    /// body is `IncrementCounter(counter)` in one step where nothing is due; `None`, with
    /// nothing changed, where the port must run the ISR whole.
    fn try_tick(&mut self, isr: IsrId, counter: CounterId) -> Option<u8>;
    /// The OS tick's fast path where alarms are due ([`Os::try_tick_due`]): the whole ISR
    /// in one step where each due alarm activates a task of its own that may be activated;
    /// the running task may change. `None`, with nothing changed, where the port must run
    /// the ISR whole.
    fn try_tick_due(&mut self, isr: IsrId, counter: CounterId) -> Option<u8>;
    /// The port tells the kernel an ISR was entered.
    ///
    /// # Errors
    /// As the kernel's `enter_isr`.
    fn enter_isr(&mut self, isr: IsrId) -> Result<(), OsError>;
    /// The port tells the kernel the innermost ISR returned.
    ///
    /// # Errors
    /// As the kernel's `exit_isr`.
    fn exit_isr(&mut self) -> Result<(), OsError>;
    /// The OS shuts itself down on a fault the port detected (a stack overflow).
    fn shutdown_on_fault(&mut self, error: OsError);
    /// The running task's job returned without ending (its `TerminateTask` refused): the
    /// kernel ends it with `E_OS_MISSINGEND`, releasing what it holds.
    ///
    /// # Errors
    /// As the kernel's `task_returned` (not called from a task).
    fn task_returned(&mut self) -> Result<(), OsError>;
    /// The configured tasks.
    fn tasks(&self) -> &'static [TaskConfig];
    /// The configured ISRs.
    fn isrs(&self) -> &'static [IsrConfig];
}

// SAFETY: `Os::get_resource` records the caller as the owner and refuses an owned resource
// (`state.owner != NONE` -> `E_OS_ACCESS`) whatever the status; only the owner's
// `release_resource` (checked: the caller must be the owner and the resource the last one
// it took) frees it.
unsafe impl<
        const T: usize,
        const R: usize,
        const C: usize,
        const A: usize,
        const I: usize,
        const Q: usize,
        K,
        H,
    > OsKernel for Os<T, R, C, A, I, Q, K, H>
where
    K: Tables<OsConfig<T, R, C, A, I>>,
    H: Hooks<Self>,
{
    #[inline]
    fn running(&self) -> Option<TaskId> {
        Os::running(self)
    }
    #[inline]
    fn task_state(&self, task: TaskId) -> Option<TaskState> {
        Os::task_state(self, task)
    }
    #[inline]
    fn interrupt_mask(&self) -> InterruptMask {
        Os::interrupt_mask(self)
    }
    #[inline(always)]
    fn masked_level(&self) -> u8 {
        Os::masked_level(self)
    }
    #[inline]
    fn is_shut_down(&self) -> bool {
        Os::is_shut_down(self)
    }
    #[inline]
    fn get_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        Os::get_resource(self, res)
    }
    #[inline]
    fn release_resource(&mut self, res: ResourceId) -> Result<(), OsError> {
        Os::release_resource(self, res)
    }
    #[inline(always)]
    fn try_get_resource(&mut self, res: ResourceId) -> Option<u8> {
        Os::try_get_resource(self, res)
    }
    #[inline(always)]
    fn try_release_resource(&mut self, res: ResourceId) -> Option<u8> {
        Os::try_release_resource(self, res)
    }
    #[inline]
    fn lock_free_resources(&self) -> u32 {
        Os::lock_free_resources(self)
    }
    fn ceiling(&self, res: ResourceId) -> Option<u8> {
        Os::ceiling(self, res)
    }
    #[inline(always)]
    fn port_view(&self) -> (u8, u32) {
        Os::port_view(self)
    }
    #[inline]
    fn activate_task(&mut self, task: TaskId) -> Result<(), OsError> {
        Os::activate_task(self, task)
    }
    #[inline(always)]
    fn try_activate_task(&mut self, task: TaskId) -> Option<(u8, u32)> {
        Os::try_activate_task(self, task)
    }
    #[inline(always)]
    fn try_tick(&mut self, isr: IsrId, counter: CounterId) -> Option<u8> {
        Os::try_tick(self, isr, counter)
    }
    #[inline]
    fn try_tick_due(&mut self, isr: IsrId, counter: CounterId) -> Option<u8> {
        Os::try_tick_due(self, isr, counter)
    }
    #[inline]
    fn enter_isr(&mut self, isr: IsrId) -> Result<(), OsError> {
        Os::enter_isr(self, isr)
    }
    #[inline]
    fn exit_isr(&mut self) -> Result<(), OsError> {
        Os::exit_isr(self)
    }
    #[inline]
    fn shutdown_on_fault(&mut self, error: OsError) {
        Os::shutdown_on_fault(self, error);
    }
    #[inline]
    fn task_returned(&mut self) -> Result<(), OsError> {
        Os::task_returned(self)
    }
    fn tasks(&self) -> &'static [TaskConfig] {
        self.config().tasks()
    }
    fn isrs(&self) -> &'static [IsrConfig] {
        self.config().isrs()
    }
}

/// `GetResource` (`take`) or `ReleaseResource` on the kernel: its fast path where it
/// applies, else the full service (which decides, refuses and reports).
#[inline]
pub(crate) fn lock_in_kernel<K: OsKernel>(
    os: &mut K,
    res: ResourceId,
    take: bool,
) -> Result<(), OsError> {
    if take {
        match os.try_get_resource(res) {
            Some(_) => Ok(()),
            None => os.get_resource(res),
        }
    } else {
        match os.try_release_resource(res) {
            Some(_) => Ok(()),
            None => os.release_resource(res),
        }
    }
}

/// How the ECU reaches the kernel on a board.
pub trait Port {
    /// The kernel type.
    type Kernel: OsKernel;

    /// Whether the caller carries out task switches itself, by running the chosen task as
    /// a nested call (the host port), instead of the port switching stacks by itself (the
    /// Cortex-M port).
    const NESTED: bool;

    /// Runs kernel services under the kernel lock. Afterwards the kernel's interrupt mask
    /// is applied, and if the kernel chose another task the port switches to it (at once
    /// where switching is the port's: before this call returns to a preempted caller).
    fn kernel<R>(&self, f: impl FnOnce(&mut Self::Kernel) -> R) -> R;

    /// Reads the kernel's state without calling a service (nothing to carry out after).
    fn inspect<R>(&self, f: impl FnOnce(&Self::Kernel) -> R) -> R;

    /// Ends the running task's job with `f` (`TerminateTask` or `ChainTask`); where the
    /// port switches stacks, a successful end never returns to the caller.
    ///
    /// # Errors
    /// What `f` returned (the job goes on).
    fn end_job(
        &self,
        f: impl FnOnce(&mut Self::Kernel) -> Result<(), OsError>,
    ) -> Result<(), OsError>;

    /// Takes a resource for the running task or ISR (`GetResource`): the kernel's fast
    /// path where it applies, else the full service. A port where the lock costs less than
    /// a kernel call overrides it.
    ///
    /// # Errors
    /// As the kernel's service.
    #[inline]
    fn get_resource(&self, res: ResourceId) -> Result<(), OsError> {
        self.kernel(|os| lock_in_kernel(os, res, true))
    }

    /// Releases a resource (`ReleaseResource`), as [`Port::get_resource`] takes it.
    ///
    /// # Errors
    /// As the kernel's service.
    #[inline]
    fn release_resource(&self, res: ResourceId) -> Result<(), OsError> {
        self.kernel(|os| lock_in_kernel(os, res, false))
    }

    /// [`Port::get_resource`] of a resource whose kind is known when the image is built:
    /// `isr_shared` says whether an ISR shares it (its ceiling at interrupt level), which
    /// a port's lock outside the kernel then need not look up ([`Resource`] calls this).
    /// Where the kind given is not the resource's, the lock is the kernel's, as correct as
    /// ever. Returns how the lock was taken, which the release is given
    /// ([`Port::release_held`]).
    ///
    /// # Errors
    /// As the kernel's service.
    #[inline]
    fn get_resource_of_kind<const ISR_SHARED: bool>(
        &self,
        res: ResourceId,
    ) -> Result<Held, OsError> {
        self.get_resource(res).map(|()| Held::other())
    }

    /// The release of a lock [`Port::get_resource_of_kind`] took, told how it was taken.
    ///
    /// # Errors
    /// As the kernel's service.
    #[inline]
    fn release_held(&self, res: ResourceId, held: Held) -> Result<(), OsError> {
        let _ = held;
        self.release_resource(res)
    }

    /// Activates a task (`ActivateTask`): the kernel's fast path where it applies, else
    /// the full service; then the port carries out what the kernel decided, as after any
    /// kernel call. A port where a switch costs less than a kernel call's end overrides
    /// it.
    ///
    /// # Errors
    /// As the kernel's service.
    #[inline]
    fn activate_task(&self, task: TaskId) -> Result<(), OsError> {
        self.kernel(|os| match os.try_activate_task(task) {
            Some(_) => Ok(()),
            None => os.activate_task(task),
        })
    }

    /// The OS tick, category-2 ISR `isr` whose whole body is `IncrementCounter(counter)`,
    /// in one kernel call: the kernel's fast path where no alarm is due, its fast path
    /// where the due alarms only activate tasks (for either, the ISR's entry, the service
    /// and its return are done), else `whole` on the kernel (the ISR's entry, its body and
    /// its return, in order), whose result this returns. Either way the port then carries
    /// out what the kernel decided, as after any kernel call.
    #[inline]
    fn tick_isr<R>(
        &self,
        isr: IsrId,
        counter: CounterId,
        whole: impl FnOnce(&mut Self::Kernel) -> R,
    ) -> TickPath<R> {
        self.kernel(|os| {
            if os.try_tick(isr, counter).is_some() {
                TickPath::NothingDue
            } else if os.try_tick_due(isr, counter).is_some() {
                TickPath::AlarmsDue
            } else {
                TickPath::Whole(whole(os))
            }
        })
    }

    /// Milliseconds since start (the OS tick).
    fn now_ms(&self) -> u64;

    /// The task a nested call runs on top of (host port), `None` when idle.
    fn current_job(&self) -> Option<TaskId> {
        None
    }

    /// A job of `task` starts (host port: its nested call); for traces.
    fn job_started(&self, _task: TaskId) {}

    /// The job of `task` that `job_started` announced is over; for traces.
    fn job_finished(&self, _task: TaskId) {}

    /// Category-2 ISR `isr` was entered (the kernel accepted its entry); for traces.
    fn isr_entered(&self, _isr: IsrId) {}

    /// The kernel refused the entry of ISR `isr`, so its body does not run and nothing
    /// clears its source: the port quiets the interrupt line (on a level-triggered line,
    /// FlexCAN's among them, returning would take the interrupt again at once: a storm).
    /// The ISR's driver is started again only by the application.
    fn isr_refused(&self, _isr: IsrId) {}

    /// A measured span `id` (the application numbers them) starts or ends here; for the
    /// instruction counts of the application's own paths.
    fn span(&self, _id: usize, _start: bool) {}

    /// Span `started` ends here and its length is filed under span `id`: for a span whose
    /// name only the path it took tells (the OS tick: the kernel's fast path or the whole
    /// ISR), so that choosing the name costs nothing before the span.
    fn span_end_as(&self, _started: usize, _id: usize) {}

    /// The running job hangs (a fault a test board injects: a task stuck in a loop).
    /// Where the port switches stacks this never returns: the job spins at its priority
    /// with interrupts enabled, so tasks above it and ISRs still run. The host port
    /// returns at once and keeps the job as the one running, which has the same effect
    /// there: the kernel still has the task running, so only tasks above it and ISRs run
    /// again.
    fn hang(&self) {}
}

/// How [`Port::get_resource_of_kind`] took a lock, for its release
/// ([`Port::release_held`]). Only the ports make one, and a release takes it, so
/// [`Resource::lock`] gives it once, to the release of the same lock. The release trusts
/// it: a caller that gives one to the release of another lock, or keeps one past a general
/// [`Port::release_resource`] of its lock, breaks the lock it names, as a general release
/// inside [`Resource::lock`]'s closure would. (Checking the resource too cost the
/// size-built image 172 bytes, with no use in the firmware's one way of locking.)
#[must_use]
#[derive(Debug, PartialEq, Eq)]
pub struct Held(Way);

#[derive(Debug, PartialEq, Eq)]
enum Way {
    /// Outside the kernel, by the port alone, with a lock that masks the ISRs up to the
    /// resource's ceiling (`masks_isrs`) or nothing: the release need not look at what
    /// the port keeps to know it is this one.
    Outside { masks_isrs: bool },
    /// Any other way: the kernel's lock, or a port's whose general release
    /// ([`Port::release_resource`]) finds out.
    Other,
}

impl Held {
    /// A lock outside the kernel, masking ISRs or not.
    pub(crate) const fn outside(masks_isrs: bool) -> Self {
        Self(Way::Outside { masks_isrs })
    }

    /// A lock taken any other way.
    pub(crate) const fn other() -> Self {
        Self(Way::Other)
    }

    /// `Some(masks_isrs)` for a lock outside the kernel.
    #[inline(always)]
    pub(crate) const fn outside_masking(&self) -> Option<bool> {
        match self.0 {
            Way::Outside { masks_isrs } => Some(masks_isrs),
            Way::Other => None,
        }
    }
}

/// The path the OS tick took ([`Port::tick_isr`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TickPath<R> {
    /// The kernel's fast path where nothing is due: the counter advanced.
    NothingDue,
    /// The kernel's fast path where alarms are due: the ISR's whole effect, its alarms'
    /// activations and the rescheduling at its return included.
    AlarmsDue,
    /// The whole ISR ran: `whole`'s result.
    Whole(R),
}

/// Data shared by tasks and ISRs, guarded by one OSEK resource.
///
/// The data is reachable only inside [`Resource::lock`], while the caller holds the
/// resource: the kernel refuses a held resource to everyone else, and the resource's
/// ceiling (derived by the configuration from every task and ISR that declares it) keeps
/// them from even running meanwhile. A task holding a resource an ISR shares masks that
/// ISR.
///
/// The resource's id is a constant of the type (`ID`, a [`ResourceId`]'s number): the
/// port's lock of it then folds to the tests and stores of that one resource, with no
/// load of the id, no bounds check on its tables and no shift by a variable (the lock
/// outside the kernel, [`Port::get_resource`]). So is whether an ISR shares it
/// (`ISR_SHARED`, from the configuration: [`cw_core::os::OsConfig::isr_shared`]): a lock
/// of a resource only tasks share then masks nothing with no table to look up, and its
/// release has no mask to put back ([`Port::get_resource_of_kind`]). Where `ISR_SHARED`
/// is not the resource's kind, its locks go to the kernel: slower, never wrong.
pub struct Resource<T, const ID: u8, const ISR_SHARED: bool> {
    data: UnsafeCell<T>,
}

// SAFETY: the data is reached only through `lock` (a `&mut` for the holder of the OSEK
// resource, which the kernel grants to one task or ISR at a time; see `OsKernel`) or
// `get_mut` (exclusive by `&mut self`).
unsafe impl<T: Send, const ID: u8, const ISR_SHARED: bool> Sync for Resource<T, ID, ISR_SHARED> {}

impl<T, const ID: u8, const ISR_SHARED: bool> Resource<T, ID, ISR_SHARED> {
    /// The resource's id.
    pub const ID: ResourceId = ResourceId(ID);

    /// The data, guarded by resource [`Resource::ID`].
    pub const fn new(data: T) -> Self {
        Self {
            data: UnsafeCell::new(data),
        }
    }

    /// The resource's id.
    pub const fn id(&self) -> ResourceId {
        Self::ID
    }

    /// Runs `f` with the data while holding the resource (`GetResource`, `f`,
    /// `ReleaseResource`).
    ///
    /// # Errors
    /// The kernel's refusal of `GetResource` (`f` does not run): `E_OS_ACCESS` when the
    /// resource is held already (a nested lock of the same data) or the caller may not
    /// take it, `E_OS_CALLEVEL`, `E_OS_DISABLEDINT`.
    #[inline]
    pub fn lock<P: Port, R>(&self, port: &P, f: impl FnOnce(&mut T) -> R) -> Result<R, OsError> {
        let held = port.get_resource_of_kind::<ISR_SHARED>(Self::ID)?;
        // SAFETY: GetResource succeeded, so the kernel records this task or ISR as the
        // owner and refuses the resource to every other one until the release below
        // (`OsKernel`'s contract); `f` cannot keep the reference past its return.
        let result = f(unsafe { &mut *self.data.get() });
        // The release cannot fail: the caller owns the resource and took none after it
        // that it still holds (`f` returned, so every lock inside it was released).
        let _ = port.release_held(Self::ID, held);
        Ok(result)
    }

    /// The data, when nothing else can reach it (the ECU is not running, or this is the
    /// simulation between its steps).
    pub fn get_mut(&mut self) -> &mut T {
        self.data.get_mut()
    }
}

/// Data one task alone uses (its SWC's state, its pins): a cell that one job at a time
/// may borrow. The configuration makes sure only its task borrows it, so a borrow never
/// fails; the borrow flag makes that a checked fact instead of an assumption.
pub struct TaskLocal<T> {
    busy: AtomicBool,
    data: UnsafeCell<T>,
}

// SAFETY: `with` hands out the `&mut` only to the caller that flipped `busy` from false to
// true with one atomic swap, and clears it after; `get_mut` is exclusive by `&mut self`.
unsafe impl<T: Send> Sync for TaskLocal<T> {}

impl<T> TaskLocal<T> {
    /// The data.
    pub const fn new(data: T) -> Self {
        Self {
            busy: AtomicBool::new(false),
            data: UnsafeCell::new(data),
        }
    }

    /// Runs `f` with the data, or returns `None` (without running it) if another job
    /// borrows it now.
    #[inline]
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> Option<R> {
        if self.busy.swap(true, Ordering::Acquire) {
            return None;
        }
        // SAFETY: this caller turned `busy` on, so no other borrow exists until it turns
        // it off below.
        let result = f(unsafe { &mut *self.data.get() });
        self.busy.store(false, Ordering::Release);
        Some(result)
    }

    /// The data, when nothing else can reach it.
    pub fn get_mut(&mut self) -> &mut T {
        self.data.get_mut()
    }
}

/// A place for one value of `T` that lives for the whole run (the ECU on a board), filled
/// once at start-up.
pub struct Slot<T> {
    taken: AtomicBool,
    data: UnsafeCell<core::mem::MaybeUninit<T>>,
}

// SAFETY: `init` hands out the only reference to the data, once (the swap of `taken`
// decides which caller); the data is never reached otherwise.
unsafe impl<T: Send + Sync> Sync for Slot<T> {}

impl<T> Slot<T> {
    /// An empty slot.
    pub const fn new() -> Self {
        Self {
            taken: AtomicBool::new(false),
            data: UnsafeCell::new(core::mem::MaybeUninit::uninit()),
        }
    }

    /// Stores `value` and returns the one reference to it; `None` (and `value` dropped) if
    /// the slot was filled before.
    // The one `&mut` is handed out once, to the caller that wins the swap.
    #[allow(clippy::mut_from_ref)]
    pub fn init(&'static self, value: T) -> Option<&'static mut T> {
        if self.taken.swap(true, Ordering::AcqRel) {
            return None;
        }
        // SAFETY: this caller won the swap: no other reference to the data exists or will.
        Some(unsafe { (*self.data.get()).write(value) })
    }
}

impl<T> Default for Slot<T> {
    fn default() -> Self {
        Self::new()
    }
}
