//! Hardware-free, verified core of the collision-warning ECU.
//!
//! The book's chapters on this crate: [the core](../../book/core.html), [the OS](../../book/os.html),
//! [the communication stack](../../book/com-stack.html) and [verification](../../book/verification.html)
//! (the links work once `cargo xtask book` has built the book into `target/book`).
//!
//! This crate holds the parts of the ECU described in Kim et al., *Design and
//! Implementation Procedure for an Advanced Driver Assistance System Based on an Open
//! Source AUTOSAR* (the collision-warning system on an NXP MPC5748G), that do not touch
//! hardware:
//!
//! - [`warning`]: the warning level for a distance (paper §4.3) with validated thresholds;
//! - [`sonar`]: HC-SR04-class echo width to distance conversion;
//! - [`com::signal`]: the AUTOSAR Com signal codec (Intel and Motorola byte order, DBC
//!   start-bit convention, signed and unsigned, PDUs up to 64 bytes);
//! - [`os`]: an OSEK/VDX OS 2.2.3 kernel with AUTOSAR OS's scalability-class-1
//!   additions, as a state machine (tasks, events, resources with immediate priority
//!   ceiling, counters and alarms, category-1 and -2 ISRs, interrupt services, hooks,
//!   application modes, shutdown, call levels);
//! - [`can`], [`canif`], [`pdur`] and [`com::ipdu`]: the CAN driver interface, the CAN
//!   Interface (transmit buffering, receive checks, modes, bus-off), the PDU Router's static
//!   routes, and Com's I-PDUs and signals (transmission modes, update bits, deadlines);
//! - [`cansm`]: the CAN State Manager's communication modes and bus-off recovery;
//! - [`ecum`]: EcuM start-up/run/shutdown and BswM's action lists;
//! - [`rte`]: typed sender-receiver ports (last-is-best and queued, with data-received
//!   events) and client-server operations;
//! - [`time`]: the 64-bit millisecond time's arithmetic in 32-bit operations;
//! - [`wdgm`]: the Watchdog Manager's alive supervision and the watchdog driver interface.
//!
//! Each BSW module reads its configuration through [`tables::Tables`]: a `&'static`
//! reference, or a zero-sized type that makes the configuration a build-time constant.
//!
//! Every kernel has a `spec` module of named, pure predicates. The same predicates are
//! executed by the bolero harnesses beside the code (`cargo test`), by the fuzz targets
//! (`cargo bolero test`) and by Kani (`cargo kani`), and guard the implementation through
//! `debug_assert!`.
//!
//! The crate is `#![no_std]`, forbids `unsafe`, and never allocates.
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod can;
pub mod canif;
pub mod cansm;
pub mod com;
pub mod ecum;
pub mod os;
pub mod pdur;
pub mod rte;
pub mod scenario;
pub mod sonar;
pub mod tables;
#[cfg(any(test, kani))]
mod testing;
pub mod time;
pub mod warning;
pub mod wdgm;
