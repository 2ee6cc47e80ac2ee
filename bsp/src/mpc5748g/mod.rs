//! The paper's board: NXP's MPC574XG-MB motherboard with the MPC574XG-324DS daughter card
//! (an MPC5748G), as the ECU would wire it: the board's facts, checked on the host, and
//! its bring-up (module `board`, built for the Book E target
//! `targets/powerpc-e200-none-eabi.json` with feature `mpc5748g`).
//!
//! | part | here | chip |
//! |---|---|---|
//! | clocks | a 40 MHz crystal through the PLL: 160 MHz system clock, 80 MHz peripheral bus, 40 MHz F40 ([`CLOCK_PLAN`]) | MC_CGM, PLLDIG, MC_ME (DRUN) |
//! | warning LEDs | the motherboard's LED0 (red) and LED1 (yellow), lit low | PG2, PG3 |
//! | HC-SR04 | trigger on a GPIO pad; echo on eMIOS_1 channel 6 (its input capture: not written yet) | PH5 (trigger), PH4 (echo, `IMCR42` = 2) |
//! | CAN | FlexCAN_0 on the motherboard's transceiver, 500 kbit/s from the crystal | PB0 (TX, `SSS` 1), PB1 (RX, `IMCR188` = 2) |
//! | OS tick | PIT channel 0, 1 ms from F40 | PIT |
//! | time base | STM_0 at 1 count per us (system clock / 160) | STM_0 |
//! | watchdog | SWT_0 disabled at start (it runs out of reset) | SWT_0 |
//! | boot | the boot header at 0x00F9_0000: boot ID 0x5A, core Z4A enabled, its start address | flash, read by the boot assist firmware |
//!
//! **This cannot run on the MPC5748G.** Its e200 cores execute only the VLE encoding of
//! the Power instruction set, and LLVM (so rustc) emits only the classic Book E encoding.
//! What is here builds, links for the chip's memory map with its boot header, and its
//! drivers' register sequences are tested on the host; it is what a Rust port would keep
//! when a VLE code generator exists (the book: [the NXP
//! boards](../../../book/nxp-boards.html#the-mpc5748g)).

#[cfg(all(feature = "mpc5748g", target_arch = "powerpc"))]
pub mod board;

use crate::chip::mpc5748g::mc_cgm::ClockPlan;
use crate::chip::mpc5748g::siul2::Pad;

/// The clock plan: NXP's for the MPC5748G from a 40 MHz crystal (the 324DS daughter card's
/// crystal is to be checked on the board).
pub const CLOCK_PLAN: ClockPlan = ClockPlan::XTAL40_160_MHZ;
/// The system clock, Hz.
pub const SYSTEM_HZ: u32 = CLOCK_PLAN.phi0_hz;
/// FlexCAN_0's protocol clock, Hz (the crystal).
pub const CAN_CLOCK_HZ: u32 = CLOCK_PLAN.can_hz();

/// The red warning LED: the motherboard's LED0 (lit low).
pub const LED_RED: Pad = Pad::new(b'G', 2);
/// The yellow warning LED: the motherboard's LED1 (lit low).
pub const LED_YELLOW: Pad = Pad::new(b'G', 3);
/// The HC-SR04's trigger (a GPIO output).
pub const SONAR_TRIGGER: Pad = Pad::new(b'H', 5);
/// The HC-SR04's echo: eMIOS_1 channel 6's input.
pub const SONAR_ECHO: Pad = Pad::new(b'H', 4);
/// eMIOS_1 channel 6's input selector (`IMCR42`) and its source for [`SONAR_ECHO`].
pub const SONAR_ECHO_IMCR: (usize, u32) = (42, 2);
/// FlexCAN_0's transmit pad.
pub const CAN_TX: Pad = Pad::new(b'B', 0);
/// FlexCAN_0's transmit function on [`CAN_TX`] (`MSCR[SSS]`).
pub const CAN_TX_SSS: u32 = 1;
/// FlexCAN_0's receive pad.
pub const CAN_RX: Pad = Pad::new(b'B', 1);
/// FlexCAN_0's receive input selector (`IMCR188`, the manual's IMCR700) and its source
/// for [`CAN_RX`].
pub const CAN_RX_IMCR: (usize, u32) = (188, 2);

/// `PCTLn` of FlexCAN_0.
pub const PCTL_FLEXCAN0: u8 = 70;
/// `PCTLn` of the PIT.
pub const PCTL_PIT: u8 = 91;
/// The run configuration (`RUN_PCn`) the board's peripherals use.
pub const RUN_PC: u8 = 1;

/// FlexCAN_0's base address.
pub const FLEXCAN0: usize = 0xFFEC_0000;

/// Where the boot header lies (the boot assist firmware's second search address, the
/// first of general flash).
pub const BOOT_HEADER_ADDRESS: u32 = 0x00F9_0000;
/// The boot header's first word: the boot ID 0x5A and core Z4A (CPU0) enabled.
pub const BOOT_ID_Z4A: u32 = 0x005A_0002;

/// The OS tick's PIT channel.
pub const TICK_CHANNEL: u8 = 0;

/// The boot header as the boot assist firmware reads it (24 bytes, big-endian): the boot
/// ID and enabled cores, the start address of Z2 (CPU2), two reserved words, the start
/// addresses of Z4A (CPU0) and Z4B (CPU1). `None` is an address of 0 (the core not
/// started by the header).
#[repr(C)]
pub struct BootHeader {
    /// [`BOOT_ID_Z4A`].
    pub id: u32,
    /// Z2's start.
    pub z2: Option<unsafe extern "C" fn() -> !>,
    /// Reserved.
    pub reserved: [u32; 2],
    /// Z4A's start.
    pub z4a: Option<unsafe extern "C" fn() -> !>,
    /// Z4B's start.
    pub z4b: Option<unsafe extern "C" fn() -> !>,
}

// SAFETY: plain data in flash, read by the boot firmware only.
unsafe impl Sync for BootHeader {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_boards_facts_hold_together() {
        assert_eq!(SYSTEM_HZ, 160_000_000);
        assert_eq!(CAN_CLOCK_HZ, 40_000_000);
        // The paper's 500 kbit/s from the crystal, exactly.
        let t = crate::chip::flexcan::driver::ctrl1_timing(CAN_CLOCK_HZ, 500_000, 875).unwrap();
        assert_eq!(t.timing().bitrate(CAN_CLOCK_HZ), Some(500_000));
        // The motherboard's LED0 and LED1: MSCR98 and MSCR99.
        assert_eq!((LED_RED.number(), LED_YELLOW.number()), (98, 99));
        assert_eq!((SONAR_TRIGGER.number(), SONAR_ECHO.number()), (117, 116));
        assert_eq!((CAN_TX.number(), CAN_RX.number()), (16, 17));
        let pads = [
            LED_RED,
            LED_YELLOW,
            SONAR_TRIGGER,
            SONAR_ECHO,
            CAN_TX,
            CAN_RX,
        ];
        for (i, a) in pads.iter().enumerate() {
            assert!(pads.iter().skip(i + 1).all(|b| a != b), "{a:?} twice");
        }
        // The boot ID in the first word's upper half, core Z4A's enable bit.
        assert_eq!(BOOT_ID_Z4A >> 16, 0x5A);
        assert_eq!(BOOT_ID_Z4A & 0xF, 0x2);
    }
}
