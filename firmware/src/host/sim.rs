//! The simulation loop: board, ECU and scenario in 1 ms steps of virtual time.

use cw_bsp::host::{
    BusRecord, CanEvent, HcSr04, HostCan, HostCanConfig, Noise, SimDelay, SimInput, SimPin, Tester,
    VirtualBus, VirtualClock,
};
use cw_core::can::Hrh;
use cw_core::ecum::BswMRequest;
use cw_core::os::{InterruptControl, TaskId, VirtualInterrupts};
use cw_core::sonar::{Echo, SonarConfig};
use cw_core::warning::{Measurement, WarningLevel};

use super::scenario::{NoiseSpec, Scenario};
use crate::board::{Board, DioIn, DioOut, PulseCapture};
use crate::config;
use crate::ecu::{CanInterrupt, Ecu};
use embedded_hal::digital::OutputPin;

/// The simulated board the ECU runs on.
pub struct HostBoard {
    clock: VirtualClock,
    can: HostCan,
    red: SimPin,
    yellow: SimPin,
    trigger: SimPin,
    echo: SimInput,
    delay: SimDelay,
    sonar: HostSonar,
    /// `Port_Init` calls so far (exactly one expected).
    port_inits: u32,
    /// Task starts: (task, virtual time in us).
    task_starts: Vec<(TaskId, u64)>,
    /// The interrupt controller: pending requests and the kernel's mask.
    irq: VirtualInterrupts,
    /// CAN controller events waiting for `CanIsr`.
    can_pending: Vec<CanInterrupt>,
}

/// The HC-SR04 on the board's Gpt capture: it answers a capture only for a trigger pulse
/// of at least 10 µs that the firmware drove on the trigger pin since the last capture.
pub struct HostSonar {
    trigger: SimPin,
    sensor: HcSr04,
    /// The obstacle's true distance now (set from the scenario).
    true_distance_mm: u32,
    /// Trigger-pin history entries already consumed by a capture.
    seen_edges: usize,
    /// Captures answered with no trigger pulse before them.
    untriggered: u32,
}

impl HostSonar {
    /// The minimum trigger pulse the sensor responds to, µs.
    const MIN_TRIGGER_US: u64 = 10;

    /// Whether a complete trigger pulse of at least 10 µs happened since the last capture.
    fn take_trigger(&mut self) -> bool {
        let new = self.trigger.changes_since(self.seen_edges);
        let triggered = new.windows(2).any(
            |w| matches!(w, [(rise, true), (fall, false)] if fall - rise >= Self::MIN_TRIGGER_US),
        );
        self.seen_edges += new.len();
        triggered
    }
}

impl PulseCapture for HostSonar {
    fn high_time_us(&mut self, timeout_us: u32) -> Option<u32> {
        if !self.take_trigger() {
            self.untriggered += 1;
            return None;
        }
        match self.sensor.measure(self.true_distance_mm) {
            Echo::Pulse { width_us } if width_us <= timeout_us => Some(width_us),
            _ => None,
        }
    }
}

impl Board for HostBoard {
    type Can = HostCan;
    type Out = SimPin;
    type In = SimInput;
    type Delay = SimDelay;
    type Capture = HostSonar;
    type Irq = VirtualInterrupts;

    fn port_init(&mut self) {
        self.port_inits += 1;
        for pin in [&mut self.red, &mut self.yellow, &mut self.trigger] {
            let _ = pin.set_low();
        }
    }

    fn can(&mut self) -> &mut HostCan {
        &mut self.can
    }

    fn dio_out(&mut self, channel: DioOut) -> &mut SimPin {
        match channel {
            DioOut::RedLed => &mut self.red,
            DioOut::YellowLed => &mut self.yellow,
            DioOut::SonarTrigger => &mut self.trigger,
        }
    }

    fn dio_in(&mut self, channel: DioIn) -> &mut SimInput {
        match channel {
            DioIn::SonarEcho => &mut self.echo,
        }
    }

    fn gpt_delay(&mut self) -> &mut SimDelay {
        &mut self.delay
    }

    fn gpt_capture(&mut self) -> &mut HostSonar {
        &mut self.sonar
    }

    fn irq(&mut self) -> &mut VirtualInterrupts {
        &mut self.irq
    }

    fn now_ms(&self) -> u64 {
        self.clock.now_ms()
    }

    fn task_started(&mut self, task: TaskId) {
        self.task_starts.push((task, self.clock.now_us()));
    }
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

/// The ECU, its board, the bus with a PC on it, and the scenario.
pub struct Simulation {
    scenario: Scenario,
    clock: VirtualClock,
    bus: VirtualBus,
    pc: Tester,
    board: HostBoard,
    ecu: Ecu,
    now_ms: u64,
    trace: Vec<TraceRow>,
    frames: Vec<BusRecord>,
    mode_requests_refused: u32,
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
        // The ECU's controller accepts the threshold frame into HRH 0 and, like a
        // controller with an open filter, everything else too, so CanIf's own checks
        // (unknown id, DLC) are exercised.
        let can = bus.attach(
            &HostCanConfig::new(&[(config::THRESHOLD_FRAME_ID, Hrh(0))]).with_catch_all(Hrh(0)),
        );
        let pc = bus.attach_tester();
        let noise = match scenario.noise {
            NoiseSpec::Off => Noise::None,
            NoiseSpec::Uniform(amplitude_mm) => Noise::Uniform { amplitude_mm },
            NoiseSpec::Gaussian(sigma_mm) => Noise::Gaussian { sigma_mm },
        };
        let sensor = HcSr04::new(SonarConfig::HC_SR04)
            .with_noise(noise)
            .with_dropout_ppm(scenario.dropout_ppm)
            .with_seed(seed);
        let trigger = SimPin::new("SonarTrigger", &clock);
        let board = HostBoard {
            red: SimPin::new("RedLED", &clock),
            yellow: SimPin::new("YellowLED", &clock),
            echo: SimInput::new("SonarEcho", false),
            delay: SimDelay::new(&clock),
            sonar: HostSonar {
                trigger: trigger.clone(),
                sensor,
                true_distance_mm: scenario.distance_at(0),
                seen_edges: 0,
                untriggered: 0,
            },
            trigger,
            clock: clock.clone(),
            can,
            port_inits: 0,
            task_starts: Vec::new(),
            irq: VirtualInterrupts::new(),
            can_pending: Vec::new(),
        };
        let ecu = Ecu::new(SonarConfig::HC_SR04)
            .map_err(|e| SimulationError(e.describe().to_string()))?;
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
            mode_requests_refused: 0,
        };
        sim.ecu.start(&mut sim.board);
        Ok(sim)
    }

    /// The ECU.
    pub const fn ecu(&self) -> &Ecu {
        &self.ecu
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
    pub fn task_starts(&self) -> &[(TaskId, u64)] {
        &self.board.task_starts
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
    pub const fn port_inits(&self) -> u32 {
        self.board.port_inits
    }

    /// Echo captures the firmware asked for without a trigger pulse before them.
    pub const fn untriggered_captures(&self) -> u32 {
        self.board.sonar.untriggered
    }

    /// Runs until virtual time `end_ms`.
    pub fn run_until_ms(&mut self, end_ms: u64) {
        while self.now_ms < end_ms {
            self.step();
        }
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
        let t = self.now_ms;
        for (_, count) in self.scenario.can_errors.iter().filter(|(at, _)| *at == t) {
            self.board.can.inject_tx_errors(*count);
        }
        for (_, frame) in self.scenario.frames.iter().filter(|(at, _)| *at == t) {
            self.pc.send(frame);
        }
        let windows = self.scenario.no_communication.clone();
        for (start, len) in windows {
            if start == t {
                self.mode_request(BswMRequest::CommunicationOff);
            } else if start + len == t {
                self.mode_request(BswMRequest::CommunicationOn);
            }
        }
        if self.scenario.shutdown_at_ms == Some(t) {
            self.mode_request(BswMRequest::EcuPostRun);
        }
        self.board.sonar.true_distance_mm = self.scenario.distance_at(t);
        self.board
            .sonar
            .sensor
            .set_forced_dropout(self.scenario.in_dropout(t));
        self.board.irq.raise(config::SYSTICK_ISR);
        self.take_interrupts();
        self.frames.extend(self.bus.take_trace());
        if t % 10 == 0 {
            self.trace.push(TraceRow {
                time_ms: t,
                true_distance_mm: self.board.sonar.true_distance_mm,
                measured: self.ecu.measurement(),
                level: self.ecu.level(),
                red: self.board.red.is_high_now(),
                yellow: self.board.yellow.is_high_now(),
            });
        }
    }

    /// Hands a mode request to the ECU; a full request queue is counted.
    fn mode_request(&mut self, request: BswMRequest) {
        if self.ecu.request_mode(request).is_err() {
            self.mode_requests_refused += 1;
        }
    }

    /// Mode requests the ECU refused because its queue was full.
    pub const fn mode_requests_refused(&self) -> u32 {
        self.mode_requests_refused
    }

    /// The CAN controller's new events raise its interrupt.
    fn deliver_can_events(&mut self) {
        for timed in self.board.can.take_events() {
            self.board.can_pending.push(match timed.event {
                CanEvent::TxConfirmation { pdu } => CanInterrupt::TxConfirmation(pdu),
                CanEvent::Received { hrh, frame } => CanInterrupt::Received(hrh, frame),
                CanEvent::BusOff => CanInterrupt::BusOff,
            });
        }
        if !self.board.can_pending.is_empty() {
            self.board.irq.raise(config::CAN_ISR);
            self.take_interrupts();
        }
        self.frames.extend(self.bus.take_trace());
    }

    /// The interrupt controller takes every pending request the kernel's mask admits,
    /// highest priority first, and runs its ISR.
    fn take_interrupts(&mut self) {
        while self.board.irq.pending() != 0 {
            let mask = self.ecu.os().interrupt_mask();
            self.board.irq.apply_mask(mask);
            let Some(isr) = self.board.irq.take_next(config::OS.isrs()) else {
                return;
            };
            match isr {
                config::SYSTICK_ISR => self.ecu.tick(&mut self.board),
                config::CAN_ISR => {
                    // Drained in place, so the buffer's allocation is kept for the next one.
                    let mut events = std::mem::take(&mut self.board.can_pending);
                    self.ecu.can_isr(&mut self.board, events.drain(..));
                    self.board.can_pending = events;
                }
                _ => {}
            }
        }
    }
}
