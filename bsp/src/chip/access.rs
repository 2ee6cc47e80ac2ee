//! The register-access seam of the chip drivers whose accesses have side effects.
//!
//! A driver reaches its peripheral through an [`Access`]: 32-bit loads and stores at
//! offsets from the peripheral's base. On silicon that is [`Mmio`], volatile accesses at
//! the base address (the one `unsafe`); on the host it is a model of the peripheral that
//! answers each access as the silicon does (FlexCAN's
//! [`FlexcanModel`](super::flexcan::FlexcanModel)), or a [`Recorder`] that keeps every
//! access in order, for the tests of a driver's register sequence (unlock, then
//! configure, within so many accesses). A driver names each register as a [`Reg`],
//! typed by its `tock-registers` bitfields, so it reads and writes fields by name.

use core::cell::{Cell, RefCell};
use core::marker::PhantomData;

use tock_registers::interfaces::{Readable, Writeable};
use tock_registers::RegisterLongName;

/// One 32-bit register access path: where the driver's loads and stores go.
pub trait Access {
    /// The word at `offset` from the peripheral's base.
    fn read(&self, offset: usize) -> u32;
    /// Stores `value` at `offset`.
    fn write(&self, offset: usize, value: u32);
}

/// One register of a peripheral, typed by its bitfields `R`.
pub struct Reg<'a, A, R> {
    access: &'a A,
    offset: usize,
    fields: PhantomData<R>,
}

impl<A: Access, R: RegisterLongName> Readable for Reg<'_, A, R> {
    type T = u32;
    type R = R;
    fn get(&self) -> u32 {
        self.access.read(self.offset)
    }
}

impl<A: Access, R: RegisterLongName> Writeable for Reg<'_, A, R> {
    type T = u32;
    type R = R;
    fn set(&self, value: u32) {
        self.access.write(self.offset, value);
    }
}

impl<'a, A, R> Reg<'a, A, R> {
    /// The register at `offset` through `access`.
    pub const fn new(access: &'a A, offset: usize) -> Self {
        Self {
            access,
            offset,
            fields: PhantomData,
        }
    }
}

/// A peripheral on silicon: volatile 32-bit loads and stores at its base address.
#[derive(Debug)]
pub struct Mmio {
    base: *mut u8,
}

impl Mmio {
    /// The peripheral at `base`.
    ///
    /// # Safety
    /// `base` must be the base address of the peripheral the driver over this value is
    /// written for (its registers mapped at the offsets that driver's register view
    /// gives), and the caller the peripheral's only user: every access made through the
    /// returned value is a volatile access to that peripheral.
    pub const unsafe fn new(base: *mut u8) -> Self {
        Self { base }
    }
}

// SAFETY: an `Mmio` is its peripheral's only user (`Mmio::new`'s contract); moving it to
// another context (a task, an ISR, the OS resource that owns the driver) keeps it the only
// user, and every access is a volatile load or store that needs no thread-local state.
unsafe impl Send for Mmio {}

impl Access for Mmio {
    fn read(&self, offset: usize) -> u32 {
        // SAFETY: `Mmio::new`'s contract: `base` is the peripheral's base, and every
        // offset its typed view produces is a 4-aligned register inside its map.
        unsafe { core::ptr::read_volatile(self.base.add(offset).cast::<u32>()) }
    }

    fn write(&self, offset: usize, value: u32) {
        // SAFETY: as in `read`; the peripheral is this value's alone (`Mmio::new`).
        unsafe { core::ptr::write_volatile(self.base.add(offset).cast::<u32>(), value) }
    }
}

/// One access a [`Recorder`] saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Seen {
    /// A load at this offset, which returned this value.
    Read(usize, u32),
    /// A store of this value at this offset.
    Write(usize, u32),
}

/// Registers as plain words that keep the last `N` accesses in order: the host tests of a
/// driver's register sequence. A load returns the last value stored at its offset (or
/// what [`Recorder::preset`] put there).
#[derive(Debug)]
pub struct Recorder<const WORDS: usize, const N: usize> {
    words: [Cell<u32>; WORDS],
    /// Bits that read as set whatever was stored (status bits the silicon sets).
    high: [Cell<u32>; WORDS],
    /// Values the next loads of an offset return, in order, before the stored word
    /// (what the silicon would change between two reads: a counter, a capture).
    script: RefCell<[Option<(usize, u32)>; SCRIPT]>,
    log: RefCell<([Option<Seen>; N], usize)>,
}

/// Scripted loads a [`Recorder`] holds at once.
const SCRIPT: usize = 16;

impl<const WORDS: usize, const N: usize> Default for Recorder<WORDS, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const WORDS: usize, const N: usize> Recorder<WORDS, N> {
    /// All words zero, nothing seen.
    pub fn new() -> Self {
        Self {
            words: core::array::from_fn(|_| Cell::new(0)),
            high: core::array::from_fn(|_| Cell::new(0)),
            script: RefCell::new([None; SCRIPT]),
            log: RefCell::new(([None; N], 0)),
        }
    }

    /// Sets the word at `offset` without recording it (a register's reset value, or what
    /// the silicon would have set).
    pub fn preset(&self, offset: usize, value: u32) {
        if let Some(w) = self.words.get(offset / 4) {
            w.set(value);
        }
    }

    /// Makes the bits of `mask` at `offset` read as set from now on (a status bit the
    /// silicon sets: an acknowledge, a clock valid).
    pub fn hold_high(&self, offset: usize, mask: u32) {
        if let Some(h) = self.high.get(offset / 4) {
            h.set(h.get() | mask);
        }
    }

    /// The next loads of `offset` return `values` in order (after any scripted before
    /// them), then the stored word again; `false` if the script is full.
    pub fn script(&self, offset: usize, values: &[u32]) -> bool {
        let mut script = self.script.borrow_mut();
        let free = script.iter().filter(|s| s.is_none()).count();
        if values.len() > free {
            return false;
        }
        let mut values = values.iter();
        for slot in script.iter_mut().filter(|s| s.is_none()) {
            match values.next() {
                Some(&v) => *slot = Some((offset, v)),
                None => break,
            }
        }
        true
    }

    fn scripted(&self, offset: usize) -> Option<u32> {
        let mut script = self.script.borrow_mut();
        let i = script
            .iter()
            .position(|s| s.is_some_and(|(o, _)| o == offset))?;
        let value = script.get_mut(i).and_then(Option::take).map(|(_, v)| v);
        // The scripted loads stay a prefix, in the order given.
        if let Some(rest) = script.get_mut(i..) {
            rest.rotate_left(1);
        }
        value
    }

    /// The word at `offset` as a load returns it now.
    pub fn word(&self, offset: usize) -> u32 {
        let i = offset / 4;
        self.words.get(i).map_or(0, Cell::get) | self.high.get(i).map_or(0, Cell::get)
    }

    /// The accesses seen, oldest first (the first `N`).
    pub fn seen(&self) -> impl Iterator<Item = Seen> + '_ {
        let log = self.log.borrow();
        let len = log.1.min(N);
        let copy = log.0;
        copy.into_iter().take(len).flatten()
    }

    /// The stores seen, oldest first: `(offset, value)`.
    pub fn writes(&self) -> impl Iterator<Item = (usize, u32)> + '_ {
        self.seen().filter_map(|s| match s {
            Seen::Write(o, v) => Some((o, v)),
            Seen::Read(..) => None,
        })
    }

    fn record(&self, seen: Seen) {
        let mut log = self.log.borrow_mut();
        let at = log.1;
        if let Some(slot) = log.0.get_mut(at) {
            *slot = Some(seen);
        }
        log.1 = at.saturating_add(1);
    }
}

impl<const WORDS: usize, const N: usize> Access for Recorder<WORDS, N> {
    fn read(&self, offset: usize) -> u32 {
        let value = self.scripted(offset).unwrap_or_else(|| self.word(offset));
        self.record(Seen::Read(offset, value));
        value
    }

    fn write(&self, offset: usize, value: u32) {
        self.preset(offset, value);
        self.record(Seen::Write(offset, value));
    }
}

#[cfg(test)]
mod tests {
    use super::{Access, Recorder, Seen};

    #[test]
    fn a_recorder_keeps_accesses_in_order_and_holds_status_bits() {
        let r: Recorder<4, 3> = Recorder::new();
        r.preset(4, 7);
        r.hold_high(8, 0x100);
        r.write(8, 1);
        assert_eq!(r.read(4), 7);
        assert_eq!(r.read(8), 0x101);
        assert_eq!(r.read(0), 0, "only the first three are kept");
        let seen: std::vec::Vec<_> = r.seen().collect();
        assert_eq!(
            seen,
            [Seen::Write(8, 1), Seen::Read(4, 7), Seen::Read(8, 0x101)]
        );
        assert_eq!(r.writes().collect::<std::vec::Vec<_>>(), [(8, 1)]);
        assert_eq!(r.read(64), 0, "outside the words");
    }

    #[test]
    fn scripted_loads_come_first_in_order_then_the_stored_word() {
        let r: Recorder<4, 8> = Recorder::new();
        r.preset(4, 9);
        assert!(r.script(4, &[1, 2]));
        assert!(r.script(0, &[5]));
        assert_eq!([r.read(4), r.read(0)], [1, 5]);
        assert!(r.script(4, &[3]));
        assert_eq!([r.read(4), r.read(4), r.read(4)], [2, 3, 9]);
        assert!(!r.script(4, &[0; 17]), "more than the script holds");
    }
}
