//! The driver's contract over the model, for the tests, the `flexcan_mailboxes` fuzz
//! target and the Kani harness: any sequence of the stack's calls and the bus's events
//! keeps the message-buffer promises.
//!
//! - **No frame reported sent that was not**: every `TxConfirmation` names a PDU whose
//!   frame the model put on the wire successfully, and is reported at most once.
//! - **One owner per buffer**: the driver never stores `DATA` over a pending buffer nor
//!   deactivates one, and a buffer the driver counts free is not pending in the module.
//! - **No received frame lost uncounted**: every frame the module stored is reported,
//!   still waiting in its buffer, or lost in an overrun the driver counted; once the
//!   events are drained the driver has counted every overrun the module had.
//! - **Configuration only in freeze mode**: the model ignored no write of the driver.

use cw_core::can::confinement::Failure;
use cw_core::can::{CanDriver, CanFrame, CanId, ControllerConfig, ControllerMode, Hrh, Hth};

use super::driver::{ClockSource, Flexcan, FlexcanConfig, FlexcanEvent, RxFilter, TxSlot};
use super::model::{FlexcanModel, RxOutcome};

/// One step of the harness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// `Can_Write` on HTH `hth % 2` with identifier `id` (standard, or extended when
    /// `extended`) and `len` bytes.
    Write {
        /// The HTH.
        hth: u8,
        /// The identifier's bits.
        id: u32,
        /// An extended identifier.
        extended: bool,
        /// The data length.
        len: u8,
    },
    /// `Can_AbortTransmission`-like withdrawal of HTH `hth % 2`'s frames.
    Abort(u8),
    /// `Can_SetControllerMode`.
    Mode(ControllerMode),
    /// The module's next frame goes on the wire; it ends now (`Some(ok)`) or stays on
    /// the wire (`None`) until the next `EndTx`.
    Transmit(Option<bool>),
    /// The frame on the wire from the module ends: sent (`true`) or failed.
    EndTx(bool),
    /// Another node's frame with this identifier and length crosses the wire.
    Receive {
        /// The identifier's bits.
        id: u32,
        /// An extended identifier.
        extended: bool,
        /// The data length.
        len: u8,
    },
    /// The bus stays idle for this many sequences of 11 recessive bits.
    Idle(u8),
    /// The interrupt handler runs: every event taken.
    Drain,
    /// One event taken.
    TakeOne,
}

/// The receive filters the harness configures: one exact standard id, one exact
/// extended id, a catch-all for standard ids.
pub const FILTERS: [RxFilter; 3] = [
    RxFilter::exact(CanId::masked(0x123, false), Hrh(0)),
    RxFilter::exact(CanId::masked(0x001A_BCDE, true), Hrh(1)),
    RxFilter::any(Hrh(2), false),
];

/// Two HTHs: two buffers, one buffer.
pub const TX: [u8; 2] = [2, 1];

/// The harness's configuration (8 MHz oscillator, as the S32K144EVB's).
pub const CONFIG: FlexcanConfig<'static> = FlexcanConfig {
    clock_source: ClockSource::Oscillator,
    clock_hz: 8_000_000,
    mailboxes: 16,
    rx: &FILTERS,
    tx: &TX,
    init_polls: super::driver::INIT_POLLS,
};

/// 500 kbit/s, sample point 87.5 %.
pub const BITRATE: ControllerConfig = ControllerConfig {
    bitrate: 500_000,
    sample_permille: 875,
};

fn frame(id: u32, extended: bool, len: u8) -> CanFrame {
    let data = [len, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77];
    CanFrame::masked(CanId::masked(id, extended), len, data)
}

/// What the harness saw.
#[derive(Debug)]
struct Books {
    /// The PDU of each write the driver took, by PDU number: its frame.
    written: [Option<CanFrame>; 64],
    next_pdu: u16,
    /// PDUs whose frame the model sent.
    sent: u64,
    /// PDUs confirmed.
    confirmed: u64,
    /// Frames the driver reported received.
    received: u32,
}

/// Runs `ops` on the driver over a fresh model (initialised, then started) and checks
/// the promises after every step; false at the first broken one.
pub fn mailboxes_keep_their_promises(ops: &[Op]) -> bool {
    let Ok(mut can) = Flexcan::new(FlexcanModel::new(), &CONFIG) else {
        return false;
    };
    if can.init(&BITRATE).is_err() || can.set_controller_mode(ControllerMode::Started).is_err() {
        return false;
    }
    let mut books = Books {
        written: [None; 64],
        next_pdu: 0,
        sent: 0,
        confirmed: 0,
        received: 0,
    };
    // The PDU of the frame on the wire from each buffer, as the driver wrote it.
    let mut on_wire: Option<(usize, CanFrame)> = None;
    for &op in ops.iter().take(64) {
        match op {
            Op::Write {
                hth,
                id,
                extended,
                len,
            } => {
                let pdu = books.next_pdu;
                let f = frame(id, extended, len);
                if can.write(Hth(hth % 2), pdu, &f).is_ok() {
                    if let Some(slot) = books.written.get_mut(usize::from(pdu)) {
                        *slot = Some(f);
                    }
                    books.next_pdu += 1;
                }
            }
            Op::Abort(hth) => can.abort(Hth(hth % 2)),
            Op::Mode(mode) => {
                let _ = can.set_controller_mode(mode);
            }
            Op::Transmit(end) => {
                let model = can.registers().access();
                if on_wire.is_none() {
                    if let Some((mb, f)) = model.offer() {
                        model.begin_tx(mb);
                        on_wire = Some((mb, f));
                    }
                }
                if let Some(ok) = end {
                    end_tx(&can, &mut on_wire, &mut books, ok);
                }
            }
            Op::EndTx(ok) => end_tx(&can, &mut on_wire, &mut books, ok),
            Op::Receive { id, extended, len } => {
                if on_wire.is_none() {
                    let _: RxOutcome = can.registers().access().receive(&frame(id, extended, len));
                }
            }
            Op::Idle(n) => {
                if on_wire.is_none() {
                    can.registers().access().idle(u32::from(n));
                }
            }
            Op::Drain => {
                while let Some(e) = can.take_event() {
                    if !account(&mut books, e) {
                        return false;
                    }
                }
            }
            Op::TakeOne => {
                if let Some(e) = can.take_event() {
                    if !account(&mut books, e) {
                        return false;
                    }
                }
            }
        }
        if !owners_agree(&can) {
            return false;
        }
    }
    // Drain: every stored frame is then reported or counted lost.
    if let Some((_, _)) = on_wire {
        end_tx(&can, &mut on_wire, &mut books, true);
    }
    while let Some(e) = can.take_event() {
        if !account(&mut books, e) {
            return false;
        }
    }
    let model = can.registers().access().stats();
    let driver = can.stats();
    books.confirmed & !books.sent == 0
        && model.rx_stored == books.received + model.rx_lost
        && driver.rx_overruns == model.overrun_episodes
        && model.ignored_writes == 0
        && owners_agree(&can)
}

/// The frame on the wire ends; if it was sent, the PDU the driver wrote it with is
/// marked sent (when the buffer holds exactly the frame that PDU wrote).
fn end_tx(
    can: &Flexcan<FlexcanModel>,
    on_wire: &mut Option<(usize, CanFrame)>,
    books: &mut Books,
    ok: bool,
) {
    let Some((mb, f)) = on_wire.take() else {
        return;
    };
    can.registers()
        .access()
        .end_tx(if ok { None } else { Some(Failure::Error) });
    if ok {
        if let TxSlot::Sending(pdu) | TxSlot::Aborting(pdu) = can.tx_slot(mb) {
            let written = books.written.get(usize::from(pdu)).copied().flatten();
            if written == Some(f) && pdu < 64 {
                books.sent |= 1 << pdu;
            }
        }
    }
}

/// Books one event; false if it breaks a promise.
fn account(books: &mut Books, event: FlexcanEvent) -> bool {
    match event {
        FlexcanEvent::TxConfirmation(pdu) => {
            let bit = 1u64.checked_shl(u32::from(pdu)).unwrap_or(0);
            let fresh = bit != 0 && books.sent & bit != 0 && books.confirmed & bit == 0;
            books.confirmed |= bit;
            fresh
        }
        FlexcanEvent::Received(..) => {
            books.received += 1;
            true
        }
        FlexcanEvent::BusOff | FlexcanEvent::ModeIndication(_) => true,
    }
}

/// The driver's free buffers are not pending in the module, and the module saw no
/// second owner.
fn owners_agree(can: &Flexcan<FlexcanModel>) -> bool {
    let model = can.registers().access();
    let stats = model.stats();
    let free_not_pending = (0..=can.layout().last())
        .all(|mb| can.tx_slot(mb) != TxSlot::Free || model.code(mb) != Some(0b1100));
    stats.pending_overwrites == 0 && stats.deactivations == 0 && free_not_pending
}

/// Decodes fuzzer bytes into harness steps (three bytes a step).
pub fn decode(bytes: &[u8]) -> impl Iterator<Item = Op> + '_ {
    bytes.chunks_exact(3).map(|chunk| {
        let &[a, b, c] = chunk else {
            return Op::Drain;
        };
        match a % 12 {
            0 | 1 => Op::Write {
                hth: b & 1,
                id: u32::from(c) << 3 | u32::from(b >> 5),
                extended: b & 2 != 0,
                len: (b >> 2) % 9,
            },
            2 => Op::Abort(b),
            3 => Op::Mode(match b % 3 {
                0 => ControllerMode::Started,
                1 => ControllerMode::Stopped,
                _ => ControllerMode::Sleep,
            }),
            4 | 5 => Op::Transmit(match b % 3 {
                0 => None,
                1 => Some(true),
                _ => Some(false),
            }),
            6 => Op::EndTx(b % 4 != 0),
            7 | 8 => Op::Receive {
                id: match c % 4 {
                    0 => 0x123,
                    1 => 0x001A_BCDE,
                    _ => u32::from(b) << 3,
                },
                extended: c % 4 == 1 || (c % 4 == 3 && b & 1 != 0),
                len: c % 9,
            },
            9 => Op::Idle(b),
            10 => Op::Drain,
            _ => Op::TakeOne,
        }
    })
}
