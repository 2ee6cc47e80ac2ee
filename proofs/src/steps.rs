//! Every sequence of steps of the kernel harnesses' domain, up to a stated length, on the
//! small configuration of the Kani proofs ([`cw_core::os::steps::SMALL`]).
//!
//! The bolero harness `os::tests::random_step_sequences_keep_the_invariants` draws random
//! sequences of [`Step`]s; the Kani proofs take one or two of them with symbolic arguments.
//! This exploration takes all of them: from the state right after `StartOS`, every distinct
//! service a [`Step`] stands for (every variant, each argument over all 256 values of its
//! byte) from every state reached, level by level, and checks the transition rules and
//! every kernel invariant ([`spec::call_and_check`]) on each transition. A state reached
//! again is not expanded twice: the kernel is deterministic, and two states that compare
//! equal behave the same (the ready queue compares its logical content). So a run to depth
//! `d` covers every sequence of at most `d` steps, of which there are more than `4358^d`.
//!
//! The whole reachable state space is not finite in practice: the interrupt-lock services
//! nest up to 255 deep each, and every level of nesting is a state of its own.

use crate::Outcome;
use cw_core::os::spec::{self, Service};
use cw_core::os::steps::{SmallOs, Step, SMALL};
use cw_core::os::OSDEFAULTAPPMODE;
use std::collections::{HashMap, HashSet};

/// Every distinct service a [`Step`] stands for: each variant with every value of each of
/// its byte arguments, in a fixed order.
pub fn every_service() -> Vec<Service> {
    let mut seen = HashSet::new();
    let mut services = Vec::new();
    let mut add = |s: Step| {
        let service = s.service();
        if seen.insert(service) {
            services.push(service);
        }
    };
    for s in [
        Step::Terminate,
        Step::Schedule,
        Step::Tick,
        Step::ExitIsr,
        Step::TaskReturn,
    ] {
        add(s);
    }
    for a in 0..=u8::MAX {
        for s in [
            Step::Activate(a),
            Step::Chain(a),
            Step::ClearEvent(a),
            Step::WaitEvent(a),
            Step::GetResource(a),
            Step::ReleaseResource(a),
            Step::FastGet(a),
            Step::FastRelease(a),
            Step::Cancel(a),
            Step::Lock(a),
            Step::EnterIsr(a),
            Step::IsrTick(a),
            Step::FastTick(a),
            Step::FastActivate(a),
            Step::Query(a),
        ] {
            add(s);
        }
        for b in 0..=u8::MAX {
            add(Step::SetEvent(a, b));
            add(Step::IsrActivate(a, b));
            for c in 0..=u8::MAX {
                add(Step::SetRel(a, b, c));
                add(Step::SetAbs(a, b, c));
            }
        }
    }
    services
}

/// What a run found.
#[derive(Debug)]
pub struct Exploration {
    /// Distinct services taken from each state.
    pub services: usize,
    /// Distinct states first reached after 0, 1, 2, … steps.
    pub new_at_depth: Vec<usize>,
    /// Transitions checked.
    pub transitions: u64,
    /// The first broken rule, with the steps from `StartOS` that break it.
    pub failure: Option<String>,
}

/// One state reached: how (its parent's index and the service taken), for the path to a
/// failure.
type Origin = Option<(usize, Service)>;

/// Explores every sequence of at most `depth` steps from the state after `StartOS`, on
/// `threads` threads; stops at the first transition that breaks a rule or an invariant.
pub fn explore(depth: usize, threads: usize) -> Exploration {
    let services = every_service();
    let mut run = Exploration {
        services: services.len(),
        new_at_depth: Vec::new(),
        transitions: 0,
        failure: None,
    };
    let Ok(mut start) = SmallOs::new(&SMALL) else {
        run.failure = Some("the small configuration was refused".into());
        return run;
    };
    if let Err(e) = start.start_os(OSDEFAULTAPPMODE) {
        run.failure = Some(format!("StartOS failed: {e:?}"));
        return run;
    }
    let mut index: HashMap<SmallOs, usize> = HashMap::from([(start, 0)]);
    let mut origins: Vec<Origin> = vec![None];
    let mut level: Vec<(SmallOs, usize)> = vec![(start, 0)];
    run.new_at_depth.push(1);
    for _ in 0..depth {
        let chunk = level.len().div_ceil(threads.max(1)).max(1);
        let found: Vec<Expanded> = std::thread::scope(|scope| {
            let workers: Vec<_> = level
                .chunks(chunk)
                .map(|part| scope.spawn(|| expand(part, &services, &index)))
                .collect();
            workers
                .into_iter()
                .map(|w| w.join().unwrap_or_else(|_| Expanded::panicked()))
                .collect()
        });
        run.transitions += (level.len() * services.len()) as u64;
        let mut next_level = Vec::new();
        for part in found {
            if let Some((from, service, rule)) = part.broken {
                run.failure = Some(format!(
                    "{rule}: {:?}",
                    path_to(&origins, from)
                        .chain(std::iter::once(service))
                        .collect::<Vec<_>>()
                ));
                return run;
            }
            for (os, from, service) in part.new {
                if let std::collections::hash_map::Entry::Vacant(slot) = index.entry(os) {
                    slot.insert(origins.len());
                    next_level.push((os, origins.len()));
                    origins.push(Some((from, service)));
                }
            }
        }
        run.new_at_depth.push(next_level.len());
        if next_level.is_empty() {
            break;
        }
        level = next_level;
    }
    run
}

/// What one thread found in its part of a level.
struct Expanded {
    /// States not reached before, with the state they came from and the service taken.
    new: Vec<(SmallOs, usize, Service)>,
    /// The first broken rule: the state's index, the service, the rule.
    broken: Option<(usize, Service, String)>,
}

impl Expanded {
    fn panicked() -> Self {
        Self {
            new: Vec::new(),
            broken: Some((0, Service::ExitIsr, "a worker thread panicked".into())),
        }
    }
}

fn expand(
    part: &[(SmallOs, usize)],
    services: &[Service],
    index: &HashMap<SmallOs, usize>,
) -> Expanded {
    let mut local = HashSet::new();
    let mut out = Expanded {
        new: Vec::new(),
        broken: None,
    };
    for &(os, from) in part {
        for &service in services {
            let mut next = os;
            if let Err(rule) = spec::call_and_check(&mut next, service) {
                out.broken = Some((from, service, rule.to_string()));
                return out;
            }
            if !index.contains_key(&next) && local.insert(next) {
                out.new.push((next, from, service));
            }
        }
    }
    out
}

/// The services from `StartOS` to state `at`.
fn path_to(origins: &[Origin], at: usize) -> impl Iterator<Item = Service> {
    let mut path = Vec::new();
    let mut here = at;
    // Each origin is an earlier index, so the walk ends within `origins.len()` steps.
    for _ in 0..origins.len() {
        match origins.get(here).copied().flatten() {
            Some((parent, service)) => {
                path.push(service);
                here = parent;
            }
            None => break,
        }
    }
    path.into_iter().rev()
}

/// The exploration to `depth` as a model-check outcome.
pub fn check_steps(depth: usize, threads: usize) -> Outcome {
    let run = explore(depth, threads);
    println!(
        "  {} services from each state; new states after 0..{depth} steps: {:?}",
        run.services, run.new_at_depth
    );
    Outcome {
        name: "small configuration (the Kani proofs'): every sequence of the harnesses' steps",
        unique_states: run.new_at_depth.iter().sum(),
        states: usize::try_from(run.transitions).unwrap_or(usize::MAX),
        failures: run.failure.into_iter().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cw_core::os::{ResourceId, ServiceCall, TaskId, RES_SCHEDULER};

    #[test]
    fn the_domain_is_every_service_a_step_stands_for() {
        let services = every_service();
        assert_eq!(services.len(), 4358);
        // Ids beyond the configuration (E_OS_ID) and RES_SCHEDULER are in it.
        for service in [
            Service::Call(ServiceCall::ActivateTask(TaskId(5))),
            Service::Call(ServiceCall::GetResource(RES_SCHEDULER)),
            Service::Call(ServiceCall::ReleaseResource(ResourceId(3))),
            Service::TaskReturn,
            Service::FastGet(ResourceId(0)),
            Service::FastRelease(RES_SCHEDULER),
            Service::FastActivate(TaskId(1)),
        ] {
            assert!(services.contains(&service), "{service:?}");
        }
    }

    #[test]
    fn two_steps_reach_what_they_must_and_break_nothing() {
        let run = explore(2, 2);
        assert_eq!(run.failure, None);
        // After StartOS: an ISR that activates A or B, ISR entries, locks; then more.
        assert_eq!(run.new_at_depth, [1, 4, 79]);
        assert_eq!(run.transitions, 5 * 4358);
    }

    #[test]
    fn a_failure_names_the_steps_from_start_os() {
        let a = Service::Call(ServiceCall::Schedule);
        let b = Service::TaskReturn;
        let origins = [None, Some((0, a)), Some((1, b)), Some((0, b))];
        assert_eq!(path_to(&origins, 2).collect::<Vec<_>>(), [a, b]);
        assert_eq!(path_to(&origins, 3).collect::<Vec<_>>(), [b]);
        assert_eq!(path_to(&origins, 0).count(), 0);
    }
}
