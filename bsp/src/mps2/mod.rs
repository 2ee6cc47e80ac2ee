//! QEMU's `mps2-an386` board (Arm MPS2 with the AN386 FPGA image: a Cortex-M4 at 25 MHz),
//! as QEMU 7.2 models it.
//!
//! | part | here | registers |
//! |---|---|---|
//! | warning LEDs | [`Led`]: FPGAIO LED bits 0 (red) and 1 (yellow) | FPGAIO `LED0` at `0x4002_8000` |
//! | CAN | [`SlcanCan`]: frames as SLCAN (Lawicel) text on UART0 | CMSDK APB UART0 at `0x4000_4000`, IRQ 0 (RX), 1 (TX) |
//! | distance sensor (live runs) | [`SensorUart`]: a UART ranging module's bytes ([`sensor`]) | CMSDK APB UART1 at `0x4000_5000`, IRQ 2 (RX) |
//! | OS tick | SysTick, 25 000 core clocks per ms | SCS |
//! | watchdog | [`CmsdkWatchdog`]: WdgM's trigger; its first expiry is an NMI, its second resets the board | CMSDK APB watchdog at `0x4000_8000` |
//! | log, exit | semihosting (`-semihosting-config enable=on,target=native`) | |
//!
//! QEMU models no FlexCAN, so the CAN controller here is a UART speaking SLCAN: what the
//! ECU sends is visible outside the emulator (QEMU's `-serial tcp:...` and python-can's
//! `slcan` interface). One transmit mailbox: a frame occupies it until its last character
//! has left the UART, then the driver reports the transmit confirmation.

pub mod semihosting;
pub mod sensor;

pub use sensor::{sensor_uart_stats, SensorUart, SensorUartStats};

use core::cell::RefCell;
use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use cortex_m::interrupt::Mutex;
use cw_core::can::confinement::{ErrorState, Failure, TransmitErrors};
use cw_core::can::timing::{self, Stuffing};
use cw_core::can::{slcan, CanBusy, CanDriver, CanFrame, ControllerMode, Hth, ModeRefused};
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};

use crate::chip::cmsdk::CmsdkUart;
use crate::chip::fpgaio::FpgaLeds;
use crate::cortex_m::{app, now_ms, now_us};
use crate::port::preempt::PortFault;

/// The core clock, Hz (SysTick counts it).
pub const SYSCLK_HZ: u32 = 25_000_000;

/// The AN386 image's peripherals this board uses, at their addresses (its memory map).
mod map {
    use crate::chip::cmsdk::{UartRegisters, WatchdogRegisters};
    use crate::chip::fpgaio::FpgaIoRegisters;

    /// CMSDK APB UART0 (the CAN controller's SLCAN link).
    pub const UART0: usize = 0x4000_4000;
    /// CMSDK APB UART1 (the sensor).
    pub const UART1: usize = 0x4000_5000;
    /// The CMSDK APB watchdog.
    pub const WATCHDOG: usize = 0x4000_8000;
    /// FPGAIO.
    pub const FPGAIO: usize = 0x4002_8000;

    /// The UART at `base` (UART0 or UART1).
    pub fn uart(base: usize) -> &'static UartRegisters {
        // SAFETY: UART0 and UART1 are CMSDK APB UARTs at these addresses on this board,
        // mapped for its whole life; the block is accessed through volatile cells only.
        unsafe { &*(base as *const UartRegisters) }
    }

    /// The watchdog.
    pub fn watchdog() -> &'static WatchdogRegisters {
        // SAFETY: as `uart`: the CMSDK APB watchdog of this board.
        unsafe { &*(WATCHDOG as *const WatchdogRegisters) }
    }

    /// FPGAIO.
    pub fn fpgaio() -> &'static FpgaIoRegisters {
        // SAFETY: as `uart`: the FPGAIO block of this board.
        unsafe { &*(FPGAIO as *const FpgaIoRegisters) }
    }
}

/// A warning LED: one bit of the FPGAIO LED register. The LED pins are the ECU's
/// `RES_LEDS`, so the register's read-modify-write never races another writer.
pub struct Led {
    bit: u32,
}

impl Led {
    /// The red LED (LED0 bit 0).
    pub const RED: Self = Self { bit: 0 };
    /// The yellow LED (LED0 bit 1).
    pub const YELLOW: Self = Self { bit: 1 };

    fn write(&self, lit: bool) {
        let (now, new) = FpgaLeds::new(map::fpgaio()).set(self.bit, lit);
        if new != now {
            led_changed(new);
        }
    }
}

/// LED register values logged with their time, from the start of the run.
pub const LED_LOG: usize = 48;

struct LedLog {
    entries: [(u32, u8); LED_LOG],
    len: usize,
    dropped: u32,
}

struct LedLogCell(core::cell::UnsafeCell<LedLog>);

// SAFETY: reached only inside `cortex_m::interrupt::free`, on a single core.
unsafe impl Sync for LedLogCell {}

static LEDS_LOGGED: LedLogCell = LedLogCell(core::cell::UnsafeCell::new(LedLog {
    entries: [(0, 0); LED_LOG],
    len: 0,
    dropped: 0,
}));

fn led_changed(value: u32) {
    let at_ms = u32::try_from(now_ms()).unwrap_or(u32::MAX);
    cortex_m::interrupt::free(|_| {
        // SAFETY: interrupts are off; the only reference to the log.
        let log = unsafe { &mut *LEDS_LOGGED.0.get() };
        match log.entries.get_mut(log.len) {
            Some(slot) => {
                *slot = (at_ms, value as u8);
                log.len += 1;
            }
            None => log.dropped = log.dropped.saturating_add(1),
        }
    });
}

/// Calls `f` with each logged change of the LED register in order (ms since the OS
/// started, the register's bits: 0 red, 1 yellow); returns how many changes came after
/// the log was full.
pub fn led_changes(mut f: impl FnMut(u32, u8)) -> u32 {
    cortex_m::interrupt::free(|_| {
        // SAFETY: as in `led_changed`; `f` does not write LEDs.
        let log = unsafe { &*LEDS_LOGGED.0.get() };
        for &(at, value) in log.entries.iter().take(log.len) {
            f(at, value);
        }
        log.dropped
    })
}

/// Both LEDs dark: the outputs' safe state, for fatal errors.
pub fn leds_safe() {
    FpgaLeds::new(map::fpgaio()).all_dark();
}

impl ErrorType for Led {
    type Error = Infallible;
}

impl OutputPin for Led {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.write(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.write(true);
        Ok(())
    }
}

/// A line the board does not have (the HC-SR04's trigger and echo: the emulated sensor
/// needs no pulse): writes go nowhere, reads are low.
pub struct Unconnected;

impl ErrorType for Unconnected {
    type Error = Infallible;
}

impl OutputPin for Unconnected {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl InputPin for Unconnected {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(false)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(true)
    }
}

/// Busy-wait delays on the core clock.
pub struct CoreDelay;

impl DelayNs for CoreDelay {
    fn delay_ns(&mut self, ns: u32) {
        // 25 cycles per µs; at least one.
        cortex_m::asm::delay((ns / 40).max(1));
    }
}

/// Starts SysTick: one interrupt per millisecond, at OSEK ISR priority `osek_priority`.
pub fn start_tick(osek_priority: u8) {
    crate::cortex_m::start_systick(SYSCLK_HZ / 1000 - 1, osek_priority);
}

/// A CAN controller event of [`SlcanCan`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlcanEvent {
    /// The frame of this PDU has left the UART.
    TxConfirmation(u16),
    /// A frame arrived (an SLCAN `t`/`T` line from the other end, or a tester's frame
    /// put on the bus with [`put_frame_on_bus`]).
    Received(CanFrame),
    /// The controller went bus-off (more than 255 in its transmit error counter): its
    /// frame is dropped without confirmation and it is stopped until restarted.
    BusOff,
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
    /// Tester frames put on the bus ([`put_frame_on_bus`]) and received.
    pub bus_frames: u32,
    /// Transmission attempts that failed ([`inject_tx_errors`]).
    pub tx_errors: u32,
    /// Times the controller went bus-off.
    pub bus_offs: u32,
}

/// The counters of UART0's SLCAN link, readable from anywhere (the end-of-run report in
/// the idle loop): each is written by the driver alone, under `RES_COM` or in `CanIsr`.
struct SlcanCounters {
    rx_frames: AtomicU32,
    rx_commands: AtomicU32,
    rx_malformed: AtomicU32,
    rx_overruns: AtomicU32,
    replies_dropped: AtomicU32,
    bus_frames: AtomicU32,
    tx_errors: AtomicU32,
    bus_offs: AtomicU32,
}

static SLCAN_COUNTERS: SlcanCounters = SlcanCounters {
    rx_frames: AtomicU32::new(0),
    rx_commands: AtomicU32::new(0),
    rx_malformed: AtomicU32::new(0),
    rx_overruns: AtomicU32::new(0),
    replies_dropped: AtomicU32::new(0),
    bus_frames: AtomicU32::new(0),
    tx_errors: AtomicU32::new(0),
    bus_offs: AtomicU32::new(0),
};

fn count(counter: &AtomicU32) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// What UART0's SLCAN link has counted since start-up.
pub fn slcan_stats() -> SlcanStats {
    let c = &SLCAN_COUNTERS;
    SlcanStats {
        rx_frames: c.rx_frames.load(Ordering::Relaxed),
        rx_commands: c.rx_commands.load(Ordering::Relaxed),
        rx_malformed: c.rx_malformed.load(Ordering::Relaxed),
        rx_overruns: c.rx_overruns.load(Ordering::Relaxed),
        replies_dropped: c.replies_dropped.load(Ordering::Relaxed),
        bus_frames: c.bus_frames.load(Ordering::Relaxed),
        tx_errors: c.tx_errors.load(Ordering::Relaxed),
        bus_offs: c.bus_offs.load(Ordering::Relaxed),
    }
}

/// Whether the controller plays the bus's faults (cw-bsp's feature `bus-faults`, for the
/// scenario images): injected transmit errors with their error counter, bus-off and its
/// recovery time, and tester frames put on the bus. A UART has no bus to fail, so the
/// production image leaves the model out; the ECU's own handling (CanSM) stays.
const BUS_FAULTS: bool = cfg!(feature = "bus-faults");

/// The bus's bit time, ns: 500 kbit/s, the ECU's CAN bitrate (as on the host's simulated
/// bus). Failed attempts, error frames and bus-off recovery take bus time in bits.
const BIT_NS: u64 = 2000;

/// Transmission attempts of the controller that the bus will fail next.
static INJECTED_TX_ERRORS: AtomicU32 = AtomicU32::new(0);

/// Tester frames on the bus, not yet taken by the controller (in the order put).
static BUS_FRAMES: Mutex<RefCell<[Option<CanFrame>; RX_QUEUE]>> =
    Mutex::new(RefCell::new([None; RX_QUEUE]));

/// Whether [`BUS_FRAMES`] may hold a frame: the controller's interrupt work reads one
/// flag, not the queue under a lock, when no tester is on the bus.
static BUS_FRAMES_WAITING: AtomicBool = AtomicBool::new(false);

/// The ms at which the controller's delayed transmission or bus-off is due (`u32::MAX`:
/// none): the OS tick raises the controller's interrupt then ([`on_tick`]).
static DEFERRED_DUE_MS: AtomicU32 = AtomicU32::new(u32::MAX);

const _: () = assert!(
    slcan::TIMESTAMP_MODULUS <= u16::MAX as u32,
    "the time stamp's modulus fits the 32-bit remainder"
);

/// The board's work in every OS tick (the application's tick calls it first): the CAN
/// controller's delayed transmission or bus-off, when due, raises its interrupt.
pub fn on_tick() {
    if BUS_FAULTS && now_ms() >= u64::from(DEFERRED_DUE_MS.load(Ordering::Relaxed)) {
        cortex_m::peripheral::NVIC::pend(Irq(1));
    }
}

/// Fault injection (a scenario's `can-errors`): the controller's next `count`
/// transmission attempts fail, each raising its transmit error counter by 8 and taking
/// the bus up to the ACK slot plus an error frame, before the automatic retransmission.
#[cfg(feature = "bus-faults")]
pub fn inject_tx_errors(count: u32) {
    let _ = INJECTED_TX_ERRORS.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
        Some(n.saturating_add(count))
    });
}

/// Takes one injected error for an attempt, if any is left.
fn take_injected_error() -> bool {
    INJECTED_TX_ERRORS
        .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
        .is_ok()
}

/// A tester's frame on the bus (a scenario's `frame`): the controller receives it and
/// raises its interrupt. A frame that finds the queue full is an overrun.
#[cfg(feature = "bus-faults")]
pub fn put_frame_on_bus(frame: CanFrame) {
    let queued = cortex_m::interrupt::free(|cs| {
        let mut frames = BUS_FRAMES.borrow(cs).borrow_mut();
        frames
            .iter_mut()
            .find(|slot| slot.is_none())
            .map(|slot| *slot = Some(frame))
            .is_some()
    });
    if queued {
        BUS_FRAMES_WAITING.store(true, Ordering::Release);
    } else {
        count(&SLCAN_COUNTERS.rx_overruns);
    }
    cortex_m::peripheral::NVIC::pend(Irq(0));
}

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

/// The trace span (`cortex_m::trace`) the driver's `Can_Write` is measured in: the
/// bus-fault check, the frame into the mailbox and the transmit interrupt requested (the
/// ECU names it `span::DRIVER_WRITE`).
pub const DRIVER_WRITE_SPAN: usize = 5;

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
pub struct SlcanCan {
    /// The UART's base address (its register block is reached through [`map::uart`]).
    uart: usize,
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
}

impl SlcanCan {
    /// The driver on UART0 (QEMU's first `-serial`).
    pub fn uart0() -> Self {
        CmsdkUart::new(map::uart(map::UART0)).init(SYSCLK_HZ, 115_200, true);
        Self {
            uart: map::UART0,
            mode: ControllerMode::Stopped,
            mailbox: None,
            line: [0; slcan::FRAME_LINE_MAX],
            len: 0,
            sent: 0,
            pdu: None,
            confirmed: None,
            source: TxSource::Idle,
            timestamps: true,
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
        }
    }

    /// The UART's driver.
    fn uart(&self) -> CmsdkUart<'static> {
        CmsdkUart::new(map::uart(self.uart))
    }

    /// Enables the UART's interrupts in the NVIC at OSEK ISR priority `osek_priority`.
    pub fn enable_interrupts(osek_priority: u8) {
        crate::cortex_m::enable_irq(Irq(0), osek_priority);
        crate::cortex_m::enable_irq(Irq(1), osek_priority);
    }

    fn queue_reply(&mut self, reply: &[u8]) {
        if REPLY_QUEUE - self.reply_len < reply.len() {
            count(&SLCAN_COUNTERS.replies_dropped);
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
                count(&SLCAN_COUNTERS.rx_overruns);
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
                            count(&SLCAN_COUNTERS.rx_frames);
                        }
                    }
                    slcan::Command::Timestamps(on) => {
                        self.timestamps = on;
                        count(&SLCAN_COUNTERS.rx_commands);
                    }
                    _ => count(&SLCAN_COUNTERS.rx_commands),
                }
            }
            Some(Err(_)) => {
                count(&SLCAN_COUNTERS.rx_malformed);
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
        self.mailbox = Some((*frame, self.timestamps.then(now_ms)));
        cortex_m::peripheral::NVIC::pend(Irq(1));
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
            || (self.recovery_end_us == 0 && INJECTED_TX_ERRORS.load(Ordering::Relaxed) == 0)
        {
            return None;
        }
        let now_us = now_us();
        if self.recovery_end_us <= now_us {
            self.recovery_end_us = 0;
        }
        let mut delayed = self.recovery_end_us > now_us;
        let mut t_ns = now_us.max(self.recovery_end_us) * 1000;
        let bits = |n: u32| u64::from(n) * BIT_NS;
        while take_injected_error() {
            delayed = true;
            count(&SLCAN_COUNTERS.tx_errors);
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
        self.uart().clear_interrupts();
        while let Some(byte) = self.uart().read_byte() {
            self.receive(byte);
        }
        while BUS_FAULTS && BUS_FRAMES_WAITING.load(Ordering::Acquire) {
            let Some(frame) = cortex_m::interrupt::free(|cs| {
                let mut frames = BUS_FRAMES.borrow(cs).borrow_mut();
                let first = frames.first_mut().and_then(Option::take);
                frames.rotate_left(1);
                if frames.first().is_none_or(Option::is_none) {
                    BUS_FRAMES_WAITING.store(false, Ordering::Release);
                }
                first
            }) else {
                break;
            };
            if self.queue(frame) {
                count(&SLCAN_COUNTERS.bus_frames);
            }
        }
        if let Some(deferred) = self
            .deferred
            .filter(|d| BUS_FAULTS && now_us() >= d.due_us())
        {
            self.deferred = None;
            DEFERRED_DUE_MS.store(u32::MAX, Ordering::Relaxed);
            match deferred {
                // The transmitter below sends it; its confirmation follows in this
                // interrupt.
                Deferred::Send { frame, .. } => {
                    self.load_line(&frame, self.timestamps.then(now_ms));
                }
                Deferred::BusOff { .. } => {
                    self.pdu = None;
                    self.mode = ControllerMode::Stopped;
                    self.bus_off = true;
                    self.bus_off_event = true;
                    count(&SLCAN_COUNTERS.bus_offs);
                }
            }
        }
        // The mailbox's frame becomes the next line once the last one is out.
        if self.sent >= self.len {
            if let Some((frame, at_ms)) = self.mailbox.take() {
                self.load_line(&frame, at_ms);
            }
        }
        while self.uart().tx_ready() {
            let Some(byte) = self.next_tx_byte() else {
                break;
            };
            self.uart().write_byte(byte);
        }
        if self.source == TxSource::Idle && self.sent >= self.len && self.reply_len == 0 {
            // Nothing left to send: the TX-empty interrupt the characters just written
            // raised would only enter `CanIsr` again for nothing.
            self.uart().clear_tx_interrupt();
            cortex_m::peripheral::NVIC::unpend(Irq(1));
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
        let frame = self.rx.get_mut(self.rx_head).and_then(Option::take)?;
        self.rx_head = (self.rx_head + 1) % RX_QUEUE;
        Some(SlcanEvent::Received(frame))
    }
}

impl CanDriver for SlcanCan {
    fn write(&mut self, _hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        // Busy while a line is waiting or on its way (also one a stop let finish), or its
        // confirmation is not yet taken.
        if self.mode != ControllerMode::Started
            || self.mailbox.is_some()
            || self.sent < self.len
            || self.confirmed.is_some()
            || self.deferred.is_some()
        {
            return Err(CanBusy);
        }
        if crate::cortex_m::trace::ENABLED {
            crate::cortex_m::trace::span_start(DRIVER_WRITE_SPAN, crate::cortex_m::trace::now());
        }
        self.pdu = Some(pdu);
        match self.attempts(frame) {
            None => self.start_line(frame),
            Some(deferred) => {
                self.deferred = Some(deferred);
                let due_ms = deferred.due_us().div_ceil(1000);
                DEFERRED_DUE_MS.store(u32::try_from(due_ms).unwrap_or(u32::MAX), Ordering::Relaxed);
            }
        }
        if crate::cortex_m::trace::ENABLED {
            crate::cortex_m::trace::span_end(DRIVER_WRITE_SPAN, crate::cortex_m::trace::now());
        }
        Ok(())
    }

    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<(), ModeRefused> {
        if self.mode == ControllerMode::Sleep && mode == ControllerMode::Started {
            return Err(ModeRefused);
        }
        if mode != ControllerMode::Started {
            // The pending transmission is cancelled: no confirmation. A line already on
            // the wire is finished, so the other end never sees half a line.
            self.pdu = None;
            self.mailbox = None;
            self.deferred = None;
            DEFERRED_DUE_MS.store(u32::MAX, Ordering::Relaxed);
            if self.source != TxSource::Frame {
                self.len = 0;
                self.sent = 0;
            }
        } else if BUS_FAULTS && self.mode != ControllerMode::Started && self.bus_off {
            // Restart after bus-off: 128 x 11 recessive bits before the next attempt,
            // with the counter at 0.
            self.bus_off = false;
            self.errors.recovered();
            self.recovery_end_us =
                now_us() + (u64::from(timing::BUS_OFF_RECOVERY_BITS) * BIT_NS).div_ceil(1000);
        }
        self.mode = mode;
        Ok(())
    }
}

/// An external interrupt line of this board.
#[derive(Debug, Clone, Copy)]
pub struct Irq(pub u16);

// SAFETY: the numbers are the board's external interrupt lines (QEMU's mps2 wiring).
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

// The log: `defmt` frames, written to the host's standard output over semihosting by
// defmt-semihosting's global logger (its critical section is cortex-m's single-core one:
// PRIMASK, restored after the frame). The format strings stay in the ELF's `.defmt`
// section, not in flash; the host decodes the frames with the ELF (`defmt-print -e ELF`,
// which `cargo xtask qemu` and the emulator tests run on QEMU's output).
use defmt_semihosting as _;

/// Ends the QEMU run (semihosting `SYS_EXIT`), successfully or not: the measuring and
/// test images' end (QEMU runs them with semihosting; a board without a debugger would
/// fault on the call, so a production image never makes it: [`halt`] resets).
pub fn exit(success: bool) -> ! {
    let code = if success {
        cortex_m_semihosting::debug::EXIT_SUCCESS
    } else {
        cortex_m_semihosting::debug::EXIT_FAILURE
    };
    cortex_m_semihosting::debug::exit(code);
    loop {
        cortex_m::asm::wfi();
    }
}

/// The board's watchdog for WdgM (`cw_core::wdgm::WdgDriver`): the CMSDK APB watchdog
/// ([`crate::chip::cmsdk::CmsdkWatchdog`]), its first expiry an NMI (the early warning,
/// which logs the reason), its second a reset of the board.
pub struct CmsdkWatchdog {
    _private: (),
}

impl CmsdkWatchdog {
    /// The board's watchdog (started by the first trigger).
    pub const fn new() -> Self {
        Self { _private: () }
    }

    fn chip() -> crate::chip::cmsdk::CmsdkWatchdog<'static> {
        crate::chip::cmsdk::CmsdkWatchdog::new(map::watchdog(), WATCHDOG_CLOCK_HZ)
    }
}

impl Default for CmsdkWatchdog {
    fn default() -> Self {
        Self::new()
    }
}

/// The watchdog's counter clock, Hz. On the AN386 FPGA image it is the 25 MHz system
/// clock; QEMU 7.2's model counts twice as fast (measured: with `WDOGLOAD` at 625,000,
/// the first expiry came 12.5 ms after the trigger, by the OS's SysTick time), so the
/// timeout is set for the model QEMU runs. A port to the physical board halves this.
const WATCHDOG_CLOCK_HZ: u32 = 2 * SYSCLK_HZ;

/// The last trigger of the watchdog, OS ms (for the report of its expiry).
static WATCHDOG_TRIGGERED_MS: AtomicU32 = AtomicU32::new(0);

impl cw_core::wdgm::WdgDriver for CmsdkWatchdog {
    fn set_trigger_condition(&mut self, timeout_ms: u16) {
        Self::chip().trigger(timeout_ms);
        WATCHDOG_TRIGGERED_MS.store(
            u32::try_from(now_ms()).unwrap_or(u32::MAX),
            Ordering::Relaxed,
        );
    }

    fn off(&mut self) {
        Self::chip().off();
    }
}

/// Whether the watchdog has expired once (its interrupt raised: the reset follows at the
/// next expiry).
pub fn watchdog_expired() -> bool {
    CmsdkWatchdog::chip().expired()
}

/// How a fatal fault ends the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FatalEnd {
    /// A system reset (`SCB::sys_reset`): the production image, as on silicon (QEMU,
    /// run with `-no-reboot`, exits).
    Reset,
    /// QEMU's exit with a failure status (semihosting): the measuring and test images,
    /// whose runs a test reads to its end.
    Exit,
}

/// The image ends fatal faults by QEMU's exit instead of a reset.
static END_BY_EXIT: AtomicBool = AtomicBool::new(false);

/// Chooses how this image ends fatal faults (a reset unless told; before start).
pub fn set_fatal_end(end: FatalEnd) {
    END_BY_EXIT.store(end == FatalEnd::Exit, Ordering::Relaxed);
}

/// A fault the OS cannot go on from, already reported: the outputs' safe state (LEDs
/// dark), then the image's end ([`FatalEnd`]): a reset, or QEMU's exit with a failure.
pub fn halt() -> ! {
    cortex_m::interrupt::disable();
    leds_safe();
    if watchdog_expired() {
        // The watchdog's reset comes at its next expiry: it, not the software, ends the run.
        loop {
            cortex_m::asm::wfi();
        }
    }
    if END_BY_EXIT.load(Ordering::Relaxed) {
        exit(false)
    }
    last_words(|| defmt::println!("RESET"));
    cortex_m::peripheral::SCB::sys_reset()
}

/// Logs a port fault with the outputs in their safe state: `FATAL: WHAT ITEM` (a stack
/// overflow then shuts the OS down, whose report follows).
pub fn report(fault: &PortFault) {
    leds_safe();
    if *fault == PortFault::Board("NMI") && watchdog_expired() {
        defmt::println!(
            "watchdog: not triggered since {} ms; expired at {} ms (NMI), its reset follows",
            WATCHDOG_TRIGGERED_MS.load(Ordering::Relaxed),
            now_ms()
        );
        return;
    }
    let (what, item) = fault.parts();
    defmt::println!("FATAL: {=str} {=str}", what, item);
}

/// A fatal error of the board or the application: LEDs to their safe state, the reason on
/// the log, then [`halt`].
pub fn fatal(what: &str) -> ! {
    leds_safe();
    last_words(|| defmt::println!("FATAL: {=str}", what));
    halt()
}

/// Logs a fatal error's report the first time only: a fault or panic inside the log
/// itself (defmt's logger refuses to be taken twice, by panicking) must not recurse.
fn last_words(log: impl FnOnce()) {
    static SPOKEN: AtomicBool = AtomicBool::new(false);
    if !SPOKEN.swap(true, Ordering::Relaxed) {
        log();
    }
}

extern "C" fn uart0_rx() {
    if let Some(app) = app() {
        app.irq(0);
    }
}

extern "C" fn uart0_tx() {
    if let Some(app) = app() {
        app.irq(1);
    }
}

/// The external interrupt line no device of the board drives: software pends it
/// ([`pend_software_irq`]), as a test's or a demo's interrupt source.
pub const SOFTWARE_IRQ: u16 = 31;

extern "C" fn software_irq() {
    if let Some(app) = app() {
        app.irq(SOFTWARE_IRQ);
    }
}

/// Enables [`SOFTWARE_IRQ`] at OSEK ISR priority `osek_priority`.
pub fn enable_software_irq(osek_priority: u8) {
    crate::cortex_m::enable_irq(Irq(SOFTWARE_IRQ), osek_priority);
}

/// Requests [`SOFTWARE_IRQ`].
pub fn pend_software_irq() {
    cortex_m::peripheral::NVIC::pend(Irq(SOFTWARE_IRQ));
}

extern "C" fn unused_irq() {
    fatal("an interrupt without a handler");
}

/// The external interrupt vector: UART0's receive and transmit lines are the CAN
/// controller's, UART1's receive line the distance sensor's, line 31 is
/// [`SOFTWARE_IRQ`]; no other line is enabled.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [extern "C" fn(); 32] = {
    let mut v: [extern "C" fn(); 32] = [unused_irq; 32];
    v[0] = uart0_rx;
    v[1] = uart0_tx;
    v[sensor::SENSOR_RX_IRQ as usize] = sensor::uart1_rx;
    v[SOFTWARE_IRQ as usize] = software_irq;
    v
};
