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
            "ECU sends frame DistanceFrame (0x101) on the bus, and no CanIfTxPduCfg carries it\n  \
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
            "I-PDU DistanceFrame lacks the bus's signal Alive of frame DistanceFrame, which \
          ECU sends\n  \
          at /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame\n  \
          and ecu.dbc: BO_ 256 DistanceFrame, SG_ Alive"
        ]
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
            "ECU receives frame Mode (0x300) on the bus, and no CanIfRxPduCfg carries it\n  \
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
    // Both the CanIf's PDU and Com's are 4 bytes long.
    let e = against(&changed(
        "BO_ 512 ThresholdConfig: 4 PC",
        "BO_ 512 ThresholdConfig: 8 PC",
    ));
    assert_eq!(e.len(), 2, "{e:#?}");
    assert!(e.iter().all(
        |e| e.contains("is 4 bytes long, its frame ThresholdConfig 8")
            && e.ends_with("and ecu.dbc: BO_ 512 ThresholdConfig")
    ));
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
fn a_data_length_check_beyond_the_frame_is_refused() {
    let bus = system::from_dbc(DBC, "ecu.dbc").expect("a bus");
    let mut ecu = ecu();
    assert_eq!(ecu.canif.rx[0].dlc, Some(4));
    // Shorter is a check CanIf may make; longer drops every frame.
    ecu.canif.rx[0].dlc = Some(3);
    assert_eq!(
        extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu),
        Ok(REPOSITORY)
    );
    ecu.canif.rx[0].dlc = Some(6);
    let e = extract::check(&bus, "ecu.dbc", cw_gen::NODE, &ecu).expect_err("dropped");
    assert_eq!(
        e[0].to_string(),
        "CanIf takes frame ThresholdConfig with 6 bytes, and the bus's frame has 4: every one \
         would be dropped\n  at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/ThresholdConfig\n  \
         and ecu.dbc: BO_ 512 ThresholdConfig"
    );
}
