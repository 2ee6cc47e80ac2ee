//! A single-producer, single-consumer ring: an interrupt puts values in, a task or the
//! idle loop takes them out, with atomics alone (no lock: the producer never waits for
//! the consumer). The boards' UART sensors use it for bytes (mps2's UART1, the
//! S32K144EVB's LPUART: [`ByteRing`]), the measuring image's trace for its record of job
//! starts ([`WordRing`]).
//!
//! The producer writes a slot and then publishes it with a release store of the tail; the
//! consumer reads slots up to the tail it acquired and hands them back with a release
//! store of the head. A value that finds the ring full is dropped and counted as an
//! overrun, as a UART's own overrun would drop it. The indices count values since start
//! and wrap at 2^32; `N` is a power of two, so `index % N` stays continuous across the
//! wrap.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// An atomic slot of a [`Ring`]: the value type it holds.
pub trait Slot {
    /// What the slot holds.
    type Value: Copy;
    /// An empty slot.
    const EMPTY: Self;
    /// The value in the slot.
    fn get(&self) -> Self::Value;
    /// Puts `value` in the slot.
    fn put(&self, value: Self::Value);
}

impl Slot for AtomicU8 {
    type Value = u8;
    const EMPTY: Self = AtomicU8::new(0);
    fn get(&self) -> u8 {
        self.load(Ordering::Relaxed)
    }
    fn put(&self, value: u8) {
        self.store(value, Ordering::Relaxed);
    }
}

impl Slot for AtomicU32 {
    type Value = u32;
    const EMPTY: Self = AtomicU32::new(0);
    fn get(&self) -> u32 {
        self.load(Ordering::Relaxed)
    }
    fn put(&self, value: u32) {
        self.store(value, Ordering::Relaxed);
    }
}

/// The ring: `N` slots of `S` (`N` a power of two, at most 2^31).
pub struct Ring<S, const N: usize> {
    slots: [S; N],
    /// Values written since start (the producer's).
    tail: AtomicU32,
    /// Values read since start (the consumer's).
    head: AtomicU32,
    /// Values offered since start.
    received: AtomicU32,
    /// Values dropped on a full ring.
    overruns: AtomicU32,
}

/// A ring of bytes.
pub type ByteRing<const N: usize> = Ring<AtomicU8, N>;

/// A ring of 32-bit words.
pub type WordRing<const N: usize> = Ring<AtomicU32, N>;

/// What a ring counted since start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RingStats {
    /// Values offered to the ring.
    pub received: u32,
    /// Values dropped because the ring was full.
    pub overruns: u32,
}

impl<S: Slot, const N: usize> Ring<S, N> {
    const SIZE_OK: () = assert!(
        N.is_power_of_two() && N <= 1 << 31,
        "a ring's size is a power of two"
    );

    /// An empty ring.
    #[allow(clippy::let_unit_value)]
    pub const fn new() -> Self {
        let () = Self::SIZE_OK;
        Self {
            slots: [const { S::EMPTY }; N],
            tail: AtomicU32::new(0),
            head: AtomicU32::new(0),
            received: AtomicU32::new(0),
            overruns: AtomicU32::new(0),
        }
    }

    /// The producer's side: `value` in, or `false` (dropped, counted) when the ring is
    /// full. Only one context may push.
    pub fn push(&self, value: S::Value) -> bool {
        self.received.fetch_add(1, Ordering::Relaxed);
        let tail = self.tail.load(Ordering::Relaxed);
        if tail.wrapping_sub(self.head.load(Ordering::Acquire)) as usize >= N {
            self.overruns.fetch_add(1, Ordering::Relaxed);
            return false;
        }
        if let Some(slot) = self.slots.get(tail as usize % N) {
            slot.put(value);
        }
        self.tail.store(tail.wrapping_add(1), Ordering::Release);
        true
    }

    /// The consumer's side: the oldest value not yet taken. Only one context may pop.
    pub fn pop(&self) -> Option<S::Value> {
        let head = self.head.load(Ordering::Relaxed);
        if head == self.tail.load(Ordering::Acquire) {
            return None;
        }
        let value = self.slots.get(head as usize % N).map(Slot::get);
        self.head.store(head.wrapping_add(1), Ordering::Release);
        value
    }

    /// How many values wait in the ring (a snapshot: either side may move it next).
    pub fn len(&self) -> u32 {
        self.tail
            .load(Ordering::Acquire)
            .wrapping_sub(self.head.load(Ordering::Acquire))
    }

    /// Whether no value waits in the ring (a snapshot, as [`Ring::len`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// What the ring counted.
    pub fn stats(&self) -> RingStats {
        RingStats {
            received: self.received.load(Ordering::Relaxed),
            overruns: self.overruns.load(Ordering::Relaxed),
        }
    }
}

impl<S: Slot, const N: usize> Default for Ring<S, N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The ring's contract against a queue of capacity `N`, for any sequence of pushes
/// (`Some(byte)`) and pops (`None`): every pop returns the queue's oldest byte, a push
/// succeeds exactly when the queue has room, and the counters count every push and every
/// dropped byte. `start` sets both indices first (near 2^32, the wrap is exercised).
pub fn behaves_as_a_bounded_queue<const N: usize>(start: u32, ops: &[Option<u8>]) -> bool {
    let ring = ByteRing::<N>::new();
    ring.tail.store(start, Ordering::Relaxed);
    ring.head.store(start, Ordering::Relaxed);
    let mut queue = [0u8; N];
    let (mut first, mut len) = (0usize, 0usize);
    let (mut pushes, mut drops) = (0u32, 0u32);
    for op in ops {
        match *op {
            Some(byte) => {
                pushes += 1;
                let room = len < N;
                if ring.push(byte) != room {
                    return false;
                }
                if room {
                    if let Some(slot) = queue.get_mut((first + len) % N) {
                        *slot = byte;
                    }
                    len += 1;
                } else {
                    drops += 1;
                }
            }
            None => {
                let expected = (len > 0).then(|| queue.get(first).copied()).flatten();
                if ring.pop() != expected {
                    return false;
                }
                if len > 0 {
                    first = (first + 1) % N;
                    len -= 1;
                }
            }
        }
    }
    ring.stats()
        == RingStats {
            received: pushes,
            overruns: drops,
        }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;

    #[test]
    fn bytes_come_out_in_order_and_a_full_ring_drops_and_counts() {
        let ring = ByteRing::<4>::new();
        assert_eq!(ring.pop(), None);
        assert!((1..=4).all(|b| ring.push(b)));
        assert!(!ring.push(5), "full");
        assert_eq!(ring.len(), 4);
        assert_eq!(ring.pop(), Some(1));
        assert!(ring.push(6));
        let out: Vec<_> = core::iter::from_fn(|| ring.pop()).collect();
        assert_eq!(out, [2, 3, 4, 6]);
        assert_eq!(
            ring.stats(),
            RingStats {
                received: 6,
                overruns: 1
            }
        );
    }

    #[test]
    fn a_word_ring_keeps_every_bit_of_its_words() {
        let ring = WordRing::<2>::new();
        assert!(ring.push(u32::MAX) && ring.push(0x8000_0001));
        assert!(!ring.push(7), "full");
        assert_eq!(ring.pop(), Some(u32::MAX));
        assert_eq!(ring.pop(), Some(0x8000_0001));
        assert_eq!(ring.pop(), None);
        assert!(ring.is_empty());
        assert_eq!(
            ring.stats(),
            RingStats {
                received: 3,
                overruns: 1
            }
        );
    }

    /// Random sequences, also across the indices' wrap at 2^32.
    #[test]
    fn the_ring_behaves_as_a_bounded_queue() {
        bolero::check!()
            .with_type::<(bool, Vec<Option<u8>>)>()
            .for_each(|(wrap, ops)| {
                let start = if *wrap { u32::MAX - 3 } else { 0 };
                assert!(behaves_as_a_bounded_queue::<4>(start, ops));
                assert!(behaves_as_a_bounded_queue::<64>(start, ops));
            });
    }

    /// Kani: every sequence of up to 6 operations on a ring of 2, from any start.
    #[cfg(kani)]
    #[kani::proof]
    #[kani::unwind(8)]
    fn every_short_sequence_behaves_as_a_bounded_queue() {
        let start: u32 = kani::any();
        let ops: [Option<u8>; 6] = kani::any();
        let len: usize = kani::any();
        kani::assume(len <= 6);
        assert!(behaves_as_a_bounded_queue::<2>(start, &ops[..len]));
    }
}
