//! The ECU description's communication held to the bus's: every disagreement between
//! `firmware/ecu.arxml` (CanIf, PduR, Com) and what the bus (`firmware/ecu.dbc`, or the
//! system description generated from it) asks of the node ECU is refused, naming the
//! ECUC item and the bus's frame or signal.

use cw_gen::extract::{self, Agreed};
use cw_gen::model::Ecu;
use cw_gen::system;

const ECU: &str = include_str!("../../firmware/ecu.arxml");
const DBC: &str = include_str!("../../firmware/ecu.dbc");
const SYSTEM: &str = include_str!("../../firmware/system.arxml");

fn ecu() -> Ecu {
    cw_gen::arxml::read(ECU.as_bytes(), "ecu.arxml")
        .expect("the ECU's description reads")
        .ecu
}

/// The errors, as the user reads them, of the ECU against `dbc`.
fn against(dbc: &str) -> Vec<String> {
    let bus = system::from_dbc(dbc, "ecu.dbc").expect("the changed DBC is a bus");
    match extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu()) {
        Ok(agreed) => panic!("the ECU agreed with the changed bus: {agreed:?}"),
        Err(e) => e.iter().map(ToString::to_string).collect(),
    }
}

/// `DBC` with `from` replaced by `to` (which must be there).
fn changed(from: &str, to: &str) -> String {
    assert!(DBC.contains(from), "{from:?} is not in ecu.dbc");
    DBC.replacen(from, to, 1)
}

const REPOSITORY: Agreed = Agreed {
    sent: 1,
    received: 1,
    signals: 4,
};

#[test]
fn the_repositorys_ecu_is_what_its_bus_gives_it() {
    let from_arxml = system::read(SYSTEM.as_bytes(), "system.arxml").expect("a bus");
    assert_eq!(
        extract::check(&from_arxml, "system.arxml", cw_gen::NODE, &ecu()),
        Ok(REPOSITORY)
    );
    let from_dbc = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    assert_eq!(
        extract::check(&from_dbc, "ecu.dbc", cw_gen::NODE, &ecu()),
        Ok(REPOSITORY)
    );
    // And through the library's entry, from the files' bytes.
    assert_eq!(
        cw_gen::check_communication(
            ECU.as_bytes(),
            "ecu.arxml",
            SYSTEM.as_bytes(),
            "system.arxml",
            cw_gen::NODE
        ),
        Ok(REPOSITORY)
    );
}

#[test]
fn a_frame_moved_to_another_identifier_is_named_on_both_sides() {
    let e = against(&changed(
        "BO_ 256 DistanceFrame: 8 ECU",
        "BO_ 257 DistanceFrame: 8 ECU",
    ));
    assert_eq!(
        e,
        [
            "CanIf sends the standard identifier 0x100, which no frame of the bus has\n  \
             at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame\n  and ecu.dbc",
            "ECU sends frame DistanceFrame (standard identifier 0x101) on the bus, and no CanIfTxPduCfg carries it\n  \
             at ecu.dbc: BO_ 257 DistanceFrame\n  and /CollisionWarning/EcucValues/CanIf/CanIfInitCfg",
        ]
    );
}

#[test]
fn a_signal_laid_out_otherwise_names_each_difference() {
    let e = against(&changed("SG_ RedBelow : 0|16@1+", "SG_ RedBelow : 7|16@0-"));
    assert_eq!(
        e,
        [
            "Com signal RedBelow: bit position 0 where the bus has 7, little endian where the bus \
          has big endian, unsigned where the bus has signed\n  \
          at /CollisionWarning/EcucValues/Com/ComConfig/RedBelow\n  \
          and ecu.dbc: BO_ 512 ThresholdConfig, SG_ RedBelow"
        ]
    );
    let e = against(&changed(
        "SG_ WarningLevel : 32|8@1+",
        "SG_ WarningLevel : 32|4@1+",
    ));
    assert_eq!(e.len(), 1);
    assert!(e[0].starts_with("Com signal WarningLevel: 8 bits where the bus has 4\n"));
}

#[test]
fn a_signal_the_ecu_sends_or_receives_must_be_in_its_i_pdu() {
    // A new signal of the frame the ECU sends: its I-PDU must carry it.
    let e = against(&changed(
        " SG_ WarningLevel",
        " SG_ Alive : 40|8@1+ (1,0) [0|255] \"\" PC\n SG_ WarningLevel",
    ));
    assert_eq!(
        e,
        [
            "ECU sends frame DistanceFrame with signal(s) Alive on the bus, and no Com I-PDU it \
             sends as the frame holds them\n  \
             at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame\n  \
             and /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame\n  \
             and ecu.dbc: BO_ 256 DistanceFrame, SG_ Alive"
        ]
    );
    // A received I-PDU without a signal the bus gives the ECU.
    let bus = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    let mut ecu = ecu();
    let ipdu = ecu
        .com
        .ipdus
        .iter_mut()
        .find(|i| i.name == "ThresholdConfig")
        .expect("the received I-PDU");
    ipdu.signals.retain(|s| s != "RedBelow");
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("lacks RedBelow");
    assert_eq!(
        e[0].to_string(),
        "ECU receives frame ThresholdConfig with signal(s) RedBelow on the bus, and no Com \
         I-PDU it routes the frame into holds them\n  \
         at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/ThresholdConfig\n  \
         and /CollisionWarning/EcucValues/Com/ComConfig/ThresholdConfig\n  \
         and ecu.dbc: BO_ 512 ThresholdConfig, SG_ RedBelow"
    );
    // A received frame routed to no Com I-PDU at all: every signal is missing.
    let mut ecu = self::ecu();
    ecu.routes.retain(|r| r.src != "ThresholdConfig_CanIf");
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("routed nowhere");
    assert!(
        e[0].what
            .starts_with("ECU receives frame ThresholdConfig with signal(s) RedBelow, YellowBelow"),
        "{e:?}"
    );
    // A Com signal the frame does not have (renamed on the bus).
    let e = against(&changed("SG_ YellowBelow", "SG_ YellowLimit"));
    assert_eq!(e.len(), 2, "{e:#?}");
    assert!(e[0].starts_with(
        "Com signal YellowBelow of I-PDU ThresholdConfig is not a signal of frame ThresholdConfig on the bus"
    ));
    assert!(e[1].starts_with("ECU receives frame ThresholdConfig with signal(s) YellowLimit"));
}

#[test]
fn a_signal_two_frames_share_may_be_named_with_its_frame() {
    // Com's signal `ThresholdConfig_RedBelow` is the bus's `RedBelow` of ThresholdConfig.
    let bus = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    let mut ecu = ecu();
    for s in &mut ecu.com.signals {
        if s.name == "RedBelow" {
            s.name = "ThresholdConfig_RedBelow".into();
        }
    }
    for i in &mut ecu.com.ipdus {
        for s in &mut i.signals {
            if s == "RedBelow" {
                *s = "ThresholdConfig_RedBelow".into();
            }
        }
    }
    assert_eq!(
        extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu),
        Ok(REPOSITORY)
    );
}

#[test]
fn a_big_endian_signal_agrees_at_its_most_significant_bit() {
    // Com's bit position and the DBC's start bit are both the most significant bit.
    let moto = changed("SG_ RedBelow : 0|16@1+", "SG_ RedBelow : 7|16@0+");
    let bus = system::from_dbc(&moto, "ecu.dbc").expect("a bus");
    let mut ecu = ecu();
    let red = ecu
        .com
        .signals
        .iter_mut()
        .find(|s| s.name == "RedBelow")
        .expect("RedBelow");
    red.endianness = cw_gen::model::Endianness::Big;
    red.bit_position = 7;
    assert_eq!(
        extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu),
        Ok(REPOSITORY)
    );
    // An update bit inside another signal of the frame is that signal's bit on the bus.
    if let Some(red) = ecu.com.signals.iter_mut().find(|s| s.name == "RedBelow") {
        red.update_bit = Some(20);
    }
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("update bit");
    assert_eq!(
        e[0].to_string(),
        "Com signal RedBelow's update bit 20 lies in the bus's signal YellowBelow of frame \
         ThresholdConfig\n  at /CollisionWarning/EcucValues/Com/ComConfig/RedBelow\n  \
         and ecu.dbc: BO_ 512 ThresholdConfig, SG_ YellowBelow"
    );
}

#[test]
fn a_frame_the_ecu_receives_needs_a_canif_rx_pdu_and_others_do_not() {
    let e = against(&format!(
        "{DBC}\nBO_ 768 Mode: 1 PC\n SG_ Mode : 0|8@1+ (1,0) [0|3] \"\" ECU\n"
    ));
    assert_eq!(
        e,
        [
            "ECU receives frame Mode (standard identifier 0x300) on the bus, and no CanIfRxPduCfg carries it\n  \
          at ecu.dbc: BO_ 768 Mode\n  and /CollisionWarning/EcucValues/CanIf/CanIfInitCfg"
        ]
    );
    // A frame between other nodes is not the ECU's to carry.
    let others = format!("{DBC}\nBO_ 768 Mode: 1 PC\n SG_ Mode : 0|8@1+ (1,0) [0|3] \"\" PC\n");
    let bus = system::from_dbc(&others, "ecu.dbc").expect("a bus");
    assert_eq!(
        extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu()),
        Ok(REPOSITORY)
    );
}

#[test]
fn a_frame_of_another_sender_or_length_is_refused() {
    let e = against(&changed(
        "BO_ 256 DistanceFrame: 8 ECU",
        "BO_ 256 DistanceFrame: 8 PC",
    ));
    assert_eq!(
        e,
        [
            "CanIf sends frame DistanceFrame, which the bus has sent by PC\n  \
          at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame\n  \
          and ecu.dbc: BO_ 256 DistanceFrame"
        ]
    );
    // The CanIf's PDU, its data length and Com's PDU are 4 bytes long.
    let e = against(&changed(
        "BO_ 512 ThresholdConfig: 4 PC",
        "BO_ 512 ThresholdConfig: 8 PC",
    ));
    assert_eq!(e.len(), 3, "{e:#?}");
    assert!(e
        .iter()
        .all(|e| e.ends_with("and ecu.dbc: BO_ 512 ThresholdConfig")));
    let pdus = e
        .iter()
        .filter(|e| e.contains("is 4 bytes long, its frame ThresholdConfig 8"))
        .count();
    assert_eq!(pdus, 2);
}

#[test]
fn a_node_the_bus_does_not_have_is_refused() {
    let bus = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    let e = extract::check(&bus, "ecu.dbc", "Gateway", &ecu()).expect_err("no such node");
    assert_eq!(
        e[0].to_string(),
        "the bus has no node Gateway: the ECU's communication cannot be checked\n  at ecu.dbc"
    );
}

#[test]
fn through_the_system_description_the_places_are_its_paths() {
    let moved = changed("SG_ WarningLevel : 32|8@1+", "SG_ WarningLevel : 40|8@1+");
    let bus = system::from_dbc(&moved, "ecu.dbc").expect("a bus").system;
    let text = system::write(&bus, cw_gen::PACKAGE).expect("written");
    let read = system::read(text.as_bytes(), "system.arxml").expect("read back");
    let e = extract::check(&read, "system.arxml", cw_gen::NODE, &ecu()).expect_err("moved");
    assert_eq!(e.len(), 1);
    assert_eq!(
        e[0].paths[0],
        "/CollisionWarning/EcucValues/Com/ComConfig/WarningLevel"
    );
    assert!(
        e[0].paths[1].starts_with("/CollisionWarning/Communication/")
            && e[0].paths[1].ends_with("WarningLevel"),
        "{:?}",
        e[0].paths
    );
}

#[test]
fn frames_of_other_nodes_leave_the_ecu_alone() {
    bolero::check!()
        .with_type::<Vec<cw_gen::spec::FrameSeed>>()
        .for_each(|frames| {
            assert!(cw_gen::spec::frames_of_other_nodes_leave_the_ecu_alone(
                frames
            ))
        });
}

#[test]
fn a_data_length_other_than_the_frames_is_refused() {
    let bus = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    let mut ecu = ecu();
    assert_eq!(ecu.canif.rx[0].dlc, Some(4));
    ecu.canif.rx[0].dlc = Some(6);
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("dropped");
    assert_eq!(
        e[0].to_string(),
        "CanIf's data length for frame ThresholdConfig is 6 bytes, and the frame has 4\n  \
         at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/ThresholdConfig\n  \
         and ecu.dbc: BO_ 512 ThresholdConfig"
    );
    let mut ecu = self::ecu();
    ecu.canif.tx[0].dlc = Some(6);
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("sent short");
    assert!(e[0]
        .what
        .starts_with("CanIf's data length for frame DistanceFrame is 6 bytes"));
}

#[test]
fn an_identifier_of_the_other_kind_or_a_frame_without_the_ecu_is_named() {
    // The same number, extended on the bus.
    let e = against(&changed(
        "BO_ 256 DistanceFrame: 8 ECU",
        "BO_ 2147483904 DistanceFrame: 8 ECU",
    ));
    assert_eq!(
        e[0],
        "CanIf sends the standard identifier 0x100, which no frame of the bus has (frame \
         DistanceFrame has the extended identifier 0x100)\n  \
         at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame\n  and ecu.dbc"
    );
    assert!(e[1].starts_with(
        "ECU sends frame DistanceFrame (extended identifier 0x100) on the bus, and no CanIfTxPduCfg carries it"
    ));
    // A frame no node sends.
    let e = against(&changed(
        "BO_ 256 DistanceFrame: 8 ECU",
        "BO_ 256 DistanceFrame: 8 Vector__XXX",
    ));
    assert!(
        e[0].starts_with("CanIf sends frame DistanceFrame, which the bus has sent by no node\n")
    );
    // A frame the ECU receives none of.
    let e = against(&DBC.replace("\"mm\" ECU", "\"mm\" PC"));
    assert!(
        e[0].starts_with(
            "CanIf receives frame ThresholdConfig, none of whose signals the bus gives ECU\n"
        ),
        "{e:?}"
    );
}

#[test]
fn a_bus_with_two_frames_or_signals_of_one_name_is_refused() {
    let twice =
        format!("{DBC}\nBO_ 768 DistanceFrame: 1 PC\n SG_ Mode : 0|8@1+ (1,0) [0|3] \"\" PC\n");
    let e = system::from_dbc(&twice, "ecu.dbc").expect_err("two frames of one name");
    assert!(
        e.iter()
            .any(|e| e.what == "two frames are named DistanceFrame"),
        "{e:?}"
    );
    let twice = changed(
        " SG_ WarningLevel",
        " SG_ Distance : 40|8@1+ (1,0) [0|255] \"\" PC\n SG_ WarningLevel",
    );
    let e = system::from_dbc(&twice, "ecu.dbc").expect_err("two signals of one name");
    assert!(
        e.iter()
            .any(|e| e.what == "frame DistanceFrame has two signals named Distance"),
        "{e:?}"
    );
}
