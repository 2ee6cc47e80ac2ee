//! The ECU's description (`firmware/ecu.arxml`) read, written back, and refused with the
//! paths named wherever it is changed into something the ECU cannot be generated from.

use cw_gen::arxml;
use cw_gen::validate;

use cw_gen::spec::ECU;

/// The description with the VALUE of the `nth` parameter of definition `def` (its last
/// segment) replaced by `value`.
fn with_value(def: &str, nth: usize, value: &str) -> String {
    let marker = format!("/{def}</DEFINITION-REF>");
    let at = ECU
        .match_indices(&marker)
        .nth(nth)
        .map(|(i, _)| i)
        .expect("the parameter is in the description");
    let open = at + ECU[at..].find("<VALUE>").expect("its value") + "<VALUE>".len();
    let close = open + ECU[open..].find("</VALUE>").expect("its value's end");
    format!("{}{value}{}", &ECU[..open], &ECU[close..])
}

/// Every error of generating `text`, as the user sees them.
fn refused(text: &str) -> Vec<String> {
    match cw_gen::generate(text.as_bytes(), "ecu.arxml") {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(ToString::to_string).collect(),
    }
}

#[test]
fn the_description_reads_checks_and_writes_back_as_it_is() {
    let read = arxml::read(ECU.as_bytes(), "ecu.arxml").expect("the description reads");
    assert_eq!(read.notes, Vec::<String>::new());
    assert_eq!(validate::check(&read.ecu), Vec::new());
    assert_eq!(read.ecu.os.tasks.len(), 6);
    assert_eq!(read.ecu.com.signals.len(), 4);
    // The writer's form is the file's: reading and writing again changes nothing.
    let again = arxml::write(&read.ecu, "CollisionWarning").expect("it writes");
    assert_eq!(again, ECU);
}

#[test]
fn the_generated_tables_name_where_each_item_came_from() {
    let out = cw_gen::generate(ECU.as_bytes(), "firmware/ecu.arxml").expect("it generates");
    for line in [
        "// /CollisionWarning/EcucValues/Os/OsLEDTask\nTaskConfig::basic(\"OsLEDTask\", 6)",
        "pub const OS_LED_TASK: TaskId = TaskId(1);",
        "AlarmAction::ActivateTask(OS_SONAR_TASK)",
        "pub const DISTANCE_INVALID: u64 = 4294967295;",
        "// /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/ThresholdConfig\nRxPduConfig {",
        "pub const CONTROLLER",
    ] {
        assert!(out.rust.contains(line), "missing: {line}");
    }
    assert!(out.rust.contains(&format!(
        "Description digest: {}",
        cw_gen::digest(ECU.as_bytes())
    )));
}

#[test]
fn a_vendors_definition_paths_read_as_the_standard_ones() {
    let standard = arxml::read(ECU.as_bytes(), "ecu.arxml").expect("reads").ecu;
    // MICROSAR's module definitions, and Arctic Core's name for the ISR priority.
    let vendor = ECU
        .replace("/AUTOSAR/EcucDefs/", "/MICROSAR/")
        .replace("/OsIsrInterruptPriority<", "/ArcOsIsrPriority<");
    let read = arxml::read(vendor.as_bytes(), "vendor.arxml").expect("reads");
    assert_eq!(read.ecu, standard);
}

#[test]
fn what_cannot_be_mapped_is_refused_with_its_path() {
    let unknown_param = ECU.replacen(
        "/OsTask/OsTaskPriority</DEFINITION-REF>",
        "/OsTask/OsTaskCoffee</DEFINITION-REF>",
        1,
    );
    assert_eq!(
        refused(&unknown_param),
        [
            "OsTask OsStartupTask has no OsTaskPriority\n  at /CollisionWarning/EcucValues/Os/OsStartupTask",
            "parameter OsTask/OsTaskCoffee cannot be mapped onto the ECU\n  at /CollisionWarning/EcucValues/Os/OsStartupTask",
        ]
    );
    let unknown_module = ECU
        .replace("/AUTOSAR/EcucDefs/Can/", "/AUTOSAR/EcucDefs/Dem/")
        .replace(">/AUTOSAR/EcucDefs/Can<", ">/AUTOSAR/EcucDefs/Dem<");
    let errors = refused(&unknown_module);
    assert!(errors.contains(&"module Dem cannot be mapped onto the ECU (Os, EcuC, Com, PduR, CanIf and Can can)\n  at /CollisionWarning/EcucValues/Can".to_string()), "{errors:?}");
    assert!(errors.contains(&"the description has no Can module".to_string()));
    let dangling = ECU.replacen(
        "/CollisionWarning/EcucValues/Os/RES_RTE</VALUE-REF>",
        "/CollisionWarning/EcucValues/Os/RES_NONE</VALUE-REF>",
        1,
    );
    assert_eq!(
        refused(&dangling),
        ["reference OsTaskResourceRef points to /CollisionWarning/EcucValues/Os/RES_NONE, which the description does not have\n  at /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
    assert_eq!(
        refused(&with_value("OsTaskSchedule", 1, "SOMETIMES")),
        ["OsTaskSchedule = `SOMETIMES`: one of FULL, NON\n  at /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
    assert_eq!(
        refused(&with_value("ComMinimumDelayTime", 0, "0.0005")),
        ["ComMinimumDelayTime = `0.0005` is not a whole number of milliseconds (in seconds)\n  at /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame/ComTxIPdu"]
    );
    let not_arxml = refused("<AUTOSAR>");
    assert_eq!(not_arxml.len(), 1);
    assert!(not_arxml[0].contains("ecu.arxml"), "{not_arxml:?}");
}

#[test]
fn a_description_the_ecu_cannot_run_is_refused_naming_every_item_involved() {
    // Two signals of one I-PDU that share bits: WarningLevel moved into Distance.
    assert_eq!(
        refused(&with_value("ComBitPosition", 1, "24")),
        ["signals Distance and WarningLevel of I-PDU DistanceFrame share bits\n  at /CollisionWarning/EcucValues/Com/ComConfig/WarningLevel\n  and /CollisionWarning/EcucValues/Com/ComConfig/Distance\n  and /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame"]
    );
    // A signal beyond its PDU.
    assert_eq!(
        refused(&with_value("ComBitPosition", 1, "60")),
        ["signal WarningLevel (8 bits at bit 60) does not fit I-PDU DistanceFrame's 8 bytes\n  at /CollisionWarning/EcucValues/Com/ComConfig/WarningLevel\n  and /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame"]
    );
    // A DLC too short for its PDU.
    assert_eq!(
        refused(&with_value("CanIfRxPduDataLength", 0, "2")),
        ["CanIf RX PDU ThresholdConfig has DLC 2 for PDU ThresholdConfig_CanIf of 4 bytes: the DLC must hold the PDU, up to 8\n  at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/ThresholdConfig\n  and /CollisionWarning/EcucValues/EcuC/EcucConfigSet/EcucPduCollection/ThresholdConfig_CanIf"]
    );
    // Two tasks on one priority.
    assert_eq!(
        refused(&with_value("OsTaskPriority", 2, "6")),
        ["two tasks have priority 6: the generator gives each task a priority of its own\n  at /CollisionWarning/EcucValues/Os/OsBswServiceTask\n  and /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
    // A priority outside the kernel's, an ISR priority outside the port's.
    assert_eq!(
        refused(&with_value("OsTaskPriority", 0, "64")),
        ["task OsStartupTask has priority 64, above the kernel's 63\n  at /CollisionWarning/EcucValues/Os/OsStartupTask"]
    );
    assert_eq!(
        refused(&with_value("OsIsrInterruptPriority", 0, "7")),
        [
            "category-1 ISR SensorRxIsr (priority 3) is not above category-2 ISR SysTickIsr (priority 7)\n  at /CollisionWarning/EcucValues/Os/SensorRxIsr\n  and /CollisionWarning/EcucValues/Os/SysTickIsr",
            "ISR SysTickIsr has priority 7, outside the port's 1..=6\n  at /CollisionWarning/EcucValues/Os/SysTickIsr",
        ]
    );
    // Duplicate CAN ids among the received PDUs cannot arise with one; a sent id beyond 11 bits.
    assert_eq!(
        refused(&with_value("CanIfTxPduCanId", 0, "0x800")),
        ["CanIf TX PDU DistanceFrame has CAN id 0x800, more than 11 bits\n  at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame"]
    );
    // An alarm whose cycle its counter cannot count.
    assert_eq!(
        refused(&with_value("OsAlarmCycleTime", 3, "70000")),
        ["alarm SonarAlarm starts after 40 and cycles every 70000 ticks: counter SystemCounter takes 1..=65535 for the start and 1..=65535 for a cycle\n  at /CollisionWarning/EcucValues/Os/SonarAlarm\n  and /CollisionWarning/EcucValues/Os/SystemCounter"]
    );
}

#[test]
fn bytes_the_arxml_library_panics_on_are_refused() {
    // autosar-data 0.23.0's lexer panics on an empty processing instruction.
    assert_eq!(
        refused("<?>"),
        ["the ARXML library failed on this file (it is not well-formed XML)\n  at ecu.arxml"]
    );
}

#[test]
fn bytes_that_are_not_a_description_are_refused_never_a_panic() {
    bolero::check!()
        .with_type::<Vec<u8>>()
        .for_each(|bytes| assert!(cw_gen::spec::bytes_generate_or_are_refused(bytes)));
}

#[test]
fn any_value_of_the_description_changed_generates_or_is_refused_with_a_path() {
    bolero::check!()
        .with_type::<(u8, String)>()
        .for_each(|(which, value)| {
            assert!(cw_gen::spec::a_changed_value_generates_or_names_paths(
                usize::from(*which),
                value
            ))
        });
}

#[test]
fn references_to_the_wrong_kind_of_container_are_refused() {
    let wrong = ECU.replacen(
        "/CollisionWarning/EcucValues/Os/RES_RTE</VALUE-REF>",
        "/CollisionWarning/EcucValues/Os/OsComTask</VALUE-REF>",
        1,
    );
    assert_eq!(
        refused(&wrong),
        ["OsTaskResourceRef points to /CollisionWarning/EcucValues/Os/OsComTask, whose definition is OsTask: it must be OsResource\n  at /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
}

#[test]
fn what_the_bus_and_the_main_functions_cannot_carry_is_refused() {
    // The two ends of a route of different lengths.
    assert_eq!(
        refused(&with_value("PduLength", 3, "8")),
        ["routing path ThresholdConfig_Rx joins PDU ThresholdConfig_CanIf of 4 bytes to PDU ThresholdConfig_Com of 8: both ends have one length\n  at /CollisionWarning/EcucValues/PduR/PduRRoutingPaths/ThresholdConfig_Rx\n  and /CollisionWarning/EcucValues/EcuC/EcucConfigSet/EcucPduCollection/ThresholdConfig_CanIf\n  and /CollisionWarning/EcucValues/EcuC/EcucConfigSet/EcucPduCollection/ThresholdConfig_Com"]
    );
    // Com's two main functions at two periods.
    assert_eq!(
        refused(&with_value("ComRxTimeBase", 0, "0.02")),
        ["ComRxTimeBase 20 ms differs from ComTxTimeBase 10 ms: the ECU runs both main functions in one task\n  at /CollisionWarning/EcucValues/Com/ComConfig/ComTimeBase"]
    );
    // A time between main functions.
    assert_eq!(
        refused(&with_value("ComMinimumDelayTime", 0, "0.005")),
        ["I-PDU DistanceFrame's minimum delay time is not a whole number of Com's 10 ms main periods\n  at /CollisionWarning/EcucValues/Com/ComConfig/DistanceFrame"]
    );
    // An init value wider than its signal.
    assert_eq!(
        refused(&with_value("ComSignalInitValue", 1, "300")),
        ["signal WarningLevel's ComSignalInitValue 300 does not fit its 8 bits\n  at /CollisionWarning/EcucValues/Com/ComConfig/WarningLevel"]
    );
    // A bit rate and segments the controller cannot have.
    assert_eq!(
        refused(&with_value("CanControllerBaudRate", 0, "2000")),
        ["CAN controller CanController at 2000 kbit/s: 1..=1000 can be configured\n  at /CollisionWarning/EcucValues/Can/CanConfigSet/CanController"]
    );
    assert_eq!(
        refused(&with_value("CanControllerSeg2", 0, "0")),
        ["CAN controller CanController: segments 7+6+0 tq and the synchronisation quantum: each segment at least 1, the bit 8..=25 tq\n  at /CollisionWarning/EcucValues/Can/CanConfigSet/CanController"]
    );
}

#[test]
fn two_items_generated_as_one_constant_are_refused() {
    // A resource whose constant is a task's.
    let renamed = ECU.replace("RES_LEDS", "OsLedTask");
    assert_eq!(
        refused(&renamed),
        ["two items of os would both be generated as the constant OS_LED_TASK: rename one\n  at /CollisionWarning/EcucValues/Os/OsLedTask\n  and /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
}

#[test]
fn a_big_endian_signal_is_placed_by_its_most_significant_bit() {
    // RedBelow as a Motorola signal: ComBitPosition names its most significant bit, as
    // the DBC's start bit and the System Template's startPosition do.
    let moto = with_value("ComSignalEndianness", 2, "BIG_ENDIAN");
    let at = moto
        .match_indices("/ComBitPosition</DEFINITION-REF>")
        .nth(2)
        .map(|(i, _)| i)
        .expect("RedBelow's position");
    let open = at + moto[at..].find("<VALUE>").expect("value") + "<VALUE>".len();
    let close = open + moto[open..].find("</VALUE>").expect("end");
    let moto = format!("{}7{}", &moto[..open], &moto[close..]);
    let out = cw_gen::generate(moto.as_bytes(), "ecu.arxml").expect("it generates");
    assert!(out
        .rust
        .contains("cw_core::signal_layout!(8; 7, 16, ByteOrder::Motorola, Signedness::Unsigned)"));
    assert_eq!(
        validate::signal_bits(7, 16, cw_gen::model::Endianness::Big, 4),
        Some(vec![7, 6, 5, 4, 3, 2, 1, 0, 15, 14, 13, 12, 11, 10, 9, 8])
    );
    // At bit 0 it runs into the next bytes' high bits, here past the PDU's end.
    assert_eq!(
        validate::signal_bits(24, 16, cw_gen::model::Endianness::Big, 4),
        None
    );
}

#[test]
fn one_received_pdu_routed_to_two_i_pdus_fans_out() {
    let mut ecu = arxml::read(ECU.as_bytes(), "ecu.arxml").expect("reads").ecu;
    let mut second = ecu.com.ipdus[1].clone();
    second.name = "ThresholdCopy".into();
    second.pdu = "ThresholdConfig_Copy".into();
    second.signals.clear();
    ecu.com.ipdus.push(second);
    let mut pdu = ecu.pdus[3].clone();
    pdu.name = "ThresholdConfig_Copy".into();
    ecu.pdus.push(pdu);
    ecu.routes[1].dests.push("ThresholdConfig_Copy".into());
    assert_eq!(validate::check(&ecu), Vec::new());
    let rust = cw_gen::rust::emit(&ecu, "ecu.arxml", "-").expect("emits");
    assert!(
        rust.contains("RxRoute::FanOut(&[RxIpduId(0), RxIpduId(1)])"),
        "{rust}"
    );
    // And it writes and reads back as it was.
    let text = arxml::write(&ecu, "CollisionWarning").expect("writes");
    assert_eq!(
        arxml::read(text.as_bytes(), "x.arxml")
            .expect("reads")
            .ecu
            .routes,
        ecu.routes
    );
}

#[test]
fn times_are_read_exactly_as_whole_milliseconds() {
    for (text, ms) in [
        ("0.01", Some(10)),
        ("0.020", Some(20)),
        ("1", Some(1000)),
        ("1.5E-2", Some(15)),
        ("2e-3", Some(2)),
        ("+0.04", Some(40)),
        ("0", Some(0)),
        ("0.0", Some(0)),
        ("4294967.295", Some(4_294_967_295)),
        ("4294967.296", None),
        ("0.0205", None),
        ("1E-4", None),
        ("-0.01", None),
        ("0.01.0", None),
        ("", None),
        (".", None),
        ("NaN", None),
        ("1e", None),
        ("123456789012345678901234567890", None),
        // A double printed with its 17 digits, zeros in odd places, -0.
        ("0.10000000000000001", Some(100)),
        ("0.020000000000000004", Some(20)),
        ("0e2147483647", Some(0)),
        ("1.", Some(1000)),
        (".5", Some(500)),
        ("007", Some(7000)),
        ("-0", Some(0)),
        ("0.0205000000000001", None),
    ] {
        assert_eq!(arxml::parse_ms(text), ms, "{text}");
    }
}

#[test]
fn a_signal_wider_than_its_type_is_refused() {
    // DistanceFrame's WarningLevel (8 bits) typed BOOLEAN.
    let text = with_value("ComSignalType", 1, "BOOLEAN");
    assert_eq!(
        refused(&text),
        ["signal WarningLevel has 8 bits, more than its ComSignalType's 1\n  at /CollisionWarning/EcucValues/Com/ComConfig/WarningLevel"]
    );
}

#[test]
fn a_received_signals_transfer_property_is_a_note_not_dropped() {
    let at = ECU
        .find("<SHORT-NAME>RedBelow</SHORT-NAME>")
        .expect("RedBelow");
    let params = at
        + ECU[at..]
            .find("<PARAMETER-VALUES>")
            .expect("its parameters")
        + "<PARAMETER-VALUES>".len();
    let text = format!(
        "{}<ECUC-TEXTUAL-PARAM-VALUE><DEFINITION-REF DEST=\"ECUC-ENUMERATION-PARAM-DEF\">/AUTOSAR/EcucDefs/Com/ComConfig/ComSignal/ComTransferProperty</DEFINITION-REF><VALUE>TRIGGERED</VALUE></ECUC-TEXTUAL-PARAM-VALUE>{}",
        &ECU[..params],
        &ECU[params..]
    );
    let read = arxml::read(text.as_bytes(), "ecu.arxml").expect("it reads");
    assert_eq!(
        read.notes,
        ["/CollisionWarning/EcucValues/Com/ComConfig/RedBelow: parameter ComTransferProperty is not used: RedBelow is received (in I-PDU ThresholdConfig), and the property applies to sent signals"]
    );
}
