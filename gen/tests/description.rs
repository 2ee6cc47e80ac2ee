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
        ["two tasks have priority 6: the ECU's OS runs one task per priority (BCC1, ECC1)\n  at /CollisionWarning/EcucValues/Os/OsBswServiceTask\n  and /CollisionWarning/EcucValues/Os/OsLEDTask"]
    );
    // A priority outside the kernel's, an ISR priority outside the port's.
    assert_eq!(
        refused(&with_value("OsTaskPriority", 0, "300")),
        ["task OsStartupTask has priority 300, above the kernel's 255\n  at /CollisionWarning/EcucValues/Os/OsStartupTask"]
    );
    assert_eq!(
        refused(&with_value("OsIsrInterruptPriority", 0, "16")),
        ["ISR SysTickIsr has priority 16, outside the port's 1..=15\n  at /CollisionWarning/EcucValues/Os/SysTickIsr"]
    );
    // Duplicate CAN ids among the received PDUs cannot arise with one; a sent id beyond 11 bits.
    assert_eq!(
        refused(&with_value("CanIfTxPduCanId", 0, "0x800")),
        ["CanIf TX PDU DistanceFrame has CAN id 0x800, more than 11 bits\n  at /CollisionWarning/EcucValues/CanIf/CanIfInitCfg/DistanceFrame"]
    );
    // An alarm whose cycle its counter cannot count.
    assert_eq!(
        refused(&with_value("OsAlarmCycleTime", 3, "70000")),
        ["alarm SonarAlarm starts after 40 and cycles every 70000 ticks, outside counter SystemCounter's 1..=65535\n  at /CollisionWarning/EcucValues/Os/SonarAlarm\n  and /CollisionWarning/EcucValues/Os/SystemCounter"]
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
