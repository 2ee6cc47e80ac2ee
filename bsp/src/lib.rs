//! Boards of the collision-warning ECU: the only home of hardware access.
//!
//! The book: [the Cortex-M4 image](../../book/cortex-m4.html) (the Cortex-M port and the mps2
//! board) and [the ECU](../../book/ecu.html) (the host board).
//!
//! The firmware (`firmware/`) composes the hardware-free services of `cw-core` with one
//! board from this crate. Whatever the board, it provides the same things:
//!
//! - **time**: a monotonic microsecond time base for the OS counter and alarms, and
//!   delays (embedded-hal 1.0 [`DelayNs`](embedded_hal::delay::DelayNs));
//! - **digital I/O** for Dio/IoHwAb: output pins for the red and yellow warning LEDs and
//!   the sonar trigger, input pins for the echo (embedded-hal 1.0
//!   [`digital`](embedded_hal::digital) traits);
//! - **the ultrasonic sensor**: one measurement yields a [`cw_core::sonar::Echo`], which
//!   the UltraSonic SWC converts with [`cw_core::sonar::SonarConfig`];
//! - **CAN controllers** implementing [`cw_core::can::CanDriver`] (`Can_Write`,
//!   `Can_SetControllerMode`), whose transmit confirmations, receptions and bus-off
//!   notifications the firmware hands to CanIf.
//!
//! Boards:
//!
//! - [`host`] (feature `host`, on by default, needs `std`): a simulated board that runs
//!   the ECU in virtual time, much faster than real time and fully deterministic: a
//!   shared virtual clock, recording pins, an HC-SR04 model with seeded noise and
//!   dropouts, a virtual CAN bus with arbitration, frame timing and error confinement,
//!   and a candump log writer.
//! - `mps2` (feature `mps2`, `thumbv7em-none-eabihf`): QEMU's mps2-an386 (Cortex-M4).
//! - [`s32k144evb`] (feature `s32k144evb`, `thumbv7em-none-eabihf`): NXP's S32K144EVB,
//!   with FlexCAN0; its pins and numbers are checked on the host.
//! - later: the NXP MPC5748G register-level BSP. The
//!   MPC5748G's cores execute only the VLE encoding, which LLVM (hence rustc) cannot emit:
//!   Rust code for it can be built for a Book E PowerPC target and checked big-endian, but
//!   does not run on that silicon.
//!
//! Without the `host` feature the crate is `no_std`.
#![no_std]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

#[cfg(feature = "host")]
extern crate std;

pub mod chip;
#[cfg(feature = "host")]
pub mod host;
pub mod icount;
pub mod mem;
pub mod mpc5748g;
pub mod port;
#[cfg(all(feature = "host", target_os = "linux"))]
pub mod realtime;
pub mod ring;
pub mod slcan;

#[cfg(all(target_arch = "arm", target_os = "none"))]
pub mod cortex_m;
#[cfg(all(feature = "mps2", target_arch = "arm", target_os = "none"))]
pub mod mps2;
pub mod s32k144evb;

#[cfg(all(
    feature = "mps2",
    feature = "s32k144evb",
    target_arch = "arm",
    target_os = "none"
))]
compile_error!("an image is for one board: features `mps2` and `s32k144evb` exclude each other");
