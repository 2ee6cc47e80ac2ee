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

#[test]
fn mode_model_holds_and_its_rules_can_fail() {
    use crate::modes::{broken_rule, ModeModel};
    use cw_core::canif::PduMode;
    use stateright::Model;

    let outcome = check_modes(1);
    assert!(outcome.failures.is_empty(), "{:?}", outcome.failures);
    assert!(outcome.unique_states > 500, "{}", outcome.unique_states);
    // The rules reject a channel online on a stopped controller, and a shut-down ECU
    // that still communicates.
    let mut s = ModeModel.init_states()[0];
    assert_eq!(broken_rule(&s), None);
    s.canif.set_pdu_mode(PduMode::Online);
    assert!(broken_rule(&s).is_some());
    let mut s = ModeModel.init_states()[0];
    for step in [
        crate::modes::ModeStep::PowerOn,
        crate::modes::ModeStep::Request(cw_core::ecum::BswMRequest::EcuPostRun),
    ] {
        s = ModeModel.next_state(&s, step).expect("a next state");
    }
    let _ = s.cansm.request(cw_core::cansm::ComMode::Full);
    let _ = s
        .cansm
        .controller_mode_indication(cw_core::can::ControllerMode::Started);
    let _ = s.ecum.main_function();
    assert!(broken_rule(&s).is_some());
}
