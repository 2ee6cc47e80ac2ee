//! The preemptive port over a model CPU, with the real kernel: every fault the port
//! guards against, named, and the switch's bookkeeping against its model (`spec`).

extern crate std;

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::vec::Vec;

use cw_core::os::{
    AlarmAction, AlarmConfig, AlarmId, ConformanceClass, CounterConfig, CounterId, Dialect,
    HookSet, Hooks, IsrConfig, IsrId, Os, OsConfig, OsDescription, OsError, ResourceId,
    ServiceCall, Status, StatusType, TaskConfig, TaskId, OSDEFAULTAPPMODE,
};

use super::spec;
use super::{check, Arch, InterruptMask, PortFault, Preemptive, Refusal, IDLE, MAX_TASKS};
use crate::port::lazy::check_any_steps;
use crate::port::lazy::word;
use crate::port::{Held, Port, TickPath};

const LOW: TaskId = TaskId(0);
const HIGH: TaskId = TaskId(1);
const WAITER: TaskId = TaskId(2);

static OS: OsConfig<3, 2, 1, 1, 3> = match OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::basic("Low", 1).autostart().uses(0b11),
            TaskConfig::basic("High", 2).uses(0b10),
            TaskConfig::extended("Waiter", 3),
        ],
        [CounterConfig {
            max_allowed_value: 0xFFFF,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        [AlarmConfig::new(
            "WakeHigh",
            CounterId(0),
            AlarmAction::ActivateTask(HIGH),
        )],
        [
            IsrConfig::cat2("Tick", 1).uses(0b01),
            IsrConfig::cat1("Fast", 3),
            IsrConfig::cat2("Can", 2),
        ],
    )
    .class(ConformanceClass::Ecc1)
    .status(Status::Extended)
    .dialect(Dialect::Autosar)
    .hooks(HookSet {
        error: true,
        shutdown: true,
        ..HookSet::NONE
    }),
) {
    Ok(cfg) => cfg,
    Err(_) => panic!("the test configuration is inconsistent"),
};

cw_core::static_tables!(TestTables: OsConfig<3, 2, 1, 1, 3> = OS);

/// What the hooks saw: the first errors, in order.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
struct Seen {
    errors: [Option<(OsError, Option<ServiceCall>)>; 4],
    shutdown: Option<StatusType>,
}

impl Seen {
    fn errors(&self) -> Vec<OsError> {
        self.errors.iter().flatten().map(|e| e.0).collect()
    }
}

type Kernel = Os<3, 2, 1, 1, 3, 3, TestTables, Seen>;

impl Hooks<Kernel> for Seen {
    fn error_hook(os: &mut Kernel, error: OsError) {
        let call = os.error_call();
        if let Some(slot) = os.hooks_mut().errors.iter_mut().find(|e| e.is_none()) {
            *slot = Some((error, call));
        }
    }

    fn shutdown_hook(os: &mut Kernel, error: StatusType) {
        os.hooks_mut().shutdown = Some(error);
    }
}

/// How a model run ended (the payload of the unwinding that stands for `!`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum End {
    Stopped,
    Halted,
    /// An ended job waited for its switch.
    JobOver,
    /// A job of the task started by a call (the model stops there; the test goes on as
    /// that job).
    Called(u8),
}

/// The model CPU: the OS-level mask, every-interrupt masking, a pending switch, the
/// guard's place, the faults reported and the first frames written.
#[derive(Default)]
struct Model {
    /// `None`: the kernel lock (the OS level); `Some(mask)`: the kernel's mask applied.
    level: Cell<Option<InterruptMask>>,
    /// How many times the kernel lock was taken.
    os_locks: Cell<u32>,
    all: Cell<bool>,
    /// Every-interrupt masking was ever turned on while the kernel lock was held.
    all_in_lock: Cell<bool>,
    switch: Cell<bool>,
    guard: Cell<u32>,
    /// The bottom of a stack whose guard the model reports written (no MPU enforces it).
    broken_guard: Cell<Option<u32>>,
    quieted: Cell<u32>,
    reports: RefCell<Vec<PortFault>>,
    frames: RefCell<Vec<(u32, u8)>>,
    /// The CPU runs a task's code, where a new job may start by a call
    /// ([`Arch::may_call_job`], with every-interrupt masking off); off by default, so
    /// that every other test's switch is the switch exception's.
    calls: Cell<bool>,
}

impl Arch for Model {
    const ISR_PRIORITIES: u8 = 6;
    const GUARD_BYTES: u32 = 256;
    const FIRST_FRAME_BYTES: u32 = 72;

    fn lock_os(&self) {
        self.os_locks.set(self.os_locks.get() + 1);
        self.level.set(None);
    }
    fn set_mask(&self, mask: InterruptMask) {
        self.level.set(Some(mask));
    }
    fn all_masked(&self) -> bool {
        self.all.get()
    }
    fn disable_all(&self) {
        if self.level.get().is_none() {
            self.all_in_lock.set(true);
        }
        self.all.set(true);
    }
    fn enable_all(&self) {
        self.all.set(false);
    }
    fn request_switch(&self) {
        self.switch.set(true);
    }
    fn wait(&self) {
        std::panic::panic_any(End::JobOver);
    }
    unsafe fn first_frame(&self, top: u32, task: u8) -> u32 {
        self.frames.borrow_mut().push((top, task));
        (top & !7) - 68
    }
    fn move_guard(&self, bottom: u32) {
        self.guard.set(bottom);
    }
    fn guard_intact(&self, bottom: u32) -> bool {
        self.broken_guard.get() != Some(bottom)
    }
    fn quiet_active_line(&self) {
        self.quieted.set(self.quieted.get() + 1);
    }
    fn report(&self, fault: &PortFault) {
        self.reports.borrow_mut().push(*fault);
    }
    fn stopped(&self) -> ! {
        std::panic::panic_any(End::Stopped)
    }
    fn halt(&self) -> ! {
        std::panic::panic_any(End::Halted)
    }
    fn now_ms(&self) -> u64 {
        0
    }
    fn may_interrupt(&self) {
        take_pending(self, true);
    }
    fn may_call_job(&self) -> bool {
        self.calls.get() && !self.all.get()
    }
    fn call_job(&self, task: u8) {
        std::panic::panic_any(End::Called(task))
    }
}

type TestPort = Preemptive<Kernel, Model>;

const SHARED: (u32, u32) = (0x1000, 0x1800);
const WAITER_STACK: (u32, u32) = (0x2000, 0x2400);

fn port() -> TestPort {
    let Ok(kernel) = Kernel::new(TestTables) else {
        panic!("the test kernel");
    };
    let port = Preemptive::new(kernel, Model::default());
    port.set_shared_stack(SHARED.0, SHARED.1);
    port
}

/// Runs `f`, which must end the way `!` functions end in the model; returns how.
fn ends(f: impl FnOnce()) -> End {
    std::panic::set_hook(std::boxed::Box::new(|_| {}));
    let caught = catch_unwind(AssertUnwindSafe(f));
    let _ = std::panic::take_hook();
    match caught {
        Ok(()) => panic!("returned instead of ending"),
        Err(payload) => match payload.downcast::<End>() {
            Ok(end) => *end,
            Err(_) => panic!("ended by a panic of the port itself"),
        },
    }
}

/// The switch the model CPU would take now: `sp` is the outgoing context's stack pointer.
fn take_switch(port: &TestPort, sp: u32) -> u32 {
    assert!(port.arch().switch.replace(false), "no switch was requested");
    port.switch(sp)
}

/// StartOS: `Low` (autostart) is chosen, the switch starts its job on the shared stack.
fn started() -> TestPort {
    HELD.with_borrow_mut(|all| *all = [const { None }; 4]);
    let port = port();
    port.set_task_stack(WAITER, WAITER_STACK.0, WAITER_STACK.1);
    port.start_checked();
    port.kernel(|os| os.start_os(OSDEFAULTAPPMODE))
        .expect("StartOS");
    take_switch(&port, SHARED.1 - 64);
    port
}

/// A category-2 ISR (`Tick`) that makes one kernel call.
fn from_isr(port: &TestPort, f: impl FnOnce(&mut Kernel)) {
    port.kernel(|os| os.enter_isr(cw_core::os::IsrId(0)))
        .expect("enter");
    port.kernel(f);
    port.kernel(|os| os.exit_isr()).expect("exit");
}

#[test]
fn an_extended_task_without_its_own_stack_is_refused_before_start_naming_it() {
    let port = port();
    let end = ends(|| port.start_checked());
    assert_eq!(end, End::Halted);
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::Refused(Refusal::NoOwnStack("Waiter"))]
    );
    // Given a stack, the same configuration starts.
    let port = self::port();
    port.set_task_stack(WAITER, WAITER_STACK.0, WAITER_STACK.1);
    port.start_checked();
    assert!(port.arch().reports.borrow().is_empty());
}

#[test]
fn more_tasks_than_the_port_holds_are_refused_naming_the_first_over() {
    const NAMES: [&str; MAX_TASKS + 1] = [
        "t0", "t1", "t2", "t3", "t4", "t5", "t6", "t7", "t8", "t9", "t10", "t11", "t12", "t13",
        "t14", "t15", "t16",
    ];
    let tasks = NAMES.map(|name| TaskConfig::basic(name, 1));
    assert_eq!(
        check(&tasks, &[], 6, Some(0)),
        Err(Refusal::TooManyTasks("t16"))
    );
    assert_eq!(check(&tasks[..MAX_TASKS], &[], 6, Some(0)), Ok(()));
}

#[test]
fn isr_priorities_the_controller_cannot_tell_apart_are_refused() {
    let fits = [IsrConfig::cat2("A", 1), IsrConfig::cat2("B", 6)];
    assert_eq!(check(&[], &fits, 6, None), Ok(()));
    // Above the controller's levels: merged with the highest (or the faults').
    let high = [IsrConfig::cat2("A", 1), IsrConfig::cat2("Seven", 7)];
    assert_eq!(
        check(&[], &high, 6, None),
        Err(Refusal::IsrPriority("Seven"))
    );
    // 0: the task switch's own level.
    let zero = [IsrConfig::cat2("Zero", 0)];
    assert_eq!(
        check(&[], &zero, 6, None),
        Err(Refusal::IsrPriority("Zero"))
    );
}

#[test]
fn a_job_whose_terminate_is_refused_ends_with_missing_end_instead_of_spinning() {
    let port = started();
    assert_eq!(port.inspect(|os| os.running()), Some(LOW));
    // Low disables every interrupt and then tries to terminate: refused.
    port.kernel(|os| os.disable_all_interrupts())
        .expect("DisableAllInterrupts");
    assert!(
        port.arch().all.get(),
        "DisableAllInterrupts masks every interrupt"
    );
    let end = ends(|| {
        let _ = port.end_job(|os| os.terminate_task());
    });
    assert_eq!(
        end,
        End::JobOver,
        "the job is over: it waits for its switch"
    );
    assert_eq!(
        port.inspect(|os| os.hooks().errors()),
        [OsError::DisabledInt, OsError::MissingEnd]
    );
    assert!(
        !port.arch().all.get(),
        "the job's interrupt lock is released"
    );
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    // The switch frees the job's stack and goes idle; the task can run again.
    take_switch(&port, SHARED.1 - 200);
    assert_eq!(port.inspect(|os| os.running()), None);
    from_isr(&port, |os| os.activate_task(LOW).expect("Low again"));
    assert_eq!(take_switch(&port, SHARED.1 - 64), SHARED.1 - 64 - 68);
}

#[test]
fn a_stack_fault_inside_a_kernel_call_shuts_the_os_down_with_stackfault() {
    let port = started();
    // The guard fault arrives while a kernel call is under way (its context never
    // resumes).
    let end = ends(|| {
        port.kernel(|_| port.stack_fault(None));
    });
    assert_eq!(end, End::Stopped, "ShutdownOS, not a fatal port fault");
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::StackOverflow(None)]
    );
    let kernel = port.stopped_kernel().expect("the OS stopped");
    assert_eq!(kernel.hooks().shutdown, Some(OsError::StackFault.status()));
}

#[test]
fn a_stack_overflow_seen_at_a_switch_names_the_task() {
    let port = started();
    // The waiter starts on its own stack, then is switched away with its stack pointer
    // inside its guard.
    port.kernel(|os| os.activate_task(WAITER))
        .expect("activate");
    take_switch(&port, SHARED.1 - 128);
    assert_eq!(
        port.arch().guard.get(),
        WAITER_STACK.0,
        "the guard moved with it"
    );
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    port.kernel(|os| os.wait_event(1)).expect("wait");
    let end = ends(|| {
        take_switch(&port, WAITER_STACK.0 + 100);
    });
    assert_eq!(end, End::Stopped);
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::StackOverflow(Some("Waiter"))]
    );
}

/// A CPU without an MPU (the S32K144) cannot stop an overflow at its first access: the
/// switch asks it whether the outgoing stack's guard was written, and a written guard is
/// the same stack fault as a stack pointer inside it, named by its task.
#[test]
fn a_guard_found_written_at_a_switch_is_a_stack_fault() {
    let port = started();
    port.kernel(|os| os.activate_task(WAITER))
        .expect("activate");
    take_switch(&port, SHARED.1 - 128);
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    port.kernel(|os| os.wait_event(1)).expect("wait");
    // The stack pointer is back above the guard, but the guard was written meanwhile.
    port.arch().broken_guard.set(Some(WAITER_STACK.0));
    let end = ends(|| {
        take_switch(&port, WAITER_STACK.1 - 200);
    });
    assert_eq!(end, End::Stopped);
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::StackOverflow(Some("Waiter"))]
    );
    let kernel = port.stopped_kernel().expect("the OS stopped");
    assert_eq!(kernel.hooks().shutdown, Some(OsError::StackFault.status()));
}

/// A job that overflows and never yields is found by the OS tick's stack monitoring: the
/// running context's guard, written, is a stack fault; an intact one changes nothing.
#[test]
fn the_ticks_stack_monitoring_finds_a_running_jobs_overflow() {
    let port = started();
    port.monitor_stack();
    assert!(port.arch().reports.borrow().is_empty(), "intact: nothing");
    // `Low` runs on the shared stack, whose guard is written.
    port.arch().broken_guard.set(Some(SHARED.0));
    let end = ends(|| port.monitor_stack());
    assert_eq!(end, End::Stopped);
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::StackOverflow(None)],
        "the shared stack: no task of its own named"
    );
}

/// An intact guard lets the switch go on: the check is of the outgoing stack alone.
#[test]
fn an_intact_guard_lets_the_switch_go_on() {
    let port = started();
    // Some other stack's guard is written; the outgoing context's is not.
    port.arch().broken_guard.set(Some(WAITER_STACK.0));
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    let sp = take_switch(&port, SHARED.1 - 64);
    assert!(sp < SHARED.1 - 64, "the high task's first frame");
    assert!(port.arch().reports.borrow().is_empty());
}

#[test]
fn a_kernel_call_inside_a_critical_section_leaves_it_closed() {
    let port = started();
    // The caller's own critical section (every interrupt masked, not by the kernel).
    port.arch().all.set(true);
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    assert!(port.arch().all.get(), "the section is still closed");
    port.arch().all.set(false);
    // The kernel's own every-interrupt masking is turned on and off by its services.
    port.kernel(|os| os.suspend_all_interrupts())
        .expect("suspend");
    assert!(port.arch().all.get());
    port.kernel(|os| os.resume_all_interrupts())
        .expect("resume");
    assert!(!port.arch().all.get());
}

#[test]
fn the_kernel_lock_is_the_os_level_and_never_masks_category_1() {
    let port = started();
    port.arch().all_in_lock.set(false);
    port.kernel(|os| {
        let _ = os.activate_task(HIGH);
    });
    port.kernel(|os| {
        let _ = os.get_task_id();
    });
    assert!(
        !port.arch().all_in_lock.get(),
        "no kernel call masked every interrupt"
    );
}

#[test]
fn the_fast_lock_applies_the_ceilings_mask_and_the_service_decides_the_rest() {
    let port = started();
    let (shared_with_tick, tasks_only) = (ResourceId(0), ResourceId(1));
    // Shared with the category-2 ISR: the lock masks it, and switches nothing.
    assert_eq!(port.get_resource(shared_with_tick), Ok(()));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::UpTo(1)));
    assert!(!port.arch().switch.get());
    // A nested lock of the same resource: the fast path declines, the service refuses
    // and reports, and the lock stays as it was.
    assert_eq!(port.get_resource(shared_with_tick), Err(OsError::Access));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::UpTo(1)));
    assert_eq!(port.inspect(|os| os.hooks().errors()), [OsError::Access]);
    assert_eq!(port.release_resource(shared_with_tick), Ok(()));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    // Out of order: refused.
    assert_eq!(port.release_resource(tasks_only), Err(OsError::NoFunc));
    // A task-level ceiling: High, activated under it, waits for the release, which
    // switches to it.
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    assert!(!port.arch().switch.get(), "High waits for the release");
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert!(port.arch().switch.get(), "the release lets High in");
    assert_eq!(port.inspect(|os| os.running()), Some(HIGH));
}

#[test]
fn the_tick_is_one_kernel_call_by_the_fast_path_or_whole() {
    let port = started();
    let (tick, counter) = (IsrId(0), CounterId(0));
    let whole = |os: &mut Kernel| {
        os.enter_isr(tick)?;
        let _ = os.increment_counter(counter);
        os.exit_isr()
    };
    // Nothing due: the kernel's fast path, the task's mask restored, no switch.
    assert_eq!(port.tick_isr(tick, counter, whole), TickPath::NothingDue);
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert!(!port.arch().switch.get());
    assert_eq!(port.kernel(|os| os.get_counter_value(counter)), Ok(1));
    // An alarm due that activates a task: the kernel's fast path for it in the same
    // kernel call; the task the alarm activated is switched to once the ISR has returned.
    port.kernel(|os| os.set_rel_alarm(AlarmId(0), 1, 0))
        .expect("SetRelAlarm");
    assert_eq!(port.tick_isr(tick, counter, whole), TickPath::AlarmsDue);
    assert_eq!(port.kernel(|os| os.get_counter_value(counter)), Ok(2));
    assert_eq!(port.inspect(|os| os.running()), Some(HIGH));
    assert!(port.arch().switch.get());
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert_eq!(port.inspect(|os| os.hooks().errors()), []);
    // Due again while that task holds its one activation: the ISR whole, which reports
    // the activation refused.
    port.kernel(|os| os.set_rel_alarm(AlarmId(0), 1, 0))
        .expect("SetRelAlarm");
    assert_eq!(port.tick_isr(tick, counter, whole), TickPath::Whole(Ok(())));
    assert_eq!(port.kernel(|os| os.get_counter_value(counter)), Ok(3));
    assert_eq!(port.inspect(|os| os.hooks().errors()), [OsError::Limit]);
}

#[test]
fn a_kernel_call_inside_a_kernel_call_is_a_fatal_fault_not_an_alias() {
    let port = started();
    // A category-1 ISR calling the OS while a task's kernel call is under way.
    let end = ends(|| {
        port.kernel(|_| port.kernel(|os| os.running()));
    });
    assert_eq!(end, End::Halted);
    assert_eq!(*port.arch().reports.borrow(), [PortFault::KernelReentered]);
}

#[test]
fn a_task_stack_that_overlaps_or_is_too_small_is_refused() {
    let port = port();
    let end = ends(|| port.set_task_stack(WAITER, SHARED.0 + 16, SHARED.0 + 0x400));
    assert_eq!(end, End::Halted);
    let port = self::port();
    let end = ends(|| port.set_task_stack(WAITER, 0x3000, 0x3000 + 256));
    assert_eq!(end, End::Halted);
    let port = self::port();
    let end = ends(|| port.set_task_stack(TaskId(MAX_TASKS as u8), 0x3000, 0x3400));
    assert_eq!(end, End::Halted);
}

#[test]
fn an_isr_whose_entry_is_refused_has_its_line_quieted() {
    let port = started();
    port.isr_refused(cw_core::os::IsrId(0));
    assert_eq!(port.arch().quieted.get(), 1);
}

#[test]
fn the_idle_loop_is_the_shared_stacks_bottom_context() {
    let port = started();
    assert_eq!(port.arch().guard.get(), SHARED.0);
    assert_eq!(*port.arch().frames.borrow(), [(SHARED.1 - 64, LOW.0)]);
    assert_eq!(IDLE as usize, MAX_TASKS);
}

/// Any legal schedule keeps every job's context apart on the shared stack and on the own
/// stacks (`spec::stacks_stay_apart`).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(20))]
fn any_schedule_keeps_the_stacks_apart() {
    bolero::check!()
        .with_type::<[(u8, u8); 8]>()
        .cloned()
        .for_each(|steps| assert!(spec::stacks_stay_apart(&steps)));
}

#[test]
fn long_schedules_keep_the_stacks_apart() {
    bolero::check!()
        .with_type::<Vec<(u8, u8)>>()
        .for_each(|steps| assert!(spec::stacks_stay_apart(steps)));
}

std::thread_local! {
    /// How [`get_of_kind`] took each resource, for [`release_of_kind`].
    static HELD: RefCell<[Option<Held>; 4]> = const { RefCell::new([None, None, None, None]) };
}

/// [`Port::get_resource_of_kind`] with the kind known only when the test runs; how the
/// lock was taken is kept for [`release_of_kind`], as the firmware's `Resource` keeps it.
fn get_of_kind(port: &TestPort, res: ResourceId, isr_shared: bool) -> Result<(), OsError> {
    let held = if isr_shared {
        port.get_resource_of_kind::<true>(res)
    } else {
        port.get_resource_of_kind::<false>(res)
    }?;
    HELD.with_borrow_mut(|all| all[usize::from(res.0) % 4] = Some(held));
    Ok(())
}

/// [`Port::release_held`] of the lock [`get_of_kind`] took of `res` (a lock taken any
/// other way where none).
fn release_of_kind(port: &TestPort, res: ResourceId) -> Result<(), OsError> {
    let held = HELD.with_borrow_mut(|all| all[usize::from(res.0) % 4].take());
    port.release_held(res, held.unwrap_or_else(Held::other))
}

/// [`Port::release_resource`], the general release: a lock [`get_of_kind`] took of
/// `res` is no longer to be released by [`release_of_kind`].
fn release(port: &TestPort, res: ResourceId) -> Result<(), OsError> {
    HELD.with_borrow_mut(|all| all[usize::from(res.0) % 4] = None);
    port.release_resource(res)
}

/// Low's answer: resource 0, which the ISR shares, by the lock that masks it (bit
/// 12), resource 1, which only tasks share, by the lock that masks nothing (bit 1).
const LOW_ANSWER: u32 = 1 << 12 | 1 << 1;

/// The kernel as the port leaves it, with a lock kept outside the kernel handed over as
/// the next kernel call would: what every kernel call sees.
fn kernel_view(port: &TestPort) -> Kernel {
    // SAFETY: the model runs one context at a time and no kernel call is under way.
    let mut view = unsafe { *port.kernel.get() };
    let lazy = port.lazy.word();
    if word::is_locked(lazy) {
        assert!(
            view.try_get_resource(word::resource(lazy)).is_some(),
            "the hand-over"
        );
    }
    view
}

/// The kernel itself, without a kernel call.
fn kernel_now(port: &TestPort) -> Kernel {
    // SAFETY: as in `kernel_view`.
    unsafe { *port.kernel.get() }
}

#[test]
fn a_tasks_lock_outside_the_kernel_is_a_store_and_a_pair_leaves_the_kernel_untouched() {
    let port = started();
    let tasks_only = ResourceId(1);
    let before = kernel_now(&port);
    let os_locks = port.arch().os_locks.get();
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    assert!(word::is_locked(port.lazy.word()));
    assert!(kernel_now(&port) == before, "the kernel was not called");
    // No ISR uses it: the store alone, not even the kernel lock.
    assert_eq!(port.arch().os_locks.get(), os_locks);
    // What a kernel call would see: Low holding it at its ceiling, which masks no ISR.
    assert_eq!(kernel_view(&port).resource_owner(tasks_only), Some(LOW));
    assert_eq!(kernel_view(&port).running_priority(), Some(2));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
    assert!(kernel_now(&port) == before, "the pair left no trace");
    // A resource an ISR shares too: the port masks the ISR itself, at the ceiling.
    let shared = ResourceId(0);
    assert_eq!(port.get_resource(shared), Ok(()));
    assert!(word::is_locked(port.lazy.word()));
    assert!(kernel_now(&port) == before, "the kernel was not called");
    // The store under the kernel lock, then the ceiling's mask.
    assert_eq!(port.arch().os_locks.get(), os_locks + 1);
    assert_eq!(kernel_view(&port).resource_owner(shared), Some(LOW));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::UpTo(1)));
    assert_eq!(
        port.arch().level.get(),
        Some(kernel_view(&port).interrupt_mask())
    );
    // Holding it, the task locks through the kernel only, which is handed the first.
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    assert_eq!(kernel_now(&port).resource_owner(shared), Some(LOW));
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), Some(LOW));
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert_eq!(port.release_resource(shared), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
    assert!(kernel_now(&port) == before, "both released");
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    // The pair again: the release puts the task's mask back itself.
    assert_eq!(port.get_resource(shared), Ok(()));
    assert_eq!(port.release_resource(shared), Ok(()));
    assert!(kernel_now(&port) == before, "the pair left no trace");
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
}

/// A lock of a kind known when the image is built ([`Port::get_resource_of_kind`]) tries
/// that kind alone: a resource only tasks share is one store and its release the answer
/// put back, neither touching the mask; one an ISR shares masks it and puts the task's
/// mask back. Where the kind given is not the resource's, the lock and release are the
/// kernel's; a lock outside the kernel whose release is not told so goes to the kernel,
/// which is handed the lock first. Every way leaves the kernel as it was.
#[test]
fn a_lock_of_a_known_kind_tries_that_kind_alone() {
    let port = started();
    let (shared, tasks_only) = (ResourceId(0), ResourceId(1));
    let before = kernel_now(&port);
    // A mask the model would not set: the pair that masks nothing leaves it alone.
    let untouched = Some(InterruptMask::UpTo(5));
    port.arch().level.set(untouched);
    assert_eq!(get_of_kind(&port, tasks_only, false), Ok(()));
    assert_eq!(port.lazy.word(), word::locked(tasks_only, false));
    assert!(kernel_now(&port) == before, "the kernel was not called");
    assert_eq!(kernel_view(&port).resource_owner(tasks_only), Some(LOW));
    assert_eq!(release_of_kind(&port, tasks_only), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
    assert_eq!(
        port.arch().level.get(),
        untouched,
        "no mask set or put back"
    );
    assert!(kernel_now(&port) == before, "the pair left no trace");
    port.arch().level.set(Some(InterruptMask::None));
    // The ISRs' kind: the ceiling's mask, then the task's.
    assert_eq!(get_of_kind(&port, shared, true), Ok(()));
    assert_eq!(port.lazy.word(), word::locked(shared, true));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::UpTo(1)));
    assert_eq!(release_of_kind(&port, shared), Ok(()));
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert!(kernel_now(&port) == before, "the pair left no trace");
    // Kinds that are not the resources': the kernel's locks.
    for (res, kind) in [(shared, false), (tasks_only, true)] {
        assert_eq!(get_of_kind(&port, res, kind), Ok(()));
        assert_eq!(port.lazy.word(), 0, "{res:?}");
        assert_eq!(kernel_now(&port).resource_owner(res), Some(LOW));
        assert_eq!(release_of_kind(&port, res), Ok(()));
        assert!(kernel_now(&port) == before, "{res:?} released");
        assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    }
    // A lock outside the kernel released without being told so: through the kernel
    // (its lock taken), handed the lock.
    let os_errors = kernel_now(&port).hooks().errors().len();
    assert_eq!(
        port.get_resource_of_kind::<true>(shared),
        Ok(Held::outside(true))
    );
    let os_locks = port.arch().os_locks.get();
    assert_eq!(port.release_held(shared, Held::other()), Ok(()));
    assert!(
        port.arch().os_locks.get() > os_locks,
        "a kernel call released it"
    );
    assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
    assert!(kernel_now(&port) == before, "released by the kernel");
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert_eq!(kernel_now(&port).hooks().errors().len(), os_errors);
}

/// A hand-over between the release's load and its store (an ISR's kernel call), then a
/// tick with nothing due before its second load: the release stored the answer it had
/// loaded before the hand-over, and the tick, which leaves the answer as it found it,
/// puts that word back; the answer's copy stays 0, so the release still finds the
/// hand-over and goes to the kernel, which releases the lock. (A tick that set the copy
/// too would make the release end outside the kernel with the kernel holding the lock.)
#[test]
fn a_tick_after_a_hand_over_inside_a_release_leaves_the_release_to_the_kernel() {
    let port = started();
    let (tick, counter, tasks_only) = (IsrId(0), CounterId(0), ResourceId(1));
    assert_eq!(get_of_kind(&port, tasks_only, false), Ok(()));
    let point = Cell::new(0);
    let released = port.lazy.release(|| {
        if point.get() == 0 {
            from_isr(&port, |os| {
                assert_eq!(os.resource_owner(tasks_only), Some(LOW), "handed over");
            });
        } else {
            let whole = |os: &mut Kernel| {
                os.enter_isr(tick)?;
                let _ = os.increment_counter(counter);
                os.exit_isr()
            };
            assert_eq!(port.tick_isr(tick, counter, whole), TickPath::NothingDue);
        }
        point.set(point.get() + 1);
    });
    assert_eq!(point.get(), 2);
    assert!(!released, "the second load finds the hand-over");
    assert_eq!(
        port.lazy.word(),
        LOW_ANSWER,
        "the tick put back the release's store"
    );
    assert_eq!(port.lazy.answer(), 0);
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), Some(LOW));
    // The release goes on as the port's does: through the kernel.
    assert_eq!(port.release_held(tasks_only, Held::other()), Ok(()));
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), None);
    assert_eq!(
        (port.lazy.word(), port.lazy.answer()),
        (LOW_ANSWER, LOW_ANSWER)
    );
}

#[test]
fn the_next_kernel_call_hands_the_lock_to_the_kernel_before_anything_else() {
    let port = started();
    let tasks_only = ResourceId(1);
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    // An ISR's first kernel call: the kernel holds the lock for Low already, so High,
    // activated by the ISR, waits for the release.
    from_isr(&port, |os| {
        assert_eq!(os.resource_owner(tasks_only), Some(LOW));
        assert_eq!(os.activate_task(HIGH), Ok(()));
    });
    assert!(!port.arch().switch.get(), "High waits for the release");
    assert_eq!(
        port.lazy.answer(),
        0,
        "handed over: the task holds a resource"
    );
    assert!(!word::is_locked(port.lazy.word()));
    // The release goes through the kernel, which switches to High.
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert!(
        !word::is_locked(port.lazy.word()),
        "High runs, with its own answer"
    );
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), None);
    assert!(port.arch().switch.get(), "the release lets High in");
    assert_eq!(kernel_now(&port).running(), Some(HIGH));
}

#[test]
fn a_tick_with_nothing_due_takes_the_lock_over_and_its_answer_says_so() {
    let port = started();
    let (tick, counter, tasks_only) = (IsrId(0), CounterId(0), ResourceId(1));
    let whole = |os: &mut Kernel| {
        os.enter_isr(tick)?;
        let _ = os.increment_counter(counter);
        os.exit_isr()
    };
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    assert_eq!(
        port.lazy.answer(),
        LOW_ANSWER,
        "the answer from before the lock"
    );
    // The tick's fast path hands the lock to the kernel first: the task holds a resource
    // now, so the answer it leaves is 0, not the one it found.
    assert_eq!(port.tick_isr(tick, counter, whole), TickPath::NothingDue);
    assert!(!port.lazy.in_kernel());
    assert_eq!((port.lazy.word(), port.lazy.answer()), (0, 0));
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), Some(LOW));
    // Another lock goes to the kernel: the same resource is refused there, the other one
    // is taken by the kernel.
    assert_eq!(port.get_resource(tasks_only), Err(OsError::Access));
    assert_eq!(port.get_resource(ResourceId(0)), Ok(()));
    assert_eq!(port.release_resource(ResourceId(0)), Ok(()));
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert_eq!(
        (port.lazy.word(), port.lazy.answer()),
        (LOW_ANSWER, LOW_ANSWER),
        "the task holds nothing again"
    );
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), None);
}

#[test]
fn a_stack_fault_while_a_lock_is_kept_outside_the_kernel_still_shuts_down_cleanly() {
    let port = started();
    let tasks_only = ResourceId(1);
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    let end = ends(|| port.stack_fault(None));
    assert_eq!(end, End::Stopped, "ShutdownOS, not a refused hand-over");
    // The lock went with the OS: the application's end reads the kernel without a
    // hand-over the stopped kernel would refuse (a fatal port fault).
    assert_eq!(port.lazy.word(), 0);
    assert_eq!(
        port.inspect(|os| os.hooks().shutdown),
        Some(OsError::StackFault.status())
    );
    assert_eq!(
        *port.arch().reports.borrow(),
        [PortFault::StackOverflow(None)]
    );
}

#[test]
fn a_nested_lock_of_the_same_resource_is_refused_by_the_kernel_as_ever() {
    let port = started();
    let tasks_only = ResourceId(1);
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    // The second lock goes through the kernel, which is handed the first and refuses.
    assert_eq!(port.get_resource(tasks_only), Err(OsError::Access));
    assert_eq!(kernel_now(&port).hooks().errors(), [OsError::Access]);
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), Some(LOW));
    assert_eq!(port.release_resource(tasks_only), Ok(()));
    assert_eq!(port.lazy.word(), LOW_ANSWER, "the answer again");
    assert_eq!(kernel_now(&port).resource_owner(tasks_only), None);
}

#[test]
fn a_job_that_ends_holding_a_lock_outside_the_kernel_gives_it_back() {
    let port = started();
    let tasks_only = ResourceId(1);
    assert_eq!(port.get_resource(tasks_only), Ok(()));
    // TerminateTask sees the lock (E_OS_RESOURCE); the job cannot end as asked and the
    // kernel ends it, releasing the lock (E_OS_MISSINGEND).
    let end = ends(|| {
        let _ = port.end_job(|os| os.terminate_task());
    });
    assert_eq!(end, End::JobOver);
    assert_eq!(port.lazy.word(), 0);
    let kernel = kernel_now(&port);
    assert_eq!(kernel.resource_owner(tasks_only), None);
    assert_eq!(
        kernel.hooks().errors(),
        [OsError::Resource, OsError::MissingEnd]
    );
}

#[test]
fn isrs_hooks_and_tasks_under_an_interrupt_lock_lock_through_the_kernel() {
    let port = started();
    // In an ISR (after its entry): the lock goes to the kernel.
    port.kernel(|os| os.enter_isr(IsrId(0))).expect("enter");
    assert_eq!(port.lazy.word(), 0);
    assert_eq!(port.get_resource(ResourceId(0)), Ok(()));
    assert_eq!(port.lazy.word(), 0);
    assert_eq!(port.release_resource(ResourceId(0)), Ok(()));
    port.kernel(|os| os.exit_isr()).expect("exit");
    // Back in Low, which may again.
    assert_eq!(port.lazy.word(), LOW_ANSWER);
    // Under SuspendOSInterrupts: the kernel refuses the lock (E_OS_CALLEVEL in AUTOSAR).
    port.kernel(|os| os.suspend_os_interrupts())
        .expect("suspend");
    assert_eq!(port.lazy.word(), 0);
    assert!(port.get_resource(ResourceId(1)).is_err());
    assert_eq!(port.lazy.word(), 0);
    port.kernel(|os| os.resume_os_interrupts()).expect("resume");
    // Inside a kernel call (a hook's lock would be one): never outside the kernel.
    // The kernel call's flag is in the word the lock tests: the kernel's answer is
    // `IN_KERNEL` alone meanwhile, and a second call is refused.
    let before = port.lazy.begin_kernel().expect("no kernel call under way");
    assert_eq!(before, LOW_ANSWER);
    assert!(port.lazy.in_kernel());
    assert_eq!(port.lazy.begin_kernel(), None);
    assert!(!port.lazy_get(ResourceId(1), false));
    assert_eq!(port.lazy.word(), word::IN_KERNEL);
    port.lazy.restore(before);
    assert!(!port.lazy.in_kernel());
    assert!(port.lazy_get(ResourceId(1), false));
    assert!(port.lazy_release(ResourceId(1), false));
}

/// One step of [`any_locks_and_calls_leave_the_kernel_as_kernel_calls_would`]: a lock or
/// release by the port's general calls or by those of a kind (either kind, so also the
/// resource's other one: the kernel's then), an ISR, or a kernel call.
fn lock_step_on_both(port: &TestPort, reference: &mut Kernel, op: u8) {
    let res = ResourceId(op / 6 % 3);
    let isr_shared = op / 18 % 2 == 1;
    match op % 6 {
        0 => assert_eq!(
            port.get_resource(res),
            reference.get_resource(res),
            "get {res:?}"
        ),
        1 => assert_eq!(
            release(port, res),
            reference.release_resource(res),
            "release {res:?}"
        ),
        2 => assert_eq!(
            get_of_kind(port, res, isr_shared),
            reference.get_resource(res),
            "get {res:?} of kind {isr_shared}"
        ),
        3 => assert_eq!(
            release_of_kind(port, res),
            reference.release_resource(res),
            "release {res:?} as taken"
        ),
        4 => {
            // An ISR that enters (where the mask lets it) and returns.
            let entered = port.kernel(|os| os.enter_isr(IsrId(0)));
            assert_eq!(entered, reference.enter_isr(IsrId(0)), "ISR entry");
            if entered.is_ok() {
                assert_eq!(port.kernel(|os| os.exit_isr()), reference.exit_isr());
            }
        }
        _ => {
            // Any kernel call of the task.
            assert_eq!(port.kernel(|os| os.get_task_id()), reference.get_task_id());
        }
    }
}

/// Any sequence of locks, releases (of either resource, or an invalid one), ISRs and
/// kernel calls of the running task: after each step the kernel a kernel call would see
/// (the lock kept outside it handed over) is the kernel that was called for every lock,
/// and every call returned the same. (A bolero test and fuzz target.)
#[test]
fn any_locks_and_calls_leave_the_kernel_as_kernel_calls_would() {
    check_any_steps(started, kernel_now, lock_step_on_both, kernel_view);
}

std::thread_local! {
    /// The interrupt the model CPU takes at the next [`Arch::may_interrupt`] point whose
    /// mask admits it ([`any_interrupt_between_the_stores_of_a_lock_outside_the_kernel`]).
    static PENDING: Cell<Option<Pending>> = const { Cell::new(None) };
}

/// An interrupt waiting for the model CPU to take it.
#[derive(Clone, Copy)]
struct Pending {
    port: &'static TestPort,
    /// `may_interrupt` points to pass first.
    after: u8,
    /// `Tick` (which locks the resource it shares with Low), else `Can` (which activates
    /// High).
    tick: bool,
    /// Whether it was taken, and whether Low held a resource then: a lock outside the
    /// kernel in the port's word, or one handed over or taken by the kernel (the answer
    /// 0): the order the kernel sees, after a lock and before its release (one that
    /// finds the answer 0 goes to the kernel after the interrupt).
    taken: Option<bool>,
}

impl Model {
    /// Whether the mask in force admits category-2 ISR `isr` (priority 1 or 2).
    fn admits(&self, priority: u8) -> bool {
        !self.all.get() && self.level.get().is_some_and(|mask| mask.admits(priority))
    }
}

/// The ISR the model takes: `Tick` locks resource 0 (which it shares with Low: taken, it
/// would be refused) and returns; `Can` activates High, and where that asks for the
/// switch, High's job runs to its end before the interrupted code goes on.
fn interrupt(port: &TestPort, tick: bool) {
    let isr = if tick { IsrId(0) } else { IsrId(2) };
    port.kernel(|os| os.enter_isr(isr)).expect("entry");
    if tick {
        assert_eq!(
            port.get_resource(ResourceId(0)),
            Ok(()),
            "the mask let in an ISR whose resource is held"
        );
        assert_eq!(port.release_resource(ResourceId(0)), Ok(()));
    } else {
        // (Refused where High is active already: the reference sees the same.)
        let _ = port.kernel(|os| os.activate_task(HIGH));
    }
    port.kernel(|os| os.exit_isr()).expect("return");
    high_runs(port);
}

/// Where a switch was asked for (to High, which an ISR activated), High's job runs to
/// its end and Low goes on.
fn high_runs(port: &TestPort) {
    if port.arch().switch.get() {
        let interrupted = SHARED.1 - 256;
        take_switch(port, interrupted);
        assert_eq!(port.inspect(|os| os.running()), Some(HIGH));
        let end = ends(|| {
            let _ = port.end_job(|os| os.terminate_task());
        });
        assert_eq!(end, End::JobOver);
        assert_eq!(take_switch(port, SHARED.1 - 400), interrupted);
    }
}

/// High's job on the reference kernel, where it runs.
fn high_runs_reference(reference: &mut Kernel) {
    if reference.running() == Some(HIGH) {
        assert_eq!(reference.terminate_task(), Ok(()));
    }
}

/// The same ISR on the reference kernel, High's job included.
fn interrupt_reference(reference: &mut Kernel, tick: bool) {
    let isr = if tick { IsrId(0) } else { IsrId(2) };
    assert_eq!(reference.enter_isr(isr), Ok(()));
    if tick {
        assert_eq!(reference.get_resource(ResourceId(0)), Ok(()));
        assert_eq!(reference.release_resource(ResourceId(0)), Ok(()));
    } else {
        let _ = reference.activate_task(HIGH);
    }
    assert_eq!(reference.exit_isr(), Ok(()));
    high_runs_reference(reference);
}

/// Takes the pending interrupt if the mask admits it now (`point`: at a `may_interrupt`
/// point, where it may have points to pass first).
fn take_pending(model: &Model, point: bool) {
    let Some(mut pending) = PENDING.get() else {
        return;
    };
    if pending.taken.is_some() {
        return;
    }
    if point && pending.after > 0 {
        pending.after -= 1;
        PENDING.set(Some(pending));
        return;
    }
    if !model.admits(if pending.tick { 1 } else { 2 }) {
        return;
    }
    let lazy = &pending.port.lazy;
    pending.taken = Some(word::is_locked(lazy.word()) || lazy.answer() == 0);
    PENDING.set(Some(pending));
    interrupt(pending.port, pending.tick);
}

/// Any sequence of locks and releases of either resource (the one Low shares with `Tick`,
/// the one it shares with High; by the general calls or by those of the resource's kind),
/// kernel calls of the task, and interrupts (`Tick`, which
/// locks the resource it shares; `Can`, which activates High) arriving at any point the
/// mask admits, between any two stores of a lock kept outside the kernel or of its release:
/// no ISR is let in whose resource the task holds, after every step the mask in force is
/// the one the kernel (the lock handed over) would apply, and the kernel is the one called
/// for every lock with each interrupt where it fell (after the lock's store, or before the
/// release's store, when it found the lock in the word or handed over: the answer's copy
/// 0). (A bolero test and fuzz target.)
#[test]
fn any_interrupt_between_the_stores_of_a_lock_outside_the_kernel() {
    bolero::check!().with_type::<Vec<u8>>().for_each(|ops| {
        let port: &'static TestPort = std::boxed::Box::leak(std::boxed::Box::new(started()));
        let mut reference = kernel_now(port);
        PENDING.set(None);
        for &op in ops.iter().take(24) {
            let res = ResourceId(op / 5 % 2);
            match op % 5 {
                0 | 1 => {
                    let take = op % 5 == 0;
                    // By the general calls, or by those of the resource's kind (the
                    // firmware's `Resource`): resource 0 is the tick's too.
                    let kind = (op / 10 % 2 == 1).then_some(res.0 == 0);
                    let result = match (take, kind) {
                        (true, None) => port.get_resource(res),
                        (false, None) => release(port, res),
                        (true, Some(isr_shared)) => get_of_kind(port, res, isr_shared),
                        (false, Some(_)) => release_of_kind(port, res),
                    };
                    // The interrupt taken inside the call, where the kernel saw it.
                    let inside = PENDING.get().and_then(|p| p.taken.map(|l| (p.tick, l)));
                    let before = inside.is_some_and(|(_, locked)| locked != take);
                    if let (Some((tick, _)), true) = (inside, before) {
                        interrupt_reference(&mut reference, tick);
                    }
                    let expected = if take {
                        reference.get_resource(res)
                    } else {
                        reference.release_resource(res)
                    };
                    assert_eq!(result, expected, "{op}");
                    // A release that lets High in (the lock was handed over).
                    high_runs(port);
                    high_runs_reference(&mut reference);
                    if let (Some((tick, _)), false) = (inside, before) {
                        interrupt_reference(&mut reference, tick);
                    }
                    if inside.is_some() {
                        PENDING.set(None);
                    }
                }
                2 => {
                    // An interrupt becomes pending, taken at a point inside a lock or a
                    // release, or between steps.
                    if PENDING.get().is_none() {
                        PENDING.set(Some(Pending {
                            port,
                            after: op / 10 % 3,
                            tick: op / 5 % 2 == 0,
                            taken: None,
                        }));
                    }
                }
                3 => {
                    // Between steps: the pending interrupt, if the mask admits it.
                    take_pending(port.arch(), false);
                    if let Some(Pending {
                        tick,
                        taken: Some(_),
                        ..
                    }) = PENDING.get()
                    {
                        interrupt_reference(&mut reference, tick);
                        PENDING.set(None);
                    }
                }
                _ => assert_eq!(port.kernel(|os| os.get_task_id()), reference.get_task_id()),
            }
            let view = kernel_view(port);
            assert!(view == reference, "after {op}: the kernel differs");
            assert_eq!(
                port.arch().level.get(),
                Some(view.interrupt_mask()),
                "after {op}: the mask in force"
            );
        }
        PENDING.set(None);
    });
}

/// The port's tables now.
fn sched(port: &TestPort) -> super::Sched {
    port.before_start(|_, s| s.clone())
}

/// `Low` runs on the shared stack, in a task's code where the CPU lets a job start by a
/// call; `High`'s activation there starts its job so.
fn high_called(port: &TestPort) {
    port.arch().calls.set(true);
    let end = ends(|| {
        let _ = port.kernel(|os| os.activate_task(HIGH));
    });
    assert_eq!(end, End::Called(HIGH.0), "High's job starts by a call");
}

/// A job that a job on the shared stack lets in by its own kernel call, of a task on the
/// shared stack, starts by a call on the caller's stack, with the kernel lock ended and
/// the new job's mask; its end gives the context back to the caller, whose call returns:
/// no switch either way, and the shared stack as it was.
#[test]
fn a_job_let_in_by_a_job_on_the_shared_stack_starts_by_a_call_and_returns_to_it() {
    let port = started();
    let before = sched(&port);
    high_called(&port);
    assert!(!port.arch().switch.get(), "no switch exception");
    assert!(!port.lazy.in_kernel(), "the kernel lock ended");
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert_eq!(port.inspect(|os| os.running()), Some(HIGH));
    let during = sched(&port);
    assert_eq!(during.current(), HIGH.0);
    assert_eq!(
        during.basic_top(),
        before.basic_top(),
        "the call writes nothing there"
    );
    assert_eq!(
        port.arch().frames.borrow().len(),
        1,
        "no first frame written"
    );
    // High ends: its end returns (a job the switch started waits for its switch).
    port.end_job(|os| os.terminate_task())
        .expect("TerminateTask");
    assert!(!port.arch().switch.get(), "no switch exception");
    assert_eq!(port.inspect(|os| os.running()), Some(LOW));
    let after = sched(&port);
    assert_eq!(after.current(), LOW.0);
    assert_eq!(after.started, before.started);
    assert_eq!(after.called_from, before.called_from);
    assert!(port.inspect(|os| os.hooks().errors()).is_empty());
}

/// Where the CPU may not start a job by a call (an ISR runs, or the caller's own critical
/// section is closed, which the switch must wait for) the switch exception does it, as
/// for a task with its own stack, whose job never starts on another's stack.
#[test]
fn a_job_starts_by_the_switch_where_a_call_may_not_start_it() {
    let port = started();
    port.arch().calls.set(true);
    port.arch().all.set(true);
    port.kernel(|os| os.activate_task(HIGH)).expect("activate");
    assert!(
        port.arch().switch.get(),
        "the switch, once the section opens"
    );
    port.arch().all.set(false);
    take_switch(&port, SHARED.1 - 200);
    assert_eq!(sched(&port).current(), HIGH.0);
    // High, on the shared stack, lets in Waiter, which has a stack of its own.
    port.kernel(|os| os.activate_task(WAITER))
        .expect("activate");
    assert!(port.arch().switch.get(), "the switch to its own stack");
    take_switch(&port, SHARED.1 - 300);
    assert_eq!(sched(&port).current(), WAITER.0);
    assert_eq!(port.arch().guard.get(), WAITER_STACK.0);
}

/// A called job that lets in a task with its own stack is switched away as every job
/// is, and resumed; a called job that chains itself gives the context back to its caller,
/// and its new job starts by the switch, below the ended job's frames, never by a call
/// from them (chaining itself again and again would nest without end). Its end gives the
/// context back to the caller where the switch saved it.
#[test]
fn a_called_job_is_preempted_resumed_and_chained_as_any_job() {
    let port = started();
    high_called(&port);
    port.kernel(|os| os.activate_task(WAITER))
        .expect("activate");
    take_switch(&port, SHARED.1 - 260);
    assert_eq!(sched(&port).current(), WAITER.0);
    port.kernel(|os| os.wait_event(1)).expect("wait");
    assert_eq!(
        take_switch(&port, WAITER_STACK.1 - 100),
        SHARED.1 - 260,
        "High resumes"
    );
    assert_eq!(sched(&port).current(), HIGH.0);
    // (On the CPU the switch runs inside the end, before it returns.)
    port.end_job(|os| os.chain_task(HIGH)).expect("ChainTask");
    assert!(port.arch().switch.get(), "the new job by the switch");
    let chained = sched(&port);
    assert_eq!(chained.current(), LOW.0, "the context is Low's again");
    assert_eq!(chained.caller_of(usize::from(HIGH.0)), None);
    let frames = port.arch().frames.borrow().len();
    let top = take_switch(&port, SHARED.1 - 300);
    assert!(
        top < SHARED.1 - 300,
        "High's new job below the ended one's frames"
    );
    assert_eq!(port.arch().frames.borrow().len(), frames + 1);
    assert_eq!(sched(&port).current(), HIGH.0);
    // Chained again: once more by the switch, at the same place (the stack does not grow).
    let end = ends(|| {
        let _ = port.end_job(|os| os.chain_task(HIGH));
    });
    assert_eq!(end, End::JobOver, "a job the switch started waits for it");
    assert_eq!(take_switch(&port, top - 40), top);
    let end = ends(|| {
        let _ = port.end_job(|os| os.terminate_task());
    });
    assert_eq!(end, End::JobOver);
    assert_eq!(
        take_switch(&port, top - 40),
        SHARED.1 - 300,
        "Low where it was saved"
    );
    assert_eq!(sched(&port).current(), LOW.0);
    assert_eq!(port.inspect(|os| os.running()), Some(LOW));
    assert!(port.inspect(|os| os.hooks().errors()).is_empty());
}

/// A called job whose end lets in a job of a task above its caller (here by chaining
/// one with a stack of its own) gives the context back to the caller and requests the
/// switch, which saves the context as the caller's, below the ended job's frames: the
/// caller resumes there, and its call returns.
#[test]
fn a_called_jobs_end_that_lets_in_another_task_saves_the_context_as_the_callers() {
    let port = started();
    high_called(&port);
    // (On the CPU the switch runs inside the end, before it returns.)
    port.end_job(|os| os.chain_task(WAITER)).expect("ChainTask");
    assert!(port.arch().switch.get(), "the switch to Waiter's stack");
    assert_eq!(sched(&port).current(), LOW.0, "the context is Low's again");
    take_switch(&port, SHARED.1 - 240);
    assert_eq!(sched(&port).current(), WAITER.0);
    assert_eq!(port.arch().guard.get(), WAITER_STACK.0);
    let end = ends(|| {
        let _ = port.end_job(|os| os.terminate_task());
    });
    assert_eq!(
        end,
        End::JobOver,
        "Waiter's job, started by the switch, waits for it"
    );
    assert_eq!(
        take_switch(&port, WAITER_STACK.1 - 100),
        SHARED.1 - 240,
        "Low resumes where the switch saved it"
    );
    assert_eq!(sched(&port).current(), LOW.0);
    assert_eq!(port.inspect(|os| os.running()), Some(LOW));
    assert!(port.inspect(|os| os.hooks().errors()).is_empty());
}

/// The port's `ActivateTask` takes the kernel's fast path where the activated task
/// preempts at task level, and then starts the job by a call at once, leaving the kernel
/// as the full service leaves it; where the fast path declines (the task at its
/// activation limit), the full service refuses and reports, and nothing starts.
#[test]
fn the_ports_activation_takes_the_kernels_fast_path_and_then_calls_the_job() {
    let port = started();
    let mut reference = kernel_now(&port);
    assert_eq!(reference.activate_task(HIGH), Ok(()));
    port.arch().calls.set(true);
    let end = ends(|| {
        let _ = port.activate_task(HIGH);
    });
    assert_eq!(end, End::Called(HIGH.0));
    assert_eq!(kernel_now(&port), reference, "the state the service leaves");
    assert!(!port.lazy.in_kernel());
    assert_eq!(port.arch().level.get(), Some(InterruptMask::None));
    assert_eq!(sched(&port).caller_of(usize::from(HIGH.0)), Some(LOW.0));
    port.end_job(|os| os.terminate_task())
        .expect("TerminateTask");
    assert_eq!(sched(&port).current(), LOW.0);
    // Low activating itself: at its limit, the service's E_OS_LIMIT.
    assert_eq!(port.activate_task(LOW), Err(OsError::Limit));
    assert!(!port.arch().switch.get());
    assert_eq!(port.inspect(|os| os.hooks().errors()), [OsError::Limit]);
    // Without calls (an ISR's context on the CPU), the switch exception.
    port.arch().calls.set(false);
    assert_eq!(port.activate_task(HIGH), Ok(()));
    assert!(port.arch().switch.get());
}
