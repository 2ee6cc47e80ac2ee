//! What the OS needs from a board's interrupt hardware, and a virtual interrupt controller
//! for boards that have none (the host board, the model checker, the conformance tests).
//!
//! The kernel keeps the logical state: which ISRs are active and at which priority, the
//! ceilings of the resources held, and the nesting of `DisableAllInterrupts`,
//! `SuspendAllInterrupts` and `SuspendOSInterrupts`. From it, [`Os::interrupt_mask`]
//! (super::Os::interrupt_mask) says which interrupts the hardware must hold pending now.
//! The board carries that out through [`InterruptControl`]: after every kernel call, it
//! applies the kernel's mask. On a Cortex-M, [`InterruptMask::All`] is PRIMASK and
//! [`InterruptMask::UpTo`] is BASEPRI at that ISR priority; the host board keeps the mask
//! in a [`VirtualInterrupts`], which then decides which pending request is taken next as
//! the NVIC would.

use super::config::IsrConfig;
use super::IsrId;

/// Which interrupts the hardware must hold pending.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InterruptMask {
    /// None: every ISR may be taken.
    None,
    /// ISRs whose priority is at or below this ISR priority are held pending; higher ones
    /// may be taken.
    UpTo(u8),
    /// Every interrupt is held pending.
    All,
}

impl InterruptMask {
    /// Whether an ISR of priority `isr_priority` may be taken under this mask.
    #[inline]
    pub const fn admits(self, isr_priority: u8) -> bool {
        match self {
            Self::None => true,
            Self::UpTo(level) => isr_priority > level,
            Self::All => false,
        }
    }
}

/// The board's interrupt hardware, as the OS drives it: one mask, applied after every
/// kernel call that may change it. The host board and the Cortex-M port implement this.
pub trait InterruptControl {
    /// Holds pending exactly the interrupts `mask` names (PRIMASK/BASEPRI on a Cortex-M).
    fn apply_mask(&mut self, mask: InterruptMask);
}

/// An interrupt controller in software: one pending flag per ISR, and the mask the kernel
/// asked for. [`VirtualInterrupts::take_next`] hands out the highest-priority pending
/// request the mask admits, as the NVIC does (equal priorities: the lower ISR id first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct VirtualInterrupts {
    pending: u64,
    mask: InterruptMask,
}

impl Default for VirtualInterrupts {
    fn default() -> Self {
        Self::new()
    }
}

impl VirtualInterrupts {
    /// No request pending; everything masked until the kernel's first mask is applied.
    pub const fn new() -> Self {
        Self {
            pending: 0,
            mask: InterruptMask::All,
        }
    }

    /// The hardware raises interrupt `isr`. Returns `false` when it was already pending
    /// (a request is one flag: the second is lost, as on real hardware). Ids of 64 and
    /// above are refused (`false`).
    pub fn raise(&mut self, isr: IsrId) -> bool {
        let Some(bit) = 1u64.checked_shl(u32::from(isr.0)) else {
            return false;
        };
        if isr.0 >= 64 || self.pending & bit != 0 {
            return false;
        }
        self.pending |= bit;
        true
    }

    /// Whether `isr` is pending.
    pub fn is_pending(&self, isr: IsrId) -> bool {
        isr.0 < 64 && self.pending & (1u64 << isr.0) != 0
    }

    /// The pending requests, one bit per ISR id.
    pub const fn pending(&self) -> u64 {
        self.pending
    }

    /// The mask in force.
    pub const fn mask(&self) -> InterruptMask {
        self.mask
    }

    /// Takes the highest-priority pending request the mask admits (clearing its flag), or
    /// `None`. `isrs` is the configuration's ISR table.
    pub fn take_next(&mut self, isrs: &[IsrConfig]) -> Option<IsrId> {
        let mut best: Option<(u8, u8)> = None;
        let mut pending = self.pending;
        while pending != 0 {
            let id = pending.trailing_zeros() as u8;
            pending &= pending - 1;
            let Some(isr) = isrs.get(usize::from(id)) else {
                continue;
            };
            if !self.mask.admits(isr.priority) {
                continue;
            }
            if best.is_none_or(|(_, p)| isr.priority > p) {
                best = Some((id, isr.priority));
            }
        }
        let (id, _) = best?;
        self.pending &= !(1u64 << id);
        Some(IsrId(id))
    }
}

impl InterruptControl for VirtualInterrupts {
    fn apply_mask(&mut self, mask: InterruptMask) {
        self.mask = mask;
    }
}
