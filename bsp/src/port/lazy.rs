//! A task's lock kept outside the kernel, the part both ports share: the port's word that
//! holds the lock, the kernel's answer to which resources the running task may lock so
//! ([`OsKernel::lock_free_resources`]), the lock's hand-over to the kernel at the next
//! kernel call, and the release. The rules are in the preemptive port's module
//! (`preempt`), which adds the interrupt masks a CPU needs around the store; the host
//! port, whose interrupts come only between jobs, keeps the lock with the store alone.
//!
//! The book: [the OS](../../../../book/os.html), "A task's lock outside the kernel".

use core::sync::atomic::{AtomicU32, Ordering};

use cw_core::os::{lock_free_bit, ResourceId};

use super::OsKernel;

/// The word's layout, one place for it: the resource + 1 (bits 0-7; 0: no lock), the
/// task + 1 once handed over (bits 8-15), [`HANDED`](word::HANDED) and
/// [`MASKED`](word::MASKED).
pub(crate) mod word {
    use cw_core::os::ResourceId;

    /// The bit that says the kernel holds the lock for the task.
    pub const HANDED: u32 = 1 << 16;
    /// The bit that says the lock masks the ISRs up to the resource's ceiling (an ISR
    /// shares it): its release must unmask them, and a release of the other kind finds
    /// another word and goes to the kernel.
    pub const MASKED: u32 = 1 << 17;
    const RES: u32 = 0xFF;
    const OWNER_SHIFT: u32 = 8;

    /// A lock of `res` that no kernel call has seen, masking ISRs or not.
    pub const fn unhanded(res: ResourceId, masked: bool) -> u32 {
        (res.0 as u32 + 1) | if masked { MASKED } else { 0 }
    }

    /// `lazy`, handed to the kernel for task slot `owner`.
    pub const fn handed(lazy: u32, owner: u8) -> u32 {
        lazy | HANDED | (owner as u32 + 1) << OWNER_SHIFT
    }

    /// Whether `lazy` is a lock no kernel call has seen.
    pub const fn is_unhanded(lazy: u32) -> bool {
        lazy != 0 && lazy & HANDED == 0
    }

    /// The resource of a lock (of a word that holds one).
    pub const fn resource(lazy: u32) -> ResourceId {
        ResourceId(((lazy & RES) as u8).wrapping_sub(1))
    }

    /// Whether `lazy` is a lock of `res` handed over (to any owner, of either kind).
    pub const fn handed_of(lazy: u32, res: ResourceId) -> bool {
        // (The owner's bits and the kind cleared: one instruction on the Cortex-M.)
        lazy & !(RES << OWNER_SHIFT | MASKED) == unhanded(res, false) | HANDED
    }

    /// Whether `lazy` was handed over for task slot `owner`.
    pub const fn owned_by(lazy: u32, owner: u8) -> bool {
        (lazy >> OWNER_SHIFT) & RES == owner as u32 + 1
    }
}

/// The lock kept outside the kernel (at most one) and the kernel's last answer to which
/// resources the running task may lock so.
#[derive(Debug)]
pub(crate) struct LazyLock {
    /// 0, or the lock, and once a kernel call has handed it to the kernel, its task
    /// ([`word`]).
    word: AtomicU32,
    /// The resources the running task may lock outside the kernel, one bit each of the
    /// kind of lock each takes ([`lock_free_bit`]): the kernel's answer at the end of
    /// the last kernel call, 0 after a lock by the kernel's
    /// fast path (the caller then holds a resource). During a kernel call of the
    /// preemptive port, [`IN_KERNEL`] alone: the port's re-entrance flag, and no resource
    /// (a hook's lock goes to the kernel), in the word the lock outside the kernel tests
    /// anyway.
    mask: AtomicU32,
}

/// The bit of the mask that says a kernel call is under way ([`LazyLock::begin_kernel`]);
/// never a resource's here (the kernel's answer is stored without it: the bit names
/// resource 15 by the kind of lock that masks ISRs, which the port therefore always
/// leaves to the kernel).
pub(crate) const IN_KERNEL: u32 = 1 << 31;

impl LazyLock {
    /// No lock, and no resource the running task may lock outside the kernel (until the
    /// first kernel call's answer).
    pub(crate) const fn new() -> Self {
        Self {
            word: AtomicU32::new(0),
            mask: AtomicU32::new(0),
        }
    }

    /// Whether the running task may lock `res` outside the kernel now, with the lock of
    /// the kind `masked` says (masking the ISRs up to the ceiling, or nothing): the
    /// kernel's last answer names it by that kind's bit ([`lock_free_bit`], which a
    /// constant `res` folds to a constant) and no other lock is kept so. During a kernel
    /// call of the preemptive port the answer is [`IN_KERNEL`] alone, which names no
    /// resource (and so a resource whose bit would be that one, the sixteenth of the ISRs'
    /// kind, is always locked by the kernel).
    #[inline(always)]
    pub(crate) fn may_take(&self, res: ResourceId, masked: bool) -> bool {
        let mask = self.mask.load(Ordering::Relaxed) & !IN_KERNEL;
        mask & lock_free_bit(res, masked) != 0 && self.word.load(Ordering::Relaxed) == 0
    }

    /// Whether the running task may lock `res` outside the kernel now with a lock of
    /// either kind (the host port, which masks nothing).
    #[cfg(feature = "host")]
    #[inline(always)]
    pub(crate) fn may_take_either(&self, res: ResourceId) -> bool {
        let either = lock_free_bit(res, false) | lock_free_bit(res, true);
        let mask = self.mask.load(Ordering::Relaxed) & !IN_KERNEL;
        mask & either != 0 && self.word.load(Ordering::Relaxed) == 0
    }

    /// The lock of `res` of the kind `masked` says, one store (where
    /// [`LazyLock::may_take`] allowed it).
    #[inline(always)]
    pub(crate) fn take(&self, res: ResourceId, masked: bool) {
        self.word
            .store(word::unhanded(res, masked), Ordering::Relaxed);
    }

    /// The release of a lock of `res` of the kind `masked` says that no kernel call has
    /// seen: one exchange of the word from that lock (which is [`word::unhanded`]: the
    /// owner's bits come with the hand-over) back to 0. It fails, with nothing done, where
    /// the word holds anything else: no lock, another, the other kind, or this one handed
    /// over by a kernel call (an ISR's) meanwhile; the caller then releases by the kernel.
    /// `false`: nothing done.
    #[inline(always)]
    pub(crate) fn clear(&self, res: ResourceId, masked: bool) -> bool {
        self.word
            .compare_exchange(
                word::unhanded(res, masked),
                0,
                Ordering::Relaxed,
                Ordering::Relaxed,
            )
            .is_ok()
    }

    /// The release of a lock of `res` that no kernel call has seen, where nothing can come
    /// between the test and the store (the host port: no interrupt comes inside a job,
    /// and its locks are all of the kind that masks nothing): the word back to 0, without
    /// the exchange a CPU needs (a locked instruction on the host). `false`: nothing done.
    #[cfg(feature = "host")]
    #[inline(always)]
    pub(crate) fn clear_alone(&self, res: ResourceId) -> bool {
        if self.word.load(Ordering::Relaxed) != word::unhanded(res, false) {
            return false;
        }
        self.word.store(0, Ordering::Relaxed);
        true
    }

    /// The word where it holds a lock no kernel call has seen, which the kernel call
    /// beginning now must hand over ([`LazyLock::hand_over`]) before anything else.
    #[inline(always)]
    pub(crate) fn to_hand_over(&self) -> Option<u32> {
        let lazy = self.word.load(Ordering::Relaxed);
        word::is_unhanded(lazy).then_some(lazy)
    }

    /// A lock kept outside the kernel meets the first kernel call since: the kernel's
    /// `GetResource` takes it now, for the running task (slot `idle` where none runs), in
    /// the task's call level (the call's own entry, an ISR's among them, comes after). So
    /// the call, and every decision it makes, sees the lock. The service, not its fast
    /// path: this is rare, and an image holds the service once (the ports call this from
    /// a function of their own kept out of line). `false`: the kernel refused it (the
    /// ports' contract broken), and the word is as it was.
    #[inline(always)]
    pub(crate) fn hand_over<K: OsKernel>(&self, kernel: &mut K, lazy: u32, idle: u8) -> bool {
        let owner = kernel.running().map_or(idle, |t| t.0);
        if kernel.get_resource(word::resource(lazy)).is_err() {
            return false;
        }
        self.word
            .store(word::handed(lazy, owner), Ordering::Relaxed);
        true
    }

    /// The lock is no longer kept: the kernel refused it at its hand-over (the host
    /// port), or the OS stopped on a fault with no kernel call to hand it to (the
    /// preemptive port).
    pub(crate) fn drop_lock(&self) {
        self.word.store(0, Ordering::Relaxed);
    }

    /// The kernel released `res`: if it was a lock kept outside the kernel and handed
    /// over, the word is free again.
    #[inline(always)]
    pub(crate) fn released(&self, res: ResourceId) {
        if word::handed_of(self.word.load(Ordering::Relaxed), res) {
            self.word.store(0, Ordering::Relaxed);
        }
    }

    /// The job of task slot `owner` ended, its locks released with it: its lock, if one
    /// was handed over, is no longer kept.
    pub(crate) fn job_ended(&self, owner: u8) {
        if word::owned_by(self.word.load(Ordering::Relaxed), owner) {
            self.word.store(0, Ordering::Relaxed);
        }
    }

    /// The kernel's answer at the end of a kernel call ([`OsKernel::lock_free_resources`],
    /// or 0 where the caller holds a resource); in the preemptive port, the kernel call's
    /// end too ([`IN_KERNEL`] cleared with the same store).
    #[inline(always)]
    pub(crate) fn set_mask(&self, lock_free: u32) {
        self.mask.store(lock_free & !IN_KERNEL, Ordering::Relaxed);
    }

    /// A kernel call begins (the preemptive port, under its kernel lock): the mask becomes
    /// [`IN_KERNEL`] alone, and the one before is returned, for a call that leaves the
    /// kernel's answer as it was ([`LazyLock::set_mask`] with it at the end). `None`,
    /// with nothing changed, where a kernel call is under way already.
    #[inline(always)]
    pub(crate) fn begin_kernel(&self) -> Option<u32> {
        let before = self.mask.load(Ordering::Relaxed);
        if before & IN_KERNEL != 0 {
            return None;
        }
        self.mask.store(IN_KERNEL, Ordering::Relaxed);
        Some(before)
    }

    /// Whether a kernel call is under way ([`LazyLock::begin_kernel`]).
    #[inline(always)]
    pub(crate) fn in_kernel(&self) -> bool {
        self.mask.load(Ordering::Relaxed) & IN_KERNEL != 0
    }

    /// The kernel's last answer.
    #[cfg(test)]
    pub(crate) fn mask(&self) -> u32 {
        self.mask.load(Ordering::Relaxed)
    }

    /// The word.
    #[cfg(test)]
    pub(crate) fn word(&self) -> u32 {
        self.word.load(Ordering::Relaxed)
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
