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
//! [`rte`] is generated from the components' description (`firmware/swc.arxml`). A
//! component implements its type's runnables trait against its type's ports trait; the
//! generated task bodies ([`rte::tasks`]) call each runnable with its prototype's context,
//! which reaches that prototype's connections and nothing else.
//!
//! ```
//! use cw_core::warning::{Measurement, WarningLevel};
//! use cw_firmware::rte::{self, tasks, ObstacleDetectionPorts, ObstacleDetectionRunnables};
//! use cw_firmware::rte::{UltraSonicPorts, UltraSonicRunnables};
//!
//! /// A sensor that always sees 0.8 m.
//! struct Sensor;
//! impl UltraSonicRunnables for Sensor {
//!     fn ultra_sonic_runnable(&mut self, ports: &mut impl UltraSonicPorts) {
//!         ports.write_sonar_data(Measurement::Distance { distance_mm: 800 });
//!     }
//! }
//!
//! let mut rte = rte::Rte::new();
//! // UltraSonic's write reaches ObstacleDetection, and fires CanTranslate's data-received
//! // event: its task is to be activated.
//! let released = tasks::os_sonar_task(&mut rte, &mut Sensor);
//! assert!(released.tasks().eq([tasks::CAN_TRANSLATE_SONAR_RECV]));
//! // The project's ObstacleDetection decides red for it.
//! let mut obstacle = cw_firmware::swc::ObstacleDetection::new();
//! let _ = tasks::os_obstacle_detection_task(&mut rte, &mut obstacle);
//! assert_eq!(rte.peek_obstacle_detection_led_request(), WarningLevel::Red);
//! ```
//!
//! A component cannot write a port it only reads (ObstacleDetection requires SonarData):
//!
//! ```compile_fail,E0599
//! use cw_firmware::rte::{ObstacleDetectionPorts, ObstacleDetectionRunnables};
//! struct Detector;
//! impl ObstacleDetectionRunnables for Detector {
//!     fn obstacle_detection_runnable(&mut self, ports: &mut impl ObstacleDetectionPorts) {
//!         ports.write_sonar_data(cw_core::warning::Measurement::Invalid);
//!     }
//! }
//! ```
//!
//! nor write a value of another interface's data type into its port:
//!
//! ```compile_fail,E0308
//! use cw_firmware::rte::{ObstacleDetectionPorts, ObstacleDetectionRunnables};
//! struct Detector;
//! impl ObstacleDetectionRunnables for Detector {
//!     fn obstacle_detection_runnable(&mut self, ports: &mut impl ObstacleDetectionPorts) {
//!         ports.write_led_request(cw_core::warning::Measurement::Invalid);
//!     }
//! }
//! ```
//!
//! nor use a port its component type does not have (an LED has no distance port):
//!
//! ```compile_fail,E0599
//! use cw_firmware::rte::{LedActuatorPorts, LedActuatorRunnables};
//! struct Led;
//! impl LedActuatorRunnables for Led {
//!     fn led_actuator_runnable(&mut self, ports: &mut impl LedActuatorPorts) {
//!         let _ = ports.read_sonar_data();
//!     }
//! }
//! ```
//!
//! nor reach another prototype's context: only the task bodies make them.
//!
//! ```compile_fail,E0624
//! let mut rte = cw_firmware::rte::Rte::new();
//! let _ = rte.red_led();
//! ```
//!
//! A task body takes the components of the runnables mapped to its task, of their types:
//!
//! ```compile_fail,E0277
//! let mut rte = cw_firmware::rte::Rte::new();
//! let mut detector = cw_firmware::swc::ObstacleDetection::new();
//! let _ = cw_firmware::rte::tasks::os_sonar_task(&mut rte, &mut detector);
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
