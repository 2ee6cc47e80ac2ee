//! Scheduler harnesses: each OSEK service's error codes and effects, scenario tests of the
//! scheduling rules, and a bolero harness that drives random service sequences and checks
//! the [`spec`] invariants after every call.
extern crate std;

use super::*;
use crate::os::config::CounterConfig;

const COUNTER: CounterConfig = CounterConfig {
    max_allowed_value: 99,
    ticks_per_base: 1,
    min_cycle: 1,
};

// Tasks: 0 Low(1, basic, 3 activations, uses R0), 1 Mid(3, extended, uses R0 and R1),
// 2 High(5, basic), 3 Np(2, non-preemptive basic), 4 Low2(1, basic, 2 activations).
// Alarms on counter 0: activate High, set event 1 of Mid, callback 7.
static CFG: OsConfig<5, 2, 1, 3> = match OsConfig::new(
    [
        TaskConfig::basic("Low", 1).activations(3).uses(0b01),
        TaskConfig::extended("Mid", 3).uses(0b11),
        TaskConfig::basic("High", 5),
        TaskConfig::basic("Np", 2).non_preemptive(),
        TaskConfig::basic("Low2", 1).activations(2),
    ],
    [COUNTER],
    [
        AlarmConfig {
            name: "ActHigh",
            counter: CounterId(0),
            action: AlarmAction::ActivateTask(TaskId(2)),
            autostart: AlarmAutostart::Off,
        },
        AlarmConfig {
            name: "EvMid",
            counter: CounterId(0),
            action: AlarmAction::SetEvent(TaskId(1), 1),
            autostart: AlarmAutostart::Off,
        },
        AlarmConfig {
            name: "Cb",
            counter: CounterId(0),
            action: AlarmAction::Callback(7),
            autostart: AlarmAutostart::Off,
        },
    ],
) {
    Ok(c) => c,
    Err(e) => panic!("{}", e.describe()),
};

type TestOs = Os<5, 2, 1, 3, 8>;
const LOW: TaskId = TaskId(0);
const MID: TaskId = TaskId(1);
const HIGH: TaskId = TaskId(2);
const NP: TaskId = TaskId(3);
const LOW2: TaskId = TaskId(4);
const R0: ResourceId = ResourceId(0);
const R1: ResourceId = ResourceId(1);

fn os() -> TestOs {
    match TestOs::new(&CFG) {
        Ok(mut os) => {
            assert_eq!(os.start(), Ok(()));
            os
        }
        Err(e) => panic!("{e:?}"),
    }
}

fn check(os: &TestOs) {
    assert!(spec::running_is_highest_ready(os), "not highest: {os:?}");
    assert!(spec::running_priority_is_ceiling(os), "ceiling: {os:?}");
    assert!(spec::activations_accounted(os), "activations: {os:?}");
    assert!(spec::resources_consistent(os), "resources: {os:?}");
    assert!(spec::waiting_is_blocked(os), "waiting: {os:?}");
}

#[test]
fn derived_configuration() {
    assert_eq!(CFG.resource_ceiling(0), Some(3));
    assert_eq!(CFG.resource_ceiling(1), Some(3));
    assert_eq!(CFG.scheduler_ceiling(), 5);
    assert_eq!(CFG.total_activations(), 8);
    assert_eq!(
        Os::<5, 2, 1, 3, 7>::new(&CFG).err(),
        Some(ConfigError::QueueCapacity { needed: 8 })
    );
}

#[test]
fn impossible_configurations_are_refused_with_the_item() {
    let t = |p| TaskConfig::basic("t", p);
    assert_eq!(
        OsConfig::<1, 0, 0, 0>::new([t(64)], [], []).err(),
        Some(ConfigError::TaskPriority { task: 0 })
    );
    assert_eq!(
        OsConfig::<2, 0, 0, 0>::new([t(1), t(1).activations(0)], [], []).err(),
        Some(ConfigError::TaskActivations { task: 1 })
    );
    assert_eq!(
        OsConfig::<1, 0, 0, 0>::new([TaskConfig::extended("e", 1).activations(2)], [], []).err(),
        Some(ConfigError::ExtendedActivations { task: 0 })
    );
    assert_eq!(
        OsConfig::<1, 1, 0, 0>::new([t(1).uses(0b10)], [], []).err(),
        Some(ConfigError::TaskResource { task: 0 })
    );
    let bad_counter = CounterConfig {
        min_cycle: 0,
        ..COUNTER
    };
    assert_eq!(
        OsConfig::<1, 0, 1, 0>::new([t(1)], [bad_counter], []).err(),
        Some(ConfigError::CounterLimits { counter: 0 })
    );
    // One task, one counter and one alarm: the error the alarm alone causes.
    let one_alarm = |counter, action, autostart| {
        OsConfig::<1, 0, 1, 1>::new(
            [t(1)],
            [COUNTER],
            [AlarmConfig {
                name: "a",
                counter,
                action,
                autostart,
            }],
        )
        .err()
    };
    assert_eq!(
        one_alarm(CounterId(1), AlarmAction::Callback(0), AlarmAutostart::Off),
        Some(ConfigError::AlarmCounter { alarm: 0 })
    );
    assert_eq!(
        one_alarm(
            CounterId(0),
            AlarmAction::SetEvent(TaskId(0), 1),
            AlarmAutostart::Off
        ),
        Some(ConfigError::AlarmAction { alarm: 0 })
    );
    assert_eq!(
        one_alarm(
            CounterId(0),
            AlarmAction::ActivateTask(TaskId(0)),
            AlarmAutostart::Relative {
                increment: 0,
                cycle: 10
            }
        ),
        Some(ConfigError::AlarmAutostart { alarm: 0 })
    );
}

#[test]
fn activate_task_errors_and_limit() {
    let mut os = os();
    assert_eq!(os.running(), None);
    assert_eq!(os.activate_task(TaskId(5)), Err(OsError::Id));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    // Two more activations queue up; the fourth is beyond the limit and changes nothing.
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.activate_task(LOW), Ok(()));
    let before = os;
    assert_eq!(os.activate_task(LOW), Err(OsError::Limit));
    assert_eq!(os, before);
    assert_eq!(os.activation_count(LOW), 3);
    // None is lost: the task runs three times.
    for remaining in (0..3).rev() {
        assert_eq!(os.running(), Some(LOW));
        assert_eq!(os.terminate_task(), Ok(()));
        assert_eq!(os.activation_count(LOW), remaining);
        check(&os);
    }
    assert_eq!(os.running(), None);
    assert_eq!(os.get_task_state(LOW), Ok(TaskState::Suspended));
}

#[test]
fn preemption_and_fifo_within_a_priority() {
    let mut os = os();
    assert_eq!(os.activate_task(LOW), Ok(()));
    // Equal priority does not preempt, and queues behind in activation order.
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(
        os.ready_at(1).collect::<std::vec::Vec<_>>(),
        [LOW2, LOW, LOW2]
    );
    // A higher priority preempts; the preempted task becomes the oldest of its priority.
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.get_task_state(LOW), Ok(TaskState::Ready));
    assert_eq!(
        os.ready_at(1).collect::<std::vec::Vec<_>>(),
        [LOW, LOW2, LOW, LOW2]
    );
    check(&os);
    assert_eq!(os.terminate_task(), Ok(()));
    // The preempted instance resumes (it was started), then the queue in FIFO order.
    assert_eq!(os.running(), Some(LOW));
    assert!(os.is_started(LOW));
    let mut order = std::vec::Vec::new();
    while let Some(t) = os.running() {
        order.push(t);
        assert_eq!(os.terminate_task(), Ok(()));
        check(&os);
    }
    assert_eq!(order, [LOW, LOW2, LOW, LOW2]);
}

#[test]
fn terminate_and_chain_errors() {
    let mut os = os();
    assert_eq!(os.terminate_task(), Err(OsError::CallLevel));
    assert_eq!(os.chain_task(LOW), Err(OsError::CallLevel));
    assert_eq!(os.schedule(), Err(OsError::CallLevel));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.terminate_task(), Err(OsError::Resource));
    assert_eq!(os.chain_task(HIGH), Err(OsError::Resource));
    assert_eq!(os.schedule(), Err(OsError::Resource));
    assert_eq!(os.release_resource(R0), Ok(()));
    assert_eq!(os.chain_task(TaskId(9)), Err(OsError::Id));
    // At interrupt level.
    assert_eq!(os.enter_isr(), Ok(()));
    assert_eq!(os.terminate_task(), Err(OsError::CallLevel));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.exit_isr(), Err(OsError::CallLevel));
    // Chain to a task at its limit: E_OS_LIMIT and the caller keeps running.
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.activate_task(LOW2), Ok(()));
    assert_eq!(os.chain_task(LOW2), Err(OsError::Limit));
    assert_eq!(os.running(), Some(LOW));
    // Chain to itself: the task is re-queued as the newest of its priority.
    assert_eq!(os.chain_task(LOW), Ok(()));
    assert_eq!(os.running(), Some(LOW2));
    assert_eq!(os.ready_at(1).collect::<std::vec::Vec<_>>(), [LOW2, LOW]);
    assert_eq!(os.activation_count(LOW), 1);
    check(&os);
    // Chain to a higher task.
    assert_eq!(os.chain_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    assert_eq!(os.get_task_state(LOW2), Ok(TaskState::Ready));
    check(&os);
}

#[test]
fn non_preemptive_task_yields_only_at_schedule() {
    let mut os = os();
    assert_eq!(os.activate_task(NP), Ok(()));
    assert_eq!(os.running_priority(), Some(5));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(
        os.running(),
        Some(NP),
        "a non-preemptive task is not preempted"
    );
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.schedule(), Ok(()));
    assert_eq!(
        os.running(),
        Some(HIGH),
        "Schedule lets the higher task run"
    );
    assert_eq!(os.ready_at(2).next(), Some(NP));
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.running(), Some(NP));
    assert_eq!(
        os.running_priority(),
        Some(5),
        "internal resource taken again"
    );
    // Schedule with nothing higher keeps the task and its priority.
    assert_eq!(os.schedule(), Ok(()));
    assert_eq!(os.running(), Some(NP));
    assert_eq!(os.running_priority(), Some(5));
    check(&os);
}

#[test]
fn resources_ceiling_and_lifo() {
    let mut os = os();
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.get_resource(ResourceId(2)), Err(OsError::Id));
    assert_eq!(os.get_resource(R0), Ok(()));
    assert_eq!(os.running_priority(), Some(3));
    assert_eq!(os.get_resource(R0), Err(OsError::Access), "occupied");
    // Mid (priority 3) is not above the ceiling: no preemption; High is.
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    // High's priority is above R0's ceiling: E_OS_ACCESS both ways.
    assert_eq!(os.get_resource(R0), Err(OsError::Access));
    assert_eq!(os.release_resource(R0), Err(OsError::Access));
    assert_eq!(os.get_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.release_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.terminate_task(), Ok(()));
    // Low resumes at its ceiling, ahead of Mid.
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.running_priority(), Some(3));
    assert_eq!(os.get_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.running_priority(), Some(5));
    assert_eq!(os.release_resource(R0), Err(OsError::NoFunc), "not LIFO");
    assert_eq!(os.release_resource(R1), Err(OsError::NoFunc), "not held");
    assert_eq!(
        os.held_resources(LOW).collect::<std::vec::Vec<_>>(),
        [RES_SCHEDULER, R0]
    );
    assert_eq!(os.release_resource(RES_SCHEDULER), Ok(()));
    assert_eq!(os.running_priority(), Some(3));
    check(&os);
    // Releasing the last resource lowers the priority and lets Mid preempt.
    assert_eq!(os.release_resource(R0), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.ready_at(1).next(), Some(LOW));
    check(&os);
    // Interrupt level never takes task resources.
    assert_eq!(os.enter_isr(), Ok(()));
    assert_eq!(os.get_resource(R1), Err(OsError::Access));
    assert_eq!(os.exit_isr(), Ok(()));
}

#[test]
fn events_wait_and_release() {
    let mut os = os();
    assert_eq!(os.set_event(MID, 1), Err(OsError::State), "suspended");
    assert_eq!(os.set_event(LOW, 1), Err(OsError::Access), "basic task");
    assert_eq!(os.get_event(LOW), Err(OsError::Access));
    assert_eq!(os.get_event(MID), Err(OsError::State));
    assert_eq!(os.set_event(TaskId(7), 1), Err(OsError::Id));
    assert_eq!(os.clear_event(1), Err(OsError::CallLevel));
    assert_eq!(os.wait_event(1), Err(OsError::CallLevel));
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.wait_event(1), Err(OsError::Access));
    assert_eq!(os.clear_event(1), Err(OsError::Access));
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.get_resource(R1), Ok(()));
    assert_eq!(os.wait_event(0b10), Err(OsError::Resource));
    assert_eq!(os.release_resource(R1), Ok(()));
    // An event already set: WaitEvent returns at once.
    assert_eq!(os.set_event(MID, 0b100), Ok(()));
    assert_eq!(os.wait_event(0b110), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.clear_event(0b100), Ok(()));
    assert_eq!(os.get_event(MID), Ok(0));
    // Wait: Low runs; an unrelated event does not release; a waited one does, at once.
    assert_eq!(os.wait_event(0b10), Ok(()));
    assert_eq!(os.get_task_state(MID), Ok(TaskState::Waiting));
    assert_eq!(os.running(), Some(LOW));
    assert_eq!(os.activate_task(MID), Err(OsError::Limit));
    assert_eq!(os.set_event(MID, 0b1), Ok(()));
    assert_eq!(os.get_task_state(MID), Ok(TaskState::Waiting));
    check(&os);
    assert_eq!(os.set_event(MID, 0b10), Ok(()));
    assert_eq!(os.running(), Some(MID));
    assert_eq!(os.get_event(MID), Ok(0b11));
    check(&os);
    // Re-activation of an extended task clears its events.
    assert_eq!(os.terminate_task(), Ok(()));
    assert_eq!(os.activate_task(MID), Ok(()));
    assert_eq!(os.get_event(MID), Ok(0));
}

#[test]
fn isr_defers_rescheduling() {
    let mut os = os();
    assert_eq!(os.activate_task(LOW), Ok(()));
    assert_eq!(os.enter_isr(), Ok(()));
    assert_eq!(os.enter_isr(), Ok(()));
    assert_eq!(os.activate_task(HIGH), Ok(()));
    assert_eq!(os.get_task_id(), Some(LOW));
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.running(), Some(LOW), "nested ISR still active");
    assert_eq!(os.exit_isr(), Ok(()));
    assert_eq!(os.running(), Some(HIGH));
    check(&os);
}

#[test]
fn alarms_relative_absolute_cyclic() {
    let mut os = os();
    let (act_high, ev_mid, cb) = (AlarmId(0), AlarmId(1), AlarmId(2));
    assert_eq!(os.set_rel_alarm(AlarmId(3), 1, 0), Err(OsError::Id));
    assert_eq!(os.set_rel_alarm(act_high, 0, 0), Err(OsError::Value));
    assert_eq!(os.set_rel_alarm(act_high, 100, 0), Err(OsError::Value));
    assert_eq!(os.set_rel_alarm(act_high, 5, 100), Err(OsError::Value));
    assert_eq!(os.get_alarm(act_high), Err(OsError::NoFunc));
    assert_eq!(os.cancel_alarm(act_high), Err(OsError::NoFunc));
    assert_eq!(os.set_rel_alarm(act_high, 5, 10), Ok(()));
    assert_eq!(os.set_rel_alarm(act_high, 5, 10), Err(OsError::State));
    assert_eq!(os.get_alarm(act_high), Ok(5));
    assert_eq!(
        os.get_alarm_base(act_high),
        Ok(AlarmBase {
            max_allowed_value: 99,
            ticks_per_base: 1,
            min_cycle: 1
        })
    );
    // Absolute at value 3 (now 0): 3 ticks away; the callback alarm at the current value
    // waits a full revolution.
    assert_eq!(os.set_abs_alarm(cb, 100, 0), Err(OsError::Value));
    assert_eq!(os.set_abs_alarm(cb, 0, 0), Ok(()));
    assert_eq!(os.get_alarm(cb), Ok(100));
    assert_eq!(os.cancel_alarm(cb), Ok(()));
    assert_eq!(os.set_abs_alarm(cb, 3, 0), Ok(()));
    assert_eq!(os.get_alarm(cb), Ok(3));
    let mut callbacks = std::vec::Vec::new();
    let mut high_runs = std::vec::Vec::new();
    for tick in 1..=30u32 {
        let report = match os.increment_counter(CounterId(0)) {
            Ok(r) => r,
            Err(e) => panic!("{e:?}"),
        };
        if report.callbacks != 0 {
            callbacks.push((tick, report.callbacks));
        }
        if os.running() == Some(HIGH) {
            high_runs.push(tick);
            assert_eq!(os.terminate_task(), Ok(()));
        }
        check(&os);
    }
    assert_eq!(callbacks, [(3, 1 << 7)]);
    assert_eq!(high_runs, [5, 15, 25]);
    assert_eq!(os.counter_value(CounterId(0)), Some(30));
    assert_eq!(os.get_alarm(act_high), Ok(5));
    // Event alarm on a suspended task: the failure is counted, not lost silently.
    assert_eq!(os.set_rel_alarm(ev_mid, 1, 0), Ok(()));
    let report = os.increment_counter(CounterId(0));
    assert_eq!(
        report.map(|r| (r.failed_actions, r.last_failure)),
        Ok((1, Some(OsError::State)))
    );
    assert_eq!(os.increment_counter(CounterId(1)), Err(OsError::Id));
    assert_eq!(os.cancel_alarm(act_high), Ok(()));
    assert!(!os.alarm_armed(act_high));
}

#[test]
fn counter_wraps_and_simultaneous_alarms_fire_in_arming_order() {
    let mut os = os();
    for _ in 0..98 {
        assert!(os.increment_counter(CounterId(0)).is_ok());
    }
    assert_eq!(os.counter_value(CounterId(0)), Some(98));
    assert_eq!(os.set_abs_alarm(AlarmId(2), 1, 0), Ok(()));
    assert_eq!(os.set_rel_alarm(AlarmId(0), 3, 0), Ok(()));
    assert_eq!(os.get_alarm(AlarmId(2)), Ok(3));
    assert!(os.increment_counter(CounterId(0)).is_ok());
    assert!(os.increment_counter(CounterId(0)).is_ok());
    assert_eq!(os.counter_value(CounterId(0)), Some(0));
    assert_eq!(os.running(), None);
    let report = os.increment_counter(CounterId(0));
    assert_eq!(report.map(|r| r.callbacks), Ok(1 << 7));
    assert_eq!(os.running(), Some(HIGH));
}

/// One call into the kernel, generated by bolero, mapped onto [`spec::Service`] with ids
/// slightly beyond the configuration so that `E_OS_ID` paths are taken too.
#[derive(Debug, Clone, Copy, bolero::TypeGenerator)]
enum Call {
    Activate(u8),
    Terminate,
    Chain(u8),
    Schedule,
    SetEvent(u8, u8),
    ClearEvent(u8),
    WaitEvent(u8),
    GetResource(u8),
    ReleaseResource(u8),
    SetRel(u8, u8, u8),
    SetAbs(u8, u8, u8),
    Cancel(u8),
    Tick,
    EnterIsr,
    ExitIsr,
    IsrTick,
    IsrActivate(u8),
}

fn service(call: Call) -> spec::Service {
    use spec::Service as S;
    let res = |r: u8| {
        if r % 3 == 2 {
            RES_SCHEDULER
        } else {
            ResourceId(r % 4)
        }
    };
    match call {
        Call::Activate(t) => S::ActivateTask(TaskId(t % 6)),
        Call::Terminate => S::TerminateTask,
        Call::Chain(t) => S::ChainTask(TaskId(t % 6)),
        Call::Schedule => S::Schedule,
        Call::SetEvent(t, m) => S::SetEvent(TaskId(t % 6), EventMask::from(m % 4)),
        Call::ClearEvent(m) => S::ClearEvent(EventMask::from(m % 4)),
        Call::WaitEvent(m) => S::WaitEvent(EventMask::from(m % 4)),
        Call::GetResource(r) => S::GetResource(res(r)),
        Call::ReleaseResource(r) => S::ReleaseResource(res(r)),
        Call::SetRel(a, inc, cyc) => S::SetRelAlarm(
            AlarmId(a % 4),
            TickType::from(inc % 8),
            TickType::from(cyc % 4),
        ),
        Call::SetAbs(a, st, cyc) => {
            S::SetAbsAlarm(AlarmId(a % 4), TickType::from(st), TickType::from(cyc % 4))
        }
        Call::Cancel(a) => S::CancelAlarm(AlarmId(a % 4)),
        Call::Tick => S::IncrementCounter(CounterId(0)),
        Call::EnterIsr => S::EnterIsr,
        Call::ExitIsr => S::ExitIsr,
        Call::IsrTick => S::IsrTick(CounterId(0)),
        Call::IsrActivate(t) => S::IsrActivateTask(TaskId(t % 6)),
    }
}

#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(9))]
fn random_service_sequences_keep_the_invariants() {
    bolero::check!()
        .with_type::<std::vec::Vec<Call>>()
        .for_each(|calls| {
            let mut os = os();
            for call in calls.iter().take(64) {
                if let Err(rule) = spec::call_and_check(&mut os, service(*call)) {
                    panic!("{call:?}: {rule}\n{os:?}");
                }
            }
        });
}

#[test]
fn transition_rules_can_fail() {
    let before = os();
    // A successful ActivateTask that changed nothing would be a lost activation.
    assert_eq!(
        spec::transition_rules(&before, &before, spec::Service::ActivateTask(LOW), Ok(())),
        Err("an activation was lost")
    );
    let mut queued_ab = before;
    let mut queued_ba = before;
    for (os, order) in [
        (&mut queued_ab, [HIGH, LOW, LOW2]),
        (&mut queued_ba, [HIGH, LOW2, LOW]),
    ] {
        for t in order {
            assert_eq!(os.activate_task(t), Ok(()));
        }
    }
    assert!(spec::fifo_discipline(&queued_ab, &queued_ba).is_err());
    assert_eq!(spec::fifo_discipline(&queued_ab, &queued_ab), Ok(()));
}
