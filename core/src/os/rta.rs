//! Response-time analysis of a task set under this OS's scheduling: fixed priorities,
//! full preemption, ISRs above every task, and resources under the immediate priority
//! ceiling protocol (OSEK's), so that a job waits for at most one section of a
//! lower-priority job (its blocking).
//!
//! For each item `i` (a task or an ISR: a [`Load`]) the analysis finds the smallest
//! fixed point of
//!
//! ```text
//! w = C_i + B_i + sum over j in hp(i) of ceil((w + J_j) / T_j) * C_j
//! ```
//!
//! and gives the worst-case response time `R_i = J_i + w`, from the release the period
//! counts from to the end of the job (Audsley, Burns, Richardson, Tindell and Wellings,
//! 1993, with release jitter as Tindell and Clark, 1994). `hp(i)` is every other item of
//! priority at or above `i`'s: an item of equal priority is counted as interference,
//! which no OSEK scheduling exceeds (a task of equal priority queued first runs first).
//! `B_i` is the longest section a lower-priority item runs at a priority at or above
//! `i`'s ([`Load::section`], [`Load::raises_to`]).
//!
//! The result is exact for independent items released together at their worst phase (the
//! tests compare it with a simulation of that schedule), and an upper bound with blocking
//! and jitter, for deadlines within the periods: a response past an item's period (where a
//! later job of the same busy period could respond later still) is reported as a miss,
//! whatever the deadline. Every figure is in one unit of time the caller
//! chooses; the arithmetic saturates (a response that reaches `u64::MAX` is a miss), and
//! an item whose response would pass its deadline is reported as missing it at the first
//! iterate past the deadline, so the iteration always ends.

/// One task or ISR of the set, in the caller's unit of time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Load {
    /// Its priority on one scale for tasks and ISRs (higher runs first; ISRs above every
    /// task).
    pub priority: u16,
    /// The shortest time between two of its releases (a period, or an ISR's minimum
    /// inter-arrival time). Not zero.
    pub period: u64,
    /// How late after the time its period counts from a release can be.
    pub jitter: u64,
    /// Its longest execution, alone (without what preempts it).
    pub wcet: u64,
    /// Its deadline, from the time its period counts from (the analysis holds it to the
    /// period where it is longer).
    pub deadline: u64,
    /// The longest it runs at a raised priority: a resource held, the kernel's lock, all of
    /// a non-preemptive job. Zero when it never raises its priority.
    pub section: u64,
    /// The highest priority it raises to in such a section (a resource's ceiling).
    pub raises_to: u16,
}

impl Load {
    /// An item released every `period` without jitter, its deadline its period, its whole
    /// execution one section at `raises_to` (the bound where its sections are not
    /// measured one by one).
    pub const fn periodic(priority: u16, period: u64, wcet: u64, raises_to: u16) -> Self {
        Self {
            priority,
            period,
            jitter: 0,
            wcet,
            deadline: period,
            section: wcet,
            raises_to,
        }
    }
}

/// The analysis of one item.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Response {
    /// Its worst-case response time meets its deadline.
    Meets {
        /// The worst-case response time.
        response: u64,
        /// Its blocking, `B_i`.
        blocking: u64,
    },
    /// Its response time may pass its deadline: the first iterate past it.
    Misses {
        /// A response time the item can reach, past its deadline (saturated at
        /// `u64::MAX`).
        at_least: u64,
        /// Its blocking, `B_i`.
        blocking: u64,
    },
    /// The item's period is zero: no analysis is possible.
    NoPeriod,
}

impl Response {
    /// The response time found (the worst case, or the first past the deadline).
    pub const fn time(self) -> Option<u64> {
        match self {
            Self::Meets { response, .. } => Some(response),
            Self::Misses { at_least, .. } => Some(at_least),
            Self::NoPeriod => None,
        }
    }

    /// Whether the item meets its deadline.
    pub const fn meets(self) -> bool {
        matches!(self, Self::Meets { .. })
    }
}

/// `B_i`: the longest section any item of lower priority than `set[i]` runs at a priority
/// at or above `set[i]`'s. Zero for an index outside the set.
pub fn blocking(set: &[Load], i: usize) -> u64 {
    let Some(me) = set.get(i) else {
        return 0;
    };
    set.iter()
        .filter(|other| other.priority < me.priority && other.raises_to >= me.priority)
        .map(|other| other.section)
        .max()
        .unwrap_or(0)
}

/// The worst-case response time of `set[i]` ([`Response::NoPeriod`] for an index outside
/// the set, or when `set[i]` or an item that preempts it has no period).
pub fn response_time(set: &[Load], i: usize) -> Response {
    let Some(me) = set.get(i) else {
        return Response::NoPeriod;
    };
    let preempting = || {
        set.iter()
            .enumerate()
            .filter(move |&(j, other)| j != i && other.priority >= me.priority)
            .map(|(_, other)| other)
    };
    if me.period == 0 || preempting().any(|other| other.period == 0) {
        return Response::NoPeriod;
    }
    let blocking = blocking(set, i);
    let own = me.wcet.saturating_add(blocking);
    // The longest `w` that still meets the deadline (held to the period); past it the
    // item misses.
    let limit = me.deadline.min(me.period).saturating_sub(me.jitter);
    let mut w = own;
    loop {
        let next = preempting().fold(own, |sum, other| {
            let releases = w.saturating_add(other.jitter).div_ceil(other.period);
            sum.saturating_add(releases.saturating_mul(other.wcet))
        });
        let response = me.jitter.saturating_add(next);
        // (A sum that saturated is past any deadline: the true response overflows.)
        if next > limit || me.jitter > me.deadline.min(me.period) || response == u64::MAX {
            return Response::Misses {
                at_least: response,
                blocking,
            };
        }
        if next == w {
            return Response::Meets { response, blocking };
        }
        // `next > w`: the sum grows with `w`, and it never exceeds `limit` here, so the
        // iteration reaches a fixed point or passes the limit.
        w = next;
    }
}

/// Sets the release jitter of every item another item's job releases, `(released,
/// releaser)` by index, to its releaser's worst-case response time (the job may release
/// it as late as its last line), again until no jitter changes: each depends on the
/// others' interference. The jitters only grow; `false` where a releaser misses its deadline or the jitters have not settled after `4 * set.len()`
/// rounds (the jitters then stand as the last round left them).
pub fn settle_jitter(set: &mut [Load], released_by: &[(usize, usize)]) -> bool {
    for _ in 0..4 * set.len().max(1) {
        let mut changed = false;
        for &(released, releaser) in released_by {
            let Response::Meets { response, .. } = response_time(set, releaser) else {
                return false;
            };
            if let Some(item) = set.get_mut(released) {
                if item.jitter != response {
                    item.jitter = response;
                    changed = true;
                }
            }
        }
        if !changed {
            return true;
        }
    }
    false
}

/// The first item of `set` (by index) that misses its deadline or cannot be analysed, with
/// its analysis; `None` when every item meets its deadline.
pub fn first_miss(set: &[Load]) -> Option<(usize, Response)> {
    (0..set.len())
        .map(|i| (i, response_time(set, i)))
        .find(|(_, r)| !r.meets())
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// An independent periodic item: its deadline its period, no jitter, no section that
    /// blocks another.
    fn periodic(priority: u16, period: u64, wcet: u64) -> Load {
        Load {
            section: 0,
            ..Load::periodic(priority, period, wcet, 0)
        }
    }

    /// The schedule the analysis bounds, simulated one unit of time at a time: every item
    /// released at 0 and then every period, the highest priority with work left running.
    /// The response time of each item's first job (the worst, released together with
    /// everything above it), or `None` when it has not ended by its deadline.
    fn simulated_first_responses(set: &[Load]) -> Vec<Option<u64>> {
        let horizon = set.iter().map(|l| l.deadline).max().unwrap_or(0);
        let mut left: Vec<u64> = set.iter().map(|_| 0).collect();
        let mut first_left: Vec<u64> = set.iter().map(|l| l.wcet).collect();
        let mut done: Vec<Option<u64>> = set.iter().map(|_| None).collect();
        for t in 0..horizon {
            for (k, l) in set.iter().enumerate() {
                if t % l.period == 0 {
                    left[k] += l.wcet;
                }
            }
            let running = (0..set.len())
                .filter(|&k| left[k] > 0)
                .max_by_key(|&k| set[k].priority);
            if let Some(k) = running {
                left[k] -= 1;
                if first_left[k] > 0 {
                    first_left[k] -= 1;
                    if first_left[k] == 0 {
                        done[k] = Some(t + 1);
                    }
                }
            }
        }
        for (k, l) in set.iter().enumerate() {
            if l.wcet == 0 {
                done[k] = Some(0);
            }
            if done[k].is_some_and(|r| r > l.deadline) {
                done[k] = None;
            }
        }
        done
    }

    /// Checks the analysis against the simulated schedule: where the first job ends by its
    /// deadline the analysis gives exactly its response time, and where it does not the
    /// analysis reports a miss.
    fn agrees_with_the_schedule(set: &[Load]) {
        let simulated = simulated_first_responses(set);
        for (i, sim) in simulated.iter().enumerate() {
            match (response_time(set, i), sim) {
                (Response::Meets { response, .. }, Some(r)) => {
                    assert_eq!(response, *r, "item {i} of {set:?}")
                }
                (Response::Misses { at_least, .. }, None) => {
                    assert!(at_least > set[i].deadline, "item {i} of {set:?}")
                }
                (analysed, sim) => {
                    panic!("item {i} of {set:?}: analysed {analysed:?}, simulated {sim:?}")
                }
            }
        }
    }

    /// Items with distinct priorities from fuzzer bytes: (period 1..=16, wcet 0..=8) each.
    fn set_from(bytes: &[(u8, u8)]) -> Vec<Load> {
        bytes
            .iter()
            .take(5)
            .enumerate()
            .map(|(k, &(p, c))| periodic(k as u16, u64::from(p % 16) + 1, u64::from(c % 9)))
            .collect()
    }

    #[test]
    fn the_textbook_set_has_the_textbook_response_times() {
        // (Burns and Wellings, Real-Time Systems, the three-task example: C 3, 3, 5 with
        // T 7, 12, 20 gives R 3, 6, 20.)
        let set = [periodic(3, 7, 3), periodic(2, 12, 3), periodic(1, 20, 5)];
        let times: Vec<_> = (0..3).map(|i| response_time(&set, i).time()).collect();
        assert_eq!(times, [Some(3), Some(6), Some(20)]);
        assert_eq!(first_miss(&set), None);
    }

    #[test]
    fn an_overloaded_set_is_refused_naming_the_lowest_item() {
        let set = [periodic(3, 7, 3), periodic(2, 12, 3), periodic(1, 20, 6)];
        let miss = first_miss(&set);
        assert!(matches!(miss, Some((2, Response::Misses { at_least, .. })) if at_least > 20));
    }

    #[test]
    fn a_lower_items_section_at_a_higher_ceiling_blocks_once() {
        let mut low = periodic(1, 100, 10);
        low.section = 4;
        low.raises_to = 3;
        let set = [periodic(3, 10, 2), periodic(2, 20, 2), low];
        assert_eq!(blocking(&set, 0), 4);
        assert_eq!(blocking(&set, 1), 4);
        // A section never blocks its own item, nor one above its ceiling.
        assert_eq!(blocking(&set, 2), 0);
        low.raises_to = 2;
        let set = [periodic(3, 10, 2), periodic(2, 20, 2), low];
        assert_eq!(blocking(&set, 0), 0);
        assert_eq!(
            response_time(&set, 1),
            Response::Meets {
                response: 2 + 4 + 2,
                blocking: 4
            }
        );
    }

    #[test]
    fn release_jitter_adds_to_the_response_and_to_the_interference() {
        let mut high = periodic(2, 10, 3);
        high.jitter = 4;
        let set = [high, periodic(1, 30, 5)];
        // The high item: its own jitter and wcet.
        assert_eq!(response_time(&set, 0).time(), Some(7));
        // The low one: w = 5 + ceil((w + 4) / 10) * 3 -> 8, then 11 (two releases).
        assert_eq!(response_time(&set, 1).time(), Some(11));
    }

    #[test]
    fn a_released_items_jitter_settles_at_its_releasers_response() {
        // Item 0 (high) is released by item 1's job (low): its jitter is item 1's
        // response, which counts item 0's interference once.
        let mut set = [periodic(2, 40, 3), periodic(1, 40, 10)];
        assert!(settle_jitter(&mut set, &[(0, 1)]));
        assert_eq!(set[0].jitter, 13);
        assert_eq!(response_time(&set, 0).time(), Some(16));
        // A releaser that misses: the set stands as it was.
        let mut missed = [periodic(2, 40, 3), periodic(1, 40, 50)];
        assert!(!settle_jitter(&mut missed, &[(0, 1)]));
        assert_eq!(missed[0].jitter, 0);
    }

    #[test]
    fn a_response_past_the_period_is_a_miss_whatever_the_deadline() {
        let mut low = periodic(1, 10, 6);
        low.deadline = 100;
        let set = [periodic(2, 10, 5), low];
        assert!(!response_time(&set, 1).meets());
    }

    #[test]
    fn jitter_past_the_deadline_is_a_miss_and_indices_outside_the_set_change_nothing() {
        // (Even with nothing to execute: released after its deadline.)
        let mut late = periodic(1, 10, 0);
        late.jitter = 11;
        assert!(!response_time(&[late], 0).meets());
        let mut set = [periodic(2, 40, 3), periodic(1, 40, 10)];
        assert_eq!(blocking(&set, 7), 0);
        // A released item outside the set: nothing to set, the releaser analysed.
        assert!(settle_jitter(&mut set, &[(7, 1)]));
        assert_eq!(set.map(|l| l.jitter), [0, 0]);
    }

    #[test]
    fn an_item_without_a_period_cannot_be_analysed() {
        let set = [periodic(2, 0, 1), periodic(1, 10, 1)];
        assert_eq!(response_time(&set, 1), Response::NoPeriod);
        assert_eq!(response_time(&set, 5), Response::NoPeriod);
        assert_eq!(first_miss(&set).map(|(i, _)| i), Some(0));
    }

    #[test]
    fn huge_figures_saturate_into_a_miss() {
        let set = [periodic(2, 1, u64::MAX), periodic(1, u64::MAX, u64::MAX)];
        assert!(matches!(
            response_time(&set, 1),
            Response::Misses {
                at_least: u64::MAX,
                ..
            }
        ));
    }

    /// Every set of up to three items with periods 1..=6 and execution times 0..=3, at
    /// every assignment of distinct priorities given by their order: the analysis equals
    /// the simulated schedule. (Under Miri: the single items.)
    #[test]
    fn every_small_set_agrees_with_its_simulated_schedule() {
        let items: Vec<(u64, u64)> = (1..=6).flat_map(|t| (0..=3).map(move |c| (t, c))).collect();
        for &a in &items {
            agrees_with_the_schedule(&[periodic(1, a.0, a.1)]);
            // (Miri, which interprets every step of the simulation, checks single items.)
            #[cfg(not(miri))]
            for &b in &items {
                agrees_with_the_schedule(&[periodic(2, a.0, a.1), periodic(1, b.0, b.1)]);
                for &c in &items {
                    agrees_with_the_schedule(&[
                        periodic(3, a.0, a.1),
                        periodic(2, b.0, b.1),
                        periodic(1, c.0, c.1),
                    ]);
                }
            }
        }
    }

    /// Sets of up to five items from the fuzzer: the analysis equals the simulated
    /// schedule (`cargo bolero test` explores more).
    #[test]
    fn generated_sets_agree_with_their_simulated_schedule() {
        bolero::check!()
            .with_type::<Vec<(u8, u8)>>()
            .for_each(|bytes| agrees_with_the_schedule(&set_from(bytes)));
    }

    /// More execution, blocking or jitter never shortens a response time.
    #[test]
    fn the_response_time_grows_with_every_input() {
        bolero::check!()
            .with_type::<(Vec<(u8, u8)>, u8, u8, u8)>()
            .for_each(|(bytes, more, section, jitter)| {
                let set = set_from(bytes);
                for i in 0..set.len() {
                    let before = response_time(&set, i);
                    let mut grown = set.clone();
                    grown[i].wcet += u64::from(*more);
                    grown[i].jitter += u64::from(*jitter % 4);
                    grown[0].section += u64::from(*section);
                    grown[0].raises_to = u16::MAX;
                    let after = response_time(&grown, i);
                    match (before, after) {
                        (
                            Response::Meets { response: b, .. },
                            Response::Meets { response: a, .. },
                        ) => {
                            assert!(a >= b)
                        }
                        (Response::Misses { .. }, after) => assert!(!after.meets()),
                        _ => {}
                    }
                }
            });
    }
}
