//! The host board: a simulated ECU board that runs in virtual time.
//!
//! Nothing here reads the wall clock or starts a thread: the simulation advances a shared
//! [`VirtualClock`] from event to event, so a run is fully determined by its scenario and
//! its seeds, and one simulated hour takes as long as its events take to compute. (A run
//! paced to the wall clock, `crate::realtime`, asks the port to note each job's start on
//! that clock too, [`HostPort::record_wall_starts`]; what the ECU does stays the same.)
//!
//! Parts (each a cheaply clonable handle where the firmware and the test both need it):
//!
//! - [`clock`]: [`VirtualClock`] (microseconds) and [`SimDelay`] (embedded-hal `DelayNs`);
//! - [`pin`]: [`SimPin`], an output pin that records every level change with its time, and
//!   [`SimInput`], an input pin whose level the simulation sets;
//! - [`sonar`]: [`HcSr04`], the ultrasonic sensor: true distance in, [`Echo`] out, with
//!   seeded noise, dropouts and the 38 ms no-echo behaviour;
//! - [`can`]: [`VirtualBus`] with [`HostFlexcan`] controllers (the FlexCAN driver over a
//!   register-level model of the module: the ECU's), [`HostCan`] controllers (AUTOSAR
//!   `Can` driver semantics, mailboxes, acceptance filters, arbitration, frame timing,
//!   error counters and bus-off, behaviourally) and [`Tester`] nodes that put arbitrary
//!   frames on the bus;
//! - [`candump`]: [`CandumpLog`], the bus trace in `candump -l` format;
//! - [`watchdog`]: [`SimWatchdog`], the watchdog that resets the ECU when WdgM stops
//!   triggering it.
//!
//! Units: times in microseconds (`_us`) unless named otherwise; the CAN bus keeps its own
//! time in nanoseconds internally so that bit times add up exactly.
//!
//! # Example: an ECU frame seen by a tester, logged as candump
//!
//! ```
//! use cw_bsp::host::{CandumpLog, HostCanConfig, VirtualBus, VirtualClock};
//! use cw_core::can::{CanDriver, CanFrame, CanId, ControllerMode, Hth};
//!
//! let clock = VirtualClock::new();
//! let bus = VirtualBus::new(&clock);
//! bus.set_tracing(true);
//! let mut ecu = bus.attach(&HostCanConfig::new(&[]));
//! let mut tester = bus.attach_tester();
//! ecu.set_controller_mode(ControllerMode::Started).unwrap();
//!
//! let id = CanId::standard(0x100).unwrap();
//! let frame = CanFrame::from_parts(id, &1500u32.to_le_bytes()).unwrap();
//! ecu.write(Hth(0), 0, &frame).unwrap();
//!
//! // Step the simulation from event to event.
//! while let Some(t) = bus.next_event_us() {
//!     clock.advance_to_us(t).unwrap();
//!     bus.run_until_now();
//! }
//! assert_eq!(tester.take_received()[0].frame, frame);
//! assert_eq!(ecu.take_events().len(), 1); // the transmit confirmation
//!
//! let mut log = CandumpLog::new(Vec::new());
//! log.drain_from(&bus).unwrap();
//! let text = String::from_utf8(log.into_inner()).unwrap();
//! assert!(text.ends_with(" can0 100#DC050000\n"));
//! ```
//!
//! [`Echo`]: cw_core::sonar::Echo
#![forbid(unsafe_code)]

pub mod can;
pub mod candump;
pub mod clock;
pub mod pin;
pub mod port;
pub mod sonar;
pub mod watchdog;

pub use can::{
    BusConfig, BusConfigError, BusRecord, BusStats, CanEvent, HostCan, HostCanConfig, HostCanStats,
    HostFlexcan, HostFlexcanAccess, NodeId, Stuffing, Tester, TimedCanEvent, UnknownNode,
    VirtualBus, WriteError,
};
pub use candump::CandumpLog;
pub use clock::{SimDelay, TimeWentBackwards, VirtualClock};
pub use pin::{SimInput, SimPin};
pub use port::HostPort;
pub use sonar::{HcSr04, Noise, XorShift64};
pub use watchdog::SimWatchdog;
