//! The Cortex-M arch of the OS port (ARMv7-M: Cortex-M4 on QEMU's mps2-an386, later the
//! S32K144): the CPU under the CPU-independent preemptive port
//! ([`crate::port::preempt`]), its exception handlers and its time base.
//!
//! The book: [the Cortex-M4 image](../../../book/cortex-m4.html) ("The port's guarantees",
//! "Layers").
//!
//! # Mechanism: PendSV context switching, one stack for the basic tasks
//!
//! The kernel decides; the port carries the decision out ([`crate::port::preempt`] keeps
//! the bookkeeping, this module does the CPU's part):
//!
//! - **Kernel lock at the OS level.** Every kernel service runs with BASEPRI at the OS
//!   level: the priority of the highest category-2 ISR, which also holds the OS tick and
//!   PendSV. Category-1 ISRs, above it, are never delayed by a kernel call; they may not
//!   call the OS (a call that finds another under way is a fatal port fault).
//! - **Task switch.** After a service, if the kernel's running task changed, the port pends
//!   PendSV, the exception of lowest priority: it runs as soon as no ISR is active and the
//!   kernel's interrupt mask allows, saves r4-r11 (and s16-s31 when the task used the FPU)
//!   on the outgoing task's stack and restores the incoming one's. A higher-priority task
//!   activated by a task therefore starts the moment the service returns; one activated
//!   by an ISR starts when the last nested ISR returns (tail-chained). A new job of a
//!   basic task that a basic task's own kernel call lets in (thread mode, PRIMASK clear)
//!   starts without PendSV: the port calls it at the end of the kernel call, on the
//!   caller's stack, and the call returns when the job has ended.
//! - **Stacks.** OSEK basic tasks run to completion and preempt each other in LIFO order,
//!   so they share one stack: a new job's first frame is built just below the deepest
//!   preempted job. The idle loop is the stack's bottom. An extended task (whose
//!   `WaitEvent` keeps its context while lower tasks run) must be given its own stack
//!   ([`set_task_stack`]); the port refuses to start otherwise. ISRs run on the main
//!   stack (MSP).
//! - **Stack guards.** The bottom 256 bytes of every task stack are a guard that MPU region
//!   0, moved at every switch (then DSB, ISB), makes inaccessible to the running context;
//!   region 1 guards the main stack below its [`MAIN_STACK_BYTES`]. An overflow faults at
//!   its first access (MemManage), and the OS shuts down with `E_OS_STACKFAULT`, also when
//!   the overflow happened inside a kernel call. A core built without the Arm MPU (the
//!   S32K144's: `MPU_TYPE[DREGION]` reads 0) cannot enforce the guards; there they are
//!   painted and checked instead, the outgoing context's at every switch, the main
//!   stack's and the running context's at every OS tick, as AUTOSAR OS's stack monitoring
//!   does: the overflow is found after the fact (within a tick), and memory below a guard
//!   may already have been written.
//! - **Masks.** The kernel's interrupt mask ([`cw_core::os::InterruptMask`]) becomes
//!   BASEPRI (`UpTo(p)`: every ISR of OSEK priority up to `p`, and PendSV, held) after every
//!   kernel call, and around a task's lock kept outside the kernel of a resource that ISRs
//!   share (the ceiling's, [`crate::port::preempt`]); PRIMASK is set and cleared only where
//!   the kernel's mask says `All` (`DisableAllInterrupts`, `SuspendAllInterrupts`), so a
//!   kernel call made inside the caller's own critical section leaves it closed.
//! - **Shutdown and faults.** When a kernel call leaves the OS shut down (`ShutdownOS`, or
//!   the OS's own on a stack fault), PRIMASK stays set for good and the port hands the end
//!   to [`App::shut_down`]. Panics, HardFault, NMI, BusFault and UsageFault go to the
//!   application's [`App::report`] and [`App::halt`] (the board's safe state, its log, then
//!   a reset or a documented halt): never a semihosting call the board may not have.
//!
//! Why not one NVIC priority level per task, as RTIC does? That scheme lets the NVIC make
//! the scheduling decision again, in hardware, and needs every task to be an interrupt
//! handler: it cannot run OSEK's extended tasks (`WaitEvent` blocks with the task's
//! context kept), and the verified kernel's decision would be duplicated by a second
//! scheduler that must be shown to agree with it. Here the kernel is the only scheduler,
//! and the cost is a software context switch (its instructions are counted in the book:
//! `docs/src/performance.md`), except where a task lets in a basic task by its own kernel
//! call: that job starts by a plain call on the caller's stack, at the end of the kernel
//! call ([`crate::port::preempt`], "A new job by a call"; `Arch::may_call_job` here: thread
//! mode, PRIMASK clear).
//!
//! NVIC priorities (3 priority bits are assumed, the fewest a Cortex-M4 implements): an
//! OSEK ISR of priority `p` (1 to 6, either category) gets `0xE0 - 0x20 * p`; PendSV gets
//! `0xE0`, the lowest; the CPU's faults keep 0, the highest.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};

use cortex_m::peripheral::scb::{Exception, SystemHandler};
use cortex_m::peripheral::{MPU, NVIC, SCB};
use cortex_m::register::{basepri, basepri_max};
use cw_core::os::{InterruptMask, IsrCategory, TaskId};

use crate::port::preempt::{Arch, Mark, PortFault, Preemptive};
use crate::port::OsKernel;

pub mod trace;

pub use crate::port::preempt::MAX_TASKS;

/// Words of the shared stack of the basic tasks (and the idle loop): 2 KiB.
pub const BASIC_STACK_WORDS: usize = 512;
/// The value painted into unused stack, to measure the deepest use.
pub const STACK_PAINT: u32 = 0xDEAD_BEEF;
/// Words at the bottom of every task stack (the shared one and each task's own): the
/// stack guard. While a context runs, the MPU makes its stack's guard inaccessible, so the
/// first access past the stack's end faults (MemManage) at that instruction; and a context
/// switch that finds a saved stack pointer inside the guard reports the overflow too.
/// Either way the OS shuts down with `E_OS_STACKFAULT`.
///
/// 256 bytes. A function's frame can move the stack pointer past the stack's end before
/// it touches memory, and the fault's own exception frame (32 bytes, 104 with the FPU's
/// registers) is then pushed below that, lowest word first; the guard must absorb both,
/// or the push would land in whatever the linker put below the stack. So an overflow is
/// caught before it writes outside the stack as long as no single frame steps more than
/// 152 bytes (224 without FPU state) past the stack's end: the usual limit of MPU guards
/// on cores without stack-limit registers (ARMv8-M has PSPLIM).
pub const GUARD_WORDS: usize = 64;
/// The main stack's size (ISRs, PendSV and the fault handlers; the exception frames go on
/// the interrupted task's stack): the bytes below the main stack pointer at the OS's start,
/// painted for [`main_stack_use`], with an MPU guard (region 1) right below them.
pub const MAIN_STACK_BYTES: u32 = 2048;
/// The highest OSEK ISR priority the port expresses (3 NVIC priority bits: 0 is the
/// faults' level, 7 PendSV's).
pub const ISR_PRIORITIES: u8 = 6;

/// The NVIC priority byte of an OSEK ISR priority (1 to [`ISR_PRIORITIES`]; the port
/// refuses a configuration with others before it starts).
pub const fn nvic_priority(osek_priority: u8) -> u8 {
    0xE0u8.wrapping_sub(0x20u8.wrapping_mul(osek_priority))
}

/// The BASEPRI value for a kernel interrupt mask (0: nothing masked).
fn basepri_for(mask: InterruptMask) -> u8 {
    match mask {
        InterruptMask::None => 0,
        InterruptMask::UpTo(p) => nvic_priority(p.max(1)),
        // PRIMASK does it; BASEPRI holds the OS level meanwhile.
        InterruptMask::All => OS_LEVEL.load(Ordering::Relaxed),
    }
}

/// The BASEPRI value for the mask of processor priority `level`: [`basepri_for`] of
/// [`InterruptMask::at_level`], with the task levels (the common case) decided by one
/// compare.
#[inline(always)]
fn basepri_at_level(level: u8) -> u8 {
    if level < cw_core::os::ISR_LEVEL_BASE {
        0
    } else {
        basepri_for(InterruptMask::at_level(level))
    }
}

/// The kernel lock's BASEPRI: the highest category-2 ISR's NVIC priority, set at start
/// (until then the lowest level that still holds PendSV); read by the switch exception
/// (`PendSV`, in assembly) and the rare masks. The kernel calls read the port's own copy
/// ([`CortexM`]); [`start`] sets both.
#[no_mangle]
static CW_PORT_OS_LEVEL: AtomicU8 = AtomicU8::new(INITIAL_OS_LEVEL);
use CW_PORT_OS_LEVEL as OS_LEVEL;

/// The kernel lock's BASEPRI before [`start`] sets it.
const INITIAL_OS_LEVEL: u8 = 0xE0;

/// The Cortex-M CPU under the preemptive port.
#[derive(Debug)]
pub struct CortexM {
    /// The kernel lock's BASEPRI, as [`CW_PORT_OS_LEVEL`] holds it: inside the port, so
    /// that every kernel call loads it at an offset from the port it already has in a
    /// register (one instruction) instead of from a global's address (three).
    os_level: AtomicU8,
}

impl CortexM {
    /// The CPU, its kernel lock at the level before start.
    pub const fn new() -> Self {
        Self {
            os_level: AtomicU8::new(INITIAL_OS_LEVEL),
        }
    }

    /// The kernel lock's BASEPRI: both copies, which stay equal (before start).
    fn set_os_level(&self, value: u8) {
        self.os_level.store(value, Ordering::Relaxed);
        OS_LEVEL.store(value, Ordering::Relaxed);
    }
}

impl Default for CortexM {
    /// [`CortexM::new`]: the kernel lock's level the global holds before start.
    fn default() -> Self {
        Self::new()
    }
}

/// The preemptive port on a Cortex-M.
pub type CortexMPort<K> = Preemptive<K, CortexM>;

/// The port of `kernel` on this CPU.
pub const fn port<K: OsKernel>(kernel: K) -> CortexMPort<K> {
    Preemptive::new(kernel, CortexM::new())
}

impl Arch for CortexM {
    const ISR_PRIORITIES: u8 = ISR_PRIORITIES;
    const GUARD_BYTES: u32 = (GUARD_WORDS * 4) as u32;
    const FIRST_FRAME_BYTES: u32 = 17 * 4 + 4;

    #[inline(always)]
    fn lock_os(&self) {
        // `basepri_max::write` ends with an ISB: the lock holds from the next instruction.
        basepri_max::write(self.os_level.load(Ordering::Relaxed));
    }

    #[inline(always)]
    fn set_mask(&self, mask: InterruptMask) {
        // SAFETY: BASEPRI only holds interrupts back; the value is the kernel's mask.
        unsafe { basepri::write(basepri_for(mask)) };
    }

    #[inline(always)]
    fn set_level(&self, level: u8) {
        // SAFETY: BASEPRI only holds interrupts back; the value is the kernel's mask.
        unsafe { basepri::write(basepri_at_level(level)) };
    }

    #[inline(always)]
    fn level_value(level: u8) -> u8 {
        basepri_at_level(level)
    }

    #[inline(always)]
    fn set_level_value(&self, value: u8) {
        // SAFETY: BASEPRI only holds interrupts back; the value is that of a resource's
        // ceiling, the kernel's mask while a task holds it.
        unsafe { basepri::write(value) };
    }

    #[inline(always)]
    fn all_masked(&self) -> bool {
        // PRIMASK "inactive": exceptions of configurable priority are not taken.
        cortex_m::register::primask::read().is_inactive()
    }

    #[inline(always)]
    fn disable_all(&self) {
        cortex_m::interrupt::disable();
    }

    #[inline(always)]
    fn enable_all(&self) {
        // SAFETY: the port unmasks only what it (or the kernel's `All` mask) masked.
        unsafe { cortex_m::interrupt::enable() };
    }

    #[inline(always)]
    fn request_switch(&self) {
        SCB::set_pendsv();
    }

    #[inline(always)]
    fn wait(&self) {
        cortex_m::asm::wfi();
    }

    unsafe fn first_frame(&self, top: u32, task: u8) -> u32 {
        let frame_top = top & !7;
        let frame = frame_top - 17 * 4;
        // The frame PendSV's return loads: r4-r11 and EXC_RETURN (its own part), then the
        // exception frame (r0-r3, r12, lr, pc, xPSR). A new job reads none of r1-r3, r12
        // and r4-r11 before writing them (it starts at `cw_port_job`, a function of one
        // argument), so only the five words that decide where and how it starts are
        // written; the others keep what the stack held (as FreeRTOS's Cortex-M ports
        // leave them).
        let word = |i: usize, value: u32| {
            // SAFETY: the caller's contract: the 72 bytes below `top` are free stack, and
            // every `i` below is under 17, the frame's words.
            unsafe { (frame as *mut u32).add(i).write_volatile(value) };
        };
        // EXC_RETURN: thread mode, process stack, no FPU state
        word(8, 0xFFFF_FFFD);
        // r0: the task index, `cw_port_job`'s argument
        word(9, u32::from(task));
        // lr: a job never returns (it ends through the kernel)
        word(14, 0xFFFF_FFFF);
        // pc: the job entry, Thumb bit cleared as the exception frame wants it
        word(15, (cw_port_job as *const () as usize as u32) & !1);
        // xPSR: Thumb state
        word(16, 0x0100_0000);
        frame
    }

    fn move_guard(&self, bottom: u32) {
        if !mpu_guards() {
            return;
        }
        // SAFETY: only region 0's base moves, to the bottom of a 256-byte-aligned stack;
        // the switch runs with the kernel lock taken.
        unsafe { (*MPU::PTR).rbar.write(bottom | RBAR_VALID) };
        // The new guard is in force before the incoming context's first access.
        cortex_m::asm::dsb();
        cortex_m::asm::isb();
    }

    fn guard_intact(&self, bottom: u32) -> bool {
        // With the MPU, the guard cannot have been written: the write would have faulted.
        mpu_guards() || guard_painted(bottom)
    }

    fn quiet_active_line(&self) {
        // IPSR: 16 + n for external interrupt n; the system exceptions (SysTick among
        // them) are not level-triggered lines.
        let ipsr: u32;
        // SAFETY: reads IPSR, no side effect.
        unsafe { core::arch::asm!("mrs {}, ipsr", out(reg) ipsr, options(nomem, nostack)) };
        if let Some(line) = (ipsr & 0x1FF).checked_sub(16) {
            NVIC::mask(Line(line as u16));
        }
    }

    fn report(&self, fault: &PortFault) {
        if let Some(app) = app() {
            app.report(fault);
        }
    }

    fn stopped(&self) -> ! {
        match app() {
            Some(app) => app.shut_down(),
            None => halt_here(),
        }
    }

    fn halt(&self) -> ! {
        match app() {
            Some(app) => app.halt(),
            None => halt_here(),
        }
    }

    #[inline]
    fn now_ms(&self) -> u64 {
        now_ms()
    }

    #[inline(always)]
    fn trace(&self, mark: Mark) {
        if !trace::ENABLED {
            return;
        }
        trace::mark(mark);
    }

    #[inline(always)]
    fn may_call_job(&self) -> bool {
        // Thread mode (IPSR 0: a task's code, no exception active) and PRIMASK clear.
        let ipsr: u32;
        // SAFETY: reads IPSR, no side effect.
        unsafe { core::arch::asm!("mrs {}, ipsr", out(reg) ipsr, options(nomem, nostack)) };
        ipsr & 0x1FF == 0 && !self.all_masked()
    }

    #[inline(always)]
    fn call_job(&self, task: u8) {
        if let Some(app) = app() {
            app.run_job(TaskId(task));
        }
    }
}

/// An external interrupt line of the NVIC, by number (a board names only the lines its
/// chip has; the port, the one active now, read from IPSR).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Line(pub u16);

// SAFETY: the numbers are external interrupt lines of the chip: a board's own, or IPSR's.
unsafe impl cortex_m::interrupt::InterruptNumber for Line {
    fn number(self) -> u16 {
        self.0
    }
}

/// Logs a fatal error's report the first time only: a fault or panic inside the log
/// itself (defmt's logger refuses to be taken twice, by panicking) must not recurse. The
/// boards' `fatal` and `halt` speak through it.
pub fn last_words(log: impl FnOnce()) {
    static SPOKEN: AtomicBool = AtomicBool::new(false);
    if !SPOKEN.swap(true, Ordering::Relaxed) {
        log();
    }
}

/// Logs a port fault: `FATAL: WHAT ITEM` (the boards' `report`, after their safe state).
pub fn log_fault(fault: &PortFault) {
    let (what, item) = fault.parts();
    defmt::println!("FATAL: {=str} {=str}", what, item);
}

/// No application to end the run: every interrupt off, the core waits for ever (a
/// documented halt: a debugger finds it here).
fn halt_here() -> ! {
    cortex_m::interrupt::disable();
    loop {
        cortex_m::asm::wfi();
    }
}

// ---- time ---------------------------------------------------------------------------

/// Milliseconds since the OS tick started: low and high words, written by SysTick alone.
static MS_LOW: AtomicU32 = AtomicU32::new(0);
static MS_HIGH: AtomicU32 = AtomicU32::new(0);

/// Milliseconds since the OS tick started (64 bits: no wrap in the ECU's life).
pub fn now_ms() -> u64 {
    loop {
        let high = MS_HIGH.load(Ordering::Acquire);
        let low = MS_LOW.load(Ordering::Acquire);
        // SysTick, the only writer, runs whole between two reads of this context: the
        // same high word twice means the pair is one value.
        if MS_HIGH.load(Ordering::Acquire) == high {
            return u64::from(high) << 32 | u64::from(low);
        }
    }
}

/// [`now_ms`] where SysTick cannot run (interrupts masked): the two words as they are.
pub(crate) fn now_ms_masked() -> u64 {
    u64::from(MS_HIGH.load(Ordering::Relaxed)) << 32 | u64::from(MS_LOW.load(Ordering::Relaxed))
}

/// The OS tick: one millisecond more (SysTick's handler, before the application's tick).
fn advance_ms() {
    let low = MS_LOW.load(Ordering::Relaxed).wrapping_add(1);
    if low == 0 {
        MS_HIGH.fetch_add(1, Ordering::Release);
    }
    MS_LOW.store(low, Ordering::Release);
}

/// The time since the OS started, µs (SysTick's position within the current ms).
pub fn now_us() -> u64 {
    let (whole, into, per_tick) = trace::systick_position();
    whole * 1000 + u64::from(into) * 1000 / u64::from(per_tick.max(1))
}

// ---- stacks ---------------------------------------------------------------------------

/// A task's own stack (aligned for its MPU guard region). Extended tasks need one:
/// `WaitEvent` keeps the task's context while tasks of lower priority run, which on the
/// shared stack would grow into it.
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
/// shared stack. A fatal port fault if `task` is out of range, the stack is too small
/// for its guard and two frames, or it overlaps another stack.
pub fn set_task_stack<K: OsKernel, const WORDS: usize>(
    port: &CortexMPort<K>,
    task: TaskId,
    stack: &'static TaskStack<WORDS>,
) {
    let bottom = stack.0.get() as u32;
    port.set_task_stack(task, bottom, bottom + (WORDS * 4) as u32);
}

/// The deepest use of `task`'s own stack so far, in bytes (`None`: it has none).
pub fn task_stack_use<K: OsKernel>(port: &CortexMPort<K>, task: TaskId) -> Option<usize> {
    let (bottom, top) = port.stack_of(task);
    (bottom != BASIC_STACK.0.get() as u32).then(|| {
        painted_use(
            bottom as *const u32,
            ((top - bottom) / 4) as usize,
            GUARD_WORDS,
        )
    })
}

/// Bytes of a painted stack of `words` words at `base` that were overwritten, above its
/// first `skip` words (a stack's guard is never written: the MPU forbids it, and reading
/// it from a context whose guard it is would fault).
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

/// Whether the guard whose lowest address is `bottom` still holds its paint in every
/// word (the check on a core without an MPU).
fn guard_painted(bottom: u32) -> bool {
    (0..GUARD_WORDS as u32).all(|i| {
        // SAFETY: `bottom` is the lowest address of a stack the port painted (the shared
        // stack, a task's own, or the main stack's guard), whose first GUARD_WORDS words
        // are its guard; without an MPU nothing forbids reading them.
        unsafe { ((bottom + 4 * i) as *const u32).read_volatile() == STACK_PAINT }
    })
}

/// Whether the MPU enforces the stack guards. Set once at start from `MPU_TYPE`: a core
/// built without the Arm MPU (the S32K144's has none: NXP fits a system MPU on the
/// crossbar instead) reads `DREGION` 0, and the guards are then checked, not enforced
/// ([`Arch::guard_intact`] at every switch for the task stacks, every OS tick for the
/// main stack).
static MPU_GUARDS: AtomicBool = AtomicBool::new(false);

fn mpu_guards() -> bool {
    MPU_GUARDS.load(Ordering::Relaxed)
}

/// Whether this core's stack guards are enforced by its MPU (`false`: checked in
/// software, see [`Arch::guard_intact`]); known once the OS has started.
pub fn stack_guards_enforced() -> bool {
    mpu_guards()
}

/// The shared stack of the basic tasks (aligned for its MPU guard region).
#[repr(C, align(256))]
struct Stack(UnsafeCell<[u32; BASIC_STACK_WORDS]>);

// SAFETY: the stack's memory is used only as the process stack (PSP) once the OS starts,
// and read by `basic_stack_use` for the painted-stack measurement.
unsafe impl Sync for Stack {}

#[link_section = ".uninit.cw_basic_stack"]
static BASIC_STACK: Stack = Stack(UnsafeCell::new([0; BASIC_STACK_WORDS]));

/// The main stack's painted region: its top (the main stack pointer when the OS
/// started) and its lowest address (the guard's top), set once by the idle loop's start.
static MAIN_TOP: AtomicU32 = AtomicU32::new(0);
#[no_mangle]
static CW_PORT_MAIN_GUARD_TOP: AtomicU32 = AtomicU32::new(0);

/// The deepest use of the main stack since the OS started, in bytes (ISRs, PendSV and
/// the fault handlers run there; the exception frames go on the interrupted task's
/// stack); at most [`MAIN_STACK_BYTES`].
pub fn main_stack_use() -> usize {
    let top = MAIN_TOP.load(Ordering::Relaxed);
    let bottom = CW_PORT_MAIN_GUARD_TOP.load(Ordering::Relaxed);
    if top == 0 {
        return 0;
    }
    painted_use(bottom as *const u32, ((top - bottom) / 4) as usize, 0)
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

// ---- the application ----------------------------------------------------------------

/// The application the port runs: the ECU's entry points and the board's ends.
pub trait App: Sync {
    /// `StartOS` (from the idle loop's context, once, with every interrupt masked: the
    /// port unmasks them when it returns).
    fn start_os(&self);
    /// One job of `task`, from its first line to `TerminateTask`.
    fn run_job(&self, task: TaskId);
    /// The idle loop's work, between interrupts (returns to wait for the next one).
    fn idle(&self);
    /// The OS tick (SysTick's handler, after the port's millisecond count advanced).
    fn tick(&self);
    /// External interrupt line `line` of the board.
    fn irq(&self, line: u16);
    /// Logs a port fault or the CPU's (with every interrupt masked): before
    /// `ShutdownOS(E_OS_STACKFAULT)` for a stack overflow, before [`App::halt`] otherwise.
    fn report(&self, fault: &PortFault);
    /// A fault the OS cannot go on from (a refused configuration, a panic, HardFault, NMI,
    /// BusFault, UsageFault): the board's safe state, then a reset or a documented halt.
    fn halt(&self) -> !;
    /// `ShutdownOS` ran (the application's own call, or the OS's on a stack fault): called
    /// once, from the kernel call that shut the OS down, with interrupts disabled for good
    /// (OSEK: the OS does not come back, no task or ISR runs again). The application puts
    /// its outputs in their safe state, reports and stops (EcuM's power-off or reset).
    /// Kernel calls that only read (the hooks' record) are still served.
    fn shut_down(&self) -> !;
}

struct AppCell(UnsafeCell<Option<&'static dyn App>>);

// SAFETY: written once by `start`, before any interrupt or task can read it.
unsafe impl Sync for AppCell {}

static APP: AppCell = AppCell(UnsafeCell::new(None));

/// The application, once `start` has registered it.
pub fn app() -> Option<&'static dyn App> {
    // SAFETY: `APP` is written only in `start`, with interrupts off, before the task
    // switch that makes any reader run; afterwards it is only read.
    unsafe { *APP.0.get() }
}

/// The running port, for the exception handlers (PendSV, MemManage): its address and the
/// handlers' entries for its kernel type.
#[derive(Clone, Copy)]
struct Registered {
    port: *const (),
    switch: unsafe fn(*const (), u32) -> u32,
    fault: unsafe fn(*const (), StackFault) -> !,
    monitor: unsafe fn(*const ()),
}

struct PortCell(UnsafeCell<Option<Registered>>);

// SAFETY: written once by `start` with interrupts off, before any exception that reads it
// can run; read-only afterwards.
unsafe impl Sync for PortCell {}

static PORT: PortCell = PortCell(UnsafeCell::new(None));

fn registered() -> Option<Registered> {
    // SAFETY: see `PortCell`.
    unsafe { *PORT.0.get() }
}

/// Which stack a guard fault hit.
#[derive(Clone, Copy, PartialEq, Eq)]
enum StackFault {
    /// The running context's task stack.
    Task,
    /// The main stack.
    Main,
}

/// # Safety
/// `port` is the address of a `CortexMPort<K>` registered by `start` (a `'static`).
unsafe fn switch_of<K: OsKernel>(port: *const (), sp: u32) -> u32 {
    // SAFETY: the caller's contract.
    let port = unsafe { &*port.cast::<CortexMPort<K>>() };
    port.switch(sp)
}

/// # Safety
/// As [`switch_of`].
unsafe fn monitor_of<K: OsKernel>(port: *const ()) {
    // SAFETY: the caller's contract.
    let port = unsafe { &*port.cast::<CortexMPort<K>>() };
    port.monitor_stack();
}

/// # Safety
/// As [`switch_of`].
unsafe fn fault_of<K: OsKernel>(port: *const (), which: StackFault) -> ! {
    // SAFETY: the caller's contract.
    let port = unsafe { &*port.cast::<CortexMPort<K>>() };
    match which {
        StackFault::Main => port.main_stack_fault(),
        StackFault::Task => port.stack_fault(port.current_own_stack_task()),
    }
}

/// Starts the OS on this port and becomes the idle loop: checks the kernel's
/// configuration against the port (task count, ISR priorities, an own stack for every
/// extended task: a refusal is a fatal port fault naming the item), paints the task
/// stacks, sets PendSV to the lowest priority and the kernel lock's level, turns the MPU's
/// stack guards on, moves thread mode to the task stack, calls `app.start_os()` and then
/// `app.idle()` between interrupts forever.
pub fn start<K: OsKernel>(app: &'static dyn App, port: &'static CortexMPort<K>) -> ! {
    cortex_m::interrupt::disable();
    // SAFETY: interrupts are off and the OS has not started: nothing else reads these.
    unsafe {
        *APP.0.get() = Some(app);
        *PORT.0.get() = Some(Registered {
            port: (port as *const CortexMPort<K>).cast(),
            switch: switch_of::<K>,
            fault: fault_of::<K>,
            monitor: monitor_of::<K>,
        });
    }
    let basic_bottom = BASIC_STACK.0.get() as u32;
    let basic_top = basic_bottom + (BASIC_STACK_WORDS * 4) as u32;
    port.set_shared_stack(basic_bottom, basic_top);
    port.start_checked();
    // The kernel lock's level: the highest category-2 ISR's.
    let os_priority = port.before_start(|k, _| {
        k.isrs()
            .iter()
            .filter(|i| i.category == IsrCategory::Two)
            .map(|i| i.priority)
            .max()
            .unwrap_or(1)
    });
    port.arch().set_os_level(nvic_priority(os_priority));
    // SAFETY: the shared stack's array, which nothing uses yet.
    unsafe { paint(basic_bottom, basic_top) };
    let own = port.own_stacks();
    for t in (0..MAX_TASKS as u8).filter(|t| own & (1 << t) != 0) {
        let (bottom, top) = port.stack_of(TaskId(t));
        // SAFETY: a task stack given by `set_task_stack`, not yet in use.
        unsafe { paint(bottom, top) };
    }
    // SAFETY: the core peripherals are taken once, here, before the OS runs.
    let mut cp = unsafe { cortex_m::Peripherals::steal() };
    // SAFETY: setting exception priorities before interrupts are enabled.
    unsafe {
        cp.SCB.set_priority(SystemHandler::PendSV, 0xE0);
    }
    // The configurable faults are taken as themselves (not escalated to HardFault), each
    // with its handler below.
    cp.SCB.enable(Exception::MemoryManagement);
    cp.SCB.enable(Exception::BusFault);
    cp.SCB.enable(Exception::UsageFault);
    // MPU_TYPE[DREGION]: the data regions the core has (0: no MPU; two are needed).
    let regions = (cp.MPU._type.read() >> 8) & 0xFF;
    MPU_GUARDS.store(regions >= 2, Ordering::Relaxed);
    if mpu_guards() {
        // SAFETY: region 0 becomes the running context's stack guard (256 bytes, no
        // access, never executable); the background map keeps every other address as
        // before for privileged code, which is all code here. The idle loop's guard (the
        // shared stack's) is the first. Region 1 (the main stack's guard) is set when the
        // main stack's top is known, before any interrupt.
        unsafe {
            cp.MPU.rnr.write(0);
            cp.MPU.rbar.write(basic_bottom);
            cp.MPU.rasr.write(GUARD_RASR);
            cp.MPU.ctrl.write(MPU_ENABLE | MPU_PRIVDEFENA);
        }
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    // SAFETY: `basic_top` is the 8-byte-aligned end of a static array reserved for this
    // stack; `cw_port_enter_idle` moves thread mode onto it and never returns.
    unsafe { cw_port_enter_idle(basic_top) }
}

/// Sets the NVIC priority of an external interrupt for an OSEK ISR priority and enables
/// it.
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
    run_systick(&mut cp.SYST, reload, true);
}

/// SysTick free-running over its whole 24-bit range (0.67 s at 25 MHz) without its
/// interrupt: the trace's clock for measurements before the OS starts, which run with
/// interrupts off for longer than a tick (a tick's wraps would go uncounted).
/// [`start_systick`] then starts the OS tick.
pub fn start_free_systick() {
    // SAFETY: as `enable_irq`.
    let mut cp = unsafe { cortex_m::Peripherals::steal() };
    run_systick(&mut cp.SYST, 0x00FF_FFFF, false);
}

/// SysTick on the core clock from zero, wrapping every `reload + 1` counts (the trace's
/// counts per period), its interrupt on or off.
fn run_systick(syst: &mut cortex_m::peripheral::SYST, reload: u32, interrupt: bool) {
    syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    syst.set_reload(reload);
    trace::set_counts_per_ms(reload + 1);
    syst.clear_current();
    if interrupt {
        syst.enable_interrupt();
    } else {
        syst.disable_interrupt();
    }
    syst.enable_counter();
}

extern "C" {
    fn cw_port_enter_idle(top: u32) -> !;
    /// Moves the main stack pointer to the main stack's top and goes on in
    /// `cw_port_main_stack_fault` (every interrupt masked; never returns).
    fn cw_port_main_overflow() -> !;
    /// The end of the linker's `.bss` and `.uninit` (cortex-m-rt's symbol): nothing of
    /// the image lives above it but the main stack.
    static _stack_end: u32;
}

/// The idle loop, on the task stack (called once by `cw_port_enter_idle`).
#[no_mangle]
extern "C" fn cw_port_idle() -> ! {
    // Thread mode runs on the task stack from here on, so the main stack pointer stays
    // where it is until an exception uses the memory below it: the main stack is the
    // MAIN_STACK_BYTES below it, painted, with its guard right below.
    let top = cortex_m::register::msp::read() & !7;
    let guard_top = (top - MAIN_STACK_BYTES) & !0xFF;
    let guard_bottom = guard_top - (GUARD_WORDS * 4) as u32;
    if guard_bottom < core::ptr::addr_of!(_stack_end) as u32 {
        fatal(PortFault::Board("the main stack does not fit above .bss"));
    }
    // SAFETY: the guard and the main stack below the main stack pointer, inside the RAM
    // the linker leaves to the main stack: nothing lives there, and interrupts are still
    // off. (The guard is painted for the check of a core without an MPU.)
    unsafe { paint(guard_bottom, top) };
    MAIN_TOP.store(top, Ordering::Relaxed);
    CW_PORT_MAIN_GUARD_TOP.store(guard_top, Ordering::Relaxed);
    if mpu_guards() {
        // SAFETY: region 1 becomes the main stack's guard: 256 bytes below its budget, no
        // access, never executable; nothing of the image lives there (checked above).
        unsafe {
            let mpu = &*MPU::PTR;
            mpu.rbar.write(guard_bottom | RBAR_VALID | 1);
            mpu.rasr.write(GUARD_RASR);
        }
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    if let Some(app) = app() {
        app.start_os();
        repaint_below_idle();
        // SAFETY: the OS runs from here on, from thread mode on the task stack.
        unsafe { cortex_m::interrupt::enable() };
        loop {
            app.idle();
            cortex_m::asm::wfi();
        }
    }
    halt_here();
}

/// Paints the shared stack again below the idle loop's frame, after the start-up: what
/// the start ran there (`StartOS`, and a measuring image's calibration and driver
/// measurements, inlined into one large frame) is over, and the deepest use reported
/// later ([`basic_stack_use`]) is then the tasks' and their interrupts', not the
/// start-up's. A loop of its own, without a call, so that it writes no frame below the
/// stack pointer while it paints there. Only in the images that report the stack's use
/// (the trace's: a production image has no report, and no use for the 40 bytes).
#[inline(always)]
fn repaint_below_idle() {
    // A margin below the stack pointer that nothing of this loop reaches.
    const MARGIN: u32 = 64;
    if !trace::ENABLED {
        return;
    }
    let bottom = BASIC_STACK.0.get() as u32 + (GUARD_WORDS * 4) as u32;
    let top = (cortex_m::register::psp::read() & !3).saturating_sub(MARGIN);
    let mut word = bottom;
    while word < top {
        // SAFETY: the shared stack's words between its guard (which the MPU may forbid,
        // so it is left out) and the idle loop's stack pointer, less a margin: interrupts
        // are still off, the first task's frame is written by the switch that follows, so
        // nothing lives there now.
        unsafe { (word as *mut u32).write_volatile(STACK_PAINT) };
        word += 4;
    }
}

/// A fatal fault: reported through the application, then its halt.
fn fatal(fault: PortFault) -> ! {
    cortex_m::interrupt::disable();
    if let Some(app) = app() {
        app.report(&fault);
        app.halt();
    }
    halt_here()
}

/// A job's first frame: r0 is its task index, pc the job entry.
#[no_mangle]
extern "C" fn cw_port_job(task: u32) -> ! {
    if let Some(app) = app() {
        app.run_job(TaskId(task as u8));
    }
    // `run_job` ends through the kernel (the port ends a job whose TerminateTask is
    // refused with E_OS_MISSINGEND); reaching here is a fault.
    fatal(PortFault::Board("a job returned"));
}

/// PendSV's decision, with the kernel lock taken: the port's switch.
#[no_mangle]
extern "C" fn cw_port_switch(sp: u32) -> u32 {
    match registered() {
        // SAFETY: registered by `start` for this port's kernel type.
        Some(r) => unsafe { (r.switch)(r.port, sp) },
        None => fatal(PortFault::Board("a task switch before start")),
    }
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

/// On a core without an MPU, the stack monitoring of every OS tick: the main stack's
/// guard, then the running context's ([`Preemptive::monitor_stack`]); a written guard is
/// that stack's overflow (`ShutdownOS(E_OS_STACKFAULT)`). A main stack overflow is
/// reported from the main stack's top (`cw_port_main_overflow` moves the main stack
/// pointer there first, as the guard faults' entries do: the interrupted contexts never
/// resume), not from the depth that overflowed.
fn monitor_stacks() {
    let Some(r) = registered() else {
        return;
    };
    let guard_top = CW_PORT_MAIN_GUARD_TOP.load(Ordering::Relaxed);
    if guard_top != 0 && !guard_painted(guard_top - (GUARD_WORDS * 4) as u32) {
        cortex_m::interrupt::disable();
        // SAFETY: every interrupt is masked and nothing returns to the contexts below:
        // the main stack is given up from here on.
        unsafe { cw_port_main_overflow() };
    }
    // SAFETY: registered by `start` for this port's kernel type; the OS tick is a
    // category-2 ISR (the configuration's), which the kernel lock masks, as
    // `monitor_stack` needs.
    unsafe { (r.monitor)(r.port) };
}

/// The main stack's overflow found by the OS tick, on a fresh main stack: the port's
/// stack fault for the main stack.
#[no_mangle]
extern "C" fn cw_port_main_stack_fault() -> ! {
    match registered() {
        // SAFETY: registered by `start` for this port's kernel type.
        Some(r) => unsafe { (r.fault)(r.port, StackFault::Main) },
        None => fatal(PortFault::Board("stack overflow before start")),
    }
}

/// A MemManage fault (or a HardFault escalated from one): a stack guard was hit.
/// `main_reset` is 1 when the entry found the main stack pointer inside the main stack's
/// guard and moved it back to the main stack's top. Never returns.
#[no_mangle]
extern "C" fn cw_port_memory_fault(main_reset: u32) -> ! {
    cortex_m::interrupt::disable();
    if !mpu_guards() {
        // No MPU, no guard: the default memory map refused an access (an execution
        // from a never-executable region, say), not a stack overflow.
        fatal(PortFault::Board("MemManage"));
    }
    // SAFETY: reads of the fault status and address registers.
    let (cfsr, mmfar) = unsafe { ((*SCB::PTR).cfsr.read(), (*SCB::PTR).mmfar.read()) };
    let guard_top = CW_PORT_MAIN_GUARD_TOP.load(Ordering::Relaxed);
    let mmar_valid = cfsr & (1 << 7) != 0;
    let in_main_guard = mmar_valid
        && mmfar < guard_top
        && mmfar >= guard_top.wrapping_sub((GUARD_WORDS * 4) as u32);
    let which = if main_reset != 0 || in_main_guard {
        StackFault::Main
    } else {
        StackFault::Task
    };
    match registered() {
        // SAFETY: registered by `start` for this port's kernel type.
        Some(r) => unsafe { (r.fault)(r.port, which) },
        None => fatal(PortFault::Board("stack overflow before start")),
    }
}

/// HardFault: a MemManage fault escalated (it came with every interrupt masked) is a
/// stack guard hit; anything else is fatal, named by the fault status register's group.
#[no_mangle]
extern "C" fn cw_port_hard_fault(main_reset: u32) -> ! {
    // SAFETY: a read of the Configurable Fault Status Register.
    let cfsr = unsafe { (*SCB::PTR).cfsr.read() };
    if cfsr & 0xFF != 0 {
        cw_port_memory_fault(main_reset);
    }
    fatal(PortFault::Board(if cfsr & 0xFF00 != 0 {
        "HardFault (a bus fault escalated)"
    } else if cfsr & 0xFFFF_0000 != 0 {
        "HardFault (a usage fault escalated)"
    } else {
        "HardFault"
    }))
}

#[cortex_m_rt::exception]
fn SysTick() {
    advance_ms();
    if !mpu_guards() {
        monitor_stacks();
    }
    if let Some(app) = app() {
        app.tick();
    }
}

#[cortex_m_rt::exception]
unsafe fn NonMaskableInt() {
    fatal(PortFault::Nmi);
}

#[cortex_m_rt::exception]
fn BusFault() {
    fatal(PortFault::Board("BusFault"));
}

#[cortex_m_rt::exception]
fn UsageFault() {
    fatal(PortFault::Board(
        "UsageFault (an undefined instruction, a division by zero, an unaligned access)",
    ));
}

#[cortex_m_rt::exception]
unsafe fn DefaultHandler(_irqn: i16) {
    fatal(PortFault::Board("an exception without a handler"));
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    if PANICKED.swap(true, Ordering::Relaxed) {
        // A panic while reporting one: no second report.
        halt_here();
    }
    fatal(PortFault::Board("panic"))
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
    // The guard faults' entries: a main stack pointer inside the main stack's guard (the
    // entry's own stacking overflowed it) is moved back to the main stack's top before
    // any Rust code pushes: the interrupted contexts never resume.
    ".section .text.MemoryManagement,\"ax\",%progbits",
    ".global MemoryManagement",
    ".type MemoryManagement,%function",
    ".thumb_func",
    "MemoryManagement:",
    "    bl cw_port_fix_msp",
    "    b cw_port_memory_fault",
    ".section .text.HardFault,\"ax\",%progbits",
    ".global HardFault",
    ".type HardFault,%function",
    ".thumb_func",
    "HardFault:",
    "    bl cw_port_fix_msp",
    "    b cw_port_hard_fault",
    // The tick's stack monitoring found the main stack's guard written: msp := the main
    // stack's top, then the stack fault (the interrupted contexts never resume).
    ".section .text.cw_port_main_overflow,\"ax\",%progbits",
    ".global cw_port_main_overflow",
    ".type cw_port_main_overflow,%function",
    ".thumb_func",
    "cw_port_main_overflow:",
    "    ldr r2, ={main_top}",
    "    ldr r2, [r2]",
    "    msr msp, r2",
    "    isb",
    "    b cw_port_main_stack_fault",
    ".ltorg",
    // r0 := 1 and msp := the main stack's top if msp lies below the main guard's top
    // (0 if the guard is not set yet); r0 := 0 otherwise. Uses r0-r2 only, no stack.
    ".section .text.cw_port_fix_msp,\"ax\",%progbits",
    ".thumb_func",
    "cw_port_fix_msp:",
    "    ldr r1, =CW_PORT_MAIN_GUARD_TOP",
    "    ldr r1, [r1]",
    "    mrs r2, msp",
    "    movs r0, #0",
    "    cmp r2, r1",
    "    bhs 1f",
    "    ldr r2, ={main_top}",
    "    ldr r2, [r2]",
    "    cbz r2, 1f",
    "    msr msp, r2",
    "    movs r0, #1",
    "1:",
    "    bx lr",
    ".ltorg",
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
    // The kernel lock (BASEPRI at the OS level): category-2 ISRs, which may change the
    // kernel's choice, wait; category-1 ISRs do not.
    "    ldr r1, =CW_PORT_OS_LEVEL",
    "    ldrb r1, [r1]",
    "    msr basepri, r1",
    "    isb",
    "    bl cw_port_switch",
    // PendSV runs only with BASEPRI clear (its priority is the lowest).
    "    movs r1, #0",
    "    msr basepri, r1",
    "    ldmia r0!, {{r4-r11, lr}}",
    "    tst lr, #0x10",
    "    it eq",
    "    vldmiaeq r0!, {{s16-s31}}",
    "    msr psp, r0",
    "    bx lr",
    ".ltorg",
    main_top = sym MAIN_TOP,
);
