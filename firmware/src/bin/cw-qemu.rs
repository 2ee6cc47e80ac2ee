//! The collision-warning ECU as a bare-metal image for QEMU's mps2-an386 (Cortex-M4).
//!
//! Build and run: `cargo xtask qemu` (README, "The ECU on an emulated Cortex-M4").
#![no_std]
#![no_main]

use cw_bsp::cortex_m::CortexMPort;
use cw_bsp::mps2::{self, CoreDelay, Led, SlcanCan, Unconnected};
use cw_bsp::port::Slot;
use cw_core::sonar::SonarConfig;
use cw_firmware::board::{BoardParts, Leds, SonarIo};
use cw_firmware::config;
use cw_firmware::ecu::Ecu;
use cw_firmware::mps2::{
    load_scenario, ImageScenario, Mps2App, Mps2Board, Mps2PortDriver, ScenarioEcho,
};

static APP: Slot<Mps2App> = Slot::new();
static SCENARIO: Slot<ImageScenario> = Slot::new();

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(kernel) = config::kernel() else {
        mps2::fatal("the OS configuration is inconsistent")
    };
    mps2::log("cw-qemu: collision-warning ECU on mps2-an386\n");
    let Some(scenario) = SCENARIO.init(load_scenario()) else {
        mps2::fatal("started twice")
    };
    let scenario: &'static ImageScenario = scenario;
    let capture = ScenarioEcho::new(SonarConfig::HC_SR04, scenario);
    let end_ms = u32::try_from(scenario.duration_ms()).unwrap_or(u32::MAX);
    let parts = BoardParts::<Mps2Board> {
        port: Mps2PortDriver,
        can: SlcanCan::uart0(),
        leds: Leds {
            red: Led::RED,
            yellow: Led::YELLOW,
        },
        sonar: SonarIo {
            trigger: Unconnected,
            echo: Unconnected,
            delay: CoreDelay,
            capture,
        },
    };
    let ecu = Ecu::new(CortexMPort::new(kernel), parts, SonarConfig::HC_SR04);
    let Some(app) = APP.init(Mps2App {
        ecu,
        end_ms,
        scenario,
    }) else {
        mps2::fatal("started twice")
    };
    app.ecu.init();
    cw_bsp::cortex_m::start(app, mps2::fatal)
}
