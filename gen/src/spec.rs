//! Named properties of the generator, run by its tests and by the fuzz targets
//! `arxml_description` and `bus_description` (`cw-fuzz`).

/// The ECU's description, as committed.
pub const ECU: &str = include_str!("../../firmware/ecu.arxml");
/// The bus's DBC, as committed.
pub const DBC: &str = include_str!("../../firmware/ecu.dbc");
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

/// Any text, as a DBC and as a system description's ARXML: read, or refused with at least
/// one error, never a panic.
pub fn a_text_is_a_bus_or_is_refused(text: &str) -> bool {
    let dbc = match crate::system::from_dbc(text, "fuzz.dbc") {
        Ok(_) => true,
        Err(e) => !e.is_empty(),
    };
    let arxml = match crate::system::read(text.as_bytes(), "fuzz.arxml") {
        Ok(_) => true,
        Err(e) => !e.is_empty(),
    };
    dbc && arxml
}

/// A frame of [`a_bus_reads_back_as_written`]'s: its id, length (modulo 9), whether the id
/// is extended, its sender (modulo the nodes and none) and its signals.
pub type FrameSeed = (u16, u8, bool, u8, Vec<SignalSeed>);
/// A signal: start bit, length (modulo 64, plus 1), Motorola, signed, and one byte each
/// choosing its factor and offset, range, unit, named values, receivers and comment.
pub type SignalSeed = (u8, u8, bool, bool, u8, u8);

/// The bus `frames` describe (frames of an id already taken are left out).
pub fn bus_of(frames: &[FrameSeed]) -> crate::system::System {
    use crate::system::{Frame, Node, Signal, System};
    const NODES: [&str; 3] = ["Ecu", "Pc", "Gateway"];
    const FACTORS: [(f64, f64); 6] = [
        (1.0, 0.0),
        (0.5, -40.0),
        (0.1, 0.0),
        (0.001, 1e6),
        (-1.0, 0.5),
        (2.0, 0.25),
    ];
    const UNITS: [&str; 4] = ["", "mm", "km/h", "%"];
    const COMMENTS: [&str; 4] = [
        "",
        "One sentence.",
        "Two words, and a comma; then more.",
        "A \"quoted\" word and a back\\slash.",
    ];
    let pick = |list: &[&str], i: u8| {
        list.get(usize::from(i) % list.len())
            .copied()
            .unwrap_or_default()
            .to_string()
    };
    let mut system = System {
        // A DBC does not name its bus: `from_dbc` calls it `CAN`.
        bus: "CAN".to_string(),
        nodes: NODES
            .iter()
            .zip(COMMENTS)
            .map(|(n, c)| Node {
                name: (*n).to_string(),
                comment: c.to_string(),
            })
            .collect(),
        frames: Vec::new(),
    };
    for (i, (id, length, extended, sender, signals)) in frames.iter().enumerate() {
        // Spread over all 29 bits of an extended identifier.
        let id = if *extended {
            u32::from(*id).wrapping_mul(0x2003) & 0x1FFF_FFFF
        } else {
            u32::from(*id) & 0x7FF
        };
        if system
            .frames
            .iter()
            .any(|f| f.id == id && f.extended == *extended)
        {
            continue;
        }
        let sender = usize::from(*sender) % (NODES.len() + 1);
        let mut frame = Frame {
            name: format!("Frame{i}"),
            id,
            extended: *extended,
            // Classic CAN's lengths, and CAN FD's 12 and 64.
            length: [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 64]
                .get(usize::from(*length) % 11)
                .copied()
                .unwrap_or(8),
            sender: NODES.get(sender).map(|n| (*n).to_string()),
            comment: pick(&COMMENTS, *length),
            signals: Vec::new(),
        };
        for (j, (start, len, big_endian, signed, scale, texts)) in signals.iter().enumerate() {
            let (factor, offset) = FACTORS
                .get(usize::from(*scale) % FACTORS.len())
                .copied()
                .unwrap_or((1.0, 0.0));
            let values = (0..texts % 4)
                .map(|v| (i64::from(v) - 1, format!("Value{v}")))
                .collect();
            let signal = Signal {
                name: format!("Signal{j}"),
                start_bit: u16::from(*start),
                length: u16::from(len % 64) + 1,
                big_endian: *big_endian,
                signed: *signed,
                factor,
                offset,
                range: (scale % 3 != 0).then_some((offset, offset + factor * 100.0)),
                unit: pick(&UNITS, *texts),
                values,
                receivers: NODES
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| texts >> (2 + k) & 1 == 1)
                    .map(|(_, n)| (*n).to_string())
                    .collect(),
                comment: pick(&COMMENTS, texts / 4),
            };
            // Only a signal that fits in the frame beside the others: a bus has no other.
            frame.signals.push(signal);
            if !crate::system::layout_errors(&frame, "").is_empty() {
                frame.signals.pop();
            }
        }
        system.frames.push(frame);
    }
    system
}

/// A bus written as ARXML reads back the same, and written as a DBC reads back the same.
pub fn a_bus_reads_back_as_written(frames: &[FrameSeed]) -> bool {
    let bus = bus_of(frames);
    let Ok(arxml) = crate::system::write(&bus, "Fuzz") else {
        return false;
    };
    let Ok(read) = crate::system::read(arxml.as_bytes(), "fuzz.arxml") else {
        return false;
    };
    let dbc = crate::system::from_dbc(&crate::system::to_dbc(&bus), "fuzz.dbc");
    read.system == bus && matches!(dbc, Ok(r) if r.system == bus)
}

/// The repository's bus with `frames` (a [`bus_of`], sent and received by the bus's other
/// node, PC) added where their identifiers are free: the ECU's communication still agrees
/// with it, frame for frame as with the repository's bus; and with any one of them sent by
/// the ECU instead, or with a signal for it, it is refused, the frame named.
pub fn frames_of_other_nodes_leave_the_ecu_alone(frames: &[FrameSeed]) -> bool {
    // Read once: the fuzz target runs this on every input.
    static REPOSITORY: std::sync::OnceLock<Option<(crate::system::Read, crate::model::Ecu)>> =
        std::sync::OnceLock::new();
    let repository = REPOSITORY.get_or_init(|| {
        let bus = crate::system::from_dbc(DBC, "ecu.dbc").ok()?;
        let ecu = crate::arxml::read(ECU.as_bytes(), "ecu.arxml").ok()?;
        Some((bus, ecu.ecu))
    });
    let Some((bus, ecu)) = repository else {
        return false;
    };
    let mut bus = bus.clone();
    let Ok(alone) = crate::extract::check(&bus, "ecu.dbc", crate::NODE, ecu) else {
        return false;
    };
    let mut added = Vec::new();
    // The bus's other node sends and receives them.
    let other = "PC".to_string();
    for mut frame in bus_of(frames).frames {
        frame.sender = frame.sender.map(|_| other.clone());
        for signal in &mut frame.signals {
            signal.receivers = vec![other.clone(); signal.receivers.len().min(1)];
        }
        let taken = bus
            .system
            .frames
            .iter()
            .any(|f| (f.id, f.extended) == (frame.id, frame.extended));
        if !taken {
            frame.name = format!("Other{}", added.len());
            added.push(frame.name.clone());
            bus.system.frames.push(frame);
        }
    }
    if crate::extract::check(&bus, "ecu.dbc", crate::NODE, ecu) != Ok(alone) {
        return false;
    }
    // Sent by the ECU, or with a signal for it: refused, the frame named.
    let refused = |ours: &crate::system::Read, name: &str| {
        matches!(
            crate::extract::check(ours, "ecu.dbc", crate::NODE, ecu),
            Err(e) if e.iter().any(|e| e.what.contains(&format!("frame {name} ")))
        )
    };
    added.iter().all(|name| {
        let mut sent = bus.clone();
        let mut received = bus.clone();
        let mut has_signals = false;
        for f in sent.system.frames.iter_mut().filter(|f| f.name == *name) {
            f.sender = Some(crate::NODE.to_string());
        }
        for f in received
            .system
            .frames
            .iter_mut()
            .filter(|f| f.name == *name)
        {
            if let Some(s) = f.signals.first_mut() {
                s.receivers.push(crate::NODE.to_string());
                has_signals = true;
            }
        }
        refused(&sent, name) && (!has_signals || refused(&received, name))
    })
}

/// The ECU's task set with the budgets `budgets` (µs, one per task and ISR with a timing
/// protection, in the description's order; 0 taken as 1, a missing one as the
/// description's): analysed, it meets every deadline or is refused naming an item; and
/// where it meets them, any one budget halved still does, no response longer (the
/// analysis is sustainable: a job that runs shorter never makes the set miss).
pub fn budgets_are_sustainable(budgets: &[u16]) -> bool {
    /// The ECU's description and the RTE's releases, read once.
    type Repository = Option<(crate::model::Ecu, Vec<(String, String)>)>;
    static REPOSITORY: std::sync::OnceLock<Repository> = std::sync::OnceLock::new();
    let repository = REPOSITORY.get_or_init(|| {
        let ecu = crate::arxml::read(ECU.as_bytes(), "ecu.arxml").ok()?.ecu;
        let sw = crate::rte::read(COMPONENTS.as_bytes(), "swc.arxml").ok()?;
        let released = crate::rte::released_by(&sw, &ecu).ok()?;
        Some((ecu, released))
    });
    let Some((ecu, released)) = repository else {
        return false;
    };
    let with = |budgets: &[u64]| {
        let mut ecu = ecu.clone();
        let tasks = ecu.os.tasks.iter_mut().filter_map(|t| t.timing.as_mut());
        let isrs = ecu.os.isrs.iter_mut().filter_map(|i| i.timing.as_mut());
        for (timing, &b) in tasks.chain(isrs).zip(budgets) {
            timing.budget_us = Some(b.max(1));
        }
        crate::timing::analyse(&ecu, released)
    };
    let budgets: Vec<u64> = budgets.iter().map(|&b| u64::from(b)).collect();
    let responses = |analysis: &crate::timing::Analysis| match analysis {
        crate::timing::Analysis::Schedulable { items, .. } => items
            .iter()
            .map(|i| i.response.time().unwrap_or(u64::MAX))
            .collect::<Vec<_>>(),
        crate::timing::Analysis::NoBudgets => Vec::new(),
    };
    match with(&budgets) {
        Err(e) => !e.is_empty() && e.iter().all(|e| !e.paths.is_empty()),
        Ok(analysis) => {
            let before = responses(&analysis);
            (0..budgets.len()).all(|k| {
                let mut halved = budgets.clone();
                if let Some(b) = halved.get_mut(k) {
                    *b /= 2;
                }
                match with(&halved) {
                    Ok(after) => responses(&after).iter().zip(&before).all(|(a, b)| a <= b),
                    Err(_) => false,
                }
            })
        }
    }
}
