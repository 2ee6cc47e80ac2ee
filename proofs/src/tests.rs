//! The model checker's own checks must be able to fail: each rule is shown a real pair of
//! kernel states that breaks it. The whole-model runs are small enough to be tests too.
use super::*;
use crate::configs;

type Fifo = Os<4, 0, 0, 0, 6>;

fn fifo_os() -> Fifo {
    let Ok(mut os) = Fifo::new(&configs::FIFO) else {
        panic!("FIFO configuration refused");
    };
    assert_eq!(os.start(), Ok(()));
    os
}

#[test]
fn fifo_rule_rejects_a_reordered_queue() {
    let model = configs::fifo();
    // H runs; A then B are queued at priority 1.
    let mut before = fifo_os();
    for t in [3, 0, 1] {
        assert_eq!(before.activate_task(TaskId(t)), Ok(()));
    }
    // The same tasks queued in the other order.
    let mut swapped = fifo_os();
    for t in [3, 1, 0] {
        assert_eq!(swapped.activate_task(TaskId(t)), Ok(()));
    }
    assert_eq!(model.check_fifo(&before, &before), None);
    // [A, B] -> [B, A] reads as "A left without being dispatched, A re-queued": refused.
    assert!(model.check_fifo(&before, &swapped).is_some());
    // A new activation at the tail is fine.
    let mut appended = before;
    assert_eq!(appended.activate_task(TaskId(0)), Ok(()));
    assert_eq!(model.check_fifo(&before, &appended), None);
}

#[test]
fn limit_rule_rejects_a_lost_activation() {
    let model = configs::fifo();
    let before = fifo_os();
    // Claiming ActivateTask succeeded while the state did not change: a lost activation.
    assert_eq!(
        model.check_transition(&before, &before, Step::Activate(TaskId(0)), Ok(())),
        Some("an activation was lost")
    );
    assert_eq!(
        model.check_transition(&before, &before, Step::Activate(TaskId(0)), Err(OsError::Limit)),
        Some("E_OS_LIMIT below the limit")
    );
}

#[test]
fn small_models_hold_every_property() {
    for outcome in [check(configs::ceiling(), 1), check(configs::fifo(), 1)] {
        assert!(outcome.failures.is_empty(), "{}: {:?}", outcome.name, outcome.failures);
        assert!(outcome.unique_states > 100, "{} explored only {}", outcome.name, outcome.unique_states);
    }
}
