//! `cw-gen`: the paper's procedure (§3.1) made real and open. The ECU is described in ARXML
//! (AUTOSAR 4); this crate reads that description, checks it, and writes the Rust
//! configuration the firmware compiles, each generated item naming the ARXML path it came
//! from.
//!
//! - [`model`]: the description as plain values, with their ARXML paths;
//! - [`arxml`]: reading and writing it with `autosar-data`;
//! - [`validate`]: the checks before generation, each error naming every path involved;
//! - [`rust`]: the generated Rust;
//! - [`rte`]: the software components and their RTE;
//! - [`system`]: the system description's communication (the bus's frames and signals),
//!   from and to a DBC;
//! - [`timing`]: the task set's response-time analysis from the tasks' and ISRs' budgets;
//! - [`extract`]: the ECU's communication (CanIf, PduR, Com) held to what the system
//!   description asks of it.
//!
//! `cargo xtask generate` runs the four steps on `firmware/ecu.arxml` and writes
//! `firmware/src/generated.rs`; `cargo xtask generate --check` (in the check command)
//! fails when the committed file is not what the description generates.

#![forbid(unsafe_code)]
// Input from outside (an ARXML file) is an error value naming its path, never a panic.
#![cfg_attr(
    not(test),
    warn(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod arxml;
mod digest;
pub mod extract;
pub mod model;
pub mod rte;
pub mod rust;
pub mod spec;
pub mod system;
pub mod timing;
pub mod validate;

pub use digest::digest;

/// The description's file, from the workspace's root.
pub const DESCRIPTION: &str = "firmware/ecu.arxml";
/// The bus's DBC, from the workspace's root.
pub const DBC: &str = "firmware/ecu.dbc";
/// The system description generated from [`DBC`], from the workspace's root.
pub const SYSTEM: &str = "firmware/system.arxml";
/// The node of the bus ([`SYSTEM`], [`DBC`]) whose ECU [`DESCRIPTION`] configures.
pub const NODE: &str = "ECU";
/// The top package of the ECU's descriptions.
pub const PACKAGE: &str = "CollisionWarning";
/// The generated file, from the workspace's root.
pub const GENERATED: &str = "firmware/src/generated.rs";
/// The software components' description, from the workspace's root.
pub const COMPONENTS: &str = "firmware/swc.arxml";
/// The generated RTE, from the workspace's root.
pub const GENERATED_RTE: &str = "firmware/src/rte.rs";

/// Everything that stops generation: each error with every path involved.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused(pub Vec<validate::Error>);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "error: {e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Refused {}

/// What generation gives: the Rust (before `rustfmt`), and notes on what the description
/// holds that this ECU does not use.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Generated {
    /// The module's text.
    pub rust: String,
    /// One sentence per item read but not used, with its path.
    pub notes: Vec<String>,
    /// What the checks before generation found, one line each (the task set's analysis).
    pub report: Vec<String>,
}

/// Reads, checks and generates the RTE: the paper's step 3 for the software components in
/// `bytes` (the file `source`, named in the generated header), whose runnables run in the
/// tasks of the OS that `ecu` (the ECUC values of `ecu_source`) describes.
///
/// # Errors
/// Everything that cannot be read, mapped or generated, at once.
pub fn generate_rte(
    bytes: &[u8],
    source: &str,
    ecu: &[u8],
    ecu_source: &str,
) -> Result<Generated, Refused> {
    let sw = rte::read(bytes, source).map_err(Refused)?;
    let ecu_bytes = ecu;
    let ecu = arxml::read(ecu_bytes, ecu_source).map_err(Refused)?.ecu;
    // The ECU's own checks first: the RTE and the analysis take its OS as valid.
    let mut errors = validate::check(&ecu);
    if errors.is_empty() {
        errors = rte::check(&sw, &ecu);
    }
    if !errors.is_empty() {
        return Err(Refused(errors));
    }
    // The task set, with the tasks the RTE's events release, analysed before generation.
    let released = rte::released_by(&sw, &ecu).map_err(|e| Refused(vec![e]))?;
    let mut report = Vec::new();
    match timing::analyse(&ecu, &released).map_err(Refused)? {
        timing::Analysis::NoBudgets => report.push(format!(
            "no task or ISR of {ecu_source} has a timing protection (OsTaskTimingProtection, OsIsrTimingProtection): the task set is not analysed"
        )),
        timing::Analysis::Schedulable { items, left_out } => {
            let without = if left_out.is_empty() {
                String::new()
            } else {
                format!(", {} ISR(s) without one left out", left_out.len())
            };
            report.push(format!(
                "the task set of {ecu_source} meets every deadline with its budgets (response-time analysis, µs{without}):"
            ));
            report.extend(items.iter().map(timing::Item::line));
            report.extend(left_out.iter().map(|isr| {
                format!("  ISR {isr} has no OsIsrTimingProtection: it is not in the analysis")
            }));
        }
    }
    // Both descriptions' digests: the firmware's build script checks the file against each.
    let digests = format!(
        "{}\n//! ECU description digest: {}",
        digest(bytes),
        digest(ecu_bytes)
    );
    let rust = rte::emit(&sw, &ecu, source, &digests).map_err(|e| Refused(vec![e]))?;
    Ok(Generated {
        rust,
        notes: sw.notes,
        report,
    })
}

/// Reads, checks and generates: the paper's step 3 for the ECUC values in `bytes` (the
/// file `source`, named in the generated header).
///
/// # Errors
/// Everything that cannot be read, mapped or generated, at once.
pub fn generate(bytes: &[u8], source: &str) -> Result<Generated, Refused> {
    let read = arxml::read(bytes, source).map_err(Refused)?;
    let errors = validate::check(&read.ecu);
    if !errors.is_empty() {
        return Err(Refused(errors));
    }
    let rust = rust::emit(&read.ecu, source, &digest(bytes)).map_err(|e| Refused(vec![e]))?;
    Ok(Generated {
        rust,
        notes: read.notes,
        report: Vec::new(),
    })
}

/// Holds the communication of the ECUC values in `ecu` (the file `ecu_source`) to what
/// the system description in `system` (the file `system_source`) asks of the bus's node
/// `node`: the paper's ECU extract, checked before generation.
///
/// # Errors
/// Either file cannot be read, the ECUC values fail their own checks
/// ([`validate::check`]), or the two disagree ([`extract::check`]), at once.
pub fn check_communication(
    ecu: &[u8],
    ecu_source: &str,
    system: &[u8],
    system_source: &str,
    node: &str,
) -> Result<extract::Agreed, Refused> {
    let bus = system::read(system, system_source).map_err(Refused)?;
    let ecu = arxml::read(ecu, ecu_source).map_err(Refused)?.ecu;
    let errors = validate::check(&ecu);
    if !errors.is_empty() {
        return Err(Refused(errors));
    }
    extract::check(&bus, system_source, node, &ecu).map_err(Refused)
}
