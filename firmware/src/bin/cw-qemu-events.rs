//! Extended tasks and the stack guard on the Cortex-M port, on QEMU's mps2-an386: a demo
//! and test image beside the ECU (whose tasks are all basic).
//!
//! | task | kind | priority | activation | stack |
//! |---|---|---|---|---|
//! | `Waiter` | extended | 3 | autostart; waits in `WaitEvent(EV_ALARM \| EV_ISR)` | its own, 1 KiB |
//! | `Worker` | basic | 2 | `WorkAlarm`, every 3 ms | shared |
//! | `Pinger` | basic | 1 | `PingAlarm`, every 7 ms: requests `PingIsr` | shared |
//!
//! `WakeAlarm` sets `EV_ALARM` on `Waiter` every 5 ms; `PingIsr` (category 2, on the
//! board's software interrupt line) sets `EV_ISR`. `Waiter` counts its wake-ups and checks
//! that each alarm wake-up came in the millisecond its alarm expired; every `Worker` job
//! also makes a kernel call inside its own critical section, which must stay closed.
//! After 40 alarm wake-ups the waiter reports, then plays the fault the command line
//! names (`--fault NAME`; semihosting), and the run succeeds only if the port handles it
//! as its guarantees say:
//!
//! | fault | what the demo does | what must follow |
//! |---|---|---|
//! | `task-stack` (default) | `Waiter` recurses without end on its own stack | the MPU guard stops it; `ShutdownOS(E_OS_STACKFAULT)`, seen by the ShutdownHook |
//! | `in-kernel` | the same, inside a kernel call | the same (not a "kernel lock taken twice") |
//! | `main-stack` | `PingIsr` recurses without end on the main stack | the main stack's guard stops it; `E_OS_STACKFAULT` |
//! | `missing-end` | one `Worker` job ends with interrupts disabled, so its `TerminateTask` is refused | `E_OS_MISSINGEND` for the job; `Worker` and `Pinger` go on running; then `task-stack` |
//! | `no-own-stack` | `Waiter`'s own stack is not given | the port refuses to start, naming `Waiter` |
//! | `reset` | a panic in `Waiter`, with the image's fatal end set to a reset | LEDs dark, `FATAL`, `RESET`: the production image's end (QEMU exits on the reset) |
//!
//! Run: `cargo xtask qemu --events` (every fault; also in the check command's `qemu`
//! stage).
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};

use cw_bsp::cortex_m::{self as port, now_ms, App, CortexMPort, TaskStack};
use cw_bsp::mps2::{self, FatalEnd};
use cw_bsp::port::preempt::PortFault;
use cw_bsp::port::{Port, Slot};
use cw_core::os::{
    status_name, AlarmAction, AlarmConfig, ConformanceClass, CounterConfig, CounterId, Dialect,
    EventMask, HookSet, Hooks, IsrConfig, IsrId, Os, OsConfig, OsDescription, OsError, Status,
    StatusType, TaskConfig, TaskId, OSDEFAULTAPPMODE,
};

const WAITER: TaskId = TaskId(0);
const WORKER: TaskId = TaskId(1);
const PINGER: TaskId = TaskId(2);
const COUNTER: CounterId = CounterId(0);
const SYSTICK_ISR: IsrId = IsrId(0);
const PING_ISR: IsrId = IsrId(1);
const EV_ALARM: EventMask = 0b01;
const EV_ISR: EventMask = 0b10;
const WAKE_PERIOD_MS: u32 = 5;
const WAKES: u32 = 40;

static OS: OsConfig<3, 0, 1, 3, 2> = match OsConfig::new(
    OsDescription::new(
        [
            TaskConfig::extended("Waiter", 3).autostart(),
            TaskConfig::basic("Worker", 2),
            TaskConfig::basic("Pinger", 1),
        ],
        [CounterConfig {
            max_allowed_value: 0xFFFF,
            ticks_per_base: 1,
            min_cycle: 1,
        }],
        [
            AlarmConfig::new(
                "WakeAlarm",
                COUNTER,
                AlarmAction::SetEvent(WAITER, EV_ALARM),
            )
            .relative(WAKE_PERIOD_MS, WAKE_PERIOD_MS),
            AlarmConfig::new("WorkAlarm", COUNTER, AlarmAction::ActivateTask(WORKER))
                .relative(3, 3),
            AlarmConfig::new("PingAlarm", COUNTER, AlarmAction::ActivateTask(PINGER))
                .relative(7, 7),
        ],
        [
            IsrConfig::cat2("SysTickIsr", 2),
            IsrConfig::cat2("PingIsr", 1),
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
    Err(e) => panic!("{}", e.describe()),
};

cw_core::static_tables!(
    /// [`OS`] as a build-time constant.
    DemoTables: OsConfig<3, 0, 1, 3, 2> = OS
);

/// What the hooks saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
struct DemoHooks {
    errors: u32,
    shutdown: Option<StatusType>,
}

type Kernel = Os<3, 0, 1, 3, 2, 3, DemoTables, DemoHooks>;

impl Hooks<Kernel> for DemoHooks {
    fn error_hook(os: &mut Kernel, _error: OsError) {
        os.hooks_mut().errors = os.hooks_mut().errors.saturating_add(1);
    }

    fn shutdown_hook(os: &mut Kernel, error: StatusType) {
        os.hooks_mut().shutdown = Some(error);
    }
}

/// The waiter's own stack.
static WAITER_STACK: TaskStack<256> = TaskStack::new();

/// Counts kept by the tasks and read by the fault report.
static ALARM_WAKES: AtomicU32 = AtomicU32::new(0);
static ISR_WAKES: AtomicU32 = AtomicU32::new(0);
static LATE_WAKES: AtomicU32 = AtomicU32::new(0);
static PINGS: AtomicU32 = AtomicU32::new(0);
static WORK_JOBS: AtomicU32 = AtomicU32::new(0);
static DIVING: AtomicU32 = AtomicU32::new(0);
/// The stack overflow the port reported: 1 the waiter's own stack, 2 the main stack.
static FAULT_ON: AtomicU32 = AtomicU32::new(0);
/// Kernel calls inside a critical section that left it open.
static SECTIONS_OPENED: AtomicU32 = AtomicU32::new(0);
/// Worker jobs after the one that ended without a proper end.
static JOBS_AFTER_MISSING_END: AtomicU32 = AtomicU32::new(0);
static PINGS_AFTER_MISSING_END: AtomicU32 = AtomicU32::new(0);
/// 1 once a Worker job has ended without a proper end.
static MISSED_END: AtomicU32 = AtomicU32::new(0);

/// The fault a run plays after the wake-ups (`--fault NAME`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fault {
    TaskStack,
    InKernel,
    MainStack,
    MissingEnd,
    NoOwnStack,
    Reset,
}

impl Fault {
    const ALL: [(&'static str, Fault); 6] = [
        ("task-stack", Fault::TaskStack),
        ("in-kernel", Fault::InKernel),
        ("main-stack", Fault::MainStack),
        ("missing-end", Fault::MissingEnd),
        ("no-own-stack", Fault::NoOwnStack),
        ("reset", Fault::Reset),
    ];

    /// The fault the semihosting command line names (`--fault NAME`), default `task-stack`.
    fn from_command_line() -> Self {
        let mut buf = [0u8; 128];
        let line = mps2::semihosting::command_line(&mut buf).unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(name) = words.find(|w| *w == "--fault").and_then(|_| words.next()) else {
            return Fault::TaskStack;
        };
        match Self::ALL.iter().find(|(n, _)| *n == name) {
            Some(&(_, fault)) => fault,
            None => mps2::fatal("--fault takes task-stack, in-kernel, main-stack, missing-end, no-own-stack or reset"),
        }
    }

    fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, f)| *f == self)
            .map_or("?", |(n, _)| *n)
    }
}

struct Demo {
    port: CortexMPort<Kernel>,
    fault: Fault,
}

impl Demo {
    fn isr(&self, isr: IsrId, body: impl FnOnce(&Self)) {
        if self.port.kernel(|os| os.enter_isr(isr)).is_err() {
            return;
        }
        self.port.isr_entered(isr);
        body(self);
        let _ = self.port.kernel(|os| os.exit_isr());
    }

    fn end_job(&self) {
        let _ = self.port.end_job(|os| os.terminate_task());
    }

    /// `Waiter`: wakes on either event, forever; the alarm's wake-ups must come every
    /// 5 ms to the millisecond.
    fn waiter(&self) {
        loop {
            if self
                .port
                .kernel(|os| os.wait_event(EV_ALARM | EV_ISR))
                .is_err()
            {
                return;
            }
            let events = self.port.kernel(|os| os.get_event(WAITER)).unwrap_or(0);
            let _ = self.port.kernel(|os| os.clear_event(events));
            if events & EV_ISR != 0 {
                ISR_WAKES.fetch_add(1, Ordering::Relaxed);
            }
            if events & EV_ALARM != 0 {
                let n = ALARM_WAKES.fetch_add(1, Ordering::Relaxed) + 1;
                if now_ms() != u64::from(n * WAKE_PERIOD_MS) {
                    LATE_WAKES.fetch_add(1, Ordering::Relaxed);
                }
                if n == WAKES {
                    self.report();
                    self.play_fault();
                }
            }
        }
    }

    fn report(&self) {
        let hooks = self.port.inspect(|os| *os.hooks());
        defmt::println!(
            "cw-qemu-events: Waiter woke {} times by WakeAlarm ({} late), {} times by PingIsr; Worker ran {} jobs, Pinger {}; kernel errors {}; Waiter's stack used {} bytes, the shared stack {}",
            ALARM_WAKES.load(Ordering::Relaxed),
            LATE_WAKES.load(Ordering::Relaxed),
            ISR_WAKES.load(Ordering::Relaxed),
            WORK_JOBS.load(Ordering::Relaxed),
            PINGS.load(Ordering::Relaxed),
            hooks.errors,
            port::task_stack_use(&self.port, WAITER).unwrap_or(0),
            port::basic_stack_use()
        );
        port::trace::read(|t| {
            for (by, row) in t.preemptions.iter().enumerate().take(3) {
                for (over, &n) in row.iter().enumerate().filter(|(_, &n)| n > 0) {
                    // The port's trace sees jobs nest; the one below is the waiting Waiter.
                    defmt::println!(
                        "cw-qemu-events: {} jobs ran on the shared stack while {} waited on its own: {}",
                        OS.tasks()[by].name,
                        OS.tasks()[over].name,
                        n
                    );
                }
            }
        });
        if self.fault == Fault::MissingEnd {
            defmt::println!(
                "cw-qemu-events: after the job that ended without TerminateTask: Worker ran {} jobs, Pinger {}",
                JOBS_AFTER_MISSING_END.load(Ordering::Relaxed),
                PINGS_AFTER_MISSING_END.load(Ordering::Relaxed)
            );
        }
        defmt::println!(
            "cw-qemu-events: kernel calls that opened the caller's critical section: {}",
            SECTIONS_OPENED.load(Ordering::Relaxed)
        );
    }

    /// The run's fault, after the wake-ups.
    fn play_fault(&self) {
        DIVING.store(1, Ordering::Relaxed);
        match self.fault {
            Fault::TaskStack | Fault::MissingEnd | Fault::NoOwnStack => {
                defmt::println!("cw-qemu-events: now overflowing the Waiter's stack on purpose");
                dive(0);
            }
            Fault::InKernel => {
                defmt::println!(
                    "cw-qemu-events: now overflowing the Waiter's stack inside a kernel call"
                );
                self.port.kernel(|_| dive(0));
            }
            Fault::MainStack => {
                defmt::println!("cw-qemu-events: now overflowing the main stack from PingIsr");
                mps2::pend_software_irq();
            }
            Fault::Reset => {
                defmt::println!("cw-qemu-events: now panicking, the fatal end set to a reset");
                mps2::set_fatal_end(FatalEnd::Reset);
                // An index the compiler cannot see is out of range.
                let table = [1u32, 2];
                let i = core::hint::black_box(2usize);
                core::hint::black_box(table[i]);
            }
        }
    }
}

/// Recursion without end, each level with a buffer the compiler must keep: runs off the
/// bottom of the stack into its guard.
#[inline(never)]
fn dive(depth: u32) -> u32 {
    let mut buf = [0u32; 16];
    for (i, w) in buf.iter_mut().enumerate() {
        // `black_box` keeps the writes, so every level really uses its 64 bytes.
        *w = core::hint::black_box(depth.wrapping_add(i as u32));
    }
    core::hint::black_box(&buf);
    dive(depth + 1).wrapping_add(buf[(depth % 16) as usize])
}

impl App for Demo {
    fn start_os(&self) {
        // Interrupts stay off until StartOS's kernel call ends (no ISR before the OS runs).
        cortex_m::interrupt::disable();
        mps2::start_tick(OS.isrs()[SYSTICK_ISR.0 as usize].priority);
        mps2::enable_software_irq(OS.isrs()[PING_ISR.0 as usize].priority);
        self.port.kernel(|os| {
            let _ = os.start_os(OSDEFAULTAPPMODE);
        });
    }

    fn run_job(&self, task: TaskId) {
        self.port.job_started(task);
        match task {
            WAITER => self.waiter(),
            WORKER => {
                let jobs = WORK_JOBS.fetch_add(1, Ordering::Relaxed) + 1;
                // Some work on the shared stack while the waiter's context is kept.
                cortex_m::asm::delay(2_000);
                // A kernel call inside the job's own critical section leaves it closed.
                cortex_m::interrupt::free(|_| {
                    let _ = self.port.kernel(|os| os.get_task_id());
                    // PRIMASK "active": interrupts are taken again.
                    if cortex_m::register::primask::read().is_active() {
                        SECTIONS_OPENED.fetch_add(1, Ordering::Relaxed);
                    }
                });
                if MISSED_END.load(Ordering::Relaxed) == 1 {
                    JOBS_AFTER_MISSING_END.fetch_add(1, Ordering::Relaxed);
                }
                if self.fault == Fault::MissingEnd && jobs == 5 {
                    // The job ends with every interrupt disabled: its TerminateTask is
                    // refused (E_OS_DISABLEDINT), so it returns without a proper end.
                    let _ = self.port.kernel(|os| os.disable_all_interrupts());
                    MISSED_END.store(1, Ordering::Relaxed);
                }
            }
            PINGER => {
                PINGS.fetch_add(1, Ordering::Relaxed);
                if MISSED_END.load(Ordering::Relaxed) == 1 {
                    PINGS_AFTER_MISSING_END.fetch_add(1, Ordering::Relaxed);
                }
                mps2::pend_software_irq();
            }
            _ => {}
        }
        self.port.job_finished(task);
        self.end_job();
    }

    fn idle(&self) {}

    fn tick(&self) {
        self.isr(SYSTICK_ISR, |demo| {
            let _ = demo.port.kernel(|os| os.increment_counter(COUNTER));
        });
    }

    fn irq(&self, line: u16) {
        if line != mps2::SOFTWARE_IRQ {
            mps2::fatal("an interrupt line the demo does not use");
        }
        self.isr(PING_ISR, |demo| {
            if demo.fault == Fault::MainStack && DIVING.load(Ordering::Relaxed) == 1 {
                dive(0);
            }
            let _ = demo.port.kernel(|os| os.set_event(WAITER, EV_ISR));
        });
    }

    fn report(&self, fault: &PortFault) {
        let (what, item) = fault.parts();
        match fault {
            PortFault::StackOverflow(Some("Waiter")) => FAULT_ON.store(1, Ordering::Relaxed),
            PortFault::MainStackOverflow => FAULT_ON.store(2, Ordering::Relaxed),
            _ => {}
        }
        defmt::println!(
            "cw-qemu-events: the port reports: {=str} {=str}",
            what,
            item
        );
    }

    fn halt(&self) -> ! {
        mps2::halt()
    }

    fn shut_down(&self) -> ! {
        mps2::leds_safe();
        let hooks = self.port.inspect(|os| *os.hooks());
        defmt::println!(
            "cw-qemu-events: ShutdownHook saw {}",
            hooks
                .shutdown
                .map_or("nothing", |s| status_name(s).unwrap_or("an unknown code"))
        );
        let expected_fault = if self.fault == Fault::MainStack { 2 } else { 1 };
        let planned = DIVING.load(Ordering::Relaxed) == 1
            && FAULT_ON.load(Ordering::Relaxed) == expected_fault;
        // The job without a proper end: E_OS_DISABLEDINT (its refused TerminateTask) and
        // E_OS_MISSINGEND (the port's end of it), then the tasks go on.
        let (errors, went_on) = if self.fault == Fault::MissingEnd {
            (
                2,
                JOBS_AFTER_MISSING_END.load(Ordering::Relaxed) > 0
                    && PINGS_AFTER_MISSING_END.load(Ordering::Relaxed) > 0,
            )
        } else {
            (0, true)
        };
        let ok = planned
            && went_on
            && hooks.shutdown == Some(OsError::StackFault.status())
            && hooks.errors == errors
            && SECTIONS_OPENED.load(Ordering::Relaxed) == 0
            && LATE_WAKES.load(Ordering::Relaxed) == 0
            && ALARM_WAKES.load(Ordering::Relaxed) == WAKES
            && ISR_WAKES.load(Ordering::Relaxed) > 0;
        defmt::println!("cw-qemu-events: {}", if ok { "ok" } else { "FAILED" });
        mps2::exit(ok)
    }
}

static DEMO: Slot<Demo> = Slot::new();

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(kernel) = Kernel::new(DemoTables) else {
        mps2::fatal("the OS configuration is inconsistent")
    };
    // A test image: a fatal fault ends the QEMU run with a failure status.
    mps2::set_fatal_end(FatalEnd::Exit);
    let fault = Fault::from_command_line();
    let Some(demo) = DEMO.init(Demo {
        port: port::port(kernel),
        fault,
    }) else {
        mps2::fatal("started twice")
    };
    let demo: &'static Demo = demo;
    if fault != Fault::NoOwnStack {
        port::set_task_stack(&demo.port, WAITER, &WAITER_STACK);
    }
    defmt::println!(
        "cw-qemu-events: extended tasks and the stack guard on mps2-an386; fault {=str}",
        fault.name()
    );
    port::start(demo, &demo.port)
}
