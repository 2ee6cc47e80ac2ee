//! The steps the kernel's harnesses take, and the small configuration they take them on.
//! One vocabulary for the Kani proofs and bolero tests of `os::tests` and for the
//! exhaustive exploration of `cw-proofs steps`, which takes every step of this domain from
//! every state it reaches.

use super::spec::Service;
use super::{
    AlarmAction, AlarmConfig, AlarmId, CounterConfig, CounterId, EventMask, IsrConfig, IsrId, Os,
    OsConfig, OsDescription, ResourceId, ServiceCall, TaskConfig, TaskId, TickType, RES_SCHEDULER,
};

/// The smallest configuration that has every kind of kernel object, without hooks: task
/// 0 A (priority 1, basic, 2 activations, uses resource 0), task 1 B (priority 2,
/// extended, uses resource 0); one counter (0 to 3); alarm 0 sets event 1 of B; ISR 0
/// (category 2, priority 1). The Kani proofs of the kernel and `cw-proofs steps` run on it.
pub static SMALL: OsConfig<2, 1, 1, 1, 1> = match OsConfig::new(OsDescription::new(
    [
        TaskConfig::basic("A", 1).activations(2).uses(0b1),
        TaskConfig::extended("B", 2).uses(0b1),
    ],
    [CounterConfig {
        max_allowed_value: 3,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [AlarmConfig::new(
        "EvB",
        CounterId(0),
        AlarmAction::SetEvent(TaskId(1), 1),
    )],
    [IsrConfig::cat2("Tick", 1)],
)) {
    Ok(c) => c,
    Err(e) => panic!("{}", e.describe()),
};

/// The kernel of [`SMALL`].
pub type SmallOs = Os<2, 1, 1, 1, 1, 3>;

/// One step of the code running on the processor, in the harnesses' terms: each argument
/// is any byte, and [`Step::service`] maps it onto a [`Service`] with ids a little beyond
/// the configurations, so that the `E_OS_ID` paths are taken too.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(test, derive(bolero::TypeGenerator))]
#[allow(missing_docs)] // Each variant is named after the service it maps to.
pub enum Step {
    Activate(u8),
    Terminate,
    Chain(u8),
    Schedule,
    SetEvent(u8, u8),
    ClearEvent(u8),
    WaitEvent(u8),
    GetResource(u8),
    ReleaseResource(u8),
    FastGet(u8),
    FastRelease(u8),
    SetRel(u8, u8, u8),
    SetAbs(u8, u8, u8),
    Cancel(u8),
    Tick,
    Lock(u8),
    EnterIsr(u8),
    ExitIsr,
    IsrTick(u8),
    FastTick(u8),
    FastActivate(u8),
    IsrActivate(u8, u8),
    TaskReturn,
    Query(u8),
}

impl Step {
    /// The service this step stands for.
    pub fn service(self) -> Service {
        use Service as S;
        use ServiceCall as Call;
        let res = |r: u8| {
            if r % 3 == 2 {
                RES_SCHEDULER
            } else {
                ResourceId(r % 4)
            }
        };
        let isr = |i: u8| IsrId(i % 4);
        match self {
            Step::Activate(t) => S::Call(Call::ActivateTask(TaskId(t % 6))),
            Step::Terminate => S::Call(Call::TerminateTask),
            Step::Chain(t) => S::Call(Call::ChainTask(TaskId(t % 6))),
            Step::Schedule => S::Call(Call::Schedule),
            Step::SetEvent(t, m) => S::Call(Call::SetEvent(TaskId(t % 6), EventMask::from(m % 4))),
            Step::ClearEvent(m) => S::Call(Call::ClearEvent(EventMask::from(m % 4))),
            Step::WaitEvent(m) => S::Call(Call::WaitEvent(EventMask::from(m % 4))),
            Step::GetResource(r) => S::Call(Call::GetResource(res(r))),
            Step::ReleaseResource(r) => S::Call(Call::ReleaseResource(res(r))),
            Step::FastGet(r) => S::FastGet(res(r)),
            Step::FastRelease(r) => S::FastRelease(res(r)),
            Step::SetRel(a, inc, cyc) => S::Call(Call::SetRelAlarm {
                alarm: AlarmId(a % 4),
                increment: TickType::from(inc % 8),
                cycle: TickType::from(cyc % 4),
            }),
            Step::SetAbs(a, st, cyc) => S::Call(Call::SetAbsAlarm {
                alarm: AlarmId(a % 4),
                start: TickType::from(st),
                cycle: TickType::from(cyc % 4),
            }),
            Step::Cancel(a) => S::Call(Call::CancelAlarm(AlarmId(a % 4))),
            Step::Tick => S::Call(Call::IncrementCounter(CounterId(0))),
            Step::Lock(k) => S::Call(match k % 6 {
                0 => Call::DisableAllInterrupts,
                1 => Call::EnableAllInterrupts,
                2 => Call::SuspendAllInterrupts,
                3 => Call::ResumeAllInterrupts,
                4 => Call::SuspendOsInterrupts,
                _ => Call::ResumeOsInterrupts,
            }),
            Step::EnterIsr(i) => S::EnterIsr(isr(i)),
            Step::ExitIsr => S::ExitIsr,
            Step::IsrTick(i) => S::Isr(isr(i), Call::IncrementCounter(CounterId(0))),
            Step::FastTick(i) => S::FastTick(isr(i), CounterId(0)),
            Step::FastActivate(t) => S::FastActivate(TaskId(t % 6)),
            Step::IsrActivate(i, t) => S::Isr(isr(i), Call::ActivateTask(TaskId(t % 6))),
            Step::TaskReturn => S::TaskReturn,
            Step::Query(q) => S::Call(match q % 5 {
                0 => Call::GetTaskId,
                1 => Call::GetTaskState(TaskId(q % 6)),
                2 => Call::GetIsrId,
                3 => Call::GetActiveApplicationMode,
                _ => Call::GetAlarm(AlarmId(q % 4)),
            }),
        }
    }
}
