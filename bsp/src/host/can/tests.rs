use super::*;
use std::vec;

pub(super) fn id(raw: u16) -> CanId {
    CanId::standard(raw).unwrap_or_else(|| panic!("bad id {raw:#x}"))
}

fn ext(raw: u32) -> CanId {
    CanId::extended(raw).unwrap_or_else(|| panic!("bad id {raw:#x}"))
}

pub(super) fn frame(id: CanId, data: &[u8]) -> CanFrame {
    CanFrame::from_parts(id, data).unwrap_or_else(|| panic!("bad test frame"))
}

/// A 500 kbit/s bus with worst-case stuffing, so frame times are easy to state:
/// a standard 8-byte frame is 132 bits (264 us), plus 3 bits (6 us) of intermission.
pub(super) fn worst_case_bus(clock: &VirtualClock) -> VirtualBus {
    let config = BusConfig {
        bitrate_bps: 500_000,
        stuffing: Stuffing::WorstCase,
    };
    VirtualBus::with_config(clock, config).unwrap_or_else(|e| panic!("{e}"))
}

pub(super) const FRAME8_US: u64 = 264;
pub(super) const SLOT8_US: u64 = 270;
/// A failed standard 8-byte attempt: 98 + 24 + 2 + 14 = 138 bits, plus intermission.
const FAILED8_SLOT_US: u64 = (138 + 3) * 2;

fn started(bus: &VirtualBus, config: &HostCanConfig) -> HostCan {
    let mut can = bus.attach(config);
    assert_eq!(
        can.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    can
}

fn confirmed(events: &[TimedCanEvent]) -> Vec<(u64, u16)> {
    events
        .iter()
        .filter_map(|e| match e.event {
            CanEvent::TxConfirmation { pdu } => Some((e.time_us, pdu)),
            _ => None,
        })
        .collect()
}

fn received_ids(records: &[BusRecord]) -> Vec<u32> {
    records.iter().map(|r| r.frame.can_id().raw()).collect()
}

#[test]
fn a_frame_is_confirmed_to_its_sender_and_received_by_the_others() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    let mut peer = started(&bus, &HostCanConfig::new(&[(id(0x100), Hrh(3))]));
    let mut tester = bus.attach_tester();
    let distance = frame(id(0x100), &[0xDC, 0x05, 0, 0, 0, 0, 0, 0]);
    clock.advance_us(1_000);
    assert_eq!(ecu.write(Hth(0), 7, &distance), Ok(()));
    assert_eq!(bus.next_event_us(), Some(1_000 + FRAME8_US));
    bus.run_until(1_000 + FRAME8_US - 1);
    assert!(
        ecu.take_events().is_empty(),
        "the frame is still on the wire"
    );
    bus.run_until(1_000 + FRAME8_US);
    assert_eq!(
        ecu.take_events(),
        [TimedCanEvent {
            time_us: 1_000 + FRAME8_US,
            event: CanEvent::TxConfirmation { pdu: 7 }
        }]
    );
    assert_eq!(
        peer.pop_event(),
        Some(TimedCanEvent {
            time_us: 1_000 + FRAME8_US,
            event: CanEvent::Received {
                hrh: Hrh(3),
                frame: distance
            }
        })
    );
    assert_eq!(peer.pop_event(), None);
    let seen = tester.take_received();
    assert_eq!(seen.len(), 1);
    assert_eq!(seen[0].sender, ecu.node());
    assert_eq!(seen[0].frame, distance);
    assert_eq!(bus.stats().frames, 1);
    assert_eq!(bus.next_event_us(), None);
}

#[test]
fn lowest_id_wins_arbitration_and_losers_follow_back_to_back() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut nodes: Vec<HostCan> = (0..3)
        .map(|_| started(&bus, &HostCanConfig::new(&[])))
        .collect();
    let mut tester = bus.attach_tester();
    for (node, raw) in nodes.iter_mut().zip([0x300, 0x100, 0x200]) {
        assert_eq!(node.write(Hth(0), raw, &frame(id(raw), &[0; 8])), Ok(()));
    }
    bus.run_until(10_000);
    let seen = tester.take_received();
    assert_eq!(received_ids(&seen), [0x100, 0x200, 0x300]);
    let times: Vec<u64> = seen.iter().map(|r| r.time_us).collect();
    assert_eq!(
        times,
        [FRAME8_US, SLOT8_US + FRAME8_US, 2 * SLOT8_US + FRAME8_US]
    );
    assert_eq!(
        confirmed(&nodes[0].take_events()),
        [(2 * SLOT8_US + FRAME8_US, 0x300)]
    );
}

#[test]
fn a_frame_written_during_a_transmission_waits_for_the_bus_even_with_higher_priority() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut low = started(&bus, &HostCanConfig::new(&[]));
    let mut high = started(&bus, &HostCanConfig::new(&[]));
    let mut tester = bus.attach_tester();
    assert_eq!(low.write(Hth(0), 1, &frame(id(0x700), &[0; 8])), Ok(()));
    bus.run_until(100);
    clock.advance_us(100);
    assert_eq!(high.write(Hth(0), 2, &frame(id(0x001), &[0; 8])), Ok(()));
    bus.run_until(10_000);
    assert_eq!(received_ids(&tester.take_received()), [0x700, 0x001]);
    assert_eq!(confirmed(&high.take_events()), [(SLOT8_US + FRAME8_US, 2)]);
}

#[test]
fn arbitration_compares_ids_bit_by_bit_across_formats() {
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut tester = bus.attach_tester();
    let mut senders: Vec<HostCan> = (0..3)
        .map(|_| started(&bus, &HostCanConfig::new(&[])))
        .collect();
    // Base id 0x100 standard beats base id 0x100 extended; an extended id with a lower base
    // (0x0FF) beats both.
    let frames = [
        frame(ext(0x100 << 18), &[1]),
        frame(id(0x100), &[2]),
        frame(ext((0x0FF << 18) | 0x3_FFFF), &[3]),
    ];
    for (s, f) in senders.iter_mut().zip(&frames) {
        assert_eq!(s.write(Hth(0), 0, f), Ok(()));
    }
    bus.run_until(10_000);
    let order: Vec<u8> = tester
        .take_received()
        .iter()
        .map(|r| r.frame.bytes()[0])
        .collect();
    assert_eq!(order, [3, 2, 1]);
}

#[test]
fn a_full_mailbox_is_busy_until_its_frame_is_confirmed() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let _tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_hths(2));
    let f = frame(id(0x123), &[0; 8]);
    assert_eq!(ecu.write(Hth(0), 1, &f), Ok(()));
    assert_eq!(ecu.try_write(Hth(0), 2, &f), Err(WriteError::Busy));
    assert_eq!(ecu.write(Hth(0), 2, &f), Err(CanBusy));
    assert_eq!(ecu.write(Hth(1), 3, &f), Ok(()), "the other HTH is free");
    assert_eq!(ecu.pending_count(), 2);
    bus.run_until(FRAME8_US);
    assert_eq!(confirmed(&ecu.take_events()), [(FRAME8_US, 1)]);
    assert_eq!(
        ecu.write(Hth(0), 2, &f),
        Ok(()),
        "free after the confirmation"
    );
}

#[test]
fn several_mailboxes_per_hth_take_several_frames() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let _tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_mailboxes_per_hth(3));
    for pdu in 0..3 {
        assert_eq!(
            ecu.write(Hth(0), pdu, &frame(id(0x200 - pdu), &[0; 8])),
            Ok(())
        );
    }
    assert_eq!(
        ecu.try_write(Hth(0), 9, &frame(id(1), &[])),
        Err(WriteError::Busy)
    );
    bus.run_until(10_000);
    // The controller offers its lowest id first, whatever the mailbox order.
    let pdus: Vec<u16> = confirmed(&ecu.take_events())
        .iter()
        .map(|&(_, p)| p)
        .collect();
    assert_eq!(pdus, [2, 1, 0]);
    assert_eq!(ecu.stats().tx_confirmed, 3);
}

#[test]
fn writes_to_a_missing_hth_or_a_stopped_controller_are_refused_as_busy() {
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut ecu = bus.attach(&HostCanConfig::new(&[]));
    let f = frame(id(0x100), &[1]);
    assert_eq!(ecu.try_write(Hth(0), 0, &f), Err(WriteError::NotStarted));
    assert_eq!(ecu.write(Hth(0), 0, &f), Err(CanBusy));
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(ecu.try_write(Hth(1), 0, &f), Err(WriteError::UnknownHth));
    assert_eq!(ecu.write(Hth(255), 0, &f), Err(CanBusy));
    let mut none = started(&bus, &HostCanConfig::new(&[]).with_mailboxes_per_hth(0));
    assert_eq!(none.try_write(Hth(0), 0, &f), Err(WriteError::Busy));
    assert_eq!(ecu.pending_count(), 0);
}

#[test]
fn controller_modes_follow_autosar() {
    use ControllerMode::{Sleep, Started, Stopped};
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut can = bus.attach(&HostCanConfig::new(&[]));
    assert_eq!(can.mode(), Stopped);
    // (from, to, accepted)
    let table = [
        (Stopped, Stopped, true),
        (Stopped, Started, true),
        (Started, Started, true),
        (Started, Sleep, false),
        (Started, Stopped, true),
        (Stopped, Sleep, true),
        (Sleep, Sleep, true),
        (Sleep, Started, false),
        (Sleep, Stopped, true),
    ];
    for (from, to, accepted) in table {
        assert_eq!(can.mode(), from);
        let result = can.set_controller_mode(to);
        assert_eq!(result.is_ok(), accepted, "{from:?} -> {to:?}");
        if accepted {
            assert_eq!(can.mode(), to);
        } else {
            assert_eq!(result, Err(ModeRefused));
            assert_eq!(can.mode(), from, "a refused request changes nothing");
        }
    }
}

#[test]
fn stopping_aborts_pending_frames_without_confirmation() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_hths(2));
    let mut other = started(&bus, &HostCanConfig::new(&[]));
    assert_eq!(other.write(Hth(0), 0, &frame(id(0x010), &[0; 8])), Ok(()));
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    assert_eq!(ecu.write(Hth(1), 2, &frame(id(0x101), &[0; 8])), Ok(()));
    clock.advance_us(FRAME8_US / 2); // `other` holds the bus
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert_eq!(ecu.pending_count(), 0);
    assert_eq!(ecu.stats().tx_aborted, 2);
    bus.run_until(10_000);
    let stopped = CanEvent::ModeIndication {
        mode: ControllerMode::Stopped,
    };
    assert_eq!(
        ecu.take_events(),
        [TimedCanEvent {
            time_us: FRAME8_US,
            event: stopped
        }],
        "no confirmation for aborted frames; stopped at the end of the frame on the wire"
    );
    assert_eq!(received_ids(&tester.take_received()), [0x010]);
}

#[test]
fn a_frame_already_on_the_wire_finishes_when_its_sender_stops() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    clock.advance_us(10);
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    bus.run_until(10_000);
    assert_eq!(received_ids(&tester.take_received()), [0x100]);
    assert_eq!(
        ecu.take_events()
            .iter()
            .map(|e| e.event)
            .collect::<Vec<_>>(),
        [CanEvent::ModeIndication {
            mode: ControllerMode::Stopped
        }],
        "no confirmation"
    );
    assert_eq!(ecu.mode(), ControllerMode::Stopped);
}

/// Asked to stop during a frame, the controller finishes that frame (here it receives
/// it), takes nothing to send, refuses to start, and stops at the frame's end; on an idle
/// bus it stops at once.
#[test]
fn a_stop_during_a_frame_completes_at_its_end() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[(id(0x7DF), Hrh(1))]));
    tester.send(&frame(id(0x7DF), &[1; 8]));
    clock.advance_us(100);
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert_eq!(ecu.mode(), ControllerMode::Started, "until the frame ends");
    assert_eq!(
        ecu.try_write(Hth(0), 1, &frame(id(0x100), &[0; 8])),
        Err(WriteError::NotStarted)
    );
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Started),
        Err(ModeRefused)
    );
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending),
        "asked again: still on the way"
    );
    clock.advance_us(FRAME8_US);
    bus.run_until_now();
    let events: Vec<_> = ecu
        .take_events()
        .iter()
        .map(|e| (e.time_us, e.event))
        .collect();
    assert_eq!(
        events,
        [
            (
                FRAME8_US,
                CanEvent::Received {
                    hrh: Hrh(1),
                    frame: frame(id(0x7DF), &[1; 8])
                }
            ),
            (
                FRAME8_US,
                CanEvent::ModeIndication {
                    mode: ControllerMode::Stopped
                }
            ),
        ]
    );
    assert_eq!(ecu.mode(), ControllerMode::Stopped);
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached),
        "an idle bus: stopped at once"
    );
    assert!(ecu.take_events().is_empty());
}

#[test]
fn the_acceptance_filter_discards_unknown_ids_unless_a_catch_all_is_set() {
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut tester = bus.attach_tester();
    let table = [
        (id(0x100), Hrh(0)),
        (id(0x200), Hrh(1)),
        (id(0x100), Hrh(9)),
    ];
    let mut filtered = started(&bus, &HostCanConfig::new(&table));
    let mut open = started(&bus, &HostCanConfig::new(&table).with_catch_all(Hrh(7)));
    // Known id, unknown id, an extended id with a known raw value, a too-short frame.
    tester.send(&frame(id(0x100), &[0xDC, 0x05, 0, 0]));
    tester.send(&frame(id(0x555), &[1, 2, 3]));
    tester.send(&frame(ext(0x100), &[4]));
    tester.send(&frame(id(0x200), &[]));
    assert_eq!(tester.queued(), 4);
    bus.run_until(10_000);
    assert_eq!(tester.queued(), 0);
    let hrhs = |can: &mut HostCan| -> Vec<(u32, Hrh, u8)> {
        can.take_events()
            .iter()
            .filter_map(|e| match e.event {
                CanEvent::Received { hrh, frame } => Some((frame.can_id().raw(), hrh, frame.len())),
                _ => None,
            })
            .collect()
    };
    assert_eq!(
        hrhs(&mut filtered),
        [(0x100, Hrh(0), 4), (0x200, Hrh(1), 0)],
        "the first table entry wins for a repeated id"
    );
    assert_eq!(filtered.stats().rx_filtered, 2);
    assert_eq!(
        hrhs(&mut open),
        [
            (0x100, Hrh(0), 4),
            (0x555, Hrh(7), 3),
            (0x100, Hrh(7), 1),
            (0x200, Hrh(1), 0)
        ]
    );
    assert_eq!(open.stats().rx_accepted, 4);
}

#[test]
fn stopped_and_sleeping_controllers_neither_receive_nor_acknowledge() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    let mut asleep = bus.attach(&HostCanConfig::new(&[]).with_catch_all(Hrh(0)));
    assert_eq!(
        asleep.set_controller_mode(ControllerMode::Sleep),
        Ok(ModeChange::Reached)
    );
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    bus.run_until(200_000);
    // Alone on the bus: every attempt lacks an acknowledgement. TEC climbs to error
    // passive and stays there; the node never goes bus-off and never gets a confirmation.
    assert!(ecu.take_events().is_empty());
    assert!(asleep.take_events().is_empty());
    assert_eq!(ecu.tec(), 128);
    assert!(ecu.is_error_passive());
    assert!(!ecu.is_bus_off());
    assert_eq!(bus.stats().frames, 0);
    assert!(bus.stats().error_frames > 100);
    // A listener arrives: the frame goes out and TEC starts to come down.
    assert_eq!(
        asleep.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        asleep.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    clock.advance_us(200_000);
    bus.run_until(201_000);
    assert_eq!(confirmed(&ecu.take_events()).len(), 1);
    assert_eq!(ecu.tec(), 127);
    assert_eq!(asleep.take_events().len(), 1);
}

#[test]
fn injected_errors_raise_tec_and_the_frame_is_retransmitted() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    assert_eq!(bus.inject_tx_errors(ecu.node(), 3), Ok(()));
    assert_eq!(ecu.write(Hth(0), 5, &frame(id(0x100), &[0; 8])), Ok(()));
    bus.run_until(FAILED8_SLOT_US);
    assert_eq!(ecu.tec(), 8, "one failed attempt");
    bus.run_until(10_000);
    let done_us = 3 * FAILED8_SLOT_US + FRAME8_US;
    assert_eq!(confirmed(&ecu.take_events()), [(done_us, 5)]);
    assert_eq!(ecu.tec(), 23, "3 x 8 up, 1 down");
    assert_eq!(bus.tec(ecu.node()), Some(23));
    assert_eq!(
        tester.take_received().len(),
        1,
        "failed attempts are not received"
    );
    assert_eq!(bus.stats().error_frames, 3);
    assert_eq!(bus.inject_tx_errors(NodeId(99), 1), Err(UnknownNode));
    assert_eq!(bus.tec(NodeId(99)), None);
}

#[test]
fn successful_transmissions_bring_tec_down_by_one_each() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let _tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    ecu.inject_tx_errors(2);
    for pdu in 0..5 {
        assert_eq!(ecu.write(Hth(0), pdu, &frame(id(0x100), &[0; 8])), Ok(()));
        clock.advance_us(5_000);
        bus.run_until_now();
    }
    assert_eq!(ecu.tec(), 16 - 5);
    assert_eq!(confirmed(&ecu.take_events()).len(), 5);
}

#[test]
fn an_error_passive_sender_lets_others_in_between_its_frames() {
    let clock = VirtualClock::new();
    let order = |passive: bool| {
        let bus = worst_case_bus(&clock);
        let mut tester = bus.attach_tester();
        let mut a = started(&bus, &HostCanConfig::new(&[]).with_mailboxes_per_hth(2));
        let mut b = started(&bus, &HostCanConfig::new(&[]));
        if passive {
            // 17 failed attempts of a warm-up frame (TEC 136), then it gets out (135).
            a.inject_tx_errors(17);
            assert_eq!(a.write(Hth(0), 0, &frame(id(0x001), &[])), Ok(()));
            bus.run_until(clock.now_us() + 100_000);
            assert!(a.is_error_passive());
            let _ = tester.take_received();
        }
        let start = clock.advance_us(100_000);
        bus.run_until_now();
        assert_eq!(a.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
        assert_eq!(a.write(Hth(0), 2, &frame(id(0x101), &[0; 8])), Ok(()));
        assert_eq!(b.write(Hth(0), 3, &frame(id(0x200), &[0; 8])), Ok(()));
        bus.run_until(start + 10_000);
        received_ids(&tester.take_received())
    };
    assert_eq!(order(false), [0x100, 0x101, 0x200]);
    assert_eq!(order(true), [0x100, 0x200, 0x101]);
}

#[test]
fn bus_off_stops_the_controller_and_recovery_takes_128_times_11_bits() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_hths(2));
    ecu.inject_tx_errors(32);
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    assert_eq!(ecu.write(Hth(1), 2, &frame(id(0x101), &[0; 8])), Ok(()));
    bus.run_until(50_000);
    let events = ecu.take_events();
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].event, CanEvent::BusOff);
    assert!(ecu.is_bus_off());
    assert_eq!(ecu.tec(), 256);
    assert_eq!(ecu.mode(), ControllerMode::Stopped);
    assert_eq!(ecu.pending_count(), 0, "pending mailboxes are dropped");
    assert_eq!(ecu.stats().tx_aborted, 2);
    assert!(tester.take_received().is_empty());
    assert_eq!(
        ecu.try_write(Hth(0), 3, &frame(id(0x100), &[])),
        Err(WriteError::NotStarted)
    );

    // CanSM restarts the controller; a frame written at once waits for the recovery.
    let restart_us = clock.advance_us(50_000);
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(ecu.write(Hth(0), 4, &frame(id(0x100), &[0; 8])), Ok(()));
    let recovery_us = 128 * 11 * 2;
    assert_eq!(recovery_us, 2_816);
    clock.advance_us(recovery_us - 1);
    assert!(ecu.is_bus_off(), "still recovering");
    clock.advance_us(1);
    assert!(!ecu.is_bus_off());
    assert_eq!(ecu.tec(), 0);
    bus.run_until(restart_us + 10_000);
    assert_eq!(
        confirmed(&ecu.take_events()),
        [(restart_us + recovery_us + FRAME8_US, 4)]
    );
}

#[test]
fn a_recovering_controller_does_not_receive() {
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut tester = bus.attach_tester();
    // Someone must acknowledge the tester's frames while the ECU is off the bus.
    let _listener = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_catch_all(Hrh(0)));
    ecu.inject_tx_errors(32);
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[])), Ok(()));
    bus.run_until(50_000);
    assert!(ecu.is_bus_off());
    let _ = ecu.take_events();
    clock.advance_us(50_000);
    assert_eq!(
        ecu.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    tester.send(&frame(id(0x222), &[]));
    bus.run_until(clock.now_us() + 1_000);
    assert!(ecu.take_events().is_empty(), "bus-off until recovered");
    clock.advance_us(3_000);
    tester.send(&frame(id(0x333), &[]));
    bus.run_until(clock.now_us() + 1_000);
    let events = ecu.take_events();
    assert_eq!(events.len(), 1, "{events:?}");
}

#[test]
fn next_event_us_lets_a_simulation_step_from_event_to_event() {
    let clock = VirtualClock::new();
    let bus = VirtualBus::new(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]).with_catch_all(Hrh(0)));
    for raw in [0x30, 0x20, 0x10] {
        tester.send(&frame(id(raw), &[raw as u8]));
    }
    let mut steps = 0;
    while let Some(t) = bus.next_event_us() {
        assert_eq!(clock.advance_to_us(t), Ok(()));
        bus.run_until_now();
        steps += 1;
        let events = ecu.take_events();
        assert_eq!(events.len(), 1, "one frame per step");
        assert_eq!(events[0].time_us, clock.now_us());
    }
    assert_eq!(steps, 3);
}

#[test]
fn bit_times_follow_the_bitrate() {
    let clock = VirtualClock::new();
    for bitrate_bps in [0, 1_000_001] {
        let config = BusConfig {
            bitrate_bps,
            ..BusConfig::DEFAULT
        };
        assert_eq!(
            VirtualBus::with_config(&clock, config).err(),
            Some(BusConfigError::Bitrate { bitrate_bps })
        );
    }
    let f = frame(id(0x100), &[0xDC, 0x05, 0, 0]);
    let at = |bitrate_bps| {
        let config = BusConfig {
            bitrate_bps,
            ..BusConfig::DEFAULT
        };
        VirtualBus::with_config(&clock, config).unwrap_or_else(|e| panic!("{e}"))
    };
    let fast = at(500_000);
    let slow = at(125_000);
    assert_eq!(fast.bit_time_ns(), 2_000);
    assert_eq!(slow.bit_time_ns(), 8_000);
    assert_eq!(slow.frame_duration_ns(&f), 4 * fast.frame_duration_ns(&f));
    let bits = timing::frame_bits(&f, Stuffing::Exact);
    assert_eq!(fast.frame_duration_ns(&f), u64::from(bits) * 2_000);
    assert_eq!(at(33_333).bit_time_ns(), 30_000);
    assert_eq!(fast.config(), BusConfig::DEFAULT);
    assert!(fast.clock().is_same_clock(&clock));
}

#[test]
fn buses_are_deterministic() {
    let run = || {
        let clock = VirtualClock::new();
        let bus = VirtualBus::new(&clock);
        bus.set_tracing(true);
        let mut t = bus.attach_tester();
        let mut e = started(&bus, &HostCanConfig::new(&[]));
        e.inject_tx_errors(5);
        for i in 0..20u16 {
            clock.advance_us(97);
            t.send(&frame(id(0x400 + i), &[i as u8; 3]));
            let _ = e.write(Hth(0), i, &frame(id(0x300 + 2 * i), &[0xA5; 8]));
            bus.run_until_now();
        }
        bus.run_until(1_000_000);
        (bus.take_trace(), e.take_events())
    };
    let first = run();
    assert!(!first.0.is_empty());
    assert_eq!(first, run());
}

#[test]
fn draining_the_trace_appends_each_frame_once_in_bus_order() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    bus.set_tracing(true);
    let mut tester = bus.attach_tester();
    // (A started node acknowledges the tester's frames.)
    let _ecu = started(&bus, &HostCanConfig::new(&[]));
    let mut all = Vec::new();
    for raw in [0x300, 0x100] {
        tester.send(&frame(id(raw), &[0; 8]));
        clock.advance_us(1_000);
        bus.run_until_now();
        bus.drain_trace_into(&mut all);
    }
    // Nothing new on the bus: nothing more is appended.
    bus.drain_trace_into(&mut all);
    assert_eq!(received_ids(&all), [0x300, 0x100]);
    assert!(bus.take_trace().is_empty());
}

#[test]
fn a_tester_frame_and_an_ecu_frame_share_the_bus_fairly() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[(id(0x050), Hrh(1))]));
    tester.send(&frame(id(0x050), &[0; 8]));
    tester.send(&frame(id(0x7FF), &[0; 8]));
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    bus.run_until(10_000);
    // FIFO at the tester: 0x050 wins, then the ECU's 0x100 beats the tester's 0x7FF.
    assert_eq!(
        confirmed(&ecu.take_events()),
        vec![(SLOT8_US + FRAME8_US, 1)]
    );
    assert_eq!(received_ids(&tester.take_received()), [0x100]);
}

#[test]
fn the_end_of_time_saturates_instead_of_overflowing() {
    let clock = VirtualClock::starting_at_us(u64::MAX - 10);
    let bus = VirtualBus::new(&clock);
    let mut tester = bus.attach_tester();
    let mut ecu = started(&bus, &HostCanConfig::new(&[]));
    assert_eq!(ecu.write(Hth(0), 1, &frame(id(0x100), &[0; 8])), Ok(()));
    tester.send(&frame(id(0x200), &[0; 8]));
    bus.run_until(u64::MAX);
    assert_eq!(bus.stats().frames, 1, "one frame ends when time runs out");
    assert!(bus.next_event_us().is_some_and(|t| t >= u64::MAX / 1_000));
}

#[test]
fn can_init_takes_the_bus_bitrate_a_flexcan_timing_reaches_and_refuses_others() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut can = started(&bus, &HostCanConfig::new(&[]));
    let at = |bitrate| ControllerConfig {
        bitrate,
        sample_permille: 875,
    };
    assert_eq!(can.init(&at(500_000)), Ok(()));
    assert_eq!(
        can.mode(),
        ControllerMode::Stopped,
        "Can_Init leaves it stopped"
    );
    // Reachable from 80 MHz, but not the bus's bitrate: the node would see only errors.
    assert_eq!(
        can.init(&at(250_000)),
        Err(InitRefused { bitrate: 250_000 })
    );
    // No FlexCAN timing gives it from 80 MHz.
    assert_eq!(
        can.init(&at(333_333)),
        Err(InitRefused { bitrate: 333_333 })
    );
}

#[test]
fn the_error_counters_follow_failed_attempts_and_bus_off() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let mut can = started(&bus, &HostCanConfig::new(&[]));
    let _tester = bus.attach_tester();
    let fresh = can.error_counters();
    assert_eq!(
        (fresh.state, fresh.tec, fresh.rec),
        (ErrorState::Active, 0, 0)
    );
    can.inject_tx_errors(17);
    assert_eq!(can.write(Hth(0), 1, &frame(id(0x100), &[1; 8])), Ok(()));
    clock.advance_us(17 * FAILED8_SLOT_US);
    bus.run_until_now();
    // 16 failed attempts (8 each) make it error passive.
    let passive = can.error_counters();
    assert_eq!((passive.state, passive.tec), (ErrorState::Passive, 128));
    can.inject_tx_errors(100);
    clock.advance_us(1_000_000);
    bus.run_until_now();
    assert_eq!(can.error_counters().state, ErrorState::BusOff);
    assert_eq!(can.error_counters().tec, can.tec());
}

#[test]
fn an_aborted_mailbox_is_neither_sent_nor_confirmed() {
    let clock = VirtualClock::new();
    let bus = worst_case_bus(&clock);
    let config = HostCanConfig::new(&[]).with_hths(2);
    let mut can = started(&bus, &config);
    let mut tester = bus.attach_tester();
    assert_eq!(can.write(Hth(0), 1, &frame(id(0x200), &[1])), Ok(()));
    assert_eq!(can.write(Hth(1), 2, &frame(id(0x100), &[2])), Ok(()));
    can.abort(Hth(0));
    assert_eq!(can.stats().tx_aborted, 1);
    clock.advance_us(10_000);
    bus.run_until_now();
    assert_eq!(confirmed(&can.take_events()).len(), 1, "only HTH 1's frame");
    assert_eq!(received_ids(&tester.take_received()), [0x100]);
}
