//! NXP FlexCAN, the CAN controller of the S32K1xx and MPC574x chips: its registers
//! ([`regs`]), its driver ([`driver`], AUTOSAR's `Can` for one controller) and, on the
//! host, a register-level model of the module ([`model`]) that the driver's tests,
//! harnesses and the host ECU run against.
//!
//! The book: [the FlexCAN chapter](../../../../book/flexcan.html).

pub mod driver;
pub mod model;
pub mod regs;
pub mod spec;

pub use driver::{
    ctrl1_timing, ClockSource, Ctrl1Timing, Flexcan, FlexcanConfig, FlexcanError, FlexcanEvent,
    FlexcanStats, Layout, LayoutError, Role, RxFilter, TxSlot,
};
pub use model::{FlexcanModel, ModelStats, Phase, RxOutcome};

#[cfg(test)]
mod tests;
