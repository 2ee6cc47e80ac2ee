//! The FlexCAN node on the virtual bus against the behavioural controller: the same
//! frames at the same times, bus-off and its recovery, a stop during a frame.

use std::boxed::Box;
use std::vec;
use std::vec::Vec;

use super::super::tests::{frame, id, worst_case_bus, FRAME8_US, SLOT8_US};
use super::*;
use crate::chip::flexcan::driver::INIT_POLLS;
use crate::chip::flexcan::{ClockSource, RxFilter};
use crate::host::{HostCanConfig, VirtualClock};
use cw_core::can::{CanId, Hrh};

const FILTERS: [RxFilter; 2] = [
    RxFilter::exact(CanId::masked(0x7DF, false), Hrh(1)),
    RxFilter::any(Hrh(0), false),
];

const CONFIG: FlexcanConfig<'static> = FlexcanConfig {
    clock_source: ClockSource::PeripheralClock,
    clock_hz: 80_000_000,
    mailboxes: 32,
    rx: &FILTERS,
    tx: &[1, 1],
    init_polls: INIT_POLLS,
};

const BITRATE: ControllerConfig = ControllerConfig {
    bitrate: 500_000,
    sample_permille: 875,
};

fn flexcan(bus: &VirtualBus) -> HostFlexcan {
    let mut can = bus.attach_flexcan(&CONFIG).unwrap();
    can.init(&BITRATE).unwrap();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    can
}

/// Runs the bus from event to event up to `until_us`, taking the controller's events
/// at each (as the host simulation's interrupt does).
fn run(
    clock: &VirtualClock,
    bus: &VirtualBus,
    can: &mut HostFlexcan,
    until_us: u64,
) -> Vec<(u64, FlexcanEvent)> {
    let mut events = Vec::new();
    let mut take = |can: &mut HostFlexcan, at| {
        while let Some(e) = can.take_event() {
            events.push((at, e));
        }
    };
    while let Some(t) = bus.next_event_us().filter(|&t| t <= until_us) {
        clock.advance_to_us(t).unwrap();
        bus.run_until(t);
        take(can, t);
    }
    clock.advance_to_us(until_us).unwrap();
    bus.run_until(until_us);
    take(can, until_us);
    events
}

/// `Can_Write` on one controller or the other.
type Writer = dyn FnMut(u16, &CanFrame);

#[test]
fn frames_cross_the_bus_at_the_same_times_as_with_the_behavioural_controller() {
    let traces: Vec<Vec<(u64, u32)>> = [false, true]
        .into_iter()
        .map(|use_flexcan| {
            let clock = VirtualClock::new();
            let bus = worst_case_bus(&clock);
            bus.set_tracing(true);
            let mut tester = bus.attach_tester();
            let mut write: Box<Writer> = if use_flexcan {
                let mut can = flexcan(&bus);
                Box::new(move |pdu, f| {
                    while can.take_event().is_some() {}
                    can.write(Hth(0), pdu, f).unwrap();
                })
            } else {
                let mut can = bus.attach(&HostCanConfig::new(&[]).with_hths(2));
                can.set_controller_mode(ControllerMode::Started).unwrap();
                Box::new(move |pdu, f| can.write(Hth(0), pdu, f).unwrap())
            };
            tester.send(&frame(id(0x050), &[1; 8]));
            write(1, &frame(id(0x100), &[2; 8]));
            clock.advance_us(1_000);
            bus.run_until_now();
            write(2, &frame(id(0x010), &[3; 8]));
            tester.send(&frame(id(0x020), &[4; 8]));
            bus.run_until(clock.now_us() + 1_000);
            bus.take_trace()
                .iter()
                .map(|r| (r.time_us, r.frame.can_id().raw()))
                .collect()
        })
        .collect();
    assert_eq!(
        traces[1],
        [
            (FRAME8_US, 0x050),
            (SLOT8_US + FRAME8_US, 0x100),
            (1_000 + FRAME8_US, 0x010),
            (1_000 + SLOT8_US + FRAME8_US, 0x020),
        ]
    );
    assert_eq!(traces[0], traces[1]);
}

#[test]
fn a_frame_is_confirmed_and_others_frames_received_through_the_filters() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut can = flexcan(&bus);
    can.write(Hth(1), 9, &frame(id(0x100), &[1, 2, 3])).unwrap();
    tester.send(&frame(id(0x7DF), &[0xAA; 8]));
    tester.send(&frame(id(0x123), &[]));
    let events = run(&clock, &bus, &mut can, 5_000);
    let us = |f: &CanFrame| bus.frame_duration_ns(f) / 1_000;
    let (sent, diag, other) = (
        frame(id(0x100), &[1, 2, 3]),
        frame(id(0x7DF), &[0xAA; 8]),
        frame(id(0x123), &[]),
    );
    // Lowest id first: the ECU's, then the tester's in the order sent; 6 us of
    // intermission between frames.
    let t1 = us(&sent);
    let t2 = t1 + 6 + us(&diag);
    let t3 = t2 + 6 + us(&other);
    assert_eq!(
        events,
        [
            (t1, FlexcanEvent::TxConfirmation(9)),
            (t2, FlexcanEvent::Received(Hrh(1), diag)),
            (t3, FlexcanEvent::Received(Hrh(0), other)),
        ]
    );
    assert_eq!(tester.take_received().len(), 1, "the ECU's frame");
    assert_eq!(can.model().stats().ignored_writes, 0);
}

#[test]
fn bus_off_stops_the_module_and_cansms_start_recovers_it_after_128_times_11_bits() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut can = flexcan(&bus);
    can.inject_tx_errors(32);
    can.write(Hth(0), 1, &frame(id(0x100), &[0; 8])).unwrap();
    let events = run(&clock, &bus, &mut can, 50_000);
    assert_eq!(
        events.iter().map(|e| e.1).collect::<Vec<_>>(),
        [FlexcanEvent::BusOff]
    );
    assert!(can.model().is_bus_off());
    assert_eq!(can.driver().mode(), ControllerMode::Stopped);
    assert!(tester.take_received().is_empty());
    // Stopped and still bus-off: nothing moves however long the bus is idle.
    let _ = run(&clock, &bus, &mut can, 100_000);
    assert!(can.model().is_bus_off());
    // CanSM's start: a frame written at once waits for the recovery.
    let restart_us = clock.now_us();
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    can.write(Hth(0), 4, &frame(id(0x100), &[0; 8])).unwrap();
    let recovery_us = 128 * 11 * 2;
    let events = run(&clock, &bus, &mut can, restart_us + recovery_us - 1);
    assert!(
        events.is_empty() && can.model().is_bus_off(),
        "still recovering"
    );
    let events = run(&clock, &bus, &mut can, restart_us + 10_000);
    assert!(!can.model().is_bus_off());
    assert_eq!(
        events,
        [(
            restart_us + recovery_us + FRAME8_US,
            FlexcanEvent::TxConfirmation(4)
        )]
    );
    assert_eq!(
        can.driver().stats().tx_discarded,
        1,
        "the first frame, withdrawn"
    );
}

#[test]
fn a_stop_during_a_frame_is_indicated_at_its_end() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut can = flexcan(&bus);
    tester.send(&frame(id(0x7DF), &[1; 8]));
    clock.advance_us(100);
    assert_eq!(
        can.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert!(!can.has_events());
    assert_eq!(can.write(Hth(0), 1, &frame(id(0x100), &[])), Err(CanBusy));
    let events = run(&clock, &bus, &mut can, 1_000);
    assert_eq!(
        events,
        vec![
            (
                FRAME8_US,
                FlexcanEvent::ModeIndication(ControllerMode::Stopped)
            ),
            (
                FRAME8_US,
                FlexcanEvent::Received(Hrh(1), frame(id(0x7DF), &[1; 8]))
            ),
        ]
    );
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        can.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached),
        "an idle bus: stopped at once"
    );
}

#[test]
fn can_init_is_refused_at_a_bitrate_the_bus_does_not_run() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut can = bus.attach_flexcan(&CONFIG).unwrap();
    let wrong = ControllerConfig {
        bitrate: 250_000,
        sample_permille: 875,
    };
    assert_eq!(can.init(&wrong), Err(InitRefused { bitrate: 250_000 }));
    assert_eq!(can.init(&BITRATE), Ok(()));
}
