//! A register-level model of the FlexCAN module, for the host.
//!
//! The model is an [`Access`]: the driver's loads and stores reach it exactly as they
//! reach the module on silicon, and it answers with the side effects the reference
//! manual gives (S32K1xx RM, chapter "FlexCAN"; the MPC5748G's FlexCAN behaves the same
//! in what is modelled). A bus (the host's virtual bus, or a test) moves frames through
//! its other side: [`FlexcanModel::offer`], [`FlexcanModel::begin_tx`],
//! [`FlexcanModel::end_tx`], [`FlexcanModel::receive`], [`FlexcanModel::idle`].
//!
//! What it enforces, with the manual's section:
//!
//! - **Modes** ("Modes of operation", "Freeze mode", "Module disable mode"): the module
//!   is disabled (`LPMACK`), frozen (`FRZACK`) or on the bus; `MCR[MDIS]` and
//!   `MCR[FRZ]`+`MCR[HALT]` ask for a mode, which is acknowledged after
//!   [`ACK_READS`] further reads of `MCR` when no frame is on the wire, or at the end of
//!   the frame on the wire (the module enters freeze mode only at the end of a frame, in
//!   the intermission or on an idle bus). Out of reset the module is disabled and asked
//!   to freeze (`MCR` = `0xD890_000F`).
//! - **Soft reset** ("Module configuration register", `SOFTRST`): `MCR` (except `MDIS`),
//!   the timer, `ECR`, `ESR1`, `IMASK1` and `IFLAG1` return to their reset values;
//!   `CTRL1`, `CTRL2`, the masks and the buffers keep theirs. The bit reads as set once
//!   more, then clear. A soft reset asked for while the module is disabled never
//!   completes (its clocks are off).
//! - **Registers writable only in freeze mode** (`CTRL1`'s timing fields, `MCR`'s
//!   configuration fields, `CTRL2`, `RXIMR`, `RXMGMASK`) and `CTRL1[CLKSRC]` writable
//!   only while disabled: a write that would change such bits at another time leaves
//!   them and is counted ([`ModelStats::ignored_writes`]).
//! - **Write 1 to clear**: `IFLAG1` and `ESR1`'s interrupt flags; `ESR1`'s error bits are
//!   cleared by reading it.
//! - **Transmit buffers** ("Transmit process", "Transmission abort mechanism" with
//!   `MCR[AEN]`): `DATA` makes a buffer pending; among pending buffers the lowest
//!   identifier goes first, then the lowest buffer (`CTRL1[LBUF]` clear). A sent frame
//!   leaves `INACTIVE` and its flag; `ABORT` written to a pending buffer that is not on
//!   the wire withdraws it at once (code `ABORT`, flag set), to the buffer on the wire at
//!   the frame's end if it failed (code `ABORT`), not at all if it succeeded (`INACTIVE`).
//!   `DATA` written over a pending buffer, and `INACTIVE` written to one (deactivation,
//!   which may lose the frame silently), are counted: a correct driver does neither.
//! - **Receive buffers** ("Receive process", "Matching process", "Message buffer
//!   lock mechanism"): an incoming frame goes to the first buffer (0 to `MAXMB`) whose
//!   code is `EMPTY`, or `FULL`/`OVERRUN` already serviced (its control word read), and
//!   whose identifier matches under its individual mask (`MCR[IRMQ]`; the global mask
//!   otherwise), `IDE` always compared; it is stored `FULL` with its flag. With no free
//!   match, the last matching buffer is overwritten and becomes `OVERRUN` (the frame it
//!   held is lost). Reading a buffer's control word locks it until the timer or another
//!   buffer's control word is read; a frame for a locked buffer waits in the serial
//!   message buffer and moves in at unlock (`OVERRUN` if a second one came meanwhile).
//! - **Fault confinement and bus-off** ("Error counters", `CTRL1[BOFFREC]`): the transmit
//!   error counter as ISO 11898-1 keeps it (`cw_core::can::confinement`); past 255 the
//!   module is bus-off (`ESR1[FLTCONF]`, `ESR1[BOFFINT]`), keeps its pending buffers and
//!   takes no part in the bus. With `BOFFREC` clear it recovers after 128 sequences of 11
//!   recessive bits on the bus ([`FlexcanModel::idle`]); with it set only if software
//!   negated it during this bus-off. Recovery sets `ESR1[BOFFDONEINT]`. The model counts
//!   the sequences only while the module is out of freeze mode.
//!
//! Simplified: the timer counts frames, not bit times; receive errors (`RXERRCNT`) and
//! warnings, remote frames, CAN FD, the legacy FIFO, `RX14MASK`/`RX15MASK`, the `BUSY`
//! code (a frame moves in between two accesses, never during one), wake-up and pretended
//! networking are not modelled.

use core::cell::RefCell;

use cw_core::can::confinement::{ErrorState, Failure, TransmitErrors};
use cw_core::can::CanFrame;

use super::regs::{
    data_bytes, data_words, id_of, id_word, mb_of, offset, Access, MAX_MAILBOXES, MB_CS, MCR,
};
use tock_registers::fields::Field;
use tock_registers::RegisterLongName;

/// Reads of `MCR` after a mode request before its acknowledge, on an idle bus.
pub const ACK_READS: u8 = 2;

/// `MCR` out of reset: disabled, freeze asked for, not ready, supervisor, `LPMACK`,
/// `MAXMB` 15.
pub const MCR_RESET: u32 = 0xD890_000F;

/// Recessive-bit sequences a bus-off node must see before it may rejoin.
pub const RECOVERY_SEQUENCES: u32 = 128;

const CODE_RX_INACTIVE: u32 = 0b0000;
const CODE_RX_FULL: u32 = 0b0010;
const CODE_RX_EMPTY: u32 = 0b0100;
const CODE_RX_OVERRUN: u32 = 0b0110;
const CODE_TX_INACTIVE: u32 = 0b1000;
const CODE_TX_ABORT: u32 = 0b1001;
const CODE_TX_DATA: u32 = 0b1100;

/// `MCR` bits writable only in freeze mode: `RFEN`, `WAK_MSK`, `SUPV`, `SLF_WAK`,
/// `WRNEN`, `SRXDIS`, `IRMQ`, `LPRIO_EN`, `AEN`, `MAXMB`.
const MCR_FREEZE_ONLY: u32 = (1 << 29)
    | (1 << 26)
    | (1 << 23)
    | (1 << 22)
    | (1 << 21)
    | (1 << 17)
    | (1 << 16)
    | (1 << 13)
    | (1 << 12)
    | 0x7F;
/// `MCR` bits the module drives (read-only to software): `NOTRDY`, `FRZACK`, `LPMACK`.
const MCR_STATUS: u32 = (1 << 27) | (1 << 24) | (1 << 20);
/// `CTRL1` bits writable only in freeze mode: the timing fields, `SMP`, `LPB`, `LOM`,
/// `LBUF`, `TSYN`.
const CTRL1_FREEZE_ONLY: u32 =
    0xFFFF_0000 | (1 << 12) | (1 << 7) | (1 << 5) | (1 << 4) | (1 << 3) | 0b111;
/// `CTRL1[CLKSRC]`, writable only while disabled.
const CTRL1_CLKSRC: u32 = 1 << 13;
/// `CTRL1[BOFFMSK]`.
const CTRL1_BOFFMSK: u32 = 1 << 15;
/// `CTRL1[BOFFREC]`.
const CTRL1_BOFFREC: u32 = 1 << 6;
/// `ESR1`'s write-1-to-clear flags: `BOFFDONEINT`, `TWRNINT`, `RWRNINT`, `BOFFINT`,
/// `ERRINT`, `WAKINT`.
const ESR1_W1C: u32 = (1 << 19) | (1 << 17) | (1 << 16) | (1 << 2) | (1 << 1) | 1;
/// `ESR1`'s error bits, cleared by a read: `BIT1ERR` to `STFERR`.
const ESR1_ERRORS: u32 = 0b11_1111 << 10;
const ESR1_BOFFINT: u32 = 1 << 2;
const ESR1_ERRINT: u32 = 1 << 1;
const ESR1_BOFFDONEINT: u32 = 1 << 19;
const ESR1_ACKERR: u32 = 1 << 13;
const ESR1_BIT0ERR: u32 = 1 << 14;

/// Where the module is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Phase {
    /// Module disable mode (`LPMACK`).
    Disabled,
    /// Freeze mode (`FRZACK`).
    Frozen,
    /// On the bus.
    Normal,
}

/// What the model counted; the driver's tests and harnesses read it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ModelStats {
    /// Frames stored into a receive buffer (overwrites included).
    pub rx_stored: u32,
    /// Frames lost: overwritten in a buffer not yet serviced, or in the serial message
    /// buffer.
    pub rx_lost: u32,
    /// Buffers that went from `FULL` to `OVERRUN` (each one is one overrun the driver
    /// can see).
    pub overrun_episodes: u32,
    /// Frames no receive buffer's filter took.
    pub rx_unmatched: u32,
    /// Frames on the wire while the module was not on the bus.
    pub rx_not_listening: u32,
    /// Frames sent.
    pub tx_sent: u32,
    /// Transmission attempts that failed.
    pub tx_failed: u32,
    /// Writes whose protected bits were left (not in freeze mode, or not disabled).
    pub ignored_writes: u32,
    /// `DATA` written to a buffer that was still pending.
    pub pending_overwrites: u32,
    /// `INACTIVE` written to a pending buffer (a deactivation).
    pub deactivations: u32,
    /// `INACTIVE` written to buffer 0 (ERR005829's workaround).
    pub reserved_inactive_writes: u32,
    /// Bus-off recoveries completed.
    pub recoveries: u32,
}

/// What became of a frame on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RxOutcome {
    /// Stored in this buffer.
    Stored(usize),
    /// Stored over an unserviced frame in this buffer, now `OVERRUN`.
    Overrun(usize),
    /// Waiting in the serial message buffer for this locked buffer.
    Held(usize),
    /// No filter matched.
    Unmatched,
    /// The module was not on the bus (disabled, frozen or bus-off): it neither received
    /// nor acknowledged the frame.
    NotListening,
}

#[derive(Debug, Clone, Copy, Default)]
struct Buffer {
    cs: u32,
    id: u32,
    data: [u32; 2],
    /// Receive: the control word was read since the frame moved in.
    serviced: bool,
    /// Transmit: an abort was asked for while the frame was on the wire.
    aborting: bool,
}

impl Buffer {
    fn code(&self) -> u32 {
        (self.cs >> 24) & 0xF
    }

    fn set_code(&mut self, code: u32) {
        self.cs = (self.cs & !(0xF << 24)) | (code << 24);
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wire {
    Tx(usize),
    Rx,
}

#[derive(Debug, Clone)]
struct State {
    mcr: u32,
    ctrl1: u32,
    ctrl2: u32,
    timer: u32,
    rxmgmask: u32,
    esr1: u32,
    imask1: u32,
    iflag1: u32,
    rximr: [u32; MAX_MAILBOXES],
    mb: [Buffer; MAX_MAILBOXES],
    phase: Phase,
    ack_countdown: u8,
    soft_reset_reads: Option<u8>,
    wire: Option<Wire>,
    locked: Option<usize>,
    /// The serial message buffer: a frame for a locked buffer, and whether a second one
    /// overwrote it.
    smb: Option<(usize, CanFrame, bool)>,
    errors: TransmitErrors,
    bus_off: bool,
    boffrec_negated: bool,
    sequences: u32,
    stats: ModelStats,
}

/// The FlexCAN module, register by register.
#[derive(Debug)]
pub struct FlexcanModel {
    state: RefCell<State>,
}

impl Default for FlexcanModel {
    fn default() -> Self {
        Self::new()
    }
}

fn bit<R: RegisterLongName>(value: u32, field: Field<u32, R>) -> bool {
    field.is_set(value)
}

impl FlexcanModel {
    /// The module out of reset.
    pub fn new() -> Self {
        Self {
            state: RefCell::new(State {
                mcr: MCR_RESET & !MCR_STATUS,
                ctrl1: 0,
                ctrl2: 0,
                timer: 0,
                rxmgmask: 0xFFFF_FFFF,
                esr1: 0,
                imask1: 0,
                iflag1: 0,
                rximr: [0xFFFF_FFFF; MAX_MAILBOXES],
                mb: [Buffer::default(); MAX_MAILBOXES],
                phase: Phase::Disabled,
                ack_countdown: 0,
                soft_reset_reads: None,
                wire: None,
                locked: None,
                smb: None,
                errors: TransmitErrors::new(),
                bus_off: false,
                boffrec_negated: false,
                sequences: 0,
                stats: ModelStats::default(),
            }),
        }
    }

    /// What the model counted.
    pub fn stats(&self) -> ModelStats {
        self.state.borrow().stats
    }

    /// Where the module is.
    pub fn phase(&self) -> Phase {
        self.state.borrow().phase
    }

    /// Whether the module is bus-off.
    pub fn is_bus_off(&self) -> bool {
        self.state.borrow().bus_off
    }

    /// Whether a bus-off module may recover once it has seen the recessive sequences:
    /// `CTRL1[BOFFREC]` clear, or negated by software during this bus-off.
    pub fn may_recover(&self) -> bool {
        let s = self.state.borrow();
        s.ctrl1 & CTRL1_BOFFREC == 0 || s.boffrec_negated
    }

    /// The transmit error counter.
    pub fn tec(&self) -> u16 {
        self.state.borrow().errors.tec()
    }

    /// Buffer `mb`'s code.
    pub fn code(&self, mb: usize) -> Option<u32> {
        self.state.borrow().mb.get(mb).map(Buffer::code)
    }

    /// The buffer locked by a read of its control word.
    pub fn locked(&self) -> Option<usize> {
        self.state.borrow().locked
    }

    /// The frame on the wire, if any, is this module's transmission from this buffer.
    pub fn transmitting(&self) -> Option<usize> {
        match self.state.borrow().wire {
            Some(Wire::Tx(mb)) => Some(mb),
            _ => None,
        }
    }

    /// Whether the module takes part in the bus: on it and not bus-off.
    pub fn is_on_bus(&self) -> bool {
        let s = self.state.borrow();
        s.phase == Phase::Normal && !s.bus_off
    }

    /// The frame the module would start now, and its buffer: the pending buffer with the
    /// lowest identifier (then the lowest number). `None` when it has none, is not on the
    /// bus, or a frame is already on the wire.
    pub fn offer(&self) -> Option<(usize, CanFrame)> {
        {
            let s = self.state.borrow();
            if s.phase != Phase::Normal || s.bus_off || s.wire.is_some() {
                return None;
            }
        }
        self.next_frame()
    }

    /// The frame the module would send next once on the bus, and its buffer: the pending
    /// buffer with the lowest identifier (then the lowest number), whatever the module's
    /// state (a bus that plans ahead asks it while the module is still recovering).
    pub fn next_frame(&self) -> Option<(usize, CanFrame)> {
        let s = self.state.borrow();
        let last = s.last();
        s.mb.iter()
            .enumerate()
            .take(last + 1)
            .filter(|(_, b)| b.code() == CODE_TX_DATA)
            .map(|(i, b)| (i, frame_of(b)))
            .min_by_key(|&(i, f)| (f.can_id().arbitration_key(), i))
    }

    /// The frame on the wire (another node's) ended in an error frame: nothing received.
    pub fn end_rx_failed(&self) {
        let mut s = self.state.borrow_mut();
        if s.wire == Some(Wire::Rx) {
            s.wire = None;
        }
        s.settle_phase();
    }

    /// Whether the interrupt line is raised: a buffer flag unmasked in `IMASK1`, or
    /// bus-off with `CTRL1[BOFFMSK]`.
    pub fn interrupt(&self) -> bool {
        let s = self.state.borrow();
        s.iflag1 & s.imask1 != 0 || (s.esr1 & ESR1_BOFFINT != 0 && s.ctrl1 & CTRL1_BOFFMSK != 0)
    }

    /// Buffer `mb`'s frame starts on the wire.
    pub fn begin_tx(&self, mb: usize) {
        self.state.borrow_mut().wire = Some(Wire::Tx(mb));
    }

    /// The frame on the wire from this module ended: sent, or failed with `failure`.
    pub fn end_tx(&self, failure: Option<Failure>) {
        let mut s = self.state.borrow_mut();
        let Some(Wire::Tx(mb)) = s.wire else {
            return;
        };
        s.wire = None;
        s.timer = s.timer.wrapping_add(1) & 0xFFFF;
        let timer = s.timer;
        match failure {
            None => {
                s.errors.sent();
                s.stats.tx_sent += 1;
                if let Some(b) = s.mb.get_mut(mb) {
                    b.aborting = false;
                    b.set_code(CODE_TX_INACTIVE);
                    b.cs = (b.cs & !0xFFFF) | timer;
                }
                s.iflag1 |= 1 << mb;
            }
            Some(failure) => {
                s.stats.tx_failed += 1;
                s.esr1 |= ESR1_ERRINT
                    | match failure {
                        Failure::NoAcknowledge => ESR1_ACKERR,
                        Failure::Error => ESR1_BIT0ERR,
                    };
                let state = s.errors.failed(failure);
                if let Some(b) = s.mb.get_mut(mb) {
                    if b.aborting {
                        b.aborting = false;
                        b.set_code(CODE_TX_ABORT);
                        s.iflag1 |= 1 << mb;
                    }
                }
                if state == ErrorState::BusOff && !s.bus_off {
                    s.bus_off = true;
                    s.sequences = 0;
                    s.boffrec_negated = false;
                    s.esr1 |= ESR1_BOFFINT;
                }
            }
        }
        s.settle_phase();
    }

    /// Another node's frame crosses the wire: what became of it here.
    pub fn receive(&self, frame: &CanFrame) -> RxOutcome {
        self.begin_rx();
        self.end_rx(frame)
    }

    /// Another node's frame starts on the wire.
    pub fn begin_rx(&self) {
        let mut s = self.state.borrow_mut();
        if s.wire.is_none() {
            s.wire = Some(Wire::Rx);
        }
    }

    /// Another node's frame on the wire ended.
    pub fn end_rx(&self, frame: &CanFrame) -> RxOutcome {
        let mut s = self.state.borrow_mut();
        if s.wire == Some(Wire::Rx) {
            s.wire = None;
        }
        let listening = s.phase == Phase::Normal && !s.bus_off;
        let outcome = if listening {
            s.timer = s.timer.wrapping_add(1) & 0xFFFF;
            s.deliver(frame)
        } else {
            s.stats.rx_not_listening += 1;
            RxOutcome::NotListening
        };
        s.settle_phase();
        outcome
    }

    /// The bus stayed idle for `sequences` sequences of 11 recessive bits: a bus-off
    /// module out of freeze mode counts them towards its recovery.
    pub fn idle(&self, sequences: u32) {
        let mut s = self.state.borrow_mut();
        s.settle_phase();
        let may_recover = s.ctrl1 & CTRL1_BOFFREC == 0 || s.boffrec_negated;
        if s.bus_off && s.phase == Phase::Normal {
            s.sequences = s.sequences.saturating_add(sequences);
            if may_recover && s.sequences >= RECOVERY_SEQUENCES {
                s.bus_off = false;
                s.errors.recovered();
                s.esr1 |= ESR1_BOFFDONEINT;
                s.stats.recoveries += 1;
            }
        }
    }
}

impl State {
    fn last(&self) -> usize {
        ((self.mcr & 0x7F) as usize).min(MAX_MAILBOXES - 1)
    }

    fn target(&self) -> Phase {
        if bit(self.mcr, MCR::MDIS) {
            Phase::Disabled
        } else if bit(self.mcr, MCR::FRZ) && bit(self.mcr, MCR::HALT) {
            Phase::Frozen
        } else {
            Phase::Normal
        }
    }

    /// At the end of a frame (or on an idle bus) the module reaches the mode asked for.
    fn settle_phase(&mut self) {
        if self.wire.is_none() {
            self.phase = self.target();
        }
    }

    fn mcr_value(&self) -> u32 {
        let mut v = self.mcr & !MCR_STATUS;
        if self.phase == Phase::Disabled {
            v |= 1 << 20;
        }
        if self.phase == Phase::Frozen {
            v |= 1 << 24;
        }
        if self.phase != Phase::Normal {
            v |= 1 << 27;
        }
        if self.soft_reset_reads.is_some() {
            v |= 1 << 25;
        }
        v
    }

    fn read_mcr(&mut self) -> u32 {
        let value = self.mcr_value();
        if let Some(n) = self.soft_reset_reads {
            if self.phase != Phase::Disabled {
                self.soft_reset_reads = n.checked_sub(1).filter(|&left| left > 0);
            }
        }
        if self.phase != self.target() && self.wire.is_none() {
            if self.ack_countdown == 0 {
                self.phase = self.target();
            } else {
                self.ack_countdown -= 1;
            }
        }
        value
    }

    fn write_mcr(&mut self, value: u32) {
        let frozen = self.phase == Phase::Frozen;
        let mut next = value & !MCR_STATUS & !(1 << 25);
        if !frozen && (next ^ self.mcr) & MCR_FREEZE_ONLY != 0 {
            self.stats.ignored_writes += 1;
            next = (next & !MCR_FREEZE_ONLY) | (self.mcr & MCR_FREEZE_ONLY);
        }
        let old_target = self.target();
        self.mcr = next;
        if value & (1 << 25) != 0 {
            self.soft_reset();
        }
        if self.target() != old_target {
            self.ack_countdown = ACK_READS;
        }
    }

    fn soft_reset(&mut self) {
        self.mcr = (MCR_RESET & !MCR_STATUS & !(1 << 31)) | (self.mcr & (1 << 31));
        self.timer = 0;
        self.errors = TransmitErrors::new();
        self.bus_off = false;
        self.esr1 = 0;
        self.imask1 = 0;
        self.iflag1 = 0;
        self.soft_reset_reads = Some(1);
        self.ack_countdown = ACK_READS;
    }

    fn write_ctrl1(&mut self, value: u32) {
        let mut next = value;
        if self.phase != Phase::Frozen && (next ^ self.ctrl1) & CTRL1_FREEZE_ONLY != 0 {
            self.stats.ignored_writes += 1;
            next = (next & !CTRL1_FREEZE_ONLY) | (self.ctrl1 & CTRL1_FREEZE_ONLY);
        }
        if self.phase != Phase::Disabled && (next ^ self.ctrl1) & CTRL1_CLKSRC != 0 {
            self.stats.ignored_writes += 1;
            next = (next & !CTRL1_CLKSRC) | (self.ctrl1 & CTRL1_CLKSRC);
        }
        if self.bus_off && next & CTRL1_BOFFREC == 0 {
            self.boffrec_negated = true;
        }
        self.ctrl1 = next;
    }

    /// A write allowed only in freeze mode: done, or counted and left.
    fn frozen_write(&mut self, apply: impl FnOnce(&mut Self)) {
        if self.phase == Phase::Frozen {
            apply(self);
        } else {
            self.stats.ignored_writes += 1;
        }
    }

    fn esr1_value(&self) -> u32 {
        let fltconf = match self.errors.state() {
            _ if self.bus_off => 2,
            ErrorState::Active => 0,
            ErrorState::Passive => 1,
            ErrorState::BusOff => 2,
        };
        let idle = u32::from(self.wire.is_none()) << 7;
        let synch = u32::from(self.phase == Phase::Normal && !self.bus_off) << 18;
        self.esr1 | (fltconf << 4) | idle | synch
    }

    fn lock(&mut self, mb: Option<usize>) {
        if self.locked != mb {
            self.unlock();
            self.locked = mb;
        }
    }

    /// Unlocks the locked buffer: a frame waiting for it moves in.
    fn unlock(&mut self) {
        self.locked = None;
        if let Some((mb, frame, overran)) = self.smb.take() {
            self.store(mb, &frame, overran);
        }
    }

    fn write_cs(&mut self, mb: usize, value: u32) {
        let Some(b) = self.mb.get(mb).copied() else {
            return;
        };
        let new_code = (value >> 24) & 0xF;
        let pending = b.code() == CODE_TX_DATA;
        let on_wire = self.wire == Some(Wire::Tx(mb));
        let aen = bit(self.mcr, MCR::AEN);
        if mb == 0 && new_code == CODE_TX_INACTIVE {
            self.stats.reserved_inactive_writes += 1;
        }
        let Some(slot) = self.mb.get_mut(mb) else {
            return;
        };
        match new_code {
            CODE_TX_ABORT if pending && aen => {
                if on_wire {
                    slot.aborting = true;
                } else {
                    slot.set_code(CODE_TX_ABORT);
                    self.iflag1 |= 1 << mb;
                }
                return;
            }
            // Abort of a buffer that is no longer pending: its frame went out (its flag
            // says so); the write changes nothing.
            CODE_TX_ABORT if self.iflag1 & (1 << mb) != 0 => return,
            CODE_TX_DATA if pending => self.stats.pending_overwrites += 1,
            CODE_TX_INACTIVE if pending => self.stats.deactivations += 1,
            _ => {}
        }
        slot.cs = value;
        slot.aborting = false;
        slot.serviced = true;
    }

    fn read_cs(&mut self, mb: usize) -> u32 {
        let cs = self.mb.get(mb).map_or(0, |b| b.cs);
        let rx = matches!(
            (cs >> 24) & 0xF,
            CODE_RX_FULL | CODE_RX_OVERRUN | CODE_RX_EMPTY | CODE_RX_INACTIVE
        );
        if rx {
            self.lock(Some(mb));
            if let Some(b) = self.mb.get_mut(mb) {
                b.serviced = true;
            }
        } else {
            self.lock(None);
        }
        cs
    }

    fn matches(&self, mb: usize, frame: &CanFrame) -> bool {
        let Some(b) = self.mb.get(mb) else {
            return false;
        };
        if !matches!(b.code(), CODE_RX_EMPTY | CODE_RX_FULL | CODE_RX_OVERRUN) {
            return false;
        }
        let id = frame.can_id();
        if bit(b.cs, MB_CS::IDE) != id.is_extended() {
            return false;
        }
        let mask = if bit(self.mcr, MCR::IRMQ) {
            self.rximr.get(mb).copied().unwrap_or(0)
        } else {
            self.rxmgmask
        };
        ((id_word(id.raw(), id.is_extended()) ^ b.id) & mask & 0x1FFF_FFFF) == 0
    }

    fn deliver(&mut self, frame: &CanFrame) -> RxOutcome {
        let last = self.last();
        let mut free = None;
        let mut fallback = None;
        for mb in 0..=last {
            if !self.matches(mb, frame) {
                continue;
            }
            let b = self.mb.get(mb).copied().unwrap_or_default();
            if b.code() == CODE_RX_EMPTY || b.serviced {
                free = Some(mb);
                break;
            }
            fallback = Some(mb);
        }
        let Some(mb) = free.or(fallback) else {
            self.stats.rx_unmatched += 1;
            return RxOutcome::Unmatched;
        };
        if self.locked == Some(mb) {
            let overran = match self.smb.take() {
                Some(_) => {
                    self.stats.rx_lost += 1;
                    true
                }
                None => false,
            };
            self.smb = Some((mb, *frame, overran));
            return RxOutcome::Held(mb);
        }
        let overrun = free.is_none();
        self.store(mb, frame, overrun);
        if overrun {
            RxOutcome::Overrun(mb)
        } else {
            RxOutcome::Stored(mb)
        }
    }

    /// Moves `frame` into buffer `mb`; `overrun`: a frame not yet serviced is lost.
    fn store(&mut self, mb: usize, frame: &CanFrame, overrun: bool) {
        let timer = self.timer;
        let Some(b) = self.mb.get_mut(mb) else {
            return;
        };
        let lost_here =
            overrun && !b.serviced && matches!(b.code(), CODE_RX_FULL | CODE_RX_OVERRUN);
        let was_full = b.code() == CODE_RX_FULL;
        let id = frame.can_id();
        let code = if overrun {
            CODE_RX_OVERRUN
        } else {
            CODE_RX_FULL
        };
        b.cs = (code << 24)
            | (u32::from(id.is_extended()) << 21)
            | (u32::from(id.is_extended()) << 22)
            | (u32::from(frame.len()) << 16)
            | (timer & 0xFFFF);
        b.id = id_word(id.raw(), id.is_extended());
        b.data = data_words(frame.bytes());
        b.serviced = false;
        self.stats.rx_stored += 1;
        if lost_here {
            self.stats.rx_lost += 1;
            if was_full {
                self.stats.overrun_episodes += 1;
            }
        } else if overrun {
            // The SMB overflowed while the buffer was locked: one frame was lost there.
            self.stats.overrun_episodes += 1;
        }
        self.iflag1 |= 1 << mb;
    }
}

/// The frame held by a transmit buffer.
fn frame_of(b: &Buffer) -> CanFrame {
    let len = ((b.cs >> 16) & 0xF).min(8) as u8;
    CanFrame::masked(id_of(b.id, bit(b.cs, MB_CS::IDE)), len, data_bytes(b.data))
}

impl Access for FlexcanModel {
    fn read(&self, off: usize) -> u32 {
        let mut s = self.state.borrow_mut();
        if let Some((mb, word)) = mb_of(off) {
            return match word {
                0 => s.read_cs(mb),
                1 => s.mb.get(mb).map_or(0, |b| b.id),
                w => s.mb.get(mb).map_or(0, |b| b.data[(w - 2) & 1]),
            };
        }
        match off {
            offset::MCR => s.read_mcr(),
            offset::CTRL1 => s.ctrl1,
            offset::CTRL2 => s.ctrl2,
            offset::TIMER => {
                s.lock(None);
                s.timer
            }
            offset::RXMGMASK => s.rxmgmask,
            offset::ECR => u32::from(s.errors.tec().min(255)),
            offset::ESR1 => {
                let v = s.esr1_value();
                s.esr1 &= !ESR1_ERRORS;
                v
            }
            offset::IMASK1 => s.imask1,
            offset::IFLAG1 => s.iflag1,
            o if (offset::RXIMR0..offset::RXIMR0 + 4 * MAX_MAILBOXES).contains(&o) => {
                s.rximr.get((o - offset::RXIMR0) / 4).copied().unwrap_or(0)
            }
            _ => 0,
        }
    }

    fn write(&self, off: usize, value: u32) {
        let mut s = self.state.borrow_mut();
        if let Some((mb, word)) = mb_of(off) {
            match word {
                0 => s.write_cs(mb, value),
                1 => {
                    if let Some(b) = s.mb.get_mut(mb) {
                        b.id = value;
                    }
                }
                w => {
                    if let Some(b) = s.mb.get_mut(mb) {
                        b.data[(w - 2) & 1] = value;
                    }
                }
            }
            return;
        }
        match off {
            offset::MCR => s.write_mcr(value),
            offset::CTRL1 => s.write_ctrl1(value),
            offset::CTRL2 => s.frozen_write(|s| s.ctrl2 = value),
            offset::TIMER => s.timer = value & 0xFFFF,
            offset::RXMGMASK => s.frozen_write(|s| s.rxmgmask = value),
            offset::ESR1 => s.esr1 &= !(value & ESR1_W1C),
            offset::IMASK1 => s.imask1 = value,
            offset::IFLAG1 => s.iflag1 &= !value,
            o if (offset::RXIMR0..offset::RXIMR0 + 4 * MAX_MAILBOXES).contains(&o) => {
                let i = (o - offset::RXIMR0) / 4;
                s.frozen_write(|s| {
                    if let Some(m) = s.rximr.get_mut(i) {
                        *m = value;
                    }
                });
            }
            _ => {}
        }
    }
}
