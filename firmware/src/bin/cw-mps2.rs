//! The collision-warning ECU as it would be flashed, on QEMU's mps2-an386 (Cortex-M4): the
//! same ECU as `cw-qemu` (configuration, SWCs, RTE, BSW, OS and port), with the ranging
//! module on UART1 as its sensor and the CAN controller on UART0 (SLCAN), and without
//! what only measures or replays: no scenario reader, no task trace or spans, no
//! end-of-run report. It runs until the OS shuts down.
//!
//! Build and run live: `cargo xtask qemu --flash` (the book: `docs/src/cortex-m4.md`, "The production image").
#![no_std]
#![no_main]

use cw_bsp::mps2::{self, Led, SensorUart};
use cw_bsp::port::Slot;
use cw_core::sonar::SonarConfig;
use cw_firmware::board::{BoardParts, Leds, ModeInputs, NoFaults, SerialSensor};
use cw_firmware::config;
use cw_firmware::ecu::Ecu;
use cw_firmware::mps2::{Mps2FlashApp, Mps2PortDriver, TiedOn};

static APP: Slot<Mps2FlashApp> = Slot::new();

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(kernel) = config::kernel() else {
        mps2::fatal("the OS configuration is inconsistent")
    };
    defmt::println!("cw-mps2: collision-warning ECU on mps2-an386 (production image)");
    let parts = BoardParts {
        watchdog: mps2::CmsdkWatchdog::new(),
        faults: NoFaults,
        port: Mps2PortDriver,
        can: mps2::slcan_uart0(),
        leds: Leds {
            red: Led::RED,
            yellow: Led::YELLOW,
        },
        sonar: SerialSensor::new(SensorUart::uart1(), config::SENSOR_SILENT_AFTER_SAMPLES),
        modes: ModeInputs {
            ignition: TiedOn,
            com_enable: TiedOn,
        },
    };
    let ecu = Ecu::new(cw_bsp::cortex_m::port(kernel), parts, SonarConfig::HC_SR04);
    let Some(app) = APP.init(Mps2FlashApp { ecu }) else {
        mps2::fatal("started twice")
    };
    app.ecu.init();
    let app: &'static Mps2FlashApp = app;
    cw_bsp::cortex_m::start(app, app.ecu.port())
}
