//! Named properties of the generator, run by its tests and by the fuzz target
//! `arxml_description` (`cw-fuzz`).

/// The ECU's description, as committed.
pub const ECU: &str = include_str!("../../firmware/ecu.arxml");

/// Any bytes: they generate, or are refused with at least one error, never a panic.
pub fn bytes_generate_or_are_refused(bytes: &[u8]) -> bool {
    match crate::generate(bytes, "fuzz.arxml") {
        Ok(out) => !out.rust.is_empty(),
        Err(e) => !e.0.is_empty(),
    }
}

/// The committed description with its `which`-th `VALUE` (counted modulo their number)
/// replaced by `value` (XML-escaped): it generates, or every error names the file or an
/// ARXML path.
pub fn a_changed_value_generates_or_names_paths(which: usize, value: &str) -> bool {
    let values: Vec<usize> = ECU.match_indices("<VALUE>").map(|(i, _)| i).collect();
    let Some(at) = values
        .len()
        .checked_sub(1)
        .and_then(|_| values.get(which % values.len()))
    else {
        return false;
    };
    let open = at + "<VALUE>".len();
    let Some(len) = ECU.get(open..).and_then(|rest| rest.find("</VALUE>")) else {
        return false;
    };
    let (Some(before), Some(after)) = (ECU.get(..open), ECU.get(open + len..)) else {
        return false;
    };
    let escaped = value.replace('&', "&amp;").replace('<', "&lt;");
    let text = format!("{before}{escaped}{after}");
    match crate::generate(text.as_bytes(), "ecu.arxml") {
        Ok(out) => out.rust.contains("pub const DESCRIPTION"),
        Err(e) => e.0.iter().all(|error| {
            error
                .paths
                .iter()
                .any(|p| p.starts_with('/') || p == "ecu.arxml")
        }),
    }
}
