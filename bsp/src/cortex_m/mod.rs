//! The Cortex-M OS port (ARMv7-M: Cortex-M4 on QEMU's mps2-an386, later the S32K144).
//!
//! # Mechanism: PendSV context switching, one stack for the basic tasks
//!
//! The kernel decides; this port carries the decision out:
//!
//! - **Kernel lock.** Every kernel service runs with PRIMASK set ([`CortexMPort::kernel`]),
//!   so no ISR can observe the kernel half-updated; a few instructions long.
//! - **Task switch.** After a service, if the kernel's running task changed, the port pends
//!   PendSV, the exception of lowest priority: it runs as soon as no ISR is active and the
//!   kernel's interrupt mask allows, saves r4-r11 (and s16-s31 when the task used the FPU)
//!   on the outgoing task's stack and restores the incoming one's. A higher-priority task
//!   activated by a task therefore starts the moment the service returns; one activated
//!   by an ISR starts when the last nested ISR returns (tail-chained).
//! - **Stacks.** OSEK basic tasks run to completion and preempt each other in LIFO order,
//!   so they share one stack: a new job's first frame is built just below the deepest
//!   preempted job. The idle loop is the stack's bottom. A task given its own stack
//!   ([`set_task_stack`]: extended tasks, whose `WaitEvent` keeps their context while
//!   lower tasks run) starts its jobs there. ISRs run on the main stack (MSP).
//! - **Stack guard.** The bottom 256 bytes of every task stack are a guard that MPU region
//!   0, moved at every switch, makes inaccessible to the running context: an overflow
//!   faults at its first access, and [`App::stack_fault`] shuts the OS down with
//!   `E_OS_STACKFAULT`.
//! - **Shutdown.** When a kernel call leaves the OS shut down (`ShutdownOS`, or the
//!   OS's own on a stack fault), PRIMASK stays set for good and no task is switched to;
//!   the port hands the end to [`App::shut_down`] (report, safe state, stop) from that
//!   call, once.
//! - **Interrupt masking.** The kernel's interrupt mask ([`cw_core::os::InterruptMask`])
//!   becomes BASEPRI (`UpTo(p)`: every ISR of OSEK priority up to `p`, and PendSV, held)
//!   or PRIMASK (`All`) after every kernel call: resources shared with ISRs and
//!   `SuspendOSInterrupts` raise BASEPRI, `DisableAllInterrupts` sets PRIMASK.
//!
//! Why not one NVIC priority level per task, as RTIC does? That scheme lets the NVIC make
//! the scheduling decision again, in hardware, and needs every task to be an interrupt
//! handler: it cannot run OSEK's extended tasks (`WaitEvent` blocks with the task's
//! context kept), and the verified kernel's decision would be duplicated by a second
//! scheduler that must be shown to agree with it. Here the kernel is the only scheduler,
//! and the cost is a software context switch (its instructions are counted in the book: `docs/src/performance.md`).
//!
//! NVIC priorities (3 priority bits are assumed, the fewest a Cortex-M4 implements): an
//! OSEK category-2 ISR of priority `p` gets `0xE0 - 0x20 * p`; PendSV gets `0xE0`, the
//! lowest.

use core::cell::UnsafeCell;

use cortex_m::peripheral::scb::SystemHandler;
use cortex_m::peripheral::{NVIC, SCB};
use cortex_m::register::basepri;
use cw_core::os::{InterruptMask, IsrId, OsError, TaskId};

use crate::port::{OsKernel, Port};

pub mod trace;

/// The most tasks the port can switch between.
pub const MAX_TASKS: usize = 16;
/// The slot of the idle loop.
const IDLE: u8 = MAX_TASKS as u8;
/// Words of the shared stack of the basic tasks (and the idle loop): 2 KiB.
pub const BASIC_STACK_WORDS: usize = 512;
/// The value painted into unused stack, to measure the deepest use.
pub const STACK_PAINT: u32 = 0xDEAD_BEEF;
/// Words at the bottom of every task stack (the shared one and each task's own): the
/// stack guard. While a context runs, the MPU makes its stack's guard inaccessible, so the
/// first access past the stack's end faults (MemManage) at that instruction; and a context
/// switch that finds a saved stack pointer inside the guard reports the overflow too.
/// Either way the application shuts the OS down with `E_OS_STACKFAULT`
/// ([`App::stack_fault`]).
///
/// 256 bytes. A function's frame can move the stack pointer past the stack's end before
/// it touches memory, and the fault's own exception frame (32 bytes, 104 with the FPU's
/// registers) is then pushed below that, lowest word first; the guard must absorb both,
/// or the push would land in whatever the linker put below the stack. So an overflow is
/// caught before it writes outside the stack as long as no single frame steps more than
/// 152 bytes (224 without FPU state) past the stack's end: the usual limit of MPU guards
/// on cores without stack-limit registers (ARMv8-M has PSPLIM).
pub const GUARD_WORDS: usize = 64;

/// The NVIC priority byte of an OSEK category-2 ISR priority (1 to 6).
pub const fn nvic_priority(osek_priority: u8) -> u8 {
    let p = if osek_priority > 6 { 6 } else { osek_priority };
    0xE0 - 0x20 * p
}

/// The BASEPRI value for a kernel interrupt mask (0: nothing masked).
const fn basepri_for(mask: InterruptMask) -> u8 {
    match mask {
        InterruptMask::None => 0,
        InterruptMask::UpTo(p) => nvic_priority(if p == 0 { 1 } else { p }),
        // PRIMASK does it; BASEPRI holds the OS level meanwhile.
        InterruptMask::All => nvic_priority(1),
    }
}

/// What the port knows of the jobs on the shared stack.
struct Sched {
    /// The slot now executing (a task index, or `IDLE`).
    current: u8,
    /// The slot the kernel chose last.
    next: u8,
    /// The current job ended (`TerminateTask`/`ChainTask` succeeded): its stack is free.
    ended: bool,
    /// Saved stack pointers of preempted jobs and of the idle loop.
    sp: [u32; MAX_TASKS + 1],
    /// Bit `t`: task `t` has a job under way (a context to resume).
    started: u32,
    /// The shared stack's top when each job started (restored when it ends).
    job_base: [u32; MAX_TASKS],
    /// Where the next new job's first frame goes.
    basic_top: u32,
    /// A kernel call is under way (a nested one would alias the kernel).
    in_kernel: bool,
    /// Each task's own stack as (lowest address, top), or (0, 0): the shared stack.
    own_stack: [(u32, u32); MAX_TASKS],
    /// `ShutdownOS` ran and the application was told ([`App::shut_down`]).
    stopped: bool,
}

struct SchedCell(UnsafeCell<Sched>);

// SAFETY: `Sched` is touched only with PRIMASK set (in `CortexMPort::kernel`, `end_job`,
// and `cw_port_switch`, which PendSV calls between `cpsid i` and `cpsie i`), on a single
// core: no two accesses overlap.
unsafe impl Sync for SchedCell {}

static SCHED: SchedCell = SchedCell(UnsafeCell::new(Sched {
    current: IDLE,
    next: IDLE,
    ended: false,
    sp: [0; MAX_TASKS + 1],
    started: 0,
    job_base: [0; MAX_TASKS],
    basic_top: 0,
    in_kernel: false,
    own_stack: [(0, 0); MAX_TASKS],
    stopped: false,
}));

/// A task's own stack (aligned for its MPU guard region). Extended tasks need one: `WaitEvent` keeps the task's context while
/// tasks of lower priority run, which on the shared stack would grow into it.
#[repr(C, align(256))]
pub struct TaskStack<const WORDS: usize>(UnsafeCell<[u32; WORDS]>);

// SAFETY: the memory is used only as its task's process stack once the OS starts (and
// painted and read word by word for the guard and the measurement).
unsafe impl<const WORDS: usize> Sync for TaskStack<WORDS> {}

impl<const WORDS: usize> TaskStack<WORDS> {
    /// A stack of `WORDS` words.
    pub const fn new() -> Self {
        Self(UnsafeCell::new([0; WORDS]))
    }
}

impl<const WORDS: usize> Default for TaskStack<WORDS> {
    fn default() -> Self {
        Self::new()
    }
}

/// Gives `task` its own stack; call before [`start`]. A task given none runs on the
/// shared stack. A fatal port error if `task` is out of range, the stack is too small
/// for its guard and one frame, or it overlaps a stack given before.
pub fn set_task_stack<const WORDS: usize>(task: TaskId, stack: &'static TaskStack<WORDS>) {
    let bottom = stack.0.get() as u32;
    let top = bottom + (WORDS * 4) as u32;
    let fits = WORDS >= GUARD_WORDS + 64;
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are off and no kernel call is under way: the only reference.
        let s = unsafe { &mut *SCHED.0.get() };
        let overlaps = s
            .own_stack
            .iter()
            .any(|&(b, t)| t != 0 && bottom < t && b < top);
        match s.own_stack.get_mut(usize::from(task.0)) {
            Some(slot) if fits && !overlaps => *slot = (bottom, top),
            _ => fatal("task stack refused (task out of range, too small, or shared)"),
        }
    });
}

/// The deepest use of `task`'s own stack so far, in bytes (`None`: it has none).
pub fn task_stack_use(task: TaskId) -> Option<usize> {
    let (bottom, top) = cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are off; a read of the table.
        let s = unsafe { &*SCHED.0.get() };
        s.own_stack.get(usize::from(task.0)).copied()
    })?;
    (top != 0).then(|| {
        painted_use(
            bottom as *const u32,
            ((top - bottom) / 4) as usize,
            GUARD_WORDS,
        )
    })
}

/// Bytes of a painted stack of `words` words at `base` that were overwritten, above its
/// first `skip` words (a task stack's guard is never written: the MPU forbids it, and
/// reading it from a context whose guard it is would fault).
fn painted_use(base: *const u32, words: usize, skip: usize) -> usize {
    let mut untouched = skip.min(words);
    while untouched < words {
        // SAFETY: the caller's stack: `words` words at `base`; a volatile read of memory
        // the tasks may use concurrently is a plain word read on this core.
        let word = unsafe { base.add(untouched).read_volatile() };
        if word != STACK_PAINT {
            break;
        }
        untouched += 1;
    }
    (words - untouched) * 4
}

/// Paints the words from `bottom` up to `top` (word-aligned addresses).
///
/// # Safety
/// The memory must be a stack nothing uses now (the OS has not started on it), and nothing
/// else may live there.
unsafe fn paint(bottom: u32, top: u32) {
    let mut word = bottom;
    while word < top {
        // SAFETY: the caller's contract.
        unsafe { (word as *mut u32).write_volatile(STACK_PAINT) };
        word += 4;
    }
}

/// The shared stack of the basic tasks (aligned for its MPU guard region).
#[repr(C, align(256))]
struct Stack(UnsafeCell<[u32; BASIC_STACK_WORDS]>);

// SAFETY: the stack's memory is used only as the process stack (PSP) once the OS starts,
// and read by `basic_stack_use` for the painted-stack measurement.
unsafe impl Sync for Stack {}

#[link_section = ".uninit.cw_basic_stack"]
static BASIC_STACK: Stack = Stack(UnsafeCell::new([0; BASIC_STACK_WORDS]));

/// The application the port runs: the ECU's entry points.
pub trait App: Sync {
    /// `StartOS` (from the idle loop's context, once).
    fn start_os(&self);
    /// One job of `task`, from its first line to `TerminateTask`.
    fn run_job(&self, task: TaskId);
    /// The idle loop's work, between interrupts (returns to wait for the next one).
    fn idle(&self);
    /// The OS tick (SysTick's handler).
    fn tick(&self);
    /// External interrupt line `line` of the board.
    fn irq(&self, line: u16);
    /// A stack overflowed (`task`'s, or the shared stack's: `None`): the application
    /// reports which and shuts the OS down with `E_OS_STACKFAULT` (its ShutdownHook sees
    /// it), which ends in [`App::shut_down`]. Called from PendSV or the MemManage fault
    /// with interrupts disabled; never returns.
    fn stack_fault(&self, task: Option<TaskId>) -> !;
    /// `ShutdownOS` ran (the application's own call, or the OS's on a fault): called once,
    /// from the kernel call that shut the OS down, in the context that made it, with
    /// interrupts disabled for good (OSEK: the OS does not come back, no task or ISR runs
    /// again). The application puts its outputs in their safe state, reports and stops
    /// (on silicon: EcuM's power-off or reset). Kernel calls that only read (the hooks'
    /// record) are still served, without switching tasks or unmasking interrupts.
    fn shut_down(&self) -> !;
}

struct AppCell(UnsafeCell<Option<&'static dyn App>>);

// SAFETY: written once by `start`, before any interrupt or task can read it.
unsafe impl Sync for AppCell {}

static APP: AppCell = AppCell(UnsafeCell::new(None));

pub(crate) fn app() -> Option<&'static dyn App> {
    // SAFETY: `APP` is written only in `start`, before the task switch that makes any
    // reader run; afterwards it is only read.
    unsafe { *APP.0.get() }
}

/// Where the kernel lives on this port.
pub struct CortexMPort<K> {
    kernel: UnsafeCell<K>,
    /// Milliseconds since start, advanced by the tick ISR.
    ms: core::sync::atomic::AtomicU32,
}

// SAFETY: the kernel is reached only in `kernel`/`inspect`/`end_job`, with PRIMASK set
// and a re-entrance check, on a single core.
unsafe impl<K: Send> Sync for CortexMPort<K> {}

impl<K: OsKernel> CortexMPort<K> {
    /// The port of `kernel`.
    pub const fn new(kernel: K) -> Self {
        Self {
            kernel: UnsafeCell::new(kernel),
            ms: core::sync::atomic::AtomicU32::new(0),
        }
    }

    /// SysTick counts since the OS started (see [`trace`]).
    pub fn now_counts(&self) -> u32 {
        trace::now(self.ms.load(core::sync::atomic::Ordering::Relaxed))
    }

    /// The tick ISR advances the millisecond time base.
    pub fn advance_ms(&self) {
        self.ms.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    }

    /// Runs `f` on the kernel with PRIMASK set; then applies the kernel's interrupt mask
    /// and pends PendSV if the kernel chose another task (or the job ended).
    #[inline(always)]
    fn locked<R>(&self, f: impl FnOnce(&mut K, &mut Sched) -> R) -> R {
        cortex_m::interrupt::disable();
        // SAFETY: PRIMASK is set, so nothing else runs until it is cleared below; the
        // `in_kernel` flag refuses a nested call, which would alias the kernel.
        let (kernel, sched) = unsafe { (&mut *self.kernel.get(), &mut *SCHED.0.get()) };
        if sched.in_kernel {
            fatal("kernel lock taken twice");
        }
        sched.in_kernel = true;
        let result = f(kernel, sched);
        sched.in_kernel = false;
        let next = kernel.running().map_or(IDLE, |t| t.0);
        if next == IDLE && kernel.is_shut_down() {
            // ShutdownOS ran: PRIMASK stays set and nothing is switched to; the first
            // call to see it hands the end to the application.
            if !core::mem::replace(&mut sched.stopped, true) {
                os_stopped();
            }
            return result;
        }
        sched.next = next;
        if next != sched.current || sched.ended {
            SCB::set_pendsv();
        }
        let mask = kernel.interrupt_mask();
        // SAFETY: BASEPRI only holds interrupts back; the value is the kernel's mask.
        unsafe { basepri::write(basepri_for(mask)) };
        if mask != InterruptMask::All {
            // SAFETY: the kernel lock ends here; the kernel's mask admits interrupts.
            unsafe { cortex_m::interrupt::enable() };
        }
        result
    }
}

impl<K: OsKernel> Port for CortexMPort<K> {
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

    fn end_job(&self, f: impl FnOnce(&mut K) -> Result<(), OsError>) -> Result<(), OsError> {
        self.locked(|kernel, sched| {
            let result = f(kernel);
            if result.is_ok() {
                sched.ended = true;
            }
            result
        })?;
        // PendSV is pending and taken as soon as the mask allows: this job is over.
        loop {
            cortex_m::asm::wfi();
        }
    }

    fn now_ms(&self) -> u64 {
        u64::from(self.ms.load(core::sync::atomic::Ordering::Relaxed))
    }

    fn job_started(&self, task: TaskId) {
        if trace::ENABLED {
            trace::job_started(task.0, self.now_counts());
        }
    }

    fn job_finished(&self, task: TaskId) {
        if trace::ENABLED {
            trace::job_finished(task.0, self.now_counts());
        }
    }

    fn isr_entered(&self, isr: IsrId) {
        if trace::ENABLED {
            trace::isr_entered(isr.0, self.now_counts());
        }
    }

    fn span(&self, id: usize, start: bool) {
        if !trace::ENABLED {
            return;
        }
        let at = self.now_counts();
        if start {
            trace::span_start(id, at);
        } else {
            trace::span_end(id, at);
        }
    }
}

/// The OS has shut down: the application ends the run.
fn os_stopped() -> ! {
    match app() {
        Some(app) => app.shut_down(),
        None => fatal("ShutdownOS before the application started"),
    }
}

/// Fatal port error: the LEDs' safe state is the board's; here the OS cannot go on.
fn fatal(what: &str) -> ! {
    cortex_m::interrupt::disable();
    crate::cortex_m::report_fatal(what);
}

/// What a board does on a fatal error (set by the board at start).
static FATAL: FatalCell = FatalCell(UnsafeCell::new(None));

struct FatalCell(UnsafeCell<Option<fn(&str) -> !>>);

// SAFETY: written once by `start` before interrupts are enabled; read-only afterwards.
unsafe impl Sync for FatalCell {}

/// Puts the board in its safe state and reports `what`; never returns.
pub fn report_fatal(what: &str) -> ! {
    // SAFETY: read-only after `start`.
    if let Some(handler) = unsafe { *FATAL.0.get() } {
        handler(what);
    }
    loop {
        cortex_m::asm::wfi();
    }
}

/// Bytes of the main stack (ISRs, exceptions) painted when the OS starts, below the main
/// stack pointer that every exception then starts from, for [`main_stack_use`].
pub const MAIN_STACK_PAINTED: usize = 2048;

/// Where the painted main stack region ends (its top), set once by `start`.
static MAIN_PAINT_TOP: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

/// The deepest use of the main stack since the OS started, in bytes (ISRs, PendSV and
/// the fault handlers run there; the exception frames go on the interrupted task's
/// stack); at most [`MAIN_STACK_PAINTED`].
pub fn main_stack_use() -> usize {
    let top = MAIN_PAINT_TOP.load(core::sync::atomic::Ordering::Relaxed);
    if top == 0 {
        return 0;
    }
    // The region has no guard: counted from its bottom.
    painted_use(
        (top as usize - MAIN_STACK_PAINTED) as *const u32,
        MAIN_STACK_PAINTED / 4,
        0,
    )
}

/// The deepest use of the shared task stack so far, in bytes (the painted words above
/// the guard that were overwritten), of [`BASIC_STACK_WORDS`] - [`GUARD_WORDS`] words.
pub fn basic_stack_use() -> usize {
    painted_use(
        BASIC_STACK.0.get().cast::<u32>(),
        BASIC_STACK_WORDS,
        GUARD_WORDS,
    )
}

/// Starts the OS on this port and becomes the idle loop: paints the task stack, sets
/// PendSV to the lowest priority, moves thread mode to the task stack, calls
/// `app.start_os()` and then `app.idle()` between interrupts forever.
///
/// `on_fatal` puts the board's outputs in their safe state and reports a fatal port error.
pub fn start(app: &'static dyn App, on_fatal: fn(&str) -> !) -> ! {
    cortex_m::interrupt::disable();
    // SAFETY: interrupts are off and the OS has not started: nothing else reads these.
    unsafe {
        *APP.0.get() = Some(app);
        *FATAL.0.get() = Some(on_fatal);
    }
    let base = BASIC_STACK.0.get().cast::<u32>();
    let basic_bottom = base as u32;
    // SAFETY: the shared stack's array, which nothing uses yet.
    unsafe { paint(basic_bottom, basic_bottom + (BASIC_STACK_WORDS * 4) as u32) };
    // SAFETY: interrupts are off: the only reference to the table.
    let own = unsafe { (*SCHED.0.get()).own_stack };
    for (bottom, top) in own.into_iter().filter(|r| r.1 != 0) {
        // SAFETY: a task stack given by `set_task_stack`, not yet in use.
        unsafe { paint(bottom, top) };
    }
    // SAFETY: one past the end of the stack array: the initial process stack pointer.
    let top = unsafe { base.add(BASIC_STACK_WORDS) } as u32;
    // SAFETY: the core peripherals are taken once, here, before the OS runs.
    let mut cp = unsafe { cortex_m::Peripherals::steal() };
    // SAFETY: setting exception priorities before interrupts are enabled.
    unsafe {
        cp.SCB.set_priority(SystemHandler::PendSV, 0xE0);
    }
    cp.SCB
        .enable(cortex_m::peripheral::scb::Exception::MemoryManagement);
    // SAFETY: region 0 becomes the running context's stack guard (256 bytes, no access,
    // never executable); the background map keeps every other address as before for
    // privileged code, which is all code here. The idle loop's guard (the shared stack's)
    // is the first.
    unsafe {
        cp.MPU.rnr.write(0);
        cp.MPU.rbar.write(BASIC_STACK.0.get() as u32);
        cp.MPU.rasr.write(GUARD_RASR);
        cp.MPU.ctrl.write(MPU_ENABLE | MPU_PRIVDEFENA);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    // SAFETY: `top` is the 8-byte-aligned end of a static array reserved for this stack;
    // `switch_to_task_stack` moves thread mode onto it and never returns.
    unsafe { switch_to_task_stack(top) }
}

/// Sets the NVIC priority of an external interrupt for an OSEK category-2 ISR priority
/// and enables it.
pub fn enable_irq<I: cortex_m::interrupt::InterruptNumber>(irq: I, osek_priority: u8) {
    // SAFETY: the core peripherals are shared by the port alone; priorities are set
    // before the interrupt is unmasked.
    let mut cp = unsafe { cortex_m::Peripherals::steal() };
    unsafe {
        cp.NVIC.set_priority(irq, nvic_priority(osek_priority));
        NVIC::unmask(irq);
    }
}

/// Sets SysTick's priority for an OSEK category-2 ISR priority and starts it with
/// `reload + 1` core clocks per tick.
pub fn start_systick(reload: u32, osek_priority: u8) {
    // SAFETY: as `enable_irq`.
    let mut cp = unsafe { cortex_m::Peripherals::steal() };
    unsafe {
        cp.SCB
            .set_priority(SystemHandler::SysTick, nvic_priority(osek_priority));
    }
    cp.SYST
        .set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    cp.SYST.set_reload(reload);
    trace::set_counts_per_ms(reload + 1);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();
}

extern "C" {
    fn cw_port_enter_idle(top: u32) -> !;
}

/// Moves thread mode onto the task stack and enters the idle loop.
///
/// # Safety
/// `top` must be the end of memory reserved for the task stack.
unsafe fn switch_to_task_stack(top: u32) -> ! {
    // SAFETY: the caller's contract.
    unsafe { cw_port_enter_idle(top) }
}

/// The idle loop, on the task stack (called once by `cw_port_enter_idle`).
#[no_mangle]
extern "C" fn cw_port_idle() -> ! {
    // Thread mode runs on the task stack from here on, so the main stack pointer stays
    // where it is until an exception uses the memory below it: paint that memory.
    let painted_top = cortex_m::register::msp::read() & !7;
    // SAFETY: below the main stack pointer, inside the RAM the linker leaves to the main
    // stack: nothing lives there, and interrupts are still off.
    unsafe { paint(painted_top - MAIN_STACK_PAINTED as u32, painted_top) };
    MAIN_PAINT_TOP.store(painted_top, core::sync::atomic::Ordering::Relaxed);
    // SAFETY: the OS starts now, from thread mode on the task stack.
    unsafe { cortex_m::interrupt::enable() };
    if let Some(app) = app() {
        app.start_os();
        loop {
            app.idle();
            cortex_m::asm::wfi();
        }
    }
    fatal("no application");
}

/// A job's first frame: r0 is its task index, pc the job entry.
#[no_mangle]
extern "C" fn cw_port_job(task: u32) -> ! {
    if let Some(app) = app() {
        app.run_job(TaskId(task as u8));
    }
    // The job could not end (the OS shut down, or `TerminateTask` was refused): the
    // task's context stays; nothing more runs on it.
    loop {
        cortex_m::asm::wfi();
    }
}

/// PendSV's decision: saves the outgoing context's stack pointer, returns the incoming
/// one's (building a new job's first frame on the shared stack). Called with PRIMASK set.
#[no_mangle]
extern "C" fn cw_port_switch(sp: u32) -> u32 {
    if let Some(task) = overflowed(sp) {
        match app() {
            Some(app) => app.stack_fault(task),
            None => fatal("stack overflow"),
        }
    }
    // SAFETY: PendSV calls this between `cpsid i` and `cpsie i`.
    let s = unsafe { &mut *SCHED.0.get() };
    let current = s.current as usize;
    let shared = |s: &Sched, t: usize| s.own_stack.get(t).is_none_or(|r| r.1 == 0);
    if s.ended && current < MAX_TASKS {
        s.started &= !(1 << current);
        if shared(s, current) {
            s.basic_top = s.job_base[current];
        }
        s.ended = false;
    } else if let Some(slot) = s.sp.get_mut(current) {
        *slot = sp;
        if shared(s, current) {
            s.basic_top = sp;
        }
    }
    let next = s.next as usize;
    let new_sp = if next >= MAX_TASKS || s.started & (1 << next) != 0 {
        s.sp.get(next).copied().unwrap_or(sp)
    } else {
        s.started |= 1 << next;
        let top = if shared(s, next) {
            s.job_base[next] = s.basic_top;
            s.basic_top
        } else {
            s.own_stack[next].1
        };
        let frame_top = top & !7;
        let frame = frame_top - 17 * 4;
        let words: [u32; 17] = [
            // r4-r11
            0,
            0,
            0,
            0,
            0,
            0,
            0,
            0,
            // EXC_RETURN: thread mode, process stack, no FPU state
            0xFFFF_FFFD,
            // r0 (the task index), r1-r3, r12
            next as u32,
            0,
            0,
            0,
            0,
            // lr: a job never returns (it ends through the kernel)
            0xFFFF_FFFF,
            // pc: the job entry, Thumb bit cleared as the exception frame wants it
            (cw_port_job as *const () as usize as u32) & !1,
            // xPSR: Thumb state
            0x0100_0000,
        ];
        for (i, w) in words.iter().enumerate() {
            // SAFETY: `frame..frame_top` lies within the task's own stack (unused: its
            // job starts now), or within the shared task stack below every preempted
            // job's context (`basic_top` is the lowest of them).
            unsafe { (frame as *mut u32).add(i).write_volatile(*w) };
        }
        frame
    };
    s.current = next as u8;
    guard_stack_of(s, next);
    new_sp
}

/// MPU RASR of a guard: enabled, 256 bytes (SIZE = 7: 2^(7+1)), no access (AP = 0),
/// never executable (XN).
const GUARD_RASR: u32 = 1 | (7 << 1) | (1 << 28);
const _: () = assert!(
    GUARD_WORDS * 4 == 1 << (7 + 1),
    "the guard is one MPU region"
);
/// MPU_CTRL: the MPU on, the default memory map as background for privileged code.
const MPU_ENABLE: u32 = 1;
const MPU_PRIVDEFENA: u32 = 1 << 2;
/// MPU_RBAR: the address applies to the region number given with it.
const RBAR_VALID: u32 = 1 << 4;

/// Moves the MPU's guard region to the bottom of the stack of `slot` (a task with its
/// own stack; otherwise the shared stack).
fn guard_stack_of(s: &Sched, slot: usize) {
    let bottom = match s.own_stack.get(slot) {
        Some(&(bottom, top)) if top != 0 => bottom,
        _ => BASIC_STACK.0.get() as u32,
    };
    // SAFETY: only region 0's base moves, to the bottom of a 256-byte-aligned stack;
    // PendSV runs with interrupts disabled, and the exception return that follows
    // synchronises the change.
    unsafe {
        (*cortex_m::peripheral::MPU::PTR)
            .rbar
            .write(bottom | RBAR_VALID)
    };
}

/// A MemManage fault (or a HardFault escalated from one): the running context touched its
/// stack guard. Reports the overflow through the application; never returns.
pub fn memory_fault() -> ! {
    // SAFETY: a fault handler with the running context stopped; the table is read only.
    let current = unsafe { (*SCHED.0.get()).current } as usize;
    // SAFETY: as above.
    let own = unsafe { (*SCHED.0.get()).own_stack.get(current).copied() };
    let task = own.filter(|r| r.1 != 0).map(|_| TaskId(current as u8));
    match app() {
        Some(app) => app.stack_fault(task),
        None => fatal("stack overflow"),
    }
}

/// Whether the outgoing context overflowed its stack: its saved stack pointer lies in the
/// guard at the stack's bottom (a context switch whose frame the MPU let through only
/// because the hardware stacked part of it before the guard). `Some(task)` for a task's
/// own stack, `Some(None)` for the shared one. The guard's words themselves are never
/// read here: the MPU forbids them to this context, reads included.
fn overflowed(sp: u32) -> Option<Option<TaskId>> {
    // SAFETY: PendSV calls `cw_port_switch` between `cpsid i` and `cpsie i`; this borrow
    // ends before the switch takes its own.
    let s = unsafe { &*SCHED.0.get() };
    let current = s.current as usize;
    let own = s.own_stack.get(current).copied().filter(|r| r.1 != 0);
    let (bottom, task) = match own {
        Some((bottom, _)) => (bottom, Some(TaskId(current as u8))),
        None => (BASIC_STACK.0.get() as u32, None),
    };
    (sp < bottom + (GUARD_WORDS * 4) as u32).then_some(task)
}

core::arch::global_asm!(
    ".section .text.cw_port_enter_idle,\"ax\",%progbits",
    ".global cw_port_enter_idle",
    ".type cw_port_enter_idle,%function",
    ".thumb_func",
    "cw_port_enter_idle:",
    "    msr psp, r0",
    "    movs r1, #2",
    "    msr control, r1",
    "    isb",
    "    bl cw_port_idle",
    "    b .",
    ".fpu fpv4-sp-d16",
    ".section .text.PendSV,\"ax\",%progbits",
    ".global PendSV",
    ".type PendSV,%function",
    ".thumb_func",
    "PendSV:",
    "    mrs r0, psp",
    "    tst lr, #0x10",
    "    it eq",
    "    vstmdbeq r0!, {{s16-s31}}",
    "    stmdb r0!, {{r4-r11, lr}}",
    "    cpsid i",
    "    bl cw_port_switch",
    "    cpsie i",
    "    ldmia r0!, {{r4-r11, lr}}",
    "    tst lr, #0x10",
    "    it eq",
    "    vldmiaeq r0!, {{s16-s31}}",
    "    msr psp, r0",
    "    bx lr",
);
