//! Named properties of the generator, run by its tests and by the fuzz target
//! `arxml_description` (`cw-fuzz`).

/// The ECU's description, as committed.
pub const ECU: &str = include_str!("../../firmware/ecu.arxml");
/// The software components' description, as committed.
pub const COMPONENTS: &str = include_str!("../../firmware/swc.arxml");

/// Any bytes: they generate, or are refused with at least one error, never a panic; as
/// basic software values and as software components.
pub fn bytes_generate_or_are_refused(bytes: &[u8]) -> bool {
    [
        crate::generate(bytes, "fuzz.arxml"),
        crate::generate_rte(bytes, "fuzz.arxml", ECU.as_bytes(), "ecu.arxml"),
    ]
    .iter()
    .all(|generated| match generated {
        Ok(out) => !out.rust.is_empty(),
        Err(e) => !e.0.is_empty(),
    })
}

/// `text` with its `which`-th element `tag` (counted modulo their number) holding `value`
/// (XML-escaped) instead; `None` if it has no such element.
pub fn with_text(text: &str, tag: &str, which: usize, value: &str) -> Option<String> {
    let (open_tag, close_tag) = (format!("<{tag}"), format!("</{tag}>"));
    // The element's start: `<TAG>` or `<TAG ` (with attributes), not `<TAG-MORE`.
    let sites: Vec<usize> = text
        .match_indices(&open_tag)
        .map(|(i, _)| i)
        .filter(|&i| matches!(text.as_bytes().get(i + open_tag.len()), Some(b'>' | b' ')))
        .collect();
    let at = *sites.get(which.checked_rem(sites.len())?)?;
    let open = at + text.get(at..)?.find('>')? + 1;
    let len = text.get(open..)?.find(&close_tag)?;
    let escaped = value.replace('&', "&amp;").replace('<', "&lt;");
    Some(format!(
        "{}{escaped}{}",
        text.get(..open)?,
        text.get(open + len..)?
    ))
}

/// Every error names the file or an ARXML path.
fn names_paths(e: &crate::Refused, file: &str) -> bool {
    e.0.iter()
        .all(|error| error.paths.iter().any(|p| p.starts_with('/') || p == file))
}

/// The committed description with its `which`-th `VALUE` (counted modulo their number)
/// replaced by `value`: it generates, or every error names the file or an ARXML path.
pub fn a_changed_value_generates_or_names_paths(which: usize, value: &str) -> bool {
    let Some(text) = with_text(ECU, "VALUE", which, value) else {
        return false;
    };
    match crate::generate(text.as_bytes(), "ecu.arxml") {
        Ok(out) => out.rust.contains("pub const DESCRIPTION"),
        Err(e) => names_paths(&e, "ecu.arxml"),
    }
}

/// The components' description with the text of its `which`-th element of kind `tag`
/// (a short name, a reference, a period, an init value, a queue length, a Rust type:
/// [`COMPONENT_TEXTS`]) replaced by `value`: the RTE generates, or every error names the
/// file or an ARXML path.
pub fn a_changed_component_generates_or_names_paths(tag: usize, which: usize, value: &str) -> bool {
    let Some(tag) = COMPONENT_TEXTS.get(tag % COMPONENT_TEXTS.len()) else {
        return false;
    };
    let Some(text) = with_text(COMPONENTS, tag, which, value) else {
        return false;
    };
    match crate::generate_rte(text.as_bytes(), "swc.arxml", ECU.as_bytes(), "ecu.arxml") {
        Ok(out) => out.rust.contains("pub struct Rte"),
        Err(e) => names_paths(&e, "swc.arxml"),
    }
}

/// The elements of the components' description whose text the harness changes.
pub const COMPONENT_TEXTS: [&str; 7] = [
    "SHORT-NAME",
    "VALUE",
    "PERIOD",
    "QUEUE-LENGTH",
    "SD",
    "TARGET-P-PORT-REF",
    "SW-IMPL-POLICY",
];
