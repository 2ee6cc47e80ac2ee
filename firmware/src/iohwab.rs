//! IoHwAb, the I/O hardware abstraction (paper §3.2.2): the ECU's signals in application
//! terms (an LED lit, an echo measured), built on the board's Dio and Gpt drivers
//! ([`crate::board`]). The SWCs never see a pin.

use cw_core::sonar::Echo;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};

use crate::board::{Board, Leds, PulseCapture, SonarIo};
use crate::swc::LedColor;

/// Length of the trigger pulse, µs (HC-SR04: at least 10 µs).
pub const TRIGGER_PULSE_US: u32 = 10;

/// A Dio channel refused a write (the board's pin driver reported an error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PinFault;

/// Lights or darkens one warning LED.
///
/// # Errors
/// [`PinFault`] if the Dio channel refused the write.
pub fn set_led<B: Board>(leds: &mut Leds<B>, color: LedColor, lit: bool) -> Result<(), PinFault> {
    let pin = match color {
        LedColor::Red => &mut leds.red,
        LedColor::Yellow => &mut leds.yellow,
    };
    let written = if lit { pin.set_high() } else { pin.set_low() };
    written.map_err(|_| PinFault)
}

/// One ultrasonic measurement: checks that the echo line is idle, sends the trigger pulse
/// (Dio + Gpt delay) and times the echo (Gpt capture).
///
/// A sensor that cannot be measured gives [`Echo::Missing`], never an error the caller
/// must handle differently: the echo line stuck high (a shorted or disconnected sensor
/// reads high on a pulled-up input), a pin the driver refuses, or no complete echo within
/// `timeout_us`. UltraSonic then treats it as a bad sample.
pub fn measure_echo<B: Board>(io: &mut SonarIo<B>, timeout_us: u32) -> Echo {
    if !matches!(io.echo.is_low(), Ok(true)) {
        return Echo::Missing;
    }
    if io.trigger.set_high().is_err() {
        return Echo::Missing;
    }
    io.delay.delay_us(TRIGGER_PULSE_US);
    if io.trigger.set_low().is_err() {
        return Echo::Missing;
    }
    match io.capture.high_time_us(timeout_us) {
        Some(width_us) => Echo::Pulse { width_us },
        None => Echo::Missing,
    }
}
