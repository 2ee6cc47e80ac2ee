//! The generated RTE compiled, as a user's crate compiles it: for a description changed as a
//! user changes it (a third LED, `RearLED`, added to the composition and mapped into
//! `OsLEDTask`), the generated module and components written against it compile without a
//! warning, and components that break the generated contract do not, with the error the
//! user sees.
//!
//! Each case is a small crate under `target/rte-compile/` (the ECU's generated tables, the
//! generated RTE, the case's components) checked by `cargo check --offline` against
//! `cw-core`, with a target directory of its own: the workspace's is locked while the tests
//! run.

use std::path::{Path, PathBuf};
use std::process::Command;

use cw_gen::spec::{COMPONENTS, ECU};

/// The block of `text` from the `open` line that holds `name` to its `close` tag.
fn block<'a>(text: &'a str, open: &str, close: &str, name: &str) -> &'a str {
    let at = text.find(name).expect("the element's name");
    let start = text[..at].rfind(open).expect("its start");
    let end = at + text[at..].find(close).expect("its end") + close.len();
    &text[start..end]
}

/// The description with `RearLED`, a third LEDActuator: its prototype, its connector from
/// ObstacleDetection and its runnable mapped into `OsLEDTask` after YellowLED's.
fn with_rear_led() -> String {
    let mut text = COMPONENTS.to_string();
    for (open, close, name) in [
        (
            "<SW-COMPONENT-PROTOTYPE>",
            "</SW-COMPONENT-PROTOTYPE>",
            "<SHORT-NAME>YellowLED</SHORT-NAME>",
        ),
        (
            "<ASSEMBLY-SW-CONNECTOR>",
            "</ASSEMBLY-SW-CONNECTOR>",
            "<SHORT-NAME>ObstacleDetection_LedRequest_YellowLED_LedRequest</SHORT-NAME>",
        ),
        (
            "<ECUC-CONTAINER-VALUE>",
            "</SUB-CONTAINERS>\n                </ECUC-CONTAINER-VALUE>",
            "<SHORT-NAME>YellowLEDInstance</SHORT-NAME>",
        ),
    ] {
        let yellow = block(&text, open, close, name).to_string();
        let rear = yellow
            .replace("YellowLED", "RearLED")
            .replace("<VALUE>1</VALUE>", "<VALUE>2</VALUE>");
        text = text.replacen(&yellow, &format!("{yellow}\n{rear}"), 1);
    }
    text
}

/// A crate of the ECU's tables, the RTE generated from `components` and `code`, checked:
/// `Ok` or the compiler's messages.
fn check(case: &str, components: &str, code: &str) -> Result<(), String> {
    let rte = cw_gen::generate_rte(
        components.as_bytes(),
        "swc.arxml",
        ECU.as_bytes(),
        "ecu.arxml",
    )
    .map_err(|e| format!("refused: {e:?}"))?;
    let tables = cw_gen::generate(ECU.as_bytes(), "ecu.arxml").expect("the ECU generates");
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the workspace");
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| workspace.join("target"), PathBuf::from)
        .join("rte-compile");
    let dir = target.join(case);
    let src = dir.join("src");
    std::fs::create_dir_all(&src).expect("the case's directory");
    let core = workspace.join("core");
    let manifest = format!(
        "[package]\nname = \"rte-compile-{case}\"\nversion = \"0.0.0\"\nedition = \"2021\"\npublish = false\n\n[dependencies]\ncw-core = {{ path = {:?} }}\n\n[workspace]\n",
        core.display().to_string()
    );
    let files = [
        (dir.join("Cargo.toml"), manifest),
        (
            src.join("lib.rs"),
            "#![no_std]\n#![deny(warnings)]\npub mod generated;\npub mod rte;\npub mod components;\n"
                .to_string(),
        ),
        (src.join("generated.rs"), tables.rust),
        (src.join("rte.rs"), rte.rust),
        (src.join("components.rs"), code.to_string()),
    ];
    for (path, text) in files {
        std::fs::write(&path, text).expect("the case's file");
    }
    // The workspace's versions of cw-core's dependencies, all in the local registry.
    std::fs::copy(workspace.join("Cargo.lock"), dir.join("Cargo.lock")).expect("the lock file");
    let out = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["check", "--offline", "--quiet", "--message-format", "short"])
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", target.join("target"))
        .env_remove("RUSTFLAGS")
        .output()
        .expect("cargo runs");
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

/// Components for the three LEDs, the detector and the sensor, and a job of each task.
const THREE_LEDS: &str = r#"
use crate::rte::{tasks, LedActuatorPorts, LedActuatorRunnables, Rte};
use cw_core::warning::WarningLevel;

/// An LED: the level its runnable read.
pub struct Led(pub Option<WarningLevel>);

impl LedActuatorRunnables for Led {
    fn led_actuator_runnable(&mut self, ports: &mut impl LedActuatorPorts) {
        self.0 = Some(ports.read_led_request());
    }
}

/// One `OsLEDTask` job: what each LED read.
pub fn led_job(rte: &mut Rte) -> [Option<WarningLevel>; 3] {
    let (mut red, mut yellow, mut rear) = (Led(None), Led(None), Led(None));
    let released = tasks::os_led_task(rte, &mut red, &mut yellow, &mut rear);
    assert!(released.tasks().next().is_none());
    [red.0, yellow.0, rear.0]
}
"#;

#[test]
fn a_changed_description_generates_an_rte_its_components_compile_against() {
    let text = with_rear_led();
    check("three-leds", &text, THREE_LEDS).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn components_that_break_the_generated_contract_do_not_compile() {
    let text = with_rear_led();
    // The task body takes the third LED now: a job written for two does not compile.
    let two = THREE_LEDS.replace(
        "tasks::os_led_task(rte, &mut red, &mut yellow, &mut rear)",
        "tasks::os_led_task(rte, &mut red, &mut yellow)",
    );
    let errors = check("two-leds", &text, &two).expect_err("it must not compile");
    assert!(errors.contains("error[E0061]"), "{errors}");
    // An LED writes the level it only reads.
    let writes = THREE_LEDS.replace(
        "self.0 = Some(ports.read_led_request());",
        "ports.write_led_request(WarningLevel::Red);",
    );
    let errors = check("led-writes", &text, &writes).expect_err("it must not compile");
    assert!(errors.contains("error[E0599]"), "{errors}");
    // A context made outside a task body.
    let made = THREE_LEDS.replace(
        "let released = tasks::os_led_task(rte, &mut red, &mut yellow, &mut rear);",
        "let _ = rte.rear_led();\n    let released = tasks::os_led_task(rte, &mut red, &mut yellow, &mut rear);",
    );
    let errors = check("context-outside", &text, &made).expect_err("it must not compile");
    assert!(errors.contains("error[E0624]"), "{errors}");
}
