//! The PC's view of the bus (paper §4.4, its Figure 8): what the page shows, computed from
//! the `DistanceFrame`s alone ([`state`]).

pub mod state;
