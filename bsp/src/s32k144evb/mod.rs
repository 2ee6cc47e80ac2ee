//! NXP's S32K144EVB-Q100 evaluation board (an S32K144: Cortex-M4F, 512 KiB flash, 60 KiB
//! SRAM), as the collision-warning ECU wires it.
//!
//! | part | here | chip |
//! |---|---|---|
//! | clocks | the 8 MHz crystal through the SPLL: core 80 MHz, bus 40 MHz, flash 26.67 MHz ([`CLOCK_PLAN`]) | SCG |
//! | warning LEDs | the board's one RGB LED, lit low: red for the red warning, red and green (yellow) for the yellow one ([`rgb`]) | PTD15 (red), PTD16 (green), PTD0 (blue, kept dark) |
//! | CAN | FlexCAN0 on the board's UJA1169TK/F system basis chip and its CAN connector, 500 kbit/s from the 8 MHz oscillator clock | PTE4 (RX), PTE5 (TX), ALT5; IRQ 78 (bus-off), 81 (buffers 0-15), 82 (16-31) |
//! | HC-SR04 | trigger on a GPIO, echo timed by a FlexTimer's input capture (both edges) | PTC1 (trigger), PTC0 = FTM0 channel 0 (echo), ALT2 |
//! | or a UART ranging module | its TX into LPUART0's receiver, 9600 baud from the 8 MHz oscillator clock, each byte into a ring by the receive interrupt ([`crate::ring`]) | PTB0 = LPUART0 RX (ALT2, header J4-05); IRQ 31 |
//! | OS tick | SysTick, 80,000 core clocks per ms | SCS |
//! | watchdog | WDOG from the 128 kHz LPO: reconfigured first at start-up, then WdgM's | WDOG |
//! | log | defmt frames over RTT (the debug probe reads them: `probe-rs run`) | |
//! | flash configuration | 16 bytes at 0x400, unsecured ([`FLASH_CONFIG`]) | FTFC |
//!
//! The pins and numbers live here, on every target, so that the host tests check them;
//! the code that touches the board (module `board`, feature `s32k144evb`) is built for
//! `thumbv7em-none-eabihf` only. The book: [the NXP boards](../../../book/nxp-boards.html).
//!
//! **Nothing here has run on an S32K144EVB.** The image builds, links with the flash
//! configuration at 0x400 (the check command reads it back from the ELF), and every
//! driver it uses is tested on the host against the register sequences of the reference
//! manual; the first run on a board is still to come.
//!
//! The EVB's CAN transceiver is inside its UJA1169TK/F system basis chip (SBC). That
//! variant leaves the factory in its Forced Normal mode: the transceiver active and the
//! SBC's own watchdog off, with no SPI command needed, so the image does not drive the
//! SBC's SPI (LPSPI1). An SBC whose non-volatile memory was rewritten to leave Forced
//! Normal mode needs its SPI set-up first (the book says how to tell).

#[cfg(all(feature = "s32k144evb", target_arch = "arm", target_os = "none"))]
pub mod board;
#[cfg(all(feature = "s32k144evb", target_arch = "arm", target_os = "none"))]
pub use board::*;

use crate::chip::s32k144::flash::FlashConfig;
use crate::chip::s32k144::scg::{ClockPlan, Clocks};
use crate::chip::s32k144::wdog::Timeout;

/// How the clocks come from the EVB's 8 MHz crystal.
pub const CLOCK_PLAN: ClockPlan = ClockPlan::EVB_80_MHZ;

/// The clocks of [`CLOCK_PLAN`] (checked against the chip's limits when the crate is
/// built: a plan that breaks one does not compile).
pub const CLOCKS: Clocks = match CLOCK_PLAN.clocks() {
    Ok(clocks) => clocks,
    Err(_) => Clocks {
        core_hz: 0,
        bus_hz: 0,
        slow_hz: 0,
        sosc_div2_hz: 0,
        spll_div2_hz: 0,
    },
};
const _: () = assert!(CLOCKS.core_hz != 0, "the EVB's clock plan breaks a limit");

/// The core clock, Hz (SysTick counts it).
pub const CORE_HZ: u32 = CLOCKS.core_hz;

/// FlexCAN0's protocol clock, Hz: the oscillator clock (`SOSCDIV2_CLK`, the crystal
/// undivided), from which the paper's 500 kbit/s is 16 quanta exactly.
pub const CAN_CLOCK_HZ: u32 = CLOCKS.sosc_div2_hz;

/// The flash configuration field the image carries at 0x400: unsecured, mass erase
/// enabled, no protection (checked when the crate is built).
pub const FLASH_CONFIG: FlashConfig = FlashConfig::UNSECURED;
const _: () = assert!(
    FLASH_CONFIG.check().is_ok(),
    "the image must never secure the chip"
);

/// The watchdog's timeout from start-up until WdgM first sets its own: long enough for
/// the clocks, the drivers' initialisation and the ECU's start (a few ms), short enough
/// that a start-up that hangs is reset.
pub const START_TIMEOUT: Timeout = match Timeout::from_ms(256) {
    Some(t) => t,
    None => Timeout {
        toval: 0,
        prescaled: false,
    },
};
const _: () = assert!(
    START_TIMEOUT.toval != 0,
    "the start-up timeout is out of range"
);

/// A pin of the chip: its port (`b'A'` to `b'E'`) and number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pin {
    /// The port's letter.
    pub port: u8,
    /// The pin's number in its port (0..=31).
    pub pin: u8,
}

impl Pin {
    const fn new(port: u8, pin: u8) -> Self {
        Self { port, pin }
    }
}

/// The RGB LED's red channel (lit low).
pub const LED_RED: Pin = Pin::new(b'D', 15);
/// The RGB LED's green channel (lit low).
pub const LED_GREEN: Pin = Pin::new(b'D', 16);
/// The RGB LED's blue channel (lit low; kept dark).
pub const LED_BLUE: Pin = Pin::new(b'D', 0);
/// FlexCAN0's receive line (ALT5).
pub const CAN_RX: Pin = Pin::new(b'E', 4);
/// FlexCAN0's transmit line (ALT5).
pub const CAN_TX: Pin = Pin::new(b'E', 5);
/// The mux alternative of FlexCAN0 on PTE4 and PTE5.
pub const CAN_ALT: u8 = 5;
/// The HC-SR04's trigger (a GPIO output).
pub const SONAR_TRIGGER: Pin = Pin::new(b'C', 1);
/// The HC-SR04's echo: FTM0 channel 0's input (ALT2), also read as a GPIO input (the
/// port's input register shows a pin's level whatever its function).
pub const SONAR_ECHO: Pin = Pin::new(b'C', 0);
/// The mux alternative of FTM0 channel 0 on PTC0.
pub const ECHO_ALT: u8 = 2;
/// The FTM0 channel that captures the echo.
pub const ECHO_CHANNEL: u8 = 0;
/// The FTM0 prescaler's power of two: the counter ticks at the core clock / 128.
pub const ECHO_PRESCALE_LOG2: u8 = 7;
/// The echo counter's tick rate, Hz (625 kHz: 1.6 us a tick, 104 ms a wrap, so the
/// HC-SR04's 38 ms no-echo pulse fits).
pub const ECHO_TICK_HZ: u32 = CORE_HZ >> ECHO_PRESCALE_LOG2;

const _: () = assert!(CLOCKS.slow_hz <= 26_670_000, "the flash's clock limit");
const _: () = assert!(
    u16::MAX as u64 * 1_000_000 / ECHO_TICK_HZ as u64 > 38_000,
    "the echo counter wraps within the HC-SR04's 38 ms no-echo pulse"
);

/// The UART ranging module's line (the alternative sensor): LPUART0's receiver, on the
/// Arduino-style header J4 (pin 5), used by nothing else on the board.
pub const SENSOR_UART_RX: Pin = Pin::new(b'B', 0);
/// The mux alternative of LPUART0 RX on PTB0.
pub const SENSOR_UART_ALT: u8 = 2;
/// LPUART0's interrupt line (receive and transmit).
pub const SENSOR_UART_IRQ: u16 = 31;
/// LPUART0's functional clock, Hz: the oscillator clock (`SOSCDIV2_CLK`), from which
/// 9600 baud is 0.04 % off.
pub const SENSOR_UART_CLOCK_HZ: u32 = CLOCKS.sosc_div2_hz;

/// The FlexCAN0 interrupt lines the ECU's `CanIsr` serves: the OR of bus-off and the
/// warnings (78), buffers 0-15 (81), buffers 16-31 (82).
pub const CAN_IRQS: [u16; 3] = [78, 81, 82];
/// The S32K144's external interrupt lines (0..=122).
pub const IRQ_LINES: usize = 123;

/// The RGB LED's red and green channels (`true`: lit) for the ECU's two warning LEDs: a
/// red warning is red, a yellow one red and green (yellow light); when both are asked
/// for, red wins (the ECU's own rule: it never lights both).
pub const fn rgb(red: bool, yellow: bool) -> (bool, bool) {
    (red || yellow, yellow && !red)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clocks_are_the_papers_and_the_chips() {
        assert_eq!(CORE_HZ, 80_000_000);
        assert_eq!(CLOCKS.bus_hz, 40_000_000);
        assert_eq!(CAN_CLOCK_HZ, 8_000_000, "the paper's 8 MHz CAN clock");
        // The paper's bit timing comes from this clock exactly: 16 quanta, 87.5 %.
        let timing =
            crate::chip::flexcan::driver::ctrl1_timing(CAN_CLOCK_HZ, 500_000, 875).unwrap();
        assert_eq!(
            (timing.presdiv, timing.propseg, timing.pseg1, timing.pseg2),
            (0, 5, 6, 1)
        );
        // 1.6 us a tick.
        assert_eq!(ECHO_TICK_HZ, 625_000);
    }

    #[test]
    fn the_rgb_led_shows_each_warning_in_its_colour() {
        assert_eq!(rgb(false, false), (false, false), "dark");
        assert_eq!(rgb(true, false), (true, false), "red");
        assert_eq!(rgb(false, true), (true, true), "yellow: red and green");
        assert_eq!(rgb(true, true), (true, false), "red wins");
    }

    #[test]
    fn the_pins_are_the_boards() {
        // The RGB LED and the CAN lines as the EVB's schematic routes them.
        assert_eq!((LED_RED.port, LED_RED.pin), (b'D', 15));
        assert_eq!((LED_GREEN.port, LED_GREEN.pin), (b'D', 16));
        assert_eq!((LED_BLUE.port, LED_BLUE.pin), (b'D', 0));
        assert_eq!(
            (CAN_RX, CAN_TX, CAN_ALT),
            (Pin::new(b'E', 4), Pin::new(b'E', 5), 5)
        );
        // No pin serves two parts.
        let pins = [
            LED_RED,
            LED_GREEN,
            LED_BLUE,
            CAN_RX,
            CAN_TX,
            SONAR_TRIGGER,
            SONAR_ECHO,
            SENSOR_UART_RX,
        ];
        for (i, a) in pins.iter().enumerate() {
            assert!(pins.iter().skip(i + 1).all(|b| a != b), "{a:?} twice");
            assert!(a.pin <= 31 && (b'A'..=b'E').contains(&a.port));
        }
        assert!(CAN_IRQS.iter().all(|&l| usize::from(l) < IRQ_LINES));
        assert!(!CAN_IRQS.contains(&SENSOR_UART_IRQ));
        // The UART module's 9600 baud from the sensor UART's clock, within 3 %.
        let d = crate::chip::s32k144::lpuart::Divisors::for_baud(
            SENSOR_UART_CLOCK_HZ,
            cw_core::sonar::uart::BAUD,
        )
        .unwrap();
        assert_eq!(d.baud(SENSOR_UART_CLOCK_HZ), 9_603);
    }

    #[test]
    fn the_flash_configuration_leaves_the_chip_open() {
        let bytes = FLASH_CONFIG.bytes();
        // FSEC at 0x40C: SEC = 0b10 (unsecured), MEEN not 0b10 (mass erase enabled).
        assert_eq!(bytes[12] & 0b11, 0b10);
        assert_ne!((bytes[12] >> 4) & 0b11, 0b10);
        assert!(START_TIMEOUT.us() >= 250_000 && START_TIMEOUT.us() <= 256_000);
    }
}
