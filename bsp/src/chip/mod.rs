//! Chips: peripherals as typed register blocks (`tock-registers`) and the drivers that
//! use them through those blocks only, never through address arithmetic.
//!
//! A driver here takes a `&RegisterBlock`: on a board it is the peripheral at its address
//! (the board's one `unsafe`), on the host a block in ordinary memory, so the driver's
//! register sequences (what it writes, in which order, with which bits) are tested on the
//! host unchanged; what the silicon does in reply (a FIFO, a counter) is the board test's
//! (QEMU) or the hardware's.
//!
//! A peripheral whose accesses have side effects the driver relies on (FlexCAN: a read
//! locks a buffer, a write of one clears a flag, an acknowledge comes later) is reached
//! through an access path instead ([`access::Access`]): the same typed registers,
//! volatile accesses on silicon and a register-level model on the host that answers each
//! access as the module does.
//!
//! - [`cmsdk`]: Arm's Cortex-M System Design Kit peripherals: the APB UART and the APB
//!   watchdog (Arm DDI 0479C);
//! - [`flexcan`]: NXP's FlexCAN (S32K1xx, MPC574x), with its register-level model;
//! - [`fpgaio`]: the MPS2 FPGA images' FPGAIO block (the LEDs);
//! - [`s32k144`]: NXP's S32K144: its watchdog, clocks, clock gates, pins, UARTs, echo
//!   capture and flash configuration field;
//! - [`mpc5748g`]: NXP's MPC5748G (the paper's MCU): its watchdog, modes, clocks, pads
//!   and timers.

pub mod access;
pub mod cmsdk;
pub mod flexcan;
pub mod fpgaio;
pub mod mpc5748g;
pub mod s32k144;
