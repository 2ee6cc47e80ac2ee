//! The two-task kernel both the criterion benchmarks (`benches/core.rs`) and the callgrind
//! probes (`examples/callgrind_probe.rs`) measure, so their figures describe the same
//! configuration: Low (priority 1) and High (5), one 1-tick counter, one callback alarm,
//! and one category-2 ISR (the timer's) from which a task is started when none runs.

use cw_core::os::{
    AlarmAction, AlarmConfig, CounterConfig, CounterId, IsrConfig, IsrId, OsConfig, OsDescription,
    TaskConfig,
};

/// The timer ISR.
pub const TICK_ISR: IsrId = IsrId(0);

/// The configuration; a broken one stops the build.
pub static TWO: OsConfig<2, 0, 1, 1, 1> = match OsConfig::new(OsDescription::new(
    [TaskConfig::basic("Low", 1), TaskConfig::basic("High", 5)],
    [CounterConfig {
        max_allowed_value: u32::MAX - 1,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [AlarmConfig::new(
        "Cb",
        CounterId(0),
        AlarmAction::Callback(0),
    )],
    [IsrConfig::cat2("Tick", 0)],
)) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};
