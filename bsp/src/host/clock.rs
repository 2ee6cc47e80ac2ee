//! Virtual time of the host board.
//!
//! [`VirtualClock`] is a shared handle (`Rc<Cell<u64>>`) on one microsecond counter:
//! every clone sees and moves the same time. Time starts at 0 (or a chosen value), moves
//! only forward, and moves only when the simulation says so; nothing here reads the wall
//! clock. The counter saturates at `u64::MAX` µs (about 584 000 years) instead of wrapping.
//!
//! [`SimDelay`] implements embedded-hal's `DelayNs` by advancing the clock, so a busy-wait
//! in a driver costs virtual time, not real time. Sub-microsecond delays are accumulated
//! and the clock moves once a whole microsecond has built up.
//!
//! Units: microseconds (`_us`), milliseconds (`_ms`, floor of the microseconds).

use core::cell::Cell;
use core::fmt;
use std::rc::Rc;

/// Shared virtual time in microseconds. Clones are handles on the same clock.
#[derive(Debug, Clone, Default)]
pub struct VirtualClock {
    now_us: Rc<Cell<u64>>,
}

/// [`VirtualClock::advance_to_us`] was asked to move time backwards; the clock is unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimeWentBackwards {
    /// The clock's time when asked, µs.
    pub now_us: u64,
    /// The earlier time requested, µs.
    pub requested_us: u64,
}

impl fmt::Display for TimeWentBackwards {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "virtual time cannot go back from {} us to {} us",
            self.now_us, self.requested_us
        )
    }
}

impl std::error::Error for TimeWentBackwards {}

impl VirtualClock {
    /// A clock at time 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// A clock starting at `start_us`.
    pub fn starting_at_us(start_us: u64) -> Self {
        Self {
            now_us: Rc::new(Cell::new(start_us)),
        }
    }

    /// The current virtual time, µs.
    pub fn now_us(&self) -> u64 {
        self.now_us.get()
    }

    /// The current virtual time in whole milliseconds (rounded down).
    pub fn now_ms(&self) -> u64 {
        self.now_us.get() / 1_000
    }

    /// Moves time forward by `delta_us` (saturating) and returns the new time, µs.
    pub fn advance_us(&self, delta_us: u64) -> u64 {
        let now = self.now_us.get().saturating_add(delta_us);
        self.now_us.set(now);
        now
    }

    /// Moves time forward to `time_us`. Asking for the current time is a no-op.
    ///
    /// # Errors
    /// [`TimeWentBackwards`] if `time_us` is earlier than now; the clock is unchanged.
    pub fn advance_to_us(&self, time_us: u64) -> Result<(), TimeWentBackwards> {
        let now_us = self.now_us.get();
        if time_us < now_us {
            return Err(TimeWentBackwards {
                now_us,
                requested_us: time_us,
            });
        }
        self.now_us.set(time_us);
        Ok(())
    }

    /// Whether `other` is a handle on the same clock.
    pub fn is_same_clock(&self, other: &Self) -> bool {
        Rc::ptr_eq(&self.now_us, &other.now_us)
    }
}

/// An embedded-hal delay that advances a [`VirtualClock`] instead of waiting.
#[derive(Debug, Clone)]
pub struct SimDelay {
    clock: VirtualClock,
    /// Nanoseconds requested but not yet a whole microsecond.
    carry_ns: u32,
}

impl SimDelay {
    /// A delay on `clock`.
    pub fn new(clock: &VirtualClock) -> Self {
        Self {
            clock: clock.clone(),
            carry_ns: 0,
        }
    }
}

impl embedded_hal::delay::DelayNs for SimDelay {
    fn delay_ns(&mut self, ns: u32) {
        let total_ns = u64::from(self.carry_ns) + u64::from(ns);
        self.clock.advance_us(total_ns / 1_000);
        // Below 1000, so it fits.
        self.carry_ns = (total_ns % 1_000) as u32;
    }

    fn delay_us(&mut self, us: u32) {
        self.clock.advance_us(u64::from(us));
    }

    fn delay_ms(&mut self, ms: u32) {
        self.clock.advance_us(u64::from(ms) * 1_000);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::delay::DelayNs;

    #[test]
    fn clones_share_one_time() {
        let clock = VirtualClock::new();
        let other = clock.clone();
        assert_eq!(clock.now_us(), 0);
        assert_eq!(other.advance_us(1_500), 1_500);
        assert_eq!(clock.now_us(), 1_500);
        assert_eq!(clock.now_ms(), 1);
        assert!(clock.is_same_clock(&other));
        assert!(!clock.is_same_clock(&VirtualClock::new()));
    }

    #[test]
    fn time_never_goes_backwards() {
        let clock = VirtualClock::starting_at_us(10_000);
        assert_eq!(clock.advance_to_us(25_000), Ok(()));
        assert_eq!(clock.advance_to_us(25_000), Ok(()), "same time is fine");
        assert_eq!(
            clock.advance_to_us(24_999),
            Err(TimeWentBackwards {
                now_us: 25_000,
                requested_us: 24_999
            })
        );
        assert_eq!(clock.now_us(), 25_000, "a refused request changes nothing");
        assert_eq!(clock.now_ms(), 25);
    }

    #[test]
    fn advancing_saturates_instead_of_wrapping() {
        let clock = VirtualClock::starting_at_us(u64::MAX - 1);
        assert_eq!(clock.advance_us(10), u64::MAX);
        assert_eq!(clock.now_us(), u64::MAX);
    }

    #[test]
    fn delays_cost_virtual_time_and_add_up_exactly() {
        let clock = VirtualClock::new();
        let mut delay = SimDelay::new(&clock);
        delay.delay_us(10);
        assert_eq!(clock.now_us(), 10);
        delay.delay_ms(2);
        assert_eq!(clock.now_us(), 2_010);
        // Four 400 ns delays are 1.6 us: the clock has moved one whole microsecond.
        for _ in 0..4 {
            delay.delay_ns(400);
        }
        assert_eq!(clock.now_us(), 2_011);
        delay.delay_ns(400);
        assert_eq!(clock.now_us(), 2_012, "2.0 us of 400 ns delays");
    }
}
