//! A FlexCAN on the virtual bus: the register-level model ([`FlexcanModel`]) as a node,
//! driven by the FlexCAN driver ([`Flexcan`]) through [`HostFlexcanAccess`].
//!
//! The bus treats the module as it treats its other controllers, with the module's own
//! rules: it offers the frame the module's arbitration picked (the lowest identifier
//! among its pending buffers), it acknowledges and receives only while on the bus (out
//! of freeze and disable mode, not bus-off), its error counter is the module's, and each
//! frame on the wire begins and ends in the model (`begin_tx`/`end_tx`,
//! `begin_rx`/`end_rx`), so a freeze asked for during a frame is acknowledged at its end.
//! A bus-off module that is back on the bus with its recovery allowed recovers
//! [`BUS_OFF_RECOVERY_BITS`] bit times after it got there, as the host's behavioural
//! controller does after its restart.
//!
//! Every access of the driver goes through [`HostFlexcanAccess`]: it time-stamps the
//! frames the driver hands to the module (the bus starts a frame no earlier than its
//! write) and, after each write that can change what the module offers (to a module
//! register, or to a buffer that waits to send or is made to) and each read of `MCR`
//! (the only read that moves the module: an acknowledge), lets the bus see the module's
//! new state (the next transmission is planned again).

use std::rc::Rc;

use core::cell::RefCell;

use cw_core::can::confinement::{ErrorState, Failure, ERROR_PASSIVE_TEC};
use cw_core::can::{
    CanBusy, CanDriver, CanFrame, ControllerConfig, ControllerMode, ErrorCounters, Hth,
    InitRefused, ModeChange, ModeRefused,
};

use super::{bus_mut, Bus, NodeId, Pending, Role, VirtualBus, BUS_OFF_RECOVERY_BITS};
use crate::chip::flexcan::model::{Phase, RECOVERY_SEQUENCES};
use crate::chip::flexcan::regs::{mb_of, offset, Access, MAX_MAILBOXES};
use crate::chip::flexcan::{Flexcan, FlexcanConfig, FlexcanEvent, FlexcanModel, LayoutError};

/// The bus's view of one FlexCAN node.
#[derive(Debug)]
pub(super) struct FlexNode {
    pub(super) model: Rc<FlexcanModel>,
    /// When the driver last stored `DATA` into each buffer, ns.
    since_ns: [u64; MAX_MAILBOXES],
    /// The frame the module offers, as the bus plans with it (`pdu` holds its buffer).
    pub(super) offer: Option<Pending>,
    /// Bus-off, back on the bus and allowed to recover: the recovery ends here.
    recovery_end_ns: Option<u64>,
}

impl FlexNode {
    fn new(model: Rc<FlexcanModel>) -> Self {
        Self {
            model,
            since_ns: [0; MAX_MAILBOXES],
            offer: None,
            recovery_end_ns: None,
        }
    }

    pub(super) fn transmit_ready_ns(&self) -> Option<u64> {
        if self.model.phase() != Phase::Normal {
            return None;
        }
        if self.model.is_bus_off() {
            return self.recovery_end_ns;
        }
        Some(0)
    }

    pub(super) fn is_active_at(&self, t_ns: u64) -> bool {
        self.model.is_on_bus()
            || (self.model.phase() == Phase::Normal
                && self.recovery_end_ns.is_some_and(|end| end <= t_ns))
    }

    /// Completes a recovery that has ended by `t_ns`; its end, if one did.
    pub(super) fn settle(&mut self, t_ns: u64) -> Option<u64> {
        let end_ns = self.recovery_end_ns.filter(|&end| end <= t_ns)?;
        self.model.idle(RECOVERY_SEQUENCES);
        if self.model.is_bus_off() {
            return None;
        }
        self.recovery_end_ns = None;
        Some(end_ns)
    }

    /// The module's frame on the wire ended; its error state after it.
    pub(super) fn end_tx(&mut self, failure: Option<Failure>) -> ErrorState {
        self.model.end_tx(failure);
        if self.model.is_bus_off() {
            ErrorState::BusOff
        } else if self.model.tec() >= ERROR_PASSIVE_TEC {
            ErrorState::Passive
        } else {
            ErrorState::Active
        }
    }

    pub(super) fn receive(&mut self, frame: &CanFrame) {
        let _ = self.model.end_rx(frame);
    }

    /// After an access of the driver: the module's offer and recovery as they are now.
    pub(super) fn refresh(&mut self, now_ns: u64, bit_ns: u64, seq: u64) {
        self.offer = self.model.next_frame().map(|(mb, frame)| Pending {
            frame,
            pdu: u16::try_from(mb).unwrap_or(0),
            since_ns: self.since_ns.get(mb).copied().unwrap_or(now_ns),
            seq,
        });
        let recovering = self.model.is_bus_off()
            && self.model.phase() == Phase::Normal
            && self.model.may_recover();
        if !recovering {
            self.recovery_end_ns = None;
        } else if self.recovery_end_ns.is_none() {
            self.recovery_end_ns =
                Some(now_ns.saturating_add(u64::from(BUS_OFF_RECOVERY_BITS) * bit_ns));
        }
    }
}

impl Bus {
    fn flex_mut(&mut self, node: usize) -> Option<&mut FlexNode> {
        match &mut self.nodes.get_mut(node)?.role {
            Role::Flexcan(f) => Some(f),
            _ => None,
        }
    }
}

/// The driver's access path to a model on the bus.
#[derive(Debug, Clone)]
pub struct HostFlexcanAccess {
    model: Rc<FlexcanModel>,
    bus: Rc<RefCell<Bus>>,
    node: usize,
}

impl HostFlexcanAccess {
    fn after_access(&self, data_written_to: Option<usize>) {
        let mut bus = bus_mut(&self.bus);
        let now_ns = bus.now_ns();
        let bit_ns = bus.bit_ns;
        let seq = bus.next_seq;
        bus.next_seq += 1;
        if let Some(flex) = bus.flex_mut(self.node) {
            if let Some(since) = data_written_to.and_then(|mb| flex.since_ns.get_mut(mb)) {
                *since = now_ns;
            }
            flex.refresh(now_ns, bit_ns, seq);
        }
    }

    /// The model behind the access path.
    pub fn model(&self) -> &FlexcanModel {
        &self.model
    }
}

/// A transmit buffer's `CODE` while its frame waits to be sent.
const CODE_DATA: u32 = 0b1100;

/// `CODE` = `DATA` in a control word.
const fn is_data_code(value: u32) -> bool {
    (value >> 24) & 0xF == CODE_DATA
}

impl Access for HostFlexcanAccess {
    fn read(&self, offset: usize) -> u32 {
        let value = self.model.read(offset);
        // Of the reads, only one of `MCR` moves the module (an acknowledge comes); the
        // others change nothing the bus plans with.
        if offset == offset::MCR {
            self.after_access(None);
        }
        value
    }

    fn write(&self, offset: usize, value: u32) {
        let buffer = mb_of(offset);
        // What the module offers the bus, and its recovery, change only with a buffer
        // that waits to send or is made to (its frame is the offer's candidate) and with
        // the module's own registers; a write to any other buffer's words (the rest of a
        // transmit buffer being filled, a receive buffer) leaves the bus's plan as it is.
        let moves = match buffer {
            None => true,
            Some((mb, word)) => {
                self.model.code(mb) == Some(CODE_DATA) || (word == 0 && is_data_code(value))
            }
        };
        self.model.write(offset, value);
        if moves {
            let data = buffer
                .filter(|&(_, word)| word == 0 && is_data_code(value))
                .map(|(mb, _)| mb);
            self.after_access(data);
        }
    }
}

/// A FlexCAN controller on a [`VirtualBus`]: the register-level model as the bus's node
/// and the FlexCAN driver over it, as the host ECU's CAN controller.
pub struct HostFlexcan {
    driver: Flexcan<HostFlexcanAccess>,
}

impl VirtualBus {
    /// Attaches a FlexCAN (a model out of reset) with its driver for `config`.
    ///
    /// # Errors
    /// [`LayoutError`] when the buffers cannot hold the configuration.
    pub fn attach_flexcan(&self, config: &FlexcanConfig<'_>) -> Result<HostFlexcan, LayoutError> {
        let model = Rc::new(FlexcanModel::new());
        let node = bus_mut(&self.bus).attach(Role::Flexcan(FlexNode::new(Rc::clone(&model))));
        let access = HostFlexcanAccess {
            model,
            bus: Rc::clone(&self.bus),
            node,
        };
        Ok(HostFlexcan {
            driver: Flexcan::new(access, config)?,
        })
    }
}

impl HostFlexcan {
    /// The node's id on its bus.
    pub fn node(&self) -> NodeId {
        NodeId(self.driver.registers().access().node)
    }

    /// The driver.
    pub const fn driver(&self) -> &Flexcan<HostFlexcanAccess> {
        &self.driver
    }

    /// The model.
    pub fn model(&self) -> &FlexcanModel {
        self.driver.registers().access().model()
    }

    /// Whether the controller has something to report: its interrupt line, or a mode
    /// change that was pending and is now acknowledged (`Can_MainFunction_Mode`'s poll).
    pub fn has_events(&self) -> bool {
        self.model().interrupt()
            || self
                .driver
                .pending_mode()
                .is_some_and(|mode| self.model_in(mode))
    }

    fn model_in(&self, mode: ControllerMode) -> bool {
        matches!(
            (mode, self.model().phase()),
            (ControllerMode::Started, Phase::Normal)
                | (ControllerMode::Stopped, Phase::Frozen)
                | (ControllerMode::Sleep, Phase::Disabled)
        )
    }

    /// The next event, as the interrupt handler reads it.
    pub fn take_event(&mut self) -> Option<FlexcanEvent> {
        self.driver.take_event()
    }

    /// Makes the module's next `count` transmission attempts fail.
    pub fn inject_tx_errors(&self, count: u32) {
        let access = self.driver.registers().access();
        let mut bus = bus_mut(&access.bus);
        if let Some(n) = bus.nodes.get_mut(access.node) {
            n.injected_errors = n.injected_errors.saturating_add(count);
        }
    }
}

#[cfg(test)]
mod tests;

impl CanDriver for HostFlexcan {
    /// The driver's `Can_Init`, refused also when the bus runs at another bitrate: the
    /// virtual bus has no bit-level model in which a node at the wrong bitrate would see
    /// only errors, so the host board refuses it here, as its behavioural controller does.
    fn init(&mut self, config: &ControllerConfig) -> Result<(), InitRefused> {
        let bus_bps = self.driver.registers().access().bus.borrow().bitrate_bps();
        if bus_bps != u64::from(config.bitrate) {
            return Err(InitRefused {
                bitrate: config.bitrate,
            });
        }
        self.driver.init(config)
    }

    fn write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        self.driver.write(hth, pdu, frame)
    }

    /// The driver's `Can_SetControllerMode`, with the bus run up to now first, so that
    /// the frame on the wire is the one there now.
    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        {
            let mut bus = self.driver.registers().access().bus.borrow_mut();
            let now_ns = bus.now_ns();
            bus.run_until_ns(now_ns);
        }
        self.driver.set_controller_mode(mode)
    }

    fn error_counters(&self) -> ErrorCounters {
        self.driver.error_counters()
    }

    fn abort(&mut self, hth: Hth) {
        self.driver.abort(hth);
    }
}
