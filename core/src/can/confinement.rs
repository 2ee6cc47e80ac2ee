//! Fault confinement of a CAN transmitter (ISO 11898-1, transmit error counter): every
//! failed attempt raises TEC by 8, every frame sent lowers it by 1; at TEC >= 128 the
//! node is error passive, above 255 it is bus-off until it recovers (128 occurrences of
//! 11 recessive bits, [`super::timing::BUS_OFF_RECOVERY_BITS`]) with TEC 0.
//!
//! An error-passive transmitter's acknowledgement error (nobody else on the bus) does not
//! raise TEC, so a lone node stays error passive and never goes bus-off.
//!
//! The host's simulated bus and the image's SLCAN controller both count with
//! [`TransmitErrors`].

/// TEC at which a node becomes error passive.
pub const ERROR_PASSIVE_TEC: u16 = 128;
/// The highest TEC before bus-off.
pub const BUS_OFF_TEC: u16 = 255;
/// TEC added per failed attempt.
pub const TEC_PER_ERROR: u16 = 8;

/// A transmitter's error state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorState {
    /// TEC below 128.
    Active,
    /// TEC 128..=255: after each of its transmissions the node waits 8 extra bit times.
    Passive,
    /// TEC above 255: the node neither transmits nor receives until it recovers.
    BusOff,
}

/// How an attempt failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// A bit, stuff, form or CRC error (or one injected by a test).
    Error,
    /// No other node acknowledged the frame.
    NoAcknowledge,
}

/// The transmit error counter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TransmitErrors {
    tec: u16,
}

impl TransmitErrors {
    /// A node fresh from reset or recovery: TEC 0.
    pub const fn new() -> Self {
        Self { tec: 0 }
    }

    /// The counter (above 255 only while bus-off).
    pub const fn tec(&self) -> u16 {
        self.tec
    }

    /// The state the counter gives.
    pub const fn state(&self) -> ErrorState {
        if self.tec > BUS_OFF_TEC {
            ErrorState::BusOff
        } else if self.tec >= ERROR_PASSIVE_TEC {
            ErrorState::Passive
        } else {
            ErrorState::Active
        }
    }

    /// A frame was sent: TEC down by one.
    pub fn sent(&mut self) -> ErrorState {
        if self.state() != ErrorState::BusOff {
            self.tec = self.tec.saturating_sub(1);
        }
        self.state()
    }

    /// An attempt failed: TEC up by 8, unless an error-passive node's frame was merely
    /// not acknowledged. A bus-off node does not transmit, so it does not count.
    pub fn failed(&mut self, failure: Failure) -> ErrorState {
        match (self.state(), failure) {
            (ErrorState::Active, _) | (ErrorState::Passive, Failure::Error) => {
                self.tec += TEC_PER_ERROR;
            }
            (ErrorState::Passive, Failure::NoAcknowledge) | (ErrorState::BusOff, _) => {}
        }
        self.state()
    }

    /// Bus-off recovery completed (or a node that never goes bus-off caps its count at
    /// the error-passive maximum, [`Self::cap`]).
    pub fn recovered(&mut self) {
        self.tec = 0;
    }

    /// Holds the counter at 255 (a node that reports errors but never leaves the bus,
    /// as a tester's interface does).
    pub fn cap(&mut self) {
        self.tec = self.tec.min(BUS_OFF_TEC);
    }
}

/// Named properties of the counter.
pub mod spec {
    use super::{ErrorState, Failure, TransmitErrors, BUS_OFF_TEC};

    /// After any sequence of outcomes: the counter stays within 0..=263 (bus-off is
    /// reached from at most 255 with one +8), bus-off is final until recovery, and an
    /// error-passive node's missing acknowledgements never take it to bus-off.
    pub fn counter_stays_confined(outcomes: impl IntoIterator<Item = Option<Failure>>) -> bool {
        let mut errors = TransmitErrors::new();
        let mut ok = true;
        for outcome in outcomes {
            let before = errors.state();
            let after = match outcome {
                None => errors.sent(),
                Some(f) => errors.failed(f),
            };
            ok &= errors.tec() <= BUS_OFF_TEC + 8;
            ok &= before != ErrorState::BusOff || after == ErrorState::BusOff;
            ok &= !(before == ErrorState::Passive
                && outcome == Some(Failure::NoAcknowledge)
                && after == ErrorState::BusOff);
        }
        ok
    }
}

#[cfg(test)]
mod tests;
