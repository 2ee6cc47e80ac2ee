//! CanIf against a recording driver: transmit, buffering when busy, transmit confirmation,
//! the receive checks, modes and bus-off.
extern crate std;

use super::*;
use std::vec::Vec;

const fn id(raw: u16) -> CanId {
    match CanId::standard(raw) {
        Some(id) => id,
        None => panic!("test id out of range"),
    }
}

static CFG: CanIfConfig<3, 3> = match CanIfConfig::new(
    [
        TxPduConfig {
            name: "Distance",
            id: id(0x100),
            dlc: 8,
            hth: Hth(0),
        },
        TxPduConfig {
            name: "Status",
            id: id(0x080),
            dlc: 2,
            hth: Hth(0),
        },
        TxPduConfig {
            name: "Other",
            id: id(0x300),
            dlc: 8,
            hth: Hth(1),
        },
    ],
    [
        RxPduConfig {
            name: "Cmd",
            id: id(0x200),
            dlc: 4,
            hrh: Hrh(0),
        },
        RxPduConfig {
            name: "Time",
            id: id(0x050),
            dlc: 8,
            hrh: Hrh(0),
        },
        RxPduConfig {
            name: "Diag",
            id: id(0x7DF),
            dlc: 8,
            hrh: Hrh(1),
        },
    ],
) {
    Ok(cfg) => cfg,
    Err(e) => panic!("{}", e.describe()),
};

#[derive(Default)]
struct Recorder {
    busy: bool,
    written: Vec<(Hth, u16, CanFrame)>,
    mode: Option<ControllerMode>,
    aborted: Vec<Hth>,
    /// Mode changes are reported later, as a FlexCAN's are.
    slow_modes: bool,
}

impl CanDriver for Recorder {
    fn init(
        &mut self,
        _config: &crate::can::ControllerConfig,
    ) -> Result<(), crate::can::InitRefused> {
        self.mode = Some(ControllerMode::Stopped);
        Ok(())
    }

    // The recorder never fails a transmission: error active, no errors counted.
    fn error_counters(&self) -> crate::can::ErrorCounters {
        crate::can::ErrorCounters::ACTIVE
    }

    fn abort(&mut self, hth: Hth) {
        self.aborted.push(hth);
        self.written.retain(|w| w.0 != hth);
    }

    fn write(&mut self, hth: Hth, pdu: u16, frame: &CanFrame) -> Result<(), CanBusy> {
        if self.busy {
            return Err(CanBusy);
        }
        self.written.push((hth, pdu, *frame));
        Ok(())
    }

    fn set_controller_mode(&mut self, mode: ControllerMode) -> Result<ModeChange, ModeRefused> {
        if self.mode == Some(ControllerMode::Sleep) && mode == ControllerMode::Started {
            return Err(ModeRefused);
        }
        self.mode = Some(mode);
        Ok(if self.slow_modes {
            ModeChange::Pending
        } else {
            ModeChange::Reached
        })
    }
}

fn online() -> (CanIf<3, 3>, Recorder) {
    online_with(&CFG)
}

/// CanIf on `cfg` with its controller started and its channel online.
fn online_with<const TX: usize, const RX: usize>(
    cfg: &'static CanIfConfig<TX, RX>,
) -> (CanIf<TX, RX>, Recorder) {
    let mut canif = CanIf::new(cfg);
    let mut can = Recorder::default();
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    canif.set_pdu_mode(PduMode::Online);
    (canif, can)
}

fn frame(raw: u16, data: &[u8]) -> CanFrame {
    match CanFrame::from_parts(id(raw), data) {
        Some(f) => f,
        None => panic!("test frame too long"),
    }
}

#[test]
fn configuration_rules() {
    assert_eq!(CFG.rx_pdu_for(id(0x050)), Some(RxPduId(1)));
    assert_eq!(CFG.rx_pdu_for(id(0x200)), Some(RxPduId(0)));
    assert_eq!(CFG.rx_pdu_for(id(0x7DF)), Some(RxPduId(2)));
    assert_eq!(CFG.rx_pdu_for(id(0x201)), None);
    let rx = |raw, dlc| RxPduConfig {
        name: "r",
        id: id(raw),
        dlc,
        hrh: Hrh(0),
    };
    assert_eq!(
        CanIfConfig::<0, 2>::new([], [rx(0x10, 8), rx(0x10, 8)]).err(),
        Some(CanIfConfigError::DuplicateRxId { pdu: 1 })
    );
    assert_eq!(
        CanIfConfig::<0, 1>::new([], [rx(0x10, 9)]).err(),
        Some(CanIfConfigError::RxDlc { pdu: 0 })
    );
    let tx = TxPduConfig {
        name: "t",
        id: id(1),
        dlc: 9,
        hth: Hth(0),
    };
    assert_eq!(
        CanIfConfig::<1, 0>::new([tx], []).err(),
        Some(CanIfConfigError::TxDlc { pdu: 0 })
    );
}

#[test]
fn transmit_needs_a_started_controller_and_an_online_channel() {
    let mut canif = CanIf::new(&CFG);
    let mut can = Recorder::default();
    assert_eq!(
        canif.transmit(&mut can, TxPduId(0), &[1]),
        Err(TransmitError::Offline)
    );
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    canif.set_pdu_mode(PduMode::TxOffline);
    assert_eq!(
        canif.transmit(&mut can, TxPduId(0), &[1]),
        Err(TransmitError::Offline)
    );
    canif.set_pdu_mode(PduMode::Online);
    assert_eq!(
        canif.transmit(&mut can, TxPduId(9), &[1]),
        Err(TransmitError::UnknownPdu)
    );
    assert_eq!(
        canif.transmit(&mut can, TxPduId(1), &[1, 2, 3]),
        Err(TransmitError::TooLong)
    );
    assert!(can.written.is_empty());
    assert_eq!(
        canif.transmit(&mut can, TxPduId(0), &[0xDC, 0x05, 0, 0, 0, 0, 0, 0]),
        Ok(())
    );
    assert_eq!(
        can.written,
        [(Hth(0), 0, frame(0x100, &[0xDC, 0x05, 0, 0, 0, 0, 0, 0]))]
    );
}

#[test]
fn busy_mailbox_buffers_newest_data_and_confirmation_sends_highest_priority_first() {
    let (mut canif, mut can) = online();
    can.busy = true;
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[1; 8]), Ok(()));
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[2; 8]), Ok(()));
    assert_eq!(canif.transmit(&mut can, TxPduId(1), &[3, 3]), Ok(()));
    assert_eq!(canif.transmit(&mut can, TxPduId(2), &[4; 8]), Ok(()));
    assert_eq!(canif.stats().tx_buffered, 4);
    assert_eq!(canif.stats().tx_overwritten, 1);
    assert!(can.written.is_empty());
    can.busy = false;
    // A confirmation on HTH 0 frees one mailbox: 0x080 (Status) outranks 0x100 (Distance).
    assert_eq!(canif.tx_confirmation(&mut can, 0), Some(TxPduId(0)));
    assert_eq!(can.written, [(Hth(0), 1, frame(0x080, &[3, 3]))]);
    assert_eq!(canif.tx_confirmation(&mut can, 1), Some(TxPduId(1)));
    assert_eq!(
        can.written[1],
        (Hth(0), 0, frame(0x100, &[2; 8])),
        "newest data wins"
    );
    assert!(
        canif.is_buffered(TxPduId(2)),
        "HTH 1 has had no confirmation"
    );
    assert_eq!(canif.tx_confirmation(&mut can, 9), None);
    // A confirmation while the mailbox is taken again keeps the data for the next one.
    can.busy = true;
    assert_eq!(canif.tx_confirmation(&mut can, 2), Some(TxPduId(2)));
    assert!(canif.is_buffered(TxPduId(2)));
    assert_eq!(can.written.len(), 2);
    can.busy = false;
    assert_eq!(canif.tx_confirmation(&mut can, 2), Some(TxPduId(2)));
    assert!(!canif.is_buffered(TxPduId(2)));
    assert_eq!(can.written.len(), 3);
    assert_eq!((can.written[2].0, can.written[2].1), (Hth(1), 2));
}

#[test]
fn receive_checks_drop_and_count_without_disturbing_anything() {
    let (mut canif, _can) = online();
    assert_eq!(
        canif.rx_indication(Hrh(0), &frame(0x200, &[1, 2, 3, 4])),
        Ok(RxPduId(0))
    );
    assert_eq!(
        canif.rx_indication(Hrh(0), &frame(0x200, &[1, 2, 3, 4, 5])),
        Ok(RxPduId(0))
    );
    assert_eq!(
        canif.rx_indication(Hrh(0), &frame(0x201, &[0; 8])),
        Err(RxDropped::UnknownId)
    );
    assert_eq!(
        canif.rx_indication(Hrh(1), &frame(0x200, &[0; 8])),
        Err(RxDropped::WrongHrh)
    );
    assert_eq!(
        canif.rx_indication(Hrh(0), &frame(0x200, &[0; 3])),
        Err(RxDropped::WrongDlc)
    );
    let stats = *canif.stats();
    assert_eq!(
        (stats.rx_unknown_id, stats.rx_wrong_hrh, stats.rx_wrong_dlc),
        (1, 1, 1)
    );
    // Receive-only still receives; offline does not.
    canif.set_pdu_mode(PduMode::TxOffline);
    assert_eq!(
        canif.rx_indication(Hrh(1), &frame(0x7DF, &[0; 8])),
        Ok(RxPduId(2))
    );
    canif.set_pdu_mode(PduMode::Offline);
    assert_eq!(
        canif.rx_indication(Hrh(1), &frame(0x7DF, &[0; 8])),
        Err(RxDropped::Offline)
    );
}

#[test]
fn bus_off_stops_the_controller_and_discards_buffers() {
    let (mut canif, mut can) = online();
    can.busy = true;
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[1; 8]), Ok(()));
    canif.controller_bus_off();
    assert_eq!(canif.controller_mode(), ControllerMode::Stopped);
    assert!(!canif.is_buffered(TxPduId(0)));
    assert_eq!(canif.stats().tx_discarded, 1);
    // A stopped controller receives nothing, although the channel is still online.
    assert_eq!(
        canif.rx_indication(Hrh(1), &frame(0x7DF, &[0; 8])),
        Err(RxDropped::Offline)
    );
    assert_eq!(
        canif.transmit(&mut can, TxPduId(0), &[1; 8]),
        Err(TransmitError::Offline)
    );
    // Recovery: started again, frames flow.
    can.busy = false;
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Started),
        Ok(ModeChange::Reached)
    );
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[5; 8]), Ok(()));
    assert_eq!(can.written.len(), 1);
    // A refused mode change leaves the mode as it was.
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Sleep),
        Ok(ModeChange::Reached)
    );
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Started),
        Err(ModeRefused)
    );
    assert_eq!(canif.controller_mode(), ControllerMode::Sleep);
}

/// Any frame on any mailbox: accepted exactly when id, HRH and DLC match the table, and
/// every drop is counted once.
#[test]
#[cfg_attr(kani, kani::proof, kani::unwind(9))]
fn any_frame_is_accepted_or_dropped_and_counted() {
    bolero::check!()
        .with_type::<(u16, u8, u8, [u8; 8])>()
        .cloned()
        .for_each(|(raw, hrh, len, data)| {
            let (mut canif, _) = online();
            let f = frame(raw & 0x7FF, &data[..usize::from(len % 9)]);
            let before = *canif.stats();
            let verdict = canif.rx_indication(Hrh(hrh % 3), &f);
            let after = *canif.stats();
            let drops =
                |s: &CanIfStats| s.rx_unknown_id + s.rx_wrong_hrh + s.rx_wrong_dlc + s.rx_offline;
            let expected = CFG
                .rx()
                .iter()
                .position(|p| p.id == f.can_id())
                .map(|i| (i, CFG.rx()[i]));
            match (verdict, expected) {
                (Ok(pdu), Some((i, cfg))) => {
                    assert_eq!(usize::from(pdu.0), i);
                    assert!(cfg.hrh == Hrh(hrh % 3) && f.len() >= cfg.dlc);
                    assert_eq!(drops(&after), drops(&before));
                }
                (Err(_), _) => assert_eq!(drops(&after), drops(&before) + 1),
                (Ok(_), None) => panic!("a frame with an unconfigured id was accepted"),
            }
        });
}

/// The transmit buffers survive exactly the transitions that keep the channel sending
/// (controller started, PDU mode online) and are discarded, each counted once, by every
/// other controller and PDU mode.
#[test]
fn buffers_are_discarded_exactly_when_the_channel_stops_sending() {
    let buffered = || {
        let (mut canif, mut can) = online();
        can.busy = true;
        assert_eq!(canif.transmit(&mut can, TxPduId(0), &[1; 8]), Ok(()));
        assert_eq!(canif.transmit(&mut can, TxPduId(2), &[2; 8]), Ok(()));
        (canif, can)
    };
    // Both buffers kept, or both discarded and counted.
    let check = |canif: &CanIf<3, 3>, kept: bool, mode: &dyn core::fmt::Debug| {
        assert_eq!(canif.is_buffered(TxPduId(0)), kept, "{mode:?}");
        assert_eq!(canif.is_buffered(TxPduId(2)), kept, "{mode:?}");
        let discarded = if kept { 0 } else { 2 };
        assert_eq!(canif.stats().tx_discarded, discarded, "{mode:?}");
    };
    for (mode, kept) in [
        (ControllerMode::Started, true),
        (ControllerMode::Stopped, false),
        (ControllerMode::Sleep, false),
    ] {
        let (mut canif, mut can) = buffered();
        assert_eq!(
            canif.set_controller_mode(&mut can, mode),
            Ok(ModeChange::Reached)
        );
        assert_eq!(canif.controller_mode(), mode);
        check(&canif, kept, &mode);
    }
    for (mode, kept) in [
        (PduMode::Online, true),
        (PduMode::TxOffline, false),
        (PduMode::Offline, false),
    ] {
        let (mut canif, _can) = buffered();
        canif.set_pdu_mode(mode);
        check(&canif, kept, &mode);
    }
}

/// Receive PDUs with ids `raws`, in that order, DLC 8.
fn rx_table<const RX: usize>(raws: [u16; RX]) -> [RxPduConfig; RX] {
    raws.map(|raw| RxPduConfig {
        name: "r",
        id: id(raw),
        dlc: 8,
        hrh: Hrh(0),
    })
}

#[test]
fn a_configuration_built_at_run_time_finds_every_receive_id_in_any_order() {
    // Every order of four ids: the table is sorted by insertion, whatever the order given.
    let raws = [0x30, 0x10, 0x7FF, 0x20];
    let mut orders = 0;
    for a in 0..4 {
        for b in 0..4 {
            for c in 0..4 {
                for d in 0..4 {
                    let order = [a, b, c, d];
                    if (0..4).any(|i| !order.contains(&i)) {
                        continue;
                    }
                    orders += 1;
                    let given = order.map(|i| raws[i]);
                    let cfg = CanIfConfig::<0, 4>::new([], rx_table(given))
                        .unwrap_or_else(|e| panic!("{given:?}: {}", e.describe()));
                    for (pdu, raw) in given.iter().enumerate() {
                        assert_eq!(
                            cfg.rx_pdu_for(id(*raw)),
                            Some(RxPduId(pdu as u16)),
                            "{given:?}"
                        );
                    }
                    assert_eq!(cfg.rx_pdu_for(id(0x11)), None);
                    // The same id twice, wherever the second one sits, is refused at it.
                    for dup in 1..4 {
                        let mut twice = given;
                        twice[dup] = given[0];
                        assert_eq!(
                            CanIfConfig::<0, 4>::new([], rx_table(twice)).err(),
                            Some(CanIfConfigError::DuplicateRxId { pdu: dup as u16 }),
                            "{twice:?}"
                        );
                    }
                }
            }
        }
    }
    assert_eq!(orders, 24);
}

#[test]
fn tables_of_255_pdus_are_the_limit() {
    let tx = |raw: u16| TxPduConfig {
        name: "t",
        id: id(raw),
        dlc: 8,
        hth: Hth(0),
    };
    let txs_255: [TxPduConfig; 255] = core::array::from_fn(|i| tx(i as u16));
    let txs_256: [TxPduConfig; 256] = core::array::from_fn(|i| tx(i as u16));
    let rxs_255: [u16; 255] = core::array::from_fn(|i| i as u16);
    let rxs_256: [u16; 256] = core::array::from_fn(|i| i as u16);
    assert!(CanIfConfig::<255, 255>::new(txs_255, rx_table(rxs_255)).is_ok());
    assert_eq!(
        CanIfConfig::<256, 1>::new(txs_256, rx_table([1])).err(),
        Some(CanIfConfigError::TooManyPdus)
    );
    assert_eq!(
        CanIfConfig::<1, 256>::new([tx(1)], rx_table(rxs_256)).err(),
        Some(CanIfConfigError::TooManyPdus)
    );
}

#[test]
fn every_configuration_error_describes_its_rule() {
    let errors = [
        (CanIfConfigError::TooManyPdus, "more than 255"),
        (
            CanIfConfigError::TxDlc { pdu: 0 },
            "transmit PDU has a DLC above 8",
        ),
        (
            CanIfConfigError::RxDlc { pdu: 0 },
            "receive PDU has a DLC above 8",
        ),
        (CanIfConfigError::DuplicateRxId { pdu: 1 }, "share a CAN id"),
    ];
    for (error, words) in errors {
        assert!(error.describe().contains(words), "{error:?}");
    }
}

#[test]
fn of_two_buffered_pdus_with_one_id_the_first_configured_goes_first() {
    static TWINS: CanIfConfig<2, 0> = match CanIfConfig::new(
        [
            TxPduConfig {
                name: "A",
                id: id(0x100),
                dlc: 1,
                hth: Hth(0),
            },
            TxPduConfig {
                name: "B",
                id: id(0x100),
                dlc: 1,
                hth: Hth(0),
            },
        ],
        [],
    ) {
        Ok(cfg) => cfg,
        Err(e) => panic!("{}", e.describe()),
    };
    let (mut canif, mut can) = online_with(&TWINS);
    can.busy = true;
    assert_eq!(canif.transmit(&mut can, TxPduId(1), &[2]), Ok(()));
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[1]), Ok(()));
    can.busy = false;
    assert_eq!(canif.tx_confirmation(&mut can, 0), Some(TxPduId(0)));
    assert_eq!(canif.tx_confirmation(&mut can, 0), Some(TxPduId(0)));
    assert_eq!(
        can.written,
        [
            (Hth(0), 0, frame(0x100, &[1])),
            (Hth(0), 1, frame(0x100, &[2]))
        ]
    );
}

/// A controller that changes modes later (a FlexCAN entering freeze mode at the end of the
/// frame on the wire): CanIf keeps the mode it knows until the driver indicates the new
/// one, so a pending stop keeps the buffers and a pending start sends nothing yet.
#[test]
fn a_pending_mode_change_takes_effect_at_its_indication() {
    let (mut canif, mut can) = online();
    can.busy = true;
    can.slow_modes = true;
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[1; 8]), Ok(()));
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Stopped),
        Ok(ModeChange::Pending)
    );
    assert_eq!(can.mode, Some(ControllerMode::Stopped), "asked");
    assert_eq!(canif.controller_mode(), ControllerMode::Started, "not yet");
    assert!(canif.is_buffered(TxPduId(0)));
    canif.controller_mode_indication(ControllerMode::Stopped);
    assert_eq!(canif.controller_mode(), ControllerMode::Stopped);
    assert!(!canif.is_buffered(TxPduId(0)));
    assert_eq!(canif.stats().tx_discarded, 1);
    // A pending start: nothing is sent before the controller says it started.
    can.busy = false;
    assert_eq!(
        canif.set_controller_mode(&mut can, ControllerMode::Started),
        Ok(ModeChange::Pending)
    );
    assert_eq!(
        canif.transmit(&mut can, TxPduId(0), &[2; 8]),
        Err(TransmitError::Offline)
    );
    canif.controller_mode_indication(ControllerMode::Started);
    assert_eq!(canif.transmit(&mut can, TxPduId(0), &[3; 8]), Ok(()));
    assert_eq!(can.written.len(), 1);
}
