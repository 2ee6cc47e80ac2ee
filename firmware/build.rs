//! Stops the build when the ECU's description (`ecu.arxml`) has changed since its tables
//! (`src/generated.rs`) were generated from it: the generated file records the digest of
//! the description it came from, computed here by the same function the generator uses.
//! The generator itself (ARXML, `autosar-data`) is not a dependency of the firmware: its
//! output is committed, as generated configuration is in AUTOSAR projects, and
//! `cargo xtask generate --check` proves it current in the check command.

include!("../gen/src/digest.rs");

fn main() {
    println!("cargo:rerun-if-changed=ecu.arxml");
    println!("cargo:rerun-if-changed=src/generated.rs");
    let (arxml, generated) = match (
        std::fs::read("ecu.arxml"),
        std::fs::read_to_string("src/generated.rs"),
    ) {
        (Ok(a), Ok(g)) => (a, g),
        (Err(e), _) => fail(&format!("cannot read ecu.arxml: {e}")),
        (_, Err(e)) => fail(&format!("cannot read src/generated.rs: {e}")),
    };
    let line = format!("Description digest: {}", digest(&arxml));
    if !generated.contains(&line) {
        fail(
            "firmware/ecu.arxml has changed since firmware/src/generated.rs was generated \
             from it: run `cargo xtask generate`",
        );
    }
}

fn fail(why: &str) -> ! {
    eprintln!("error: {why}");
    std::process::exit(1)
}
