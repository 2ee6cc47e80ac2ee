//! The task set's response-time analysis before generation: the ECU's tasks and ISRs
//! with the execution budgets and time frames of their timing protection
//! (`firmware/ecu.arxml`), released as the alarms and the RTE's events release them.

use cw_core::os::rta::Response;
use cw_gen::model::{Ecu, Timing};
use cw_gen::timing::{self, Analysis, Release};

const ECU: &str = include_str!("../../firmware/ecu.arxml");
const COMPONENTS: &str = include_str!("../../firmware/swc.arxml");

fn ecu() -> Ecu {
    cw_gen::arxml::read(ECU.as_bytes(), "ecu.arxml")
        .expect("the ECU's description reads")
        .ecu
}

fn released_by(ecu: &Ecu) -> Vec<(String, String)> {
    let sw = cw_gen::rte::read(COMPONENTS.as_bytes(), "swc.arxml").expect("components");
    cw_gen::rte::released_by(&sw, ecu).expect("the RTE's releases")
}

fn timing_of<'e>(ecu: &'e mut Ecu, name: &str) -> &'e mut Timing {
    let task = ecu.os.tasks.iter_mut().find(|t| t.name == name);
    let timing = match task {
        Some(t) => t.timing.as_mut(),
        None => ecu
            .os
            .isrs
            .iter_mut()
            .find(|i| i.name == name)
            .and_then(|i| i.timing.as_mut()),
    };
    timing.expect("a task or ISR with a timing protection")
}

#[test]
fn the_ecus_task_set_meets_every_deadline_with_its_budgets() {
    let ecu = ecu();
    let released = released_by(&ecu);
    assert_eq!(released, [("OsComTask".into(), "OsSonarTask".into())]);
    let Ok(Analysis::Schedulable { items, left_out }) = timing::analyse(&ecu, &released) else {
        panic!("the ECU's task set is schedulable");
    };
    // The start-up task runs once, before any alarm; the UART's ISR has no budget.
    assert_eq!(left_out, ["SensorRxIsr"]);
    let names: Vec<&str> = items.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "OsLEDTask",
            "OsBswServiceTask",
            "OsObstacleDetectionTask",
            "OsComTask",
            "OsSonarTask",
            "SysTickIsr",
            "CanIsr"
        ]
    );
    let item = |name: &str| items.iter().find(|i| i.name == name).expect(name);
    let led = item("OsLEDTask");
    assert_eq!(
        (led.release.clone(), led.load.period, led.load.wcet),
        (Release::Alarm, 10_000, 100)
    );
    // OsComTask comes once per sonar job, as late as that job's response.
    let (com, sonar) = (item("OsComTask"), item("OsSonarTask"));
    assert_eq!(com.release, Release::Task("OsSonarTask".into()));
    assert_eq!(com.load.period, 40_000);
    let Response::Meets { response, .. } = sonar.response else {
        panic!("the sonar job meets its deadline");
    };
    assert_eq!(com.load.jitter, response);
    // The ISRs above every task.
    assert!(items
        .iter()
        .filter(|i| i.name.ends_with("Isr"))
        .all(|isr| items
            .iter()
            .filter(|t| t.name.ends_with("Task"))
            .all(|t| isr.load.priority > t.load.priority)));
    assert!(items.iter().all(|i| i.response.meets()));
}

#[test]
fn a_budget_that_cannot_be_met_is_refused_naming_what_preempts() {
    let mut ecu = ecu();
    let released = released_by(&ecu);
    timing_of(&mut ecu, "OsObstacleDetectionTask").budget_us = Some(19_500);
    let e = timing::analyse(&ecu, &released).expect_err("it misses");
    // The LED task, above it, waits for its section on the RTE's resource (bounded by
    // its whole budget): it misses too.
    assert!(e.iter().any(|e| e
        .what
        .starts_with("OsLEDTask can miss its deadline: its response can reach 20750 µs (its budget 100 µs, blocking 19500 µs")));
    let first = e
        .iter()
        .find(|e| e.what.starts_with("OsObstacleDetectionTask"))
        .expect("the obstacle task misses");
    assert!(
        first
            .what
            .starts_with("OsObstacleDetectionTask can miss its deadline: its response can reach"),
        "{first}"
    );
    assert!(
        first.what.ends_with("past its deadline of 20000 µs"),
        "{first}"
    );
    assert_eq!(
        first.paths[0],
        "/CollisionWarning/EcucValues/Os/OsObstacleDetectionTask/OsTaskTimingProtection"
    );
    // What preempts it: the two tasks above it and the ISRs.
    for above in ["OsLEDTask", "OsBswServiceTask", "SysTickIsr", "CanIsr"] {
        assert!(
            first
                .paths
                .iter()
                .any(|p| p.contains(&format!("/{above}/"))),
            "{above} in {:?}",
            first.paths
        );
    }
    // The tasks below it wait for it: they miss too.
    assert!(e.iter().any(|e| e.what.starts_with("OsSonarTask can miss")));
}

#[test]
fn a_released_task_inherits_its_writers_response_as_jitter() {
    let mut ecu = ecu();
    let released = released_by(&ecu);
    // A longer sonar job releases OsComTask later: its jitter grows with it.
    let before = match timing::analyse(&ecu, &released) {
        Ok(Analysis::Schedulable { items, .. }) => items,
        other => panic!("{other:?}"),
    };
    timing_of(&mut ecu, "OsSonarTask").budget_us = Some(5_000);
    let after = match timing::analyse(&ecu, &released) {
        Ok(Analysis::Schedulable { items, .. }) => items,
        other => panic!("{other:?}"),
    };
    let jitter = |items: &[timing::Item]| {
        items
            .iter()
            .find(|i| i.name == "OsComTask")
            .map(|i| i.load.jitter)
            .expect("OsComTask")
    };
    assert!(jitter(&after) >= jitter(&before) + 4_800);
}

#[test]
fn every_task_needs_a_budget_and_a_release_the_analysis_can_tell() {
    let mut ecu = ecu();
    let released = released_by(&ecu);
    timing_of(&mut ecu, "OsLEDTask").budget_us = None;
    let e = timing::analyse(&ecu, &released).expect_err("no budget");
    assert_eq!(
        e[0].to_string(),
        "task OsLEDTask has no OsTaskExecutionBudget: the task set's analysis needs every \
         task's\n  at /CollisionWarning/EcucValues/Os/OsLEDTask/OsTaskTimingProtection"
    );
    // OsComTask, without the RTE's event that releases it, needs a time frame.
    let ecu = self::ecu();
    let e = timing::analyse(&ecu, &[]).expect_err("no release");
    assert_eq!(
        e[0].to_string(),
        "task OsComTask cannot be analysed: no cyclic alarm, data-received event or \
         OsTaskTimeFrame gives its releases\n  at /CollisionWarning/EcucValues/Os/OsComTask"
    );
    let mut ecu = self::ecu();
    timing_of(&mut ecu, "OsComTask").time_frame_us = Some(40_000);
    assert!(matches!(
        timing::analyse(&ecu, &[]),
        Ok(Analysis::Schedulable { .. })
    ));
    // An ISR's timing protection needs both figures.
    let mut ecu = self::ecu();
    timing_of(&mut ecu, "CanIsr").time_frame_us = None;
    let e = timing::analyse(&ecu, &released).expect_err("no time frame");
    assert!(e[0]
        .what
        .starts_with("ISR CanIsr's timing protection needs both"));
}

#[test]
fn without_any_timing_protection_nothing_is_analysed() {
    let mut ecu = ecu();
    for t in &mut ecu.os.tasks {
        t.timing = None;
    }
    for i in &mut ecu.os.isrs {
        i.timing = None;
    }
    assert_eq!(timing::analyse(&ecu, &[]), Ok(Analysis::NoBudgets));
}

#[test]
fn a_non_preemptive_task_blocks_every_task_above_it_for_its_budget() {
    let mut ecu = ecu();
    let released = released_by(&ecu);
    // The sonar task without resources, its budget above any other section.
    let sonar = ecu
        .os
        .tasks
        .iter_mut()
        .find(|t| t.name == "OsSonarTask")
        .expect("sonar");
    sonar.resources.clear();
    if let Some(t) = sonar.timing.as_mut() {
        t.budget_us = Some(300);
    }
    let blocking = |ecu: &Ecu, name: &str| {
        let Ok(Analysis::Schedulable { items, .. }) = timing::analyse(ecu, &released) else {
            panic!("schedulable");
        };
        match items.iter().find(|i| i.name == name).map(|i| i.response) {
            Some(Response::Meets { blocking, .. }) => blocking,
            other => panic!("{name}: {other:?}"),
        }
    };
    let (led, can) = (blocking(&ecu, "OsLEDTask"), blocking(&ecu, "CanIsr"));
    assert!(led < 300, "preemptive: {led}");
    if let Some(sonar) = ecu.os.tasks.iter_mut().find(|t| t.name == "OsSonarTask") {
        sonar.preemptive = false;
    }
    assert_eq!(
        blocking(&ecu, "OsLEDTask"),
        300,
        "the sonar job's whole budget"
    );
    // An ISR still preempts it.
    assert_eq!(blocking(&ecu, "CanIsr"), can);
}

#[test]
fn a_time_frame_of_zero_two_writers_or_a_lock_budget_are_refused() {
    let mut ecu = ecu();
    let released = released_by(&ecu);
    timing_of(&mut ecu, "SysTickIsr").time_frame_us = Some(0);
    let e = timing::analyse(&ecu, &released).expect_err("no time between releases");
    assert!(e[0]
        .what
        .starts_with("ISR SysTickIsr's timing protection needs both"));
    let ecu = self::ecu();
    let two = [
        ("OsComTask".to_string(), "OsSonarTask".to_string()),
        ("OsComTask".to_string(), "OsLEDTask".to_string()),
    ];
    let e = timing::analyse(&ecu, &two).expect_err("two writers");
    assert_eq!(
        e[0].what,
        "task OsComTask is released by the jobs of OsLEDTask and OsSonarTask: the analysis \
         takes one writer per released task"
    );
    // An interrupt lock section is not modelled: only 0 is taken.
    let lock = "<VALUE>0.0001</VALUE>\n                        </ECUC-NUMERICAL-PARAM-VALUE>";
    assert!(ECU.contains(lock));
    let text = ECU.replacen(
        lock,
        &format!(
            "{lock}\n                        <ECUC-NUMERICAL-PARAM-VALUE>\n                          \
             <DEFINITION-REF DEST=\"ECUC-FLOAT-PARAM-DEF\">/AUTOSAR/EcucDefs/Os/OsTask/\
             OsTaskTimingProtection/OsTaskAllInterruptLockBudget</DEFINITION-REF>\n                          \
             <VALUE>0.00001</VALUE>\n                        </ECUC-NUMERICAL-PARAM-VALUE>"
        ),
        1,
    );
    let e = cw_gen::arxml::read(text.as_bytes(), "ecu.arxml").expect_err("a lock budget");
    assert_eq!(
        e[0].to_string(),
        "OsTaskAllInterruptLockBudget = 10 µs: interrupt lock sections are not in the task \
         set's analysis (0 or none is taken)\n  \
         at /CollisionWarning/EcucValues/Os/OsLEDTask/OsTaskTimingProtection"
    );
}

#[test]
fn budgets_are_read_in_whole_microseconds_and_refused_otherwise() {
    use cw_gen::arxml::parse_exact_us;
    assert_eq!(parse_exact_us("0.0001"), Some(100));
    assert_eq!(parse_exact_us("1E-4"), Some(100));
    assert_eq!(parse_exact_us("0.04"), Some(40_000));
    assert_eq!(parse_exact_us("0.0000005"), None);
    // A double a tool printed with all its digits.
    assert_eq!(cw_gen::arxml::parse_us("1.4999999999999999E-4"), Some(150));
    let text = ECU.replacen("<VALUE>0.0001</VALUE>", "<VALUE>0.00010005</VALUE>", 1);
    let e = cw_gen::arxml::read(text.as_bytes(), "ecu.arxml").expect_err("refused");
    assert_eq!(
        e[0].to_string(),
        "OsTaskExecutionBudget = `0.00010005` is not a whole number of microseconds (in \
         seconds)\n  at /CollisionWarning/EcucValues/Os/OsLEDTask/OsTaskTimingProtection"
    );
}

#[test]
fn generation_refuses_an_unschedulable_task_set() {
    // The sonar task's budget 45 ms, past its 40 ms period.
    let text = ECU.replacen(
        "<VALUE>0.0002</VALUE>",
        "<VALUE>0.045</VALUE>",
        2, // OsComTask's, then OsSonarTask's
    );
    let e = cw_gen::generate_rte(
        COMPONENTS.as_bytes(),
        "swc.arxml",
        text.as_bytes(),
        "ecu.arxml",
    )
    .expect_err("unschedulable");
    assert!(e
        .0
        .iter()
        .any(|e| e.what.starts_with("OsSonarTask can miss its deadline")));
}

#[test]
fn any_budgets_meet_every_deadline_or_are_refused_and_a_shorter_job_never_misses() {
    bolero::check!()
        .with_type::<Vec<u16>>()
        .for_each(|budgets| assert!(cw_gen::spec::budgets_are_sustainable(budgets)));
}
