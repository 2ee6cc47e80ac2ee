//! NXP's MPC5748G (the paper's MCU: two e200z4 cores and an e200z2, 6 MiB of flash, 768
//! KiB of SRAM, eight FlexCANs): the modules a board of this ECU brings up, as registers
//! reached through an access path ([`crate::chip::access`]), each driver tested on the
//! host for the register sequence it writes.
//!
//! - [`swt`]: the software watchdog, running out of reset, disabled or started;
//! - [`mc_me`]: the modes (DRUN, RUN0), their clock sources, the peripherals' clocks;
//! - [`mc_cgm`]: the PLL from the 40 MHz crystal and the clock dividers;
//! - [`siul2`]: the pads' functions and the GPIO pads (embedded-hal output pins);
//! - [`pit`]: the periodic timer (the OS tick);
//! - [`stm`]: the system timer (the time base).
//!
//! FlexCAN, the same module as on the S32K144, is [`crate::chip::flexcan`]: the MPC5748G's
//! FlexCAN_0 is at 0xFFEC_0000, clocked from the crystal.
//!
//! Registers, offsets and keys as NXP's MPC5748G header and NXP's and the DEVKIT-MPC5748G's
//! published sources
//! give them (the book lists which fact comes from where). **No code here can run on the
//! MPC5748G**: its cores execute only the VLE instruction encoding, which LLVM cannot
//! emit. The modules build for a Book E PowerPC target (`targets/`) and their tests run on
//! the host and, big-endian, under Miri. The book: [the NXP
//! boards](../../../../book/nxp-boards.html#the-mpc5748g).

pub mod mc_cgm;
pub mod mc_me;
pub mod pit;
pub mod siul2;
pub mod stm;
pub mod swt;
