//! The Watchdog Manager's alive supervision (AUTOSAR WdgM, SWS_WdgM), in its smallest
//! honest form, and the watchdog driver interface (AUTOSAR Wdg) it triggers.
//!
//! Each supervised entity (a periodic task) reports alive indications: one per job. Every
//! WdgM main function (a BSW task's job) hands over the indications counted since the
//! last one. An entity's *supervision reference cycle* is a number of main functions; at
//! the end of each, the indications counted in it must lie within `expected - min_margin
//! ..= expected + max_margin` (SWS_WdgM_00074, `WdgMExpectedAliveIndications`,
//! `WdgMMinMargin`, `WdgMMaxMargin`). A missing or an extra indication is a failed
//! supervision. An entity whose failed reference cycles exceed its tolerance
//! (`WdgMFailedAliveSupervisionRefCycleTol`) is *expired*; so is then the global status,
//! and after `expired_tolerance` more main functions (`WdgMExpiredSupervisionCycleTol`)
//! it is *stopped*: WdgM no longer triggers the watchdog, which resets the ECU when its
//! timeout runs out. Nothing brings an expired or stopped status back but that reset
//! (SWS_WdgM_00077, 00117).
//!
//! The first reference cycle of every entity is not judged: the main function and the
//! supervised tasks start together, so the first cycle may hold fewer indications than a
//! full one (AUTOSAR leaves the start to the configuration's activation of each entity).
//!
//! The counting is the caller's (the ECU counts each task's indications in an atomic it
//! alone increments); this module is the rule, a pure state machine, tested against
//! [`spec`].

/// One supervised entity's alive supervision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AliveSupervision {
    /// The entity's name (the task's), for reports.
    pub name: &'static str,
    /// Main functions per supervision reference cycle (at least 1).
    pub reference_cycle: u16,
    /// Alive indications expected in one reference cycle.
    pub expected: u16,
    /// Fewer indications tolerated.
    pub min_margin: u16,
    /// More indications tolerated.
    pub max_margin: u16,
    /// Failed reference cycles tolerated before the entity expires.
    pub failed_tolerance: u16,
}

impl AliveSupervision {
    /// An entity expecting `expected` indications every `reference_cycle` main functions,
    /// without margins or tolerance.
    pub const fn new(name: &'static str, reference_cycle: u16, expected: u16) -> Self {
        Self {
            name,
            reference_cycle,
            expected,
            min_margin: 0,
            max_margin: 0,
            failed_tolerance: 0,
        }
    }

    /// Whether `count` indications in one reference cycle pass.
    pub const fn passes(&self, count: u32) -> bool {
        let low = self.expected.saturating_sub(self.min_margin) as u32;
        let high = self.expected as u32 + self.max_margin as u32;
        count >= low && count <= high
    }
}

/// A supervision status (local, per entity, or global).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// Every judged reference cycle passed (or the failures are within tolerance).
    Ok,
    /// Failed reference cycles, within the tolerance.
    Failed,
    /// Beyond the tolerance: the watchdog is triggered only within the expired tolerance.
    Expired,
    /// The watchdog is no longer triggered; the reset follows.
    Stopped,
}

/// The first failed reference cycle that expired an entity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Failure {
    /// The entity's index in the configuration.
    pub entity: usize,
    /// Its name.
    pub name: &'static str,
    /// The indications counted in the failed reference cycle.
    pub counted: u32,
    /// The indications expected.
    pub expected: u16,
    /// The main function (1 for the first) whose judgement expired it.
    pub main_function: u32,
}

/// The WdgM of `N` supervised entities.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct WdgM<const N: usize> {
    config: &'static [AliveSupervision; N],
    /// Main functions into each entity's current reference cycle.
    calls: [u16; N],
    /// Indications counted in each entity's current reference cycle.
    counts: [u32; N],
    /// Whether each entity's first reference cycle is over (later ones are judged).
    judging: [bool; N],
    /// Failed reference cycles of each entity so far.
    failed: [u16; N],
    local: [Status; N],
    global: Status,
    /// Main functions since the global status expired.
    expired_for: u16,
    /// Main functions an expired status still triggers the watchdog.
    expired_tolerance: u16,
    main_functions: u32,
    failure: Option<Failure>,
}

/// What one main function decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Verdict {
    /// Trigger (refresh) the watchdog now.
    pub trigger: bool,
    /// The global status after this main function.
    pub status: Status,
    /// The status became `Expired` in this main function (the safe state begins now).
    pub expired_now: bool,
}

impl<const N: usize> WdgM<N> {
    /// `WdgM_Init`: every entity supervised from the first main function on; an expired
    /// global status still triggers the watchdog in `expired_tolerance` main functions
    /// (the one that expired it included), then stops.
    pub const fn new(config: &'static [AliveSupervision; N], expired_tolerance: u16) -> Self {
        Self {
            config,
            calls: [0; N],
            counts: [0; N],
            judging: [false; N],
            failed: [0; N],
            local: [Status::Ok; N],
            global: Status::Ok,
            expired_for: 0,
            expired_tolerance,
            main_functions: 0,
            failure: None,
        }
    }

    /// `WdgM_MainFunction`, with each entity's alive indications since the last one.
    pub fn main_function(&mut self, indications: &[u32; N]) -> Verdict {
        self.main_functions = self.main_functions.saturating_add(1);
        let was = self.global;
        // Every table has one entry per entity: walked together, without an index.
        let entities = self
            .config
            .iter()
            .enumerate()
            .zip(self.calls.iter_mut().zip(self.counts.iter_mut()))
            .zip(indications)
            .zip(
                self.judging
                    .iter_mut()
                    .zip(self.failed.iter_mut().zip(self.local.iter_mut())),
            );
        for ((((e, config), (calls, count)), &new), (judging, (failed, local))) in entities {
            *count = count.saturating_add(new);
            *calls = calls.saturating_add(1);
            if *calls < config.reference_cycle.max(1) {
                continue;
            }
            let counted = core::mem::take(count);
            *calls = 0;
            if !core::mem::replace(judging, true) {
                continue;
            }
            if config.passes(counted) || *local == Status::Expired {
                continue;
            }
            *failed = failed.saturating_add(1);
            if *failed > config.failed_tolerance {
                *local = Status::Expired;
                if self.failure.is_none() {
                    self.failure = Some(Failure {
                        entity: e,
                        name: config.name,
                        counted,
                        expected: config.expected,
                        main_function: self.main_functions,
                    });
                }
            } else {
                *local = Status::Failed;
            }
        }
        self.global = match self.global {
            Status::Stopped => Status::Stopped,
            Status::Expired => {
                self.expired_for = self.expired_for.saturating_add(1);
                if self.expired_for >= self.expired_tolerance {
                    Status::Stopped
                } else {
                    Status::Expired
                }
            }
            Status::Ok | Status::Failed => {
                if self.local.contains(&Status::Expired) {
                    if self.expired_tolerance == 0 {
                        Status::Stopped
                    } else {
                        Status::Expired
                    }
                } else if self.local.contains(&Status::Failed) {
                    Status::Failed
                } else {
                    Status::Ok
                }
            }
        };
        Verdict {
            trigger: self.global != Status::Stopped,
            status: self.global,
            expired_now: matches!(was, Status::Ok | Status::Failed)
                && matches!(self.global, Status::Expired | Status::Stopped),
        }
    }

    /// The global status (`WdgM_GetGlobalStatus`).
    pub const fn global_status(&self) -> Status {
        self.global
    }

    /// Entity `e`'s local status (`WdgM_GetLocalStatus`).
    pub fn local_status(&self, e: usize) -> Option<Status> {
        self.local.get(e).copied()
    }

    /// The failure that expired the first entity, if any.
    pub const fn failure(&self) -> Option<Failure> {
        self.failure
    }

    /// The configuration.
    pub const fn config(&self) -> &'static [AliveSupervision; N] {
        self.config
    }
}

/// The watchdog driver (AUTOSAR Wdg): the hardware, or a model of it, that resets the ECU
/// when it is not triggered in time.
pub trait WdgDriver {
    /// `Wdg_SetTriggerCondition`: the ECU is reset unless this is called again within
    /// `timeout_ms` (0: as soon as possible). The first call starts the watchdog.
    fn set_trigger_condition(&mut self, timeout_ms: u16);
    /// `Wdg_SetMode(WDGIF_OFF_MODE)`: the watchdog stops (EcuM's shutdown, after which no
    /// task triggers it).
    fn off(&mut self);
}

/// The rules, as pure predicates over a run, for the tests and the fuzz target.
pub mod spec {
    use super::{AliveSupervision, Status, WdgM};

    /// Runs `WdgM` over `rounds` (each the indications of one main function) and checks:
    /// an entity expires exactly when one of its judged reference cycles (every one but
    /// the first) fails with no tolerance left; the global status is `Ok` until then and
    /// never comes back; the watchdog is triggered exactly while the status is not
    /// `Stopped`.
    pub fn alive_rule<const N: usize>(
        config: &'static [AliveSupervision; N],
        expired_tolerance: u16,
        rounds: &[[u32; N]],
    ) -> bool {
        let mut wdgm = WdgM::new(config, expired_tolerance);
        // The reference, written out: per entity, the counts of its cycles.
        let mut cycle_count = [0u32; N];
        let mut calls = [0u16; N];
        let mut cycles = [0u32; N];
        let mut failed = [0u16; N];
        let mut expired = [false; N];
        let mut expired_at: Option<usize> = None;
        for (round, indications) in rounds.iter().enumerate() {
            for e in 0..N {
                cycle_count[e] = cycle_count[e].saturating_add(indications[e]);
                calls[e] += 1;
                if calls[e] >= config[e].reference_cycle.max(1) {
                    cycles[e] += 1;
                    if cycles[e] > 1 && !expired[e] && !config[e].passes(cycle_count[e]) {
                        failed[e] += 1;
                        if failed[e] > config[e].failed_tolerance {
                            expired[e] = true;
                        }
                    }
                    cycle_count[e] = 0;
                    calls[e] = 0;
                }
            }
            if expired_at.is_none() && expired.contains(&true) {
                expired_at = Some(round);
            }
            let verdict = wdgm.main_function(indications);
            let stopped_from = expired_at.map(|r| r + usize::from(expired_tolerance));
            let expected_status = match expired_at {
                None if failed.iter().any(|&f| f > 0) => Status::Failed,
                None => Status::Ok,
                Some(_) if stopped_from.is_some_and(|s| round >= s) => Status::Stopped,
                Some(_) => Status::Expired,
            };
            if verdict.status != expected_status
                || verdict.trigger != (expected_status != Status::Stopped)
                || verdict.expired_now != (expired_at == Some(round))
            {
                return false;
            }
            for (e, &x) in expired.iter().enumerate() {
                if (wdgm.local_status(e) == Some(Status::Expired)) != x {
                    return false;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests;
