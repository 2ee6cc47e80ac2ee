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
//! that each alarm wake-up came in the millisecond its alarm expired. After 40 alarm
//! wake-ups it reports, then overflows its own stack on purpose: the MPU guard below the
//! stack must stop it at the first access, and the port must shut the OS down with
//! `E_OS_STACKFAULT` for the ShutdownHook to see. The run succeeds only then.
//!
//! Run: `cargo xtask qemu --events` (also in the check command's `qemu` stage).
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};

use cw_bsp::cortex_m::{self as port, App, CortexMPort, TaskStack};
use cw_bsp::mps2;
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
/// 1: the stack fault the port reported was on the waiter's own stack.
static FAULT_ON_WAITER: AtomicU32 = AtomicU32::new(0);

struct Demo {
    port: CortexMPort<Kernel>,
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
                if mps2::now_ms() != n * WAKE_PERIOD_MS {
                    LATE_WAKES.fetch_add(1, Ordering::Relaxed);
                }
                if n == WAKES {
                    self.report();
                    DIVING.store(1, Ordering::Relaxed);
                    dive(0);
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
            port::task_stack_use(WAITER).unwrap_or(0),
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
        defmt::println!("cw-qemu-events: now overflowing the Waiter's stack on purpose");
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
                WORK_JOBS.fetch_add(1, Ordering::Relaxed);
                // Some work on the shared stack while the waiter's context is kept.
                cortex_m::asm::delay(2_000);
            }
            PINGER => {
                PINGS.fetch_add(1, Ordering::Relaxed);
                mps2::pend_software_irq();
            }
            _ => {}
        }
        self.port.job_finished(task);
        self.end_job();
    }

    fn idle(&self) {}

    fn tick(&self) {
        self.port.advance_ms();
        self.isr(SYSTICK_ISR, |demo| {
            let _ = demo.port.kernel(|os| os.increment_counter(COUNTER));
        });
    }

    fn irq(&self, line: u16) {
        if line != mps2::SOFTWARE_IRQ {
            mps2::fatal("an interrupt line the demo does not use");
        }
        self.isr(PING_ISR, |demo| {
            let _ = demo.port.kernel(|os| os.set_event(WAITER, EV_ISR));
        });
    }

    fn stack_fault(&self, task: Option<TaskId>) -> ! {
        let who = task.map_or("the shared", |t| OS.tasks()[usize::from(t.0)].name);
        defmt::println!(
            "cw-qemu-events: stack overflow caught by the MPU guard on {} stack; ShutdownOS(E_OS_STACKFAULT)",
            who
        );
        FAULT_ON_WAITER.store(u32::from(task == Some(WAITER)), Ordering::Relaxed);
        // The port hands the end to `shut_down`.
        self.port
            .kernel(|os| os.shutdown_on_fault(OsError::StackFault));
        mps2::fatal("the OS did not shut down on a stack overflow")
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
        let planned =
            DIVING.load(Ordering::Relaxed) == 1 && FAULT_ON_WAITER.load(Ordering::Relaxed) == 1;
        let ok = planned
            && hooks.shutdown == Some(OsError::StackFault.status())
            && hooks.errors == 0
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
    port::set_task_stack(WAITER, &WAITER_STACK);
    let Some(demo) = DEMO.init(Demo {
        port: CortexMPort::new(kernel),
    }) else {
        mps2::fatal("started twice")
    };
    defmt::println!("cw-qemu-events: extended tasks and the stack guard on mps2-an386");
    port::start(demo, mps2::fatal)
}
