//! Emulator in the loop: the Cortex-M4 image on QEMU is the same ECU as the host
//! simulation (same frames, same LED levels, times within one OS tick, the schedule as
//! configured), and it refuses a scenario file it cannot read, naming why.
//!
//! Run with `cargo xtask qemu --compare`: it builds the image and sets `CW_QEMU_IMAGE`.

use std::path::{Path, PathBuf};

use cw_tests::{compare, image, run_image, simulate};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn out(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("qemu")
        .join(name)
}

/// The image on `scenario` against the simulation, both with the sensor model's seed 1;
/// prints the counts compared.
fn same_ecu(scenario: &str) -> cw_tests::ImageRun {
    same_ecu_seeded(scenario, 1)
}

/// The image on `scenario` against the simulation, both with sensor seed `seed`.
fn same_ecu_seeded(scenario: &str, seed: u64) -> cw_tests::ImageRun {
    let image = image().unwrap_or_else(|e| panic!("{e}"));
    let path = root().join("scenarios").join(scenario);
    let dir = out(&format!("{scenario}-seed{seed}"));
    let run = run_image(&image, Some(&path), seed, &dir).unwrap_or_else(|e| panic!("{e}"));
    assert!(run.success, "the image failed:\n{}", run.report);
    let schedule = run
        .schedule()
        .unwrap_or_else(|| panic!("no schedule line in:\n{}", run.report));
    assert!(
        schedule.contains(" 0 not by a higher priority; 0 periodic tasks"),
        "the image's schedule check failed: {schedule}"
    );
    let image_trace = run.trace().unwrap_or_else(|e| panic!("{e}"));
    let host = simulate(&path, seed).unwrap_or_else(|e| panic!("{e}"));
    let a = compare(&image_trace, &host).unwrap_or_else(|e| panic!("{scenario}: {e}"));
    println!(
        "same ECU on scenarios/{scenario} (seed {seed}): {} CAN frames compared (id and payload, in order; \
         the image sent {} more), times within {:.3} ms; {} red and {} yellow LED levels \
         compared in order, times within {:.3} ms; schedule: {schedule}",
        a.frames, a.image_extra, a.frame_skew_ms, a.red, a.yellow, a.led_skew_ms
    );
    run
}

#[test]
fn figure7_is_the_same_ecu_on_the_image() {
    same_ecu("figure7.txt");
}

#[test]
fn faults_is_the_same_ecu_on_the_image() {
    same_ecu("faults.txt");
}

#[test]
fn no_communication_is_the_same_ecu_on_the_image() {
    same_ecu("no-communication.txt");
}

/// The ignition goes off: EcuM's post-run darkens the LEDs and calls ShutdownOS(E_OK); on
/// the image the run ends there (interrupts off for good), with the same frames and LED
/// levels as the host simulation, whose ECU stays silent after it.
#[test]
fn shutdown_is_the_same_ecu_on_the_image_and_ends_at_shutdown_os() {
    let run = same_ecu("shutdown.txt");
    let line = run
        .report
        .lines()
        .find(|l| l.starts_with("cw-qemu: ShutdownOS at "))
        .unwrap_or_else(|| panic!("no ShutdownOS line in:\n{}", run.report));
    assert!(
        line.ends_with("ShutdownHook saw E_OK; no task or interrupt runs from here on"),
        "{line}"
    );
    // The scenario's shutdown is at 6 s and it lasts 8 s: the run ends within the
    // post-run's few BSW cycles of 6 s, not at 8 s.
    let at: u32 = line
        .trim_start_matches("cw-qemu: ShutdownOS at ")
        .split(' ')
        .next()
        .and_then(|ms| ms.parse().ok())
        .unwrap_or_else(|| panic!("no time in `{line}`"));
    assert!((6_000..6_100).contains(&at), "{line}");
}

/// A task hangs (`stall`): on the image as on the host, WdgM's alive supervision fails at
/// the same main function, the LEDs go dark, and the watchdog (QEMU's CMSDK model on the
/// image, the host board's model) resets the ECU 50 ms after the last trigger; the frames
/// and LED levels up to the reset are the same.
#[test]
fn a_stalled_task_is_caught_by_the_watchdog_on_the_image_as_on_the_host() {
    let image = image().unwrap_or_else(|e| panic!("{e}"));
    let path = root().join("scenarios").join("stall.txt");
    let run = run_image(&image, Some(&path), 1, &out("stall")).unwrap_or_else(|e| panic!("{e}"));
    // The reset ends QEMU (`-no-reboot`) with status 0, before any end-of-run report.
    assert!(
        run.success,
        "the image did not end by a reset:\n{}",
        run.report
    );
    let line = |prefix: &str| {
        run.report
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in:\n{}", run.report))
            .to_string()
    };
    let wdgm = line("cw-qemu: WdgM: ");
    let watchdog = line("watchdog: ");
    // With the failure, what the kernel refused until then: the hung task's alarm came
    // again while it still ran, an activation refused with E_OS_LIMIT (service 0,
    // ActivateTask; status 4).
    let kernel = line("cw-qemu: kernel errors ");
    let errors: u32 = kernel
        .strip_prefix("cw-qemu: kernel errors ")
        .and_then(|rest| rest.split(',').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count in `{kernel}`"));
    assert!(errors >= 1, "{kernel}");
    assert!(
        kernel.ends_with(", ISR entries refused 0; the last error: service 0, status 4"),
        "{kernel}"
    );
    assert!(
        !run.report.contains("cw-qemu: end at"),
        "the run ended by the reset"
    );
    // The host's figures.
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let scenario = cw_firmware::host::Scenario::parse(&text).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = cw_firmware::host::Simulation::new(scenario, 1).unwrap_or_else(|e| panic!("{e}"));
    sim.run();
    let failure = sim
        .ecu()
        .supervision()
        .and_then(|(_, f)| f)
        .unwrap_or_else(|| panic!("the host's supervision did not fail"));
    let failed_ms = u64::from(failure.main_function) * 10;
    let last_ms = sim.watchdog().last_trigger_us().unwrap_or(0) / 1000;
    let reset_ms = sim.reset_at_us().unwrap_or(0) / 1000;
    assert_eq!((failed_ms, last_ms, reset_ms), (2040, 2030, 2080));
    assert_eq!(
        wdgm,
        format!(
            "cw-qemu: WdgM: the alive supervision of {} failed at {failed_ms} ms (0 of 1 alive indications): LEDs dark, the watchdog no longer triggered",
            failure.name
        )
    );
    // The model's first expiry (its NMI) comes half-way: the reset follows at the second.
    assert_eq!(
        watchdog,
        format!(
            "watchdog: not triggered since {last_ms} ms; expired at {} ms (NMI), its reset follows",
            last_ms + 25
        )
    );
    let image_trace = run.trace().unwrap_or_else(|e| panic!("{e}"));
    let host = simulate(&path, 1).unwrap_or_else(|e| panic!("{e}"));
    let a = compare(&image_trace, &host).unwrap_or_else(|e| panic!("stall.txt: {e}"));
    println!(
        "stall.txt: WdgM failed at {failed_ms} ms, last trigger {last_ms} ms, reset at {reset_ms} ms on both; {} frames, {} red and {} yellow LED levels the same",
        a.frames, a.red, a.yellow
    );
}

/// A scenario the image cannot read or play: the run fails, the LEDs stay dark, and the
/// report names the file, the line and the fault.
fn refused(name: &str, text: Option<&str>, reason: &str) {
    let image = image().unwrap_or_else(|e| panic!("{e}"));
    let dir = out(name.trim_end_matches(".txt"));
    let path = dir.join(name);
    if let Some(text) = text {
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    }
    let run = run_image(&image, Some(&path), 1, &dir).unwrap_or_else(|e| panic!("{e}"));
    assert!(!run.success, "the image accepted {name}:\n{}", run.report);
    let want = format!("FATAL: scenario {}: {reason}", path.display());
    assert!(
        run.report.lines().any(|l| l == want),
        "expected `{want}` in:\n{}",
        run.report
    );
    assert!(run.slcan.is_empty(), "no frame before the scenario is read");
}

#[test]
fn a_malformed_scenario_is_refused_with_its_line() {
    refused(
        "teleport.txt",
        Some("hold 500 1000\nteleport 3\n"),
        "line 2: unknown command `teleport`",
    );
}

/// Sensor noise and random dropouts: the image draws them from the host simulation's own
/// sensor model, with the same generator and seed, so it measures what the host does.
#[test]
fn noisy_and_unreliable_sensors_are_the_same_ecu_on_the_image() {
    same_ecu("approach.txt");
    same_ecu("unreliable.txt");
}

/// The seed on the image's command line reaches its sensor model: another seed gives the
/// host other frames, and the image the same ones as the host.
#[test]
fn the_sensor_seed_reaches_the_image() {
    let path = root().join("scenarios").join("unreliable.txt");
    let frames = |seed| {
        simulate(&path, seed)
            .unwrap_or_else(|e| panic!("{e}"))
            .frames
            .into_iter()
            .map(|(_, frame)| frame)
            .collect::<Vec<_>>()
    };
    assert_ne!(
        frames(1),
        frames(7),
        "seeds 1 and 7 give the host the same frames"
    );
    same_ecu_seeded("unreliable.txt", 7);
}

#[test]
fn a_missing_or_oversized_scenario_file_is_refused() {
    refused("missing.txt", None, "the host cannot open it");
    let long = "# padding\n".repeat(200) + "hold 500 1000\n";
    let reason = format!("{} bytes is more than the image reads", long.len());
    refused("long.txt", Some(&long), &reason);
}
