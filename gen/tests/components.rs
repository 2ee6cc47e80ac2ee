//! The software components' description (`firmware/swc.arxml`) read and generated into the
//! RTE, and refused with the paths named wherever it is changed into something the RTE
//! cannot be generated from.

use cw_gen::rte;
use cw_gen::spec::{self, COMPONENTS, ECU};

/// The RTE generated from `text` and the ECU's committed description.
fn rte_of(text: &str) -> Result<cw_gen::Generated, cw_gen::Refused> {
    cw_gen::generate_rte(text.as_bytes(), "swc.arxml", ECU.as_bytes(), "ecu.arxml")
}

/// What `text` generates; it must.
fn generated(text: &str) -> cw_gen::Generated {
    rte_of(text).expect("it generates")
}

/// Every error of generating the RTE from `text`, as the user sees them.
fn refused(text: &str) -> Vec<String> {
    match rte_of(text) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(ToString::to_string).collect(),
    }
}

/// `COMPONENTS` with `from` (which must be there, once) replaced by `to`.
fn edited(from: &str, to: &str) -> String {
    assert_eq!(COMPONENTS.matches(from).count(), 1, "{from}");
    COMPONENTS.replacen(from, to, 1)
}

const PKG: &str = "/CollisionWarning/SwComponentTypes";

#[test]
fn the_components_read_check_and_generate_the_rte_the_ecu_uses() {
    let sw = rte::read(COMPONENTS.as_bytes(), "swc.arxml").expect("the description reads");
    let ecu = cw_gen::arxml::read(ECU.as_bytes(), "ecu.arxml")
        .expect("reads")
        .ecu;
    assert_eq!(rte::check(&sw, &ecu), Vec::new());
    assert_eq!(sw.components.len(), 6);
    assert_eq!(sw.composition.prototypes.len(), 7);
    assert_eq!(sw.composition.connectors.len(), 6);
    let fields: Vec<(String, Option<u64>, bool, usize)> = rte::buffers(&sw)
        .into_iter()
        .map(|b| (b.field, b.queue, b.notify, b.carries.len()))
        .collect();
    assert_eq!(
        fields,
        [
            // One buffer for the sender's plain receivers (ObstacleDetection), one for the
            // receiver whose runnable a data-received event starts (CanTranslate).
            ("ultra_sonic_sonar_data".to_string(), None, false, 1),
            ("can_translate_sonar_recv".to_string(), None, true, 1),
            // RedLED, YellowLED and CanTranslate read the newest level from one buffer.
            ("obstacle_detection_led_request".to_string(), None, false, 3),
            ("bswm_mode_request".to_string(), Some(4), false, 1),
        ]
    );
    let out = generated(COMPONENTS);
    assert!(out.rust.contains(
        "ultra_sonic_sonar_data: LastIsBest::new(cw_core::warning::Measurement::Invalid, false)"
    ));
    assert!(out.rust.contains(&format!(
        "/// UltraSonic.SonarData -> CanTranslate.SonarRecv ({PKG}/CollisionWarning/UltraSonic_SonarData_CanTranslate_SonarRecv)"
    )));
    assert!(out.rust.contains("type Data = cw_core::ecum::BswMRequest;"));
    // Each prototype's context has its ports, in their directions, and no other.
    for method in [
        "impl UltraSonicPorts for UltraSonicContext<'_> {\n    /// Writes `ultra_sonic_sonar_data`, `can_translate_sonar_recv`.",
        "fn write_sonar_data(&mut self, value: cw_core::warning::Measurement) {\n        let _ = self.rte.ultra_sonic_sonar_data.write(value);\n        if self.rte.can_translate_sonar_recv.write(value).0 {\n            self.released.0 |= 0x1;\n        }",
        "fn take_sonar_recv(&mut self) -> Result<cw_core::warning::Measurement, RteError>",
        "fn send_mode_request(&mut self, value: cw_core::ecum::BswMRequest) -> Result<(), RteError>",
        "fn receive_mode_request(&mut self) -> Result<cw_core::ecum::BswMRequest, RteError>",
        // Only the task bodies make an application prototype's context; the BSW's is public.
        "\n    fn red_led(&mut self) -> RedLedContext<'_>",
        "\n    pub fn bswm(&mut self) -> BswmContext<'_>",
        // A component type's runnables, taking its type's ports.
        "pub trait LedActuatorRunnables {",
        "fn led_actuator_runnable(&mut self, ports: &mut impl LedActuatorPorts);",
        // The task bodies: each runnable in its position, on its prototype's component.
        "pub fn os_led_task(\n        rte: &mut Rte,\n        red_led: &mut impl LedActuatorRunnables,\n        yellow_led: &mut impl LedActuatorRunnables,\n    ) -> Released {\n        red_led.led_actuator_runnable(&mut rte.red_led());\n        yellow_led.led_actuator_runnable(&mut rte.yellow_led());\n        Released::NONE\n    }",
        "let mut ports = rte.ultra_sonic();\n        ultra_sonic.ultra_sonic_runnable(&mut ports);\n        released.0 |= ports.released.0;",
        "pub const ACTIVATED: [TaskId; 1] = [os::OS_COM_TASK];",
    ] {
        assert!(out.rust.contains(method), "{method}");
    }
    let red = out
        .rust
        .find("impl LedActuatorPorts for RedLedContext<'_> {")
        .expect("RedLED's ports");
    let red = &out.rust[red..red + out.rust[red..].find("\n}\n").expect("their end")];
    assert_eq!(red.matches("fn ").count(), 1, "{red}");
    assert!(red.contains("fn read_led_request(&self) -> cw_core::warning::WarningLevel"));
}

#[test]
fn names_become_snake_case_fields() {
    for (name, snake) in [
        ("UltraSonic", "ultra_sonic"),
        ("LEDActuator", "led_actuator"),
        ("RedLED", "red_led"),
        ("BswM", "bswm"),
        ("SonarRecv", "sonar_recv"),
        ("Can2Bus", "can2_bus"),
    ] {
        assert_eq!(rte::snake(name), snake);
    }
}

#[test]
fn a_required_port_connected_to_nothing_is_refused_with_its_path() {
    // The connector into RedLED removed.
    let start = COMPONENTS
        .find("<ASSEMBLY-SW-CONNECTOR>\n                  <SHORT-NAME>ObstacleDetection_LedRequest_RedLED_LedRequest")
        .expect("the connector");
    let end = start
        + COMPONENTS[start..]
            .find("</ASSEMBLY-SW-CONNECTOR>")
            .expect("its end")
        + "</ASSEMBLY-SW-CONNECTOR>".len();
    let text = format!("{}{}", &COMPONENTS[..start], &COMPONENTS[end..]);
    assert_eq!(
        refused(&text),
        [format!(
            "required port RedLED.LedRequest is connected to nothing\n  at {PKG}/LEDActuator/LedRequest\n  and {PKG}/CollisionWarning/RedLED"
        )]
    );
}

#[test]
fn two_writers_of_one_port_are_refused_naming_both_connectors() {
    // A second sensor (a rear UltraSonic) wired to the same receiver.
    let text = edited(
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>ObstacleDetection</SHORT-NAME>",
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>RearSonic</SHORT-NAME>\n                  <TYPE-TREF DEST=\"APPLICATION-SW-COMPONENT-TYPE\">/CollisionWarning/SwComponentTypes/UltraSonic</TYPE-TREF>\n                </SW-COMPONENT-PROTOTYPE>\n                <SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>ObstacleDetection</SHORT-NAME>",
    );
    let text = text.replacen(
        "<CONNECTORS>",
        &format!(
            "<CONNECTORS>\n<ASSEMBLY-SW-CONNECTOR><SHORT-NAME>Rear</SHORT-NAME><PROVIDER-IREF><CONTEXT-COMPONENT-REF DEST=\"SW-COMPONENT-PROTOTYPE\">{PKG}/CollisionWarning/RearSonic</CONTEXT-COMPONENT-REF><TARGET-P-PORT-REF DEST=\"P-PORT-PROTOTYPE\">{PKG}/UltraSonic/SonarData</TARGET-P-PORT-REF></PROVIDER-IREF><REQUESTER-IREF><CONTEXT-COMPONENT-REF DEST=\"SW-COMPONENT-PROTOTYPE\">{PKG}/CollisionWarning/ObstacleDetection</CONTEXT-COMPONENT-REF><TARGET-R-PORT-REF DEST=\"R-PORT-PROTOTYPE\">{PKG}/ObstacleDetection/SonarData</TARGET-R-PORT-REF></REQUESTER-IREF></ASSEMBLY-SW-CONNECTOR>"
        ),
        1,
    );
    // (The new sensor's runnable is mapped to no task either.)
    assert_eq!(
        refused(&text),
        [
            format!(
                "required port ObstacleDetection.SonarData has two writers, RearSonic.SonarData and UltraSonic.SonarData: a non-queued port has one\n  at {PKG}/ObstacleDetection/SonarData\n  and {PKG}/CollisionWarning/Rear\n  and {PKG}/CollisionWarning/UltraSonic_SonarData_ObstacleDetection_SonarData"
            ),
            format!(
                "runnable RearSonic.UltraSonicRunnable (Every40ms) is mapped to no task: it would never run\n  at {PKG}/UltraSonic/UltraSonicBehavior/Every40ms\n  and {PKG}/CollisionWarning/RearSonic\n  and /CollisionWarning/EcucValues/Rte"
            ),
        ]
    );
}

#[test]
fn a_connector_between_ports_of_two_interfaces_is_refused() {
    // The level's connector into CanTranslate aimed at its distance port instead.
    let text = edited(
        &format!("{PKG}/CanTranslate/LedRequest</TARGET-R-PORT-REF>"),
        &format!("{PKG}/CanTranslate/SonarRecv</TARGET-R-PORT-REF>"),
    );
    let errors = refused(&text);
    assert!(
        errors.contains(&format!(
            "connector joins ObstacleDetection.LedRequest (LedRequestInterface) to CanTranslate.SonarRecv (SonarDataInterface): a connector joins ports of one interface\n  at {PKG}/CollisionWarning/ObstacleDetection_LedRequest_CanTranslate_LedRequest\n  and {PKG}/ObstacleDetection/LedRequest\n  and {PKG}/CanTranslate/SonarRecv"
        )),
        "{errors:#?}"
    );
    // CanTranslate's level port is then connected to nothing, its distance port twice.
    assert!(errors
        .iter()
        .any(|e| e.starts_with("required port CanTranslate.LedRequest is connected to nothing")));
}

#[test]
fn what_the_rte_cannot_carry_is_refused_with_its_path() {
    let cases = [
        (
            edited(
                "<SD GID=\"RustType\">cw_core::warning::Measurement</SD>",
                "<SD GID=\"RustType\">cw_core::warning::Measure ment</SD>",
            ),
            "data type's Rust type `cw_core::warning::Measure ment` is not a Rust path\n  at /CollisionWarning/DataTypes/Measurement".to_string(),
        ),
        (
            edited("<QUEUE-LENGTH>4</QUEUE-LENGTH>", "<QUEUE-LENGTH>0</QUEUE-LENGTH>"),
            format!("queued port BswM.ModeRequest: a QUEUE-LENGTH of 1..=64 is needed (it has 0)\n  at {PKG}/BswM/ModeRequest\n  and /CollisionWarning/PortInterfaces/ModeRequestInterface"),
        ),
        (
            edited("<PERIOD>0.02</PERIOD>", "<PERIOD>0.0205</PERIOD>"),
            format!("timing event period `0.0205`: a whole number of ms above 0, in seconds, can be generated\n  at {PKG}/ObstacleDetection/ObstacleDetectionBehavior/Every20ms"),
        ),
        (
            edited(
                &format!("<START-ON-EVENT-REF DEST=\"RUNNABLE-ENTITY\">{PKG}/LEDActuator/LEDActuatorBehavior/LEDActuatorRunnable</START-ON-EVENT-REF>"),
                &format!("<START-ON-EVENT-REF DEST=\"RUNNABLE-ENTITY\">{PKG}/LEDActuator/LEDActuatorBehavior/Blink</START-ON-EVENT-REF>"),
            ),
            format!("START-ON-EVENT-REF {PKG}/LEDActuator/LEDActuatorBehavior/Blink refers to nothing in the description\n  at {PKG}/LEDActuator/LEDActuatorBehavior/Every10ms"),
        ),
    ];
    for (text, expected) in cases {
        let errors = refused(&text);
        assert!(
            errors.contains(&expected),
            "{expected}\nnot in\n{errors:#?}"
        );
    }
    // A second runnable of the LED, which no event starts.
    let text = edited(
        "<SHORT-NAME>LEDActuatorRunnable</SHORT-NAME>",
        "<SHORT-NAME>Blink</SHORT-NAME>\n<SYMBOL>Blink</SYMBOL>\n</RUNNABLE-ENTITY>\n<RUNNABLE-ENTITY>\n<SHORT-NAME>LEDActuatorRunnable</SHORT-NAME>",
    );
    assert_eq!(
        refused(&text),
        [format!("runnable LEDActuator.Blink is started by no event: it would never run\n  at {PKG}/LEDActuator/LEDActuatorBehavior/Blink")]
    );
}

#[test]
fn a_kind_of_element_the_rte_does_not_generate_is_refused_never_dropped() {
    let text = edited(
        "<SENDER-RECEIVER-INTERFACE>\n              <SHORT-NAME>LedRequestInterface</SHORT-NAME>",
        "<CLIENT-SERVER-INTERFACE>\n              <SHORT-NAME>Calibration</SHORT-NAME>\n            </CLIENT-SERVER-INTERFACE>\n            <SENDER-RECEIVER-INTERFACE>\n              <SHORT-NAME>LedRequestInterface</SHORT-NAME>",
    );
    assert_eq!(
        refused(&text),
        ["CLIENT-SERVER-INTERFACE cannot be mapped onto the ECU's components\n  at /CollisionWarning/PortInterfaces/Calibration"]
    );
}

#[test]
fn any_text_of_the_components_changed_generates_or_is_refused_with_a_path() {
    bolero::check!()
        .with_type::<(u8, u8, String)>()
        .for_each(|(tag, which, value)| {
            assert!(spec::a_changed_component_generates_or_names_paths(
                usize::from(*tag),
                usize::from(*which),
                value
            ));
        });
}

/// The mapping container of `instance` (`<prototype>Instance`), whole.
fn mapping_of(instance: &str) -> (usize, usize) {
    let at = COMPONENTS
        .find(&format!("<SHORT-NAME>{instance}Instance</SHORT-NAME>"))
        .expect("the instance");
    let start = at
        + COMPONENTS[at..]
            .find("<SUB-CONTAINERS>")
            .expect("its mappings")
        + "<SUB-CONTAINERS>".len();
    let end = start
        + COMPONENTS[start..]
            .find("</SUB-CONTAINERS>")
            .expect("their end");
    (start, end)
}

/// `COMPONENTS` with `from` replaced by `to` inside `instance`'s mappings.
fn in_mapping(instance: &str, from: &str, to: &str) -> String {
    let (start, end) = mapping_of(instance);
    let inside = &COMPONENTS[start..end];
    assert_eq!(inside.matches(from).count(), 1, "{from}");
    format!(
        "{}{}{}",
        &COMPONENTS[..start],
        inside.replacen(from, to, 1),
        &COMPONENTS[end..]
    )
}

const RTE: &str = "/CollisionWarning/EcucValues/Rte";
const OS: &str = "/CollisionWarning/EcucValues/Os";

#[test]
fn the_runnables_tasks_are_generated_from_the_rte_mapping() {
    let out = generated(COMPONENTS);
    assert!(out.rust.contains("/// | `OsLEDTask` | RedLED.LEDActuatorRunnable (every 10 ms), YellowLED.LEDActuatorRunnable (every 10 ms) |"));
    assert!(out
        .rust
        .contains("pub const CAN_TRANSLATE_SONAR_RECV: TaskId = os::OS_COM_TASK;"));
    assert!(out.rust.contains(
        "pub const RELEASED_BY: [(TaskId, TaskId); 1] = [(os::OS_COM_TASK, os::OS_SONAR_TASK)];"
    ));
}

#[test]
fn a_runnable_mapped_to_no_task_or_twice_is_refused() {
    // ObstacleDetection's mapping removed.
    let (start, end) = mapping_of("ObstacleDetection");
    let text = format!("{}{}", &COMPONENTS[..start], &COMPONENTS[end..]);
    assert_eq!(
        refused(&text),
        [format!("runnable ObstacleDetection.ObstacleDetectionRunnable (Every20ms) is mapped to no task: it would never run\n  at {PKG}/ObstacleDetection/ObstacleDetectionBehavior/Every20ms\n  and {PKG}/CollisionWarning/ObstacleDetection\n  and {RTE}")]
    );
    // RedLED's mapping written twice, the second in another position.
    let (start, end) = mapping_of("RedLED");
    let twice = COMPONENTS[start..end]
        .replace("Every10msMapping", "AgainMapping")
        .replace("<VALUE>0</VALUE>", "<VALUE>2</VALUE>");
    let text = format!("{}{twice}{}", &COMPONENTS[..end], &COMPONENTS[end..]);
    assert_eq!(
        refused(&text),
        [format!("runnable RedLED.LEDActuatorRunnable (Every10ms) is mapped twice: an event runs its runnable in one task, once\n  at {RTE}/RedLEDInstance/Every10msMapping\n  and {RTE}/RedLEDInstance/AgainMapping")]
    );
}

#[test]
fn a_runnable_in_a_task_of_another_period_or_kind_is_refused() {
    let errors = refused(&in_mapping(
        "ObstacleDetection",
        &format!("{OS}/OsObstacleDetectionTask<"),
        &format!("{OS}/OsLEDTask<"),
    ));
    // (It also takes RedLED's position 0 in that task.)
    assert_eq!(
        errors,
        [
            format!("runnable ObstacleDetection.ObstacleDetectionRunnable runs every 20 ms (Every20ms), but task OsLEDTask runs every 10 ms\n  at {RTE}/ObstacleDetectionInstance/Every20msMapping\n  and {PKG}/ObstacleDetection/ObstacleDetectionBehavior/Every20ms\n  and {OS}/OsLEDTask"),
            format!("two runnables at position 0 of task {OS}/OsLEDTask\n  at {RTE}/RedLEDInstance/Every10msMapping\n  and {RTE}/ObstacleDetectionInstance/Every20msMapping"),
        ]
    );
    let errors = refused(&in_mapping(
        "CanTranslate",
        &format!("{OS}/OsComTask<"),
        &format!("{OS}/OsSonarTask<"),
    ));
    assert!(
        errors.contains(&format!("runnable CanTranslate.CanTranslateRunnable runs when SonarRecv receives data, but task OsSonarTask runs every 40 ms: the RTE activates a data-received event's task\n  at {RTE}/CanTranslateInstance/OnSonarRecvMapping\n  and {PKG}/CanTranslate/CanTranslateBehavior/OnSonarRecv\n  and {OS}/OsSonarTask")),
        "{errors:#?}"
    );
    let errors = refused(&in_mapping(
        "ModeManager",
        &format!("{OS}/OsBswServiceTask<"),
        &format!("{OS}/OsNoSuchTask<"),
    ));
    assert_eq!(
        errors,
        [format!("RteMappedToTaskRef {OS}/OsNoSuchTask is not a task of the OS's description\n  at {RTE}/ModeManagerInstance/Every10msMapping")]
    );
    let errors = refused(&in_mapping(
        "YellowLED",
        "<VALUE>1</VALUE>",
        "<VALUE>0</VALUE>",
    ));
    assert_eq!(
        errors,
        [format!("two runnables at position 0 of task {OS}/OsLEDTask\n  at {RTE}/YellowLEDInstance/Every10msMapping\n  and {RTE}/RedLEDInstance/Every10msMapping")]
    );
}

#[test]
fn names_generated_as_one_rust_item_are_refused() {
    // A prototype `Red_LED` beside `RedLED`: both `rte.red_led()`.
    let text = edited(
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>YellowLED</SHORT-NAME>",
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>Red_LED</SHORT-NAME>\n                  <TYPE-TREF DEST=\"APPLICATION-SW-COMPONENT-TYPE\">/CollisionWarning/SwComponentTypes/LEDActuator</TYPE-TREF>\n                </SW-COMPONENT-PROTOTYPE>\n                <SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>YellowLED</SHORT-NAME>",
    );
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("two prototypes would be generated as `rte.red_led()`\n  at {PKG}/CollisionWarning/Red_LED\n  and {PKG}/CollisionWarning/RedLED")),
        "{errors:#?}"
    );
    // An interface named as the RTE itself.
    let text = COMPONENTS.replace("SonarDataInterface", "Rte");
    let errors = refused(&text);
    assert!(
        errors.contains(&"interface Rte has the name of an item the generated RTE defines or uses\n  at /CollisionWarning/PortInterfaces/Rte".to_string()),
        "{errors:#?}"
    );
    // An interface named as a component type's generated trait.
    let text = COMPONENTS.replace("SonarDataInterface", "LedActuatorRunnables");
    let errors = refused(&text);
    assert!(
        errors.contains(&"interface LedActuatorRunnables has the name of an item the generated RTE defines or uses\n  at /CollisionWarning/PortInterfaces/LedActuatorRunnables".to_string()),
        "{errors:#?}"
    );
    // A prototype named as a task body's parameter or local.
    for name in ["Rte", "Ports", "Released"] {
        let text = COMPONENTS.replace("YellowLED", name);
        let errors = refused(&text);
        let method = name.to_lowercase();
        assert!(
            errors.contains(&format!("prototype {name} would be generated as `rte.{method}()`, a name Rust or the RTE already has\n  at {PKG}/CollisionWarning/{name}")),
            "{errors:#?}"
        );
    }
    // Two component types as one trait.
    let text = COMPONENTS.replace("ModeManager", "LED_Actuator");
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("two component types would be generated as one trait `LedActuatorPorts`\n  at {PKG}/LED_Actuator\n  and {PKG}/LEDActuator")),
        "{errors:#?}"
    );
}

#[test]
fn references_of_the_wrong_kind_or_place_and_specs_of_the_wrong_kind_are_refused() {
    // The LED's event starting ObstacleDetection's runnable.
    let text = edited(
        &format!("<START-ON-EVENT-REF DEST=\"RUNNABLE-ENTITY\">{PKG}/LEDActuator/LEDActuatorBehavior/LEDActuatorRunnable</START-ON-EVENT-REF>"),
        &format!("<START-ON-EVENT-REF DEST=\"RUNNABLE-ENTITY\">{PKG}/ObstacleDetection/ObstacleDetectionBehavior/ObstacleDetectionRunnable</START-ON-EVENT-REF>"),
    );
    assert!(refused(&text).contains(&format!(
        "the event starts {PKG}/ObstacleDetection/ObstacleDetectionBehavior/ObstacleDetectionRunnable, which is not a runnable of its component's behaviour\n  at {PKG}/LEDActuator/LEDActuatorBehavior/Every10ms"
    )));
    // ModeManager's queued data sent with a non-queued com spec.
    let text = edited(
        "<QUEUED-SENDER-COM-SPEC>\n                      <DATA-ELEMENT-REF DEST=\"VARIABLE-DATA-PROTOTYPE\">/CollisionWarning/PortInterfaces/ModeRequestInterface/Request</DATA-ELEMENT-REF>\n                    </QUEUED-SENDER-COM-SPEC>",
        "<NONQUEUED-SENDER-COM-SPEC>\n                      <DATA-ELEMENT-REF DEST=\"VARIABLE-DATA-PROTOTYPE\">/CollisionWarning/PortInterfaces/ModeRequestInterface/Request</DATA-ELEMENT-REF>\n                    </NONQUEUED-SENDER-COM-SPEC>",
    );
    assert_eq!(
        refused(&text),
        [format!("port ModeManager.ModeRequest has a non-queued com spec for the queued data of interface ModeRequestInterface\n  at {PKG}/ModeManager/ModeRequest\n  and /CollisionWarning/PortInterfaces/ModeRequestInterface")]
    );
    // No Rte module at all.
    let start = COMPONENTS
        .find("<AR-PACKAGE>\n          <SHORT-NAME>EcucValues</SHORT-NAME>")
        .expect("the Rte's package");
    let end =
        start + COMPONENTS[start..].find("</AR-PACKAGE>").expect("its end") + "</AR-PACKAGE>".len();
    let text = format!("{}{}", &COMPONENTS[..start], &COMPONENTS[end..]);
    assert_eq!(
        refused(&text),
        ["the description has no Rte module: no runnable is mapped to a task\n  at swc.arxml"]
    );
}

#[test]
fn what_the_rte_reads_but_does_not_use_is_a_note() {
    assert_eq!(generated(COMPONENTS).notes, Vec::<String>::new());
    let text = edited(
        "<SHORT-NAME>LEDActuatorRunnable</SHORT-NAME>\n                      <MINIMUM-START-INTERVAL>0</MINIMUM-START-INTERVAL>",
        "<SHORT-NAME>LEDActuatorRunnable</SHORT-NAME>\n                      <MINIMUM-START-INTERVAL>0.005</MINIMUM-START-INTERVAL>",
    );
    assert_eq!(
        generated(&text).notes,
        [format!("{PKG}/LEDActuator/LEDActuatorBehavior/LEDActuatorRunnable: MINIMUM-START-INTERVAL `0.005` is not used by the generated RTE")]
    );
}

#[test]
fn names_the_traits_contexts_and_task_bodies_would_share_are_refused() {
    // A runnable named as a keyword.
    let text = COMPONENTS.replace("LEDActuatorRunnable", "Loop");
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("runnable Loop of LEDActuator would be generated as the keyword `loop`\n  at {PKG}/LEDActuator/LEDActuatorBehavior/Loop")),
        "{errors:#?}"
    );
    // A prototype named as a measurement accessor.
    let text = COMPONENTS.replace("YellowLED", "PeekLevel");
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("prototype PeekLevel would be generated as `rte.peek_level()`, a name Rust or the RTE already has\n  at {PKG}/CollisionWarning/PeekLevel")),
        "{errors:#?}"
    );
    // Interfaces named as an item of the prelude the module uses, or as a context.
    for name in ["Ok", "Released", "RedLedContext", "tasks"] {
        let text = COMPONENTS.replace("SonarDataInterface", name);
        let errors = refused(&text);
        assert!(
            errors.contains(&format!("interface {name} has the name of an item the generated RTE defines or uses\n  at /CollisionWarning/PortInterfaces/{name}")),
            "{errors:#?}"
        );
    }
    // Two prototypes with two accessors but one context: `red_led()` and `red__led()`,
    // both `RedLedContext`.
    let text = edited(
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>YellowLED</SHORT-NAME>",
        "<SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>Red__LED</SHORT-NAME>\n                  <TYPE-TREF DEST=\"APPLICATION-SW-COMPONENT-TYPE\">/CollisionWarning/SwComponentTypes/LEDActuator</TYPE-TREF>\n                </SW-COMPONENT-PROTOTYPE>\n                <SW-COMPONENT-PROTOTYPE>\n                  <SHORT-NAME>YellowLED</SHORT-NAME>",
    );
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("two prototypes would be generated as one context `RedLedContext`\n  at {PKG}/CollisionWarning/Red__LED\n  and {PKG}/CollisionWarning/RedLED")),
        "{errors:#?}"
    );
    // Two tasks whose bodies would be one function (`OsLEDTask` and `OsLedTask`).
    let text = in_mapping(
        "YellowLED",
        &format!("{OS}/OsLEDTask<"),
        &format!("{OS}/OsLedTask<"),
    );
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("two tasks' bodies would be generated as one function `os_led_task`\n  at {OS}/OsLedTask\n  and {OS}/OsLEDTask")),
        "{errors:#?}"
    );
}

#[test]
fn two_data_received_events_on_one_port_are_refused() {
    let event = COMPONENTS
        .find("<DATA-RECEIVED-EVENT>")
        .expect("the data-received event");
    let end = event
        + COMPONENTS[event..]
            .find("</DATA-RECEIVED-EVENT>")
            .expect("its end")
        + "</DATA-RECEIVED-EVENT>".len();
    let again = COMPONENTS[event..end].replace(
        "<SHORT-NAME>OnSonarRecv</SHORT-NAME>",
        "<SHORT-NAME>OnSonarRecvAgain</SHORT-NAME>",
    );
    let text = format!("{}\n{again}{}", &COMPONENTS[..end], &COMPONENTS[end..]);
    let errors = refused(&text);
    assert!(
        errors.contains(&format!("two data-received events on CanTranslate.SonarRecv: one buffer notes new data, for one event\n  at {PKG}/CanTranslate/CanTranslateBehavior/OnSonarRecvAgain\n  and {PKG}/CanTranslate/CanTranslateBehavior/OnSonarRecv")),
        "{errors:#?}"
    );
}
