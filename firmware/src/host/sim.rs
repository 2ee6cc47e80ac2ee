//! The simulation loop: board, ECU and scenario in 1 ms steps of virtual time.

use cw_bsp::host::{
    BusRecord, CanEvent, HcSr04, HostCan, HostCanConfig, Noise, SimPin, Tester, VirtualBus,
    VirtualClock,
};
use cw_core::can::Hrh;
use cw_core::os::TaskId;
use cw_core::sonar::{Echo, SonarConfig};
use cw_core::warning::{Measurement, WarningLevel};

use super::scenario::{NoiseSpec, Scenario};
use crate::board::Board;
use crate::config;
use crate::ecu::{CanInterrupt, Ecu};
use crate::swc::LedColor;

/// The simulated board the ECU runs on.
pub struct HostBoard {
    clock: VirtualClock,
    can: HostCan,
    red: SimPin,
    yellow: SimPin,
    sensor: HcSr04,
    /// The obstacle's true distance now (set from the scenario).
    true_distance_mm: u32,
    /// Task starts: (task, virtual time in us).
    task_starts: Vec<(TaskId, u64)>,
}

impl Board for HostBoard {
    type Can = HostCan;
    type Led = SimPin;

    fn can(&mut self) -> &mut HostCan {
        &mut self.can
    }

    fn led(&mut self, color: LedColor) -> &mut SimPin {
        match color {
            LedColor::Red => &mut self.red,
            LedColor::Yellow => &mut self.yellow,
        }
    }

    fn sonar_echo(&mut self) -> Echo {
        self.sensor.measure(self.true_distance_mm)
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
        let board = HostBoard {
            red: SimPin::new("RedLED", &clock),
            yellow: SimPin::new("YellowLED", &clock),
            clock: clock.clone(),
            can,
            sensor,
            true_distance_mm: scenario.distance_at(0),
            task_starts: Vec::new(),
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
        self.board.true_distance_mm = self.scenario.distance_at(t);
        self.board
            .sensor
            .set_forced_dropout(self.scenario.in_dropout(t));
        self.ecu.tick(&mut self.board);
        self.frames.extend(self.bus.take_trace());
        if t % 10 == 0 {
            self.trace.push(TraceRow {
                time_ms: t,
                true_distance_mm: self.board.true_distance_mm,
                measured: self.ecu.measurement(),
                level: self.ecu.level(),
                red: self.board.red.is_high_now(),
                yellow: self.board.yellow.is_high_now(),
            });
        }
    }

    fn deliver_can_events(&mut self) {
        for timed in self.board.can.take_events() {
            let event = match timed.event {
                CanEvent::TxConfirmation { pdu } => CanInterrupt::TxConfirmation(pdu),
                CanEvent::Received { hrh, frame } => CanInterrupt::Received(hrh, frame),
                CanEvent::BusOff => CanInterrupt::BusOff,
            };
            self.ecu.can_event(&mut self.board, event);
        }
        self.frames.extend(self.bus.take_trace());
    }
}
