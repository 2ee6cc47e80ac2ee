//! The collision-warning ECU on NXP's S32K144EVB: the same ECU as every image
//! (configuration, SWCs, RTE, BSW, OS and port) on the board's FlexCAN0, RGB LED, HC-SR04
//! (GPIO trigger, FTM0 input capture) and watchdog, logging over RTT. With feature
//! `s32k144evb-uart` the sensor is a UART ranging module on LPUART0 instead.
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
use cw_firmware::s32k144evb::{EvbApp, EvbPortDriver, CAN_CONFIG};

#[cfg(not(feature = "s32k144evb-uart"))]
use cw_firmware::s32k144evb::{sonar as sensor, EvbBoard as Board};
#[cfg(feature = "s32k144evb-uart")]
use cw_firmware::s32k144evb::{uart_sensor as sensor, EvbUartBoard as Board};

static APP: Slot<EvbApp<Board>> = Slot::new();

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
    defmt::println!(
        "cw-s32k144: collision-warning ECU on the S32K144EVB; sensor: {=str}",
        if cfg!(feature = "s32k144evb-uart") {
            "UART ranging module on LPUART0 (PTB0)"
        } else {
            "HC-SR04 (trigger PTC1, echo PTC0 on FTM0)"
        }
    );
    let parts: BoardParts<Board> = BoardParts {
        watchdog: EvbWatchdog::new(),
        faults: NoFaults,
        port: EvbPortDriver,
        can,
        leds: Leds {
            red: Led::RED,
            yellow: Led::YELLOW,
        },
        sonar: sensor(),
        modes: ModeInputs {
            ignition: TiedOn,
            com_enable: TiedOn,
        },
    };
    let ecu = Ecu::new(cw_bsp::cortex_m::port(kernel), parts, SonarConfig::HC_SR04);
    let app = EvbApp {
        ecu,
        uart_sensor: cfg!(feature = "s32k144evb-uart"),
    };
    let Some(app) = APP.init(app) else {
        evb::fatal("started twice")
    };
    app.ecu.init();
    let app: &'static EvbApp<Board> = app;
    cw_bsp::cortex_m::start(app, app.ecu.port())
}
