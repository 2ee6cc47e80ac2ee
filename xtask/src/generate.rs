//! `cargo xtask generate [--check]`: the paper's step 3. The ECU's description
//! (`firmware/ecu.arxml`, ECUC values in ARXML) is read, checked and turned into the
//! firmware's configuration tables (`firmware/src/generated.rs`, laid out by `rustfmt`).
//! With `--check` (the check command's `clippy` stage), nothing is written: the command
//! fails when the committed file is not what the description generates.

use crate::process::{root, target_dir, Cmd};
use crate::Result;

/// Options of `cargo xtask generate`.
#[derive(clap::Args, Default)]
pub struct Options {
    /// Do not write: fail if firmware/src/generated.rs differs from what the description
    /// generates
    #[arg(long)]
    pub check: bool,
}

/// The generated text for the description's bytes, laid out by `rustfmt`; the notes on
/// what the description holds that the ECU does not use are printed.
fn generated(bytes: &[u8]) -> Result<String> {
    let out = cw_gen::generate(bytes, cw_gen::DESCRIPTION).map_err(|e| {
        format!(
            "{}: the description cannot be generated:\n{e}",
            cw_gen::DESCRIPTION
        )
    })?;
    for note in &out.notes {
        println!("generate: note: {note}");
    }
    let dir = target_dir().join("xtask-generate");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let file = dir.join("generated.rs");
    std::fs::write(&file, &out.rust).map_err(|e| format!("writing {}: {e}", file.display()))?;
    Cmd::new("rustfmt")
        .args(["--edition", "2021"])
        .arg(&file)
        .run()?;
    std::fs::read_to_string(&file).map_err(|e| format!("reading {}: {e}", file.display()))
}

/// Generates, or checks what is committed.
pub fn run(options: &Options) -> Result {
    let source = root().join(cw_gen::DESCRIPTION);
    let bytes = std::fs::read(&source).map_err(|e| format!("reading {}: {e}", source.display()))?;
    let text = generated(&bytes)?;
    let target = root().join(cw_gen::GENERATED);
    let committed = std::fs::read_to_string(&target).unwrap_or_default();
    if options.check {
        if committed == text {
            println!(
                "generate: {} is what {} generates",
                cw_gen::GENERATED,
                cw_gen::DESCRIPTION
            );
            Ok(())
        } else {
            Err(format!(
                "{} is not what {} generates: run `cargo xtask generate` and commit both",
                cw_gen::GENERATED,
                cw_gen::DESCRIPTION
            ))
        }
    } else {
        if committed != text {
            std::fs::write(&target, &text)
                .map_err(|e| format!("writing {}: {e}", target.display()))?;
        }
        println!(
            "generate: {} from {} ({})",
            cw_gen::GENERATED,
            cw_gen::DESCRIPTION,
            if committed == text {
                "unchanged"
            } else {
                "written"
            }
        );
        Ok(())
    }
}
