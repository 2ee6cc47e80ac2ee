//! Com I-PDUs and signals (AUTOSAR SWS COM): `Com_SendSignal`, `Com_ReceiveSignal`,
//! `Com_InvalidateSignal`, `Com_RxIndication`, `Com_TxConfirmation`, `Com_MainFunctionTx`
//! and `Com_MainFunctionRx`.
//!
//! Transmission modes (`ComTxModeMode`): periodic, direct (with `ComTxModeNumberOfRepetitions`
//! and repetition period), mixed, none; signal transfer properties: pending, triggered,
//! triggered on change, and their "without repetition" variants; the minimum delay time
//! (MDT) between two transmissions of an I-PDU applies to every transmission. A triggered
//! transmission is sent at once from `send_signal` when the MDT allows it (so the
//! SWC-to-mailbox path is one call chain), and otherwise at the MDT's expiry.
//!
//! Reception: update bits (a signal whose update bit is clear is not taken over), deadline
//! monitoring per I-PDU with replace-by-init of its signals and a timeout notification,
//! and the invalidation value (`receive_signal` reports [`ComError::Invalid`]).
//!
//! Time: the main functions run every `main_period_ms` (configuration); every time in
//! the tables is converted to main-function cycles when the configuration is built.
//!
//! Main-function cost: pending work sits in a hierarchical timer wheel (`Wheel`), one
//! linked list per slot; a main function looks only at the slot of the current cycle, so
//! an I-PDU with nothing due costs nothing, however far ahead its next event lies. Events
//! up to [`WHEEL`] cycles ahead sit in the slot of their cycle; further ones in coarser
//! slots, from which they move down at most once per level as their time approaches. A
//! reception does not move its I-PDU in the wheel: the stale entry is re-filed when its
//! slot comes up (lazy deadline reset).

use super::signal::{SignalLayout, SignalValue, Signedness};
use crate::tables::Tables;

/// Slots per level of the timer wheel (a power of two): events up to this many cycles
/// ahead are filed by their cycle, further ones by coarser blocks of cycles.
pub const WHEEL: usize = 64;
/// Bits of a cycle number that pick the slot within one level.
const SLOT_BITS: u32 = WHEEL.trailing_zeros();
/// Levels of the wheel: enough for any distance between two `u32` cycles, so no entry is
/// ever looked at before the block of its cycle starts.
const LEVELS: usize = (u32::BITS as usize).div_ceil(SLOT_BITS as usize);
// The coarsest level `list_for` can choose, for a distance of 2^31 or more, exists.
const _: () = assert!((u32::BITS - 1) / SLOT_BITS < LEVELS as u32);
/// End of a list.
const NIL: u8 = u8::MAX;
/// `Wheel::list` of an entry that is not filed.
const UNFILED: u16 = u16::MAX;

/// A transmitted I-PDU of Com.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TxIpduId(pub u16);
/// A received I-PDU of Com.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RxIpduId(pub u16);
/// A Com signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SignalId(pub u16);

/// `ComTxModeMode` with its timing, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TxMode {
    /// Never sent by Com itself (`NONE`).
    None,
    /// Sent every `period_ms`, first after `offset_ms`.
    Periodic {
        /// Cycle time.
        period_ms: u32,
        /// First transmission after start.
        offset_ms: u32,
    },
    /// Sent when a triggering signal is written, then repeated `repetitions` times every
    /// `repetition_period_ms`.
    Direct {
        /// Additional transmissions after the first.
        repetitions: u8,
        /// Time between repetitions.
        repetition_period_ms: u32,
    },
    /// Periodic and direct together.
    Mixed {
        /// Cycle time.
        period_ms: u32,
        /// First periodic transmission after start.
        offset_ms: u32,
        /// Additional direct transmissions after the first.
        repetitions: u8,
        /// Time between repetitions.
        repetition_period_ms: u32,
    },
}

/// `ComTransferProperty` of a transmitted signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TransferProperty {
    /// Writing never triggers a transmission.
    Pending,
    /// Every write triggers a transmission (with repetitions).
    Triggered,
    /// A write that changes the value triggers a transmission (with repetitions).
    TriggeredOnChange,
    /// Every write triggers one transmission, no repetitions.
    TriggeredWithoutRepetition,
    /// A changing write triggers one transmission, no repetitions.
    TriggeredOnChangeWithoutRepetition,
}

/// A transmitted I-PDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TxIpduConfig {
    /// Name, for traces.
    pub name: &'static str,
    /// Length in bytes.
    pub len: u8,
    /// Transmission mode.
    pub mode: TxMode,
    /// Minimum delay between two transmissions, ms (0: none).
    pub mdt_ms: u32,
}

/// A received I-PDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RxIpduConfig {
    /// Name, for traces.
    pub name: &'static str,
    /// Length in bytes.
    pub len: u8,
    /// Reception deadline, ms (0: not monitored).
    pub deadline_ms: u32,
}

/// Where a signal lives and how it behaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SignalDirection {
    /// Sent in this I-PDU, with this transfer property.
    Tx(TxIpduId, TransferProperty),
    /// Received in this I-PDU.
    Rx(RxIpduId),
}

/// One signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SignalConfig<const N: usize> {
    /// Name, for traces.
    pub name: &'static str,
    /// Direction and I-PDU.
    pub direction: SignalDirection,
    /// Position in the I-PDU.
    pub layout: SignalLayout<N>,
    /// Initial raw value (and the replacement on a reception timeout).
    pub init: u64,
    /// Raw value that means "invalid", if any.
    pub invalid: Option<u64>,
    /// Bit position (DBC numbering) of the signal's update bit, if any.
    pub update_bit: Option<u16>,
}

/// A broken configuration rule, naming the table and entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ComConfigError {
    /// A table holds more than 254 entries, or the main period is 0.
    Limits,
    /// An I-PDU is longer than the PDU type `N` or empty.
    IpduLength {
        /// Index of the I-PDU (TX table first, then RX).
        ipdu: u16,
    },
    /// A time is not a whole, non-zero number of main-function periods where one is needed.
    Timing {
        /// Index of the I-PDU (TX table first, then RX).
        ipdu: u16,
    },
    /// A signal names a missing I-PDU, lies beyond its I-PDU's length, its update bit
    /// overlaps it or lies outside, or its init/invalid values do not fit.
    Signal {
        /// Index of the signal.
        signal: u16,
    },
}

impl ComConfigError {
    /// A sentence describing the broken rule.
    pub const fn describe(&self) -> &'static str {
        match self {
            Self::Limits => "more than 254 Com I-PDUs or signals, or a zero main period",
            Self::IpduLength { .. } => "a Com I-PDU is empty or longer than the PDU type",
            Self::Timing { .. } => {
                "a Com time is not a whole, non-zero number of main-function periods"
            }
            Self::Signal { .. } => {
                "a Com signal does not fit its I-PDU, or its update bit or values are wrong"
            }
        }
    }
}

/// Timing of one TX I-PDU in main-function cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
struct TxTiming {
    period: u32,
    offset: u32,
    repetitions: u8,
    repetition_period: u32,
    direct: bool,
    mdt: u32,
}

/// Validated Com configuration for `N`-byte PDUs: `TX`/`RX` I-PDUs and `S` signals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ComConfig<const N: usize, const TX: usize, const RX: usize, const S: usize> {
    tx: [TxIpduConfig; TX],
    rx: [RxIpduConfig; RX],
    signals: [SignalConfig<N>; S],
    main_period_ms: u32,
    tx_timing: [TxTiming; TX],
    rx_deadline: [u32; RX],
    /// Derived: whether any signal of an RX I-PDU has an update bit.
    rx_update_bits: [bool; RX],
    /// Derived: per TX I-PDU, the update bits of its signals (cleared after sending).
    tx_update_mask: [[u8; N]; TX],
}

const fn cycles(ms: u32, period_ms: u32) -> Option<u32> {
    if ms % period_ms == 0 {
        Some(ms / period_ms)
    } else {
        None
    }
}

const fn fits(value: u64, mask: u64) -> bool {
    value & !mask == 0
}

impl<const N: usize, const TX: usize, const RX: usize, const S: usize> ComConfig<N, TX, RX, S> {
    /// Validates the tables and converts times to main-function cycles.
    ///
    /// # Errors
    /// The first [`ComConfigError`] found.
    pub const fn new(
        main_period_ms: u32,
        tx: [TxIpduConfig; TX],
        rx: [RxIpduConfig; RX],
        signals: [SignalConfig<N>; S],
    ) -> Result<Self, ComConfigError> {
        Self::checked(main_period_ms, tx, rx, signals)
    }

    /// [`Self::new`]'s checks and derived tables. (A function of its own because
    /// cargo-mutants leaves functions named `new` alone: see `docs/src/mutants.md`.)
    const fn checked(
        main_period_ms: u32,
        tx: [TxIpduConfig; TX],
        rx: [RxIpduConfig; RX],
        signals: [SignalConfig<N>; S],
    ) -> Result<Self, ComConfigError> {
        if TX > 254 || RX > 254 || S > 254 || main_period_ms == 0 {
            return Err(ComConfigError::Limits);
        }
        let mut tx_timing = [TxTiming {
            period: 0,
            offset: 0,
            repetitions: 0,
            repetition_period: 0,
            direct: false,
            mdt: 0,
        }; TX];
        let mut i = 0;
        while i < TX {
            let ipdu = i as u16;
            if tx[i].len == 0 || tx[i].len as usize > N {
                return Err(ComConfigError::IpduLength { ipdu });
            }
            let timing = &mut tx_timing[i];
            let (period, offset, reps, rep_period, direct) = match tx[i].mode {
                TxMode::None => (0, 0, 0, 0, false),
                TxMode::Periodic {
                    period_ms,
                    offset_ms,
                } => (period_ms, offset_ms, 0, 0, false),
                TxMode::Direct {
                    repetitions,
                    repetition_period_ms,
                } => (0, 0, repetitions, repetition_period_ms, true),
                TxMode::Mixed {
                    period_ms,
                    offset_ms,
                    repetitions,
                    repetition_period_ms,
                } => (
                    period_ms,
                    offset_ms,
                    repetitions,
                    repetition_period_ms,
                    true,
                ),
            };
            let (Some(p), Some(o), Some(r), Some(m)) = (
                cycles(period, main_period_ms),
                cycles(offset, main_period_ms),
                cycles(rep_period, main_period_ms),
                cycles(tx[i].mdt_ms, main_period_ms),
            ) else {
                return Err(ComConfigError::Timing { ipdu });
            };
            let periodic = !matches!(tx[i].mode, TxMode::None | TxMode::Direct { .. });
            if (periodic && p == 0) || (reps > 0 && r == 0) {
                return Err(ComConfigError::Timing { ipdu });
            }
            timing.period = p;
            timing.offset = o;
            timing.repetitions = reps;
            timing.repetition_period = r;
            timing.direct = direct;
            timing.mdt = m;
            i += 1;
        }
        let mut rx_deadline = [0u32; RX];
        let mut i = 0;
        while i < RX {
            let ipdu = (TX + i) as u16;
            if rx[i].len == 0 || rx[i].len as usize > N {
                return Err(ComConfigError::IpduLength { ipdu });
            }
            match cycles(rx[i].deadline_ms, main_period_ms) {
                Some(d) => rx_deadline[i] = d,
                None => return Err(ComConfigError::Timing { ipdu }),
            }
            i += 1;
        }
        let mut rx_update_bits = [false; RX];
        let mut tx_update_mask = [[0u8; N]; TX];
        let mut s = 0;
        while s < S {
            let sig = &signals[s];
            let err = Err(ComConfigError::Signal { signal: s as u16 });
            let len = match sig.direction {
                SignalDirection::Tx(id, _) if (id.0 as usize) < TX => tx[id.0 as usize].len,
                SignalDirection::Rx(id) if (id.0 as usize) < RX => rx[id.0 as usize].len,
                _ => return err,
            };
            if !super::signal::spec::layout_fits(
                len as usize,
                sig.layout.start_bit(),
                sig.layout.length_bits(),
                sig.layout.byte_order(),
            ) {
                return err;
            }
            let mask = sig.layout.mask();
            if !fits(sig.init, mask) {
                return err;
            }
            if let Some(invalid) = sig.invalid {
                if !fits(invalid, mask) {
                    return err;
                }
            }
            if let Some(bit) = sig.update_bit {
                if bit as usize >= len as usize * 8 {
                    return err;
                }
                // The update bit must not be one of the signal's own bits.
                let mut k = 0;
                while k < sig.layout.length_bits() {
                    let p = super::signal::spec::bit_position(
                        sig.layout.start_bit(),
                        sig.layout.length_bits(),
                        sig.layout.byte_order(),
                        k,
                    );
                    if p == bit as usize {
                        return err;
                    }
                    k += 1;
                }
                match sig.direction {
                    SignalDirection::Rx(id) => rx_update_bits[id.0 as usize] = true,
                    SignalDirection::Tx(id, _) => {
                        tx_update_mask[id.0 as usize][bit as usize / 8] |= 1 << (bit % 8);
                    }
                }
            }
            s += 1;
        }
        Ok(Self {
            tx,
            rx,
            signals,
            main_period_ms,
            tx_timing,
            rx_deadline,
            rx_update_bits,
            tx_update_mask,
        })
    }

    /// The signal table.
    pub const fn signals(&self) -> &[SignalConfig<N>; S] {
        &self.signals
    }

    /// The TX I-PDU table.
    pub const fn tx(&self) -> &[TxIpduConfig; TX] {
        &self.tx
    }

    /// The RX I-PDU table.
    pub const fn rx(&self) -> &[RxIpduConfig; RX] {
        &self.rx
    }

    /// The main-function period, ms.
    pub const fn main_period_ms(&self) -> u32 {
        self.main_period_ms
    }
}

/// Why a Com call was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ComError {
    /// No such signal, or the signal has the other direction.
    UnknownSignal,
    /// The value does not fit the signal.
    OutOfRange,
    /// The received value is the signal's invalidation value.
    Invalid,
    /// The signal has no invalidation value.
    NoInvalidValue,
}

/// A hierarchical timer wheel over `K` entries (I-PDUs), each filed for one cycle: O(1)
/// filing, and a main function visits only the entries due in its cycle.
///
/// Distances count from `next`, the first cycle whose slot is still to be taken (the
/// cycle after the caller's). Level 0 is a plain wheel of `WHEEL` one-cycle slots: an
/// entry due less than `WHEEL` cycles after `next` waits in slot `due % WHEEL` and is
/// taken in cycle `due`. Level `l` has `WHEEL` slots of `WHEEL^l` cycles each (a block)
/// and holds the entries due `WHEEL^l` to `WHEEL^(l+1) - 1` cycles after `next`, in the
/// slot of `due`'s block. In the first cycle of a block (a multiple of `WHEEL^l`) the
/// block's slot is emptied and its entries, all due within the block, are filed again from
/// there: they land on a lower level ("cascade"). The first start of a block in that slot
/// after filing is the start of `due`'s own block (the one before is `WHEEL^(l+1)` cycles
/// earlier, before the filing), so an entry is moved at most once per level on its way
/// down and is taken exactly in cycle `due`. A cycle therefore visits the entries due in
/// it and, on a block start, the entries due within the block that starts; an entry whose
/// event lies beyond is not looked at. [`LEVELS`] levels cover every `u32` distance.
///
/// Order: the entries due in one cycle are handled last-filed first. Filing pushes at the
/// front of a list; a cascade appends at the end, because an entry filed directly on a
/// level was filed after every entry for the same cycle that comes down to it (it was
/// nearer then). Entries filed at most `WHEEL` cycles ahead thus go to level 0 exactly as
/// in a one-level wheel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Wheel<const K: usize> {
    /// List heads: level `l`, slot `s` at `l * WHEEL + s`.
    head: [u8; LEVELS * WHEEL],
    next: [u8; K],
    /// The cycle each filed entry is filed for.
    due: [u32; K],
    /// The list (index into `head`) each entry is in, or [`UNFILED`].
    list: [u16; K],
}

impl<const K: usize> Wheel<K> {
    const fn new() -> Self {
        Self {
            head: [NIL; LEVELS * WHEEL],
            next: [NIL; K],
            due: [0; K],
            list: [UNFILED; K],
        }
    }

    /// Files entry `k` for cycle `due`; `now` is the cycle the caller is at (already
    /// taken), so an entry due in `now` or earlier is filed for `now + 1`, the first cycle
    /// still to be taken. An entry already filed for the same or an earlier cycle stays
    /// where it is (its slot re-files it when it comes up); one filed for a later cycle is
    /// moved.
    fn file(&mut self, k: usize, due: u32, now: u32) {
        if k >= K {
            return;
        }
        let next = now.wrapping_add(1);
        let due = due.max(next);
        if self.list[k] != UNFILED {
            if self.due[k] <= due {
                return;
            }
            self.unlink(k);
        }
        self.push(k, due, next);
    }

    /// Puts entry `k` at the front of the list for cycle `due`, where `next` is the first
    /// cycle whose level-0 slot is still to be taken.
    fn push(&mut self, k: usize, due: u32, next: u32) {
        let list = list_for(due, next);
        self.next[k] = self.head[list];
        self.head[list] = k as u8;
        self.due[k] = due;
        self.list[k] = list as u16;
    }

    /// Puts entry `k`, filed for `self.due[k]`, at the end of its list as seen from cycle
    /// `next` (a cascade: the entries filed there directly are all younger).
    fn append(&mut self, k: usize, next: u32) {
        let list = list_for(self.due[k], next);
        self.next[k] = NIL;
        self.list[k] = list as u16;
        let mut node = self.head[list] as usize;
        if node >= K {
            self.head[list] = k as u8;
            return;
        }
        while (self.next[node] as usize) < K {
            node = self.next[node] as usize;
        }
        self.next[node] = k as u8;
    }

    /// Removes filed entry `k` from its list.
    fn unlink(&mut self, k: usize) {
        let list = usize::from(self.list[k]);
        self.list[k] = UNFILED;
        // Always in range for a filed entry; `get_mut` keeps a panic path out of the code.
        let Some(head) = self.head.get_mut(list) else {
            return;
        };
        if *head as usize == k {
            *head = self.next[k];
        } else {
            let mut node = *head as usize;
            while node < K {
                if self.next[node] as usize == k {
                    self.next[node] = self.next[k];
                    break;
                }
                node = self.next[node] as usize;
            }
        }
    }

    /// Whether cycle `now` has work for [`Self::take`]: entries filed for it, or entries
    /// to bring down because a block starts. A level-1 block starts every `WHEEL` cycles
    /// and its slot is empty unless something is due in it; higher levels are looked at
    /// every `WHEEL^2` cycles. An idle cycle costs this check only.
    #[inline(always)]
    fn busy(&self, now: u32) -> bool {
        let slot = now as usize % WHEEL;
        if slot == 0 {
            return block_start_busy(&self.head, now);
        }
        self.head[slot] != NIL
    }

    /// Detaches the list of the entries due in cycle `now`, after bringing down those due
    /// in the blocks that start in `now`; the caller handles them and re-files what is not
    /// due yet.
    fn take(&mut self, now: u32) -> u8 {
        if now % WHEEL as u32 == 0 {
            self.cascade(now);
        }
        core::mem::replace(&mut self.head[now as usize % WHEEL], NIL)
    }

    /// Cycle `now` starts a block on level 1 and maybe on higher levels: each such level's
    /// slot for the block is emptied and its entries are appended to the lists they belong
    /// in as seen from `now` (one or more levels lower; one due in `now` lands in level 0's
    /// slot for `now`, taken next). Finest level first, so that for each cycle the older
    /// entries (from the coarser levels) come last. No entry lands in a slot emptied here:
    /// one that goes from level `l` to a level `j >= 1` is due `WHEEL^j` to `WHEEL^l - 1`
    /// cycles after `now`, a multiple of `WHEEL^l`, so in a later level-`j` block.
    fn cascade(&mut self, now: u32) {
        for level in 1..LEVELS {
            let shift = level as u32 * SLOT_BITS;
            // A level-`l` block starts in the cycles that are multiples of `WHEEL^l`.
            if now & ((1 << shift) - 1) != 0 {
                break;
            }
            let block = (now >> shift) as usize % WHEEL;
            let mut entries = core::mem::replace(&mut self.head[level * WHEEL + block], NIL);
            while let Some(k) = self.pop(&mut entries) {
                self.append(k, now);
            }
        }
    }

    /// Next entry of a detached list, un-filing it.
    fn pop(&mut self, list: &mut u8) -> Option<usize> {
        let k = *list as usize;
        if k >= K {
            return None;
        }
        *list = self.next[k];
        self.list[k] = UNFILED;
        Some(k)
    }
}

/// [`Wheel::busy`] for a cycle that starts a level-1 block (one in `WHEEL`, out of line).
#[cold]
#[inline(never)]
fn block_start_busy(head: &[u8; LEVELS * WHEEL], now: u32) -> bool {
    head[0] != NIL
        || now % (WHEEL * WHEEL) as u32 == 0
        || head[WHEEL + (now as usize / WHEEL) % WHEEL] != NIL
}

/// The list (index into `Wheel::head`) for an entry due in cycle `due`, where `next` is
/// the first cycle whose level-0 slot is still to be taken: level 0 if `due` is among the
/// `WHEEL` cycles from `next` on (or already past), else the level `l` with
/// `WHEEL^l <= due - next < WHEEL^(l+1)`, in the slot of `due`'s block.
#[inline(always)]
fn list_for(due: u32, next: u32) -> usize {
    let distance = due.saturating_sub(next);
    if distance < WHEEL as u32 {
        return due as usize % WHEEL;
    }
    // At most (32 - 1) / SLOT_BITS, which is below LEVELS (asserted where LEVELS is).
    let level = ((u32::BITS - 1 - distance.leading_zeros()) / SLOT_BITS) as usize;
    level * WHEEL + (due >> (level as u32 * SLOT_BITS)) as usize % WHEEL
}

/// The Com state for a configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Com<
    const N: usize,
    const TX: usize,
    const RX: usize,
    const S: usize,
    C = &'static ComConfig<N, TX, RX, S>,
> {
    cfg: C,
    tx_buf: [[u8; N]; TX],
    rx_buf: [[u8; N]; RX],
    /// Main-function calls so far: the current call is numbered `tx_now` (1-based), and a
    /// write between calls happens at the time of the last call.
    tx_now: u32,
    rx_now: u32,
    /// Next periodic transmission (cycle), per TX I-PDU.
    tx_next_periodic: [u32; TX],
    /// Repetitions still to send, and when the next is due.
    tx_reps_left: [u8; TX],
    tx_next_rep: [u32; TX],
    /// A triggered transmission waiting for the MDT to expire.
    tx_deferred: [bool; TX],
    /// Cycle of the last transmission, or `None`.
    tx_last: [Option<u32>; TX],
    tx_wheel: Wheel<TX>,
    /// Deadline (cycle) of each monitored RX I-PDU; timed-out flags.
    rx_due: [u32; RX],
    rx_timed_out: [bool; RX],
    rx_wheel: Wheel<RX>,
}

impl<const N: usize, const TX: usize, const RX: usize, const S: usize, C> Com<N, TX, RX, S, C>
where
    C: Tables<ComConfig<N, TX, RX, S>>,
{
    /// `Com_Init`: every signal holds its init value; periodic I-PDUs start after their
    /// offset; deadline monitoring starts now.
    pub fn new(cfg: C) -> Self {
        Self::init(cfg)
    }

    /// [`Self::new`]'s work. (A function of its own because cargo-mutants leaves functions
    /// named `new` alone: see `docs/src/mutants.md`.)
    fn init(cfg: C) -> Self {
        let mut com = Self {
            cfg,
            tx_buf: [[0; N]; TX],
            rx_buf: [[0; N]; RX],
            tx_now: 0,
            rx_now: 0,
            tx_next_periodic: [0; TX],
            tx_reps_left: [0; TX],
            tx_next_rep: [0; TX],
            tx_deferred: [false; TX],
            tx_last: [None; TX],
            tx_wheel: Wheel::new(),
            rx_due: [0; RX],
            rx_timed_out: [false; RX],
            rx_wheel: Wheel::new(),
        };
        for s in 0..S {
            com.write_init(s);
        }
        for i in 0..TX {
            let t = cfg.tables().tx_timing[i];
            if t.period > 0 {
                // Offset 0: the first main function call (call number 1) transmits.
                com.tx_next_periodic[i] = t.offset + 1;
                com.tx_wheel.file(i, t.offset + 1, 0);
            }
        }
        for i in 0..RX {
            let d = cfg.tables().rx_deadline[i];
            if d > 0 {
                // Counted down by the main function: the d-th call without a reception.
                com.rx_due[i] = d;
                com.rx_wheel.file(i, d, 0);
            }
        }
        com
    }

    fn write_init(&mut self, s: usize) {
        let Some(&sig) = self.cfg().signals.get(s) else {
            return;
        };
        match sig.direction {
            SignalDirection::Tx(id, _) => {
                if let Some(buf) = self.tx_buf.get_mut(usize::from(id.0)) {
                    sig.layout.pack_masked(buf, sig.init);
                }
            }
            SignalDirection::Rx(id) => {
                if let Some(buf) = self.rx_buf.get_mut(usize::from(id.0)) {
                    sig.layout.pack_masked(buf, sig.init);
                }
            }
        }
    }

    /// The current contents of a TX I-PDU (its configured length).
    pub fn tx_ipdu(&self, id: TxIpduId) -> Option<&[u8]> {
        let len = usize::from(self.cfg().tx.get(usize::from(id.0))?.len);
        self.tx_buf.get(usize::from(id.0)).map(|b| &b[..len])
    }

    /// Whether an RX I-PDU's deadline expired since its last reception.
    pub fn rx_timed_out(&self, id: RxIpduId) -> bool {
        self.rx_timed_out
            .get(usize::from(id.0))
            .copied()
            .unwrap_or(false)
    }

    /// `Com_SendSignal`: writes the value into its I-PDU and, if the transfer property and
    /// the transmission mode say so, transmits through `transmit` now (or when the MDT
    /// expires).
    ///
    /// # Errors
    /// [`ComError::UnknownSignal`] or [`ComError::OutOfRange`]; nothing changes then.
    ///
    /// Always inlined: a call that names its signal by a constant (as generated RTE code
    /// does) folds the lookup, the layout and the transfer property with a constant
    /// table (`Tables`), leaving the pack and the I-PDU's update.
    #[inline(always)]
    pub fn send_signal(
        &mut self,
        signal: SignalId,
        value: SignalValue,
        transmit: impl FnMut(TxIpduId, &[u8]) -> bool,
    ) -> Result<(), ComError> {
        let (sig, i, property) = self.tx_signal(signal)?;
        let buf = self.tx_buf.get_mut(i).ok_or(ComError::UnknownSignal)?;
        // Only the on-change properties need the old value.
        let on_change = matches!(
            property,
            TransferProperty::TriggeredOnChange
                | TransferProperty::TriggeredOnChangeWithoutRepetition
        );
        let old = if on_change {
            sig.layout.unpack_raw(buf)
        } else {
            0
        };
        sig.layout
            .pack(buf, value)
            .map_err(|_| ComError::OutOfRange)?;
        let changed = on_change && sig.layout.unpack_raw(buf) != old;
        self.after_write(sig, i, property, changed, transmit);
        Ok(())
    }

    /// A transmitted signal's configuration, I-PDU index and transfer property.
    #[inline(always)]
    fn tx_signal(
        &self,
        signal: SignalId,
    ) -> Result<(&'static SignalConfig<N>, usize, TransferProperty), ComError> {
        let cfg = self.cfg();
        let sig = cfg
            .signals
            .get(usize::from(signal.0))
            .ok_or(ComError::UnknownSignal)?;
        match sig.direction {
            SignalDirection::Tx(ipdu, property) => Ok((sig, usize::from(ipdu.0), property)),
            SignalDirection::Rx(_) => Err(ComError::UnknownSignal),
        }
    }

    /// `Com_InvalidateSignal`: writes the signal's invalidation value, with the same
    /// transmission behaviour as a write.
    ///
    /// # Errors
    /// [`ComError::UnknownSignal`] or [`ComError::NoInvalidValue`].
    #[inline(always)]
    pub fn invalidate_signal(
        &mut self,
        signal: SignalId,
        transmit: impl FnMut(TxIpduId, &[u8]) -> bool,
    ) -> Result<(), ComError> {
        let (sig, i, property) = self.tx_signal(signal)?;
        let invalid = sig.invalid.ok_or(ComError::NoInvalidValue)?;
        let buf = self.tx_buf.get_mut(i).ok_or(ComError::UnknownSignal)?;
        let changed = sig.layout.unpack_raw(buf) != invalid;
        sig.layout.pack_masked(buf, invalid);
        self.after_write(sig, i, property, changed, transmit);
        Ok(())
    }

    #[inline(always)]
    fn after_write(
        &mut self,
        sig: &SignalConfig<N>,
        i: usize,
        property: TransferProperty,
        changed: bool,
        transmit: impl FnMut(TxIpduId, &[u8]) -> bool,
    ) {
        if let Some(bit) = sig.update_bit {
            set_bit(&mut self.tx_buf[i], bit);
        }
        let timing = self.cfg().tx_timing[i];
        let (triggers, repeat) = match property {
            TransferProperty::Pending => (false, false),
            TransferProperty::Triggered => (true, true),
            TransferProperty::TriggeredOnChange => (changed, true),
            TransferProperty::TriggeredWithoutRepetition => (true, false),
            TransferProperty::TriggeredOnChangeWithoutRepetition => (changed, false),
        };
        if triggers && timing.direct {
            self.tx_reps_left[i] = if repeat { timing.repetitions } else { 0 };
            self.request(i, transmit);
        }
    }

    /// A triggered transmission of I-PDU `i`: now if the MDT allows, else at its expiry.
    fn request(&mut self, i: usize, transmit: impl FnMut(TxIpduId, &[u8]) -> bool) {
        let now = self.tx_now;
        let mdt_end = self.mdt_end(i);
        if now >= mdt_end {
            self.send(i, transmit);
            if self.tx_reps_left[i] > 0 {
                self.tx_next_rep[i] = now + self.cfg().tx_timing[i].repetition_period;
                self.tx_wheel.file(i, self.tx_next_rep[i], now);
            }
        } else {
            self.tx_deferred[i] = true;
            self.tx_wheel.file(i, mdt_end, now);
        }
    }

    fn mdt_end(&self, i: usize) -> u32 {
        let mdt = self.cfg().tx_timing[i].mdt;
        match self.tx_last[i] {
            Some(last) if mdt > 0 => last + mdt,
            _ => 0,
        }
    }

    /// Hands I-PDU `i` to the lower layer and clears its update bits.
    fn send(&mut self, i: usize, mut transmit: impl FnMut(TxIpduId, &[u8]) -> bool) {
        let len = usize::from(self.cfg().tx[i].len);
        if transmit(TxIpduId(i as u16), &self.tx_buf[i][..len]) {
            self.tx_last[i] = Some(self.tx_now);
            let mask = &self.cfg().tx_update_mask[i];
            if mask.iter().any(|m| *m != 0) {
                for (byte, m) in self.tx_buf[i].iter_mut().zip(mask) {
                    *byte &= !m;
                }
            }
        }
    }

    /// `Com_MainFunctionTx`: one main-function period has passed; sends what is due
    /// (periodic transmissions, repetitions, transmissions the MDT held back).
    #[inline]
    pub fn main_function_tx(&mut self, transmit: impl FnMut(TxIpduId, &[u8]) -> bool) {
        self.tx_now = self.tx_now.wrapping_add(1);
        if self.tx_wheel.busy(self.tx_now) {
            self.tx_cycle(transmit);
        }
    }

    /// The work of a cycle that is not idle, out of line so that an idle call stays a
    /// few instructions.
    #[inline(never)]
    fn tx_cycle(&mut self, mut transmit: impl FnMut(TxIpduId, &[u8]) -> bool) {
        let now = self.tx_now;
        let mut list = self.tx_wheel.take(now);
        while let Some(i) = self.tx_wheel.pop(&mut list) {
            self.tx_due(i, now, &mut transmit);
        }
    }

    fn tx_due(&mut self, i: usize, now: u32, transmit: &mut impl FnMut(TxIpduId, &[u8]) -> bool) {
        let timing = self.cfg().tx_timing[i];
        let periodic_due = timing.period > 0 && self.tx_next_periodic[i] <= now;
        let rep_due = self.tx_reps_left[i] > 0 && self.tx_next_rep[i] <= now;
        let deferred_due = self.tx_deferred[i];
        if (periodic_due || rep_due || deferred_due) && now >= self.mdt_end(i) {
            self.tx_deferred[i] = false;
            if rep_due && !deferred_due {
                self.tx_reps_left[i] -= 1;
            }
            self.send(i, &mut *transmit);
            if periodic_due {
                self.tx_next_periodic[i] = now + timing.period;
            }
            // The next repetition's time (read only while repetitions are left).
            if rep_due || deferred_due {
                self.tx_next_rep[i] = now + timing.repetition_period;
            }
        }
        // A periodic or repeated transmission that the MDT holds back stays due (its time
        // is not advanced) and goes out when the MDT ends. It is not marked deferred: that
        // mark is for a triggered transmission, which does not count as a repetition, and
        // a held repetition must (else repetitions closer than the MDT never end).
        // Re-file for the earliest pending event, and no earlier than the MDT allows.
        let mut next = u32::MAX;
        if timing.period > 0 {
            next = next.min(self.tx_next_periodic[i]);
        }
        if self.tx_reps_left[i] > 0 {
            next = next.min(self.tx_next_rep[i]);
        }
        if self.tx_deferred[i] {
            next = next.min(self.mdt_end(i));
        }
        if next != u32::MAX {
            self.tx_wheel.file(i, next.max(self.mdt_end(i)), now);
        }
    }

    /// `Com_RxIndication`: an RX I-PDU arrived. Signals whose update bit is clear keep their
    /// previous value; the deadline restarts.
    #[inline]
    pub fn rx_indication(&mut self, ipdu: RxIpduId, data: &[u8]) {
        let i = usize::from(ipdu.0);
        let Some(cfg) = self.cfg().rx.get(i) else {
            return;
        };
        let len = usize::from(cfg.len).min(data.len());
        let Some(data) = data.get(..len) else {
            return;
        };
        if self.cfg().rx_update_bits.get(i).copied().unwrap_or(false) {
            self.merge_updated(i, data);
        } else if let Some(buf) = self.rx_buf.get_mut(i).and_then(|b| b.get_mut(..len)) {
            buf.copy_from_slice(data);
        }
        if let Some(timed_out) = self.rx_timed_out.get_mut(i) {
            *timed_out = false;
        }
        let deadline = self.cfg().rx_deadline.get(i).copied().unwrap_or(0);
        if deadline > 0 {
            // The wheel entry stays where it is; its slot re-files it (lazy reset).
            let now = self.rx_now;
            if let Some(due) = self.rx_due.get_mut(i) {
                *due = now + deadline;
            }
        }
    }

    /// Takes over, from `data`, the signals of RX I-PDU `i` that have no update bit or
    /// whose update bit is set.
    fn merge_updated(&mut self, i: usize, data: &[u8]) {
        let mut incoming = [0u8; N];
        incoming[..data.len()].copy_from_slice(data);
        for sig in self.cfg().signals.iter() {
            if sig.direction != SignalDirection::Rx(RxIpduId(i as u16)) {
                continue;
            }
            let take = sig.update_bit.is_none_or(|bit| get_bit(&incoming, bit));
            if take {
                let raw = sig.layout.unpack_raw(&incoming);
                sig.layout.pack_masked(&mut self.rx_buf[i], raw);
            }
        }
    }

    /// `Com_MainFunctionRx`: one main-function period has passed; an RX I-PDU whose
    /// deadline expired gets its signals replaced by their init values, and `on_timeout`
    /// is told. Monitoring then restarts.
    #[inline]
    pub fn main_function_rx(&mut self, on_timeout: impl FnMut(RxIpduId)) {
        self.rx_now = self.rx_now.wrapping_add(1);
        if self.rx_wheel.busy(self.rx_now) {
            self.rx_cycle(on_timeout);
        }
    }

    /// The work of a cycle that is not idle, out of line.
    #[inline(never)]
    fn rx_cycle(&mut self, mut on_timeout: impl FnMut(RxIpduId)) {
        let now = self.rx_now;
        let mut list = self.rx_wheel.take(now);
        while let Some(i) = self.rx_wheel.pop(&mut list) {
            if self.rx_due[i] <= now {
                self.replace_by_init(i);
                self.rx_timed_out[i] = true;
                on_timeout(RxIpduId(i as u16));
                self.rx_due[i] = now + self.cfg().rx_deadline[i];
            }
            self.rx_wheel.file(i, self.rx_due[i], now);
        }
    }

    fn replace_by_init(&mut self, i: usize) {
        for s in 0..S {
            if self.cfg().signals[s].direction == SignalDirection::Rx(RxIpduId(i as u16)) {
                self.write_init(s);
            }
        }
    }

    /// `Com_ReceiveSignal`: the signal's current value, sign-extended for signed signals.
    ///
    /// # Errors
    /// [`ComError::UnknownSignal`]; [`ComError::Invalid`] when the value is the signal's
    /// invalidation value.
    #[inline]
    pub fn receive_signal(&self, signal: SignalId) -> Result<SignalValue, ComError> {
        let sig = self
            .cfg()
            .signals
            .get(usize::from(signal.0))
            .ok_or(ComError::UnknownSignal)?;
        let SignalDirection::Rx(ipdu) = sig.direction else {
            return Err(ComError::UnknownSignal);
        };
        let buf = self
            .rx_buf
            .get(usize::from(ipdu.0))
            .ok_or(ComError::UnknownSignal)?;
        if let Some(invalid) = sig.invalid {
            if sig.layout.unpack_raw(buf) == invalid {
                return Err(ComError::Invalid);
            }
        }
        Ok(sig.layout.unpack(buf))
    }

    /// The signedness of a signal, for callers that convert values.
    pub fn signedness(&self, signal: SignalId) -> Option<Signedness> {
        self.cfg()
            .signals
            .get(usize::from(signal.0))
            .map(|s| s.layout.signedness())
    }

    /// The configuration tables.
    #[inline(always)]
    fn cfg(&self) -> &'static ComConfig<N, TX, RX, S> {
        self.cfg.tables()
    }
}

/// Sets bit `bit` of `buf` (an update bit: they are cleared through the I-PDU's mask).
fn set_bit<const N: usize>(buf: &mut [u8; N], bit: u16) {
    if let Some(b) = buf.get_mut(usize::from(bit / 8)) {
        *b |= 1u8 << (bit % 8);
    }
}

fn get_bit<const N: usize>(buf: &[u8; N], bit: u16) -> bool {
    buf.get(usize::from(bit / 8))
        .is_some_and(|b| b & (1 << (bit % 8)) != 0)
}

#[cfg(test)]
mod tests;
