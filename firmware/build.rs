//! Stops the build when one of the ECU's descriptions has changed since the Rust generated
//! from it: `ecu.arxml` (the basic software's ECUC values) for `src/generated.rs`,
//! `swc.arxml` (the software components) and `ecu.arxml` (their tasks) for `src/rte.rs`.
//! Each generated file records the digests of its descriptions, computed here by the same
//! function the generator uses.
//! The generator itself (ARXML, `autosar-data`) is not a dependency of the firmware: its
//! output is committed, as generated configuration is in AUTOSAR projects, and
//! `cargo xtask generate --check` proves it current in the check command.

include!("../gen/src/digest.rs");

fn main() {
    for (description, generated) in [
        ("ecu.arxml", "src/generated.rs"),
        ("swc.arxml", "src/rte.rs"),
    ] {
        println!("cargo:rerun-if-changed={description}");
        println!("cargo:rerun-if-changed={generated}");
        let (arxml, text) = match (
            std::fs::read(description),
            std::fs::read_to_string(generated),
        ) {
            (Ok(a), Ok(g)) => (a, g),
            (Err(e), _) => fail(&format!("cannot read {description}: {e}")),
            (_, Err(e)) => fail(&format!("cannot read {generated}: {e}")),
        };
        let line = format!("Description digest: {}", digest(&arxml));
        if !text.contains(&line) {
            fail(&format!(
                "firmware/{description} has changed since firmware/{generated} was generated \
                 from it: run `cargo xtask generate`"
            ));
        }
    }
    // The RTE's tasks are the OS's: `src/rte.rs` records the ECU description's digest too.
    match (
        std::fs::read("ecu.arxml"),
        std::fs::read_to_string("src/rte.rs"),
    ) {
        (Ok(ecu), Ok(rte))
            if rte.contains(&format!("ECU description digest: {}", digest(&ecu))) => {}
        _ => fail(
            "firmware/ecu.arxml has changed since firmware/src/rte.rs was generated with its \
             tasks: run `cargo xtask generate`",
        ),
    }
}

fn fail(why: &str) -> ! {
    eprintln!("error: {why}");
    std::process::exit(1)
}
