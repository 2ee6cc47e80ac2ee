//! Simulated digital pins (the Dio channels of the host board).
//!
//! [`SimPin`] is an output pin (embedded-hal 1.0 `OutputPin` and `StatefulOutputPin`, error
//! type [`Infallible`]) that records every level *change* as `(time_us, high)`, timed by
//! the shared [`VirtualClock`]. Writing the level the pin already has records nothing, as
//! a logic analyser would show nothing. [`SimPin::level_at`] answers what the pin showed at
//! any past time, which is how tests check the LED timing of the warning levels.
//!
//! [`SimInput`] is an input pin (`InputPin`) whose level the simulation sets.
//!
//! Both are cheaply clonable handles: the firmware owns one clone through its Dio driver,
//! the test or scenario keeps another to observe or drive the pin.
//!
//! Simplified: pins are ideal (no rise time, no glitches, no electrical conflicts).

use core::cell::{Cell, RefCell};
use core::convert::Infallible;
use std::rc::Rc;
use std::vec::Vec;

use embedded_hal::digital::{ErrorType, InputPin, OutputPin, StatefulOutputPin};

use super::clock::VirtualClock;

#[derive(Debug)]
struct OutputState {
    clock: VirtualClock,
    initial_high: bool,
    high: bool,
    history: Vec<(u64, bool)>,
}

/// A simulated output pin that records its level changes in virtual time.
#[derive(Debug, Clone)]
pub struct SimPin {
    name: Rc<str>,
    state: Rc<RefCell<OutputState>>,
}

impl SimPin {
    /// A pin named `name` (e.g. `"RedLED"`), low at start, timed by `clock`.
    pub fn new(name: &str, clock: &VirtualClock) -> Self {
        Self::with_initial_level(name, clock, false)
    }

    /// A pin starting at the given level (`true` = high). The start level is not a change
    /// and is not in the history.
    pub fn with_initial_level(name: &str, clock: &VirtualClock, high: bool) -> Self {
        Self {
            name: Rc::from(name),
            state: Rc::new(RefCell::new(OutputState {
                clock: clock.clone(),
                initial_high: high,
                high,
                history: Vec::new(),
            })),
        }
    }

    /// The pin's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Every level change so far as `(time_us, high)`, oldest first.
    pub fn history(&self) -> Vec<(u64, bool)> {
        self.state.borrow().history.clone()
    }

    /// The level changes from the `first`-th on (0-based), oldest first: what happened
    /// since an observer last looked, without copying the whole history.
    pub fn changes_since(&self, first: usize) -> Vec<(u64, bool)> {
        let state = self.state.borrow();
        state.history.get(first..).unwrap_or(&[]).to_vec()
    }

    /// The number of level changes so far.
    pub fn change_count(&self) -> usize {
        self.state.borrow().history.len()
    }

    /// Lets go of the first `count` level changes (at most all), for a run that would
    /// otherwise keep them all (a live simulation): the level after the last one forgotten
    /// becomes the start level, so [`Self::level_at`] gives it for any time before the
    /// changes kept. The changes kept are numbered from 0 again.
    pub fn forget_changes(&self, count: usize) {
        let mut state = self.state.borrow_mut();
        let count = count.min(state.history.len());
        if let Some(&(_, high)) = count.checked_sub(1).and_then(|i| state.history.get(i)) {
            state.initial_high = high;
        }
        state.history.drain(..count);
    }

    /// Whether the pin drives high now.
    pub fn is_high_now(&self) -> bool {
        self.state.borrow().high
    }

    /// The level the pin showed at `time_us`: the last change at or before that time, or
    /// the start level. Several changes within one microsecond: the last one counts.
    pub fn level_at(&self, time_us: u64) -> bool {
        let state = self.state.borrow();
        // History times never decrease, so the changes up to `time_us` are a prefix.
        let upto = state.history.partition_point(|&(t, _)| t <= time_us);
        match upto.checked_sub(1).and_then(|i| state.history.get(i)) {
            Some(&(_, high)) => high,
            None => state.initial_high,
        }
    }

    fn drive(&self, high: bool) {
        let mut state = self.state.borrow_mut();
        if state.high != high {
            state.high = high;
            let now = state.clock.now_us();
            state.history.push((now, high));
        }
    }
}

impl ErrorType for SimPin {
    type Error = Infallible;
}

impl OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.drive(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.drive(true);
        Ok(())
    }
}

impl StatefulOutputPin for SimPin {
    fn is_set_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.is_high_now())
    }

    fn is_set_low(&mut self) -> Result<bool, Infallible> {
        Ok(!self.is_high_now())
    }
}

/// A simulated input pin whose level the simulation sets.
#[derive(Debug, Clone)]
pub struct SimInput {
    name: Rc<str>,
    high: Rc<Cell<bool>>,
}

impl SimInput {
    /// An input named `name` at the given level (`true` = high).
    pub fn new(name: &str, high: bool) -> Self {
        Self {
            name: Rc::from(name),
            high: Rc::new(Cell::new(high)),
        }
    }

    /// The pin's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Sets the level the firmware reads (`true` = high).
    pub fn set_level(&self, high: bool) {
        self.high.set(high);
    }

    /// The level the firmware reads now.
    pub fn level(&self) -> bool {
        self.high.get()
    }
}

impl ErrorType for SimInput {
    type Error = Infallible;
}

impl InputPin for SimInput {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.high.get())
    }

    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!self.high.get())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::digital::PinState;

    /// Drives the pin as the firmware would: through the embedded-hal traits only.
    fn firmware_sets<P: OutputPin<Error = Infallible>>(pin: &mut P, high: bool) {
        let Ok(()) = pin.set_state(PinState::from(high));
    }

    #[test]
    fn records_changes_with_their_virtual_time() {
        let clock = VirtualClock::new();
        let observer = SimPin::new("RedLED", &clock);
        let mut pin = observer.clone();
        assert_eq!(observer.name(), "RedLED");
        clock.advance_us(1_000);
        firmware_sets(&mut pin, true);
        clock.advance_us(500);
        firmware_sets(&mut pin, true); // no change: nothing recorded
        clock.advance_us(500);
        firmware_sets(&mut pin, false);
        assert_eq!(observer.history(), [(1_000, true), (2_000, false)]);
        assert_eq!(observer.change_count(), 2);
        assert_eq!(observer.changes_since(1), [(2_000, false)]);
        assert_eq!(observer.changes_since(2), []);
        assert_eq!(observer.changes_since(9), [], "beyond the end: nothing new");
        assert!(!observer.is_high_now());
    }

    #[test]
    fn level_at_answers_for_any_past_time() {
        let clock = VirtualClock::new();
        let mut pin = SimPin::new("YellowLED", &clock);
        clock.advance_us(100);
        firmware_sets(&mut pin, true);
        clock.advance_us(100);
        firmware_sets(&mut pin, false);
        // Two changes in the same microsecond: the last one is what the pin showed.
        firmware_sets(&mut pin, true);
        assert!(!pin.level_at(0), "start level before any change");
        assert!(!pin.level_at(99));
        assert!(pin.level_at(100), "a change is visible at its own time");
        assert!(pin.level_at(199));
        assert!(pin.level_at(200));
        assert!(pin.level_at(u64::MAX));
    }

    #[test]
    fn forgotten_changes_leave_the_level_they_set_as_the_start() {
        let clock = VirtualClock::new();
        let mut pin = SimPin::new("Trigger", &clock);
        for t in 1..=3 {
            clock.advance_us(10);
            firmware_sets(&mut pin, t % 2 == 1);
        }
        // Changes: 10 high, 20 low, 30 high. Forget the first two.
        pin.forget_changes(2);
        assert_eq!(pin.history(), [(30, true)]);
        assert!(
            !pin.level_at(0),
            "the level the forgotten changes left: low"
        );
        assert!(pin.level_at(30));
        pin.forget_changes(99);
        assert_eq!(pin.change_count(), 0);
        assert!(pin.level_at(0) && pin.is_high_now());
    }

    #[test]
    fn stateful_pin_reads_back_and_toggles() {
        let clock = VirtualClock::new();
        let mut pin = SimPin::with_initial_level("Trigger", &clock, true);
        assert_eq!(pin.is_set_high(), Ok(true));
        assert!(pin.level_at(0));
        clock.advance_us(10);
        assert_eq!(pin.toggle(), Ok(()));
        assert_eq!(pin.is_set_low(), Ok(true));
        assert_eq!(pin.history(), [(10, false)]);
    }

    #[test]
    fn input_reads_what_the_simulation_sets() {
        let scenario = SimInput::new("Echo", false);
        let mut firmware = scenario.clone();
        assert_eq!(firmware.is_high(), Ok(false));
        scenario.set_level(true);
        assert_eq!(firmware.is_high(), Ok(true));
        assert_eq!(firmware.is_low(), Ok(false));
        assert!(scenario.level());
        assert_eq!(firmware.name(), "Echo");
    }
}
