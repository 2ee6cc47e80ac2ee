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
use cw_firmware::mps2::{Mps2App, Mps2Board, Mps2PortDriver, ScenarioEcho, FIGURE7};

static APP: Slot<Mps2App> = Slot::new();

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(kernel) = config::kernel() else {
        mps2::fatal("the OS configuration is inconsistent")
    };
    let capture = ScenarioEcho::new(SonarConfig::HC_SR04, FIGURE7);
    let end_ms = capture.duration_ms();
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
    let Some(app) = APP.init(Mps2App { ecu, end_ms }) else {
        mps2::fatal("started twice")
    };
    app.ecu.init();
    mps2::log("cw-qemu: collision-warning ECU on mps2-an386, scenario Figure 7\n");
    cw_bsp::cortex_m::start(app, mps2::fatal)
}
