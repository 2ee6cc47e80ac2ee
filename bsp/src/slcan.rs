//! A CAN controller over any byte UART, speaking SLCAN (Lawicel): what a board without a
//! CAN controller of its own (QEMU's mps2-an386) offers the ECU as its CAN driver, and
//! what the next such board reuses. The board gives it a [`ByteUart`] and a
//! [`SlcanBoard`] (its time, its trace marks); the bus around it (its counters and the
//! faults a scenario plays) is a [`SlcanBus`], a `static` of atomics.
//!
//! Frames `Can_Write` accepts go to a one-frame mailbox; the controller's interrupt work
//! ([`SlcanCan::take_event`], run by the ECU's `CanIsr`) encodes the line, feeds the UART
//! while it takes bytes, confirms the frame when its last character has left, decodes
//! received lines and answers commands, as a Lawicel adapter does. The host tests run it
//! over a model UART.

use core::sync::atomic::{AtomicU32, Ordering};

use cw_core::can::confinement::{ErrorState, Failure, TransmitErrors};
use cw_core::can::timing::{self, Stuffing};
use cw_core::can::{
    slcan, CanBusy, CanDriver, CanFrame, CanId, ControllerConfig, ControllerMode, ErrorCounters,
    Hth, InitRefused, ModeChange, ModeRefused,
};

#[cfg(feature = "host")]
pub mod spec;
#[cfg(test)]
mod tests;

/// A UART the controller talks through.
pub trait ByteUart {
    /// The transmitter takes a byte now.
    fn tx_ready(&self) -> bool;
    /// Hands `byte` to the transmitter (when [`ByteUart::tx_ready`]).
    fn write_byte(&mut self, byte: u8);
    /// The received byte, if one is there.
    fn read_byte(&mut self) -> Option<u8>;
    /// Acknowledges the UART's interrupts.
    fn clear_interrupts(&mut self);
    /// Nothing is left to send: the transmit interrupt acknowledged and withdrawn (it
    /// would only run the interrupt work again for nothing).
    fn tx_idle(&mut self);
    /// Requests the controller's interrupt work (the UART's transmit interrupt): a frame
    /// is in the mailbox.
    fn request_service(&mut self);
}

/// What the controller needs of the board besides its UART.
pub trait SlcanBoard {
    /// Milliseconds since start (frame time stamps).
    fn now_ms() -> u64;
    /// Microseconds since start (the bus-fault model's bus times).
    fn now_us() -> u64;
    /// `Can_Write` starts (`true`) or ends: a trace mark, if the board measures it.
    fn mark_write(_start: bool) {}
}

/// A CAN controller event of [`SlcanCan`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlcanEvent {
    /// The frame of this PDU has left the UART.
    TxConfirmation(u16),
    /// A frame arrived (an SLCAN `t`/`T` line from the other end, or a tester's frame
    /// put on the bus with [`SlcanBus::put_frame`]).
    Received(CanFrame),
    /// The controller went bus-off (more than 255 in its transmit error counter): its
    /// frame is dropped without confirmation and it is stopped until restarted.
    BusOff,
    /// The controller reached a mode it could not reach at once: a stop asked for while a
    /// frame's line was on the UART takes effect when the line's last character has left.
    ModeIndication(ControllerMode),
}

/// What the SLCAN link has counted since start-up.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SlcanStats {
    /// Frames received and handed to `CanIsr`.
    pub rx_frames: u32,
    /// Commands (`O`, `C`, `Sn`, `V`, ...) answered.
    pub rx_commands: u32,
    /// Lines refused (malformed or unsupported), each answered with BEL.
    pub rx_malformed: u32,
    /// Frames dropped because `CanIsr` had not yet taken the earlier ones.
    pub rx_overruns: u32,
    /// Replies not sent because the reply queue was full.
    pub replies_dropped: u32,
    /// Tester frames put on the bus ([`SlcanBus::put_frame`]) and received.
    pub bus_frames: u32,
    /// Transmission attempts that failed ([`SlcanBus::inject_tx_errors`]).
    pub tx_errors: u32,
    /// Times the controller went bus-off.
    pub bus_offs: u32,
}

fn count(counter: &AtomicU32) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// Whether the controller plays the bus's faults (cw-bsp's feature `bus-faults`, for the
/// scenario images): injected transmit errors with their error counter, bus-off and its
/// recovery time, and tester frames put on the bus. A UART has no bus to fail, so the
/// production image leaves the model out; the ECU's own handling (CanSM) stays.
const BUS_FAULTS: bool = cfg!(feature = "bus-faults");

/// The bus's bit time, ns: 500 kbit/s, the ECU's CAN bitrate (as on the host's simulated
/// bus). Failed attempts, error frames and bus-off recovery take bus time in bits.
const BIT_NS: u64 = 2000;

/// The bus around one SLCAN controller, shared with whoever plays its faults (a
/// scenario's tick) and reads its counters (a report): every field an atomic, so a
/// `static` of it is reached from any context without a lock.
pub struct SlcanBus {
    /// Transmission attempts of the controller that the bus will fail next.
    injected_tx_errors: AtomicU32,
    /// Tester frames on the bus, not yet taken by the controller: a ring of one
    /// producer (the tick) and one consumer (the controller's interrupt work).
    frames: [FrameCell; RX_QUEUE],
    frames_head: AtomicU32,
    frames_tail: AtomicU32,
    /// The ms at which the controller's delayed transmission or bus-off is due
    /// (0: none; a deferral is always due after 0 ms).
    deferred_due_ms: AtomicU32,
    rx_frames: AtomicU32,
    rx_commands: AtomicU32,
    rx_malformed: AtomicU32,
    rx_overruns: AtomicU32,
    replies_dropped: AtomicU32,
    bus_frames: AtomicU32,
    tx_errors: AtomicU32,
    bus_offs: AtomicU32,
}

/// One frame of the tester ring, as words: the raw id with its format (bit 31:
/// extended), the length, and the data.
struct FrameCell {
    id: AtomicU32,
    len: AtomicU32,
    data: [AtomicU32; 2],
}

impl FrameCell {
    const fn empty() -> Self {
        Self {
            id: AtomicU32::new(0),
            len: AtomicU32::new(0),
            data: [AtomicU32::new(0), AtomicU32::new(0)],
        }
    }

    fn store(&self, frame: &CanFrame) {
        let id = frame.can_id();
        let raw = id.raw() | if id.is_extended() { 1 << 31 } else { 0 };
        self.id.store(raw, Ordering::Relaxed);
        self.len
            .store(frame.bytes().len() as u32, Ordering::Relaxed);
        let mut data = [0u8; 8];
        if let Some(dst) = data.get_mut(..frame.bytes().len()) {
            dst.copy_from_slice(frame.bytes());
        }
        let [a, b, c, d, e, f, g, h] = data;
        let [low, high] = &self.data;
        low.store(u32::from_le_bytes([a, b, c, d]), Ordering::Relaxed);
        high.store(u32::from_le_bytes([e, f, g, h]), Ordering::Relaxed);
    }

    fn load(&self) -> CanFrame {
        let raw = self.id.load(Ordering::Relaxed);
        let [low, high] = &self.data;
        let [a, b, c, d] = low.load(Ordering::Relaxed).to_le_bytes();
        let [e, f, g, h] = high.load(Ordering::Relaxed).to_le_bytes();
        let len = self.len.load(Ordering::Relaxed) as u8;
        CanFrame::masked(
            CanId::masked(raw & !(1 << 31), raw & (1 << 31) != 0),
            len,
            [a, b, c, d, e, f, g, h],
        )
    }
}

impl SlcanBus {
    /// A quiet bus: no fault injected, no tester frame, every counter 0.
    pub const fn new() -> Self {
        Self {
            injected_tx_errors: AtomicU32::new(0),
            frames: [const { FrameCell::empty() }; RX_QUEUE],
            frames_head: AtomicU32::new(0),
            frames_tail: AtomicU32::new(0),
            deferred_due_ms: AtomicU32::new(0),
            rx_frames: AtomicU32::new(0),
            rx_commands: AtomicU32::new(0),
            rx_malformed: AtomicU32::new(0),
            rx_overruns: AtomicU32::new(0),
            replies_dropped: AtomicU32::new(0),
            bus_frames: AtomicU32::new(0),
            tx_errors: AtomicU32::new(0),
            bus_offs: AtomicU32::new(0),
        }
    }

    /// What the link has counted since start-up.
    pub fn stats(&self) -> SlcanStats {
        SlcanStats {
            rx_frames: self.rx_frames.load(Ordering::Relaxed),
            rx_commands: self.rx_commands.load(Ordering::Relaxed),
            rx_malformed: self.rx_malformed.load(Ordering::Relaxed),
            rx_overruns: self.rx_overruns.load(Ordering::Relaxed),
            replies_dropped: self.replies_dropped.load(Ordering::Relaxed),
            bus_frames: self.bus_frames.load(Ordering::Relaxed),
            tx_errors: self.tx_errors.load(Ordering::Relaxed),
            bus_offs: self.bus_offs.load(Ordering::Relaxed),
        }
    }

    /// Whether the controller's delayed transmission or bus-off is due at `now_ms` (the
    /// board's tick then raises the controller's interrupt).
    pub fn deferred_due(&self, now_ms: u64) -> bool {
        let due = self.deferred_due_ms.load(Ordering::Relaxed);
        BUS_FAULTS && due != 0 && now_ms >= u64::from(due)
    }

    /// Fault injection (a scenario's `can-errors`): the controller's next `count`
    /// transmission attempts fail, each raising its transmit error counter by 8 and
    /// taking the bus up to the ACK slot plus an error frame, before the automatic
    /// retransmission.
    pub fn inject_tx_errors(&self, count: u32) {
        let _ = self
            .injected_tx_errors
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
                Some(n.saturating_add(count))
            });
    }

    /// Takes one injected error for an attempt, if any is left.
    fn take_injected_error(&self) -> bool {
        self.injected_tx_errors
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
            .is_ok()
    }

    /// A tester's frame on the bus (a scenario's `frame`; one producer): the controller
    /// receives it in its next interrupt work, which the board raises. A frame that finds
    /// the ring full is an overrun.
    pub fn put_frame(&self, frame: &CanFrame) {
        let tail = self.frames_tail.load(Ordering::Relaxed);
        if tail.wrapping_sub(self.frames_head.load(Ordering::Acquire)) as usize >= RX_QUEUE {
            count(&self.rx_overruns);
            return;
        }
        if let Some(cell) = self.frames.get(tail as usize % RX_QUEUE) {
            cell.store(frame);
        }
        self.frames_tail
            .store(tail.wrapping_add(1), Ordering::Release);
    }

    /// The oldest tester frame (one consumer: the controller's interrupt work).
    fn take_frame(&self) -> Option<CanFrame> {
        let head = self.frames_head.load(Ordering::Relaxed);
        if head == self.frames_tail.load(Ordering::Acquire) {
            return None;
        }
        let frame = self
            .frames
            .get(head as usize % RX_QUEUE)
            .map(FrameCell::load);
        self.frames_head
            .store(head.wrapping_add(1), Ordering::Release);
        frame
    }
}

impl Default for SlcanBus {
    fn default() -> Self {
        Self::new()
    }
}

const _: () = assert!(
    slcan::TIMESTAMP_MODULUS <= u16::MAX as u32,
    "the time stamp's modulus fits the 32-bit remainder"
);

/// A transmission the bus holds back (failed attempts first, or bus-off recovery).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Deferred {
    /// The frame goes out when its successful attempt ends, µs.
    Send { frame: CanFrame, due_us: u64 },
    /// The last failed attempt took the counter above 255, µs.
    BusOff { due_us: u64 },
}

impl Deferred {
    const fn due_us(&self) -> u64 {
        match *self {
            Self::Send { due_us, .. } | Self::BusOff { due_us } => due_us,
        }
    }
}

/// Received frames waiting for `CanIsr`.
const RX_QUEUE: usize = 4;
/// Reply bytes waiting for the UART.
const REPLY_QUEUE: usize = 32;

/// Where the transmitter takes its next character from: it finishes one line before
/// starting another, so a reply never lands inside a frame's line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TxSource {
    Idle,
    Frame,
    Reply,
}

/// A CAN controller on a UART speaking SLCAN (`cw_core::can::slcan`): transmitted
/// frames go out as `t`/`T` lines, time-stamped with the OS time of `Can_Write` in ms
/// (Lawicel `Z1`, on from reset; `Z0` turns it off); received lines are decoded, frames queued for
/// `CanIsr`, commands answered as a Lawicel adapter answers them, malformed lines
/// counted and answered with BEL. The channel commands (`O`, `C`, `Sn`) are acknowledged
/// but change nothing: the UART is the bus itself, always open.
pub struct SlcanCan<U, B: 'static> {
    uart: U,
    bus: &'static SlcanBus,
    board: core::marker::PhantomData<B>,
    mode: ControllerMode,
    /// The mailbox: a frame `Can_Write` accepted, with its time stamp, that the transmit
    /// interrupt has not yet turned into a line.
    mailbox: Option<(CanFrame, Option<u64>)>,
    /// The line being sent and how far.
    line: [u8; slcan::FRAME_LINE_MAX],
    len: usize,
    sent: usize,
    pdu: Option<u16>,
    /// A confirmation waiting for `CanIsr`.
    confirmed: Option<u16>,
    source: TxSource,
    /// Frame lines carry the time stamp (Lawicel `Z1`, on from reset here).
    timestamps: bool,
    /// The bus's bitrate (`Can_Init`), a Lawicel adapter's.
    bitrate: u32,
    decoder: slcan::Decoder,
    rx: [Option<CanFrame>; RX_QUEUE],
    rx_head: usize,
    replies: [u8; REPLY_QUEUE],
    reply_head: usize,
    reply_len: usize,
    /// The transmit error counter.
    errors: TransmitErrors,
    /// Bus-off, not yet restarted.
    bus_off: bool,
    /// A bus-off `CanIsr` has not yet taken.
    bus_off_event: bool,
    /// After a restart from bus-off: no attempt before this time, µs (0: none).
    recovery_end_us: u64,
    /// A transmission the bus holds back.
    deferred: Option<Deferred>,
    /// The mode a stop (or sleep) asked for during a line takes when the line is out.
    switching_to: Option<ControllerMode>,
    /// A mode reached late, not yet indicated to `CanIsr`.
    mode_event: Option<ControllerMode>,
}

impl<U: ByteUart, B: SlcanBoard> SlcanCan<U, B> {
    /// The controller on `uart` (set up, its interrupts on), on the bus `bus`.
    pub const fn new(uart: U, bus: &'static SlcanBus) -> Self {
        Self {
            uart,
            bus,
            board: core::marker::PhantomData,
            mode: ControllerMode::Stopped,
            mailbox: None,
            line: [0; slcan::FRAME_LINE_MAX],
            len: 0,
            sent: 0,
            pdu: None,
            confirmed: None,
            source: TxSource::Idle,
            timestamps: true,
            bitrate: 500_000,
            decoder: slcan::Decoder::new(),
            rx: [None; RX_QUEUE],
            rx_head: 0,
            replies: [0; REPLY_QUEUE],
            reply_head: 0,
            reply_len: 0,
            errors: TransmitErrors::new(),
            bus_off: false,
            bus_off_event: false,
            recovery_end_us: 0,
            deferred: None,
            switching_to: None,
            mode_event: None,
        }
    }

    /// Cancels the pending transmission: no confirmation. A line already on the wire is
    /// finished, so the other end never sees half a line.
    fn withdraw(&mut self) {
        self.pdu = None;
        self.mailbox = None;
        self.deferred = None;
        self.bus.deferred_due_ms.store(0, Ordering::Relaxed);
        if self.source != TxSource::Frame {
            self.len = 0;
            self.sent = 0;
        }
    }

    /// The bitrate `init` took (500 kbit/s until then).
    pub const fn bitrate(&self) -> u32 {
        self.bitrate
    }

    /// The bus (its counters, its faults).
    pub const fn bus(&self) -> &'static SlcanBus {
        self.bus
    }

    fn queue_reply(&mut self, reply: &[u8]) {
        if REPLY_QUEUE - self.reply_len < reply.len() {
            count(&self.bus.replies_dropped);
            return;
        }
        for &b in reply {
            if let Some(slot) = self
                .replies
                .get_mut((self.reply_head + self.reply_len) % REPLY_QUEUE)
            {
                *slot = b;
            }
            self.reply_len += 1;
        }
    }

    /// Queues a received frame for `CanIsr`; a full queue is an overrun (`false`).
    fn queue(&mut self, frame: CanFrame) -> bool {
        let free = (0..RX_QUEUE)
            .map(|i| (self.rx_head + i) % RX_QUEUE)
            .find(|&i| self.rx.get(i).is_some_and(Option::is_none));
        match free.and_then(|i| self.rx.get_mut(i)) {
            Some(slot) => {
                *slot = Some(frame);
                true
            }
            None => {
                count(&self.bus.rx_overruns);
                false
            }
        }
    }

    /// Out of line: `pump` runs in `CanIsr` on the main stack, and the decoder's locals
    /// would add to its frame.
    #[inline(never)]
    fn receive(&mut self, byte: u8) {
        match self.decoder.push(byte) {
            None => {}
            Some(Ok(command)) => {
                self.queue_reply(command.reply());
                match command {
                    slcan::Command::Frame(frame) => {
                        if self.queue(frame) {
                            count(&self.bus.rx_frames);
                        }
                    }
                    slcan::Command::Timestamps(on) => {
                        self.timestamps = on;
                        count(&self.bus.rx_commands);
                    }
                    _ => count(&self.bus.rx_commands),
                }
            }
            Some(Err(_)) => {
                count(&self.bus.rx_malformed);
                self.queue_reply(slcan::ERROR_REPLY);
            }
        }
    }

    /// The next character to send, if any, finishing the current line first.
    fn next_tx_byte(&mut self) -> Option<u8> {
        if self.source == TxSource::Idle {
            self.source = if self.reply_len > 0 {
                TxSource::Reply
            } else if self.sent < self.len {
                TxSource::Frame
            } else {
                return None;
            };
        }
        let byte = if self.source == TxSource::Frame {
            let byte = self.line.get(self.sent).copied().unwrap_or(b'\r');
            self.sent += 1;
            if self.sent >= self.len {
                self.source = TxSource::Idle;
                if let Some(pdu) = self.pdu.take() {
                    self.confirmed = Some(pdu);
                    let _ = self.errors.sent();
                }
                if let Some(mode) = self.switching_to.take() {
                    self.mode = mode;
                    self.mode_event = Some(mode);
                }
            }
            byte
        } else {
            let byte = self.replies.get(self.reply_head).copied().unwrap_or(b'\r');
            self.reply_head = (self.reply_head + 1) % REPLY_QUEUE;
            self.reply_len = self.reply_len.saturating_sub(1);
            if byte == b'\r' || byte == slcan::ERROR_REPLY[0] || self.reply_len == 0 {
                self.source = TxSource::Idle;
            }
            byte
        };
        Some(byte)
    }

    /// Puts `frame` into the mailbox, time-stamped now, and requests the transmit
    /// interrupt, which encodes its line and hands it to the UART: as a FlexCAN message
    /// buffer is written and its code set to transmit, and the controller does the rest.
    fn start_line(&mut self, frame: &CanFrame) {
        self.mailbox = Some((*frame, self.timestamps.then(B::now_ms)));
        self.uart.request_service();
    }

    /// Puts `frame`'s line (time-stamped `at_ms`) where the transmitter takes it from.
    fn load_line(&mut self, frame: &CanFrame, at_ms: Option<u64>) {
        // Lawicel's time stamp counts ms modulo 60 000: the remainder of the 64-bit time,
        // in 32-bit operations, here in the interrupt rather than in `Can_Write`.
        let stamp = at_ms.map(|ms| cw_core::time::rem_u64(ms, slcan::TIMESTAMP_MODULUS as u16));
        self.len = slcan::encode_frame_at(frame, stamp, &mut self.line);
        self.sent = 0;
    }

    /// The bus's verdict on `frame`, written now: `None` if it goes out at once;
    /// otherwise when it goes out after the bus-off recovery and the failed attempts
    /// injected (each taking the bus up to the ACK slot, an error frame and the
    /// intermission, plus the suspend time while error passive), or when the counter
    /// passes 255 and the controller goes bus-off.
    fn attempts(&mut self, frame: &CanFrame) -> Option<Deferred> {
        // The common case costs two loads: no recovery under way, no error injected.
        if !BUS_FAULTS
            || (self.recovery_end_us == 0
                && self.bus.injected_tx_errors.load(Ordering::Relaxed) == 0)
        {
            return None;
        }
        let now_us = B::now_us();
        if self.recovery_end_us <= now_us {
            self.recovery_end_us = 0;
        }
        let mut delayed = self.recovery_end_us > now_us;
        let mut t_ns = now_us.max(self.recovery_end_us) * 1000;
        let bits = |n: u32| u64::from(n) * BIT_NS;
        while self.bus.take_injected_error() {
            delayed = true;
            count(&self.bus.tx_errors);
            t_ns += bits(timing::failed_attempt_bits(frame, Stuffing::Exact));
            match self.errors.failed(Failure::Error) {
                ErrorState::BusOff => {
                    return Some(Deferred::BusOff {
                        due_us: t_ns.div_ceil(1000),
                    })
                }
                ErrorState::Passive => {
                    t_ns += bits(timing::INTERMISSION_BITS + timing::SUSPEND_TRANSMISSION_BITS);
                }
                ErrorState::Active => t_ns += bits(timing::INTERMISSION_BITS),
            }
        }
        delayed.then(|| Deferred::Send {
            frame: *frame,
            due_us: (t_ns + bits(timing::frame_bits(frame, Stuffing::Exact))).div_ceil(1000),
        })
    }

    /// The controller's interrupt work: received characters into the decoder, tester
    /// frames into the receive queue, a held-back transmission or bus-off when due, the
    /// mailbox's frame encoded as a line, and lines into the UART while it takes them. A
    /// frame line sent completely frees the transmitter and leaves its confirmation for
    /// `CanIsr`.
    fn pump(&mut self) {
        self.uart.clear_interrupts();
        while let Some(byte) = self.uart.read_byte() {
            self.receive(byte);
        }
        while BUS_FAULTS {
            let Some(frame) = self.bus.take_frame() else {
                break;
            };
            if self.queue(frame) {
                count(&self.bus.bus_frames);
            }
        }
        if let Some(deferred) = self
            .deferred
            .filter(|d| BUS_FAULTS && B::now_us() >= d.due_us())
        {
            self.deferred = None;
            self.bus.deferred_due_ms.store(0, Ordering::Relaxed);
            match deferred {
                // The transmitter below sends it; its confirmation follows in this
                // interrupt.
                Deferred::Send { frame, .. } => {
                    self.load_line(&frame, self.timestamps.then(B::now_ms));
                }
                Deferred::BusOff { .. } => {
                    self.pdu = None;
                    self.mode = ControllerMode::Stopped;
                    self.bus_off = true;
                    self.bus_off_event = true;
                    count(&self.bus.bus_offs);
                }
            }
        }
        // The mailbox's frame becomes the next line once the last one is out.
        if self.sent >= self.len {
            if let Some((frame, at_ms)) = self.mailbox.take() {
                self.load_line(&frame, at_ms);
            }
        }
        while self.uart.tx_ready() {
            let Some(byte) = self.next_tx_byte() else {
                break;
            };
            self.uart.write_byte(byte);
        }
        if self.source == TxSource::Idle && self.sent >= self.len && self.reply_len == 0 {
            // Nothing left to send: the TX-empty interrupt the characters just written
            // raised would only enter `CanIsr` again for nothing.
            self.uart.tx_idle();
        }
    }

    /// The UART's interrupt work, then the next event, if any: a transmit confirmation
    /// first, then the oldest received frame.
    pub fn take_event(&mut self) -> Option<SlcanEvent> {
        self.pump();
        if let Some(pdu) = self.confirmed.take() {
            return Some(SlcanEvent::TxConfirmation(pdu));
        }
        if core::mem::take(&mut self.bus_off_event) {
            return Some(SlcanEvent::BusOff);
        }
        if let Some(mode) = self.mode_event.take() {
            return Some(SlcanEvent::ModeIndication(mode));
        }
        let frame = self.rx.get_mut(self.rx_head).and_then(Option::take)?;
        self.rx_head = (self.rx_head + 1) % RX_QUEUE;
        Some(SlcanEvent::Received(frame))
    }
}

/// The bitrates a Lawicel adapter's `Sn` command sets, by `n`.
pub const LAWICEL_BITRATES: [u32; 9] = [
    10_000, 20_000, 50_000, 100_000, 125_000, 250_000, 500_000, 800_000, 1_000_000,
];

impl<U: ByteUart, B: SlcanBoard> CanDriver for SlcanCan<U, B> {
    /// Takes a bitrate a Lawicel adapter can be set to (`S0` to `S8`); the UART itself
    /// carries the frames at its own baud rate, so the sample point is the adapter's.
    /// Stops the controller, its waiting frame withdrawn.
    fn init(&mut self, config: &ControllerConfig) -> Result<(), InitRefused> {
        if !LAWICEL_BITRATES.contains(&config.bitrate) {
            return Err(InitRefused {
                bitrate: config.bitrate,
            });
        }
        self.bitrate = config.bitrate;
        self.withdraw();
        self.mode = ControllerMode::Stopped;
        self.switching_to = None;
        Ok(())
    }

    fn error_counters(&self) -> ErrorCounters {
        ErrorCounters {
            state: if self.bus_off {
                ErrorState::BusOff
            } else {
                self.errors.state()
            },
            tec: self.errors.tec(),
            // A UART link has no receive errors of the CAN kind: a malformed line is
            // counted by the bus (`rx_malformed`), not by an error counter.
            rec: 0,
        }
    }

    /// One mailbox for every HTH: the waiting frame (or a transmission the bus holds
    /// back) goes, without confirmation; a line already on the wire finishes.
    fn abort(&mut self, _hth: Hth) {
        self.withdraw();
    }

    fn write(&mut self, _hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        // Busy while a line is waiting or on its way (also one a stop let finish), or its
        // confirmation is not yet taken.
        if self.mode != ControllerMode::Started
            || self.switching_to.is_some()
            || self.mailbox.is_some()
            || self.sent < self.len
            || self.confirmed.is_some()
            || self.deferred.is_some()
        {
            return Err(CanBusy);
        }
        B::mark_write(true);
        self.pdu = Some(pdu);
        match self.attempts(frame) {
            None => self.start_line(frame),
            Some(deferred) => {
                self.deferred = Some(deferred);
                let due_ms = deferred.due_us().div_ceil(1000);
                self.bus.deferred_due_ms.store(
                    u32::try_from(due_ms).unwrap_or(u32::MAX).max(1),
                    Ordering::Relaxed,
                );
            }
        }
        B::mark_write(false);
        Ok(())
    }

    /// A stop (or sleep) asked for while a frame's line is on the UART waits for the
    /// line's end ([`ModeChange::Pending`], then [`SlcanEvent::ModeIndication`]), so the
    /// other end never sees half a line; meanwhile the controller takes no frame and
    /// refuses to start. Every other change is reached at once.
    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        let switching = self.switching_to.is_some();
        if mode == ControllerMode::Started && (switching || self.mode == ControllerMode::Sleep) {
            return Err(ModeRefused);
        }
        if mode != ControllerMode::Started {
            self.withdraw();
            if switching || (self.source == TxSource::Frame && self.sent < self.len) {
                self.switching_to = Some(mode);
                return Ok(ModeChange::Pending);
            }
        } else if BUS_FAULTS && self.mode != ControllerMode::Started && self.bus_off {
            // Restart after bus-off: 128 x 11 recessive bits before the next attempt,
            // with the counter at 0.
            self.bus_off = false;
            self.errors.recovered();
            self.recovery_end_us =
                B::now_us() + (u64::from(timing::BUS_OFF_RECOVERY_BITS) * BIT_NS).div_ceil(1000);
        }
        self.mode = mode;
        Ok(ModeChange::Reached)
    }
}
