//! Ready queue: one FIFO per priority over a shared pool of `Q` entries, and a 64-bit
//! bitmap of non-empty priorities, so that every operation is O(1): the highest ready
//! priority is `63 - leading_zeros(bitmap)`.
//!
//! Each entry is one activation record (a task id). A list ends at its `tail`: the `next`
//! link of the newest entry is never read, so appending writes no terminator. Equality and hashing look at the
//! logical content (the sequence of tasks at each priority), not at which pool slots hold
//! it, so two queues that will behave the same compare equal.

use core::hash::{Hash, Hasher};

const NIL: u8 = u8::MAX;
const LEVELS: usize = 64;

/// The pool is full: more records than the configuration's activations allow. The
/// kernel's limit checks make this unreachable; it is an error value, not a panic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct QueueFull;

#[derive(Debug, Clone, Copy)]
pub(crate) struct ReadyQueue<const Q: usize> {
    bitmap: u64,
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
            bitmap: 0,
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
        if self.bitmap == 0 {
            None
        } else {
            Some(63 - self.bitmap.leading_zeros() as u8)
        }
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
            self.bitmap |= 1 << p;
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
            self.bitmap |= 1 << p;
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
            self.bitmap &= !(1 << p);
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
        let mut bits = self.bitmap;
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
        self.bitmap
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
        q.bitmap |= 0b111;
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
}
