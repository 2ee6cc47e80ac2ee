//! The bring-up image of the paper's board (the MPC574XG-MB with the MPC574XG-324DS): the
//! board layer linked for the paper's MCU, with its boot header and start-up code. It
//! brings the board up (SWT_0 off, the PLL at 160 MHz, the pads), starts FlexCAN_0 at the
//! paper's 500 kbit/s with the ECU's buffers (`config::flexcan`), and blinks LED0 (the red
//! warning LED) at 1 Hz from the PIT's 1 ms tick while it empties the controller's
//! buffers; a failed step leaves the LEDs dark and stops.
//!
//! **It cannot run on the MPC5748G**: its cores execute only VLE code, and this is Book E
//! code (the book: `docs/src/nxp-boards.md`, "The MPC5748G"). It is built and checked by
//! `cargo xtask mpc5748g`: the target, the linker script and the boot header in place.
#![no_std]
#![no_main]

use cw_bsp::chip::flexcan::ClockSource;
use cw_bsp::mpc5748g::{self as devkit, board};
use cw_core::can::{CanDriver, ControllerConfig, ControllerMode};
use cw_firmware::config;

/// The paper's bit rate, sampled at 87.5 %.
const CAN: ControllerConfig = ControllerConfig {
    bitrate: 500_000,
    sample_permille: 875,
};

/// The entry the start-up code calls once the RAM is initialised.
#[no_mangle]
pub extern "C" fn cw_mpc5748g_main() -> ! {
    if board::bring_up().is_err() {
        stop();
    }
    let Ok(mut can) = board::flexcan0(&config::flexcan(
        ClockSource::Oscillator,
        devkit::CAN_CLOCK_HZ,
    )) else {
        stop()
    };
    if can.init(&CAN).is_err() || can.set_controller_mode(ControllerMode::Started).is_err() {
        stop();
    }
    let led = board::led(devkit::LED_RED);
    let mut ms: u32 = 0;
    loop {
        if board::tick_elapsed() {
            ms = ms.wrapping_add(1);
            if ms % 500 == 0 {
                led.set((ms / 500) % 2 == 1);
            }
        }
        while can.take_event().is_some() {}
    }
}

fn stop() -> ! {
    board::leds_safe();
    loop {
        core::hint::spin_loop();
    }
}
