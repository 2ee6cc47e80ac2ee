//! The bus's system description (`firmware/system.arxml`) and its DBC (`firmware/ecu.dbc`):
//! each from the other, read back the same; canmatrix's export of the DBC read as the
//! same bus; what neither can carry refused with its place named.

use cw_gen::spec;
use cw_gen::system;

const DBC: &str = include_str!("../../firmware/ecu.dbc");
const SYSTEM: &str = include_str!("../../firmware/system.arxml");
/// `canconvert firmware/ecu.dbc ecu.arxml`, canmatrix 1.3.3 (PyPI), as it wrote it.
const CANMATRIX: &str = include_str!("data/ecu-canmatrix-1.3.3.arxml");

fn bus() -> system::System {
    system::from_dbc(DBC, "ecu.dbc")
        .expect("the DBC is a bus")
        .system
}

fn errors(e: Vec<cw_gen::validate::Error>) -> Vec<String> {
    e.iter().map(ToString::to_string).collect()
}

#[test]
fn the_dbc_is_the_bus_the_firmware_uses() {
    let bus = bus();
    assert_eq!(bus.nodes.len(), 2);
    let names: Vec<&str> = bus.frames.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["DistanceFrame", "ThresholdConfig"]);
    let distance = &bus.frames[0];
    assert_eq!(
        (distance.id, distance.extended, distance.length),
        (0x100, false, 8)
    );
    assert_eq!(distance.sender.as_deref(), Some("ECU"));
    let d = &distance.signals[0];
    assert_eq!(
        (d.start_bit, d.length, d.big_endian, d.signed),
        (0, 32, false, false)
    );
    assert_eq!(d.range, Some((0.0, 4_294_967_295.0)));
    assert_eq!(d.receivers, ["PC"]);
    assert_eq!(
        d.values,
        [
            (4_294_967_294, "NothingInRange".to_string()),
            (4_294_967_295, "Invalid".to_string())
        ]
    );
}

#[test]
fn the_committed_system_description_is_the_dbcs_bus_both_ways() {
    let read = system::read(SYSTEM.as_bytes(), "system.arxml").expect("it reads");
    assert_eq!(read.system, bus());
    assert_eq!(read.notes, Vec::<String>::new());
    // Written again, it is the committed file (`cargo xtask generate --check` says the same).
    assert_eq!(
        system::write(&bus(), cw_gen::PACKAGE).expect("it writes"),
        SYSTEM
    );
    // The DBC written from it is the same bus.
    let back = system::to_dbc(&read.system);
    assert_eq!(
        system::from_dbc(&back, "back.dbc")
            .expect("it parses")
            .system,
        bus()
    );
}

#[test]
fn canmatrixs_export_of_the_dbc_is_read_as_the_same_bus() {
    let read = system::read(CANMATRIX.as_bytes(), "ecu-canmatrix.arxml").expect("it reads");
    let (differences, unchecked) = system::differences(&bus(), &read.system);
    assert_eq!(differences, Vec::<String>::new());
    // canmatrix exports no range for a signal with named values.
    assert_eq!(
        unchecked,
        [
            "signal DistanceFrame.Distance: the range (0.0, 4294967295.0) is not in the description",
            "signal DistanceFrame.WarningLevel: the range (0.0, 3.0) is not in the description",
        ]
    );
    // What it writes that the model has no place for, or writes its own way, is noted.
    assert!(
        read.notes.iter().any(|n| n
            == "/Cluster/CAN/CAN/DistanceFrame: PDU-TRIGGERING-REF /Cluster/CAN/IPDUTRIGG_DistanceFrame refers to nothing; the frame's I-PDU is read from its PDU-TO-FRAME-MAPPING"),
        "{:#?}",
        read.notes
    );
    assert!(
        read.notes.iter().any(|n| n.contains(
            "the value name `NothingInRange` is read from DESC, not the VT `cm_0_NothingInRange`"
        )),
        "{:#?}",
        read.notes
    );
}

#[test]
fn what_the_dbc_cannot_give_a_system_description_is_refused_naming_message_and_signal() {
    // A multiplexed signal.
    let muxed = DBC.replace(
        " SG_ WarningLevel : 32|8@1+",
        " SG_ WarningLevel M : 32|8@1+",
    );
    assert_eq!(
        system::from_dbc(&muxed, "ecu.dbc").map_err(errors),
        Err(vec![
            "signal DistanceFrame.WarningLevel is multiplexed: multiplexing is not mapped\n  at ecu.dbc: BO_ 256 DistanceFrame, SG_ WarningLevel".to_string()
        ])
    );
    // A factor of 0 gives every raw value one physical value.
    let flat = DBC.replace("RedBelow : 0|16@1+ (1,0)", "RedBelow : 0|16@1+ (0,0)");
    let e = system::from_dbc(&flat, "ecu.dbc")
        .map_err(errors)
        .expect_err("refused");
    assert!(
        e[0].contains("signal ThresholdConfig.RedBelow has the factor 0"),
        "{e:#?}"
    );
    // Not a DBC.
    let e = system::from_dbc("BO_ 1 X: 8", "x.dbc")
        .map_err(errors)
        .expect_err("refused");
    assert!(e[0].starts_with("the DBC does not parse"), "{e:#?}");
}

#[test]
fn what_a_system_description_cannot_carry_is_refused_with_its_path() {
    // A frame triggering whose frame is not there.
    let dangling = SYSTEM.replacen(
        ">/CollisionWarning/Communication/Frames/DistanceFrame<",
        ">/CollisionWarning/Communication/Frames/Nowhere<",
        1,
    );
    let e = system::read(dangling.as_bytes(), "system.arxml").map_err(errors);
    assert_eq!(
        e,
        Err(vec![
            "FRAME-REF /CollisionWarning/Communication/Frames/Nowhere refers to nothing in the description\n  at /CollisionWarning/Communication/Clusters/CAN/CANChannel/DistanceFrame".to_string()
        ])
    );
    // A second cluster.
    let two = SYSTEM.replacen(
        "<CAN-CLUSTER>\n",
        "<CAN-CLUSTER>\n<SHORT-NAME>Second</SHORT-NAME></CAN-CLUSTER><CAN-CLUSTER>\n",
        1,
    );
    let e = system::read(two.as_bytes(), "system.arxml")
        .map_err(errors)
        .expect_err("refused");
    assert!(
        e.iter().any(|e| e.starts_with("two CAN clusters")),
        "{e:#?}"
    );
    // A float signal's base type.
    let float = SYSTEM.replacen(
        "<BASE-TYPE-ENCODING>NONE<",
        "<BASE-TYPE-ENCODING>IEEE754<",
        1,
    );
    let e = system::read(float.as_bytes(), "system.arxml")
        .map_err(errors)
        .expect_err("refused");
    assert!(
        e.iter().any(|e| e.starts_with("BASE-TYPE-ENCODING IEEE754: only integer signals are mapped\n  at /CollisionWarning/Communication/BaseTypes/")),
        "{e:#?}"
    );
    // No CAN bus at all.
    let e = system::read(cw_gen::spec::ECU.as_bytes(), "ecu.arxml").map_err(errors);
    assert_eq!(
        e,
        Err(vec![
            "no CAN-CLUSTER: the description has no CAN bus\n  at ecu.arxml".to_string()
        ])
    );
}

#[test]
fn any_bus_reads_back_as_written_as_arxml_and_as_a_dbc() {
    bolero::check!()
        .with_type::<Vec<spec::FrameSeed>>()
        .for_each(|frames| assert!(spec::a_bus_reads_back_as_written(frames)));
}

#[test]
fn any_text_is_a_bus_or_is_refused() {
    bolero::check!()
        .with_type::<String>()
        .for_each(|text| assert!(spec::a_text_is_a_bus_or_is_refused(text)));
}

#[test]
fn what_no_bus_has_is_refused_naming_the_message() {
    let refused = |from: &str, to: &str| -> Vec<String> {
        assert_eq!(DBC.matches(from).count(), 1, "{from}");
        match system::from_dbc(&DBC.replacen(from, to, 1), "ecu.dbc") {
            Ok(_) => Vec::new(),
            Err(e) => errors(e),
        }
    };
    let cases = [
        // An identifier beyond 11 bits without the extended bit.
        (
            "BO_ 512 ThresholdConfig: 4 PC",
            "BO_ 4096 ThresholdConfig: 4 PC",
            "message ThresholdConfig's identifier 4096 is out of a standard (11-bit) identifier's range\n  at ecu.dbc: BO_ 4096 ThresholdConfig",
        ),
        // Two messages of one identifier.
        (
            "BO_ 512 ThresholdConfig: 4 PC",
            "BO_ 256 ThresholdConfig: 4 PC",
            "messages DistanceFrame and ThresholdConfig have one identifier, 256\n  at ecu.dbc: BO_ 256 ThresholdConfig",
        ),
        // A length no CAN frame has.
        (
            "BO_ 512 ThresholdConfig: 4 PC",
            "BO_ 512 ThresholdConfig: 9 PC",
            "message ThresholdConfig is 9 bytes long: no CAN frame has that length\n  at ecu.dbc: BO_ 512 ThresholdConfig",
        ),
        // A signal beyond its frame.
        (
            "BO_ 256 DistanceFrame: 8 ECU",
            "BO_ 256 DistanceFrame: 4 ECU",
            "signal DistanceFrame.WarningLevel (start bit 32, 8 bits, Intel) does not fit in its 4-byte frame\n  at ecu.dbc: BO_ 256 DistanceFrame",
        ),
        // Two signals over one bit.
        (
            " SG_ WarningLevel : 32|8@1+",
            " SG_ WarningLevel : 24|8@1+",
            "signals DistanceFrame.Distance and DistanceFrame.WarningLevel share bits\n  at ecu.dbc: BO_ 256 DistanceFrame",
        ),
        // A receiver that is no node of the bus.
        (
            "[0|3] \"\" PC",
            "[0|3] \"\" Dash",
            "node Dash of message DistanceFrame is not one of BU_'s\n  at ecu.dbc: BO_ 256 DistanceFrame",
        ),
    ];
    for (from, to, error) in cases {
        let errors = refused(from, to);
        assert_eq!(errors, [error.to_string()], "{to}");
    }
}

#[test]
fn what_a_system_description_has_no_place_for_is_a_note() {
    let dbc = format!(
        "{DBC}\nBO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX\n SG_ Spare : 0|8@1+ (1,0) [0|0] \"\" Vector__XXX\n\nBA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\nBA_ \"GenMsgCycleTime\" BO_ 256 40;\n"
    );
    let read = system::from_dbc(&dbc, "ecu.dbc").expect("it reads");
    assert_eq!(read.system, bus());
    assert_eq!(
        read.notes,
        [
            "ecu.dbc: 2 attribute definitions and values (BA_DEF_, BA_): the system description has no place for them",
            "ecu.dbc: BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: the pseudo-message of signals no message carries is not a frame",
        ]
    );
}
