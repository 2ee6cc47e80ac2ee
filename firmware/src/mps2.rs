//! The ECU on QEMU's mps2-an386 (Cortex-M4): the board's drivers named for [`Board`], and
//! the ECU's entry points for the Cortex-M port (`cw_bsp::cortex_m::App`).
//!
//! The sensor is deterministic: QEMU cannot time an HC-SR04 echo, so the Gpt capture
//! returns the echo width the scenario's obstacle distance gives at the current OS time,
//! converted by the same `SonarConfig::distance_to_echo_us` as the host simulation's
//! sensor model.

use cw_bsp::cortex_m::{App, CortexMPort};
use cw_bsp::mps2::{self, CoreDelay, Led, SlcanCan, SlcanEvent, Unconnected};
use cw_bsp::port::Port;
use cw_core::can::Hrh;
use cw_core::os::{OsError, TaskId};
use cw_core::sonar::SonarConfig;

use crate::board::{Board, CanEvents, CanInterrupt, PortDriver, PulseCapture};
use crate::config::{self, Kernel};
use crate::ecu::{span, Ecu};

/// The mps2-an386 board's drivers.
pub struct Mps2Board;

impl Board for Mps2Board {
    type Can = SlcanCan;
    type Led = Led;
    type Trigger = Unconnected;
    type Echo = Unconnected;
    type Delay = CoreDelay;
    type Capture = ScenarioEcho;
    type Port = Mps2PortDriver;
}

/// The ECU on this board.
pub type Mps2Ecu = Ecu<CortexMPort<Kernel>, Mps2Board>;

impl CanEvents for SlcanCan {
    fn take_event(&mut self) -> Option<CanInterrupt> {
        SlcanCan::take_event(self).map(|event| match event {
            SlcanEvent::TxConfirmation(pdu) => CanInterrupt::TxConfirmation(pdu),
            // The UART is one receive mailbox; CanIf filters by id.
            SlcanEvent::Received(frame) => CanInterrupt::Received(Hrh(0), frame),
        })
    }
}

/// The Port driver: the LED outputs low.
pub struct Mps2PortDriver;

impl PortDriver for Mps2PortDriver {
    fn port_init(&mut self) {
        mps2::leds_safe();
    }
}

/// An obstacle movement: held distances, mm, each for a duration, ms, back to back.
pub type Holds = &'static [(u32, u32)];

/// The paper's Figure 7: the obstacle held at 0.5, 1.0, 1.5, 2.0 and 2.5 m, 3 s each
/// (`scenarios/figure7.txt`).
pub const FIGURE7: Holds = &[
    (500, 3000),
    (1000, 3000),
    (1500, 3000),
    (2000, 3000),
    (2500, 3000),
];

/// The echo a scenario's obstacle gives, on the Gpt capture.
pub struct ScenarioEcho {
    sensor: SonarConfig,
    holds: Holds,
}

impl ScenarioEcho {
    /// The sensor `sensor` seeing the obstacle move as `holds` says.
    pub const fn new(sensor: SonarConfig, holds: Holds) -> Self {
        Self { sensor, holds }
    }

    /// The obstacle's distance at `t_ms` (the last one after the end).
    pub fn distance_at(&self, t_ms: u32) -> u32 {
        let mut start = 0u32;
        for &(mm, duration) in self.holds {
            start = start.saturating_add(duration);
            if t_ms < start {
                return mm;
            }
        }
        self.holds.last().map_or(0, |h| h.0)
    }

    /// The scenario's length, ms.
    pub fn duration_ms(&self) -> u32 {
        self.holds.iter().fold(0u32, |t, h| t.saturating_add(h.1))
    }
}

impl PulseCapture for ScenarioEcho {
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        let distance = self.distance_at(mps2::now_ms());
        let width = if distance > self.sensor.max_range_mm() {
            self.sensor.echo_timeout_us()
        } else {
            self.sensor
                .distance_to_echo_us(distance)
                .min(self.sensor.echo_timeout_us())
        };
        (width <= timeout_us).then_some(width)
    }
}

/// The ECU and how long its scenario lasts.
pub struct Mps2App {
    /// The ECU.
    pub ecu: Mps2Ecu,
    /// The run ends (QEMU exits) at this OS time, ms.
    pub end_ms: u32,
}

impl App for Mps2App {
    fn start_os(&self) {
        // Interrupts stay off until StartOS's own kernel call ends: an interrupt before it
        // would be an ISR the kernel cannot accept yet (a port error), and the calibration
        // may take longer than a tick when QEMU runs in real time.
        cortex_m::interrupt::disable();
        mps2::start_tick(config::OS.isrs()[config::SYSTICK_ISR.0 as usize].priority);
        calibrate(self.ecu.port());
        SlcanCan::enable_interrupts(config::OS.isrs()[config::CAN_ISR.0 as usize].priority);
        self.ecu.start_os();
    }

    fn run_job(&self, task: TaskId) {
        self.ecu.run_job(task);
    }

    fn idle(&self) {
        if mps2::now_ms() < self.end_ms {
            return;
        }
        let hooks = self.ecu.hooks();
        let schedule_ok = report_trace();
        let link = mps2::slcan_stats();
        cw_bsp::mps2_log!(
            "cw-qemu: slcan received {} frames, {} commands, {} malformed lines; {} overruns, {} replies dropped\n",
            link.rx_frames,
            link.rx_commands,
            link.rx_malformed,
            link.rx_overruns,
            link.replies_dropped
        );
        cw_bsp::mps2_log!(
            "cw-qemu: end at {} ms; kernel errors {}, port errors {}; task stack used {} of {} bytes, main stack (ISRs) {} bytes\n",
            mps2::now_ms(),
            hooks.errors,
            hooks.port_errors,
            cw_bsp::cortex_m::basic_stack_use(),
            (cw_bsp::cortex_m::BASIC_STACK_WORDS - cw_bsp::cortex_m::GUARD_WORDS) * 4,
            cw_bsp::cortex_m::main_stack_use()
        );
        mps2::exit(schedule_ok && hooks.errors == 0 && hooks.port_errors == 0);
    }

    fn tick(&self) {
        self.ecu.port().advance_ms();
        self.ecu.tick();
    }

    fn irq(&self, line: u16) {
        match line {
            // UART0 RX and TX: the CAN controller.
            0 | 1 => self.ecu.can_isr(),
            _ => mps2::fatal("an interrupt line the ECU does not use"),
        }
    }

    fn stack_fault(&self, task: Option<TaskId>) -> ! {
        self.ecu
            .port()
            .kernel(|os| os.shutdown_on_fault(OsError::StackFault));
        let shutdown = self.ecu.hooks().shutdown;
        cw_bsp::mps2_log!(
            "cw-qemu: stack overflow on the {} stack: ShutdownOS(E_OS_STACKFAULT), ShutdownHook saw {:?}\n",
            task.map_or("shared task", |t| task_name(usize::from(t.0))),
            shutdown
        );
        mps2::fatal("stack overflow")
    }
}

/// The task slot the calibration's jobs use (no task of the ECU has it).
const CALIBRATION_SLOT: usize = cw_bsp::cortex_m::MAX_TASKS - 1;

/// Measures what the measuring costs: 1,000 back-to-back span marks and job marks, before
/// the OS starts (its tick runs already, so the SysTick counts advance).
fn calibrate(port: &CortexMPort<Kernel>) {
    for _ in 0..1000 {
        port.span(span::CALIBRATION, true);
        port.span(span::CALIBRATION, false);
        port.job_started(TaskId(CALIBRATION_SLOT as u8));
        port.job_finished(TaskId(CALIBRATION_SLOT as u8));
    }
    cw_bsp::cortex_m::trace::clear_events();
}

/// The name of task `t` in the configuration.
fn task_name(t: usize) -> &'static str {
    config::OS.tasks().get(t).map_or("?", |c| c.name)
}

/// Prints the LED changes and the task trace (`cw_bsp::cortex_m::trace`) over
/// semihosting, one fact per line, for `cargo xtask qemu --compare` and for reading:
///
/// - `led MS RED YELLOW`: the LED register changed at MS ms;
/// - `task NAME jobs N preempted P max-span US`: per task;
/// - `preempt BY OVER N`: jobs of BY that started on top of a job of OVER;
/// - `isr NAME OVER N`: entries of an ISR while OVER ran (`idle`: the idle loop);
/// - `event US start|end|isr NAME`: the first events of the run, in order (ISR entries
///   only when they interrupt a task);
/// - `schedule ...`: the check that every preemption was by a task of higher priority
///   and every periodic task's longest job ended within its period (`false` if not).
fn report_trace() -> bool {
    use cw_bsp::cortex_m::trace::{self, EventKind, SpanRecord, IDLE_ROW};
    let dropped = mps2::led_changes(|at, bits| {
        cw_bsp::mps2_log!("cw-qemu: led {} {} {}\n", at, bits & 1, (bits >> 1) & 1);
    });
    if dropped > 0 {
        cw_bsp::mps2_log!("cw-qemu: led changes not logged {}\n", dropped);
    }
    let isr_name = |i: usize| config::OS.isrs().get(i).map_or("?", |c| c.name);
    trace::read(|t| {
        // Under `-icount shift=0`: one SysTick count is 40 instructions. The measuring's
        // own cost (a back-to-back pair, calibrated at start) is taken off every span.
        let span_cal = t.spans.get(span::CALIBRATION).copied().unwrap_or_default();
        let job_cal = t
            .tasks
            .get(CALIBRATION_SLOT)
            .map(|r| r.span)
            .unwrap_or_default();
        let instructions = |r: &SpanRecord, cal: &SpanRecord| {
            let mean = |r: &SpanRecord| r.sum * 40 / u64::from(r.count.max(1));
            let scale = |c: u32| (u64::from(c) * 40).saturating_sub(mean(cal));
            (
                mean(r).saturating_sub(mean(cal)),
                scale(r.min),
                scale(r.max),
            )
        };
        cw_bsp::mps2_log!(
            "cw-qemu: instructions below are SysTick counts x 40: exact under -icount shift=0 only\n"
        );
        cw_bsp::mps2_log!(
            "cw-qemu: measuring costs {} instructions per span, {} per job (calibration, taken off below)\n",
            instructions(&span_cal, &SpanRecord::default()).0,
            instructions(&job_cal, &SpanRecord::default()).0
        );
        for (i, r) in t.tasks.iter().enumerate().take(config::OS.tasks().len()) {
            let (mean, min, max) = instructions(&r.span, &job_cal);
            cw_bsp::mps2_log!(
                "cw-qemu: task {} jobs {} preempted {} instructions mean {} min {} max {}\n",
                task_name(i),
                r.jobs,
                r.preempted,
                mean,
                min,
                max
            );
        }
        for (name, r) in span::NAMES.iter().zip(&t.spans) {
            let (mean, min, max) = instructions(r, &span_cal);
            cw_bsp::mps2_log!(
                "cw-qemu: span {}: {} times, instructions mean {} min {} max {}\n",
                name,
                r.count,
                mean,
                min,
                max
            );
        }
        for (by, row) in t.preemptions.iter().enumerate() {
            for (over, &n) in row.iter().enumerate().filter(|(_, &n)| n > 0) {
                cw_bsp::mps2_log!(
                    "cw-qemu: preempt {} {} {}\n",
                    task_name(by),
                    task_name(over),
                    n
                );
            }
        }
        for (isr, row) in t.isr_over.iter().enumerate() {
            for (over, &n) in row.iter().enumerate().filter(|(_, &n)| n > 0) {
                let over = if over == IDLE_ROW {
                    "idle"
                } else {
                    task_name(over)
                };
                cw_bsp::mps2_log!("cw-qemu: isr {} {} {}\n", isr_name(isr), over, n);
            }
        }
        let mut preemptions = 0u32;
        let mut wrong = 0u32;
        for (by, row) in t.preemptions.iter().enumerate() {
            for (over, &n) in row.iter().enumerate().filter(|(_, &n)| n > 0) {
                preemptions = preemptions.saturating_add(u32::from(n));
                let priority = |i: usize| config::OS.tasks().get(i).map_or(0, |c| c.priority);
                if priority(by) <= priority(over) {
                    wrong = wrong.saturating_add(u32::from(n));
                }
            }
        }
        let late = t
            .tasks
            .iter()
            .zip(config::PERIOD_MS)
            .filter(|(r, period)| {
                *period > 0 && r.span.max >= period.saturating_mul(t.counts_per_ms)
            })
            .count();
        cw_bsp::mps2_log!(
            "cw-qemu: schedule {} preemptions, {} not by a higher priority; {} periodic tasks with a job longer than the period\n",
            preemptions,
            wrong,
            late
        );
        for e in t.events.iter().take(t.events_len) {
            let (what, name) = match e.kind {
                EventKind::JobStart(task) => ("start", task_name(usize::from(task))),
                EventKind::JobEnd(task) => ("end", task_name(usize::from(task))),
                EventKind::Isr(isr) => ("isr", isr_name(usize::from(isr))),
            };
            let at_us = u64::from(e.at) * 1000 / u64::from(t.counts_per_ms.max(1));
            cw_bsp::mps2_log!("cw-qemu: event {} {} {}\n", at_us, what, name);
        }
        wrong == 0 && late == 0
    })
}
