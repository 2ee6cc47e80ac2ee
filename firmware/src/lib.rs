//! The collision-warning ECU of the paper, composed: its configuration ([`config`]), its
//! SWCs ([`swc`]), its RTE ([`rte`]), the I/O hardware abstraction ([`iohwab`]) and the
//! ECU that runs them on a [`board::Board`] ([`ecu`]). Everything here is `no_std` and builds for `thumbv7em-none-eabihf`; the host
//! simulation (feature `host`) adds the simulated board and the command-line tool.
//!
//! The book: [the ECU](../../book/ecu.html), [its scenarios](../../book/scenarios.html) and
//! [the Cortex-M4 image](../../book/cortex-m4.html).
//!
//! # The RTE's contract
//!
//! [`rte`] is generated from the components' description (`firmware/swc.arxml`): each
//! prototype reaches the connections through its own ports, typed by their interfaces.
//!
//! ```
//! use cw_core::warning::{Measurement, WarningLevel};
//! let mut rte = cw_firmware::rte::Rte::new();
//! // UltraSonic's write reaches ObstacleDetection, and notes new data for CanTranslate,
//! // whose data-received event then runs.
//! let noted = rte.ultra_sonic().write_sonar_data(Measurement::Distance { distance_mm: 800 });
//! assert!(noted.0);
//! assert_eq!(rte.obstacle_detection().read_sonar_data(), Measurement::Distance { distance_mm: 800 });
//! assert_eq!(rte.can_translate().take_sonar_recv(), Ok(Measurement::Distance { distance_mm: 800 }));
//! let _ = rte.obstacle_detection().write_led_request(WarningLevel::Red);
//! assert_eq!(rte.red_led().read_led_request(), WarningLevel::Red);
//! ```
//!
//! A component cannot write a port it only reads (ObstacleDetection requires SonarData):
//!
//! ```compile_fail,E0599
//! let mut rte = cw_firmware::rte::Rte::new();
//! rte.obstacle_detection().write_sonar_data(cw_core::warning::Measurement::Invalid);
//! ```
//!
//! nor write a value of another interface's data type into its port:
//!
//! ```compile_fail,E0308
//! let mut rte = cw_firmware::rte::Rte::new();
//! rte.obstacle_detection().write_led_request(cw_core::warning::Measurement::Invalid);
//! ```
//!
//! nor use a port its component type does not have (an LED has no distance port):
//!
//! ```compile_fail,E0599
//! let mut rte = cw_firmware::rte::Rte::new();
//! let _ = rte.red_led().read_sonar_data();
//! ```
#![cfg_attr(not(any(test, feature = "host")), no_std)]
#![forbid(unsafe_code)]

// The host port runs each job to its end: an extended task's wait would return at once.
#[cfg(all(feature = "extended-tasks", feature = "host"))]
compile_error!(
    "feature `extended-tasks` is for the Cortex-M measuring image `cw-qemu` (build it with --no-default-features --features scenario,extended-tasks)"
);

pub mod board;
pub mod config;
#[cfg(all(target_arch = "arm", target_os = "none"))]
pub mod cortex_m;
pub mod ecu;
pub mod generated;
#[cfg(feature = "host")]
pub mod host;
pub mod iohwab;
#[cfg(all(feature = "mps2", target_arch = "arm", target_os = "none"))]
pub mod mps2;
pub mod rte;
#[cfg(all(feature = "s32k144evb", target_arch = "arm", target_os = "none"))]
pub mod s32k144evb;
// The evaluation's parts, for the measuring images and the host only: the production
// image compiles neither (a generic function with more callers in this crate is inlined
// differently before the link, which moved the production image's `CanIsr` by 132 bytes).
#[cfg(any(test, feature = "host", feature = "trace"))]
pub mod schedulability;
#[cfg(any(test, feature = "host", feature = "trace"))]
pub mod stack_probe;
pub mod swc;
