//! `cargo xtask system`: a bus's system description (ARXML) and its DBC, each from the
//! other, and the two compared:
//!
//! - `--from-dbc BUS.dbc [--out BUS.arxml]`: the DBC's nodes, frames and signals as an
//!   AUTOSAR system description (`cw_gen::system::write`);
//! - `--to-dbc BUS.arxml [--out BUS.dbc]`: a system description (this project's, or one
//!   canmatrix exported) as a DBC; what it reads and has no place for is a note (on the
//!   standard error: the DBC may be on the standard output);
//! - `--compare BUS.dbc BUS.arxml`: every difference between the two, naming frame and
//!   signal; it fails on any.
//!
//! `cargo xtask generate` writes the repository's own, `firmware/system.arxml` from
//! `firmware/ecu.dbc`, and `--check` holds the two to each other.

use std::path::{Path, PathBuf};

use crate::Result;

/// Options of `cargo xtask system`.
#[derive(clap::Args, Default)]
pub struct Options {
    /// Write this DBC as a system description (ARXML)
    #[arg(long, value_name = "DBC")]
    pub from_dbc: Option<PathBuf>,
    /// Write this system description (ARXML) as a DBC
    #[arg(long, value_name = "ARXML")]
    pub to_dbc: Option<PathBuf>,
    /// Compare a DBC and a system description: fails on any difference
    #[arg(long, num_args = 2, value_names = ["DBC", "ARXML"])]
    pub compare: Vec<PathBuf>,
    /// Where to write (the standard output if not given)
    #[arg(long, short, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Errors of the generator, one per line with their paths.
pub fn listed(errors: &[cw_gen::validate::Error]) -> String {
    errors
        .iter()
        .map(|e| format!("error: {e}"))
        .collect::<Vec<_>>()
        .join("\n")
}

fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    // UTF-8, else Windows-1252 (as CANdb++ writes), as `cw-can` reads a DBC.
    Ok(cw_can::dbc::text_of(&bytes))
}

/// The DBC at `path` as a system, its notes printed (on the standard error: the standard
/// output may be a file's text).
pub fn dbc_system(path: &Path) -> Result<cw_gen::system::System> {
    let name = path.display().to_string();
    let read = cw_gen::system::from_dbc(&read_text(path)?, &name).map_err(|e| {
        format!(
            "{name}: the DBC cannot be described as a system:\n{}",
            listed(&e)
        )
    })?;
    for note in &read.notes {
        eprintln!("system: note: {note}");
    }
    Ok(read.system)
}

/// The system description at `path`, its notes printed (on the standard error).
pub fn arxml_system(path: &Path) -> Result<cw_gen::system::System> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| format!("reading {name}: {e}"))?;
    let read = cw_gen::system::read(&bytes, &name).map_err(|e| {
        format!(
            "{name}: the system description cannot be read:\n{}",
            listed(&e)
        )
    })?;
    for note in &read.notes {
        eprintln!("system: note: {note}");
    }
    Ok(read.system)
}

/// Compares a DBC with a system description: the differences fail, what the description
/// does not give is printed.
pub fn compare(dbc: &Path, arxml: &Path) -> Result {
    let (differences, unchecked) =
        cw_gen::system::differences(&dbc_system(dbc)?, &arxml_system(arxml)?);
    for u in &unchecked {
        println!("system: not checked: {u}");
    }
    if differences.is_empty() {
        println!(
            "system: {} and {} describe the same bus",
            dbc.display(),
            arxml.display()
        );
        Ok(())
    } else {
        Err(format!(
            "{} and {} differ:\n{}",
            dbc.display(),
            arxml.display(),
            differences.join("\n")
        ))
    }
}

fn emit(text: &str, out: Option<&Path>) -> Result {
    match out {
        Some(path) => {
            std::fs::write(path, text).map_err(|e| format!("writing {}: {e}", path.display()))
        }
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Runs the subcommand.
pub fn run(options: &Options) -> Result {
    match (
        &options.from_dbc,
        &options.to_dbc,
        options.compare.as_slice(),
    ) {
        (Some(dbc), None, []) => {
            let system = dbc_system(dbc)?;
            let text = cw_gen::system::write(&system, cw_gen::PACKAGE)
                .map_err(|e| format!("{}: {e}", dbc.display()))?;
            emit(&text, options.out.as_deref())
        }
        (None, Some(arxml), []) => {
            let system = arxml_system(arxml)?;
            emit(&cw_gen::system::to_dbc(&system), options.out.as_deref())
        }
        (None, None, [dbc, arxml]) => compare(dbc, arxml),
        _ => Err("give one of --from-dbc DBC, --to-dbc ARXML or --compare DBC ARXML".to_string()),
    }
}
