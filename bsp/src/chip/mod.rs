//! Chips: peripherals as typed register blocks (`tock-registers`) and the drivers that
//! use them through those blocks only, never through address arithmetic.
//!
//! A driver here takes a `&RegisterBlock`: on a board it is the peripheral at its address
//! (the board's one `unsafe`), on the host a block in ordinary memory, so the driver's
//! register sequences (what it writes, in which order, with which bits) are tested on the
//! host unchanged; what the silicon does in reply (a FIFO, a counter) is the board test's
//! (QEMU) or the hardware's.
//!
//! - [`cmsdk`]: Arm's Cortex-M System Design Kit peripherals: the APB UART and the APB
//!   watchdog (Arm DDI 0479C);
//! - [`fpgaio`]: the MPS2 FPGA images' FPGAIO block (the LEDs).
//!
//! Next: the S32K144's LPUART, FlexCAN and WDOG, and the MPC5748G's.

pub mod cmsdk;
pub mod fpgaio;
