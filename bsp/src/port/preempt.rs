//! The preemptive port without the CPU: the kernel lock, the task switch's bookkeeping
//! (which job runs on which stack, where a new job's first frame goes), the end of a job,
//! stack faults and the checks of a configuration against what the port can do. The CPU
//! comes in through [`Arch`]: the Cortex-M port (`crate::cortex_m`) is this module over
//! its exceptions, BASEPRI, PRIMASK and MPU; the host tests run it over a model CPU
//! (`tests.rs`), with bolero harnesses that are also fuzz targets and Kani proofs.
//!
//! The book: [the Cortex-M4 image](../../../../book/cortex-m4.html), "The port's guarantees".
//!
//! # The rules it keeps
//!
//! - **Kernel lock at the OS level.** A kernel call masks what the OS serves (category-2
//!   ISRs, the OS tick, the task switch), not every interrupt: a category-1 ISR, whose
//!   priority the configuration puts above every category-2 one, is never delayed by a
//!   kernel call. A kernel call that finds another under way (a category-1 ISR calling the
//!   OS, which OSEK forbids) is a fatal port fault, never a second `&mut` on the kernel.
//! - **Masks.** After every call the OS level mask is the kernel's; every-interrupt masking
//!   (`DisableAllInterrupts`, `SuspendAllInterrupts`) is turned on and off only where the
//!   kernel's mask says so, so a kernel call made inside the caller's own critical
//!   section leaves that section closed.
//! - **One stack for the basic tasks.** OSEK basic tasks start and end in LIFO order, so
//!   a new job's first frame goes just below the deepest preempted job on the shared
//!   stack; a job that ends gives its part back. A task that can wait (an extended task)
//!   keeps its context while lower tasks run, so it must have a stack of its own: the
//!   port refuses to start otherwise ([`check`]), naming the task.
//! - **A new job by a call.** Where a job on the shared stack that goes on lets in, by
//!   its own kernel call, a new job of a task on the shared stack (an `ActivateTask`, a
//!   `Schedule`, a `ReleaseResource`), and the CPU runs a task's code with no critical
//!   section of the caller's own ([`Arch::may_call_job`]), the port calls the new job at
//!   the end of that kernel call, on the caller's stack, instead of requesting the switch
//!   exception: the LIFO order above makes the new job end before its caller resumes, as
//!   a call does. Its end gives the context back to the caller ([`back_to_caller`]),
//!   whose call returns; if the kernel then chose another job, the switch exception saves
//!   the context as the caller's, below the ended job's frames, and starts that job
//!   there (never a call from an ended job: a job that chains itself would nest on its
//!   own dead frames without end). The kernel's decisions and state are the same either
//!   way: only how the port carries out a switch changes (`spec::stacks_stay_apart`
//!   covers both ways).
//! - **A job that cannot end** (its `TerminateTask` refused: interrupts left disabled, a
//!   resource still held) is ended by the kernel's `task_returned` (`E_OS_MISSINGEND` to
//!   the ErrorHook, its resources and locks released, as AUTOSAR's SWS_Os_00052 and
//!   SWS_Os_00069 say), instead of spinning at its priority for ever.
//! - **A task's lock outside the kernel.** A task at task level that holds nothing and
//!   has no interrupt lock in force takes a resource it declares
//!   ([`Os::lock_free_resources`](cw_core::os::Os::lock_free_resources), asked at the end
//!   of every kernel call, and kept in the port's `lazy` word) without a kernel call: one
//!   store of the lock into that word, in the answer's place, where no ISR uses it; where
//!   ISRs share it, the same store under the kernel lock and then the mask of the
//!   resource's ceiling (BASEPRI), the order that keeps every ISR that could find the word
//!   from finding a weaker mask. The kernel's answer names each resource by the kind of
//!   lock its ceiling makes, and a resource's type may carry that kind, so the lock of one
//!   no ISR uses needs no table; the lock in the word names no resource, so the lock's one
//!   test refuses a second lock too. The release puts the answer's copy back in the word
//!   and reads the copy again, which a hand-over sets to 0 (then the kernel releases it),
//!   and for a lock that masked ISRs the task's mask (none) again.
//!   The kernel is told at the task's
//!   next kernel call, or at the next ISR's entry, whichever comes first: `enter` hands the
//!   lock to the kernel's own fast path before anything else, so the kernel sees the same
//!   calls in the same order, and every decision it makes (a switch, an error, the mask an
//!   ISR returns to) sees the lock. A lock and release with no kernel call between them
//!   leave the kernel as they found it, with the masks the port applied
//!   (`cw_core::os::spec::lock_pair_leaves_no_trace`), so the kernel need never see them.
//!   A lock handed over is released through the kernel. One such lock at a time: a second,
//!   nested, goes through the kernel. The tests take an interrupt, one per call, at each
//!   point the code marks between two stores ([`Arch::may_interrupt`]).
//! - **Stack faults.** A context switch that finds the outgoing stack pointer inside the
//!   stack's guard or, on a CPU without an MPU, the guard's memory written
//!   ([`Arch::guard_intact`]), or the CPU's guard fault, ends in
//!   `ShutdownOS(E_OS_STACKFAULT)` with
//!   the ShutdownHook, also when the fault interrupted a kernel call (whose context never
//!   resumes).

use core::cell::UnsafeCell;
use core::sync::atomic::{compiler_fence, AtomicU8, Ordering};

use cw_core::os::{
    CounterId, InterruptMask, IsrConfig, IsrId, OsError, ResourceId, TaskConfig, TaskId, TaskKind,
    TaskState, ISR_LEVEL_BASE,
};

use super::lazy::LazyLock;
use super::{Held, OsKernel, Port, TickPath};

pub mod spec;
#[cfg(test)]
mod tests;

/// The most tasks the port switches between (its tables' size; the kernel allows more,
/// which [`check`] refuses).
pub const MAX_TASKS: usize = 16;
/// The slot of the idle loop in the port's tables.
pub const IDLE: u8 = MAX_TASKS as u8;

/// What the port needs of the CPU.
///
/// An implementation is the interrupt controller and the stack layout of one core; every
/// method is short and does exactly what it says (the decisions are this module's).
pub trait Arch {
    /// The OSEK ISR priorities the interrupt controller tells apart: `1 ..= ISR_PRIORITIES`
    /// (above them the CPU's own faults, below them the task switch).
    const ISR_PRIORITIES: u8;
    /// Bytes at the bottom of every task stack that the stack guard covers.
    const GUARD_BYTES: u32;
    /// Bytes a new job's first frame takes below its stack's top (alignment included).
    const FIRST_FRAME_BYTES: u32;

    /// Takes the kernel lock: masks every interrupt the OS serves (category-2 ISRs, the OS
    /// tick, the task switch); category-1 ISRs above the OS level keep running.
    fn lock_os(&self);
    /// Sets the OS-level mask to the kernel's interrupt mask, ending the kernel lock
    /// (`All`: the OS level; every other interrupt is [`Arch::disable_all`]'s).
    fn set_mask(&self, mask: InterruptMask);
    /// [`Arch::set_mask`] for the mask of processor priority `level`
    /// ([`InterruptMask::at_level`]; `u8::MAX` is `All`), as the port ends every kernel
    /// call; a CPU may map the level to its mask register more directly.
    #[inline(always)]
    fn set_level(&self, level: u8) {
        self.set_mask(InterruptMask::at_level(level));
    }
    /// What [`Arch::set_level`] puts in the mask register for processor priority `level`,
    /// an interrupt level (at or above `ISR_LEVEL_BASE`, below `u8::MAX`), computed once:
    /// the port keeps it per resource for the locks outside the kernel, and takes 0 for a
    /// ceiling at a task's level, so the value of an interrupt level is never 0. The level
    /// itself by default.
    #[inline(always)]
    fn level_value(level: u8) -> u8 {
        level
    }
    /// [`Arch::set_level`] with the value [`Arch::level_value`] computed for the level.
    #[inline(always)]
    fn set_level_value(&self, value: u8) {
        self.set_level(value);
    }
    /// Whether every interrupt is masked now ([`Arch::disable_all`], or the caller's own
    /// critical section).
    fn all_masked(&self) -> bool;
    /// Masks every interrupt (category 1 included).
    fn disable_all(&self);
    /// Unmasks what [`Arch::disable_all`] masked.
    fn enable_all(&self);
    /// Requests the task switch, which runs when no ISR is active and the mask allows.
    fn request_switch(&self);
    /// Waits for an interrupt (a job that has ended waits here for its switch).
    fn wait(&self);
    /// Writes a new job's first frame for `task` just below `top` and returns the stack
    /// pointer the switch loads.
    ///
    /// # Safety
    /// The [`Arch::FIRST_FRAME_BYTES`] below `top` must be stack memory nothing uses.
    unsafe fn first_frame(&self, top: u32, task: u8) -> u32;
    /// Moves the running context's stack guard to the stack whose lowest address is
    /// `bottom`.
    fn move_guard(&self, bottom: u32);
    /// Whether the guard of the stack whose lowest address is `bottom` is untouched. A
    /// CPU that enforces the guards (an MPU) answers `true`; one that cannot checks the
    /// guard's memory, and the switch calls this for the outgoing context: an overflow is
    /// then found at the next switch instead of at its first access (AUTOSAR OS's stack
    /// monitoring).
    fn guard_intact(&self, bottom: u32) -> bool;
    /// Masks the interrupt line of the ISR running now (its entry was refused, so nothing
    /// clears its source).
    fn quiet_active_line(&self);
    /// Logs a fault (the port goes on to end the run: `ShutdownOS` or [`Arch::halt`]).
    fn report(&self, fault: &PortFault);
    /// The OS has shut down: the application's end (its report, safe state, stop).
    fn stopped(&self) -> !;
    /// A fault the OS cannot go on from: the board's safe state, then reset or halt.
    fn halt(&self) -> !;
    /// Milliseconds since the OS tick started.
    fn now_ms(&self) -> u64;
    /// A mark for the task trace (the measuring images); nothing by default.
    fn trace(&self, _mark: Mark) {}
    /// A point in the port's paths outside the kernel (a lock kept there, its release)
    /// where an interrupt the mask in force admits may arrive: nothing on a CPU, where the
    /// interrupt comes by itself. The port's model CPU takes one there, so that its
    /// harness checks every place between two stores.
    #[inline(always)]
    fn may_interrupt(&self) {}
    /// Whether a new job may start here by a call, on the running context's stack: the
    /// CPU runs a task's code (no ISR or exception active) and every interrupt is
    /// unmasked but for the OS level's mask (no critical section of the caller's own,
    /// which a switch must wait for). `false` keeps every switch the switch exception's.
    fn may_call_job(&self) -> bool;
    /// Runs a job of `task` from its first line to its end (the application's job entry),
    /// as a call: it returns once the job has ended and its caller goes on.
    fn call_job(&self, task: u8);
}

/// A mark the port passes to the CPU's task trace.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// A job of the task starts.
    JobStarted(TaskId),
    /// The task's job is over.
    JobFinished(TaskId),
    /// The kernel accepted the category-2 ISR's entry.
    IsrEntered(IsrId),
    /// A measured span of the application starts.
    SpanStart(usize),
    /// A measured span of the application ends.
    SpanEnd(usize),
    /// Measured span `started` ends and its length is filed under span `id`.
    SpanEndAs {
        /// The span that started.
        started: usize,
        /// The span its length is filed under.
        id: usize,
    },
}

/// A fault of the port (every one names what it is about).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PortFault {
    /// The configuration asks for something the port cannot do (refused at start).
    Refused(Refusal),
    /// A task stack given to the port is refused (the task, and why).
    StackRefused {
        /// The task's index.
        task: u8,
        /// Why.
        why: &'static str,
    },
    /// A kernel call was made while another was under way (a category-1 ISR called the
    /// OS, or the port was re-entered).
    KernelReentered,
    /// A stack overflowed: a task's own (named) or the shared one (`None`); the OS shuts
    /// down with `E_OS_STACKFAULT`.
    StackOverflow(Option<&'static str>),
    /// The main stack (ISRs, exceptions) overflowed into its guard.
    MainStackOverflow,
    /// The OS shut down before the application was there to end the run.
    NoApplication,
    /// A task's lock kept outside the kernel was refused when it was handed to the
    /// kernel (the port's own contract broken; never seen).
    LockRefused,
    /// The non-maskable interrupt (on the boards here, the watchdog's first timeout).
    Nmi,
    /// A fault of the CPU or the board (its name).
    Board(&'static str),
}

impl PortFault {
    /// What happened and to what: two words a log prints without formatting machinery.
    pub const fn parts(&self) -> (&'static str, &'static str) {
        match *self {
            Self::Refused(r) => r.parts(),
            Self::StackRefused { why, .. } => ("task stack refused", why),
            Self::KernelReentered => (
                "kernel call inside a kernel call",
                "a category-1 ISR may not call the OS",
            ),
            Self::StackOverflow(Some(task)) => ("stack overflow on the stack of", task),
            Self::StackOverflow(None) => ("stack overflow on", "the shared task stack"),
            Self::MainStackOverflow => ("stack overflow on", "the main stack (ISRs)"),
            Self::NoApplication => ("the OS stopped", "without an application"),
            Self::LockRefused => (
                "a lock kept outside the kernel",
                "was refused when handed to it",
            ),
            Self::Nmi => ("fault", "NMI"),
            Self::Board(what) => ("fault", what),
        }
    }
}

/// Why the port refuses a configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// More tasks than the port's tables hold ([`MAX_TASKS`]); names the first one over.
    TooManyTasks(&'static str),
    /// An extended task without a stack of its own: on the shared stack, a lower task
    /// resumed while it waits would overwrite its saved context.
    NoOwnStack(&'static str),
    /// An ISR priority outside `1 ..= Arch::ISR_PRIORITIES`: the interrupt controller
    /// would merge it with another level, or with the task switch's.
    IsrPriority(&'static str),
}

impl Refusal {
    /// What is refused and which item.
    pub const fn parts(&self) -> (&'static str, &'static str) {
        match *self {
            Self::TooManyTasks(task) => ("more tasks than the port holds, from", task),
            Self::NoOwnStack(task) => ("an extended task needs a stack of its own:", task),
            Self::IsrPriority(isr) => ("an ISR priority the port cannot express:", isr),
        }
    }
}

/// Checks a configuration against what the port can do: at most [`MAX_TASKS`] tasks,
/// every ISR priority in `1 ..= isr_priorities`, and (when `has_own_stack` is known)
/// every extended task with a stack of its own. A `const fn`, so an image checks its
/// configuration when it is built ([`assert_fits`]); [`Preemptive::start_checked`] checks
/// again at start, with the stacks given.
///
/// # Errors
/// The first item refused.
pub const fn check(
    tasks: &[TaskConfig],
    isrs: &[IsrConfig],
    isr_priorities: u8,
    own_stacks: Option<u32>,
) -> Result<(), Refusal> {
    let mut t = 0;
    while t < tasks.len() {
        if t >= MAX_TASKS {
            return Err(Refusal::TooManyTasks(tasks[t].name));
        }
        if let (TaskKind::Extended, Some(stacks)) = (tasks[t].kind, own_stacks) {
            if stacks & (1 << t) == 0 {
                return Err(Refusal::NoOwnStack(tasks[t].name));
            }
        }
        t += 1;
    }
    let mut i = 0;
    while i < isrs.len() {
        let p = isrs[i].priority;
        if p == 0 || p > isr_priorities {
            return Err(Refusal::IsrPriority(isrs[i].name));
        }
        i += 1;
    }
    Ok(())
}

/// [`check`] when the image is built (stacks are given at start and checked there): a
/// build error naming the item refused. For a `const _: () = assert_fits(..);` item only:
/// its panics are build errors, never reached at run time.
#[allow(clippy::panic)]
pub const fn assert_fits(tasks: &[TaskConfig], isrs: &[IsrConfig], isr_priorities: u8) {
    // A const panic formats one `&str`: the item; the line says which rule.
    match check(tasks, isrs, isr_priorities, None) {
        Ok(()) => {}
        // More tasks than the port's tables hold (MAX_TASKS), from this one on.
        Err(Refusal::TooManyTasks(task)) => panic!("{}", task),
        // An ISR priority outside 1 ..= isr_priorities.
        Err(Refusal::IsrPriority(isr)) => panic!("{}", isr),
        // (Not without stacks.)
        Err(Refusal::NoOwnStack(task)) => panic!("{}", task),
    }
}

/// The port's view of the jobs and their stacks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sched {
    /// The slot now executing (a task index, or [`IDLE`]).
    current: u8,
    /// The slot the kernel chose last.
    next: u8,
    /// The current job ended (`TerminateTask`, `ChainTask` or `task_returned`): its stack
    /// part is free.
    ended: bool,
    /// Saved stack pointers of preempted (or waiting) jobs and of the idle loop.
    sp: [u32; MAX_TASKS + 1],
    /// Bit `t`: task `t` has a job under way (a context to resume).
    started: u32,
    /// The shared stack's top when each job on it started (given back when it ends).
    job_base: [u32; MAX_TASKS],
    /// Of each job started by a call ([`start_by_call`]), the slot of the job that called
    /// it, which goes on when it ends, plus one; 0 for a job the switch started.
    called_from: [u8; MAX_TASKS],
    /// Where the next new job's first frame goes on the shared stack.
    basic_top: u32,
    /// The shared stack: (lowest address, top).
    shared: (u32, u32),
    /// Each task's own stack as (lowest address, top), or (0, 0): the shared stack.
    own_stack: [(u32, u32); MAX_TASKS],
    /// The port set every-interrupt masking for the kernel's `All` mask.
    all_for_kernel: bool,
    /// The OS has shut down and the application was told.
    stopped: bool,
}

impl Sched {
    /// Before start: nothing runs, no stack is known.
    pub const fn new() -> Self {
        Self {
            current: IDLE,
            next: IDLE,
            ended: false,
            sp: [0; MAX_TASKS + 1],
            started: 0,
            job_base: [0; MAX_TASKS],
            called_from: [0; MAX_TASKS],
            basic_top: 0,
            shared: (0, 0),
            own_stack: [(0, 0); MAX_TASKS],
            all_for_kernel: false,
            stopped: false,
        }
    }

    /// Whether `slot` runs on the shared stack.
    fn on_shared(&self, slot: usize) -> bool {
        self.own_stack.get(slot).is_none_or(|r| r.1 == 0)
    }

    /// Whether the job under way in `slot` was started by a call.
    fn was_called(&self, slot: usize) -> bool {
        self.called_from.get(slot).is_some_and(|&from| from != 0)
    }

    /// The slot that called the job under way in `slot`, if a call started it.
    pub fn caller_of(&self, slot: usize) -> Option<u8> {
        self.called_from
            .get(slot)
            .and_then(|&from| from.checked_sub(1))
    }

    /// Gives `slot` its own stack `bottom .. top` (nothing if out of range).
    pub(crate) fn set_own_stack(&mut self, slot: usize, bottom: u32, top: u32) {
        if let Some(own) = self.own_stack.get_mut(slot) {
            *own = (bottom, top);
        }
    }

    /// The stack of `slot`: (lowest address, top).
    pub fn stack_of(&self, slot: usize) -> (u32, u32) {
        match self.own_stack.get(slot) {
            Some(&own) if own.1 != 0 => own,
            _ => self.shared,
        }
    }

    /// The slot now executing.
    pub const fn current(&self) -> u8 {
        self.current
    }

    /// One bit per task with a stack of its own.
    pub fn own_stacks(&self) -> u32 {
        self.own_stack
            .iter()
            .enumerate()
            .filter(|(_, r)| r.1 != 0)
            .fold(0, |bits, (t, _)| bits | 1 << t)
    }

    /// Where the next new job on the shared stack starts.
    pub const fn basic_top(&self) -> u32 {
        self.basic_top
    }
}

impl Default for Sched {
    fn default() -> Self {
        Self::new()
    }
}

/// What a context switch does, decided from the port's tables alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// Resume the saved context at this stack pointer.
    Resume(u32),
    /// Start a new job of `task`: its first frame goes below `top`.
    Start {
        /// The task.
        task: u8,
        /// Its first frame's top.
        top: u32,
    },
    /// The outgoing context's stack pointer lies in its stack's guard: an overflow (the
    /// task's own stack, or the shared one: `None`).
    Overflow(Option<u8>),
}

/// The switch's decision: saves the outgoing context's stack pointer `sp` (or frees its
/// part of the shared stack if its job ended) and names the incoming context.
pub fn decide(s: &mut Sched, sp: u32, guard_bytes: u32) -> Switch {
    let current = usize::from(s.current);
    let (bottom, _) = s.stack_of(current);
    if sp < bottom.saturating_add(guard_bytes) {
        return Switch::Overflow((!s.on_shared(current)).then_some(s.current));
    }
    if s.ended && current < MAX_TASKS {
        s.started &= !(1 << current);
        if s.on_shared(current) {
            s.basic_top = s.job_base[current];
        }
        s.ended = false;
    } else if let Some(slot) = s.sp.get_mut(current) {
        *slot = sp;
        if s.on_shared(current) {
            s.basic_top = sp;
        }
    }
    let next = usize::from(s.next);
    s.current = s.next;
    if next >= MAX_TASKS || s.started & (1 << next) != 0 {
        return Switch::Resume(s.sp.get(next).copied().unwrap_or(sp));
    }
    s.started |= 1 << next;
    let top = if s.on_shared(next) {
        s.job_base[next] = s.basic_top;
        s.basic_top
    } else {
        s.own_stack[next].1
    };
    Switch::Start {
        task: next as u8,
        top,
    }
}

/// What the end of a kernel call returns where no job starts by a call (else the task).
const NO_CALL: u8 = IDLE;

/// The mask that ends a kernel lock ([`Preemptive::end_lock`]).
#[derive(Clone, Copy)]
enum LockEnd {
    /// The kernel's mask as a processor level.
    Level(u8),
    /// Every-interrupt masking began or ended: the kernel's mask.
    AllChanged(InterruptMask),
}

/// Whether the kernel's choice `s.next` may start by a call from the running job: a new
/// job of a task on the shared stack, the running context a job on the shared stack that
/// goes on (OSEK's basic tasks start and end in LIFO order there, so the new job ends
/// before its caller resumes, as a call does).
pub fn callable(s: &Sched) -> bool {
    let (current, next) = (usize::from(s.current), usize::from(s.next));
    // (A job under way has its bit in `started`: `next` is not `current`.)
    !s.ended
        && current < MAX_TASKS
        && next < MAX_TASKS
        && s.started & (1 << next) == 0
        && s.on_shared(current)
        && s.on_shared(next)
}

/// The bookkeeping of a new job of `s.next` started by a call ([`callable`]): it runs
/// on the running job's stack below the call, and its caller's context is the call
/// chain above it. The port writes nothing on the stack for it (a switch away from the
/// new job saves the new job's stack pointer, below both), so there is no check of the
/// stack pointer here: the call is one more call of the caller's, under the same guard.
pub fn start_by_call(s: &mut Sched) {
    let next = usize::from(s.next);
    if let Some(from) = s.called_from.get_mut(next) {
        *from = s.current + 1;
    }
    s.started |= 1 << next;
    s.current = s.next;
}

/// The running job ended and was started by a call: the context is its caller's again
/// (whose call returns once the ended job's frames are left), and the switch, if the
/// kernel chose another job, saves it as the caller's. `false`: not such a job, nothing
/// done.
pub fn back_to_caller(s: &mut Sched) -> bool {
    let current = usize::from(s.current);
    let Some(from) = s.called_from.get_mut(current) else {
        return false;
    };
    if !s.ended || *from == 0 {
        return false;
    }
    s.current = core::mem::take(from) - 1;
    s.started &= !(1 << current);
    s.ended = false;
    true
}

/// The preemptive port of a kernel `K` on a CPU `A`.
///
/// Laid out in the order declared (`repr(C)`): the kernel first, then the tables, the
/// lock outside the kernel with the kernel call's flag and the CPU (the kernel lock's
/// level), which every kernel call reads, and the table of ceilings' masks last, so that
/// its size moves none of the others. (In the compiler's own order, the table shrinking
/// by 15 bytes moved fields, and the image's tick handler then spilled registers it had
/// kept: 14 instructions more on a tick with alarms due.)
#[repr(C)]
pub struct Preemptive<K, A> {
    kernel: UnsafeCell<K>,
    sched: UnsafeCell<Sched>,
    /// A task's lock kept outside the kernel and the resources the running task may lock
    /// so (the module's rules); with them the flag that a kernel call is under way (a
    /// second one would alias the kernel), outside `sched` so that the check itself takes
    /// no reference to the tables, and in the word the lock outside the kernel tests
    /// anyway ([`LazyLock::begin_kernel`]).
    lazy: LazyLock,
    arch: A,
    /// The mask a lock kept outside the kernel applies, per resource: the
    /// [`Arch::level_value`] of its ceiling ([`OsKernel::ceiling`]) where that is an
    /// interrupt level, 0 where it is a task's (no mask), computed by
    /// [`Preemptive::start_checked`]. (Until then no task runs, so nothing is locked
    /// outside the kernel.)
    lazy_levels: [AtomicU8; LAZY_RESOURCES],
}

/// The resources a lock may be kept outside the kernel for
/// ([`cw_core::os::LOCK_FREE_RESOURCES`]), each with its bits in the kernel's answer
/// ([`OsKernel::lock_free_resources`]).
const LAZY_RESOURCES: usize = cw_core::os::LOCK_FREE_RESOURCES as usize;

/// The processor priority a task returns to when it releases a lock kept outside the
/// kernel: the task held nothing and had no interrupt lock when it took the lock, so it
/// masked no interrupt (`cw_core::os::spec::lock_pair_leaves_no_trace`), and level 0
/// masks none.
const TASK_LEVEL: u8 = 0;

// SAFETY: the kernel and the tables are reached only with the kernel lock taken (every
// ISR that may call the OS and the task switch masked, on a single core) and the kernel
// call's flag (`LazyLock::begin_kernel`) set by a test and a store that refuse a second
// entry; the fault paths that take them without the flag never return to the context
// they interrupted.
unsafe impl<K: Send, A: Sync> Sync for Preemptive<K, A> {}

impl<K: OsKernel, A: Arch> Preemptive<K, A> {
    /// The port of `kernel` on `arch`.
    pub const fn new(kernel: K, arch: A) -> Self {
        Self {
            kernel: UnsafeCell::new(kernel),
            sched: UnsafeCell::new(Sched::new()),
            lazy: LazyLock::new(),
            lazy_levels: [const { AtomicU8::new(0) }; LAZY_RESOURCES],
            arch,
        }
    }

    /// The CPU.
    pub const fn arch(&self) -> &A {
        &self.arch
    }

    /// Runs `f` on the tables with every interrupt masked, outside any kernel call
    /// (set-up, reports).
    fn with_sched<R>(&self, f: impl FnOnce(&mut Sched) -> R) -> R {
        self.masked(|_, sched| f(sched))
    }

    /// Runs `f` on the kernel (to read it) and the tables with every interrupt masked,
    /// outside any kernel call: for set-up before the OS starts, where there is no
    /// decision of the kernel to carry out and no category-1 ISR to delay yet.
    pub fn before_start<R>(&self, f: impl FnOnce(&K, &mut Sched) -> R) -> R {
        self.masked(f)
    }

    fn masked<R>(&self, f: impl FnOnce(&K, &mut Sched) -> R) -> R {
        let masked = self.arch.all_masked();
        self.arch.disable_all();
        if self.lazy.in_kernel() {
            self.fatal(PortFault::KernelReentered);
        }
        // SAFETY: every interrupt is masked and no kernel call is under way: the only
        // references to the kernel and the tables.
        let result = f(unsafe { &*self.kernel.get() }, unsafe {
            &mut *self.sched.get()
        });
        if !masked {
            self.arch.enable_all();
        }
        result
    }

    /// Tells the port where the shared stack of the basic tasks is; before start.
    pub fn set_shared_stack(&self, bottom: u32, top: u32) {
        self.with_sched(|s| {
            s.shared = (bottom, top);
            s.basic_top = top;
        });
    }

    /// Gives `task` its own stack `bottom .. top`; before start. A fatal port fault if
    /// `task` is out of range, the stack is too small for its guard and one frame, or it
    /// overlaps a stack given before.
    pub fn set_task_stack(&self, task: TaskId, bottom: u32, top: u32) {
        let refused = self.with_sched(|s| {
            let overlaps = s
                .own_stack
                .iter()
                .chain(core::iter::once(&s.shared))
                .any(|&(b, t)| t != 0 && bottom < t && b < top);
            let fits = top > bottom && top - bottom >= A::GUARD_BYTES + 2 * A::FIRST_FRAME_BYTES;
            let slot = usize::from(task.0);
            if slot >= MAX_TASKS {
                Some("task out of range")
            } else if !fits {
                Some("too small for its guard and a frame")
            } else if overlaps {
                Some("overlaps another stack")
            } else {
                s.set_own_stack(slot, bottom, top);
                None
            }
        });
        if let Some(why) = refused {
            self.fatal(PortFault::StackRefused { task: task.0, why });
        }
    }

    /// The stack of `task` (its own, or the shared one): (lowest address, top).
    pub fn stack_of(&self, task: TaskId) -> (u32, u32) {
        self.with_sched(|s| s.stack_of(usize::from(task.0)))
    }

    /// One bit per task with its own stack.
    pub fn own_stacks(&self) -> u32 {
        self.with_sched(|s| s.own_stacks())
    }

    /// Checks the kernel's configuration against the port (task count, ISR priorities,
    /// an own stack for every extended task); a fatal port fault naming the item if it
    /// does not fit; then computes each resource's mask for the locks outside the kernel.
    /// Called by the CPU's start, before the OS starts: a port that starts the OS without
    /// it would lock a resource that ISRs share with the store alone.
    pub fn start_checked(&self) {
        let stacks = self.own_stacks();
        let refused =
            self.before_start(|k, _| check(k.tasks(), k.isrs(), A::ISR_PRIORITIES, Some(stacks)));
        if let Err(r) = refused {
            self.fatal(PortFault::Refused(r));
        }
        self.before_start(|k, _| {
            for (r, level) in (0u8..).zip(&self.lazy_levels) {
                let value = match k.ceiling(ResourceId(r)) {
                    Some(ceiling) if ceiling >= ISR_LEVEL_BASE => A::level_value(ceiling),
                    _ => 0,
                };
                level.store(value, Ordering::Relaxed);
            }
        });
        // The idle loop is the shared stack's bottom context.
        self.with_sched(|s| s.guard_slot_start());
    }

    /// A kernel call found another under way: a fatal port fault. Out of line and without
    /// arguments, so that the kernel lock's callers keep small frames.
    #[cold]
    #[inline(never)]
    fn reentered(&self) -> ! {
        self.fatal(PortFault::KernelReentered)
    }

    /// A fatal port fault: reported, then the board's end.
    pub fn fatal(&self, fault: PortFault) -> ! {
        self.arch.disable_all();
        self.arch.report(&fault);
        self.arch.halt()
    }

    /// Runs `f` on the kernel under the kernel lock, then carries out what the kernel
    /// decided: the OS-level mask, every-interrupt masking if the kernel's mask changed
    /// it, the task switch, or the end of the OS.
    #[inline(always)]
    fn locked<R>(&self, f: impl FnOnce(&mut K, &mut Sched) -> R) -> R {
        let (kernel, sched) = self.enter();
        let result = f(kernel, sched);
        self.leave();
        result
    }

    /// The kernel lock taken: the kernel and the tables ([`Preemptive::enter_saving`]).
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    fn enter(&self) -> (&mut K, &mut Sched) {
        let (kernel, sched, _) = self.enter_saving();
        (kernel, sched)
    }

    /// The kernel lock taken: the kernel, the tables, and the lock word from before the
    /// call (the kernel's answer, which resources the running task may lock outside the
    /// kernel, or a release's store of it just after a hand-over, whose copy says 0; 0
    /// where a lock kept outside the kernel was handed over now, since the task holds a
    /// resource), for a call that leaves the answer as it was: the word alone goes back
    /// ([`Preemptive::leave_restoring`] with it, never [`Preemptive::leave_at`], which
    /// would set the copy too). Not generic
    /// over the call, so a size-optimised image keeps one copy (a speed-optimised one
    /// inlines it).
    #[inline]
    #[allow(clippy::mut_from_ref)]
    fn enter_saving(&self) -> (&mut K, &mut Sched, u32) {
        self.arch.lock_os();
        // A plain load and store (one core; the lock holds every ISR that may call the OS):
        // a category-1 ISR calling the OS during a kernel call finds the flag set.
        let Some(mut lock_free) = self.lazy.begin_kernel() else {
            self.reentered()
        };
        compiler_fence(Ordering::SeqCst);
        let (kernel, sched) = self.tables();
        if let Some(lock) = LazyLock::to_hand_over(lock_free) {
            self.hand_over(kernel, lock);
            lock_free = 0;
        }
        (kernel, sched, lock_free)
    }

    /// The kernel and the tables, in a kernel call (the kernel lock taken, the kernel
    /// call's flag on): the references of [`Preemptive::enter`], taken again by the
    /// call's end, which must not be given them as arguments (a job it starts by a call
    /// makes kernel calls of its own, and takes them again).
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    fn tables(&self) -> (&mut K, &mut Sched) {
        // SAFETY: the kernel lock masks every ISR that may call the OS and the switch, and
        // the caller turned the kernel call's flag on: the only references until the
        // call's end turns it off (each caller takes them once, and the earlier ones are
        // not used after).
        unsafe { (&mut *self.kernel.get(), &mut *self.sched.get()) }
    }

    /// A task's lock kept outside the kernel meets the first kernel call since
    /// ([`LazyLock::hand_over`]); a refusal breaks the port's own contract: a fatal fault.
    #[cold]
    #[inline(never)]
    fn hand_over(&self, kernel: &mut K, lock: u32) {
        if !self.lazy.hand_over(kernel, lock) {
            self.fatal(PortFault::LockRefused);
        }
    }

    /// `GetResource` outside the kernel, where the module's rules allow it: the running
    /// task may lock `res` so, by a lock of the kind `masked` says, and no other lock is
    /// kept outside the kernel ([`LazyLock::may_take`]), and no kernel call is under way (a
    /// hook's lock goes to the kernel). The kernel's answer names a resource no ISR shares
    /// by the kind that masks nothing: one store. One that ISRs share it names by the other
    /// kind: the store under the kernel lock and then the mask of the resource's ceiling.
    /// No kernel call either way. The kernel hears of the lock at the next kernel call
    /// ([`Preemptive::hand_over`]). `false`: nothing done.
    #[inline(always)]
    fn lazy_get(&self, res: ResourceId, masked: bool) -> bool {
        // (During a kernel call the word is the kernel call's flag alone, and while a lock
        // is kept outside the kernel the lock: neither names a resource.)
        if !self.lazy.may_take(res, masked) {
            return false;
        }
        if !masked {
            // (An ISR between the test and the store finds nothing to hand over, and a
            // task it lets in ends, or waits holding nothing, before this one goes on: the
            // word holds the task's answer again and the mask is the task's.) No ISR uses
            // the resource, and an
            // ISR that finds the word ends with the mask of the task at its ceiling, a
            // task's level, which masks nothing.
            self.arch.may_interrupt();
            self.lazy.take(res, false);
        } else {
            let Some(level) = self.lazy_levels.get(usize::from(res.0)) else {
                return false;
            };
            let value = level.load(Ordering::Relaxed);
            if value == 0 {
                // (Not computed yet: the port has not started, and no task runs.)
                return false;
            }
            // (An ISR between the test and the kernel lock: as above.) The store under the
            // kernel lock: an ISR that finds the word finds the ceiling's mask in force,
            // which it keeps (the kernel it hands the lock to masks as much). Without it
            // an ISR above the ceiling, between the ceiling's mask and the store, would end
            // by putting back the mask of a task that holds nothing.
            self.arch.may_interrupt();
            self.arch.lock_os();
            self.arch.may_interrupt();
            self.lazy.take(res, true);
            self.arch.may_interrupt();
            self.arch.set_level_value(value);
        }
        // The resource's data is reached only after the lock.
        compiler_fence(Ordering::SeqCst);
        true
    }

    /// `ReleaseResource` of a lock of `res` of the kind `masked` says, where the word
    /// holds it (the general release, which does not know how the lock was taken): the
    /// release outside the kernel ([`Preemptive::release_outside`]). `false`: nothing done
    /// (no such lock in the word: the kernel's, or of the other kind, or handed over).
    #[inline(always)]
    fn lazy_release(&self, res: ResourceId, masked: bool) -> bool {
        compiler_fence(Ordering::SeqCst);
        self.arch.may_interrupt();
        // (An ISR between the test and the release hands the lock over: the release then
        // finds the answer 0.)
        self.lazy.holds(res, masked) && self.release_outside(masked)
    }

    /// `ReleaseResource` of the lock the running task took outside the kernel, of the
    /// kind `masked` says: the kernel's answer back in the word and read again
    /// ([`LazyLock::release`]: no exchange, since an ISR that hands the lock over between
    /// the read and the store leaves the answer 0, which the second read finds); then,
    /// for a lock that masked ISRs, the task's mask again. `false`: the lock was handed
    /// to the kernel, which releases it, masks included.
    #[inline(always)]
    fn release_outside(&self, masked: bool) -> bool {
        // The resource's data is left before the release.
        compiler_fence(Ordering::SeqCst);
        self.arch.may_interrupt();
        if !self.lazy.release(|| self.arch.may_interrupt()) {
            return false;
        }
        if masked {
            // (An ISR between the release and the mask finds a task that holds nothing,
            // and ends with the task's mask, which this puts back too.)
            self.arch.may_interrupt();
            self.arch.set_level(TASK_LEVEL);
        }
        true
    }

    /// Carries out what the kernel decided and ends the kernel lock: the OS-level mask,
    /// every-interrupt masking if the kernel's mask changed it, the task switch, or the
    /// end of the OS. A job started by a call that ended gives the context back to its
    /// caller ([`back_to_caller`]). A new job the running job's own kernel call let in
    /// starts by a call where it may ([`callable`], [`Arch::may_call_job`]), once the
    /// kernel lock has ended and the references to the kernel and the tables are no
    /// longer used ([`Preemptive::call_job`]).
    #[inline]
    fn leave(&self) {
        let (kernel, sched) = self.tables();
        let next = kernel.running().map_or(IDLE, |t| t.0);
        if next == IDLE && kernel.is_shut_down() {
            self.stopping(sched);
            return;
        }
        sched.next = next;
        let mut call = NO_CALL;
        if next != sched.current || sched.ended {
            if sched.ended {
                // A job started by a call gives the context back to its caller; if the
                // kernel chose another job, the switch exception saves the context as the
                // caller's, below the ended job's frames. (A new job started by a call
                // from there would nest on those frames, and a job that chains itself
                // would nest without end.) A job the switch started: the switch frees
                // its part of the stack.
                if !back_to_caller(sched) || next != sched.current {
                    self.arch.request_switch();
                }
            } else if self.arch.may_call_job() {
                call = self.switch_or_call(sched);
            } else {
                // (An ISR's kernel call, the common one here: the switch exception, after
                // the ISR.)
                self.arch.request_switch();
            }
        }
        let end = self.end_lock(kernel, sched);
        // The references above are no longer used: an interrupt the mask below lets in,
        // and the job called, take them again.
        self.apply(end);
        if call != NO_CALL {
            self.call_job(call);
        }
    }

    /// The kernel lock's end, with the references of the kernel call: the kernel's mask
    /// as a level (`InterruptMask::at_level`; `u8::MAX` is `All`), and which resources
    /// the running task may lock outside the kernel now. Returns the mask to apply, which
    /// the caller applies once it no longer uses those references ([`Preemptive::apply`]).
    #[inline(always)]
    fn end_lock(&self, kernel: &K, sched: &mut Sched) -> LockEnd {
        let (level, lock_free) = kernel.port_view();
        let all = level == u8::MAX;
        let end = if all == sched.all_for_kernel {
            LockEnd::Level(level)
        } else {
            // DisableAllInterrupts or SuspendAllInterrupts began or ended.
            sched.all_for_kernel = all;
            LockEnd::AllChanged(InterruptMask::at_level(level))
        };
        compiler_fence(Ordering::SeqCst);
        // The answer, and the kernel call's end with it.
        self.lazy.set_answer(lock_free);
        end
    }

    /// Applies the mask that ends the kernel lock ([`Preemptive::end_lock`]).
    #[inline(always)]
    fn apply(&self, end: LockEnd) {
        match end {
            LockEnd::Level(level) => self.arch.set_level(level),
            LockEnd::AllChanged(mask) => self.all_changed(mask),
        }
    }

    /// The kernel chose another job for a job that goes on, in a task's code
    /// ([`Arch::may_call_job`]): the new job by a call where it may start so
    /// ([`callable`]; its task returned, the bookkeeping done), else the switch exception
    /// requested ([`NO_CALL`] returned).
    #[inline(never)]
    fn switch_or_call(&self, sched: &mut Sched) -> u8 {
        if callable(sched) {
            start_by_call(sched);
            return sched.current;
        }
        self.arch.request_switch();
        NO_CALL
    }

    /// [`Sched::called_from`] of `slot`, read through a raw pointer (no reference to the
    /// tables, which an interrupt may be using), 0 for a slot out of range.
    fn called_from_raw(&self, slot: u8) -> u8 {
        let slot = usize::from(slot);
        if slot >= MAX_TASKS {
            return 0;
        }
        // SAFETY: a one-byte read inside the table (checked above), through a raw pointer:
        // no reference is made; an interrupt that writes it has ended before this context
        // runs again (one core), and the caller's own slot changes only at its job's end.
        unsafe {
            core::ptr::addr_of!((*self.sched.get()).called_from)
                .cast::<u8>()
                .add(slot)
                .read()
        }
    }

    /// A job started by a call ([`start_by_call`]), with the kernel lock ended: the
    /// application's job entry, which returns once the job has ended and the context is
    /// its caller's again ([`back_to_caller`]). A job that returns without its end is a
    /// fatal fault, as for a job the switch started.
    #[inline(never)]
    fn call_job(&self, task: u8) {
        self.arch.call_job(task);
        // SAFETY: a read of the caller's own slot, which no kernel call changes but the
        // job's end (before this point) or this job's start; no reference to the tables
        // is held here.
        if self.called_from_raw(task) != 0 {
            self.fatal(PortFault::Board("a job returned"));
        }
    }

    /// A lock's kernel call (`take`: `GetResource`, else `ReleaseResource`): the kernel's
    /// fast path under the kernel lock, then the level's mask; where it declines, the full
    /// service and the port's whole carrying-out.
    #[inline(always)]
    fn lock_step(&self, res: ResourceId, take: bool) -> Result<(), OsError> {
        let (kernel, _) = self.enter();
        let fast = if take {
            kernel.try_get_resource(res)
        } else {
            kernel.try_release_resource(res)
        };
        match fast {
            Some(level) => {
                let lock_free = if take {
                    // The caller holds a resource now: nothing may be locked outside the
                    // kernel (`spec::fast_path_agrees`), no need to ask.
                    0
                } else {
                    // (The caller holds one fewer.)
                    kernel.lock_free_resources()
                };
                self.leave_at(level, lock_free);
                Ok(())
            }
            None => self.lock_service(res, take),
        }
    }

    /// A lock (`take`) or release as a kernel call: under the kernel lock the kernel's
    /// fast path pushes the resource and raises the task's priority and preemption
    /// threshold to the ceiling (taking a resource never lets another task in), or pops it
    /// where no task above the restored priority is ready; the port then sets the OS-level
    /// mask to the level. Where the fast path declines, the full service and the port's
    /// whole carrying-out, in the same kernel lock. Out of line, so that a lock outside the
    /// kernel saves no register but the frame pointer and the return address, and one
    /// function for both, so that the image holds the kernel lock's entry and end once.
    #[inline(never)]
    fn lock_call(&self, res: ResourceId, take: bool) -> Result<(), OsError> {
        self.lock_step(res, take)
    }

    /// The rest of a lock's kernel call whose fast path declined, with the kernel lock
    /// taken: the full `GetResource` (`take`) or `ReleaseResource`, then the port's whole
    /// carrying-out. Out of line, so that the fast path's frame stays small, and one
    /// function for both, so that the image holds the carrying-out once.
    #[cold]
    #[inline(never)]
    fn lock_service(&self, res: ResourceId, take: bool) -> Result<(), OsError> {
        let (kernel, _) = self.tables();
        let result = if take {
            kernel.get_resource(res)
        } else {
            kernel.release_resource(res)
        };
        self.leave();
        result
    }

    /// The rest of an activation whose fast path declined, with the kernel lock taken: the
    /// full `ActivateTask`, then the port's whole carrying-out.
    #[cold]
    #[inline(never)]
    fn activate_service(&self, task: TaskId) -> Result<(), OsError> {
        let (kernel, _) = self.tables();
        let result = kernel.activate_task(task);
        self.leave();
        result
    }

    /// Ends the kernel lock after a fast path: the running task, its switch state and the
    /// every-interrupt masking are as they were (the fast paths run only at task level
    /// with no interrupt lock in force), the kernel's mask is that of processor priority
    /// `level` and its answer `lock_free` ([`OsKernel::lock_free_resources`]), stored
    /// with the kernel call's end.
    #[inline(always)]
    fn leave_at(&self, level: u8, lock_free: u32) {
        compiler_fence(Ordering::SeqCst);
        self.lazy.set_answer(lock_free);
        self.arch.set_level(level);
    }

    /// [`Preemptive::leave_at`] for a call that left the kernel's answer as it was:
    /// `before`, the word as the call found it (0 where the call took a lock over), goes
    /// back alone ([`LazyLock::restore`]).
    #[inline(always)]
    fn leave_restoring(&self, level: u8, before: u32) {
        compiler_fence(Ordering::SeqCst);
        self.lazy.restore(before);
        self.arch.set_level(level);
    }

    /// The kernel's `All` mask began (every interrupt masked before the OS-level mask
    /// drops) or ended (unmasked after the OS-level mask is in place, so nothing the
    /// kernel still holds slips through).
    #[cold]
    #[inline(never)]
    fn all_changed(&self, mask: InterruptMask) {
        if mask == InterruptMask::All {
            self.arch.disable_all();
            self.arch.set_mask(mask);
        } else {
            self.arch.set_mask(mask);
            self.arch.enable_all();
        }
    }

    /// ShutdownOS ran: every interrupt stays masked and nothing is switched to; the first
    /// call to see it hands the end to the application.
    #[cold]
    #[inline(never)]
    fn stopping(&self, sched: &mut Sched) {
        self.arch.disable_all();
        let first = !core::mem::replace(&mut sched.stopped, true);
        // No resource outside the kernel, and the kernel call's end.
        self.lazy.stop();
        if first {
            self.arch.stopped();
        }
    }

    /// The switch (the CPU's switch exception calls it with the kernel lock taken): saves
    /// the outgoing stack pointer, returns the incoming one, building a new job's first
    /// frame; moves the stack guard. A stack pointer found in its guard, or a guard found
    /// written ([`Arch::guard_intact`]), is a stack fault.
    pub fn switch(&self, sp: u32) -> u32 {
        // SAFETY: the CPU calls this with the kernel lock taken, outside every kernel call
        // (the switch runs only when no ISR is active and the lock is free).
        let s = unsafe { &mut *self.sched.get() };
        // A guard found written (a CPU without an MPU) is an overflow as a stack pointer
        // inside it is: `decide` is given one (0 lies inside every guard).
        let sp = if self.arch.guard_intact(s.stack_of(usize::from(s.current)).0) {
            sp
        } else {
            0
        };
        let new_sp = match decide(s, sp, A::GUARD_BYTES) {
            Switch::Overflow(task) => self.stack_fault(task.map(TaskId)),
            Switch::Resume(sp) => sp,
            // SAFETY: `top` is the top of the task's own stack (its job starts now, so
            // nothing uses it), or the shared stack's top below every preempted job on it
            // (`basic_top` is the lowest of their saved stack pointers).
            Switch::Start { task, top } => unsafe { self.arch.first_frame(top, task) },
        };
        self.arch.move_guard(s.stack_of(usize::from(s.current)).0);
        new_sp
    }

    /// The running context overflowed its stack (the CPU's guard fault, or the switch's
    /// check): reported, then `ShutdownOS(E_OS_STACKFAULT)`, whose ShutdownHook runs, and
    /// the application's end. Also from inside a kernel call: the context it interrupted
    /// never resumes, so its kernel call is abandoned, not re-entered.
    pub fn stack_fault(&self, task: Option<TaskId>) -> ! {
        self.arch.disable_all();
        let name = task.and_then(|t| self.task_name(t));
        self.shut_down_on(PortFault::StackOverflow(name))
    }

    /// The main stack (ISRs, exceptions) overflowed into its guard: reported, then
    /// `ShutdownOS(E_OS_STACKFAULT)` as for a task stack ([`Preemptive::stack_fault`]).
    pub fn main_stack_fault(&self) -> ! {
        self.arch.disable_all();
        self.shut_down_on(PortFault::MainStackOverflow)
    }

    fn shut_down_on(&self, fault: PortFault) -> ! {
        self.arch.report(&fault);
        // SAFETY: every interrupt is masked and the context that may hold the kernel
        // (an interrupted kernel call) never runs again: this is the only reference used
        // from here on.
        let (kernel, sched) = unsafe { (&mut *self.kernel.get(), &mut *self.sched.get()) };
        kernel.shutdown_on_fault(OsError::StackFault);
        sched.stopped = true;
        // A lock kept outside the kernel has no kernel to go to now (a stopped kernel
        // refuses the hand-over): it goes. No resource outside the kernel from here, and
        // the abandoned call's flag goes with the same store: the application's end may
        // still read the kernel (its hooks' record), which a stopped OS serves.
        self.lazy.stop();
        self.arch.stopped()
    }

    /// Stack monitoring from the OS tick, for a CPU that cannot enforce the guards: the
    /// running context's guard checked ([`Arch::guard_intact`]); a written guard is a
    /// stack fault, as at a switch. (A job that overflows and never yields is found
    /// here, within a tick, instead of at its next switch.)
    pub fn monitor_stack(&self) {
        // SAFETY: called from the OS tick, an interrupt the kernel lock masks: no kernel
        // call or switch is under way, so the table is not being written; a read.
        let s = unsafe { &*self.sched.get() };
        if !self.arch.guard_intact(s.stack_of(usize::from(s.current)).0) {
            self.stack_fault(self.current_own_stack_task());
        }
    }

    /// The task running now, when it has a stack of its own (for the guard fault).
    pub fn current_own_stack_task(&self) -> Option<TaskId> {
        // SAFETY: called from the guard fault with every interrupt masked; a read.
        let s = unsafe { &*self.sched.get() };
        let current = usize::from(s.current);
        (!s.on_shared(current)).then_some(TaskId(s.current))
    }

    fn task_name(&self, task: TaskId) -> Option<&'static str> {
        // SAFETY: a read of the configuration (static) through the kernel, with every
        // interrupt masked.
        let kernel = unsafe { &*self.kernel.get() };
        kernel.tasks().get(usize::from(task.0)).map(|t| t.name)
    }

    /// The kernel without the lock, for reports after the OS has stopped (every
    /// interrupt masked for good, nothing else runs).
    pub fn stopped_kernel(&self) -> Option<&K> {
        // SAFETY: once stopped no kernel call changes anything (every call only reads),
        // and every interrupt stays masked.
        let stopped = unsafe { (*self.sched.get()).stopped };
        // SAFETY: as above.
        stopped.then(|| unsafe { &*self.kernel.get() })
    }
}

impl Sched {
    /// At start: the idle loop runs on the shared stack.
    fn guard_slot_start(&mut self) {
        self.current = IDLE;
        self.next = IDLE;
    }
}

impl<K: OsKernel, A: Arch> Port for Preemptive<K, A> {
    type Kernel = K;
    const NESTED: bool = false;

    #[inline]
    fn kernel<R>(&self, f: impl FnOnce(&mut K) -> R) -> R {
        self.locked(|kernel, _| f(kernel))
    }

    #[inline]
    fn inspect<R>(&self, f: impl FnOnce(&K) -> R) -> R {
        self.locked(|kernel, _| f(kernel))
    }

    /// The OS tick in one kernel call: under the kernel lock the kernel's fast path
    /// advances the counter where nothing is due, and the port restores the interrupted
    /// context's mask. Where alarms are due, the kernel's fast path for them, or where
    /// that declines `whole` (the ISR's entry, body and return), in the same kernel lock;
    /// then the port carries out what the kernel decided (the switch to a task an alarm
    /// activated, once the ISR returns).
    #[inline]
    fn tick_isr<R>(
        &self,
        isr: IsrId,
        counter: CounterId,
        whole: impl FnOnce(&mut K) -> R,
    ) -> TickPath<R> {
        let (kernel, _, lock_free) = self.enter_saving();
        if let Some(level) = kernel.try_tick(isr, counter) {
            // (A tick changes nothing for the interrupted task: the kernel's answer is the
            // one from before the call, 0 if the call took a lock over.)
            self.leave_restoring(level, lock_free);
            return TickPath::NothingDue;
        }
        let path = if kernel.try_tick_due(isr, counter).is_some() {
            TickPath::AlarmsDue
        } else {
            TickPath::Whole(whole(kernel))
        };
        self.leave();
        path
    }

    /// The lock by the stack resource policy. A task's lock of one of its own resources,
    /// holding nothing else, is kept outside the kernel: one store, under the kernel lock
    /// and with the ceiling's mask after it where ISRs share the resource; no kernel call
    /// (the module's rules). Otherwise the kernel call `lock_call`.
    #[inline]
    fn get_resource(&self, res: ResourceId) -> Result<(), OsError> {
        if self.lazy_get(res, false) || self.lazy_get(res, true) {
            return Ok(());
        }
        self.lock_call(res, true)
    }

    /// The release, as [`Preemptive::get_resource`] takes the lock: a lock kept outside
    /// the kernel that no kernel call has seen is the kernel's answer back in the word,
    /// and the task's mask again where the lock masked ISRs (no task became ready
    /// meanwhile: that takes a kernel call, which hands the lock over);
    /// otherwise the kernel call `lock_call`.
    #[inline]
    fn release_resource(&self, res: ResourceId) -> Result<(), OsError> {
        if self.lazy_release(res, false) || self.lazy_release(res, true) {
            return Ok(());
        }
        self.lock_call(res, false)
    }

    /// [`Preemptive::get_resource`] with the kind of lock outside the kernel known when
    /// the image is built: only that kind is tried (where the resource is of the other
    /// kind, the kernel's answer never names it so, and the lock goes to the kernel). The
    /// answer says which way it went, for the release.
    #[inline]
    fn get_resource_of_kind<const ISR_SHARED: bool>(
        &self,
        res: ResourceId,
    ) -> Result<Held, OsError> {
        if self.lazy_get(res, ISR_SHARED) {
            return Ok(Held::outside(ISR_SHARED));
        }
        self.lock_call(res, true).map(|()| Held::other())
    }

    /// The release of a lock [`Preemptive::get_resource_of_kind`] took: outside the
    /// kernel, the answer back in the word with no test of the word first, and no mask
    /// to put back where the lock masks nothing; the kernel's release otherwise, and
    /// where the lock was handed over meanwhile.
    #[inline]
    fn release_held(&self, res: ResourceId, held: Held) -> Result<(), OsError> {
        if let Some(masks_isrs) = held.outside_masking() {
            if self.release_outside(masks_isrs) {
                return Ok(());
            }
        }
        self.lock_call(res, false)
    }

    /// `ActivateTask` by the kernel's fast path where the activated task preempts the
    /// caller at task level ([`OsKernel::try_activate_task`]): the port's part of the
    /// switch follows at once, with the kernel's view the fast path returned (the new job
    /// by a call where it may start so, else the switch exception), without the general
    /// end of a kernel call. Otherwise the full service and that general end.
    #[inline(never)]
    fn activate_task(&self, task: TaskId) -> Result<(), OsError> {
        let (kernel, sched) = self.enter();
        let Some((level, lock_free)) = kernel.try_activate_task(task) else {
            return self.activate_service(task);
        };
        sched.next = task.0;
        let call = if self.arch.may_call_job() && callable(sched) {
            start_by_call(sched);
            task.0
        } else {
            self.arch.request_switch();
            NO_CALL
        };
        compiler_fence(Ordering::SeqCst);
        // The kernel's answer, and the kernel call's end with it.
        self.lazy.set_answer(lock_free);
        // The fast path runs only with no interrupt lock in force: the kernel's mask is a
        // level, and every-interrupt masking stays off.
        self.arch.set_level(level);
        if call != NO_CALL {
            self.call_job(call);
        }
        Ok(())
    }

    fn end_job(&self, f: impl FnOnce(&mut K) -> Result<(), OsError>) -> Result<(), OsError> {
        let (result, ended, called) = self.locked(|kernel, sched| {
            let result = f(kernel);
            if result.is_ok() {
                sched.ended = true;
            } else if kernel.running().is_some_and(|t| {
                t.0 == sched.current && kernel.task_state(t) == Some(TaskState::Running)
            }) {
                // The job cannot end as asked: it returns without a proper end, and the
                // kernel ends it (E_OS_MISSINGEND, its resources and locks released).
                if kernel.task_returned().is_ok() {
                    sched.ended = true;
                }
            }
            let called = sched.was_called(usize::from(sched.current));
            (result, sched.ended, called)
        });
        if ended && !called {
            // The switch is pending and runs as soon as the mask allows: this job is over.
            loop {
                self.arch.wait();
            }
        }
        // A job started by a call returns to its caller (if the kernel chose another job,
        // the switch it requested ran first, and this context is the caller's); not in a
        // task's job (nothing to end): the caller goes on.
        result
    }

    fn now_ms(&self) -> u64 {
        self.arch.now_ms()
    }

    #[inline]
    fn job_started(&self, task: TaskId) {
        self.arch.trace(Mark::JobStarted(task));
    }

    #[inline]
    fn job_finished(&self, task: TaskId) {
        self.arch.trace(Mark::JobFinished(task));
    }

    #[inline]
    fn isr_entered(&self, isr: IsrId) {
        self.arch.trace(Mark::IsrEntered(isr));
    }

    fn isr_refused(&self, _isr: IsrId) {
        self.arch.quiet_active_line();
    }

    fn hang(&self) {
        loop {
            self.arch.wait();
        }
    }

    #[inline]
    fn span(&self, id: usize, start: bool) {
        self.arch.trace(if start {
            Mark::SpanStart(id)
        } else {
            Mark::SpanEnd(id)
        });
    }

    #[inline]
    fn span_end_as(&self, started: usize, id: usize) {
        self.arch.trace(Mark::SpanEndAs { started, id });
    }
}
