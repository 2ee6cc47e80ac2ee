//! WdgM's alive supervision against its rule (`spec::alive_rule`), and the cases by name.

extern crate std;

use std::vec::Vec;

use super::*;

static THREE: [AliveSupervision; 3] = [
    // Every main function (a 10 ms task beside a 10 ms main function).
    AliveSupervision::new("Every", 1, 1),
    // Every second (a 20 ms task).
    AliveSupervision::new("Second", 2, 1),
    // Four per four, with a margin of one either way and one failed cycle tolerated.
    AliveSupervision {
        name: "Loose",
        reference_cycle: 4,
        expected: 4,
        min_margin: 1,
        max_margin: 1,
        failed_tolerance: 1,
    },
];

/// The indications of a healthy run: every entity as configured.
fn healthy(round: usize) -> [u32; 3] {
    [1, u32::from(round % 2 == 1), 1]
}

#[test]
fn a_healthy_run_triggers_every_time() {
    let mut wdgm = WdgM::new(&THREE, 0);
    for round in 0..100 {
        let v = wdgm.main_function(&healthy(round));
        assert_eq!(
            v,
            Verdict {
                trigger: true,
                status: Status::Ok,
                expired_now: false
            },
            "round {round}"
        );
    }
    assert_eq!(wdgm.failure(), None);
}

#[test]
fn the_first_reference_cycle_is_not_judged() {
    let mut wdgm = WdgM::new(&THREE, 0);
    // Nothing at all: the first main function ends only `Every`'s first cycle, unjudged.
    assert_eq!(wdgm.main_function(&[0, 0, 0]).status, Status::Ok);
    // The second ends its second cycle, judged: none of the one expected.
    let v = wdgm.main_function(&[0, 0, 0]);
    assert_eq!((v.status, v.trigger), (Status::Stopped, false));
    assert_eq!(
        wdgm.failure().map(|f| (f.name, f.main_function)),
        Some(("Every", 2))
    );
}

#[test]
fn a_missing_indication_expires_the_entity_and_stops_the_trigger() {
    let mut wdgm = WdgM::new(&THREE, 0);
    for round in 0..8 {
        assert!(wdgm.main_function(&healthy(round)).trigger);
    }
    // `Second` misses its indication in the cycle that ends at round 9.
    assert!(wdgm.main_function(&[1, 0, 1]).trigger, "round 8: mid-cycle");
    let v = wdgm.main_function(&[1, 0, 1]);
    assert_eq!(
        v,
        Verdict {
            trigger: false,
            status: Status::Stopped,
            expired_now: true
        }
    );
    assert_eq!(
        wdgm.failure(),
        Some(Failure {
            entity: 1,
            name: "Second",
            counted: 0,
            expected: 1,
            main_function: 10
        })
    );
    assert_eq!(wdgm.local_status(1), Some(Status::Expired));
    assert_eq!(wdgm.local_status(0), Some(Status::Ok));
    // Nothing brings it back.
    for round in 10..20 {
        let v = wdgm.main_function(&healthy(round));
        assert_eq!(
            v,
            Verdict {
                trigger: false,
                status: Status::Stopped,
                expired_now: false
            }
        );
    }
}

#[test]
fn an_extra_indication_fails_as_a_missing_one_does() {
    let mut wdgm = WdgM::new(&THREE, 0);
    for round in 0..4 {
        assert!(wdgm.main_function(&healthy(round)).trigger);
    }
    let v = wdgm.main_function(&[2, 0, 1]);
    assert_eq!(v.status, Status::Stopped);
    assert_eq!(
        wdgm.failure().map(|f| (f.name, f.counted)),
        Some(("Every", 2))
    );
}

#[test]
fn margins_and_the_failed_tolerance_are_kept() {
    let mut wdgm = WdgM::new(&THREE, 0);
    let rounds = |wdgm: &mut WdgM<3>, loose: [u32; 4], from: usize| {
        let mut last = None;
        for (i, l) in loose.into_iter().enumerate() {
            let mut ind = healthy(from + i);
            ind[2] = l;
            last = Some(wdgm.main_function(&ind));
        }
        last
    };
    // The first cycle (not judged), then 3 of 4 (within the margin), 5 of 4 (within).
    for (i, loose) in [[1, 1, 1, 1], [1, 1, 1, 0], [2, 1, 1, 1]]
        .into_iter()
        .enumerate()
    {
        assert_eq!(
            rounds(&mut wdgm, loose, 4 * i).map(|v| v.status),
            Some(Status::Ok)
        );
    }
    // 2 of 4: failed, within the tolerance of one failed cycle.
    assert_eq!(
        rounds(&mut wdgm, [1, 1, 0, 0], 12).map(|v| v.status),
        Some(Status::Failed)
    );
    assert_eq!(wdgm.local_status(2), Some(Status::Failed));
    // A second failed cycle: expired.
    let v = rounds(&mut wdgm, [0, 0, 0, 0], 16);
    assert_eq!(
        v.map(|v| (v.status, v.expired_now)),
        Some((Status::Stopped, true))
    );
}

#[test]
fn the_expired_tolerance_triggers_that_many_main_functions_more() {
    let mut wdgm = WdgM::new(&THREE, 2);
    for round in 0..4 {
        wdgm.main_function(&healthy(round));
    }
    let v = wdgm.main_function(&[0, 0, 1]);
    assert_eq!(
        v,
        Verdict {
            trigger: true,
            status: Status::Expired,
            expired_now: true
        }
    );
    assert_eq!(wdgm.main_function(&[1, 1, 1]).status, Status::Expired);
    assert_eq!(wdgm.main_function(&[1, 0, 1]).status, Status::Stopped);
}

/// Any run of up to 12 main functions keeps the rule (`spec::alive_rule`).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(14))]
fn any_run_keeps_the_alive_rule() {
    bolero::check!()
        .with_type::<([[u8; 3]; 12], u8, u8)>()
        .cloned()
        .for_each(|(rounds, len, tolerance)| {
            let rounds: [[u32; 3]; 12] = rounds.map(|r| r.map(|n| u32::from(n % 4)));
            let len = usize::from(len % 13);
            assert!(spec::alive_rule(
                &THREE,
                u16::from(tolerance % 3),
                &rounds[..len]
            ));
        });
}

#[test]
fn long_runs_keep_the_alive_rule() {
    bolero::check!()
        .with_type::<(Vec<[u8; 3]>, u8)>()
        .for_each(|(rounds, tolerance)| {
            let rounds: Vec<[u32; 3]> =
                rounds.iter().map(|r| r.map(|n| u32::from(n % 3))).collect();
            assert!(spec::alive_rule(&THREE, u16::from(tolerance % 3), &rounds));
        });
}
