//! A virtual classic-CAN bus with controllers that behave like real ones.
//!
//! [`VirtualBus`] is a shared handle on one bus segment at a configurable bitrate
//! (default 500 kbit/s). Nodes attach to it:
//!
//! - [`HostCan`]: an ECU's CAN controller and its AUTOSAR `Can` driver
//!   ([`CanDriver`]): transmit mailboxes grouped by hardware transmit handle (HTH), an
//!   acceptance filter mapping CAN ids to hardware receive handles (HRH), controller modes,
//!   a transmit error counter (TEC) and bus-off. What the interrupt handlers would report
//!   is queued as [`TimedCanEvent`]s for the firmware to hand to CanIf.
//! - [`HostFlexcan`]: a FlexCAN, register by register
//!   ([`crate::chip::flexcan::FlexcanModel`]), and the FlexCAN driver over it: the host
//!   ECU's controller. It keeps the promises below as the module does (see the `flexcan`
//!   module here for how the bus drives the model).
//! - [`Tester`]: an external node (a PC interface, another ECU) that puts arbitrary frames
//!   on the bus, including ids and lengths no ECU table knows, and sees every frame.
//!
//! # Time
//!
//! Controllers take frames at the [`VirtualClock`]'s current time. The bus moves only when
//! told: [`VirtualBus::run_until`] carries out every arbitration and transmission that
//! finishes by then, and [`VirtualBus::next_event_us`] says when the next one would end,
//! so an event-driven simulation can advance the clock from event to event. Run the bus up
//! to the clock (not beyond it): arbitration decided ahead of the clock cannot see frames
//! written later at an earlier time. Internally the bus counts nanoseconds so bit times add
//! up exactly; events carry the microsecond at which they have happened (rounded up). The
//! bit time is `1e9 / bitrate` rounded to a whole nanosecond, exact for all the usual
//! rates (10 k to 1 Mbit/s; 33.3 kbit/s becomes 30 030 ns). Bus time saturates after
//! about 584 years of virtual time; the bus then stops moving frames.
//!
//! # Frames on the wire
//!
//! See [`timing`] (`cw_core::can::timing`): 44 + 8 x DLC bits (standard) or 64 + 8 x DLC bits (extended) from SOF
//! through EOF, plus stuff bits (counted exactly from the real bit pattern and CRC by
//! default, or the worst case), then 3 bits of intermission. Events (confirmation,
//! reception) happen at the end of EOF; the next SOF can follow the intermission.
//!
//! # Arbitration
//!
//! Whenever the bus is idle and frames are pending, every node that may transmit offers
//! its highest-priority pending frame; the frame with the lowest arbitration field wins,
//! compared bit by bit as on the wire: the 11-bit base id first, then a standard frame
//! beats an extended frame with the same base id (its dominant RTR meets the recessive
//! SRR), then the 18 id extension bits. Losers stay pending and contend again at the next
//! idle bus. A controller offers the lowest-id frame among its mailboxes (ties: the lowest
//! mailbox); a tester offers its frames in the order sent (a FIFO, like a SocketCAN
//! queue).
//!
//! # Error confinement (ISO 11898-1, transmitter side)
//!
//! - A failed attempt raises TEC by 8 and the frame is retransmitted automatically. Failed
//!   attempts come from [`VirtualBus::inject_tx_errors`] (the next n attempts of a node
//!   fail) or from a missing acknowledgement (no other node is active: a lone node keeps
//!   retransmitting; once error passive, at TEC >= 128, an ACK error no longer raises its
//!   TEC, so it stays error passive and never reaches bus-off, as on a real bus).
//! - A failed attempt occupies the bus up to the ACK slot, then an error frame (6 + 8
//!   bits), then the intermission; nobody receives the frame.
//! - Each successful transmission lowers TEC by 1.
//! - An error-passive transmitter (TEC >= 128) waits 8 extra bit times (suspend
//!   transmission) after each of its transmissions before it may start another; other
//!   nodes may take the bus meanwhile.
//! - TEC > 255: bus-off. The controller goes to `Stopped`, its pending mailboxes are
//!   dropped without confirmation and a [`CanEvent::BusOff`] is queued. After
//!   `set_controller_mode(Started)` it needs 128 x 11 recessive bits (modelled as 1408 bit
//!   times of bus time from that call) before it transmits, receives or acknowledges again;
//!   TEC is 0 from then on. Frames written meanwhile wait in their mailboxes.
//! - A tester node counts its TEC too but never goes bus-off (its TEC stops at 255).
//!
//! # Controller modes (AUTOSAR SWS Can, `Can_SetControllerMode`)
//!
//! `Stopped -> Started`, `Started -> Stopped` (pending mailboxes are aborted without
//! confirmation), `Stopped -> Sleep`, `Sleep -> Stopped` (wake-up by software). Refused with
//! [`ModeRefused`]: `Sleep -> Started` and `Started -> Sleep`. Requesting the current mode
//! is accepted and changes nothing (AUTOSAR flags `Started -> Started` as a development
//! error only; the hardware state is the same either way). Only a started controller that
//! is not bus-off transmits, receives and acknowledges.
//!
//! A stop asked for while a frame is on the wire completes when that frame ends, as a
//! FlexCAN enters freeze mode only in the intermission or on an idle bus: the request is
//! [`ModeChange::Pending`], the controller finishes the frame (sending or receiving it),
//! then stops and queues [`CanEvent::ModeIndication`]. Meanwhile it takes no frame to send
//! and refuses to start. Every other mode change is reached at once (a FlexCAN leaves
//! freeze mode within a few clock cycles; the bus integration after a bus-off is the
//! recovery above, with frames waiting in their mailboxes).
//!
//! # Writes that cannot be taken
//!
//! [`HostCan::try_write`] says why ([`WriteError`]); through [`CanDriver::write`] every
//! refusal is [`CanBusy`]: a full mailbox, a controller that is not started, and an HTH the
//! controller does not have (it has no free mailbox, so nothing is sent and the caller
//! keeps the frame).
//!
//! # Deliberately simplified
//!
//! Receive errors (REC) and error frames caused by receivers, overload frames, remote
//! frames, CAN FD, receive FIFO overruns (event queues are unbounded), acceptance masks
//! (filters match exact ids), single-shot mode, wake-up by bus activity, and transmission of
//! the in-flight frame being cut short: a controller stopped while its frame is on the wire
//! lets the frame finish (the others receive it) but gets no confirmation.

pub use cw_core::can::timing;

use core::cell::{Cell, RefCell, RefMut};
use core::fmt;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

use cw_core::can::{
    bittiming, CanBusy, CanDriver, CanFrame, CanId, ControllerConfig, ControllerMode,
    ErrorCounters, Hrh, Hth, InitRefused, ModeChange, ModeRefused,
};

use super::clock::VirtualClock;
pub use flexcan::{HostFlexcan, HostFlexcanAccess};
pub use timing::Stuffing;
use timing::{
    failed_attempt_bits, frame_bits, BUS_OFF_RECOVERY_BITS, INTERMISSION_BITS,
    SUSPEND_TRANSMISSION_BITS,
};

use cw_core::can::confinement::{ErrorState, Failure, TransmitErrors};

/// A node on a [`VirtualBus`], numbered in order of attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(usize);

impl NodeId {
    /// Position in attachment order (0 for the first node).
    pub const fn index(self) -> usize {
        self.0
    }
}

/// Bus parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BusConfig {
    /// Bitrate in bit/s, 1..=1 000 000 (classic CAN).
    pub bitrate_bps: u32,
    /// How stuff bits are counted.
    pub stuffing: Stuffing,
}

impl BusConfig {
    /// 500 kbit/s, exact stuffing.
    pub const DEFAULT: Self = Self {
        bitrate_bps: 500_000,
        stuffing: Stuffing::Exact,
    };
}

impl Default for BusConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A refused [`BusConfig`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BusConfigError {
    /// The bitrate is 0 or above 1 Mbit/s.
    Bitrate {
        /// The refused bitrate, bit/s.
        bitrate_bps: u32,
    },
}

impl fmt::Display for BusConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bitrate { bitrate_bps } => write!(
                f,
                "CAN bitrate {bitrate_bps} bit/s is outside 1..=1000000 bit/s"
            ),
        }
    }
}

impl std::error::Error for BusConfigError {}

/// What a controller reports to the driver's upper layer (what its interrupts signal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CanEvent {
    /// A frame written with this PDU handle was sent (`CanIf_TxConfirmation`).
    TxConfirmation {
        /// The handle given to `write`.
        pdu: u16,
    },
    /// A frame passed the acceptance filter into this receive handle (`CanIf_RxIndication`).
    Received {
        /// The receive handle the filter chose.
        hrh: Hrh,
        /// The frame.
        frame: CanFrame,
    },
    /// The controller went bus-off (`CanIf_ControllerBusOff`).
    BusOff,
    /// The controller reached a mode it was asked for and could not reach at once
    /// (`CanIf_ControllerModeIndication`).
    ModeIndication {
        /// The mode it is in now.
        mode: ControllerMode,
    },
}

/// A [`CanEvent`] and the virtual time at which it happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimedCanEvent {
    /// End of the frame (or of the error frame) that caused it, µs, rounded up.
    pub time_us: u64,
    /// What happened.
    pub event: CanEvent,
}

/// A frame that completed on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BusRecord {
    /// End of the frame's EOF, µs, rounded up.
    pub time_us: u64,
    /// The node that sent it.
    pub sender: NodeId,
    /// The frame.
    pub frame: CanFrame,
}

/// Bus-wide counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BusStats {
    /// Frames transmitted successfully.
    pub frames: u64,
    /// Failed attempts (each followed by an error frame).
    pub error_frames: u64,
}

/// Counters of one controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct HostCanStats {
    /// Frames sent and confirmed.
    pub tx_confirmed: u64,
    /// Pending frames dropped by a stop or bus-off.
    pub tx_aborted: u64,
    /// Frames that passed the acceptance filter.
    pub rx_accepted: u64,
    /// Frames the acceptance filter discarded.
    pub rx_filtered: u64,
}

/// Why [`HostCan::try_write`] did not take a frame. Nothing was queued.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WriteError {
    /// The controller is not started.
    NotStarted,
    /// The controller has no such HTH.
    UnknownHth,
    /// Every mailbox of the HTH holds a pending frame.
    Busy,
}

impl From<WriteError> for CanBusy {
    fn from(_: WriteError) -> Self {
        CanBusy
    }
}

/// No node with this id is attached to the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct UnknownNode;

/// The hardware configuration of one [`HostCan`] controller.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct HostCanConfig {
    hth_count: u8,
    mailboxes_per_hth: u8,
    acceptance: Vec<(CanId, Hrh)>,
    catch_all: Option<Hrh>,
}

impl HostCanConfig {
    /// One HTH (`Hth(0)`) with one mailbox, and this acceptance table: a frame whose id is
    /// in the table goes to that entry's HRH (the first entry wins if an id repeats); any
    /// other frame is discarded by the hardware filter.
    pub fn new(acceptance: &[(CanId, Hrh)]) -> Self {
        Self {
            hth_count: 1,
            mailboxes_per_hth: 1,
            acceptance: acceptance.to_vec(),
            catch_all: None,
        }
    }

    /// Sets the number of HTHs: `Hth(0)` to `Hth(count - 1)`.
    pub fn with_hths(mut self, count: u8) -> Self {
        self.hth_count = count;
        self
    }

    /// Sets the number of transmit mailboxes behind each HTH (0 makes every write busy).
    pub fn with_mailboxes_per_hth(mut self, mailboxes: u8) -> Self {
        self.mailboxes_per_hth = mailboxes;
        self
    }

    /// Frames that match no acceptance entry go to `hrh` instead of being discarded, so
    /// unknown ids reach CanIf (whose own checks are then under test).
    pub fn with_catch_all(mut self, hrh: Hrh) -> Self {
        self.catch_all = Some(hrh);
        self
    }
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    frame: CanFrame,
    pdu: u16,
    since_ns: u64,
    seq: u64,
}

#[derive(Debug)]
struct Controller {
    mode: ControllerMode,
    bus_off: bool,
    /// Set by a start after bus-off: when the 128 x 11 recessive bits are complete.
    recovery_end_ns: Option<u64>,
    /// Asked to stop while a frame was on the wire: it stops at the frame's end.
    stopping: bool,
    hth_count: usize,
    mailboxes_per_hth: usize,
    /// `hth_count * mailboxes_per_hth` slots, HTH-major.
    mailboxes: Vec<Option<Pending>>,
    /// Acceptance table as `(CanId::key, hrh)`, sorted, one entry per key.
    acceptance: Vec<(u32, Hrh)>,
    catch_all: Option<Hrh>,
    events: VecDeque<TimedCanEvent>,
    stats: HostCanStats,
}

impl Controller {
    fn new(config: &HostCanConfig) -> Self {
        let mut acceptance: Vec<(u32, Hrh)> = config
            .acceptance
            .iter()
            .map(|&(id, hrh)| (id.key(), hrh))
            .collect();
        // Stable: among equal ids the first table entry stays first and survives dedup.
        acceptance.sort_by_key(|&(key, _)| key);
        acceptance.dedup_by_key(|&mut (key, _)| key);
        let slots = usize::from(config.hth_count) * usize::from(config.mailboxes_per_hth);
        Self {
            mode: ControllerMode::Stopped,
            bus_off: false,
            recovery_end_ns: None,
            stopping: false,
            hth_count: usize::from(config.hth_count),
            mailboxes_per_hth: usize::from(config.mailboxes_per_hth),
            mailboxes: std::vec![None; slots],
            acceptance,
            catch_all: config.catch_all,
            events: VecDeque::new(),
            stats: HostCanStats::default(),
        }
    }

    fn filter(&self, id: CanId) -> Option<Hrh> {
        match self.acceptance.binary_search_by_key(&id.key(), |&(k, _)| k) {
            Ok(i) => self.acceptance.get(i).map(|&(_, hrh)| hrh),
            Err(_) => self.catch_all,
        }
    }

    fn abort_all(&mut self) {
        for slot in &mut self.mailboxes {
            if slot.take().is_some() {
                self.stats.tx_aborted += 1;
            }
        }
    }

    /// Active on the bus at `t_ns`: started and not bus-off (or recovered by then).
    fn is_active_at(&self, t_ns: u64) -> bool {
        self.mode == ControllerMode::Started
            && (!self.bus_off || self.recovery_end_ns.is_some_and(|r| r <= t_ns))
    }
}

#[derive(Debug, Default)]
struct TesterState {
    queue: VecDeque<Pending>,
    received: Vec<BusRecord>,
}

#[derive(Debug)]
enum Role {
    Controller(Controller),
    Tester(TesterState),
    Flexcan(flexcan::FlexNode),
}

#[derive(Debug)]
struct Node {
    errors: TransmitErrors,
    injected_errors: u32,
    /// Error-passive suspend: no new transmission before this time.
    ready_at_ns: u64,
    role: Role,
}

impl Node {
    /// Earliest time the node may start a transmission, `None` if it may not at all.
    fn transmit_ready_ns(&self) -> Option<u64> {
        match &self.role {
            Role::Controller(c) => {
                if c.mode != ControllerMode::Started {
                    return None;
                }
                let recovered = if c.bus_off { c.recovery_end_ns? } else { 0 };
                Some(recovered.max(self.ready_at_ns))
            }
            Role::Tester(_) => Some(self.ready_at_ns),
            Role::Flexcan(f) => f.transmit_ready_ns().map(|r| r.max(self.ready_at_ns)),
        }
    }

    /// The frames this node could offer: `(slot, pending)`.
    fn pending(&self) -> impl Iterator<Item = (usize, &Pending)> {
        let (mailboxes, queue_head) = match &self.role {
            Role::Controller(c) => (c.mailboxes.as_slice(), None),
            Role::Tester(t) => (&[][..], t.queue.front().map(|p| (0, p))),
            // The module's own arbitration picked its frame; its slot is its buffer.
            Role::Flexcan(f) => (&[][..], f.offer.as_ref().map(|p| (usize::from(p.pdu), p))),
        };
        mailboxes
            .iter()
            .enumerate()
            .filter_map(|(i, m)| m.as_ref().map(|p| (i, p)))
            .chain(queue_head)
    }

    fn pending_at(&self, slot: usize) -> Option<&Pending> {
        match &self.role {
            Role::Controller(c) => c.mailboxes.get(slot).and_then(Option::as_ref),
            Role::Tester(t) => t.queue.front().filter(|_| slot == 0),
            Role::Flexcan(f) => f.offer.as_ref().filter(|p| usize::from(p.pdu) == slot),
        }
    }

    fn can_ack_at(&self, t_ns: u64) -> bool {
        match &self.role {
            Role::Controller(c) => c.is_active_at(t_ns),
            Role::Tester(_) => true,
            Role::Flexcan(f) => f.is_active_at(t_ns),
        }
    }

    /// Completes a bus-off recovery that has ended by `t_ns`.
    /// Returns whether a recovery ended (the node's state changed).
    fn settle(&mut self, t_ns: u64) -> bool {
        if let Role::Flexcan(f) = &mut self.role {
            if let Some(end_ns) = f.settle(t_ns) {
                self.ready_at_ns = self.ready_at_ns.max(end_ns);
                return true;
            }
            return false;
        }
        if let Role::Controller(c) = &mut self.role {
            if let Some(end_ns) = c.recovery_end_ns.filter(|&r| c.bus_off && r <= t_ns) {
                c.bus_off = false;
                c.recovery_end_ns = None;
                self.errors.recovered();
                // Settling early (an accessor at `t_ns`) must not let a frame start before
                // the recovery ended.
                self.ready_at_ns = self.ready_at_ns.max(end_ns);
                return true;
            }
        }
        false
    }

    /// Removes the pending frame `seq` from `slot`; false if it is no longer there.
    fn remove_pending(&mut self, slot: usize, seq: u64) -> bool {
        match &mut self.role {
            Role::Controller(c) => match c.mailboxes.get_mut(slot) {
                Some(m) if m.is_some_and(|p| p.seq == seq) => {
                    *m = None;
                    true
                }
                _ => false,
            },
            Role::Tester(t) => {
                if t.queue.front().is_some_and(|p| p.seq == seq) {
                    t.queue.pop_front();
                    true
                } else {
                    false
                }
            }
            // The module clears its buffer itself at the frame's end.
            Role::Flexcan(_) => false,
        }
    }
}

/// Whether the attempt on the wire will succeed, decided when it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Sent,
    InjectedError,
    NoAck,
}

/// The next transmission: who, when, and how it ends.
#[derive(Debug, Clone, Copy)]
struct Plan {
    node: usize,
    slot: usize,
    start_ns: u64,
    end_ns: u64,
    outcome: Outcome,
}

#[derive(Debug, Clone, Copy)]
struct InFlight {
    node: usize,
    slot: usize,
    seq: u64,
    frame: CanFrame,
    pdu: u16,
    end_ns: u64,
    outcome: Outcome,
}

impl InFlight {
    /// The failure this attempt ended with, if it failed.
    fn outcome_failure(&self) -> Option<Failure> {
        match self.outcome {
            Outcome::Sent => None,
            Outcome::InjectedError => Some(Failure::Error),
            Outcome::NoAck => Some(Failure::NoAcknowledge),
        }
    }
}

fn ns_to_us_ceil(ns: u64) -> u64 {
    ns.div_ceil(1_000)
}

#[derive(Debug)]
struct Bus {
    clock: VirtualClock,
    config: BusConfig,
    bit_ns: u64,
    nodes: Vec<Node>,
    /// The bus is free for the next SOF from here.
    idle_at_ns: u64,
    in_flight: Option<InFlight>,
    next_seq: u64,
    tracing: bool,
    trace: Vec<BusRecord>,
    stats: BusStats,
    /// The next transmission as `plan` last computed it, while nothing it depends on has
    /// changed (`None`: to be computed). The plan is a function of the bus's state alone,
    /// not of the clock; every access that can change that state clears this.
    plan_cache: Cell<Option<Option<Plan>>>,
}

/// Borrows the bus to change what the next transmission depends on (mailboxes, queues,
/// modes, error counters, bus-off recovery): the cached plan is dropped.
fn bus_mut(bus: &RefCell<Bus>) -> RefMut<'_, Bus> {
    let b = bus.borrow_mut();
    b.plan_cache.set(None);
    b
}

impl Bus {
    fn now_ns(&self) -> u64 {
        self.clock.now_us().saturating_mul(1_000)
    }

    /// The bus's bitrate, from its whole-nanosecond bit time (rounded to nearest).
    fn bitrate_bps(&self) -> u64 {
        (1_000_000_000 + self.bit_ns / 2) / self.bit_ns.max(1)
    }

    fn bits_ns(&self, bits: u32) -> u64 {
        u64::from(bits) * self.bit_ns
    }

    fn attach(&mut self, role: Role) -> usize {
        self.nodes.push(Node {
            errors: TransmitErrors::new(),
            injected_errors: 0,
            ready_at_ns: 0,
            role,
        });
        self.nodes.len() - 1
    }

    fn new_pending(&mut self, frame: &CanFrame, pdu: u16) -> Pending {
        let seq = self.next_seq;
        self.next_seq += 1;
        Pending {
            frame: *frame,
            pdu,
            since_ns: self.now_ns(),
            seq,
        }
    }

    /// The next transmission if nothing else is written meanwhile.
    /// The next transmission (cached: see `plan_cache`).
    fn plan(&self) -> Option<Plan> {
        if let Some(plan) = self.plan_cache.get() {
            return plan;
        }
        let plan = self.compute_plan();
        self.plan_cache.set(Some(plan));
        plan
    }

    fn compute_plan(&self) -> Option<Plan> {
        let offers = || {
            self.nodes.iter().enumerate().flat_map(|(i, node)| {
                let ready = node.transmit_ready_ns();
                node.pending()
                    .filter_map(move |(slot, p)| ready.map(|r| (i, slot, p, p.since_ns.max(r))))
            })
        };
        let earliest_ns = offers().map(|(_, _, _, t)| t).min()?;
        let start_ns = earliest_ns.max(self.idle_at_ns);
        let (node, slot, pending, _) = offers()
            .filter(|&(_, _, _, t)| t <= start_ns)
            .min_by_key(|&(i, slot, p, _)| (p.frame.can_id().arbitration_key(), i, slot))?;
        let sender = self.nodes.get(node)?;
        let acked = self
            .nodes
            .iter()
            .enumerate()
            .any(|(j, other)| j != node && other.can_ack_at(start_ns));
        let outcome = if sender.injected_errors > 0 {
            Outcome::InjectedError
        } else if !acked {
            Outcome::NoAck
        } else {
            Outcome::Sent
        };
        let bits = match outcome {
            Outcome::Sent => frame_bits(&pending.frame, self.config.stuffing),
            Outcome::InjectedError | Outcome::NoAck => {
                failed_attempt_bits(&pending.frame, self.config.stuffing)
            }
        };
        Some(Plan {
            node,
            slot,
            start_ns,
            end_ns: start_ns.saturating_add(self.bits_ns(bits)),
            outcome,
        })
    }

    fn commit(&mut self, plan: Plan) {
        self.plan_cache.set(None);
        let Some(node) = self.nodes.get_mut(plan.node) else {
            return;
        };
        let _ = node.settle(plan.start_ns);
        if plan.outcome == Outcome::InjectedError {
            node.injected_errors -= 1;
        }
        let Some(p) = node.pending_at(plan.slot).copied() else {
            return;
        };
        for (j, other) in self.nodes.iter().enumerate() {
            if let Role::Flexcan(f) = &other.role {
                if j == plan.node {
                    f.model.begin_tx(plan.slot);
                } else {
                    f.model.begin_rx();
                }
            }
        }
        self.in_flight = Some(InFlight {
            node: plan.node,
            slot: plan.slot,
            seq: p.seq,
            frame: p.frame,
            pdu: p.pdu,
            end_ns: plan.end_ns,
            outcome: plan.outcome,
        });
    }

    fn run_until_ns(&mut self, t_ns: u64) {
        loop {
            if self.in_flight.is_none() {
                match self.plan() {
                    Some(plan) if plan.start_ns <= t_ns => self.commit(plan),
                    _ => return,
                }
            }
            match self.in_flight.take() {
                Some(f) if f.end_ns <= t_ns => {
                    self.complete(f);
                    if self.idle_at_ns == u64::MAX {
                        // Time has saturated (after about 584 years): nothing can follow.
                        return;
                    }
                }
                Some(f) => {
                    self.in_flight = Some(f);
                    return;
                }
                None => return,
            }
        }
    }

    /// The frame `f` has ended: its outcome delivered, then the controllers that were
    /// asked to stop during it stop.
    fn complete(&mut self, f: InFlight) {
        self.deliver(f);
        let time_us = ns_to_us_ceil(f.end_ns);
        for node in &mut self.nodes {
            if let Role::Controller(c) = &mut node.role {
                if core::mem::take(&mut c.stopping) {
                    c.mode = ControllerMode::Stopped;
                    c.events.push_back(TimedCanEvent {
                        time_us,
                        event: CanEvent::ModeIndication {
                            mode: ControllerMode::Stopped,
                        },
                    });
                }
            }
        }
    }

    fn deliver(&mut self, f: InFlight) {
        self.plan_cache.set(None);
        self.idle_at_ns = f.end_ns.saturating_add(self.bits_ns(INTERMISSION_BITS));
        let suspend_until_ns = self
            .idle_at_ns
            .saturating_add(self.bits_ns(SUSPEND_TRANSMISSION_BITS));
        let time_us = ns_to_us_ceil(f.end_ns);
        for node in &mut self.nodes {
            let _ = node.settle(f.end_ns);
        }
        let sent = f.outcome == Outcome::Sent;
        if sent {
            self.stats.frames += 1;
        } else {
            self.stats.error_frames += 1;
        }
        let (bit_ns, seq) = (self.bit_ns, self.next_seq);
        self.next_seq += 1;
        let Some(sender) = self.nodes.get_mut(f.node) else {
            return;
        };
        let state = if let Role::Flexcan(flex) = &mut sender.role {
            let state = flex.end_tx(f.outcome_failure());
            // The module's buffers changed at the frame's end: the bus plans with what it
            // offers now.
            flex.refresh(f.end_ns, bit_ns, seq);
            state
        } else if sent {
            if sender.remove_pending(f.slot, f.seq) {
                if let Role::Controller(c) = &mut sender.role {
                    c.stats.tx_confirmed += 1;
                    c.events.push_back(TimedCanEvent {
                        time_us,
                        event: CanEvent::TxConfirmation { pdu: f.pdu },
                    });
                }
            }
            sender.errors.sent()
        } else if f.outcome == Outcome::InjectedError {
            sender.errors.failed(Failure::Error)
        } else {
            sender.errors.failed(Failure::NoAcknowledge)
        };
        match state {
            ErrorState::BusOff => match &mut sender.role {
                Role::Controller(c) => {
                    c.bus_off = true;
                    c.recovery_end_ns = None;
                    c.mode = ControllerMode::Stopped;
                    c.abort_all();
                    c.events.push_back(TimedCanEvent {
                        time_us,
                        event: CanEvent::BusOff,
                    });
                }
                Role::Tester(_) => sender.errors.cap(),
                // The module raised BOFFINT itself; its driver stops it.
                Role::Flexcan(_) => {}
            },
            ErrorState::Passive => sender.ready_at_ns = suspend_until_ns,
            ErrorState::Active => {}
        }
        if !sent {
            for node in &mut self.nodes {
                if let Role::Flexcan(flex) = &mut node.role {
                    flex.model.end_rx_failed();
                }
            }
            return;
        }
        let sender_id = NodeId(f.node);
        for (j, node) in self.nodes.iter_mut().enumerate() {
            if j == f.node {
                continue;
            }
            match &mut node.role {
                Role::Controller(c) => {
                    if !c.is_active_at(f.end_ns) {
                        continue;
                    }
                    match c.filter(f.frame.can_id()) {
                        Some(hrh) => {
                            c.stats.rx_accepted += 1;
                            c.events.push_back(TimedCanEvent {
                                time_us,
                                event: CanEvent::Received {
                                    hrh,
                                    frame: f.frame,
                                },
                            });
                        }
                        None => c.stats.rx_filtered += 1,
                    }
                }
                Role::Tester(t) => t.received.push(BusRecord {
                    time_us,
                    sender: sender_id,
                    frame: f.frame,
                }),
                Role::Flexcan(flex) => flex.receive(&f.frame),
            }
        }
        if self.tracing {
            self.trace.push(BusRecord {
                time_us,
                sender: sender_id,
                frame: f.frame,
            });
        }
    }

    fn controller_mut(&mut self, node: usize) -> Option<&mut Controller> {
        match &mut self.nodes.get_mut(node)?.role {
            Role::Controller(c) => Some(c),
            Role::Tester(_) | Role::Flexcan(_) => None,
        }
    }

    fn controller(&self, node: usize) -> Option<&Controller> {
        match &self.nodes.get(node)?.role {
            Role::Controller(c) => Some(c),
            Role::Tester(_) | Role::Flexcan(_) => None,
        }
    }
}

/// A shared handle on one virtual CAN bus. Clones are handles on the same bus.
#[derive(Debug, Clone)]
pub struct VirtualBus {
    bus: Rc<RefCell<Bus>>,
}

impl VirtualBus {
    /// A 500 kbit/s bus with exact stuffing, timed by `clock`.
    pub fn new(clock: &VirtualClock) -> Self {
        Self::build(clock, BusConfig::DEFAULT)
    }

    /// A bus with the given parameters.
    ///
    /// # Errors
    /// [`BusConfigError::Bitrate`] for a bitrate of 0 or above 1 Mbit/s.
    pub fn with_config(clock: &VirtualClock, config: BusConfig) -> Result<Self, BusConfigError> {
        if config.bitrate_bps == 0 || config.bitrate_bps > 1_000_000 {
            return Err(BusConfigError::Bitrate {
                bitrate_bps: config.bitrate_bps,
            });
        }
        Ok(Self::build(clock, config))
    }

    fn build(clock: &VirtualClock, config: BusConfig) -> Self {
        let bps = u64::from(config.bitrate_bps.max(1));
        let bit_ns = (1_000_000_000 + bps / 2) / bps;
        Self {
            bus: Rc::new(RefCell::new(Bus {
                clock: clock.clone(),
                config,
                bit_ns,
                nodes: Vec::new(),
                idle_at_ns: 0,
                in_flight: None,
                next_seq: 0,
                tracing: false,
                trace: Vec::new(),
                stats: BusStats::default(),
                plan_cache: Cell::new(None),
            })),
        }
    }

    /// The bus parameters.
    pub fn config(&self) -> BusConfig {
        self.bus.borrow().config
    }

    /// One bit time, ns.
    pub fn bit_time_ns(&self) -> u64 {
        self.bus.borrow().bit_ns
    }

    /// The clock the bus runs on.
    pub fn clock(&self) -> VirtualClock {
        self.bus.borrow().clock.clone()
    }

    /// How long `frame` occupies the bus from SOF through EOF when sent successfully, ns
    /// (the intermission adds 3 bit times before the next frame).
    pub fn frame_duration_ns(&self, frame: &CanFrame) -> u64 {
        let bus = self.bus.borrow();
        bus.bits_ns(frame_bits(frame, bus.config.stuffing))
    }

    /// Attaches a controller (initially `Stopped`, TEC 0).
    pub fn attach(&self, config: &HostCanConfig) -> HostCan {
        let node = bus_mut(&self.bus).attach(Role::Controller(Controller::new(config)));
        HostCan {
            bus: Rc::clone(&self.bus),
            node,
        }
    }

    /// Attaches a tester node (always active, receives every frame).
    pub fn attach_tester(&self) -> Tester {
        let node = bus_mut(&self.bus).attach(Role::Tester(TesterState::default()));
        Tester {
            bus: Rc::clone(&self.bus),
            node,
        }
    }

    /// Carries out every arbitration and transmission that ends by `time_us`; a frame
    /// still on the wire then finishes in a later call.
    pub fn run_until(&self, time_us: u64) {
        self.bus
            .borrow_mut()
            .run_until_ns(time_us.saturating_mul(1_000));
    }

    /// [`Self::run_until`] the clock's current time.
    pub fn run_until_now(&self) {
        let mut bus = self.bus.borrow_mut();
        let now_ns = bus.now_ns();
        bus.run_until_ns(now_ns);
    }

    /// When the frame (or failed attempt) now on the wire, or else the next one, ends, µs
    /// (rounded up), if nothing else is written meanwhile; `None` when nothing is pending.
    pub fn next_event_us(&self) -> Option<u64> {
        let bus = self.bus.borrow();
        match &bus.in_flight {
            Some(f) => Some(ns_to_us_ceil(f.end_ns)),
            None => bus.plan().map(|p| ns_to_us_ceil(p.end_ns)),
        }
    }

    /// Makes the next `count` transmission attempts of `node` fail (added to any already
    /// injected).
    ///
    /// # Errors
    /// [`UnknownNode`] if no such node is attached.
    pub fn inject_tx_errors(&self, node: NodeId, count: u32) -> Result<(), UnknownNode> {
        let mut bus = bus_mut(&self.bus);
        let n = bus.nodes.get_mut(node.0).ok_or(UnknownNode)?;
        n.injected_errors = n.injected_errors.saturating_add(count);
        Ok(())
    }

    /// The transmit error counter of `node` (`None` if no such node).
    pub fn tec(&self, node: NodeId) -> Option<u16> {
        let mut bus = self.bus.borrow_mut();
        let now_ns = bus.now_ns();
        let n = bus.nodes.get_mut(node.0)?;
        let settled = n.settle(now_ns);
        let tec = n.errors.tec();
        if settled {
            bus.plan_cache.set(None);
        }
        Some(tec)
    }

    /// Starts or stops recording completed frames for [`Self::take_trace`] and [`Self::drain_trace_into`].
    pub fn set_tracing(&self, on: bool) {
        self.bus.borrow_mut().tracing = on;
    }

    /// The frames completed since the last call (while tracing), in bus order.
    pub fn take_trace(&self) -> Vec<BusRecord> {
        core::mem::take(&mut self.bus.borrow_mut().trace)
    }

    /// Moves the frames completed since the last call (while tracing), in bus order, to
    /// the end of `out`. The bus keeps its buffer, so a frame costs no allocation.
    pub fn drain_trace_into(&self, out: &mut Vec<BusRecord>) {
        out.append(&mut self.bus.borrow_mut().trace);
    }

    /// Bus-wide counters.
    pub fn stats(&self) -> BusStats {
        self.bus.borrow().stats
    }
}

/// One CAN controller on a [`VirtualBus`] and its AUTOSAR `Can` driver.
#[derive(Debug)]
pub struct HostCan {
    bus: Rc<RefCell<Bus>>,
    node: usize,
}

impl HostCan {
    /// The node's id on its bus.
    pub fn node(&self) -> NodeId {
        NodeId(self.node)
    }

    fn with<R>(&self, default: R, f: impl FnOnce(&Node) -> R) -> R {
        let mut bus = self.bus.borrow_mut();
        let now_ns = bus.now_ns();
        let Some(node) = bus.nodes.get_mut(self.node) else {
            return default;
        };
        let settled = node.settle(now_ns);
        let result = f(node);
        if settled {
            bus.plan_cache.set(None);
        }
        result
    }

    /// `Can_Write` with the reason for a refusal.
    ///
    /// # Errors
    /// [`WriteError`]; nothing was queued.
    pub fn try_write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), WriteError> {
        let mut bus = bus_mut(&self.bus);
        let pending = bus.new_pending(frame, pdu);
        let c = bus
            .controller_mut(self.node)
            .ok_or(WriteError::NotStarted)?;
        if c.mode != ControllerMode::Started || c.stopping {
            return Err(WriteError::NotStarted);
        }
        if usize::from(hth.0) >= c.hth_count {
            return Err(WriteError::UnknownHth);
        }
        let first = usize::from(hth.0) * c.mailboxes_per_hth;
        let free = c
            .mailboxes
            .iter_mut()
            .skip(first)
            .take(c.mailboxes_per_hth)
            .find(|m| m.is_none())
            .ok_or(WriteError::Busy)?;
        *free = Some(pending);
        Ok(())
    }

    /// The controller mode.
    pub fn mode(&self) -> ControllerMode {
        self.with(ControllerMode::Stopped, |n| match &n.role {
            Role::Controller(c) => c.mode,
            Role::Tester(_) | Role::Flexcan(_) => ControllerMode::Started,
        })
    }

    /// The transmit error counter (above 255 while bus-off, 0 once recovered).
    pub fn tec(&self) -> u16 {
        self.with(0, |n| n.errors.tec())
    }

    /// Whether the controller is bus-off now (until its recovery after a restart is done).
    pub fn is_bus_off(&self) -> bool {
        self.with(false, |n| match &n.role {
            Role::Controller(c) => c.bus_off,
            Role::Tester(_) => false,
            Role::Flexcan(f) => f.model.is_bus_off(),
        })
    }

    /// Whether the controller is error passive (TEC >= 128, not bus-off).
    pub fn is_error_passive(&self) -> bool {
        self.with(false, |n| n.errors.state() == ErrorState::Passive)
    }

    /// Frames waiting in the transmit mailboxes.
    pub fn pending_count(&self) -> usize {
        self.with(0, |n| n.pending().count())
    }

    /// Makes the next `count` transmission attempts fail.
    pub fn inject_tx_errors(&self, count: u32) {
        let mut bus = bus_mut(&self.bus);
        if let Some(n) = bus.nodes.get_mut(self.node) {
            n.injected_errors = n.injected_errors.saturating_add(count);
        }
    }

    /// Counters of this controller.
    pub fn stats(&self) -> HostCanStats {
        let bus = self.bus.borrow();
        bus.controller(self.node)
            .map_or_else(HostCanStats::default, |c| c.stats)
    }

    /// Takes the queued events, oldest first.
    pub fn take_events(&mut self) -> Vec<TimedCanEvent> {
        let mut out = Vec::new();
        self.drain_events_into(&mut out);
        out
    }

    /// Moves the queued events, oldest first, to the end of `out`.
    pub fn drain_events_into(&mut self, out: &mut Vec<TimedCanEvent>) {
        let mut bus = self.bus.borrow_mut();
        if let Some(c) = bus.controller_mut(self.node) {
            out.extend(c.events.drain(..));
        }
    }

    /// Whether events are queued (the controller's interrupt request).
    pub fn has_events(&self) -> bool {
        self.bus
            .borrow()
            .controller(self.node)
            .is_some_and(|c| !c.events.is_empty())
    }

    /// Takes the oldest queued event.
    pub fn pop_event(&mut self) -> Option<TimedCanEvent> {
        self.bus
            .borrow_mut()
            .controller_mut(self.node)?
            .events
            .pop_front()
    }
}

/// The modelled controllers' clock, Hz: an S32K144's FlexCAN on its 80 MHz system
/// clock. `Can_Init` takes a bitrate only if a FlexCAN bit timing gives it exactly from
/// this clock ([`cw_core::can::bittiming::FLEXCAN`]).
pub const HOST_CAN_CLOCK_HZ: u32 = 80_000_000;

impl CanDriver for HostCan {
    /// Refused when no FlexCAN bit timing gives the bitrate from [`HOST_CAN_CLOCK_HZ`],
    /// or when the bus runs at another bitrate (the controller would see only errors).
    /// Stops the controller, its pending frames withdrawn.
    fn init(&mut self, config: &ControllerConfig) -> Result<(), InitRefused> {
        let refused = InitRefused {
            bitrate: config.bitrate,
        };
        bittiming::find(
            HOST_CAN_CLOCK_HZ,
            config.bitrate,
            config.sample_permille,
            &bittiming::FLEXCAN,
        )
        .map_err(|_| refused)?;
        let mut bus = bus_mut(&self.bus);
        if bus.bitrate_bps() != u64::from(config.bitrate) {
            return Err(refused);
        }
        let c = bus.controller_mut(self.node).ok_or(refused)?;
        c.abort_all();
        c.mode = ControllerMode::Stopped;
        c.stopping = false;
        Ok(())
    }

    fn error_counters(&self) -> ErrorCounters {
        self.with(ErrorCounters::ACTIVE, |n| ErrorCounters {
            state: match &n.role {
                Role::Controller(c) if c.bus_off => ErrorState::BusOff,
                _ => n.errors.state(),
            },
            tec: n.errors.tec(),
            // The virtual bus has no receive errors (a receiver sees every frame the
            // arbitration lets through): the counter stays 0.
            rec: 0,
        })
    }

    fn abort(&mut self, hth: Hth) {
        let mut bus = bus_mut(&self.bus);
        if let Some(c) = bus.controller_mut(self.node) {
            let first = usize::from(hth.0) * c.mailboxes_per_hth;
            let mut aborted = 0;
            for slot in c.mailboxes.iter_mut().skip(first).take(c.mailboxes_per_hth) {
                if slot.take().is_some() {
                    aborted += 1;
                }
            }
            c.stats.tx_aborted += aborted;
        }
    }

    /// Every refusal of [`HostCan::try_write`] is [`CanBusy`], including an HTH the
    /// controller does not have and a controller that is not started.
    fn write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        self.try_write(hth, pdu, frame).map_err(CanBusy::from)
    }

    /// A stop asked for while a frame is on the wire (anyone's: the controller finishes
    /// the frame it sends or receives, as a FlexCAN enters freeze mode only at the
    /// frame's end) is [`ModeChange::Pending`] until that frame ends; then a
    /// [`CanEvent::ModeIndication`] follows. Every other change is reached at once. A
    /// controller on its way to stopped refuses to start.
    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        use ControllerMode::{Sleep, Started, Stopped};
        let mut bus = bus_mut(&self.bus);
        let now_ns = bus.now_ns();
        // The bus up to now, so that the frame on the wire is the one there now.
        bus.run_until_ns(now_ns);
        let on_the_wire = bus.in_flight.is_some_and(|f| f.end_ns > now_ns);
        let recovery_ns = bus.bits_ns(BUS_OFF_RECOVERY_BITS);
        let node = bus.nodes.get_mut(self.node).ok_or(ModeRefused)?;
        let _ = node.settle(now_ns);
        let Role::Controller(c) = &mut node.role else {
            return Err(ModeRefused);
        };
        if c.stopping {
            return if mode == Stopped {
                Ok(ModeChange::Pending)
            } else {
                Err(ModeRefused)
            };
        }
        match (c.mode, mode) {
            (Started, Started) | (Stopped, Stopped) | (Sleep, Sleep) => {}
            (Stopped, Started) => {
                if c.bus_off {
                    c.recovery_end_ns = Some(now_ns.saturating_add(recovery_ns));
                }
                c.mode = Started;
            }
            (Started, Stopped) => {
                c.abort_all();
                if on_the_wire {
                    c.stopping = true;
                    return Ok(ModeChange::Pending);
                }
                c.mode = Stopped;
            }
            (Stopped, Sleep) | (Sleep, Stopped) => c.mode = mode,
            (Sleep, Started) | (Started, Sleep) => return Err(ModeRefused),
        }
        Ok(ModeChange::Reached)
    }
}

/// An external node that puts arbitrary frames on the bus and sees every frame.
#[derive(Debug)]
pub struct Tester {
    bus: Rc<RefCell<Bus>>,
    node: usize,
}

impl Tester {
    /// The node's id on its bus.
    pub fn node(&self) -> NodeId {
        NodeId(self.node)
    }

    /// Queues `frame` for transmission from now; frames go out in the order sent. Any id
    /// and any length 0..=8 is fine: the ECU's filters and CanIf decide what to make of it.
    pub fn send(&mut self, frame: &CanFrame) {
        let mut bus = bus_mut(&self.bus);
        let pending = bus.new_pending(frame, 0);
        if let Some(Node {
            role: Role::Tester(t),
            ..
        }) = bus.nodes.get_mut(self.node)
        {
            t.queue.push_back(pending);
        }
    }

    /// Frames queued and not yet sent.
    pub fn queued(&self) -> usize {
        match self.bus.borrow().nodes.get(self.node) {
            Some(Node {
                role: Role::Tester(t),
                ..
            }) => t.queue.len(),
            _ => 0,
        }
    }

    /// Takes the frames other nodes sent since the last call, in bus order.
    pub fn take_received(&mut self) -> Vec<BusRecord> {
        match self.bus.borrow_mut().nodes.get_mut(self.node) {
            Some(Node {
                role: Role::Tester(t),
                ..
            }) => core::mem::take(&mut t.received),
            _ => Vec::new(),
        }
    }
}

mod flexcan;

#[cfg(test)]
mod tests;
