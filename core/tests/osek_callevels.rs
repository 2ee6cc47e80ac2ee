//! OSEK OS conformance, call levels: every service called from every context, in both
//! dialects, against the standards' tables (OSEK OS 2.2.3 Figure 12-1; the AUTOSAR SWS OS
//! table of allowed calling contexts), which this file states on its own, apart from the
//! kernel's. A service called where the table does not allow it returns `E_OS_CALLEVEL`;
//! anywhere else, whatever it returns, it is not that.
//!
//! The kernel is driven into each context for real: before `StartOS`, idle, in a task, in a
//! category-1 and a category-2 ISR, inside each hook as the kernel calls it, in an alarm
//! callback, and after `ShutdownOS`. There every service is probed on a copy of the kernel
//! (the kernel is a plain value), so that one probe's effects do not change the next.

use cw_core::os::call::perform;
use cw_core::os::{
    AlarmAction, AlarmConfig, AlarmId, AppMode, Context, CounterConfig, CounterId, Dialect,
    HookSet, Hooks, IsrConfig, IsrId, Os, OsConfig, OsDescription, OsError, ResourceId,
    ServiceCall, ServiceId, StatusType, TaskConfig, TaskId, OSDEFAULTAPPMODE,
};

/// The contexts, in the order of the table's columns.
const CONTEXTS: [(char, Context); 12] = [
    ('B', Context::BeforeStart),
    ('I', Context::Idle),
    ('T', Context::Task),
    ('1', Context::Isr1),
    ('2', Context::Isr2),
    ('E', Context::ErrorHook),
    ('P', Context::PreTaskHook),
    ('Q', Context::PostTaskHook),
    ('S', Context::StartupHook),
    ('D', Context::ShutdownHook),
    ('C', Context::AlarmCallback),
    ('X', Context::ShutDown),
];

/// Where each service may be called: OSEK, then AUTOSAR. One letter per context: B before
/// `StartOS`, I idle (none: the idle loop calls nothing), T task, 1 and 2 ISR category 1
/// and 2, E `ErrorHook`, P `PreTaskHook`, Q `PostTaskHook`, S `StartupHook`, D
/// `ShutdownHook`, C alarm callback, X after `ShutdownOS`.
pub const TABLE: [(ServiceId, &str, &str); 30] = [
    (ServiceId::ActivateTask, "T2", "T2"),
    (ServiceId::TerminateTask, "T", "T"),
    (ServiceId::ChainTask, "T", "T"),
    (ServiceId::Schedule, "T", "T"),
    (ServiceId::GetTaskId, "T2EPQ", "T2EPQ"),
    (ServiceId::GetTaskState, "T2EPQ", "T2EPQ"),
    (ServiceId::DisableAllInterrupts, "T12", "BT12EPQSDCX"),
    (ServiceId::EnableAllInterrupts, "T12", "BT12EPQSDCX"),
    (ServiceId::SuspendAllInterrupts, "T12EPQC", "BT12EPQSDCX"),
    (ServiceId::ResumeAllInterrupts, "T12EPQC", "BT12EPQSDCX"),
    (ServiceId::SuspendOsInterrupts, "T12", "T12EPQSDC"),
    (ServiceId::ResumeOsInterrupts, "T12", "T12EPQSDC"),
    (ServiceId::GetResource, "T2", "T2"),
    (ServiceId::ReleaseResource, "T2", "T2"),
    (ServiceId::SetEvent, "T2", "T2"),
    (ServiceId::ClearEvent, "T", "T"),
    (ServiceId::GetEvent, "T2EPQ", "T2EPQ"),
    (ServiceId::WaitEvent, "T", "T"),
    (ServiceId::GetAlarmBase, "T2EPQ", "T2EPQ"),
    (ServiceId::GetAlarm, "T2EPQ", "T2EPQ"),
    (ServiceId::SetRelAlarm, "T2", "T2"),
    (ServiceId::SetAbsAlarm, "T2", "T2"),
    (ServiceId::CancelAlarm, "T2", "T2"),
    (ServiceId::GetActiveApplicationMode, "T2EPQSD", "T2EPQSD"),
    (ServiceId::StartOs, "B", "B"),
    (ServiceId::ShutdownOs, "T2ES", "T2ES"),
    (ServiceId::GetIsrId, "T2E", "T2E"),
    (ServiceId::IncrementCounter, "T2", "T2"),
    (ServiceId::GetCounterValue, "T2", "T2"),
    (ServiceId::GetElapsedValue, "T2", "T2"),
];

/// A call of `service` with valid arguments.
fn call_of(service: ServiceId) -> Option<ServiceCall> {
    use ServiceCall as S;
    let alarm = AlarmId(0);
    Some(match service {
        ServiceId::ActivateTask => S::ActivateTask(TaskId(1)),
        ServiceId::TerminateTask => S::TerminateTask,
        ServiceId::ChainTask => S::ChainTask(TaskId(1)),
        ServiceId::Schedule => S::Schedule,
        ServiceId::GetTaskId => S::GetTaskId,
        ServiceId::GetTaskState => S::GetTaskState(TaskId(0)),
        ServiceId::DisableAllInterrupts => S::DisableAllInterrupts,
        ServiceId::EnableAllInterrupts => S::EnableAllInterrupts,
        ServiceId::SuspendAllInterrupts => S::SuspendAllInterrupts,
        ServiceId::ResumeAllInterrupts => S::ResumeAllInterrupts,
        ServiceId::SuspendOsInterrupts => S::SuspendOsInterrupts,
        ServiceId::ResumeOsInterrupts => S::ResumeOsInterrupts,
        ServiceId::GetResource => S::GetResource(ResourceId(0)),
        ServiceId::ReleaseResource => S::ReleaseResource(ResourceId(0)),
        ServiceId::SetEvent => S::SetEvent(TaskId(0), 1),
        ServiceId::ClearEvent => S::ClearEvent(1),
        ServiceId::GetEvent => S::GetEvent(TaskId(0)),
        ServiceId::WaitEvent => S::WaitEvent(1),
        ServiceId::GetAlarmBase => S::GetAlarmBase(alarm),
        ServiceId::GetAlarm => S::GetAlarm(alarm),
        ServiceId::SetRelAlarm => S::SetRelAlarm {
            alarm: AlarmId(1),
            increment: 5,
            cycle: 0,
        },
        ServiceId::SetAbsAlarm => S::SetAbsAlarm {
            alarm: AlarmId(1),
            start: 5,
            cycle: 0,
        },
        ServiceId::CancelAlarm => S::CancelAlarm(alarm),
        ServiceId::GetActiveApplicationMode => S::GetActiveApplicationMode,
        ServiceId::StartOs => S::StartOs(OSDEFAULTAPPMODE),
        ServiceId::ShutdownOs => S::ShutdownOs(0),
        ServiceId::GetIsrId => S::GetIsrId,
        ServiceId::IncrementCounter => S::IncrementCounter(CounterId(0)),
        ServiceId::GetCounterValue => S::GetCounterValue(CounterId(0)),
        ServiceId::GetElapsedValue => S::GetElapsedValue(CounterId(0), 0),
        ServiceId::TaskMissingEnd | ServiceId::IsrMissingEnd | ServiceId::HookMissingEnd => {
            return None
        }
    })
}

/// The hooks' data: in which context to probe, and what was found there (one bit per
/// service refused with `E_OS_CALLEVEL`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
struct Probe {
    target: Option<Context>,
    refused: Option<u64>,
}

type Kernel = Os<2, 1, 1, 2, 2, 2, &'static OsConfig<2, 1, 1, 2, 2>, Probe>;

/// Calls every service on copies of `os`, as the code running now; returns those refused
/// with `E_OS_CALLEVEL`.
fn probe_here(os: &Kernel) -> u64 {
    let mut refused = 0;
    for &(service, _, _) in &TABLE {
        let Some(call) = call_of(service) else {
            continue;
        };
        let mut copy = *os;
        copy.hooks_mut().target = None;
        if perform(&mut copy, call) == Err(OsError::CallLevel) {
            refused |= service.bit();
        }
    }
    refused
}

fn probe_in_hook(os: &mut Kernel, context: Context) {
    if os.hooks().target == Some(context) && os.hooks().refused.is_none() {
        let refused = probe_here(os);
        os.hooks_mut().refused = Some(refused);
    }
}

impl Hooks<Kernel> for Probe {
    fn startup_hook(os: &mut Kernel) {
        probe_in_hook(os, Context::StartupHook);
    }
    fn shutdown_hook(os: &mut Kernel, _error: StatusType) {
        probe_in_hook(os, Context::ShutdownHook);
    }
    fn pre_task_hook(os: &mut Kernel) {
        probe_in_hook(os, Context::PreTaskHook);
    }
    fn post_task_hook(os: &mut Kernel) {
        probe_in_hook(os, Context::PostTaskHook);
    }
    fn error_hook(os: &mut Kernel, _error: OsError) {
        probe_in_hook(os, Context::ErrorHook);
    }
    fn alarm_callback(os: &mut Kernel, _callback: u8) {
        probe_in_hook(os, Context::AlarmCallback);
    }
}

const fn config(dialect: Dialect) -> OsConfig<2, 1, 1, 2, 2> {
    match OsConfig::new(
        OsDescription::new(
            [
                TaskConfig::extended("t1", 1).uses(0b1).autostart(),
                TaskConfig::basic("t2", 2),
            ],
            [CounterConfig {
                max_allowed_value: 99,
                ticks_per_base: 1,
                min_cycle: 1,
            }],
            [
                AlarmConfig::new("cb", CounterId(0), AlarmAction::Callback(0)).relative(1, 0),
                AlarmConfig::new("a1", CounterId(0), AlarmAction::ActivateTask(TaskId(1))),
            ],
            [IsrConfig::cat2("isr2", 1), IsrConfig::cat1("isr1", 5)],
        )
        .dialect(dialect)
        .hooks(HookSet::ALL),
    ) {
        Ok(cfg) => cfg,
        Err(_) => panic!("call-level configuration refused"),
    }
}

static OSEK: OsConfig<2, 1, 1, 2, 2> = config(Dialect::Osek);
static AUTOSAR: OsConfig<2, 1, 1, 2, 2> = config(Dialect::Autosar);

/// Drives a kernel into `context` and returns the services refused there.
fn refused_in(cfg: &'static OsConfig<2, 1, 1, 2, 2>, context: Context) -> u64 {
    let probe = Probe {
        target: Some(context),
        refused: None,
    };
    let Ok(mut os) = Kernel::with_hooks(cfg, probe) else {
        panic!("kernel refused");
    };
    if context == Context::BeforeStart {
        return probe_here(&os);
    }
    // StartupHook, PreTaskHook (t1 is dispatched) run inside StartOS.
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    match context {
        Context::Task => return probe_here(&os),
        Context::Isr2 | Context::Isr1 => {
            let isr = if context == Context::Isr2 { 0 } else { 1 };
            assert_eq!(os.enter_isr(IsrId(isr)), Ok(()));
            assert_eq!(os.context(), context);
            return probe_here(&os);
        }
        // A service that fails at task level calls ErrorHook.
        Context::ErrorHook => {
            let _ = os.activate_task(TaskId(9));
        }
        // t1 waits: PostTaskHook.
        Context::PostTaskHook => {
            let _ = os.wait_event(1);
        }
        // The tick expires the callback alarm.
        Context::AlarmCallback => {
            let _ = os.increment_counter(CounterId(0));
        }
        Context::ShutdownHook => {
            let _ = os.shutdown_os(0);
        }
        Context::Idle => {
            let _ = os.wait_event(1);
            assert_eq!(os.context(), Context::Idle);
            return probe_here(&os);
        }
        Context::ShutDown => {
            let _ = os.shutdown_os(0);
            assert_eq!(os.context(), Context::ShutDown);
            return probe_here(&os);
        }
        _ => {}
    }
    match os.hooks().refused {
        Some(refused) => refused,
        None => panic!("the kernel never called the hook of {context:?}"),
    }
}

/// The services `column` of the table allows in `letter`'s context.
fn allowed(column: usize, letter: char) -> u64 {
    TABLE
        .iter()
        .filter(|row| if column == 0 { row.1 } else { row.2 }.contains(letter))
        .fold(0, |m, row| m | row.0.bit())
}

fn names(mask: u64) -> Vec<&'static str> {
    TABLE
        .iter()
        .filter(|row| mask & row.0.bit() != 0)
        .map(|row| row.0.name())
        .collect()
}

#[track_caller]
fn check_dialect(cfg: &'static OsConfig<2, 1, 1, 2, 2>, column: usize) {
    let every: u64 = TABLE.iter().fold(0, |m, row| m | row.0.bit());
    for (letter, context) in CONTEXTS {
        let expected_refused = every & !allowed(column, letter);
        let refused = refused_in(cfg, context);
        assert_eq!(
            refused,
            expected_refused,
            "{context:?}: refused with E_OS_CALLEVEL {:?}, the standard refuses {:?}",
            names(refused),
            names(expected_refused)
        );
    }
}

/// Every service in every context, OSEK's table.
#[test]
fn cl_osek_every_service_in_every_context() {
    check_dialect(&OSEK, 0);
}

/// Every service in every context, AUTOSAR's table.
#[test]
fn cl_autosar_every_service_in_every_context() {
    check_dialect(&AUTOSAR, 1);
}

/// `StartOS` only before the OS runs, and only with a configured application mode.
#[test]
fn cl_startos_outside_the_os_only() {
    let Ok(mut os) = Kernel::with_hooks(&OSEK, Probe::default()) else {
        panic!("kernel refused");
    };
    assert_eq!(os.start_os(AppMode(1)), Err(OsError::Value));
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Ok(()));
    assert_eq!(os.start_os(OSDEFAULTAPPMODE), Err(OsError::CallLevel));
}

/// The OS chapter's table of services (`docs/src/os.md`) says the same as this file's.
#[test]
#[cfg_attr(
    miri,
    ignore = "text parsing: nothing for Miri; the test stage runs it natively"
)]
fn cl_os_chapter_table_matches() {
    let chapter = include_str!("../../docs/src/os.md");
    for &(service, osek, autosar) in &TABLE {
        let row_start = format!("| `{}` |", service.name());
        let Some(line) = chapter.lines().find(|l| l.starts_with(&row_start)) else {
            panic!("docs/src/os.md has no row for {}", service.name());
        };
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | service | OSEK | AUTOSAR | status codes | tests |
        let (Some(o), Some(a)) = (cells.get(2), cells.get(3)) else {
            panic!("docs/src/os.md row for {} is short: {line}", service.name());
        };
        assert_eq!(
            *o,
            osek,
            "docs/src/os.md: OSEK call levels of {}",
            service.name()
        );
        assert_eq!(
            *a,
            autosar,
            "docs/src/os.md: AUTOSAR call levels of {}",
            service.name()
        );
    }
}
