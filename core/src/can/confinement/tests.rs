//! The transmit error counter: the standard's numbers, and confinement under any outcomes.
use super::*;

#[test]
fn thirty_two_errors_in_a_row_take_a_node_bus_off() {
    let mut e = TransmitErrors::new();
    for k in 1..=31 {
        let state = e.failed(Failure::Error);
        let want = if k >= 16 {
            ErrorState::Passive
        } else {
            ErrorState::Active
        };
        assert_eq!(state, want, "after {k} errors");
    }
    assert_eq!(e.failed(Failure::Error), ErrorState::BusOff);
    assert_eq!(e.tec(), 256);
    assert_eq!(e.sent(), ErrorState::BusOff, "a bus-off node sends nothing");
    e.recovered();
    assert_eq!((e.state(), e.tec()), (ErrorState::Active, 0));
}

#[test]
fn a_lone_error_passive_node_stays_error_passive() {
    let mut e = TransmitErrors::new();
    for _ in 0..1000 {
        let _ = e.failed(Failure::NoAcknowledge);
    }
    assert_eq!((e.state(), e.tec()), (ErrorState::Passive, 128));
    assert_eq!(e.sent(), ErrorState::Active, "127 after one frame sent");
}

/// Any sequence of outcomes keeps the counter confined (`spec::counter_stays_confined`).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(42))]
fn any_outcomes_keep_the_counter_confined() {
    bolero::check!()
        .with_type::<([u8; 40], u8)>()
        .cloned()
        .for_each(|(codes, len)| {
            let outcomes = codes[..usize::from(len % 41)].iter().map(|c| match c % 3 {
                0 => None,
                1 => Some(Failure::Error),
                _ => Some(Failure::NoAcknowledge),
            });
            assert!(spec::counter_stays_confined(outcomes));
        });
}
