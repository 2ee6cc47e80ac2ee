//! Scenarios on the host: `cw_core::scenario` (the format, its one parser, the obstacle's
//! movement), with room for 64 lines of each kind. The Cortex-M image reads the same
//! files into a smaller `cw_core::scenario::Scenario`.

pub use cw_core::scenario::{NoiseSpec, ScenarioError};

/// Lines of each kind a host scenario holds.
pub const HOST_CAPACITY: usize = 64;

/// A scenario on the host.
pub type Scenario = cw_core::scenario::Scenario<HOST_CAPACITY>;
