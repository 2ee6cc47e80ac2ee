//! The simulation loop: board, ECU and scenario in 1 ms steps of virtual time, the
//! milliseconds where nothing happens but the OS tick passed over at once.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use cw_bsp::chip::flexcan::{ClockSource, FlexcanConfig};
use cw_bsp::host::can::HOST_CAN_CLOCK_HZ;
use cw_bsp::host::{
    BusRecord, HcSr04, HostFlexcan, HostPort, Noise, SimDelay, SimInput, SimPin, SimWatchdog,
    Tester, VirtualBus, VirtualClock,
};
use cw_core::can::CanFrame;
use cw_core::os::TaskId;
use cw_core::sonar::{Echo, SonarConfig};
use cw_core::warning::{Measurement, Thresholds, WarningLevel};

use super::scenario::Scenario;
use crate::board::{
    Board, BoardParts, CanEvents, CanInterrupt, EchoSensor, Leds, ModeInputs, PortDriver,
    PulseCapture, Stalls,
};
use crate::config::{self, Kernel};
use crate::ecu::Ecu;
use embedded_hal::digital::OutputPin;

/// The simulated board the ECU runs on: its drivers' types.
pub struct HostBoard;

impl Board for HostBoard {
    type Can = HostFlexcan;
    type Led = SimPin;
    type Sensor = EchoSensor<SimPin, SimInput, SimDelay, HostSonar>;
    type ModeInput = SimInput;
    type Port = HostPortDriver;
    type Watchdog = SimWatchdog;
    type Faults = Stalls<{ super::scenario::HOST_CAPACITY }>;
}

/// The ECU on the host port and board.
pub type HostEcu = Ecu<HostPort<Kernel>, HostBoard>;

impl CanEvents for HostFlexcan {
    fn take_event(&mut self) -> Option<CanInterrupt> {
        HostFlexcan::take_event(self).map(CanInterrupt::from)
    }
}

/// The ECU's FlexCAN as FlexCAN0 of an S32K144 on an 80 MHz peripheral clock.
const CAN_CONFIG: FlexcanConfig<'static> =
    config::flexcan(ClockSource::PeripheralClock, HOST_CAN_CLOCK_HZ);

/// The simulated Port driver: drives the output pins low and counts its calls.
pub struct HostPortDriver {
    outputs: [SimPin; 3],
    inits: Rc<Cell<u32>>,
}

impl PortDriver for HostPortDriver {
    fn port_init(&mut self) {
        self.inits.set(self.inits.get() + 1);
        for pin in &mut self.outputs {
            let _ = pin.set_low();
        }
    }
}

/// The HC-SR04 as the scenario moves it.
struct SonarState {
    sensor: HcSr04,
    /// The obstacle's true distance now (set from the scenario).
    true_distance_mm: u32,
    /// Trigger-pin history entries already consumed by a capture.
    seen_edges: usize,
    /// Captures answered with no trigger pulse before them.
    untriggered: u32,
    /// When each capture answered with an echo, µs (for the end-to-end latencies).
    echoes_us: Vec<u64>,
}

/// The HC-SR04 on the board's Gpt capture: it answers a capture only for a trigger pulse
/// of at least 10 µs that the firmware drove on the trigger pin since the last capture.
pub struct HostSonar {
    trigger: SimPin,
    state: Rc<RefCell<SonarState>>,
    clock: VirtualClock,
}

impl HostSonar {
    /// The minimum trigger pulse the sensor responds to, µs.
    const MIN_TRIGGER_US: u64 = 10;

    /// Whether a complete trigger pulse of at least 10 µs happened since the last capture.
    fn take_trigger(&self, state: &mut SonarState) -> bool {
        let new = self.trigger.changes_since(state.seen_edges);
        let triggered = new.windows(2).any(
            |w| matches!(w, [(rise, true), (fall, false)] if fall - rise >= Self::MIN_TRIGGER_US),
        );
        state.seen_edges += new.len();
        triggered
    }
}

impl PulseCapture for HostSonar {
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        let mut state = self.state.borrow_mut();
        if !self.take_trigger(&mut state) {
            state.untriggered += 1;
            return None;
        }
        let distance = state.true_distance_mm;
        match state.sensor.measure(distance) {
            Echo::Pulse { width_us } if width_us <= timeout_us => {
                state.echoes_us.push(self.clock.now_us());
                Some(width_us)
            }
            _ => None,
        }
    }
}

/// What the simulation keeps of the board to drive and observe it.
struct BoardView {
    red: SimPin,
    yellow: SimPin,
    trigger: SimPin,
    echo: SimInput,
    ignition: SimInput,
    com_enable: SimInput,
    sonar: Rc<RefCell<SonarState>>,
    port_inits: Rc<Cell<u32>>,
}

/// One row of the trace, every 10 ms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TraceRow {
    /// Virtual time, ms.
    pub time_ms: u64,
    /// The obstacle's true distance, mm.
    pub true_distance_mm: u32,
    /// What the ECU measured.
    pub measured: Measurement,
    /// The level ObstacleDetection decided.
    pub level: WarningLevel,
    /// Red LED lit.
    pub red: bool,
    /// Yellow LED lit.
    pub yellow: bool,
}

impl TraceRow {
    /// The CSV header.
    pub const CSV_HEADER: &'static str =
        "time_ms,true_distance_mm,measured_distance_mm,level,red,yellow,measurement";

    /// The row as CSV; the measured distance is empty when there is none, and the last
    /// column says why (`distance`, `nothing_in_range` or `invalid`).
    pub fn csv(&self) -> String {
        let (measured, kind) = match self.measured {
            Measurement::Distance { distance_mm } => (distance_mm.to_string(), "distance"),
            Measurement::NothingInRange => (String::new(), "nothing_in_range"),
            Measurement::Invalid => (String::new(), "invalid"),
        };
        format!(
            "{},{},{},{:?},{},{},{}",
            self.time_ms,
            self.true_distance_mm,
            measured,
            self.level,
            u8::from(self.red),
            u8::from(self.yellow),
            kind
        )
    }
}

/// Why a simulation could not be set up.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimulationError(pub String);

impl std::fmt::Display for SimulationError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SimulationError {}

/// End-to-end latencies of a run, µs of virtual time (the evaluation's, `cargo xtask
/// eval`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EndToEnd {
    /// For each echo the sensor gave: when the sonar job captured it (the echo's end, as
    /// the capture sees it), and how long until the distance frame that carries it ended
    /// on the bus (an echo whose frame did not leave before the next echo is left out).
    pub echo_to_frame: Vec<(u64, u64)>,
    /// Each threshold crossing and its latency to the LEDs; `None` where the scenario
    /// sends the ECU frames (they may change the thresholds).
    pub crossing_to_led: Option<Vec<Crossing>>,
}

/// The obstacle's true distance crossed a threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crossing {
    /// When, µs (the first millisecond at the new level).
    pub at_us: u64,
    /// The level it entered.
    pub level: WarningLevel,
    /// How long until the LEDs showed that level (0: they already did), `None` if they had
    /// not by the next crossing or the run's end.
    pub latency_us: Option<u64>,
}

/// The ECU, its board, the bus with a PC on it, and the scenario.
pub struct Simulation {
    scenario: Scenario,
    clock: VirtualClock,
    bus: VirtualBus,
    pc: Tester,
    board: BoardView,
    ecu: HostEcu,
    now_ms: u64,
    trace: Vec<TraceRow>,
    frames: Vec<BusRecord>,
    watchdog: SimWatchdog,
    /// The watchdog's reset, µs: the run ended there.
    reset_at_us: Option<u64>,
    /// When `CanIsr` was entered, µs.
    can_isr_entries: Vec<u64>,
}

impl Simulation {
    /// Powers the ECU on at time 0 on a fresh board.
    ///
    /// # Errors
    /// [`SimulationError`] if the ECU's configuration is inconsistent.
    pub fn new(scenario: Scenario, seed: u64) -> Result<Self, SimulationError> {
        let clock = VirtualClock::new();
        let bus = VirtualBus::new(&clock);
        bus.set_tracing(true);
        let can = bus
            .attach_flexcan(&CAN_CONFIG)
            .map_err(|e| SimulationError(format!("the CAN controller's buffers: {e}")))?;
        let pc = bus.attach_tester();
        let sensor = HcSr04::new(SonarConfig::HC_SR04)
            .with_noise(Noise::from(scenario.noise))
            .with_dropout_ppm(scenario.dropout_ppm)
            .with_seed(seed);
        let red = SimPin::new("RedLED", &clock);
        let yellow = SimPin::new("YellowLED", &clock);
        let trigger = SimPin::new("SonarTrigger", &clock);
        let echo = SimInput::new("SonarEcho", false);
        let ignition = SimInput::new("Ignition", true);
        let com_enable = SimInput::new("ComEnable", true);
        let sonar = Rc::new(RefCell::new(SonarState {
            sensor,
            true_distance_mm: scenario.distance_at(0),
            seen_edges: 0,
            untriggered: 0,
            echoes_us: Vec::new(),
        }));
        let port_inits = Rc::new(Cell::new(0));
        let stalls = Stalls::of(&scenario, config::OS.tasks()).map_err(|name| {
            SimulationError(format!(
                "scenario: `stall {}`: no task of that name",
                name.as_str()
            ))
        })?;
        let watchdog = SimWatchdog::new(&clock);
        let parts = BoardParts::<HostBoard> {
            watchdog: watchdog.clone(),
            faults: stalls,
            port: HostPortDriver {
                outputs: [red.clone(), yellow.clone(), trigger.clone()],
                inits: port_inits.clone(),
            },
            can,
            leds: Leds {
                red: red.clone(),
                yellow: yellow.clone(),
            },
            modes: ModeInputs {
                ignition: ignition.clone(),
                com_enable: com_enable.clone(),
            },
            sonar: EchoSensor {
                trigger: trigger.clone(),
                echo: echo.clone(),
                delay: SimDelay::new(&clock),
                capture: HostSonar {
                    trigger: trigger.clone(),
                    state: sonar.clone(),
                    clock: clock.clone(),
                },
            },
        };
        let board = BoardView {
            red,
            yellow,
            trigger,
            echo,
            ignition,
            com_enable,
            sonar,
            port_inits,
        };
        let kernel = config::kernel().map_err(|e| SimulationError(e.describe().to_string()))?;
        let port = HostPort::new(kernel, &clock);
        let ecu = Ecu::new(port, parts, SonarConfig::HC_SR04);
        let mut sim = Self {
            scenario,
            clock,
            bus,
            pc,
            board,
            ecu,
            now_ms: 0,
            trace: Vec::new(),
            frames: Vec::new(),
            watchdog,
            reset_at_us: None,
            can_isr_entries: Vec::new(),
        };
        sim.ecu.init();
        sim.ecu.start_os();
        Ok(sim)
    }

    /// The ECU (for inspection between steps).
    pub fn ecu(&mut self) -> &mut HostEcu {
        &mut self.ecu
    }

    /// Virtual time, ms.
    pub const fn now_ms(&self) -> u64 {
        self.now_ms
    }

    /// The scenario.
    pub const fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The trace so far (one row per 10 ms).
    pub fn trace(&self) -> &[TraceRow] {
        &self.trace
    }

    /// Every frame that completed on the bus so far, in order.
    pub fn frames(&self) -> &[BusRecord] {
        &self.frames
    }

    /// Task starts so far: (task, virtual time in us).
    pub fn task_starts(&self) -> Vec<(TaskId, u64)> {
        self.ecu.port().job_starts().clone()
    }

    /// When `CanIsr` was entered so far, µs of virtual time (the controller's events: a
    /// frame sent, received, an error).
    pub fn can_isr_entries(&self) -> &[u64] {
        &self.can_isr_entries
    }

    /// The red LED pin (with its history).
    pub fn red_led(&self) -> &SimPin {
        &self.board.red
    }

    /// The yellow LED pin (with its history).
    pub fn yellow_led(&self) -> &SimPin {
        &self.board.yellow
    }

    /// The sensor's trigger pin (with its history).
    pub fn sonar_trigger(&self) -> &SimPin {
        &self.board.trigger
    }

    /// The sensor's echo line, which a test may force (a sensor stuck high).
    pub fn sonar_echo_line(&self) -> &SimInput {
        &self.board.echo
    }

    /// `Port_Init` calls so far.
    pub fn port_inits(&self) -> u32 {
        self.board.port_inits.get()
    }

    /// Echo captures the firmware asked for without a trigger pulse before them.
    pub fn untriggered_captures(&self) -> u32 {
        self.board.sonar.borrow().untriggered
    }

    /// The PC sends `frame` now (the view's sender panel); it goes on the bus at the next
    /// step, as a scenario's `frame` line does.
    pub fn send_from_pc(&mut self, frame: &CanFrame) {
        self.pc.send(frame);
    }

    /// The frames completed since the last call (or the start), taken out of the record:
    /// what a live view reads as it goes.
    pub fn take_frames(&mut self) -> Vec<BusRecord> {
        core::mem::take(&mut self.frames)
    }

    /// Lets go of every record kept so far (the trace, the task starts, the pins'
    /// histories, what the PC received), so that a simulation that runs for hours in real
    /// time holds constant memory. Frames not yet taken stay.
    pub fn forget_history(&mut self) {
        self.trace = Vec::new();
        self.can_isr_entries = Vec::new();
        self.ecu.port().forget_job_starts();
        for pin in [&self.board.red, &self.board.yellow] {
            pin.forget_changes(pin.change_count());
        }
        // The sensor reads the trigger's edges since it last looked: only those it has
        // seen go.
        let mut sonar = self.board.sonar.borrow_mut();
        self.board.trigger.forget_changes(sonar.seen_edges);
        sonar.seen_edges = 0;
        sonar.echoes_us = Vec::new();
        drop(sonar);
        drop(self.pc.take_received());
    }

    /// Runs until virtual time `end_ms`.
    ///
    /// Tickless: the milliseconds in which nothing would happen but the OS tick with
    /// nothing due (`Simulation::quiet_ms`) are passed over in one kernel step
    /// (`Os::try_ticks`, which takes them only where each tick's fast path would), and the
    /// next millisecond is stepped whole. The CAN log and the trace are those of a run
    /// stepped every millisecond.
    pub fn run_until_ms(&mut self, end_ms: u64) {
        while self.now_ms < end_ms && self.reset_at_us.is_none() {
            let quiet = self.quiet_ms(end_ms);
            if quiet > 0 && self.ecu.quiet_ticks(quiet) {
                self.now_ms += quiet;
            }
            self.step();
        }
    }

    /// How many of the milliseconds after now have nothing to step but the OS tick with
    /// nothing due: they end before the next millisecond that has a trace row, a CAN
    /// event (a frame's end on the bus), a scenario event (injected errors, the PC's
    /// frames), the watchdog's deadline, or an alarm due, and before the run's last
    /// millisecond. (The inputs the scenario sets every millisecond, the distance, the
    /// mode inputs and the sensor's dropouts, are read only by the tasks, which run only
    /// in stepped milliseconds.)
    fn quiet_ms(&self, end_ms: u64) -> u64 {
        let now = self.now_ms;
        let trace_row = (now / 10 + 1) * 10;
        let bus = self.bus.next_event_us().map(|t| t.div_ceil(1000));
        let watchdog = self.watchdog.deadline_us().map(|t| t.div_ceil(1000));
        let scenario = self
            .scenario
            .can_errors
            .iter()
            .map(|(at, _)| u64::from(*at))
            .chain(self.scenario.frames.iter().map(|(at, _)| u64::from(*at)))
            .filter(|&at| at > now)
            .min();
        let alarm = now.saturating_add(self.ecu.ticks_to_expiry());
        let next = [bus, watchdog, scenario]
            .into_iter()
            .flatten()
            .fold(end_ms.min(trace_row).min(alarm), u64::min);
        next.saturating_sub(now + 1)
    }

    /// When the watchdog reset the ECU, µs (the run ended there), if it did.
    pub const fn reset_at_us(&self) -> Option<u64> {
        self.reset_at_us
    }

    /// The watchdog (its triggers, its last one).
    pub const fn watchdog(&self) -> &SimWatchdog {
        &self.watchdog
    }

    /// Runs the whole scenario.
    pub fn run(&mut self) {
        let end = self.scenario.duration_ms();
        self.run_until_ms(end);
    }

    /// One millisecond: the bus catches up, scenario events happen, the timer interrupt
    /// fires, and every 10 ms a trace row is taken.
    fn step(&mut self) {
        self.now_ms += 1;
        let now_us = self.now_ms * 1000;
        // Deliver every CAN event up to now, each at its own time.
        while let Some(t) = self.bus.next_event_us().filter(|t| *t <= now_us) {
            let _ = self.clock.advance_to_us(t);
            self.bus.run_until(t);
            self.deliver_can_events();
        }
        let _ = self.clock.advance_to_us(now_us);
        self.bus.run_until_now();
        self.deliver_can_events();
        if let Some(at_us) = self.watchdog.reset_due() {
            // The watchdog resets the ECU before this tick: every output de-energised,
            // nothing of the ECU runs from here on (the run ends; a board would start
            // again from power-on).
            self.reset_at_us = Some(at_us);
            let _ = self.board.red.set_low();
            let _ = self.board.yellow.set_low();
            let _ = self.board.trigger.set_low();
            return;
        }
        let t = self.now_ms;
        for (_, count) in self
            .scenario
            .can_errors
            .iter()
            .filter(|(at, _)| u64::from(*at) == t)
        {
            self.ecu.com_stack().can.inject_tx_errors(*count);
        }
        for (_, frame) in self
            .scenario
            .frames
            .iter()
            .filter(|(at, _)| u64::from(*at) == t)
        {
            self.pc.send(frame);
        }
        // The mode inputs: ignition off from the shutdown time on, communication
        // disabled inside the no-communication windows; ModeManager samples them.
        self.board.ignition.set_level(self.scenario.ignition_on(t));
        self.board
            .com_enable
            .set_level(!self.scenario.in_no_communication(t));
        {
            let mut sonar = self.board.sonar.borrow_mut();
            sonar.true_distance_mm = self.scenario.distance_at(t);
            sonar.sensor.set_forced_dropout(self.scenario.in_dropout(t));
        }
        self.ecu.port().raise(config::os::SYS_TICK_ISR);
        self.take_interrupts();
        self.bus.drain_trace_into(&mut self.frames);
        if t % 10 == 0 {
            self.trace.push(TraceRow {
                time_ms: t,
                true_distance_mm: self.board.sonar.borrow().true_distance_mm,
                measured: self.ecu.measurement(),
                level: self.ecu.level(),
                red: self.board.red.is_high_now(),
                yellow: self.board.yellow.is_high_now(),
            });
        }
    }

    /// The run's end-to-end latencies ([`EndToEnd`]), in virtual time. The crossings are
    /// of the paper's thresholds, [`Thresholds::PAPER`]: `None` where the scenario sends
    /// the ECU frames (they may set other thresholds).
    pub fn end_to_end(&self) -> EndToEnd {
        let ecu_frames: Vec<u64> = self
            .frames
            .iter()
            .filter(|r| r.frame.can_id() == config::canif::DISTANCE_FRAME_ID)
            .map(|r| r.time_us)
            .collect();
        let echoes = self.board.sonar.borrow().echoes_us.clone();
        let echo_to_frame = echoes
            .iter()
            .enumerate()
            .filter_map(|(i, &at)| {
                let next_echo = echoes.get(i + 1).copied().unwrap_or(u64::MAX);
                let k = ecu_frames.partition_point(|&f| f < at);
                let frame = *ecu_frames.get(k)?;
                (frame < next_echo).then_some((at, frame - at))
            })
            .collect();
        let crossing_to_led = self
            .scenario
            .frames
            .is_empty()
            .then(|| self.crossings_to_leds());
        EndToEnd {
            echo_to_frame,
            crossing_to_led,
        }
    }

    /// Each time the scenario's true distance crosses a threshold of [`Thresholds::PAPER`]
    /// (from one millisecond to the next, up to now), and how long after it, and before the
    /// next crossing, the LEDs first showed the level it entered (red alone, yellow alone,
    /// both dark).
    fn crossings_to_leds(&self) -> Vec<Crossing> {
        let thresholds = Thresholds::PAPER;
        let level = |t: u64| thresholds.level_for_distance(self.scenario.distance_at(t));
        let (red, yellow) = (self.board.red.history(), self.board.yellow.history());
        // The LEDs' levels as they changed, in time order: (µs, red, yellow).
        let mut leds: Vec<(u64, bool, bool)> = Vec::with_capacity(red.len() + yellow.len());
        let (mut r, mut y, mut i, mut j) = (false, false, 0, 0);
        while i < red.len() || j < yellow.len() {
            let next_red = red.get(i).map_or(u64::MAX, |c| c.0);
            let next_yellow = yellow.get(j).map_or(u64::MAX, |c| c.0);
            let at = next_red.min(next_yellow);
            if next_red == at {
                r = red.get(i).is_some_and(|c| c.1);
                i += 1;
            }
            if next_yellow == at {
                y = yellow.get(j).is_some_and(|c| c.1);
                j += 1;
            }
            leds.push((at, r, y));
        }
        let shows = |l: WarningLevel, r: bool, y: bool| match l {
            WarningLevel::Red => r && !y,
            WarningLevel::Yellow => y && !r,
            WarningLevel::Off => !r && !y,
            WarningLevel::Fault => false,
        };
        let mut crossings: Vec<(u64, WarningLevel)> = Vec::new();
        let mut before = level(0);
        for t in 1..=self.now_ms {
            let now = level(t);
            if now != before {
                crossings.push((t * 1000, now));
            }
            before = now;
        }
        crossings
            .iter()
            .enumerate()
            .map(|(i, &(at_us, now))| {
                // The LEDs' state at the crossing, then each change after it, up to the next
                // crossing (a level that the next crossing superseded is never shown).
                let until = crossings.get(i + 1).map_or(u64::MAX, |c| c.0);
                let k = leds.partition_point(|c| c.0 <= at_us);
                let state_then = k.checked_sub(1).and_then(|k| leds.get(k));
                let shown = if state_then.is_some_and(|&(_, r, y)| shows(now, r, y)) {
                    Some(0)
                } else {
                    leds.get(k..)
                        .unwrap_or(&[])
                        .iter()
                        .take_while(|c| c.0 < until)
                        .find(|&&(_, r, y)| shows(now, r, y))
                        .map(|c| c.0 - at_us)
                };
                Crossing {
                    at_us,
                    level: now,
                    latency_us: shown,
                }
            })
            .collect()
    }

    /// Mode requests the ECU's RTE queue had no room for.
    pub fn mode_requests_refused(&self) -> u32 {
        self.ecu.mode_requests_dropped()
    }

    /// The CAN controller's new events raise its interrupt.
    fn deliver_can_events(&mut self) {
        if self.ecu.com_stack().can.has_events() {
            self.ecu.port().raise(config::os::CAN_ISR);
            self.take_interrupts();
        }
        self.bus.drain_trace_into(&mut self.frames);
    }

    /// The interrupt controller takes every pending request the kernel's mask admits,
    /// highest priority first, and runs its ISR.
    fn take_interrupts(&mut self) {
        loop {
            let next = self.ecu.port().take_interrupt(config::OS.isrs());
            match next {
                Some(config::os::SYS_TICK_ISR) => self.ecu.tick(),
                Some(config::os::CAN_ISR) => {
                    self.can_isr_entries.push(self.clock.now_us());
                    self.ecu.can_isr();
                }
                _ => return,
            }
        }
    }
}
