//! `firmware/ecu.dbc` and the Com/CanIf tables describe the same frames: ids, lengths,
//! and every signal's start bit, length, byte order and signedness.

use can_dbc::{ByteOrder as DbcOrder, Dbc, MessageId, ValueType};
use cw_core::com::ipdu::SignalDirection;
use cw_core::com::signal::{ByteOrder, Signedness};
use cw_core::pdur::RxRoute;
use cw_firmware::config;

fn dbc() -> Dbc {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/ecu.dbc"))
        .expect("ecu.dbc readable");
    Dbc::try_from(text.as_str()).expect("ecu.dbc parses")
}

#[test]
fn every_com_signal_matches_the_dbc() {
    let dbc = dbc();
    let mut checked = 0;
    for sig in config::COM.signals() {
        // The frame of the signal's I-PDU, through PduR's routes.
        let (frame_id, ipdu_len) = match sig.direction {
            SignalDirection::Tx(id, _) => {
                let lpdu = config::pdur::TX[usize::from(id.0)];
                let canif = config::CANIF.tx()[usize::from(lpdu.0)];
                (canif.id, config::COM.tx()[usize::from(id.0)].len)
            }
            SignalDirection::Rx(id) => {
                let k = config::pdur::RX
                    .iter()
                    .position(|route| match route {
                        RxRoute::One(to) => *to == id,
                        RxRoute::FanOut(to) => to.contains(&id),
                        RxRoute::Drop => false,
                    })
                    .expect("every received I-PDU is routed from a CanIf RX PDU");
                let canif = config::CANIF.rx()[k];
                (canif.id, config::COM.rx()[usize::from(id.0)].len)
            }
        };
        let msg = dbc
            .messages
            .iter()
            .find(|m| m.id == MessageId::Standard(frame_id.raw() as u16))
            .unwrap_or_else(|| panic!("no DBC message with id {:#x}", frame_id.raw()));
        assert_eq!(msg.size, u64::from(ipdu_len), "{}: length", msg.name);
        let s = msg
            .signals
            .iter()
            .find(|s| s.name == sig.name)
            .unwrap_or_else(|| panic!("signal {} missing in {}", sig.name, msg.name));
        assert_eq!(
            s.start_bit,
            u64::from(sig.layout.start_bit()),
            "{}: start bit",
            sig.name
        );
        assert_eq!(
            s.size,
            u64::from(sig.layout.length_bits()),
            "{}: length",
            sig.name
        );
        let order = match s.byte_order {
            DbcOrder::LittleEndian => ByteOrder::Intel,
            DbcOrder::BigEndian => ByteOrder::Motorola,
        };
        assert_eq!(order, sig.layout.byte_order(), "{}: byte order", sig.name);
        let sign = match s.value_type {
            ValueType::Signed => Signedness::Signed,
            ValueType::Unsigned => Signedness::Unsigned,
        };
        assert_eq!(sign, sig.layout.signedness(), "{}: signedness", sig.name);
        checked += 1;
    }
    // And nothing in the DBC is missing from Com.
    let in_dbc: usize = dbc.messages.iter().map(|m| m.signals.len()).sum();
    assert_eq!(checked, in_dbc, "every DBC signal has a Com signal");
}

#[test]
fn the_distance_is_the_papers_32_bit_little_endian_signal() {
    let dbc = dbc();
    let msg = dbc
        .messages
        .iter()
        .find(|m| m.name == "DistanceFrame")
        .expect("DistanceFrame");
    let d = msg
        .signals
        .iter()
        .find(|s| s.name == "Distance")
        .expect("Distance");
    assert_eq!(
        (d.start_bit, d.size, d.byte_order, d.unit.as_str()),
        (0, 32, DbcOrder::LittleEndian, "mm")
    );
}
