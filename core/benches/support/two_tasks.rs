//! The two-task kernel both the criterion benchmarks (`benches/core.rs`) and the callgrind
//! probes (`examples/callgrind_probe.rs`) measure, so their figures describe the same
//! configuration: Low (priority 1) and High (5), one 1-tick counter, one callback alarm.

use cw_core::os::{
    AlarmAction, AlarmAutostart, AlarmConfig, CounterConfig, CounterId, OsConfig, TaskConfig,
};

/// The configuration; a broken one stops the build.
pub static TWO: OsConfig<2, 0, 1, 1> = match OsConfig::new(
    [TaskConfig::basic("Low", 1), TaskConfig::basic("High", 5)],
    [CounterConfig {
        max_allowed_value: u32::MAX - 1,
        ticks_per_base: 1,
        min_cycle: 1,
    }],
    [AlarmConfig {
        name: "Cb",
        counter: CounterId(0),
        action: AlarmAction::Callback(0),
        autostart: AlarmAutostart::Off,
    }],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};
