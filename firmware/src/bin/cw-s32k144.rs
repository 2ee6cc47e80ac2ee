//! The collision-warning ECU on NXP's S32K144EVB: the same ECU as every image
//! (configuration, SWCs, RTE, BSW, OS and port) on the board's FlexCAN0, RGB LED, HC-SR04
//! (GPIO trigger, FTM0 input capture) and watchdog, logging over RTT.
//!
//! Build and check: `cargo xtask s32k144`; flash and run with a probe: `cargo xtask
//! s32k144 --flash` (the book: `docs/src/nxp-boards.md`).
#![no_std]
#![no_main]

use cw_bsp::port::Slot;
use cw_bsp::s32k144evb::{self as evb, EvbWatchdog, Led};
use cw_core::sonar::SonarConfig;
use cw_firmware::board::{BoardParts, Leds, ModeInputs, NoFaults, TiedOn};
use cw_firmware::config;
use cw_firmware::ecu::Ecu;
use cw_firmware::s32k144evb::{sonar, EvbApp, EvbPortDriver, CAN_CONFIG};

static APP: Slot<EvbApp> = Slot::new();

#[cortex_m_rt::entry]
fn main() -> ! {
    // First: the watchdog resets the chip 8 ms after reset unless reconfigured.
    evb::start_up();
    let Ok(kernel) = config::kernel() else {
        evb::fatal("the OS configuration is inconsistent")
    };
    let Ok(can) = evb::flexcan0(&CAN_CONFIG) else {
        evb::fatal("the CAN configuration does not fit FlexCAN0's buffers")
    };
    defmt::println!("cw-s32k144: collision-warning ECU on the S32K144EVB");
    let parts = BoardParts {
        watchdog: EvbWatchdog::new(),
        faults: NoFaults,
        port: EvbPortDriver,
        can,
        leds: Leds {
            red: Led::RED,
            yellow: Led::YELLOW,
        },
        sonar: sonar(),
        modes: ModeInputs {
            ignition: TiedOn,
            com_enable: TiedOn,
        },
    };
    let ecu = Ecu::new(cw_bsp::cortex_m::port(kernel), parts, SonarConfig::HC_SR04);
    let Some(app) = APP.init(EvbApp { ecu }) else {
        evb::fatal("started twice")
    };
    app.ecu.init();
    let app: &'static EvbApp = app;
    cw_bsp::cortex_m::start(app, app.ecu.port())
}
