//! The collision-warning ECU as a bare-metal image for QEMU's mps2-an386 (Cortex-M4).
//!
//! Build and run: `cargo xtask qemu` (the book: `docs/src/cortex-m4.md`). With the feature
//! `extended-tasks`, the periodic tasks have the paper's structure (extended tasks waiting
//! for their alarms' events, each on its own stack): `cargo xtask eval` measures both.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicBool, AtomicU32};

use cw_bsp::mps2::{self, FatalEnd, Led};
use cw_bsp::port::{Slot, TaskLocal};
use cw_core::sonar::SonarConfig;
use cw_firmware::board::{BoardParts, Leds, ModeInputs, Stalls};
use cw_firmware::config;
use cw_firmware::ecu::Ecu;
use cw_firmware::mps2::{
    load, ImageScenario, ModeLine, Mps2App, Mps2Board, Mps2PortDriver, Mps2Sensor, ScenarioInput,
};
use cw_firmware::stack_probe::Stack;

static APP: Slot<Mps2App> = Slot::new();
static SCENARIO: Slot<ImageScenario> = Slot::new();
static PROBES: Slot<Stack> = Slot::new();

/// The periodic tasks' own stacks where they are extended tasks (the paper's structure,
/// feature `extended-tasks`): each keeps its context while it waits for its alarm's event.
#[cfg(feature = "extended-tasks")]
static EXTENDED_STACKS: [cw_bsp::cortex_m::TaskStack<512>; 4] =
    [const { cw_bsp::cortex_m::TaskStack::new() }; 4];

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(kernel) = config::kernel() else {
        mps2::fatal("the OS configuration is inconsistent")
    };
    // A measuring image: a fatal fault ends the QEMU run with a failure status.
    mps2::set_fatal_end(FatalEnd::Exit);
    defmt::println!("cw-qemu: collision-warning ECU on mps2-an386");
    let start = load();
    let (uart_sensor, seed) = (start.uart_sensor, start.seed);
    let Some(scenario) = SCENARIO.init(start.scenario) else {
        mps2::fatal("started twice")
    };
    let scenario: &'static ImageScenario = scenario;
    let end_ms = start.duration_ms.unwrap_or_else(|| scenario.duration_ms());
    let Ok(stalls) = Stalls::of(scenario, config::OS.tasks()) else {
        mps2::fatal("the scenario's `stall` names no task of the OS configuration")
    };
    let parts = BoardParts::<Mps2Board> {
        watchdog: mps2::CmsdkWatchdog::new(),
        faults: stalls,
        port: Mps2PortDriver,
        can: mps2::slcan_uart0(),
        leds: Leds {
            red: Led::RED,
            yellow: Led::YELLOW,
        },
        sonar: Mps2Sensor::new(uart_sensor, scenario, seed),
        modes: ModeInputs {
            ignition: ScenarioInput::new(scenario, ModeLine::Ignition),
            com_enable: ScenarioInput::new(scenario, ModeLine::ComEnable),
        },
    };
    let ecu = Ecu::new(cw_bsp::cortex_m::port(kernel), parts, SonarConfig::HC_SR04);
    let probes = probes();
    let Some(app) = APP.init(Mps2App {
        ecu,
        end_ms,
        scenario,
        uart_sensor,
        job_records: start.job_records,
        records_written: AtomicU32::new(0),
        records_lost: AtomicU32::new(0),
        taking_records: AtomicBool::new(false),
        records_in_flight: AtomicU32::new(0),
        probes: TaskLocal::new(probes),
    }) else {
        mps2::fatal("started twice")
    };
    app.ecu.init();
    let app: &'static Mps2App = app;
    #[cfg(feature = "extended-tasks")]
    for (task, stack) in [
        config::os::OS_LED_TASK,
        config::os::OS_BSW_SERVICE_TASK,
        config::os::OS_OBSTACLE_DETECTION_TASK,
        config::os::OS_SONAR_TASK,
    ]
    .into_iter()
    .zip(&EXTENDED_STACKS)
    {
        cw_bsp::cortex_m::set_task_stack(app.ecu.port(), task, stack);
    }
    cw_bsp::cortex_m::start(app, app.ecu.port())
}

/// The layer probes' stack (the paper's Figure 10), measured before the OS starts, in its
/// static. Never inlined: the stack is built in this function's frame, which is gone
/// before `main`'s stack pointer becomes the main stack's top at the OS's start.
#[inline(never)]
fn probes() -> Option<&'static mut Stack> {
    PROBES.init(Stack::started().ok()?)
}
