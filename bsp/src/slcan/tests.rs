//! The SLCAN controller over a model UART: what goes out, what comes in, what is
//! confirmed, on the host.

extern crate std;

use std::vec::Vec;

use super::*;

use super::spec::{events, set_ms, started as controller};

fn frame(id: u16, data: &[u8]) -> CanFrame {
    let Some(f) = CanId::standard(id).and_then(|id| CanFrame::from_parts(id, data)) else {
        panic!("a test frame");
    };
    f
}

#[test]
fn a_written_frame_leaves_as_its_time_stamped_line_and_is_confirmed_after_its_last_byte() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    set_ms(61_234);
    let f = frame(0x100, &[1, 2]);
    assert_eq!(c.write(Hth(0), 7, &f), Ok(()));
    assert!(
        uart.0.borrow().service_requested,
        "the interrupt work is requested"
    );
    assert!(
        uart.0.borrow().sent.is_empty(),
        "Can_Write only fills the mailbox"
    );
    assert_eq!(c.write(Hth(0), 8, &f), Err(CanBusy), "one mailbox");
    // The time stamp is Can_Write's time, modulo 60 000 ms.
    let mut line = [0u8; slcan::FRAME_LINE_MAX];
    let len = slcan::encode_frame_at(&f, Some(1_234), &mut line);
    assert_eq!(events(&mut c), [SlcanEvent::TxConfirmation(7)]);
    assert_eq!(uart.0.borrow().sent, line[..len]);
    assert!(
        uart.0.borrow().idles >= 1,
        "nothing left: the TX interrupt withdrawn"
    );
    assert_eq!(c.write(Hth(0), 8, &f), Ok(()), "free again");
}

#[test]
fn a_line_that_does_not_fit_the_transmitter_at_once_is_finished_later_and_then_confirmed() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    uart.0.borrow_mut().room = 3;
    assert_eq!(c.write(Hth(0), 1, &frame(0x123, &[0xAA; 8])), Ok(()));
    assert_eq!(events(&mut c), [], "three bytes out, no confirmation yet");
    assert_eq!(uart.0.borrow().sent.len(), 3);
    uart.0.borrow_mut().room = usize::MAX;
    assert_eq!(events(&mut c), [SlcanEvent::TxConfirmation(1)]);
    assert!(uart.0.borrow().sent.ends_with(b"\r"));
}

#[test]
fn received_lines_become_frames_commands_are_answered_and_garbage_gets_bel() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    uart.0
        .borrow_mut()
        .incoming
        .extend(b"t2004E8030000\rV\rxyz\r");
    let got = events(&mut c);
    assert_eq!(
        got,
        [SlcanEvent::Received(frame(0x200, &[0xE8, 0x03, 0, 0]))]
    );
    let sent = uart.0.borrow().sent.clone();
    assert!(
        sent.contains(&slcan::ERROR_REPLY[0]),
        "BEL for the garbage line"
    );
    let stats = BUS.stats();
    assert_eq!(
        (stats.rx_frames, stats.rx_commands, stats.rx_malformed),
        (1, 1, 1)
    );
}

#[test]
fn a_stopped_controller_refuses_frames_and_drops_the_one_waiting() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    assert_eq!(c.write(Hth(0), 3, &frame(0x100, &[9])), Ok(()));
    assert_eq!(
        c.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        events(&mut c),
        [],
        "no confirmation for the cancelled frame"
    );
    assert!(uart.0.borrow().sent.is_empty());
    assert_eq!(c.write(Hth(0), 4, &frame(0x100, &[9])), Err(CanBusy));
    assert_eq!(
        c.set_controller_mode(ControllerMode::Sleep),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        c.set_controller_mode(ControllerMode::Started),
        Err(ModeRefused),
        "not from sleep"
    );
}

/// A stop asked for while a frame's line is on the UART lets the line finish (no
/// confirmation: the frame was withdrawn) and takes effect after its last character; the
/// controller takes no frame and refuses to start meanwhile. With no line under way, a
/// stop is immediate.
#[test]
fn a_stop_during_a_line_waits_for_its_end_and_is_indicated() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    uart.0.borrow_mut().room = 3;
    assert_eq!(c.write(Hth(0), 1, &frame(0x123, &[0xAA; 8])), Ok(()));
    assert_eq!(events(&mut c), [], "three bytes out");
    assert_eq!(
        c.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert_eq!(c.write(Hth(0), 2, &frame(0x100, &[1])), Err(CanBusy));
    assert_eq!(
        c.set_controller_mode(ControllerMode::Started),
        Err(ModeRefused)
    );
    assert_eq!(
        c.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Pending),
        "still on the way"
    );
    uart.0.borrow_mut().room = usize::MAX;
    assert_eq!(
        events(&mut c),
        [SlcanEvent::ModeIndication(ControllerMode::Stopped)],
        "the line finished, unconfirmed, then the stop"
    );
    assert!(uart.0.borrow().sent.ends_with(b"\r"));
    assert_eq!(
        c.set_controller_mode(ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        c.set_controller_mode(ControllerMode::Stopped),
        Ok(ModeChange::Reached),
        "no line under way"
    );
    assert_eq!(events(&mut c), []);
}

#[test]
fn the_tester_ring_keeps_order_and_counts_an_overrun() {
    static BUS: SlcanBus = SlcanBus::new();
    let frames: Vec<CanFrame> = (0..5u16).map(|i| frame(0x300 + i, &[i as u8])).collect();
    for f in &frames {
        BUS.put_frame(f);
    }
    assert_eq!(BUS.stats().rx_overruns, 1, "a ring of four");
    for f in &frames[..4] {
        assert_eq!(BUS.take_frame(), Some(*f));
    }
    assert_eq!(BUS.take_frame(), None);
    // Extended ids and empty frames keep their form through the ring.
    let Some(ext) = CanId::extended(0x1ABC_DEF0).and_then(|id| CanFrame::from_parts(id, &[]))
    else {
        panic!("an extended frame");
    };
    BUS.put_frame(&ext);
    assert_eq!(BUS.take_frame(), Some(ext));
}

/// Any 12 writes, received bytes, transmitter room and interrupt work: every accepted
/// frame is confirmed once, in order, after its whole line went out
/// (`spec::operations_confirm_each_frame_once`).
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(40))]
fn any_operations_confirm_each_frame_once_after_its_whole_line() {
    bolero::check!()
        .with_type::<[(u8, u8, u8); 12]>()
        .for_each(|ops| assert!(super::spec::operations_confirm_each_frame_once(ops)));
}

/// The same over sequences of any length.
#[test]
fn long_operation_sequences_confirm_each_frame_once() {
    bolero::check!()
        .with_type::<Vec<(u8, u8, u8)>>()
        .for_each(|ops| assert!(super::spec::operations_confirm_each_frame_once(ops)));
}

#[test]
fn can_init_takes_a_lawicel_bitrate_and_leaves_the_controller_stopped() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, _uart) = controller(&BUS);
    let at = |bitrate| ControllerConfig {
        bitrate,
        sample_permille: 875,
    };
    assert_eq!(c.init(&at(250_000)), Ok(()));
    assert_eq!(c.bitrate(), 250_000);
    assert_eq!(
        c.write(Hth(0), 1, &frame(0x100, &[1])),
        Err(CanBusy),
        "stopped after Can_Init"
    );
    assert_eq!(c.init(&at(83_333)), Err(InitRefused { bitrate: 83_333 }));
    assert_eq!(c.bitrate(), 250_000, "a refusal keeps the configuration");
}

#[test]
fn an_aborted_frame_is_neither_sent_nor_confirmed_and_the_counters_are_error_active() {
    static BUS: SlcanBus = SlcanBus::new();
    let (mut c, uart) = controller(&BUS);
    assert_eq!(c.write(Hth(0), 5, &frame(0x100, &[1])), Ok(()));
    c.abort(Hth(0));
    assert_eq!(events(&mut c), []);
    assert!(uart.0.borrow().sent.is_empty());
    assert_eq!(
        c.write(Hth(0), 6, &frame(0x100, &[2])),
        Ok(()),
        "free again"
    );
    let e = c.error_counters();
    assert_eq!(
        (e.state, e.tec, e.rec),
        (cw_core::can::confinement::ErrorState::Active, 0, 0)
    );
}
