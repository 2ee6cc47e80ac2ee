//! The measuring image on mps2-an386 (`cw-qemu`): scenarios read over semihosting and
//! played, the task trace and the end-of-run report; the board's drivers named for
//! [`Board`], and the ECU's entry points for the Cortex-M port (`cw_bsp::cortex_m::App`).
//!
//! The sensor is one of two ([`Mps2Sensor`]):
//! - by default the scenario's: QEMU cannot time an HC-SR04 echo, so the Gpt capture
//!   returns the echo width the scenario's obstacle distance gives at the current OS
//!   time through the host simulation's own sensor model (`cw_core::sonar::model`: the
//!   scenario's `noise` and `dropout-rate` drawn from the same generator with the same
//!   seed, `--seed N`, default 1), and no echo in the scenario's `dropout` windows;
//! - with `--sensor uart` on the semihosting command line, a UART ranging module
//!   (A02YYUW protocol, `cw_core::sonar::uart`) on UART1, QEMU's second `-serial`: what
//!   a live run's test program sends there is what the ECU measures. The scenario's
//!   movements and dropouts are then not played; its length and bus events are.
//!
//! The scenario is a `cw_core::scenario` file, read over semihosting at start
//! ([`load`]), by default the paper's Figure 7 compiled in. The image plays its
//! movements (`hold`, `ramp`), `dropout`, `can-errors` (the SLCAN controller's next
//! attempts fail, with the same error counter and bus times as the host's simulated bus)
//! and `frame` (a tester's frame reaches the controller in the ms after its time, as it
//! does on the host's bus), and `no-communication` and `shutdown` through the mode inputs
//! ([`ScenarioInput`]) that the ModeManager SWC samples, as on the host board. A
//! `shutdown` ends the run at `ShutdownOS` (the port's [`App::shut_down`]): interrupts
//! stay off, the report follows. It plays every command the host simulation does.
//!
//! For the evaluation (`cargo xtask eval`, the paper's Table 1), `--duration-ms N` runs
//! the scenario for N ms instead of its own length (its last position held), and
//! `--job-records PATH` has the idle loop write every job's start and end to the host file
//! PATH as it goes (`cw_bsp::cortex_m::trace::job_record`: the task's slot, start or end,
//! and the SysTick count in one little-endian word). The idle loop takes the records off
//! the trace's ring in every run, written or not, so that the job marks take the same
//! path in every run as in their calibration.

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use cw_bsp::cortex_m::{now_ms, App, CortexMPort};
use cw_bsp::mps2::semihosting::HostFile;
use cw_bsp::mps2::{self, CoreDelay, Led, SensorUart, SlcanCan, Unconnected};
use cw_bsp::port::preempt::PortFault;
use cw_bsp::port::{Port, TaskLocal};
use cw_core::os::TaskId;
use cw_core::scenario::Scenario;
use cw_core::sonar::model::{EchoModel, Noise};
use cw_core::sonar::{Echo, SonarConfig};
use cw_core::warning::Measurement;

use super::{
    board_irq, isr_priority, report_supervision, shutdown_report, start_os_with_devices,
    Mps2PortDriver,
};
use crate::board::{Board, DistanceSensor, EchoSensor, PulseCapture, SerialSensor, Stalls};
use crate::config::{self, Kernel};
use crate::ecu::{span, Ecu};
use crate::schedulability;
use crate::stack_probe::Stack;

/// The mps2-an386 board's drivers.
pub struct Mps2Board;

impl Board for Mps2Board {
    type Can = SlcanCan;
    type Led = Led;
    type Sensor = Mps2Sensor;
    type ModeInput = ScenarioInput;
    type Port = Mps2PortDriver;
    type Watchdog = mps2::CmsdkWatchdog;
    type Faults = Stalls<IMAGE_CAPACITY>;
}

/// The image's sensor.
pub enum Mps2Sensor {
    /// The scenario's obstacle, as an HC-SR04's echo (no trigger or echo line: the
    /// capture computes the width).
    Scenario(EchoSensor<Unconnected, Unconnected, CoreDelay, ScenarioEcho>),
    /// A UART ranging module on UART1.
    Uart(SerialSensor<SensorUart>),
}

impl Mps2Sensor {
    /// The sensor a run asked for: the module on UART1 if `uart`, else the scenario's
    /// obstacle, its noise and dropouts drawn with generator seed `seed`.
    pub fn new(uart: bool, scenario: &'static ImageScenario, seed: u64) -> Self {
        if uart {
            Self::Uart(SerialSensor::new(
                SensorUart::uart1(),
                config::SENSOR_SILENT_AFTER_SAMPLES,
            ))
        } else {
            Self::Scenario(EchoSensor {
                trigger: Unconnected,
                echo: Unconnected,
                delay: CoreDelay,
                capture: ScenarioEcho::new(SonarConfig::HC_SR04, scenario, seed),
            })
        }
    }
}

impl DistanceSensor for Mps2Sensor {
    fn sample(&mut self, config: &SonarConfig) -> Measurement {
        match self {
            Self::Scenario(sensor) => sensor.sample(config),
            Self::Uart(sensor) => sensor.sample(config),
        }
    }
}

/// The ECU on this board.
pub type Mps2Ecu = Ecu<CortexMPort<Kernel>, Mps2Board>;

/// Lines of each kind a scenario on the image holds.
pub const IMAGE_CAPACITY: usize = 8;

/// A scenario on the image.
pub type ImageScenario = Scenario<IMAGE_CAPACITY>;

/// The paper's Figure 7, compiled in: the scenario when none is given.
pub const FIGURE7: &str = include_str!("../../../scenarios/figure7.txt");

/// The longest scenario file the image reads, bytes.
pub const SCENARIO_FILE_MAX: usize = 1024;

/// Why the image cannot play a scenario.
enum Refused<'a> {
    /// The file could not be read.
    File(cw_bsp::mps2::semihosting::HostFileError),
    /// The text is not UTF-8.
    NotText,
    /// A malformed line.
    Parse(cw_core::scenario::ScenarioError<'a>),
}

impl core::fmt::Display for Refused<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::File(e) => write!(f, "{e}"),
            Self::NotText => write!(f, "it is not UTF-8 text"),
            Self::Parse(e) => write!(f, "{e}"),
        }
    }
}

/// What the semihosting command line asks for (QEMU's `-semihosting-config
/// ...,arg=cw-qemu,arg=--scenario,arg=PATH,arg=--sensor,arg=uart`).
pub struct Start {
    /// The scenario: its movements, faults, bus events and length.
    pub scenario: ImageScenario,
    /// The sensor is the UART ranging module on UART1 (`--sensor uart`).
    pub uart_sensor: bool,
    /// The seed of the scenario sensor's noise and dropouts (`--seed N`, default 1, as
    /// the host simulation's).
    pub seed: u64,
    /// How long the run lasts (`--duration-ms N`), else the scenario's own length.
    pub duration_ms: Option<u64>,
    /// The host file the job records go to (`--job-records PATH`).
    pub job_records: Option<HostFile>,
}

/// The run the command line asks for: the scenario file named by `--scenario PATH`, read
/// from the host (at most [`SCENARIO_FILE_MAX`] bytes), or Figure 7; the sensor named
/// by `--sensor scenario|uart` (default `scenario`); the sensor model's seed by `--seed N`
/// (default 1). The scenario's name goes to the log; a file that cannot be read or
/// parsed, an unknown sensor or a bad seed is a fatal error naming the file, the line and
/// the fault.
/// Never inlined: its buffers leave the main stack before the OS starts.
#[inline(never)]
pub fn load() -> Start {
    let mut line = [0u8; 256];
    let line = cw_bsp::mps2::semihosting::command_line(&mut line).unwrap_or("");
    let option = |name: &str| {
        let mut words = line.split_whitespace();
        words.find(|w| *w == name)?;
        words.next()
    };
    let uart_sensor = match option("--sensor") {
        None | Some("scenario") => false,
        Some("uart") => true,
        Some(_) => {
            mps2::leds_safe();
            defmt::println!("FATAL: --sensor takes `scenario` or `uart`");
            mps2::exit(false)
        }
    };
    let seed = match option("--seed").map(str::parse::<u64>) {
        None => 1,
        Some(Ok(seed)) => seed,
        Some(Err(_)) => {
            mps2::leds_safe();
            defmt::println!("FATAL: --seed takes a whole number");
            mps2::exit(false)
        }
    };
    let duration_ms = match option("--duration-ms").map(str::parse::<u64>) {
        None => None,
        Some(Ok(ms)) if ms > 0 => Some(ms),
        Some(_) => {
            mps2::leds_safe();
            defmt::println!("FATAL: --duration-ms takes a whole number of ms above 0");
            mps2::exit(false)
        }
    };
    let job_records = match option("--job-records") {
        None => None,
        Some(path) => match HostFile::create(path) {
            Ok(file) => {
                defmt::println!("cw-qemu: job records to {}", path);
                Some(file)
            }
            Err(e) => {
                mps2::leds_safe();
                defmt::println!("FATAL: job records {}: {}", path, defmt::Display2Format(&e));
                mps2::exit(false)
            }
        },
    };
    let mut text = [0u8; SCENARIO_FILE_MAX];
    let (name, scenario) = match option("--scenario") {
        None => ("scenarios/figure7.txt (compiled in)", parse(FIGURE7)),
        Some(path) => (
            path,
            cw_bsp::mps2::semihosting::read_file(path, &mut text)
                .map_err(Refused::File)
                .and_then(|len| {
                    text.get(..len)
                        .and_then(|t| core::str::from_utf8(t).ok())
                        .ok_or(Refused::NotText)
                })
                .and_then(parse),
        ),
    };
    match scenario {
        Ok(s) => {
            defmt::println!(
                "cw-qemu: scenario {}: {} movements, {} dropouts, {} CAN error bursts, {} tester frames, {} ms",
                name,
                s.segments.len(),
                s.dropouts.len(),
                s.can_errors.len(),
                s.frames.len(),
                s.duration_ms()
            );
            if uart_sensor {
                defmt::println!("cw-qemu: sensor: the UART ranging module on UART1 (the scenario's movements and dropouts are not played)");
            }
            Start {
                scenario: s,
                uart_sensor,
                seed,
                duration_ms,
                job_records,
            }
        }
        Err(e) => {
            mps2::leds_safe();
            defmt::println!("FATAL: scenario {}: {}", name, defmt::Display2Format(&e));
            mps2::exit(false)
        }
    }
}

/// Reads and checks a scenario for the image.
fn parse(text: &str) -> Result<ImageScenario, Refused<'_>> {
    ImageScenario::parse(text).map_err(Refused::Parse)
}

/// A mode input the scenario drives (the board has no such lines): its level at the
/// current OS ms.
pub struct ScenarioInput {
    scenario: &'static ImageScenario,
    line: ModeLine,
}

/// Which mode input a [`ScenarioInput`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeLine {
    /// The ignition: on until the scenario's `shutdown`.
    Ignition,
    /// Communication enable: off inside the scenario's `no-communication` windows.
    ComEnable,
}

impl ScenarioInput {
    /// The input `line` as `scenario` drives it.
    pub const fn new(scenario: &'static ImageScenario, line: ModeLine) -> Self {
        Self { scenario, line }
    }
}

impl embedded_hal::digital::ErrorType for ScenarioInput {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::InputPin for ScenarioInput {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        let now = now_ms();
        Ok(match self.line {
            ModeLine::Ignition => self.scenario.ignition_on(now),
            ModeLine::ComEnable => !self.scenario.in_no_communication(now),
        })
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        self.is_high().map(|high| !high)
    }
}

/// The echo a scenario's obstacle gives, on the Gpt capture: the host simulation's sensor
/// model ([`EchoModel`]) with the scenario's noise and random dropouts, drawn from the
/// same generator with the same seed, so the image measures what the host does.
pub struct ScenarioEcho {
    model: EchoModel,
    scenario: &'static ImageScenario,
}

impl ScenarioEcho {
    /// The sensor `sensor` seeing the obstacle move as `scenario` says, its generator
    /// seeded with `seed`.
    pub fn new(sensor: SonarConfig, scenario: &'static ImageScenario, seed: u64) -> Self {
        Self {
            model: EchoModel::new(sensor, seed)
                .with_noise(Noise::from(scenario.noise))
                .with_dropout_ppm(scenario.dropout_ppm),
            scenario,
        }
    }
}

impl PulseCapture for ScenarioEcho {
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        let now = now_ms();
        // A `dropout` window is an unplugged sensor: no echo, nothing drawn (as the
        // host's forced dropout).
        if self.scenario.in_dropout(now) {
            return None;
        }
        match self.model.echo(self.scenario.distance_at(now)) {
            Echo::Missing => None,
            Echo::Pulse { width_us } => (width_us <= timeout_us).then_some(width_us),
        }
    }
}

/// The ECU and how long its scenario lasts.
pub struct Mps2App {
    /// The ECU.
    pub ecu: Mps2Ecu,
    /// The run ends (QEMU exits) at this OS time, ms.
    pub end_ms: u64,
    /// The scenario's bus events.
    pub scenario: &'static ImageScenario,
    /// The sensor is the UART ranging module.
    pub uart_sensor: bool,
    /// Where the job records go (`--job-records`), else nowhere.
    pub job_records: Option<HostFile>,
    /// Job records written to [`Mps2App::job_records`].
    pub records_written: AtomicU32,
    /// Job records the host failed to write.
    pub records_lost: AtomicU32,
    /// A context is taking job records off the ring (the ring has one reader: a task that
    /// ends the run while the idle loop was taking them finds this set).
    pub taking_records: AtomicBool,
    /// Job records taken off the ring and not yet written.
    pub records_in_flight: AtomicU32,
    /// The communication stack the layer probes run on (the paper's Figure 10), in a
    /// static: built on the main stack before the OS (`Stack::started`), measured once
    /// before the OS starts.
    pub probes: TaskLocal<Option<&'static mut Stack>>,
}

impl App for Mps2App {
    fn start_os(&self) {
        // Interrupts stay off until StartOS's own kernel call ends: an interrupt before it
        // would be an ISR the kernel cannot accept yet (a port error), and the calibration
        // may take longer than a tick when QEMU runs in real time.
        cortex_m::interrupt::disable();
        // The measurements before the OS run on SysTick free-running (longer than a tick
        // with interrupts off), then the OS tick starts.
        mps2::start_measuring_clock();
        calibrate(self.ecu.port());
        measure_flexcan(self.ecu.port());
        let _ = self.probes.with(|probes| {
            if let Some(stack) = probes.as_deref_mut() {
                measure_stack(self.ecu.port(), stack);
            }
        });
        mps2::start_tick(isr_priority(config::os::SYS_TICK_ISR));
        cw_bsp::cortex_m::trace::set_isr_spans(span::ISR_SPANS);
        start_os_with_devices(&self.ecu, self.uart_sensor);
    }

    fn run_job(&self, task: TaskId) {
        self.ecu.run_job(task);
    }

    fn idle(&self) {
        let _ = self.take_job_records();
        report_supervision("cw-qemu", &self.ecu);
        if now_ms() < self.end_ms {
            return;
        }
        // The scenario's end, with the OS running (a `shutdown` line ends the run at
        // ShutdownOS, earlier).
        self.end_run(true)
    }

    fn tick(&self) {
        // The scenario's bus events, before the OS tick, as the host simulation orders
        // them: errors injected at their ms; a tester's frame, which takes a fraction of
        // a ms on the bus, received in the ms after it was sent (the controller's
        // bus-fault model: cw-bsp's `bus-faults`, which this module's feature brings).
        mps2::on_tick();
        {
            let now = u32::try_from(now_ms()).unwrap_or(u32::MAX);
            for &(_, count) in self.scenario.can_errors.iter().filter(|(at, _)| *at == now) {
                mps2::inject_tx_errors(count);
            }
            for &(_, frame) in self
                .scenario
                .frames
                .iter()
                .filter(|(at, _)| at.checked_add(1) == Some(now))
            {
                mps2::put_frame_on_bus(frame);
            }
        }
        self.ecu.tick();
    }

    fn irq(&self, line: u16) {
        board_irq(&self.ecu, line);
    }

    fn report(&self, fault: &PortFault) {
        report_supervision("cw-qemu", &self.ecu);
        if *fault == PortFault::Nmi && mps2::watchdog_expired() {
            // The watchdog's reset ends the run without the end-of-run report: the LED
            // changes so far go to the log now.
            report_leds();
        }
        mps2::report(fault);
    }

    fn halt(&self) -> ! {
        mps2::halt()
    }

    fn shut_down(&self) -> ! {
        let ok = shutdown_report("cw-qemu", &self.ecu);
        self.end_run(ok)
    }
}

impl Mps2App {
    /// Takes the job records off the trace's ring ([`cw_bsp::cortex_m::trace::take_job_record`])
    /// and writes them to the host file, if the run names one, 16 at a time: in the idle
    /// loop, without an interrupt lock (the ring's producer preempts it freely), and at
    /// the run's end. A semihosting call is one instruction of the run's virtual time.
    /// The ring has one reader at a time: `false` where another context was taking them
    /// (a task that ends the run while the idle loop was in here), nothing done.
    #[inline(never)]
    fn take_job_records(&self) -> bool {
        use cw_bsp::cortex_m::trace::take_job_record;
        if self.taking_records.swap(true, Ordering::Acquire) {
            return false;
        }
        let mut bytes = [0u8; 64];
        loop {
            let mut len = 0;
            for chunk in bytes.chunks_exact_mut(4) {
                let Some(word) = take_job_record() else { break };
                chunk.copy_from_slice(&word.to_le_bytes());
                len += 4;
            }
            let Some(taken) = bytes.get(..len).filter(|b| !b.is_empty()) else {
                break;
            };
            let count = (len / 4) as u32;
            self.records_in_flight.store(count, Ordering::Relaxed);
            match &self.job_records {
                Some(file) if file.write(taken).is_ok() => {
                    self.records_written.fetch_add(count, Ordering::Relaxed);
                }
                Some(_) => {
                    self.records_lost.fetch_add(count, Ordering::Relaxed);
                }
                None => {}
            }
            self.records_in_flight.store(0, Ordering::Relaxed);
        }
        self.taking_records.store(false, Ordering::Release);
        true
    }

    /// The job records' report, where the run writes them: the periodic tasks (slot,
    /// name, period), the time base, and what the record holds and lost.
    fn report_job_records(&self) {
        if !self.take_job_records() {
            // The run ends in a task that preempted the idle loop while it took records
            // off the ring: those it held, and those still on the ring, are not written.
            let held = self.records_in_flight.load(Ordering::Relaxed);
            let left = cw_bsp::cortex_m::trace::job_records_waiting();
            self.records_lost
                .fetch_add(held.saturating_add(left), Ordering::Relaxed);
        }
        if self.job_records.is_none() {
            return;
        }
        let counts_per_ms = cw_bsp::cortex_m::trace::read(|t| t.counts_per_ms);
        defmt::println!(
            "cw-qemu: job records time base {} counts per ms",
            counts_per_ms
        );
        for (slot, &period) in config::PERIOD_MS.iter().enumerate() {
            if period > 0 {
                defmt::println!(
                    "cw-qemu: job records periodic {} {} {} ms",
                    slot,
                    task_name(slot),
                    period
                );
            }
        }
        let ring = cw_bsp::cortex_m::trace::job_records_stats();
        defmt::println!(
            "cw-qemu: job records {} dropped, {} written, {} not written",
            ring.overruns,
            self.records_written.load(Ordering::Relaxed),
            self.records_lost.load(Ordering::Relaxed)
        );
    }

    /// The end-of-run report over semihosting, then QEMU's exit: success if `ok`, the
    /// schedule held and no kernel or port error was counted.
    fn end_run(&self, ok: bool) -> ! {
        let hooks = self.ecu.hooks();
        let task_stack = cw_bsp::cortex_m::basic_stack_use();
        let main_stack = cw_bsp::cortex_m::main_stack_use();
        let schedule_ok = report_trace();
        self.report_job_records();
        let link = mps2::slcan_stats();
        defmt::println!(
            "cw-qemu: slcan received {} frames, {} commands, {} malformed lines; {} overruns, {} replies dropped",
            link.rx_frames,
            link.rx_commands,
            link.rx_malformed,
            link.rx_overruns,
            link.replies_dropped
        );
        defmt::println!(
            "cw-qemu: bus {} tester frames received, {} failed attempts, {} bus-offs",
            link.bus_frames,
            link.tx_errors,
            link.bus_offs
        );
        if self.uart_sensor {
            let uart = mps2::sensor_uart_stats();
            let counts = self.ecu.with_sensor(|sensor| match sensor {
                Mps2Sensor::Uart(s) => s.ranger.counts(),
                Mps2Sensor::Scenario(_) => Default::default(),
            });
            let c = counts.unwrap_or_default();
            defmt::println!(
                "cw-qemu: sensor received {} bytes: {} frames, {} bad checksums, {} in the blind zone, {} stray bytes; {} overruns, {} silent samples",
                uart.received,
                c.frames,
                c.bad_checksums,
                c.blind,
                c.stray_bytes,
                uart.overruns,
                c.silent_samples
            );
        }
        defmt::println!(
            "cw-qemu: end at {} ms; kernel errors {}, port errors {}; task stack used {} of {} bytes, main stack (ISRs) {} bytes",
            now_ms(),
            hooks.errors,
            hooks.port_errors,
            task_stack,
            (cw_bsp::cortex_m::BASIC_STACK_WORDS - cw_bsp::cortex_m::GUARD_WORDS) * 4,
            main_stack
        );
        if config::EXTENDED_TASKS {
            // The periodic tasks' own stacks (the paper's structure).
            for (slot, task) in (0u8..).zip(config::OS.tasks()) {
                if let Some(used) = cw_bsp::cortex_m::task_stack_use(self.ecu.port(), TaskId(slot))
                {
                    defmt::println!(
                        "cw-qemu: extended task {=str}: own stack used {} bytes",
                        task.name,
                        used
                    );
                }
            }
        }
        mps2::exit(ok && schedule_ok && hooks.errors == 0 && hooks.port_errors == 0);
    }
}

/// The task slot the calibration's jobs use (no task of the ECU has it).
const CALIBRATION_SLOT: usize = cw_bsp::cortex_m::MAX_TASKS - 1;

/// How many times the measurements before the OS starts repeat each path: the figures
/// are exact to about an instruction each time, and the repetitions run after `Wdg_Init`
/// with interrupts off, so they must end well within the watchdog's first expiry (25 ms
/// after its trigger). At 32 ns an instruction the FlexCAN driver's loop takes about 7 ms
/// and the calibration about 4; the OS's first tick comes about 12 ms after the reset
/// (QEMU's log of executed instructions, 2026-11-27).
const REPEATS: u16 = 200;

/// How many times the calibration measures each kind of mark: a mark runs the same
/// instructions every time, so the mean of 50 is its cost to a sixteenth of a count.
const CALIBRATION_REPEATS: u16 = 50;

/// Measures what the measuring costs, [`CALIBRATION_REPEATS`] times each, before the OS
/// starts (on SysTick free-running), and gives the trace the costs it takes off every
/// span and job (`cw_bsp::cortex_m::trace::MarkCosts`): an empty span's and an empty
/// job's length (what their own marks leave inside them), then each kind of mark's whole
/// cost, as the length of an empty span around it less an empty span's. The trace's
/// event list is filled first, as it is a few ms into every run, so that the job and ISR
/// marks take the path they take in the run (an event counted, not kept).
#[inline(never)]
fn calibrate(port: &CortexMPort<Kernel>) {
    use cw_bsp::cortex_m::trace::{self, MarkCosts, SpanRecord};
    let slot = TaskId(CALIBRATION_SLOT as u8);
    let (outer, inner) = (span::CALIBRATION, span::CALIBRATION_INNER);
    for _ in 0..trace::EVENTS {
        port.job_started(slot);
        port.job_finished(slot);
    }
    let mean = |r: SpanRecord| {
        let per = r.sum.checked_div(u64::from(r.count)).unwrap_or(0);
        u32::try_from(per).unwrap_or(u32::MAX)
    };
    // The mean length of `outer` over the repetitions of `marks`.
    let measure = |marks: &dyn Fn()| {
        for _ in 0..CALIBRATION_REPEATS {
            marks();
        }
        mean(trace::take_span(outer))
    };
    let span_inside = measure(&|| {
        port.span(outer, true);
        port.span(outer, false);
    });
    let around = |marks: &dyn Fn()| measure(marks).saturating_sub(span_inside);
    let span_start = around(&|| {
        port.span(outer, true);
        port.span(inner, true);
        port.span(outer, false);
        port.span(inner, false);
    });
    let span_end = around(&|| {
        port.span(inner, true);
        port.span(outer, true);
        port.span(inner, false);
        port.span(outer, false);
    });
    let job_start = around(&|| {
        port.span(outer, true);
        port.job_started(slot);
        port.span(outer, false);
        port.job_finished(slot);
    });
    let job_end = around(&|| {
        port.job_started(slot);
        port.span(outer, true);
        port.job_finished(slot);
        port.span(outer, false);
    });
    // Inside a job, as the ISRs that interrupt a task are entered.
    port.job_started(slot);
    let isr_entered = around(&|| {
        port.span(outer, true);
        port.isr_entered(config::os::CAN_ISR);
        port.span(outer, false);
    });
    port.job_finished(slot);
    let _ = trace::take_jobs(slot.0);
    for _ in 0..CALIBRATION_REPEATS {
        port.job_started(slot);
        port.job_finished(slot);
    }
    let job_inside = mean(trace::take_jobs(slot.0));
    trace::calibrated(MarkCosts {
        span_start,
        span_end,
        job_start,
        job_end,
        isr_entered,
        span_inside,
        job_inside,
    });
}

/// Counts the FlexCAN driver's own paths, [`REPEATS`] times each, before the OS starts: the
/// ECU's buffer layout (`config::CAN_FILTERS`, `config::CAN_TX_BUFFERS`) on FlexCAN's
/// register map in RAM (`mps2::flexcan_ram`: QEMU has no FlexCAN). Between the driver's
/// calls, this function does what the module would: it marks the written frame sent
/// (code `INACTIVE` and its flag), then puts a received frame into the first receive
/// buffer (code `FULL`, identifier, data and its flag).
#[inline(never)]
fn measure_flexcan(port: &CortexMPort<Kernel>) {
    use cw_bsp::chip::flexcan::regs::interfaces::Writeable;
    use cw_bsp::chip::flexcan::regs::MB_CS;
    use cw_bsp::chip::flexcan::{ClockSource, Flexcan};
    use cw_core::can::{CanDriver, CanFrame, ControllerMode, Hth};
    // The S32K144EVB's FlexCAN0: the paper's 8 MHz oscillator clock.
    let config = config::flexcan(ClockSource::Oscillator, 8_000_000);
    let Some(ram) = mps2::flexcan_ram::take() else {
        return;
    };
    let Ok(mut can) = Flexcan::new(ram, &config) else {
        return;
    };
    // All-zero registers read as a module on the bus: the start is reached at once.
    let _ = can.set_controller_mode(ControllerMode::Started);
    let tx_mb = 1 + config::CAN_FILTERS.len();
    let Some(frame) = CanFrame::from_parts(
        config::canif::THRESHOLD_CONFIG_ID,
        &[1, 2, 3, 4, 5, 6, 7, 8],
    ) else {
        return;
    };
    for pdu in 0..REPEATS {
        // (Opaque to the compiler, as a frame the ECU sends: nothing of the write is
        // computed once for the whole loop.)
        let frame = core::hint::black_box(frame);
        port.span(span::FLEXCAN_WRITE, true);
        let written = can.write(Hth(0), pdu, &frame);
        port.span(span::FLEXCAN_WRITE, false);
        let regs = can.registers();
        regs.mb_cs(tx_mb).write(MB_CS::CODE::TxInactive);
        regs.iflag1().set(1 << tx_mb);
        port.span(span::FLEXCAN_TX_CONFIRMATION, true);
        let confirmed = can.take_event();
        port.span(span::FLEXCAN_TX_CONFIRMATION, false);
        let regs = can.registers();
        regs.mb_id(1).set(u32::from(pdu & 0x7FF) << 18);
        regs.mb_data(1, 0).set(u32::from(pdu));
        regs.mb_cs(1).write(MB_CS::CODE::RxFull + MB_CS::DLC.val(8));
        regs.iflag1().set(1 << 1);
        port.span(span::FLEXCAN_RX, true);
        let received = can.take_event();
        port.span(span::FLEXCAN_RX, false);
        if written.is_err() || confirmed.is_none() || received.is_none() {
            defmt::println!("cw-qemu: the FlexCAN measurement went wrong at {}", pdu);
            return;
        }
    }
}

/// The task set for the response-time analysis ([`schedulability`]) with this run's
/// longest jobs and ISRs, net of the marks, in instructions: one line per task and ISR,
/// `rta NAME slot S released-by R priority P raises-to X period T deadline D wcet C`
/// (`S` the task's slot, 255 for an ISR; `R` `tick` for a task its alarm activates, the
/// name of the task whose job activates it, `event` for an ISR). `cargo xtask eval`
/// analyses it. Out of line, after the trace's report.
#[inline(never)]
fn report_schedulability(measured: &schedulability::Measured) {
    defmt::println!("cw-qemu: rta unit instructions, {} per ms", measured.per_ms);
    for (i, l) in schedulability::loads(measured).iter().enumerate() {
        let Some((name, task)) = schedulability::item(i) else {
            continue;
        };
        let released_by = match task {
            None => "event",
            Some(task) => schedulability::RELEASED_BY
                .iter()
                .find(|(t, _)| *t == task)
                .map_or("tick", |&(_, by)| task_name(usize::from(by.0))),
        };
        defmt::println!(
            "cw-qemu: rta {} slot {} released-by {} priority {} raises-to {} period {} deadline {} wcet {}",
            name,
            task.map_or(u8::MAX, |t| t.0),
            released_by,
            l.priority,
            l.raises_to,
            l.period,
            l.deadline,
            l.wcet
        );
    }
}

/// Calls of each stack probe measured: each probe's path is the same on every call (its
/// input varies only in the distance's value), and twenty keep the nine probes within
/// about 2 ms of virtual time with interrupts off, before the watchdog's first expiry.
const STACK_REPEATS: u32 = 20;

/// Counts each probe of the communication stack's layers (the paper's Figure 10,
/// [`crate::stack_probe`]), [`STACK_REPEATS`] times each, before the OS starts, and prints
/// `stack probe NAME: N times, instructions mean M min A max B` per probe: the same code
/// callgrind counts on x86-64. The probes' stack is the image's static one
/// ([`Mps2App::probes`]): the task stack, where the start runs, has no room for it.
#[inline(never)]
fn measure_stack(port: &CortexMPort<Kernel>, stack: &mut Stack) {
    use crate::stack_probe::Probe;
    use cw_bsp::cortex_m::trace;
    use cw_bsp::icount;
    let inside = trace::read(|t| t.costs.span_inside);
    let mut sink = 0u64;
    for probe in Probe::ALL {
        let _ = trace::take_span(span::STACK_PROBE);
        for i in 0..STACK_REPEATS {
            sink ^= stack.call(probe, i, |start| port.span(span::STACK_PROBE, start));
        }
        let r = trace::take_span(span::STACK_PROBE);
        let own = r.sum.saturating_sub(u64::from(inside) * u64::from(r.count));
        let scale = |c: u32| icount::instructions(u64::from(c.saturating_sub(inside)));
        defmt::println!(
            "cw-qemu: stack probe {}: {} times, instructions mean {} min {} max {}",
            probe.name(),
            r.count,
            icount::mean_instructions(own, r.count),
            scale(r.min),
            scale(r.max)
        );
    }
    core::hint::black_box(sink);
}

/// The name of task `t` in the configuration.
fn task_name(t: usize) -> &'static str {
    config::OS.tasks().get(t).map_or("?", |c| c.name)
}

/// Prints the LED register's changes so far: `led MS RED YELLOW` lines.
fn report_leds() {
    let dropped = mps2::led_changes(|at, bits| {
        defmt::println!("cw-qemu: led {} {} {}", at, bits & 1, (bits >> 1) & 1);
    });
    if dropped > 0 {
        defmt::println!("cw-qemu: led changes not logged {}", dropped);
    }
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
    use cw_bsp::icount;
    report_leds();
    let isr_name = |i: usize| config::OS.isrs().get(i).map_or("?", |c| c.name);
    let mut measured = None;
    let ok = trace::read(|t| {
        // Under the runs' `-icount` (`cw_bsp::icount`): a SysTick count is 40 ns, an
        // instruction 32 ns. The trace took every mark's cost off every span and job
        // open around it; what a span's or job's own marks leave inside it (calibrated at
        // start) is taken off here.
        let costs = t.costs;
        let instructions = |r: &SpanRecord, inside: u32| {
            // (The mean to the nearest instruction; a single span, min or max, to about one.)
            let own = r.sum.saturating_sub(u64::from(inside) * u64::from(r.count));
            let scale = |c: u32| icount::instructions(u64::from(c.saturating_sub(inside)));
            (
                icount::mean_instructions(own, r.count),
                scale(r.min),
                scale(r.max),
            )
        };
        let cost = |c: u32| icount::mean_instructions(u64::from(c), 1);
        defmt::println!(
            "cw-qemu: instructions below are SysTick counts x {}/{}: exact under -icount {} only",
            icount::NS_PER_SYSTICK_COUNT,
            icount::NS_PER_INSTRUCTION,
            icount::VIRTUAL
        );
        defmt::println!(
            "cw-qemu: measuring costs {} instructions per span, {} per job (calibration, taken off below)",
            cost(costs.span_inside),
            cost(costs.job_inside)
        );
        defmt::println!(
            "cw-qemu: marks seen from a span around them (calibration, taken off every span and job they fall in): span start {} end {}, job start {} end {}, ISR entry {}",
            cost(costs.span_start),
            cost(costs.span_end),
            cost(costs.job_start),
            cost(costs.job_end),
            cost(costs.isr_entered)
        );
        let mut task_wcet = [0u64; 6];
        for (i, r) in t.tasks.iter().enumerate().take(config::OS.tasks().len()) {
            let (mean, min, max) = instructions(&r.span, costs.job_inside);
            let (own_mean, _, own_max) = instructions(&r.own, costs.job_inside);
            if let Some(wcet) = task_wcet.get_mut(i) {
                *wcet = own_max;
            }
            defmt::println!(
                "cw-qemu: task {} jobs {} preempted {} instructions mean {} min {} max {}, own mean {} max {}",
                task_name(i),
                r.jobs,
                r.preempted,
                mean,
                min,
                max,
                own_mean,
                own_max
            );
        }
        let span_max = |id: usize| {
            t.spans
                .get(id)
                .map_or(0, |r| instructions(r, costs.span_inside).2)
        };
        measured = Some(schedulability::Measured {
            per_ms: 1_000_000 / icount::NS_PER_INSTRUCTION,
            task_wcet,
            tick_wcet: span_max(span::TICK_ALARMS_DUE).max(span_max(span::TICK_NOTHING_DUE)),
            can_isr_wcet: span_max(span::CAN_ISR),
        });
        let flexcan = span::FLEXCAN_NAMES
            .iter()
            .chain(&span::MORE_NAMES)
            .filter_map(|&(id, name)| t.spans.get(id).map(|r| (name, r)));
        for (name, r) in span::NAMES.iter().copied().zip(&t.spans).chain(flexcan) {
            let (mean, min, max) = instructions(r, costs.span_inside);
            defmt::println!(
                "cw-qemu: span {}: {} times, instructions mean {} min {} max {}",
                name,
                r.count,
                mean,
                min,
                max
            );
        }
        for (by, row) in t.preemptions.iter().enumerate() {
            for (over, &n) in row.iter().enumerate().filter(|(_, &n)| n > 0) {
                defmt::println!(
                    "cw-qemu: preempt {} {} {}",
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
                defmt::println!("cw-qemu: isr {} {} {}", isr_name(isr), over, n);
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
                *period > 0
                    && r.span.max
                        >= period
                            .saturating_mul(t.counts_per_ms)
                            .saturating_mul(trace::PER_COUNT)
            })
            .count();
        defmt::println!(
            "cw-qemu: schedule {} preemptions, {} not by a higher priority; {} periodic tasks with a job longer than the period",
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
            defmt::println!("cw-qemu: event {} {} {}", at_us, what, name);
        }
        wrong == 0 && late == 0
    });
    // Out of the trace's lock and its closure's frame: the analysis's own frames are
    // deep for the task stack the report runs on.
    if let Some(measured) = measured {
        report_schedulability(&measured);
    }
    ok
}
