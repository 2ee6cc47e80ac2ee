//! The small models are quick enough to run as tests; the transition rules' own ability
//! to fail is tested beside them in `cw-core` (`os::tests::transition_rules_can_fail`).
use super::*;
use crate::configs;

#[test]
fn small_models_hold_every_property() {
    for outcome in [check(configs::ceiling(), 1), check(configs::fifo(), 1)] {
        assert!(
            outcome.failures.is_empty(),
            "{}: {:?}",
            outcome.name,
            outcome.failures
        );
        assert!(
            outcome.unique_states > 100,
            "{} explored only {}",
            outcome.name,
            outcome.unique_states
        );
    }
}
