//! The host port: the OS port of the simulation. Tasks run as nested calls on one stack
//! (a preempting task is called from inside the preempted one, as a single-stack OSEK
//! kernel runs basic tasks), and interrupts are taken between jobs, when the simulation
//! raises them and the kernel's interrupt mask admits them: the simulation takes them
//! only through [`HostPort::take_interrupt`], which applies the kernel's mask first, so
//! the mask need not be applied after every service call.
//!
//! A task's lock of one of its own resources, holding nothing else, is kept outside the
//! kernel as the preemptive port keeps it (`crate::port::preempt`, "A task's lock outside
//! the kernel"): one store, and the kernel is handed the lock at the next kernel call.
//! No interrupt comes inside a job here, so the store needs no mask around it.

use std::cell::{Ref, RefCell};
use std::vec::Vec;

use cw_core::os::{
    InterruptControl, IsrConfig, IsrId, OsError, ResourceId, TaskId, VirtualInterrupts,
};

use super::clock::VirtualClock;
use crate::port::lazy::LazyLock;
use crate::port::{lock_in_kernel, OsKernel, Port};

/// The host port of a kernel `K`.
pub struct HostPort<K> {
    kernel: RefCell<K>,
    /// A task's lock kept outside the kernel, and which resources the running task may
    /// lock so.
    lazy: LazyLock,
    irq: RefCell<VirtualInterrupts>,
    clock: VirtualClock,
    /// The jobs on the stack, innermost last.
    jobs: RefCell<Vec<TaskId>>,
    /// Every job start: (task, virtual time in µs).
    starts: RefCell<Vec<(TaskId, u64)>>,
    /// Every job start since [`HostPort::record_wall_starts`] (a run paced to the wall
    /// clock): task, virtual time in µs, and the wall clock's time
    /// (`crate::realtime::now_ns`).
    wall_starts: RefCell<Vec<(TaskId, u64, u64)>>,
    /// Whether [`HostPort::record_wall_starts`] was called (tested on every job start:
    /// a flag, not the list's borrow).
    record_wall: core::cell::Cell<bool>,
    /// ISRs whose entry the kernel refused, in order (their lines quieted).
    refused: RefCell<Vec<IsrId>>,
}

impl<K: OsKernel> HostPort<K> {
    /// The port of `kernel`, timed by `clock`.
    pub fn new(kernel: K, clock: &VirtualClock) -> Self {
        Self {
            kernel: RefCell::new(kernel),
            lazy: LazyLock::new(),
            irq: RefCell::new(VirtualInterrupts::new()),
            clock: clock.clone(),
            jobs: RefCell::new(Vec::new()),
            starts: RefCell::new(Vec::new()),
            wall_starts: RefCell::new(Vec::new()),
            record_wall: core::cell::Cell::new(false),
            refused: RefCell::new(Vec::new()),
        }
    }

    /// The kernel, for inspection (with a lock kept outside it handed over).
    pub fn os(&self) -> Ref<'_, K> {
        self.hand_over();
        self.kernel.borrow()
    }

    /// A lock kept outside the kernel is handed to it, where there is one: what is read
    /// of the kernel then includes it.
    #[inline]
    fn hand_over(&self) {
        if LazyLock::to_hand_over(self.lazy.now()).is_some() {
            self.hand_over_now();
        }
    }

    /// [`HostPort::hand_over`]'s kernel call (rare: a lock is kept outside the kernel only
    /// inside a job, and a job reads the kernel by kernel calls).
    #[cold]
    #[inline(never)]
    fn hand_over_now(&self) {
        self.kernel(|_| ());
    }

    /// A lock kept outside the kernel meets the first kernel call since
    /// ([`LazyLock::hand_over`]). A refusal (never seen: the kernel's own contract broken)
    /// reached ErrorHook, which counts it, and the lock is no longer kept: the call's end
    /// puts the kernel's answer in the word over it.
    #[cold]
    #[inline(never)]
    fn hand_over_to(&self, kernel: &mut K, lock: u32) {
        let _ = self.lazy.hand_over(kernel, lock);
    }

    /// A lock's kernel call: the kernel's fast path where it applies, else the service.
    /// Out of line, so that the lock outside the kernel stays small where it is inlined.
    #[inline(never)]
    fn lock_call(&self, res: ResourceId, take: bool) -> Result<(), OsError> {
        self.kernel(|os| lock_in_kernel(os, res, take))
    }

    /// Raises an interrupt request.
    pub fn raise(&self, isr: IsrId) {
        self.irq.borrow_mut().raise(isr);
    }

    /// The highest-priority pending request the kernel's interrupt mask admits, taken off
    /// the controller (`None`: nothing to take now).
    pub fn take_interrupt<const I: usize>(&self, isrs: &[IsrConfig; I]) -> Option<IsrId> {
        let mut irq = self.irq.borrow_mut();
        if irq.pending() == 0 {
            return None;
        }
        irq.apply_mask(self.os().interrupt_mask());
        irq.take_next(isrs)
    }

    /// The ISRs whose entry the kernel refused, in order: the port quieted their lines
    /// (the simulation takes no further request of theirs).
    pub fn refused_isrs(&self) -> Ref<'_, Vec<IsrId>> {
        self.refused.borrow()
    }

    /// Every job start so far: (task, virtual time in µs).
    pub fn job_starts(&self) -> Ref<'_, Vec<(TaskId, u64)>> {
        self.starts.borrow()
    }

    /// From now on every job start is also recorded with the wall clock's time (Linux's
    /// monotonic clock, `crate::realtime::now_ns`), for a run paced to it
    /// ([`HostPort::wall_job_starts`]).
    #[cfg(target_os = "linux")]
    pub fn record_wall_starts(&self) {
        self.record_wall.set(true);
    }

    /// The job starts since [`HostPort::record_wall_starts`]: (task, virtual µs,
    /// monotonic ns); empty if it was not called.
    pub fn wall_job_starts(&self) -> Vec<(TaskId, u64, u64)> {
        self.wall_starts.borrow().clone()
    }

    /// Lets go of the job starts so far (a live simulation, which would keep them all).
    pub fn forget_job_starts(&self) {
        *self.starts.borrow_mut() = Vec::new();
    }
}

impl<K: OsKernel> Port for HostPort<K> {
    type Kernel = K;
    const NESTED: bool = true;

    /// Runs `f` on the kernel, a lock kept outside it handed over first; then asks which
    /// resources the running task may lock outside the kernel.
    #[inline]
    fn kernel<R>(&self, f: impl FnOnce(&mut K) -> R) -> R {
        let mut kernel = self.kernel.borrow_mut();
        if let Some(lock) = LazyLock::to_hand_over(self.lazy.now()) {
            self.hand_over_to(&mut kernel, lock);
        }
        let result = f(&mut kernel);
        self.lazy.set_answer(kernel.lock_free_resources());
        result
    }

    #[inline]
    fn inspect<R>(&self, f: impl FnOnce(&K) -> R) -> R {
        f(&self.os())
    }

    /// The lock outside the kernel where the rules allow it (the running task may lock
    /// `res` so, no other lock is kept so, no kernel call is under way): one store.
    /// Otherwise the kernel's fast path, or the service.
    #[inline]
    fn get_resource(&self, res: ResourceId) -> Result<(), OsError> {
        if self.lazy.may_take_either(res) && self.kernel.try_borrow_mut().is_ok() {
            // (No mask on the host: a lock of either kind is the one that masks nothing.)
            self.lazy.take(res, false);
            return Ok(());
        }
        self.lock_call(res, true)
    }

    /// The release of a lock kept outside the kernel that no kernel call has seen: the
    /// kernel's answer back in the word, where the word still holds the lock (no interrupt
    /// comes inside a job here, so nothing comes between the test and the store; a kernel
    /// call the job made inside the lock handed it over). Otherwise through the kernel.
    /// (The port's lock of a kind is this lock and its release this release: the port's
    /// default [`Port::get_resource_of_kind`] and [`Port::release_held`].)
    #[inline]
    fn release_resource(&self, res: ResourceId) -> Result<(), OsError> {
        if self.lazy.clear_alone(res) {
            return Ok(());
        }
        self.lock_call(res, false)
    }

    fn end_job(
        &self,
        f: impl FnOnce(&mut K) -> Result<(), cw_core::os::OsError>,
    ) -> Result<(), cw_core::os::OsError> {
        self.kernel(f)
    }

    fn now_ms(&self) -> u64 {
        self.clock.now_ms()
    }

    fn current_job(&self) -> Option<TaskId> {
        self.jobs.borrow().last().copied()
    }

    fn job_started(&self, task: TaskId) {
        self.jobs.borrow_mut().push(task);
        let now_us = self.clock.now_us();
        self.starts.borrow_mut().push((task, now_us));
        #[cfg(target_os = "linux")]
        if self.record_wall.get() {
            let wall_ns = crate::realtime::now_ns();
            self.wall_starts.borrow_mut().push((task, now_us, wall_ns));
        }
    }

    fn job_finished(&self, _task: TaskId) {
        self.jobs.borrow_mut().pop();
    }

    fn isr_refused(&self, isr: IsrId) {
        self.refused.borrow_mut().push(isr);
    }
}

#[cfg(test)]
mod tests;
