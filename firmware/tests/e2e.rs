//! End to end on the host board: scenario in, LEDs, trace and CAN frames out, through
//! every layer (sensor, UltraSonic, RTE, ObstacleDetection, LEDActuator, CanTranslate, Com,
//! PduR, CanIf, the CAN controller and the bus), scheduled by the OSEK kernel.

use cw_core::warning::{Measurement, WarningLevel};
use cw_firmware::config;
use cw_firmware::host::{Scenario, Simulation, TraceRow};

fn run(text: &str) -> Simulation {
    let scenario = Scenario::parse(text).expect("test scenario parses");
    let mut sim = Simulation::new(scenario, 1).expect("ECU configuration is consistent");
    sim.run();
    sim
}

/// Rows of the second half of `[start_ms, end_ms)`: the settled state.
fn settled(trace: &[TraceRow], start_ms: u64, end_ms: u64) -> Vec<TraceRow> {
    let mid = start_ms + (end_ms - start_ms) / 2;
    trace
        .iter()
        .filter(|r| r.time_ms >= mid && r.time_ms < end_ms)
        .copied()
        .collect()
}

fn leds(level: WarningLevel) -> (bool, bool) {
    (level == WarningLevel::Red, level == WarningLevel::Yellow)
}

#[test]
fn figure7_red_only_yellow_only_and_off() {
    let sim = run("hold 500 2000\nhold 1000 2000\nhold 1500 2000\nhold 2000 2000\nhold 2500 2000");
    let expected = [
        (true, false),
        (false, true),
        (false, true),
        (false, false),
        (false, false),
    ];
    for (i, want) in expected.into_iter().enumerate() {
        let start = 2000 * i as u64;
        let rows = settled(sim.trace(), start, start + 2000);
        assert!(!rows.is_empty());
        for r in rows {
            assert_eq!(
                (r.red, r.yellow),
                want,
                "at {} mm, t = {} ms",
                r.true_distance_mm,
                r.time_ms
            );
        }
    }
}

#[test]
fn exact_thresholds_through_the_whole_stack() {
    let sim = run(&std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/boundaries.txt"
    ))
    .expect("scenario file"));
    let want = [
        (999, WarningLevel::Red),
        (1000, WarningLevel::Yellow),
        (1999, WarningLevel::Yellow),
        (2000, WarningLevel::Off),
    ];
    for (i, (mm, level)) in want.into_iter().enumerate() {
        let start = 1000 * i as u64;
        for r in settled(sim.trace(), start, start + 1000) {
            assert_eq!(r.measured, Measurement::Distance { distance_mm: mm });
            assert_eq!(r.level, level, "{mm} mm");
            assert_eq!((r.red, r.yellow), leds(level), "{mm} mm");
        }
    }
}

#[test]
fn leds_follow_the_decision_within_one_led_task_period() {
    let sim = run("hold 2500 500\nramp 2500 300 4000\nramp 300 2500 4000");
    let rows = sim.trace();
    for pair in rows.windows(2) {
        let decided = pair[0].level;
        if decided == WarningLevel::Fault {
            continue;
        }
        assert_eq!(
            (pair[1].red, pair[1].yellow),
            leds(decided),
            "10 ms after t = {} ms",
            pair[0].time_ms
        );
    }
}

#[test]
fn periodic_tasks_run_exactly_on_their_periods_and_every_sample_leaves_as_a_frame() {
    let sim = run("ramp 300 3000 5000");
    let starts = sim.task_starts();
    for (task, period_ms) in [
        (config::os::OS_LED_TASK, 10),
        (config::os::OS_BSW_SERVICE_TASK, 10),
        (config::os::OS_OBSTACLE_DETECTION_TASK, 20),
        (config::os::OS_SONAR_TASK, 40),
    ] {
        let times: Vec<u64> = starts
            .iter()
            .filter(|(t, _)| *t == task)
            .map(|(_, us)| *us)
            .collect();
        assert!(times.len() > 100 / period_ms as usize);
        assert_eq!(times[0], period_ms * 1000, "{task:?} first activation");
        for w in times.windows(2) {
            assert_eq!(w[1] - w[0], period_ms * 1000, "{task:?} period");
        }
    }
    // CanTranslate runs right after every sonar sample: UltraSonic's measurement took the
    // trigger pulse (the echo is timed by the capture hardware), then its write activated
    // OsComTask, which preempted it at once.
    let sonar: Vec<u64> = starts
        .iter()
        .filter(|(t, _)| *t == config::os::OS_SONAR_TASK)
        .map(|(_, us)| *us)
        .collect();
    let com: Vec<u64> = starts
        .iter()
        .filter(|(t, _)| *t == config::os::OS_COM_TASK)
        .map(|(_, us)| *us)
        .collect();
    let sample_done: Vec<u64> = sonar
        .iter()
        .map(|t| t + u64::from(cw_firmware::iohwab::TRIGGER_PULSE_US))
        .collect();
    assert_eq!(com, sample_done);
    // And its frame completes on the bus within a millisecond, every time.
    let frames: Vec<u64> = sim
        .frames()
        .iter()
        .filter(|f| f.frame.can_id() == config::canif::DISTANCE_FRAME_ID)
        .map(|f| f.time_us)
        .collect();
    let sent_by_end: Vec<u64> = sonar
        .iter()
        .copied()
        .filter(|t| *t + 1000 <= 5000 * 1000)
        .collect();
    assert_eq!(frames.len(), sent_by_end.len());
    for (frame_us, sample_us) in frames.iter().zip(&sent_by_end) {
        assert!(
            *frame_us > *sample_us && *frame_us - *sample_us < 1000,
            "frame {frame_us} after sample {sample_us}"
        );
    }
}

#[test]
fn sensor_dropout_gives_fault_blinking_and_the_invalidation_value_then_recovers() {
    let sim = run("hold 1500 6000\ndropout 1000 2000");
    let rows = sim.trace();
    let during = settled(rows, 1000, 3000);
    assert!(during.iter().all(|r| r.level == WarningLevel::Fault));
    assert!(
        during.iter().any(|r| r.red && r.yellow) && during.iter().any(|r| !r.red && !r.yellow),
        "blinking"
    );
    let invalid_frames = sim
        .frames()
        .iter()
        .filter(|f| f.time_us > 1_200_000 && f.time_us < 3_000_000)
        .filter(|f| f.frame.bytes()[..4] == [0xFF; 4])
        .count();
    assert!(
        invalid_frames > 20,
        "the distance carries the invalidation value ({invalid_frames} frames)"
    );
    for r in settled(rows, 3000, 6000) {
        assert_eq!(
            (r.level, r.red, r.yellow),
            (WarningLevel::Yellow, false, true),
            "recovered at {} ms",
            r.time_ms
        );
    }
}

#[test]
fn bus_off_is_recovered_by_cansm_and_frames_flow_again() {
    let mut sim = run("hold 1500 3000\ncan-errors 1000 40");
    assert_eq!(sim.ecu().cansm().bus_off_total(), 1);
    let after: Vec<_> = sim
        .frames()
        .iter()
        .filter(|f| f.time_us > 1_100_000)
        .collect();
    assert!(after.len() > 40, "frames after recovery: {}", after.len());
    assert_eq!(sim.ecu().stats().os_errors, 0);
}

#[test]
fn malformed_frames_are_dropped_and_counted_and_disturb_nothing() {
    let mut sim = run("hold 800 3000\nframe 1000 200#E803\nframe 1100 7FF#0102030405060708\nframe 2000 200#F401E803");
    assert_eq!(
        sim.ecu().stats().rx_dropped,
        2,
        "short frame and unknown id"
    );
    assert_eq!(sim.ecu().canif().stats().rx_wrong_dlc, 1);
    assert_eq!(sim.ecu().canif().stats().rx_unknown_id, 1);
    // Before the valid threshold frame: red; after (red < 500, yellow < 1000): yellow.
    assert!(settled(sim.trace(), 1000, 2000)
        .iter()
        .all(|r| r.level == WarningLevel::Red));
    assert!(settled(sim.trace(), 2000, 3000)
        .iter()
        .all(|r| r.level == WarningLevel::Yellow));
    assert_eq!(sim.ecu().stats().frames_refused, 0);
}

#[test]
fn thresholds_the_pc_sends_are_refused_when_invalid() {
    let mut sim = run("hold 800 2000\nframe 500 200#D007E803");
    assert_eq!(
        sim.ecu().thresholds(),
        cw_core::warning::Thresholds::PAPER,
        "2000 < 1000 is refused"
    );
}

#[test]
fn io_stack_inits_ports_once_and_triggers_the_sensor_before_every_echo() {
    let mut sim = run("hold 1500 2000");
    assert_eq!(sim.port_inits(), 1, "Port_Init runs once, in start-up one");
    // Every OsSonarTask drives one trigger pulse of at least 10 us (rising then falling
    // edge), and the capture never ran without one.
    let sonar_runs = sim
        .task_starts()
        .iter()
        .filter(|(t, _)| *t == config::os::OS_SONAR_TASK)
        .count();
    let edges = sim.sonar_trigger().history();
    assert_eq!(edges.len(), 2 * sonar_runs);
    for pulse in edges.chunks(2) {
        let [(rise, true), (fall, false)] = pulse else {
            panic!("trigger edges out of order: {pulse:?}");
        };
        assert!(fall - rise >= 10, "trigger pulse {} us", fall - rise);
    }
    assert_eq!(sim.untriggered_captures(), 0);
    assert_eq!(sim.ecu().stats().pin_faults, 0);
}

#[test]
fn an_echo_line_stuck_high_is_a_sensor_fault_and_recovers_when_released() {
    let scenario = Scenario::parse("hold 1500 4000").expect("test scenario parses");
    let mut sim = Simulation::new(scenario, 1).expect("ECU configuration is consistent");
    sim.run_until_ms(1000);
    assert_eq!(sim.ecu().level(), WarningLevel::Yellow);
    let triggers_before = sim.sonar_trigger().change_count();
    sim.sonar_echo_line().set_level(true);
    sim.run_until_ms(2000);
    assert_eq!(sim.ecu().level(), WarningLevel::Fault);
    assert_eq!(sim.ecu().measurement(), Measurement::Invalid);
    // The sensor is not triggered while its echo line is stuck.
    assert_eq!(sim.sonar_trigger().change_count(), triggers_before);
    sim.sonar_echo_line().set_level(false);
    sim.run_until_ms(2200);
    assert_eq!(sim.ecu().level(), WarningLevel::Yellow);
    assert_eq!(sim.ecu().stats().os_errors, 0);
}

#[test]
fn no_communication_silences_the_bus_but_not_the_leds_then_frames_resume() {
    let mut sim = run("hold 500 3000\nno-communication 1000 1000");
    let distance_frames = |from_us: u64, to_us: u64| {
        sim.frames()
            .iter()
            .filter(|f| f.frame.can_id() == config::canif::DISTANCE_FRAME_ID)
            .filter(|f| f.time_us >= from_us && f.time_us < to_us)
            .count()
    };
    // The request is carried out by the next BSW main function (within 10 ms) and the last
    // frame already in the controller may still complete (within 1 ms after that).
    assert_eq!(distance_frames(1_011_000, 2_000_000), 0, "silent");
    assert!(distance_frames(2_050_000, 3_000_000) >= 20, "frames again");
    // Com kept writing; CanIf refused what it could not send, and counted it.
    assert!(sim.ecu().stats().frames_refused >= 24);
    for r in settled(sim.trace(), 1000, 2000) {
        assert_eq!((r.level, r.red, r.yellow), (WarningLevel::Red, true, false));
    }
    assert_eq!(sim.ecu().stats().os_errors, 0);
}

/// The no-communication request reaches the controller while the PC's frame is on the
/// wire: the controller finishes that frame (and receives it) before it stops, and says so
/// with a mode indication; CanSM reaches no communication then, and full communication
/// again when the window ends. Without a frame on the wire, the stop is immediate.
#[test]
fn a_stop_during_a_frame_on_the_wire_completes_at_its_end_and_is_indicated() {
    let text = "hold 500 3000\nno-communication 1000 1000";
    let mut sim = run(&format!("{text}\nframe 1000 7FF#0102030405060708"));
    assert_eq!(sim.ecu().stats().mode_indications, 1);
    assert_eq!(
        sim.ecu().stats().rx_dropped,
        1,
        "received, then dropped by id"
    );
    assert_eq!(
        sim.ecu().cansm().current_mode(),
        cw_core::cansm::ComMode::Full
    );
    assert_eq!(sim.ecu().cansm().mode_request_timeouts(), 0);
    let silent = |sim: &Simulation| {
        sim.frames()
            .iter()
            .filter(|f| f.frame.can_id() == config::canif::DISTANCE_FRAME_ID)
            .all(|f| f.time_us < 1_011_000 || f.time_us >= 2_000_000)
    };
    assert!(silent(&sim));
    let mut at_once = run(text);
    assert_eq!(at_once.ecu().stats().mode_indications, 0);
    assert!(silent(&at_once));
}

#[test]
fn ignition_off_goes_through_post_run_to_shutdown_with_leds_dark_and_bus_silent() {
    let mut sim = run("hold 500 3000\nshutdown 1000");
    assert!(sim.ecu().is_off());
    assert_eq!(sim.ecu().ecum().state(), cw_core::ecum::EcuMState::Shutdown);
    assert_eq!(
        sim.ecu().cansm().current_mode(),
        cw_core::cansm::ComMode::No
    );
    let last_frame = sim
        .frames()
        .iter()
        .map(|f| f.time_us)
        .max()
        .expect("frames before the shutdown");
    assert!(last_frame < 1_011_000, "last frame at {last_frame} us");
    for r in sim.trace().iter().filter(|r| r.time_ms >= 1010) {
        assert!(!r.red && !r.yellow, "LEDs dark at {} ms", r.time_ms);
    }
    // Nothing runs any more: no task started after the shutdown.
    let last_start = sim.task_starts().iter().map(|(_, us)| *us).max();
    assert!(last_start.is_some_and(|t| t < 1_011_000));
    assert_eq!(sim.ecu().stats().os_errors, 0);
    assert_eq!(sim.mode_requests_refused(), 0);
}

#[test]
fn an_isr_the_kernel_refuses_has_its_line_quieted_not_left_pending() {
    let mut sim = run("hold 500 2000\nshutdown 1000");
    assert!(sim.ecu().is_off());
    assert!(sim.ecu().port().refused_isrs().is_empty());
    // The CAN controller's interrupt arrives after ShutdownOS: the kernel refuses its
    // entry, so its body (which would clear the source) does not run; the port quiets the
    // line instead of returning to take it again.
    sim.ecu().can_isr();
    assert_eq!(*sim.ecu().port().refused_isrs(), [config::os::CAN_ISR]);
}

#[test]
fn communication_is_not_restarted_during_post_run() {
    // Ignition off at 1001 ms, and communication enabled again at 1005 ms (the end of a
    // no-communication window): ModeManager sees both edges at 1010 ms and asks for
    // post-run first, so BswM refuses the communication restart and counts it, and the
    // ECU shuts down silent.
    let mut sim = run("hold 500 2000\nno-communication 900 105\nshutdown 1001");
    assert!(sim.ecu().is_off());
    assert_eq!(sim.ecu().stats().mode_requests_refused, 1);
    assert_eq!(
        sim.ecu().cansm().current_mode(),
        cw_core::cansm::ComMode::No
    );
    assert!(sim.frames().iter().all(|f| f.time_us < 911_000));
}

#[test]
fn a_live_run_taking_frames_and_forgetting_its_records_sees_the_same_bus() {
    let text = "hold 800 1500\nhold 1800 1500";
    let whole = run(text);
    let scenario = Scenario::parse(text).expect("test scenario parses");
    let mut live = Simulation::new(scenario, 1).expect("ECU configuration is consistent");
    let mut frames = Vec::new();
    while live.now_ms() < 3000 {
        let next = live.now_ms() + 10;
        live.run_until_ms(next);
        frames.extend(live.take_frames());
        live.forget_history();
        assert!(live.trace().is_empty() && live.task_starts().is_empty());
        assert_eq!(live.red_led().change_count(), 0);
        assert!(live.sonar_trigger().change_count() <= 2);
    }
    assert_eq!(frames, whole.frames(), "the same frames at the same times");
    assert_eq!(live.red_led().is_high_now(), whole.red_led().is_high_now());
    assert_eq!(
        live.yellow_led().level_at(0),
        live.yellow_led().is_high_now()
    );
}

#[test]
fn thresholds_the_pc_sends_live_are_taken_by_the_ecu() {
    let scenario = Scenario::parse("hold 800 2000").expect("test scenario parses");
    let mut sim = Simulation::new(scenario, 1).expect("ECU configuration is consistent");
    sim.run_until_ms(500);
    assert_eq!(sim.ecu().level(), WarningLevel::Red);
    // RedBelow 500 mm, YellowBelow 1000 mm: 800 mm is yellow now.
    let frame = cw_core::can::CanFrame::from_parts(
        cw_core::can::CanId::standard(0x200).expect("0x200 is a standard id"),
        &[0xF4, 0x01, 0xE8, 0x03],
    )
    .expect("4 bytes fit");
    sim.send_from_pc(&frame);
    sim.run_until_ms(1000);
    assert_eq!(
        sim.ecu().thresholds(),
        cw_core::warning::Thresholds::new(500, 1000).expect("valid")
    );
    assert_eq!(sim.ecu().level(), WarningLevel::Yellow);
    assert!(
        sim.frames().iter().any(|r| r.frame == frame),
        "the PC's frame is on the bus"
    );
}

#[test]
fn the_supervised_tasks_are_named_as_in_the_os_configuration() {
    for (task, alive) in config::SUPERVISED.iter().zip(&config::ALIVE) {
        assert_eq!(config::OS.tasks()[usize::from(task.0)].name, alive.name);
        assert_eq!(
            u32::from(alive.reference_cycle) * config::BSW_PERIOD_MS,
            config::PERIOD_MS[usize::from(task.0)]
        );
    }
}

#[test]
fn a_healthy_run_keeps_every_supervision_and_the_watchdog_triggered() {
    let mut sim = run("hold 500 3000");
    assert!(
        !sim.ecu().com_stack().can_init_refused,
        "Can_Init at 500 kbit/s, the bus's"
    );
    assert_eq!(sim.reset_at_us(), None);
    assert_eq!(
        sim.ecu().supervision(),
        Some((cw_core::wdgm::Status::Ok, None))
    );
    // Ecu::init's first trigger, then one per OsBswServiceTask job.
    assert_eq!(sim.watchdog().triggers(), 1 + 3000 / 10);
}

#[test]
fn a_stalled_task_fails_its_supervision_goes_dark_and_the_watchdog_resets_the_ecu() {
    let mut sim = run("hold 500 3000\nstall OsSonarTask 1000");
    // The sonar job at 1000 ms hangs; its reference cycle (4 main functions) that ends at
    // 1040 ms holds none of the one alive indication expected.
    let (status, failure) = sim.ecu().supervision().expect("no job under way");
    assert_eq!(status, cw_core::wdgm::Status::Stopped);
    let failure = failure.expect("a failure");
    assert_eq!(
        (failure.name, failure.counted, failure.expected),
        ("OsSonarTask", 0, 1)
    );
    assert_eq!(u64::from(failure.main_function) * 10, 1040);
    // The last trigger was the main function before (1030 ms); the reset 50 ms later.
    assert_eq!(sim.watchdog().last_trigger_us(), Some(1_030_000));
    assert_eq!(sim.reset_at_us(), Some(1_080_000));
    assert!(sim.now_ms() <= 1081, "the run ended at the reset");
    // Red before the stall (0.5 m), dark from the failure on.
    let lit = |t: u64| {
        sim.trace()
            .iter()
            .find(|r| r.time_ms == t)
            .map(|r| (r.red, r.yellow))
    };
    assert_eq!(lit(1000), Some((true, false)));
    for t in (1050..=1070).step_by(10) {
        assert_eq!(lit(t), Some((false, false)), "dark at {t} ms");
    }
    // The hung job was still running when its alarm fired again (E_OS_LIMIT at 1040).
    assert_eq!(sim.ecu().stats().os_errors, 1);
}

#[test]
fn a_stall_above_the_main_function_stops_the_trigger_itself() {
    // OsLEDTask (priority 6) hangs at 1000 ms: OsBswServiceTask (5), which runs WdgM's main
    // function, never runs again, so nothing judges or triggers: the watchdog resets 50 ms
    // after the last trigger (990 ms).
    let mut sim = run("hold 500 3000\nstall OsLEDTask 1000");
    assert_eq!(sim.watchdog().last_trigger_us(), Some(990_000));
    assert_eq!(sim.reset_at_us(), Some(1_040_000));
    assert_eq!(sim.ecu().supervision().map(|s| s.1), Some(None));
}

#[test]
fn after_shutdown_the_watchdog_is_off_and_resets_nothing() {
    let mut sim = run("hold 500 3000\nshutdown 1000");
    assert!(sim.ecu().is_off());
    assert_eq!(sim.reset_at_us(), None);
    assert_eq!(sim.now_ms(), 3000);
}

#[test]
fn a_stall_of_no_task_is_refused_naming_it() {
    let scenario = Scenario::parse("hold 500 3000\nstall OsNoSuchTask 1000").expect("parses");
    match Simulation::new(scenario, 1) {
        Ok(_) => panic!("a stall of an unknown task was accepted"),
        Err(e) => assert_eq!(
            e.to_string(),
            "scenario: `stall OsNoSuchTask`: no task of that name"
        ),
    }
}
