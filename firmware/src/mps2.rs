//! The ECU on QEMU's mps2-an386 (Cortex-M4): the board's drivers named for [`Board`], and
//! the ECU's entry points for the Cortex-M port (`cw_bsp::cortex_m::App`).
//!
//! The sensor is deterministic: QEMU cannot time an HC-SR04 echo, so the Gpt capture
//! returns the echo width the scenario's obstacle distance gives at the current OS time,
//! converted by the same `SonarConfig::distance_to_echo_us` as the host simulation's
//! sensor model.

use cw_bsp::cortex_m::{App, CortexMPort};
use cw_bsp::mps2::{self, CoreDelay, Led, SlcanCan, SlcanEvent, Unconnected};
use cw_core::os::TaskId;
use cw_core::sonar::SonarConfig;

use crate::board::{Board, CanEvents, CanInterrupt, PortDriver, PulseCapture};
use crate::config::{self, Kernel};
use crate::ecu::Ecu;

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
        mps2::start_tick(config::OS.isrs()[config::SYSTICK_ISR.0 as usize].priority);
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
        cw_bsp::mps2_log!(
            "cw-qemu: end at {} ms; kernel errors {}, port errors {}; task stack used {} of {} bytes\n",
            mps2::now_ms(),
            hooks.errors,
            hooks.port_errors,
            cw_bsp::cortex_m::basic_stack_use(),
            cw_bsp::cortex_m::BASIC_STACK_WORDS * 4
        );
        mps2::exit(hooks.errors == 0 && hooks.port_errors == 0);
    }

    fn tick(&self) {
        self.ecu.port().advance_ms();
        self.ecu.tick();
    }

    fn irq(&self, _line: u16) {
        self.ecu.can_isr();
    }
}
