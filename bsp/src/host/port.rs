//! The host port: the OS port of the simulation. Tasks run as nested calls on one stack
//! (a preempting task is called from inside the preempted one, as a single-stack OSEK
//! kernel runs basic tasks), and interrupts are taken between jobs, when the simulation
//! raises them and the kernel's interrupt mask admits them: the simulation takes them
//! only through [`HostPort::take_interrupt`], which applies the kernel's mask first, so
//! the mask need not be applied after every service call.

use std::cell::{Ref, RefCell};
use std::vec::Vec;

use cw_core::os::{InterruptControl, IsrConfig, IsrId, TaskId, VirtualInterrupts};

use super::clock::VirtualClock;
use crate::port::{OsKernel, Port};

/// The host port of a kernel `K`.
pub struct HostPort<K> {
    kernel: RefCell<K>,
    irq: RefCell<VirtualInterrupts>,
    clock: VirtualClock,
    /// The jobs on the stack, innermost last.
    jobs: RefCell<Vec<TaskId>>,
    /// Every job start: (task, virtual time in µs).
    starts: RefCell<Vec<(TaskId, u64)>>,
    /// ISRs whose entry the kernel refused, in order (their lines quieted).
    refused: RefCell<Vec<IsrId>>,
}

impl<K: OsKernel> HostPort<K> {
    /// The port of `kernel`, timed by `clock`.
    pub fn new(kernel: K, clock: &VirtualClock) -> Self {
        Self {
            kernel: RefCell::new(kernel),
            irq: RefCell::new(VirtualInterrupts::new()),
            clock: clock.clone(),
            jobs: RefCell::new(Vec::new()),
            starts: RefCell::new(Vec::new()),
            refused: RefCell::new(Vec::new()),
        }
    }

    /// The kernel, for inspection.
    pub fn os(&self) -> Ref<'_, K> {
        self.kernel.borrow()
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
        irq.apply_mask(self.kernel.borrow().interrupt_mask());
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

    /// Lets go of the job starts so far (a live simulation, which would keep them all).
    pub fn forget_job_starts(&self) {
        *self.starts.borrow_mut() = Vec::new();
    }
}

impl<K: OsKernel> Port for HostPort<K> {
    type Kernel = K;
    const NESTED: bool = true;

    #[inline]
    fn kernel<R>(&self, f: impl FnOnce(&mut K) -> R) -> R {
        f(&mut self.kernel.borrow_mut())
    }

    #[inline]
    fn inspect<R>(&self, f: impl FnOnce(&K) -> R) -> R {
        f(&self.kernel.borrow())
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
        self.starts.borrow_mut().push((task, self.clock.now_us()));
    }

    fn job_finished(&self, _task: TaskId) {
        self.jobs.borrow_mut().pop();
    }

    fn isr_refused(&self, isr: IsrId) {
        self.refused.borrow_mut().push(isr);
    }
}
