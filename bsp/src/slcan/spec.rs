//! The controller's contract over a model UART, for the tests and the `slcan_controller`
//! fuzz target (host only: the model keeps its bytes in `std` collections).

extern crate std;

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

use super::{ByteUart, SlcanBoard, SlcanBus, SlcanCan, SlcanEvent};
use cw_core::can::{slcan, CanDriver, CanFrame, CanId, ControllerMode, Hth, ModeChange};

std::thread_local! {
    static NOW_US: Cell<u64> = const { Cell::new(0) };
}

/// The model's board: time stands still unless a test moves it.
pub struct ModelBoard;

impl SlcanBoard for ModelBoard {
    fn now_ms() -> u64 {
        NOW_US.with(Cell::get) / 1000
    }
    fn now_us() -> u64 {
        NOW_US.with(Cell::get)
    }
}

/// Sets the model board's time, ms (this thread's).
pub fn set_ms(ms: u64) {
    NOW_US.with(|t| t.set(ms * 1000));
}

/// What the model UART saw and holds.
#[derive(Debug, Default)]
pub struct Wire {
    /// Bytes the controller sent.
    pub sent: Vec<u8>,
    /// Bytes waiting to be received.
    pub incoming: VecDeque<u8>,
    /// Bytes the transmitter takes before it is full.
    pub room: usize,
    /// The controller asked for its interrupt work.
    pub service_requested: bool,
    /// Times it said nothing was left to send.
    pub idles: u32,
}

/// A UART in memory, shared with the test that watches it.
#[derive(Debug, Clone, Default)]
pub struct ModelUart(pub Rc<RefCell<Wire>>);

impl ByteUart for ModelUart {
    fn tx_ready(&self) -> bool {
        self.0.borrow().room > 0
    }
    fn write_byte(&mut self, byte: u8) {
        let mut w = self.0.borrow_mut();
        w.sent.push(byte);
        w.room = w.room.saturating_sub(1);
    }
    fn read_byte(&mut self) -> Option<u8> {
        self.0.borrow_mut().incoming.pop_front()
    }
    fn clear_interrupts(&mut self) {}
    fn tx_idle(&mut self) {
        self.0.borrow_mut().idles += 1;
    }
    fn request_service(&mut self) {
        self.0.borrow_mut().service_requested = true;
    }
}

/// The controller on the model.
pub type ModelController = SlcanCan<ModelUart, ModelBoard>;

/// A started controller on a model UART with unlimited room, on `bus`.
pub fn started(bus: &'static SlcanBus) -> (ModelController, ModelUart) {
    let uart = ModelUart::default();
    uart.0.borrow_mut().room = usize::MAX;
    let mut c = SlcanCan::new(uart.clone(), bus);
    let _ = c.set_controller_mode(ControllerMode::Started);
    (c, uart)
}

/// Every event the interrupt work gives now.
pub fn events(c: &mut ModelController) -> Vec<SlcanEvent> {
    std::iter::from_fn(|| c.take_event()).collect()
}

/// Runs `ops` (each `(op, a, b)`: a write, a received byte, the transmitter's room, the
/// interrupt work, a stop or a start) and checks:
/// - every confirmation is of an accepted frame, once, in order, and its line went out
///   whole; with no stop among the operations, every accepted frame is confirmed and the
///   frame lines that went out are the accepted frames, in order;
/// - the UART never carries half a line: a stop during a line lets it finish;
/// - every stop the controller could not reach at once is indicated exactly once, when
///   the line is out, and no other mode is ever indicated.
pub fn operations_confirm_each_frame_once(ops: &[(u8, u8, u8)]) -> bool {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = started(&BUS);
    let mut accepted: Vec<(u16, CanFrame)> = Vec::new();
    let mut confirmed: Vec<u16> = Vec::new();
    let mut stops = 0u32;
    let mut pending_stops = 0u32;
    let mut indications = 0u32;
    let mut only_stops_indicated = true;
    let mut take = |c: &mut ModelController, confirmed: &mut Vec<u16>| {
        for e in events(c) {
            match e {
                SlcanEvent::TxConfirmation(p) => confirmed.push(p),
                SlcanEvent::ModeIndication(m) => {
                    indications += 1;
                    only_stops_indicated &= m == ControllerMode::Stopped;
                }
                SlcanEvent::Received(_) | SlcanEvent::BusOff => {}
            }
        }
    };
    for (i, &(op, a, b)) in ops.iter().enumerate() {
        match op % 6 {
            0 => {
                let id = CanId::masked(u32::from(a) << 3 | u32::from(b % 8), false);
                let f = CanFrame::masked(id, 2, [a, b, 0, 0, 0, 0, 0, 0]);
                let pdu = i as u16;
                if c.write(Hth(0), pdu, &f).is_ok() {
                    accepted.push((pdu, f));
                }
            }
            1 => uart.0.borrow_mut().incoming.push_back(a),
            2 => uart.0.borrow_mut().room = usize::from(a % 40),
            3 => take(&mut c, &mut confirmed),
            4 => {
                stops += 1;
                let already = c.switching_to.is_some();
                if c.set_controller_mode(ControllerMode::Stopped) == Ok(ModeChange::Pending)
                    && !already
                {
                    pending_stops += 1;
                }
            }
            _ => {
                let _ = c.set_controller_mode(ControllerMode::Started);
            }
        }
    }
    uart.0.borrow_mut().room = usize::MAX;
    take(&mut c, &mut confirmed);
    let sent = uart.0.borrow().sent.clone();
    let lines: Vec<CanFrame> = sent
        .split(|&b| b == b'\r' || b == slcan::ERROR_REPLY[0])
        .filter_map(|l| slcan::parse_adapter_line(l).ok().map(|(f, _)| f))
        .collect();
    let whole_lines = sent
        .last()
        .is_none_or(|&b| b == b'\r' || b == slcan::ERROR_REPLY[0]);
    // Confirmed PDUs: accepted ones, in order, each once; their frames among the lines.
    let mut rest = accepted.iter();
    let confirmed_frames: Option<Vec<CanFrame>> = confirmed
        .iter()
        .map(|&p| rest.find(|a| a.0 == p).map(|a| a.1))
        .collect();
    let Some(confirmed_frames) = confirmed_frames else {
        return false;
    };
    let mut out = lines.iter();
    let lines_out = confirmed_frames.iter().all(|f| out.any(|l| l == f));
    let all_confirmed = stops > 0 || {
        let pdus: Vec<u16> = accepted.iter().map(|a| a.0).collect();
        let frames: Vec<CanFrame> = accepted.iter().map(|a| a.1).collect();
        confirmed == pdus && lines == frames
    };
    lines_out
        && all_confirmed
        && whole_lines
        && indications == pending_stops
        && only_stops_indicated
        && c.switching_to.is_none()
}
