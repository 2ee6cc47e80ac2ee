//! `cargo xtask generate [--check]`: the paper's step 3. The ECU's descriptions are read,
//! checked and turned into Rust the firmware compiles, laid out by `rustfmt`:
//! `firmware/ecu.arxml` (the basic software's ECUC values) into its configuration tables
//! (`firmware/src/generated.rs`), `firmware/swc.arxml` (the software components and their
//! composition) into its RTE (`firmware/src/rte.rs`), and the bus's DBC (`firmware/ecu.dbc`)
//! into its system description (`firmware/system.arxml`), to which the ECU description's
//! communication (CanIf, PduR, Com) is held before anything is generated. With `--check` (the check command's
//! `clippy` stage), nothing is written: the command fails when a committed file is not
//! what its description generates.

use crate::process::{root, target_dir, Cmd};
use crate::Result;

/// Options of `cargo xtask generate`.
#[derive(clap::Args, Default)]
pub struct Options {
    /// Do not write: fail if firmware/src/generated.rs or firmware/src/rte.rs differs from
    /// what its description generates
    #[arg(long)]
    pub check: bool,
}

/// What generates a file: from a description's bytes, its file name and the ECU
/// description's bytes.
type Generate = fn(&[u8], &str, &[u8]) -> std::result::Result<cw_gen::Generated, cw_gen::Refused>;

/// One description and the file generated from it.
struct Pair {
    description: &'static str,
    generated: &'static str,
    /// Generates from the description's bytes and the ECU description's.
    generate: Generate,
}

const PAIRS: [Pair; 2] = [
    Pair {
        description: cw_gen::DESCRIPTION,
        generated: cw_gen::GENERATED,
        generate: |bytes, source, _| cw_gen::generate(bytes, source),
    },
    Pair {
        description: cw_gen::COMPONENTS,
        generated: cw_gen::GENERATED_RTE,
        // The runnables' tasks are the OS's, in the ECU's description.
        generate: |bytes, source, ecu| {
            cw_gen::generate_rte(bytes, source, ecu, cw_gen::DESCRIPTION)
        },
    },
];

/// The generated text for a description's bytes, laid out by `rustfmt`; the notes on
/// what the description holds that the ECU does not use are printed.
fn generated(pair: &Pair, bytes: &[u8], ecu: &[u8]) -> Result<String> {
    let out = (pair.generate)(bytes, pair.description, ecu).map_err(|e| {
        format!(
            "{}: the description cannot be generated:\n{e}",
            pair.description
        )
    })?;
    for note in &out.notes {
        println!("generate: note: {note}");
    }
    for line in &out.report {
        println!("generate: {line}");
    }
    let dir = target_dir().join("xtask-generate");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let name = std::path::Path::new(pair.generated)
        .file_name()
        .map_or_else(|| "generated.rs".into(), |n| n.to_os_string());
    let file = dir.join(name);
    std::fs::write(&file, &out.rust).map_err(|e| format!("writing {}: {e}", file.display()))?;
    Cmd::new("rustfmt")
        .args(["--edition", "2021"])
        .arg(&file)
        .run()?;
    std::fs::read_to_string(&file).map_err(|e| format!("reading {}: {e}", file.display()))
}

/// The system description from the bus's DBC (`firmware/system.arxml` from
/// `firmware/ecu.dbc`): written, or checked (`--check`). Both ways: the description reads
/// back as the DBC's bus, and the DBC written from it does too.
fn system(check: bool) -> Result<String> {
    use cw_gen::system;
    let dbc = crate::system::dbc_system(&root().join(cw_gen::DBC))?;
    let text = system::write(&dbc, cw_gen::PACKAGE).map_err(|e| {
        format!(
            "{}: the system description cannot be written: {e}",
            cw_gen::DBC
        )
    })?;
    let back = system::read(text.as_bytes(), cw_gen::SYSTEM).map_err(|e| {
        format!(
            "{}: what {} generates does not read back:\n{}",
            cw_gen::SYSTEM,
            cw_gen::DBC,
            crate::system::listed(&e)
        )
    })?;
    let (differences, _) = system::differences(&dbc, &back.system);
    if back.system != dbc || !differences.is_empty() {
        return Err(format!(
            "{} does not read back as {}: {}",
            cw_gen::SYSTEM,
            cw_gen::DBC,
            differences.join("; ")
        ));
    }
    let again = system::from_dbc(&system::to_dbc(&back.system), "the DBC written from it")
        .map_err(|e| crate::system::listed(&e))?
        .system;
    if again != dbc {
        let (differences, _) = system::differences(&dbc, &again);
        return Err(format!(
            "the DBC written from {} is not {}: {}",
            cw_gen::SYSTEM,
            cw_gen::DBC,
            differences.join("; ")
        ));
    }
    settle(
        check,
        cw_gen::SYSTEM,
        cw_gen::DBC,
        &text,
        "; each reads back as the other's bus",
    )?;
    Ok(text)
}

/// The ECU description's communication held to what the system description asks of the
/// ECU's node (`cw_gen::NODE`): its frames, PDUs and signals.
fn communication(ecu: &[u8], system: &str) -> Result {
    let agreed = cw_gen::check_communication(
        ecu,
        cw_gen::DESCRIPTION,
        system.as_bytes(),
        cw_gen::SYSTEM,
        cw_gen::NODE,
    )
    .map_err(|e| {
        format!(
            "{}'s communication is not what {} gives node {}:\n{e}",
            cw_gen::DESCRIPTION,
            cw_gen::SYSTEM,
            cw_gen::NODE
        )
    })?;
    println!(
        "generate: {}'s communication is what {} gives node {} (frames sent {}, received {}; Com signals {})",
        cw_gen::DESCRIPTION,
        cw_gen::SYSTEM,
        cw_gen::NODE,
        agreed.sent,
        agreed.received,
        agreed.signals
    );
    Ok(())
}

/// Writes `text` into `generated` (from the workspace's root), generated from
/// `description`, where it differs; or, with `check`, fails where it differs. `more` ends
/// the line of a check that passed.
fn settle(check: bool, generated: &str, description: &str, text: &str, more: &str) -> Result {
    let target = root().join(generated);
    let committed = std::fs::read_to_string(&target).unwrap_or_default();
    if check {
        if committed != text {
            return Err(format!(
                "{generated} is not what {description} generates: run `cargo xtask generate` and commit both"
            ));
        }
        println!("generate: {generated} is what {description} generates{more}");
    } else {
        if committed != text {
            std::fs::write(&target, text)
                .map_err(|e| format!("writing {}: {e}", target.display()))?;
        }
        println!(
            "generate: {generated} from {description} ({})",
            if committed == text {
                "unchanged"
            } else {
                "written"
            }
        );
    }
    Ok(())
}

/// Generates, or checks what is committed.
pub fn run(options: &Options) -> Result {
    let system = system(options.check)?;
    let ecu_path = root().join(cw_gen::DESCRIPTION);
    let ecu =
        std::fs::read(&ecu_path).map_err(|e| format!("reading {}: {e}", ecu_path.display()))?;
    for (k, pair) in PAIRS.iter().enumerate() {
        let source = root().join(pair.description);
        let bytes =
            std::fs::read(&source).map_err(|e| format!("reading {}: {e}", source.display()))?;
        let text = generated(pair, &bytes, &ecu)?;
        settle(options.check, pair.generated, pair.description, &text, "")?;
        // Once the ECUC values have passed their own checks, their communication against
        // the bus's, before the RTE.
        if k == 0 {
            communication(&ecu, &system)?;
        }
    }
    Ok(())
}
