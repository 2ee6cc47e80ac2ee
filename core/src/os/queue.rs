//! Ready queue: one FIFO per priority over a shared pool of `Q` entries, and a 64-bit
//! bitmap of non-empty priorities, so that every operation is O(1): the highest ready
//! priority is `63 - leading_zeros(bitmap)`.
//!
//! The bitmap is kept in words of the processor's size (`usize`): one on a 64-bit host,
//! two on a 32-bit core, where a 64-bit shift by a priority known only at run time takes
//! a dozen instructions and a word's bit three (a load, an or, a store); the highest
//! priority tests the upper word first ([`bits`], whose tests run both layouts).

use core::hash::{Hash, Hasher};

const NIL: u8 = u8::MAX;
const LEVELS: usize = 64;
/// Words of the bitmap.
const WORDS: usize = LEVELS / usize::BITS as usize;

/// A bitmap of the 64 priorities in words of any width that divides 64: bit `p` is bit
/// `p % BITS` of word `p / BITS`.
pub(crate) mod bits {
    /// An unsigned word of a bitmap.
    pub(crate) trait Word: Copy {
        /// Its width.
        const BITS: usize;
        /// Bit `i` (below `BITS`) alone.
        fn bit(i: usize) -> Self;
        /// Whether any bit is set.
        fn any(self) -> bool;
        /// The highest set bit of a word with one set.
        fn top(self) -> usize;
        /// `self | other`.
        fn or(self, other: Self) -> Self;
        /// `self & !other`.
        fn clear(self, other: Self) -> Self;
        /// The word as the low bits of a `u64`.
        fn wide(self) -> u64;
    }

    macro_rules! word {
        ($($t:ty),*) => {$(
            impl Word for $t {
                const BITS: usize = <$t>::BITS as usize;
                #[inline(always)]
                fn bit(i: usize) -> Self {
                    1 << (i % <Self as Word>::BITS)
                }
                #[inline(always)]
                fn any(self) -> bool {
                    self != 0
                }
                #[inline(always)]
                fn top(self) -> usize {
                    <Self as Word>::BITS - 1 - self.leading_zeros() as usize
                }
                #[inline(always)]
                fn or(self, other: Self) -> Self {
                    self | other
                }
                #[inline(always)]
                fn clear(self, other: Self) -> Self {
                    self & !other
                }
                #[inline(always)]
                fn wide(self) -> u64 {
                    self as u64
                }
            }
        )*};
    }
    word!(u32, u64, usize);

    /// Sets bit `p` (below 64; a word index past the map wraps, so the index is always
    /// in range).
    #[inline(always)]
    pub(crate) fn set<W: Word, const N: usize>(map: &mut [W; N], p: usize) {
        let word = &mut map[(p / W::BITS) % N];
        *word = word.or(W::bit(p));
    }

    /// Clears bit `p` (below 64; as for [`set`]).
    #[inline(always)]
    pub(crate) fn clear<W: Word, const N: usize>(map: &mut [W; N], p: usize) {
        let word = &mut map[(p / W::BITS) % N];
        *word = word.clear(W::bit(p));
    }

    /// The highest set bit, the upper words first.
    #[inline(always)]
    pub(crate) fn highest<W: Word>(map: &[W]) -> Option<u8> {
        let mut w = map.len();
        while w > 0 {
            w -= 1;
            let word = map[w];
            if word.any() {
                return Some((w * W::BITS + word.top()) as u8);
            }
        }
        None
    }

    /// The bitmap as one `u64`.
    pub(crate) fn wide<W: Word>(map: &[W]) -> u64 {
        let mut all = 0;
        for (w, word) in map.iter().enumerate() {
            all |= word.wide() << (w * W::BITS);
        }
        all
    }
}

/// The pool is full: more records than the configuration's activations allow. The
/// kernel's limit checks make this unreachable; it is an error value, not a panic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct QueueFull;

#[derive(Debug, Clone, Copy)]
pub(crate) struct ReadyQueue<const Q: usize> {
    /// The non-empty priorities ([`bits`]).
    bitmap: [usize; WORDS],
    head: [u8; LEVELS],
    tail: [u8; LEVELS],
    next: [u8; Q],
    task: [u8; Q],
    free: u8,
}

impl<const Q: usize> ReadyQueue<Q> {
    pub(crate) const fn new() -> Self {
        let mut next = [NIL; Q];
        let mut i = 0;
        while i + 1 < Q {
            next[i] = (i + 1) as u8;
            i += 1;
        }
        Self {
            bitmap: [0; WORDS],
            head: [NIL; LEVELS],
            tail: [NIL; LEVELS],
            next,
            task: [0; Q],
            free: if Q == 0 { NIL } else { 0 },
        }
    }

    /// Highest priority with a ready entry.
    #[inline(always)]
    pub(crate) fn highest(&self) -> Option<u8> {
        bits::highest(&self.bitmap)
    }

    #[inline(always)]
    fn alloc(&mut self, task: u8) -> Result<usize, QueueFull> {
        let slot = self.free as usize;
        if slot >= Q {
            return Err(QueueFull);
        }
        self.free = self.next[slot];
        self.task[slot] = task;
        Ok(slot)
    }

    /// Appends an entry at the tail of `prio` (newest).
    #[inline(always)]
    pub(crate) fn push_back(&mut self, prio: u8, task: u8) -> Result<(), QueueFull> {
        let slot = self.alloc(task)?;
        let p = (prio & 63) as usize;
        let tail = self.tail[p] as usize;
        if tail < Q {
            self.next[tail] = slot as u8;
        } else {
            self.head[p] = slot as u8;
            bits::set(&mut self.bitmap, p);
        }
        self.tail[p] = slot as u8;
        Ok(())
    }

    /// Inserts an entry at the head of `prio` (oldest): a preempted task.
    #[inline]
    pub(crate) fn push_front(&mut self, prio: u8, task: u8) -> Result<(), QueueFull> {
        let slot = self.alloc(task)?;
        let p = (prio & 63) as usize;
        self.next[slot] = self.head[p];
        if self.head[p] == NIL {
            self.tail[p] = slot as u8;
            bits::set(&mut self.bitmap, p);
        }
        self.head[p] = slot as u8;
        Ok(())
    }

    /// Removes and returns the oldest entry of `prio`.
    #[inline]
    pub(crate) fn pop_front(&mut self, prio: u8) -> Option<u8> {
        let p = (prio & 63) as usize;
        let slot = self.head[p] as usize;
        if slot >= Q {
            return None;
        }
        let task = self.task[slot];
        if slot == usize::from(self.tail[p]) {
            self.head[p] = NIL;
            self.tail[p] = NIL;
            bits::clear(&mut self.bitmap, p);
        } else {
            self.head[p] = self.next[slot];
        }
        self.next[slot] = self.free;
        self.free = slot as u8;
        Some(task)
    }

    /// The tasks queued at `prio`, oldest first.
    pub(crate) fn iter(&self, prio: u8) -> Iter<'_, Q> {
        let p = (prio & 63) as usize;
        Iter {
            queue: self,
            slot: self.head[p],
            last: self.tail[p],
            left: Q,
        }
    }

    /// The priorities with ready entries, lowest first. Each holds at least one of the
    /// pool's `Q` records, so there are at most `Q` of them: the walk is bounded by the
    /// configuration, not by the bitmap's 64 bits (which is what lets a model checker
    /// unwind it only `Q` times).
    pub(crate) fn levels(&self) -> impl Iterator<Item = u8> + Clone {
        let mut bits = self.bitmap();
        core::iter::from_fn(move || {
            if bits == 0 {
                return None;
            }
            let p = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            Some(p)
        })
        .take(Q)
    }

    /// Bitmap of non-empty priorities.
    pub(crate) fn bitmap(&self) -> u64 {
        bits::wide(&self.bitmap)
    }
}

/// Iterator over one priority's entries, oldest first. A list never holds more than the
/// pool's `Q` records, and the walk stops there whatever the links say.
#[derive(Clone)]
pub(crate) struct Iter<'a, const Q: usize> {
    queue: &'a ReadyQueue<Q>,
    slot: u8,
    last: u8,
    left: usize,
}

impl<const Q: usize> Iterator for Iter<'_, Q> {
    type Item = u8;
    fn next(&mut self) -> Option<u8> {
        // The count goes down before anything else is looked at, so that it falls by one
        // on every call whatever the links hold.
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let s = self.slot as usize;
        if s >= Q {
            return None;
        }
        self.slot = if self.slot == self.last {
            NIL
        } else {
            self.queue.next[s]
        };
        Some(self.queue.task[s])
    }
}

impl<const Q: usize> PartialEq for ReadyQueue<Q> {
    fn eq(&self, other: &Self) -> bool {
        self.bitmap == other.bitmap && self.levels().all(|p| self.iter(p).eq(other.iter(p)))
    }
}

impl<const Q: usize> Eq for ReadyQueue<Q> {}

impl<const Q: usize> Hash for ReadyQueue<Q> {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.bitmap.hash(state);
        for p in self.levels() {
            for t in self.iter(p) {
                t.hash(state);
            }
            NIL.hash(state);
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use core::hash::BuildHasher;
    use std::collections::hash_map::RandomState;
    use std::vec::Vec;

    fn tasks<const Q: usize>(q: &ReadyQueue<Q>, prio: u8) -> Vec<u8> {
        q.iter(prio).collect()
    }

    /// A queue without room refuses every entry and stays empty.
    #[test]
    fn a_queue_of_no_entries_refuses_every_push() {
        let mut q = ReadyQueue::<0>::new();
        assert_eq!(q.push_back(1, 0), Err(QueueFull));
        assert_eq!(q.push_front(1, 0), Err(QueueFull));
        assert_eq!(q.highest(), None);
        assert_eq!(q.pop_front(1), None);
        assert_eq!(q, ReadyQueue::<0>::new());
    }

    /// Equal (and hashed alike) exactly when every priority holds the same tasks in the
    /// same order, whichever pool slots hold them.
    #[test]
    fn equal_exactly_when_every_priority_holds_the_same_tasks() {
        let hash = RandomState::new();
        let mut a = ReadyQueue::<8>::new();
        let mut b = ReadyQueue::<8>::new();
        assert_eq!(a.push_back(3, 1), Ok(()));
        assert_eq!(a.push_back(3, 2), Ok(()));
        // `b` reaches the same content through other slots.
        assert_eq!(b.push_back(5, 7), Ok(()));
        assert_eq!(b.push_back(3, 1), Ok(()));
        assert_eq!(b.pop_front(5), Some(7));
        assert_eq!(b.push_back(3, 2), Ok(()));
        assert!(a == b);
        assert_eq!(hash.hash_one(a), hash.hash_one(b));
        let mut other_order = ReadyQueue::<8>::new();
        assert_eq!(other_order.push_back(3, 2), Ok(()));
        assert_eq!(other_order.push_back(3, 1), Ok(()));
        let mut other_task = ReadyQueue::<8>::new();
        assert_eq!(other_task.push_back(3, 1), Ok(()));
        assert_eq!(other_task.push_back(3, 4), Ok(()));
        let mut other_priority = ReadyQueue::<8>::new();
        assert_eq!(other_priority.push_back(3, 1), Ok(()));
        assert_eq!(other_priority.push_back(4, 2), Ok(()));
        let mut shorter = ReadyQueue::<8>::new();
        assert_eq!(shorter.push_back(3, 1), Ok(()));
        for differing in [other_order, other_task, other_priority, shorter] {
            assert!(a != differing, "{differing:?}");
            assert!(differing != a, "{differing:?}");
            // Not required of `Hash`, but what keeps the model checker's state sets fast:
            // different queues (here, the same bitmap with other tasks) hash apart.
            assert_ne!(hash.hash_one(a), hash.hash_one(differing), "{differing:?}");
        }
        assert!(ReadyQueue::<8>::new() == ReadyQueue::<8>::new());
        assert!(a != ReadyQueue::<8>::new());
    }

    /// A pool of `Q` records takes exactly `Q` (from either end), refuses the next one
    /// with `QueueFull` and stays as it was; at the largest pool a `u8` slot can address
    /// (255) too.
    fn full_pool_refuses_the_next_record<const Q: usize>() {
        let mut q = ReadyQueue::<Q>::new();
        for i in 0..Q {
            let (prio, task) = ((i % 64) as u8, (i % 251) as u8);
            let pushed = if i % 2 == 0 {
                q.push_back(prio, task)
            } else {
                q.push_front(prio, task)
            };
            assert_eq!(pushed, Ok(()), "record {i} of {Q}");
        }
        let full = q;
        assert_eq!(q.push_back(0, 1), Err(QueueFull));
        assert_eq!(q.push_front(63, 1), Err(QueueFull));
        assert!(q == full);
        let popped: usize = (0..64u8)
            .map(|p| core::iter::from_fn(|| q.pop_front(p)).count())
            .sum();
        assert_eq!(popped, Q);
        assert_eq!((q.bitmap(), q.highest()), (0, None));
        assert_eq!(q.push_back(9, 3), Ok(()));
        assert_eq!(tasks(&q, 9), [3]);
    }

    #[test]
    fn a_full_pool_refuses_the_next_record() {
        full_pool_refuses_the_next_record::<1>();
        full_pool_refuses_the_next_record::<8>();
        full_pool_refuses_the_next_record::<255>();
    }

    /// A list whose links were corrupted into a cycle is walked at most `Q` entries deep,
    /// and the levels of a bitmap with more bits than records at most `Q` wide: the walks
    /// end whatever the state holds.
    #[test]
    fn walks_end_after_the_pool_size_even_on_a_corrupted_queue() {
        let mut q = ReadyQueue::<2>::new();
        assert_eq!(q.push_back(5, 7), Ok(()));
        assert_eq!(q.push_back(5, 8), Ok(()));
        // The tail's link, never read on a sound list, now points back to the head, and
        // the tail is moved off the list so the walk never meets it.
        q.next[1] = 0;
        q.tail[5] = NIL - 1;
        assert_eq!(q.iter(5).take(10).collect::<Vec<_>>(), [7, 8]);
        q.bitmap[0] |= 0b111;
        assert_eq!(q.levels().collect::<Vec<_>>(), [0, 1]);
    }

    /// FIFO per priority, a preempted task back at the head, the highest priority first.
    #[test]
    fn fifo_per_priority_and_preempted_tasks_first() {
        let mut q = ReadyQueue::<4>::new();
        assert_eq!(q.highest(), None);
        assert_eq!(q.push_back(2, 1), Ok(()));
        assert_eq!(q.push_back(2, 2), Ok(()));
        assert_eq!(q.push_front(2, 3), Ok(()));
        assert_eq!(q.push_back(40, 4), Ok(()));
        assert_eq!((q.highest(), q.bitmap()), (Some(40), (1 << 40) | (1 << 2)));
        assert_eq!(tasks(&q, 2), [3, 1, 2]);
        assert_eq!(q.pop_front(40), Some(4));
        assert_eq!(q.pop_front(40), None);
        assert_eq!(q.highest(), Some(2));
        assert_eq!(
            [q.pop_front(2), q.pop_front(2), q.pop_front(2)],
            [Some(3), Some(1), Some(2)]
        );
        assert_eq!(q.highest(), None);
    }

    /// Every set of up to two priorities in the bitmap of two 32-bit words (the Cortex-M's)
    /// and of one 64-bit word (a 64-bit host's) is the same `u64`, with the same highest
    /// bit, through every set and clear.
    #[test]
    fn bitmaps_of_either_width_agree_with_one_u64() {
        fn check<W: bits::Word, const N: usize>(zero: [W; N]) {
            for a in 0..64 {
                for b in 0..64 {
                    let mut map = zero;
                    let mut model = 0u64;
                    for (p, set) in [(a, true), (b, true), (a, false), (b, false)] {
                        if set {
                            bits::set(&mut map, p);
                            model |= 1 << p;
                        } else {
                            bits::clear(&mut map, p);
                            model &= !(1 << p);
                        }
                        let highest = model.checked_ilog2().map(|h| h as u8);
                        assert_eq!((bits::wide(&map), bits::highest(&map)), (model, highest));
                    }
                }
            }
        }
        check([0u32; 2]);
        check([0u64; 1]);
    }

    /// Every two priorities, the same or either side of the bitmap's word boundary (31 and
    /// 32): the bitmap holds exactly their bits, the highest is the larger, and emptying
    /// one level leaves the other's bit.
    #[test]
    fn every_pair_of_priorities_is_marked_and_found() {
        for a in 0..64u8 {
            for b in 0..64u8 {
                let mut q = ReadyQueue::<2>::new();
                assert_eq!(q.push_back(a, 1), Ok(()));
                assert_eq!(q.push_front(b, 2), Ok(()));
                assert_eq!(q.bitmap(), (1u64 << a) | (1u64 << b), "{a} {b}");
                assert_eq!(q.highest(), Some(a.max(b)), "{a} {b}");
                assert_eq!(q.levels().count(), if a == b { 1 } else { 2 });
                assert_eq!(q.pop_front(b), Some(2));
                assert_eq!((q.bitmap(), q.highest()), (1u64 << a, Some(a)), "{a} {b}");
                assert_eq!(q.pop_front(a), Some(1));
                assert_eq!((q.bitmap(), q.highest()), (0, None), "{a} {b}");
            }
        }
    }
}
