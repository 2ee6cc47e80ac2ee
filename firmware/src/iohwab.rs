//! IoHwAb, the I/O hardware abstraction (paper §3.2.2): the ECU's signals in application
//! terms (an LED lit, an echo measured), built on the board's Dio and Gpt drivers
//! ([`crate::board`]). The SWCs never see a pin.

use cw_core::sonar::{Echo, SonarConfig};
use cw_core::warning::Measurement;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};

use crate::board::{Board, DistanceSensor, EchoSensor, Leds, PulseCapture, SerialRx, SerialSensor};
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

/// A Dio input channel's level: `Some(high)`, or `None` when the driver refuses the read.
pub fn read_input<P: InputPin>(pin: &mut P) -> Option<bool> {
    pin.is_high().ok()
}

/// One ultrasonic measurement: checks that the echo line is idle, sends the trigger pulse
/// (Dio + Gpt delay) and times the echo (Gpt capture).
///
/// A sensor that cannot be measured gives [`Echo::Missing`], never an error the caller
/// must handle differently: the echo line stuck high (a shorted or disconnected sensor
/// reads high on a pulled-up input), a pin the driver refuses, or no complete echo within
/// `timeout_us`. UltraSonic then treats it as a bad sample.
pub fn measure_echo<T: OutputPin, E: InputPin, D: DelayNs, C: PulseCapture>(
    io: &mut EchoSensor<T, E, D, C>,
    timeout_us: u32,
) -> Echo {
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

impl<T: OutputPin, E: InputPin, D: DelayNs, C: PulseCapture> DistanceSensor
    for EchoSensor<T, E, D, C>
{
    fn sample(&mut self, config: &SonarConfig) -> Measurement {
        config.measure(measure_echo(self, config.echo_timeout_us()))
    }
}

impl<R: SerialRx> DistanceSensor for SerialSensor<R> {
    /// The frames received since the last sample, by `cw_core::sonar::uart::Ranger`'s
    /// rules: the newest decides; between frames the last distance stands until the
    /// module has been silent too long.
    fn sample(&mut self, config: &SonarConfig) -> Measurement {
        let rx = &mut self.rx;
        self.ranger
            .sample(core::iter::from_fn(|| rx.read_byte()), config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cw_core::sonar::uart::encode;
    use std::collections::VecDeque;

    /// The bytes on a UART, as its interrupt would have buffered them.
    struct Wire(VecDeque<u8>);

    impl SerialRx for Wire {
        fn read_byte(&mut self) -> Option<u8> {
            self.0.pop_front()
        }
    }

    /// Each sample takes what arrived since the last one, all of it: a frame split
    /// across two samples is decoded in the second, and the newest frame decides.
    #[test]
    fn serial_sensor_samples_what_arrived_since_the_last_sample() {
        let config = SonarConfig::HC_SR04;
        let mut sensor = SerialSensor::new(Wire(VecDeque::new()), 2);
        assert_eq!(sensor.sample(&config), Measurement::Invalid, "nothing yet");
        let [a, b, c, d] = encode(1953);
        sensor.rx.0.extend([a, b]);
        assert_eq!(sensor.sample(&config), Measurement::Invalid, "half a frame");
        sensor.rx.0.extend([c, d]);
        sensor.rx.0.extend(encode(800));
        assert_eq!(
            sensor.sample(&config),
            Measurement::Distance { distance_mm: 800 }
        );
        assert!(sensor.rx.0.is_empty());
        assert_eq!(
            sensor.sample(&config),
            Measurement::Distance { distance_mm: 800 },
            "between frames the last distance stands"
        );
        assert_eq!(sensor.sample(&config), Measurement::Invalid, "silent");
        assert_eq!(sensor.ranger.counts().frames, 2);
    }
}
