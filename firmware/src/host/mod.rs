//! The ECU on the simulated host board (`cw_bsp::host`), driven by a [`Scenario`] in
//! virtual time: the 1 ms timer interrupt, the CAN interrupt, the sensor that sees the
//! scenario's obstacle, and a PC on the bus.

pub mod scenario;
pub mod sim;

pub use scenario::{NoiseSpec, Scenario, ScenarioError};
pub use sim::{Simulation, SimulationError, TraceRow};
