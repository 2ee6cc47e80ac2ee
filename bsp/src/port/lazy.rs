//! A task's lock kept outside the kernel, the part both ports share: one word that holds
//! the kernel's answer to which resources the running task may lock so
//! ([`OsKernel::lock_free_resources`]), or the lock itself, or the kernel call's flag; a
//! copy of the answer for the release; the lock's hand-over to the kernel at the next
//! kernel call. The rules are in the preemptive port's module (`preempt`), which adds the
//! interrupt masks a CPU needs around the store; the host port, whose interrupts come
//! only between jobs, keeps the lock with the store alone.
//!
//! The book: [the OS](../../../../book/os.html), "A task's lock outside the kernel".

use core::sync::atomic::{compiler_fence, AtomicU32, Ordering};

use cw_core::os::{lock_free_bit, ResourceId, LOCK_FREE_RESOURCES};

use super::OsKernel;

/// The word's values, one place for them: the kernel's answer (its bits below 24:
/// [`lock_free_bit`]), a lock kept outside the kernel ([`word::locked`]: [`word::LOCKED`]
/// and the resource's number in the bits above 24, with [`word::MASKED`]), or
/// [`word::IN_KERNEL`]. Neither of the last two has a bit of any answer, so the lock's one
/// test of its resource's bit also finds the word free and no kernel call under way.
pub(crate) mod word {
    use cw_core::os::ResourceId;

    /// A kernel call is under way (the preemptive port's re-entrance flag).
    pub const IN_KERNEL: u32 = 1 << 31;
    /// The word holds a lock kept outside the kernel.
    pub const LOCKED: u32 = 1 << 30;
    /// The lock masks the ISRs up to the resource's ceiling (an ISR shares it): its
    /// release must unmask them.
    pub const MASKED: u32 = 1 << 29;
    const RES_SHIFT: u32 = 24;
    const RES: u32 = 0x1F;

    /// A lock of `res` that no kernel call has seen, masking ISRs or not.
    pub const fn locked(res: ResourceId, masked: bool) -> u32 {
        LOCKED | if masked { MASKED } else { 0 } | (res.0 as u32 & RES) << RES_SHIFT
    }

    /// Whether `word` holds a lock (no kernel call under way).
    pub const fn is_locked(word: u32) -> bool {
        word & (LOCKED | IN_KERNEL) == LOCKED
    }

    /// The resource of a lock (of a word that holds one).
    pub const fn resource(word: u32) -> ResourceId {
        ResourceId((word >> RES_SHIFT & RES) as u8)
    }
}

// Every answer's bit lies below the lock's and the flag's, and every resource an answer
// names fits in the lock's bits for its number.
const _: () = assert!(
    lock_free_bit(ResourceId(LOCK_FREE_RESOURCES - 1), true) < 1 << 24
        && lock_free_bit(ResourceId(LOCK_FREE_RESOURCES - 1), false) < 1 << 24
        && word::resource(word::locked(ResourceId(LOCK_FREE_RESOURCES - 1), true)).0
            == LOCK_FREE_RESOURCES - 1
);

/// The lock kept outside the kernel (at most one) and the kernel's last answer to which
/// resources the running task may lock so.
#[derive(Debug)]
pub(crate) struct LazyLock {
    /// The kernel's answer at the end of the last kernel call (one bit of each resource
    /// the running task may lock outside the kernel, of the kind of lock each takes:
    /// [`lock_free_bit`]; 0 where it holds a resource); or the lock the task took since
    /// ([`word::locked`]); or, during a kernel call of the preemptive port,
    /// [`word::IN_KERNEL`] alone ([`LazyLock::begin_kernel`]).
    word: AtomicU32,
    /// The kernel's answer as the last kernel call that asked the kernel gave it, or 0
    /// since a lock kept outside the kernel was handed over (the task holds a resource
    /// then). The release puts it back in the word, and reads it again after: 0 says the
    /// lock was handed over before the store ([`LazyLock::release`]).
    answer: AtomicU32,
}

impl LazyLock {
    /// No lock, and no resource the running task may lock outside the kernel (until the
    /// first kernel call's answer).
    pub(crate) const fn new() -> Self {
        Self {
            word: AtomicU32::new(0),
            answer: AtomicU32::new(0),
        }
    }

    /// Whether the running task may lock `res` outside the kernel now, with the lock of
    /// the kind `masked` says (masking the ISRs up to the ceiling, or nothing): the word
    /// holds the kernel's last answer, which names it by that kind's bit
    /// ([`lock_free_bit`], which a constant `res` folds to a constant). A lock kept so
    /// already, or a kernel call under way, leaves no answer in the word, so no bit.
    #[inline(always)]
    pub(crate) fn may_take(&self, res: ResourceId, masked: bool) -> bool {
        self.word.load(Ordering::Relaxed) & lock_free_bit(res, masked) != 0
    }

    /// Whether the running task may lock `res` outside the kernel now with a lock of
    /// either kind (the host port, which masks nothing).
    #[cfg(feature = "host")]
    #[inline(always)]
    pub(crate) fn may_take_either(&self, res: ResourceId) -> bool {
        let either = lock_free_bit(res, false) | lock_free_bit(res, true);
        self.word.load(Ordering::Relaxed) & either != 0
    }

    /// The lock of `res` of the kind `masked` says, one store in place of the answer
    /// (where [`LazyLock::may_take`] allowed it).
    #[inline(always)]
    pub(crate) fn take(&self, res: ResourceId, masked: bool) {
        self.word
            .store(word::locked(res, masked), Ordering::Relaxed);
    }

    /// Whether the word holds a lock of `res` of the kind `masked` says that no kernel
    /// call has seen (the release of a lock whose taker did not keep how it took it).
    #[inline(always)]
    pub(crate) fn holds(&self, res: ResourceId, masked: bool) -> bool {
        self.word.load(Ordering::Relaxed) == word::locked(res, masked)
    }

    /// The release of the lock the running task took outside the kernel: the answer back
    /// in the word, then the answer read again. A kernel call (an ISR's) that came before
    /// the store handed the lock over and left the answer 0 (the task holds the resource
    /// in the kernel), so the second read says so, and the caller releases by the kernel
    /// (whose end puts the right answer in the word over the one stored here). One that
    /// comes after the store finds no lock to hand over. `between` runs at each point an
    /// interrupt may come (the tests' model CPU takes one there). `false`: released by
    /// the kernel it must be.
    #[inline(always)]
    pub(crate) fn release(&self, between: impl Fn()) -> bool {
        let answer = self.answer.load(Ordering::Relaxed);
        between();
        // The order of the three is the release's whole argument, and they are accesses
        // of two words that nothing else orders: the compiler must neither move the second
        // load above the store nor take the first load's value for it (no instruction on a
        // single core, whose interrupts see its accesses in program order).
        compiler_fence(Ordering::SeqCst);
        self.word.store(answer, Ordering::Relaxed);
        compiler_fence(Ordering::SeqCst);
        between();
        self.answer.load(Ordering::Relaxed) != 0
    }

    /// The release of a lock of `res` that no kernel call has seen, where nothing can come
    /// between the test and the store (the host port: no interrupt comes inside a job,
    /// and its locks are all of the kind that masks nothing): the answer back in the word.
    /// `false`: nothing done (the word holds no such lock).
    #[cfg(feature = "host")]
    #[inline(always)]
    pub(crate) fn clear_alone(&self, res: ResourceId) -> bool {
        if !self.holds(res, false) {
            return false;
        }
        self.word
            .store(self.answer.load(Ordering::Relaxed), Ordering::Relaxed);
        true
    }

    /// `word` (the word as a kernel call found it) where it holds a lock no kernel call
    /// has seen, which the kernel call must hand over ([`LazyLock::hand_over`]) before
    /// anything else.
    #[inline(always)]
    pub(crate) fn to_hand_over(word: u32) -> Option<u32> {
        word::is_locked(word).then_some(word)
    }

    /// The word now (the host port, whose kernel calls do not set the flag).
    #[cfg(feature = "host")]
    #[inline(always)]
    pub(crate) fn now(&self) -> u32 {
        self.word.load(Ordering::Relaxed)
    }

    /// A lock kept outside the kernel meets the first kernel call since: the kernel's
    /// `GetResource` takes it now, for the running task, in the task's call level (the
    /// call's own entry, an ISR's among them, comes after). So the call, and every
    /// decision it makes, sees the lock, and the answer is 0 from here (the task holds a
    /// resource), which the lock's release reads. The service, not its fast path: this is
    /// rare, and an image holds the service once (the ports call this from a function of
    /// their own kept out of line). `false`: the kernel refused it (the ports' contract
    /// broken).
    #[inline(always)]
    pub(crate) fn hand_over<K: OsKernel>(&self, kernel: &mut K, lock: u32) -> bool {
        if kernel.get_resource(word::resource(lock)).is_err() {
            return false;
        }
        self.answer.store(0, Ordering::Relaxed);
        true
    }

    /// The kernel's answer at the end of a kernel call that asked the kernel
    /// ([`OsKernel::lock_free_resources`], or 0 where the caller holds a resource): in the
    /// copy, then in the word, which in the preemptive port ends the kernel call (the flag
    /// cleared with the same store).
    #[inline(always)]
    pub(crate) fn set_answer(&self, answer: u32) {
        self.answer.store(answer, Ordering::Relaxed);
        self.word.store(answer, Ordering::Relaxed);
    }

    /// The end of a kernel call that left the kernel's answer as it was (the preemptive
    /// port): `before`, what [`LazyLock::begin_kernel`] returned, back in the word alone,
    /// or 0 where the call handed a lock over ([`LazyLock::hand_over`] set the copy). The
    /// copy stays: `before` may be the answer a release stored just after a hand-over
    /// (above), which the copy, 0, contradicts until the release's kernel call.
    #[inline(always)]
    pub(crate) fn restore(&self, before: u32) {
        self.word.store(before, Ordering::Relaxed);
    }

    /// No resource may be locked outside the kernel, and none is: the OS stopped (with
    /// no kernel call to hand a lock to, on a fault).
    pub(crate) fn stop(&self) {
        self.set_answer(0);
    }

    /// A kernel call begins (the preemptive port, under its kernel lock): the word becomes
    /// [`word::IN_KERNEL`] alone, and the one before is returned: the answer, for a call
    /// that leaves it as it was ([`LazyLock::restore`]), or a lock to hand over. `None`,
    /// with nothing changed, where a kernel call is under way already.
    #[inline(always)]
    pub(crate) fn begin_kernel(&self) -> Option<u32> {
        let before = self.word.load(Ordering::Relaxed);
        if before & word::IN_KERNEL != 0 {
            return None;
        }
        self.word.store(word::IN_KERNEL, Ordering::Relaxed);
        Some(before)
    }

    /// Whether a kernel call is under way ([`LazyLock::begin_kernel`]).
    #[inline(always)]
    pub(crate) fn in_kernel(&self) -> bool {
        self.word.load(Ordering::Relaxed) & word::IN_KERNEL != 0
    }

    /// The word.
    #[cfg(test)]
    pub(crate) fn word(&self) -> u32 {
        self.word.load(Ordering::Relaxed)
    }

    /// The copy of the kernel's answer.
    #[cfg(test)]
    pub(crate) fn answer(&self) -> u32 {
        self.answer.load(Ordering::Relaxed)
    }
}

/// The harness both ports' tests run (a bolero test and fuzz target): any sequence of
/// steps (the first 24 bytes, each one `step` on the port and on the reference kernel),
/// from `start`'s port and, as the reference, the kernel it holds (`now`); after each
/// step, the kernel a kernel call would see (`view`: the lock kept outside it handed
/// over) is the reference kernel, the one called for every lock.
#[cfg(test)]
pub(crate) fn check_any_steps<P, K: PartialEq>(
    start: impl Fn() -> P + core::panic::RefUnwindSafe,
    now: impl Fn(&P) -> K + core::panic::RefUnwindSafe,
    step: impl Fn(&P, &mut K, u8) + core::panic::RefUnwindSafe,
    view: impl Fn(&P) -> K + core::panic::RefUnwindSafe,
) {
    bolero::check!()
        .with_type::<std::vec::Vec<u8>>()
        .for_each(|ops| {
            let port = start();
            let mut reference = now(&port);
            for &op in ops.iter().take(24) {
                step(&port, &mut reference, op);
                assert!(
                    view(&port) == reference,
                    "after {op}: the kernel differs from the one called for every lock"
                );
            }
        });
}
