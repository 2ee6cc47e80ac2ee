//! Ready queue: one FIFO per priority over a shared pool of `Q` entries, and a 64-bit
//! bitmap of non-empty priorities, so that every operation is O(1): the highest ready
//! priority is `63 - leading_zeros(bitmap)`.
//!
//! The head of a priority may be held outside the pool, in that priority's `front` slot:
//! a preempted task goes there ([`ReadyQueue::push_front`]), one store and the bitmap's
//! bit instead of a record taken from the pool and linked in. The kernel finds the slot
//! free whenever it preempts a task: a preempted task is the head of its priority, so no
//! task is dispatched at that priority, and none is preempted there, before it resumes.
//! (The kernel's tests, the OSEK conformance suite, the exhaustive step sequences and the
//! models never take the other way, which a build that stops there showed.) Where the
//! slot is taken, its task moves to the pool's head first and the order is the same.
//! Every reading of the queue (its entries per priority, equality, the hash) sees the slot
//! as the head: where a record is kept is not part of the queue's state.
//!
//! The bitmap is kept in words of the processor's size (`usize`): one on a 64-bit host,
//! two on a 32-bit core, where a 64-bit shift by a priority known only at run time takes
//! a dozen instructions and a word's bit three (a load, an or, a store); the highest
//! priority tests the upper word first ([`bits`], whose tests run both layouts).

use core::hash::{Hash, Hasher};

const NIL: u8 = u8::MAX;
/// The index of a priority's list head in [`ReadyQueue`]'s `ends`.
const HEAD: usize = 0;
/// The index of a priority's `front` slot in [`ReadyQueue`]'s `ends`.
const FRONT: usize = 1;
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
    /// Per priority, the head of the pool's list (`[HEAD]`: a slot of the pool, or `NIL`)
    /// and the `front` slot (`[FRONT]`: the priority's head when that is held outside the
    /// pool, a preempted task, or `NIL`), which the pool's list follows. One halfword per
    /// priority, so that `pop_front` tests both with one load and one compare
    /// ([`ReadyQueue::pool_head`]).
    ends: [[u8; 2]; LEVELS],
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
            ends: [[NIL; 2]; LEVELS],
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
            self.ends[p][HEAD] = slot as u8;
            bits::set(&mut self.bitmap, p);
        }
        self.tail[p] = slot as u8;
        Ok(())
    }

    /// Inserts an entry at the head of `prio` (oldest): a preempted task. Into the
    /// priority's `front` slot where that is free (the kernel's case, see the module),
    /// with no record of the pool; otherwise the task in the slot moves to the pool's
    /// head first. (A task numbered `NIL`, never the kernel's, goes to the pool's head.)
    #[inline]
    pub(crate) fn push_front(&mut self, prio: u8, task: u8) -> Result<(), QueueFull> {
        let p = (prio & 63) as usize;
        if self.ends[p][FRONT] != NIL || task == NIL {
            return self.push_front_pooled(p, task);
        }
        self.ends[p][FRONT] = task;
        bits::set(&mut self.bitmap, p);
        Ok(())
    }

    /// [`ReadyQueue::push_front`] where the `front` slot is taken (or `task` cannot be
    /// held there): the slot's task to the pool's head, then `task` into the slot (or to
    /// the pool's head before it). `QueueFull` where the pool has no room, with the
    /// entries as they were (the slot's task may have moved to the pool's head, which is
    /// the same place in the order).
    #[cold]
    fn push_front_pooled(&mut self, p: usize, task: u8) -> Result<(), QueueFull> {
        let front = self.ends[p][FRONT];
        if front != NIL {
            self.link_front(p, front)?;
            self.ends[p][FRONT] = NIL;
        }
        if task == NIL {
            return self.link_front(p, task);
        }
        self.ends[p][FRONT] = task;
        Ok(())
    }

    /// A record of the pool for `task` at the head of priority `p`'s list.
    fn link_front(&mut self, p: usize, task: u8) -> Result<(), QueueFull> {
        let slot = self.alloc(task)?;
        self.next[slot] = self.ends[p][HEAD];
        if self.ends[p][HEAD] == NIL {
            self.tail[p] = slot as u8;
        }
        self.ends[p][HEAD] = slot as u8;
        bits::set(&mut self.bitmap, p);
        Ok(())
    }

    /// Removes and returns the oldest entry of `prio`: the `front` slot's task if there
    /// is one, else the head of the pool's list.
    #[inline]
    pub(crate) fn pop_front(&mut self, prio: u8) -> Option<u8> {
        let p = (prio & 63) as usize;
        let Some(slot) = self.pool_head(p) else {
            let front = self.ends[p][FRONT];
            if front == NIL {
                return None;
            }
            self.ends[p][FRONT] = NIL;
            if self.ends[p][HEAD] == NIL {
                bits::clear(&mut self.bitmap, p);
            }
            return Some(front);
        };
        let task = self.task[slot];
        if slot == usize::from(self.tail[p]) {
            self.ends[p][HEAD] = NIL;
            self.tail[p] = NIL;
            bits::clear(&mut self.bitmap, p);
        } else {
            self.ends[p][HEAD] = self.next[slot];
        }
        self.next[slot] = self.free;
        self.free = slot as u8;
        Some(task)
    }

    /// The head of priority `p`'s list in the pool where that is the priority's head (its
    /// `front` slot free and the list not empty): `ends[p]` read as one little-endian
    /// halfword is `0xFF00 + head` exactly then (the slot `NIL` is `0xFF`), so that minus
    /// `0xFF00`, wrapping in 32 bits, is below `Q` exactly then (a `front` slot taken
    /// leaves the halfword below `0xFF00`, and the difference at least `2^32 - 0xFF00`).
    #[inline(always)]
    fn pool_head(&self, p: usize) -> Option<usize> {
        let ends = u32::from(u16::from_le_bytes(self.ends[p]));
        let slot = ends.wrapping_sub(u32::from(NIL) << 8) as usize;
        (slot < Q).then_some(slot)
    }

    /// The tasks queued at `prio`, oldest first.
    pub(crate) fn iter(&self, prio: u8) -> Iter<'_, Q> {
        let p = (prio & 63) as usize;
        Iter {
            queue: self,
            front: self.ends[p][FRONT],
            slot: self.ends[p][HEAD],
            last: self.tail[p],
            left: Q,
        }
    }

    /// The priorities with ready entries, lowest first. The kernel's pool has a record for
    /// every activation there can be at once (`Q`), and each such priority holds at least
    /// one activation (in the pool or in its `front` slot), so there are at most `Q` of
    /// them: the walk is bounded by the configuration, not by the bitmap's 64 bits (which
    /// is what lets a model checker unwind it only `Q` times). (Outside the kernel, a
    /// queue with more `front` slots taken than that is walked over its `Q` lowest
    /// priorities, here and in the comparison and hash that use this.)
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
    /// The `front` slot's task, not yet given (`NIL`: none, or given).
    front: u8,
    slot: u8,
    last: u8,
    left: usize,
}

impl<const Q: usize> Iterator for Iter<'_, Q> {
    type Item = u8;
    fn next(&mut self) -> Option<u8> {
        if self.front != NIL {
            let task = self.front;
            self.front = NIL;
            return Some(task);
        }
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

    /// The same entries at every one of the 64 priorities (`==` walks the `Q` lowest
    /// non-empty ones, all of the kernel's; these tests fill more).
    fn same<const Q: usize>(a: &ReadyQueue<Q>, b: &ReadyQueue<Q>) -> bool {
        a.bitmap() == b.bitmap() && (0..64).all(|p| a.iter(p).eq(b.iter(p)))
    }

    /// A queue without a pool refuses every entry the pool must hold (any at a tail, a
    /// second at a head) and stays as it was; a preempted task needs no record of the pool.
    #[test]
    fn a_queue_of_no_entries_refuses_every_record_of_the_pool() {
        let mut q = ReadyQueue::<0>::new();
        assert_eq!(q.push_back(1, 0), Err(QueueFull));
        assert_eq!(q.push_front(1, NIL), Err(QueueFull));
        assert!(same(&q, &ReadyQueue::<0>::new()));
        assert_eq!(q.highest(), None);
        assert_eq!(q.pop_front(1), None);
        assert_eq!(q.push_front(1, 0), Ok(()));
        let one = q;
        assert_eq!(q.push_front(1, 2), Err(QueueFull));
        assert_eq!(q.push_back(1, 2), Err(QueueFull));
        assert!(same(&q, &one));
        assert_eq!((q.highest(), tasks(&q, 1)), (Some(1), [0].to_vec()));
        assert_eq!(q.pop_front(1), Some(0));
        assert!(same(&q, &ReadyQueue::<0>::new()));
    }

    /// Two tasks put at one priority's head in turn (never the kernel's case): the second
    /// is the head, the first next, then the older entries; also for a task numbered
    /// `NIL`, which the `front` slot cannot hold.
    #[test]
    fn a_second_task_at_the_head_goes_before_the_first() {
        let mut q = ReadyQueue::<4>::new();
        assert_eq!(q.push_back(7, 1), Ok(()));
        assert_eq!(q.push_front(7, 2), Ok(()));
        assert_eq!(q.push_front(7, 3), Ok(()));
        assert_eq!(tasks(&q, 7), [3, 2, 1]);
        assert_eq!(q.push_front(7, NIL), Ok(()));
        assert_eq!(tasks(&q, 7), [NIL, 3, 2, 1]);
        // The pool is full now, its four records in the list; the slot, free, takes a
        // head, and the next head needs a record.
        assert_eq!(q.push_front(7, 4), Ok(()));
        assert_eq!(q.push_front(7, 5), Err(QueueFull));
        assert_eq!(tasks(&q, 7), [4, NIL, 3, 2, 1]);
        let popped: Vec<_> = core::iter::from_fn(|| q.pop_front(7)).collect();
        assert_eq!(popped, [4, NIL, 3, 2, 1]);
        assert_eq!((q.bitmap(), q.highest()), (0, None));
        // A preempted task alone at its priority, the pool's list after it.
        assert_eq!(q.push_front(9, 5), Ok(()));
        assert_eq!(q.push_back(9, 6), Ok(()));
        assert_eq!(q.pop_front(9), Some(5));
        assert_eq!((q.highest(), tasks(&q, 9)), (Some(9), [6].to_vec()));
        assert_eq!(q.pop_front(9), Some(6));
        assert_eq!((q.bitmap(), q.highest()), (0, None));
    }

    /// Any sequence of up to 48 operations (a task at a tail, at a head, the oldest taken;
    /// any task, at eight priorities: both ends of the bitmap and both sides of its
    /// 32-bit words' boundary) against a model of one FIFO per priority: the same entries
    /// in the same order at every priority, the same bitmap and highest priority; a record
    /// is refused only when the entries fill the pool, and a refusal changes nothing. A
    /// test and fuzz target; the kernel's Kani proofs take the queue through the kernel.
    #[test]
    fn any_operations_keep_one_fifo_per_priority() {
        use std::collections::VecDeque;
        const LEVELS: [u8; 8] = [0, 1, 30, 31, 32, 33, 62, 63];
        bolero::check!()
            .with_type::<Vec<(u8, u8, u8)>>()
            .for_each(|ops| {
                let mut q = ReadyQueue::<6>::new();
                let mut model: Vec<VecDeque<u8>> = (0..64).map(|_| VecDeque::new()).collect();
                for &(kind, level, task) in ops.iter().take(48) {
                    let prio = LEVELS[usize::from(level % 8)];
                    let p = usize::from(prio);
                    let entries: usize = model.iter().map(VecDeque::len).sum();
                    let before = q;
                    match kind % 3 {
                        0 | 1 => {
                            let pushed = if kind % 3 == 0 {
                                q.push_back(prio, task)
                            } else {
                                q.push_front(prio, task)
                            };
                            match pushed {
                                Ok(()) if kind % 3 == 0 => model[p].push_back(task),
                                Ok(()) => model[p].push_front(task),
                                Err(QueueFull) => {
                                    assert!(entries >= 6, "refused with {entries} entries");
                                    assert!(same(&q, &before), "a refusal changed the queue");
                                }
                            }
                        }
                        _ => assert_eq!(q.pop_front(prio), model[p].pop_front()),
                    }
                    let mut bitmap = 0u64;
                    for level in LEVELS {
                        let fifo = &model[usize::from(level)];
                        assert!(q.iter(level).eq(fifo.iter().copied()), "priority {level}");
                        if !fifo.is_empty() {
                            bitmap |= 1 << level;
                        }
                    }
                    assert_eq!(q.bitmap(), bitmap);
                    assert_eq!(q.highest(), bitmap.checked_ilog2().map(|h| h as u8));
                }
            });
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

    /// A pool of `Q` records takes exactly `Q` at the tails and refuses the next one with
    /// `QueueFull`, the entries as they were; a head takes no record where its priority's
    /// `front` slot is free, and one where it is not (refused on the full pool); at the
    /// largest pool a `u8` slot can address (255) too.
    fn full_pool_refuses_the_next_record<const Q: usize>() {
        let mut q = ReadyQueue::<Q>::new();
        for i in 0..Q {
            let (prio, task) = ((i % 64) as u8, (i % 251) as u8);
            assert_eq!(q.push_back(prio, task), Ok(()), "record {i} of {Q}");
        }
        let full = q;
        assert_eq!(q.push_back(0, 1), Err(QueueFull));
        assert!(same(&q, &full));
        // Heads in the free slots of every priority: no record of the pool.
        for p in 0..64u8 {
            assert_eq!(q.push_front(p, 252), Ok(()), "priority {p}");
        }
        let heads = q;
        assert_eq!(q.push_front(63, 1), Err(QueueFull));
        assert!(same(&q, &heads));
        let popped: usize = (0..64u8)
            .map(|p| {
                assert_eq!(q.pop_front(p), Some(252), "priority {p}");
                core::iter::from_fn(|| q.pop_front(p)).count()
            })
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
