//! A watchdog model for the host board: the ECU's watchdog driver (AUTOSAR Wdg's
//! `Wdg_SetTriggerCondition`) in virtual time. It resets the ECU when the time since the
//! last trigger reaches the timeout given with it; the simulation asks it every step and
//! ends the run at the reset, as a board's power-on reset ends what the ECU was doing.

use std::cell::Cell;
use std::rc::Rc;

use cw_core::wdgm::WdgDriver;

use super::clock::VirtualClock;

/// The watchdog, a cheaply clonable handle: the ECU's driver and the simulation share it.
#[derive(Debug, Clone)]
pub struct SimWatchdog {
    clock: VirtualClock,
    state: Rc<Cell<WatchdogState>>,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct WatchdogState {
    /// When the reset comes unless triggered again, µs (`None`: not started).
    deadline_us: Option<u64>,
    /// The last trigger, µs.
    last_trigger_us: Option<u64>,
    triggers: u64,
}

impl SimWatchdog {
    /// A watchdog timed by `clock`, not started.
    pub fn new(clock: &VirtualClock) -> Self {
        Self {
            clock: clock.clone(),
            state: Rc::new(Cell::new(WatchdogState::default())),
        }
    }

    /// The time of the reset, µs, if it is due at or before now.
    pub fn reset_due(&self) -> Option<u64> {
        self.state
            .get()
            .deadline_us
            .filter(|&t| t <= self.clock.now_us())
    }

    /// When the reset comes unless the watchdog is triggered again, µs (`None`: not
    /// started).
    pub fn deadline_us(&self) -> Option<u64> {
        self.state.get().deadline_us
    }

    /// The last trigger, µs.
    pub fn last_trigger_us(&self) -> Option<u64> {
        self.state.get().last_trigger_us
    }

    /// Triggers so far.
    pub fn triggers(&self) -> u64 {
        self.state.get().triggers
    }
}

impl WdgDriver for SimWatchdog {
    fn set_trigger_condition(&mut self, timeout_ms: u16) {
        let now = self.clock.now_us();
        let mut s = self.state.get();
        s.deadline_us = Some(now + u64::from(timeout_ms) * 1000);
        s.last_trigger_us = Some(now);
        s.triggers += 1;
        self.state.set(s);
    }

    fn off(&mut self) {
        let mut s = self.state.get();
        s.deadline_us = None;
        self.state.set(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_resets_at_the_timeout_after_the_last_trigger_and_not_before() {
        let clock = VirtualClock::new();
        let mut wdg = SimWatchdog::new(&clock);
        let seen = wdg.clone();
        assert_eq!(seen.reset_due(), None, "not started");
        clock.advance_us(1_000_000);
        assert_eq!(seen.reset_due(), None, "not started: no reset");
        wdg.set_trigger_condition(50);
        clock.advance_us(49_999);
        assert_eq!(seen.reset_due(), None);
        wdg.set_trigger_condition(50);
        clock.advance_us(49_999);
        assert_eq!(seen.reset_due(), None, "the trigger moved the deadline");
        clock.advance_us(1);
        assert_eq!(seen.reset_due(), Some(1_099_999));
        assert_eq!(seen.triggers(), 2);
        assert_eq!(seen.last_trigger_us(), Some(1_049_999));
    }

    #[test]
    fn switched_off_it_never_resets() {
        let clock = VirtualClock::new();
        let mut wdg = SimWatchdog::new(&clock);
        wdg.set_trigger_condition(50);
        wdg.off();
        clock.advance_us(10_000_000);
        assert_eq!(wdg.reset_due(), None);
    }
}
