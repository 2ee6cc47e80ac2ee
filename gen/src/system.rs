//! The system description's communication: the CAN cluster, its frames, their I-PDUs and
//! signals, and which ECU sends and receives each, the part of an AUTOSAR system
//! description a DBC file also holds. Read from ARXML (this project's, or a DBC exported
//! by canmatrix), written as ARXML (AUTOSAR [`crate::arxml::VERSION`]), and converted from
//! and to a DBC, so that `firmware/ecu.dbc` and `firmware/system.arxml` can be held to
//! describe one bus.
//!
//! The mapping, DBC to ARXML:
//!
//! | DBC | ARXML |
//! |---|---|
//! | `BU_` node, its `CM_ BU_` | `ECU-INSTANCE`, its `DESC` |
//! | `BO_` message: id, name, length, transmitter | `CAN-FRAME-TRIGGERING` (`IDENTIFIER`, `CAN-ADDRESSING-MODE`) of a `CAN-FRAME` (`FRAME-LENGTH`) holding one `I-SIGNAL-I-PDU` at byte 0; the transmitter's `FRAME-PORT` `OUT` |
//! | `SG_` signal: start bit, length, byte order | `I-SIGNAL-TO-I-PDU-MAPPING` (`START-POSITION`: the DBC's start bit, the least significant bit for Intel, the most significant for Motorola; `PACKING-BYTE-ORDER`) of an `I-SIGNAL` (`LENGTH`) |
//! | signedness | the `I-SIGNAL`'s `SW-BASE-TYPE`, `BASE-TYPE-ENCODING` `2C` or `NONE` |
//! | factor, offset, `VAL_` | the `COMPU-METHOD`: a linear scale (`COMPU-RATIONAL-COEFFS`: offset and factor over 1) and a scale per named value (`COMPU-CONST` `VT`) |
//! | `[min\|max]` | the `DATA-CONSTR`'s `PHYS-CONSTRS` (read also from a linear scale's limits, which AUTOSAR gives as raw values) |
//! | unit | `UNIT` `DISPLAY-NAME` |
//! | receivers | each receiver's `I-SIGNAL-PORT` `IN` on the signal's `I-SIGNAL-TRIGGERING` |
//! | `CM_ BO_`, `CM_ SG_` | the `CAN-FRAME`'s and the `SYSTEM-SIGNAL`'s `DESC` |
//!
//! What neither side can carry (multiplexed signals, floats, a message with two
//! transmitters, another cluster's kind, container or multiplexed I-PDUs) is refused
//! with its place named; what is read but has no place in the other (I-PDU groups, a
//! CAN controller) or is written another tool's way (canmatrix's dangling
//! `PDU-TRIGGERING-REF`, its value names in `DESC`) is a note.

use std::collections::HashMap;
use std::fmt::Write as _;

use autosar_data::{AttributeName, AutosarModel, Element, ElementName, EnumItem};

use crate::rte::{path_of, text};
use crate::validate::Error;

/// One CAN bus as a system description holds it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct System {
    /// The cluster's name.
    pub bus: String,
    /// The ECUs on it.
    pub nodes: Vec<Node>,
    /// Its frames.
    pub frames: Vec<Frame>,
}

/// An ECU on the bus.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Node {
    /// Its name.
    pub name: String,
    /// Its description.
    pub comment: String,
}

/// A frame and the one I-PDU it carries.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frame {
    /// Its name.
    pub name: String,
    /// Its identifier (without a DBC's extended-id bit).
    pub id: u32,
    /// A 29-bit identifier.
    pub extended: bool,
    /// Its length, bytes.
    pub length: u8,
    /// The ECU that sends it.
    pub sender: Option<String>,
    /// Its description.
    pub comment: String,
    /// Its signals.
    pub signals: Vec<Signal>,
}

/// A signal of a frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Signal {
    /// Its name.
    pub name: String,
    /// The DBC's start bit: the least significant bit for Intel, the most significant for
    /// Motorola (DBC numbering).
    pub start_bit: u16,
    /// Its length, bits.
    pub length: u16,
    /// Motorola (big-endian) byte order.
    pub big_endian: bool,
    /// Two's complement.
    pub signed: bool,
    /// Physical = raw * factor + offset.
    pub factor: f64,
    /// See `factor`.
    pub offset: f64,
    /// The physical range, where the description gives one.
    pub range: Option<(f64, f64)>,
    /// The unit.
    pub unit: String,
    /// Named raw values.
    pub values: Vec<(i64, String)>,
    /// The ECUs that receive it.
    pub receivers: Vec<String>,
    /// Its description.
    pub comment: String,
}

/// A system description read: the bus, one sentence per element read but not used, and
/// where each frame and signal was read.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Read {
    /// The bus.
    pub system: System,
    /// What was read and has no place in the model, with its path.
    pub notes: Vec<String>,
    /// Where each frame and signal was read.
    pub places: Places,
}

/// Where the frames and signals of a bus were read: an ARXML path (the frame's
/// `CAN-FRAME-TRIGGERING`, the signal's `I-SIGNAL-TO-I-PDU-MAPPING`) or a DBC's line
/// (`ecu.dbc: BO_ 256 DistanceFrame, SG_ Distance`), for errors that name them.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Places {
    frames: HashMap<String, String>,
    signals: HashMap<(String, String), String>,
}

impl Places {
    /// The frame `frame`'s place (its name, where it was not read).
    pub fn frame(&self, frame: &str) -> String {
        self.frames
            .get(frame)
            .cloned()
            .unwrap_or_else(|| format!("frame {frame}"))
    }

    /// The place of the signal `signal` of the frame `frame`.
    pub fn signal(&self, frame: &str, signal: &str) -> String {
        self.signals
            .get(&(frame.to_string(), signal.to_string()))
            .cloned()
            .unwrap_or_else(|| format!("signal {signal} of frame {frame}"))
    }

    fn add_frame(&mut self, frame: &str, at: &str) {
        self.frames.insert(frame.to_string(), at.to_string());
    }

    fn add_signal(&mut self, frame: &str, signal: &str, at: &str) {
        self.signals
            .insert((frame.to_string(), signal.to_string()), at.to_string());
    }
}

/// The DBC's name for "no node".
const NO_NODE: &str = "Vector__XXX";

/// A DBC's text (`source` names it in errors) as a system: every message, signal, node,
/// comment and value table. What a system description has no place for (attributes,
/// signal groups, environment variables, global value tables, the pseudo-message of
/// signals no message carries) is a note.
///
/// # Errors
/// The DBC does not parse, or holds what a system description of this project cannot
/// carry or what no bus has (a multiplexed or float signal, a message with two
/// transmitters, an identifier out of its range or used twice, a length no CAN frame has,
/// a signal outside its frame or over another, a node `BU_` does not list), each named
/// with its message and signal.
pub fn from_dbc(text: &str, source: &str) -> Result<Read, Vec<Error>> {
    let dbc = can_dbc::Dbc::try_from(text).map_err(|e| {
        vec![Error::new(
            format!("the DBC does not parse: {e:?}"),
            &[source],
        )]
    })?;
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let mut places = Places::default();
    // The identifiers as written: the parser keeps 16 bits of a standard one and 29 of an
    // extended one.
    let mut written: HashMap<&str, u64> = HashMap::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        if words.next() == Some("BO_") {
            if let (Some(id), Some(name)) =
                (words.next().and_then(|i| i.parse().ok()), words.next())
            {
                written.insert(name.trim_end_matches(':'), id);
            }
        }
    }
    let attributes = dbc.attribute_definitions.len()
        + dbc.attribute_values_database.len()
        + dbc.attribute_values_node.len()
        + dbc.attribute_values_message.len()
        + dbc.attribute_values_signal.len();
    for (what, count) in [
        (
            "attribute definitions and values (BA_DEF_, BA_)",
            attributes,
        ),
        ("signal groups (SIG_GROUP_)", dbc.signal_groups.len()),
        (
            "environment variables (EV_)",
            dbc.environment_variables.len(),
        ),
        ("global value tables (VAL_TABLE_)", dbc.value_tables.len()),
    ] {
        if count > 0 {
            notes.push(format!(
                "{source}: {count} {what}: the system description has no place for them"
            ));
        }
    }
    let id_of = |id: can_dbc::MessageId| match id {
        can_dbc::MessageId::Standard(id) => (u32::from(id), false),
        can_dbc::MessageId::Extended(id) => (id, true),
    };
    let mut comments: HashMap<(Option<(u32, bool)>, String), String> = HashMap::new();
    for c in &dbc.comments {
        match c {
            can_dbc::Comment::Node { name, comment } => {
                comments.insert((None, name.clone()), comment.clone());
            }
            can_dbc::Comment::Message { id, comment } => {
                comments.insert((Some(id_of(*id)), String::new()), comment.clone());
            }
            can_dbc::Comment::Signal {
                message_id,
                name,
                comment,
            } => {
                comments.insert((Some(id_of(*message_id)), name.clone()), comment.clone());
            }
            can_dbc::Comment::EnvVar { .. } | can_dbc::Comment::Plain { .. } => {}
        }
    }
    let comment = |key: (Option<(u32, bool)>, String)| {
        comments.get(&key).map(|c| unescaped(c)).unwrap_or_default()
    };
    let mut system = System {
        bus: "CAN".to_string(),
        nodes: dbc
            .nodes
            .iter()
            .map(|n| Node {
                name: n.0.clone(),
                comment: comment((None, n.0.clone())),
            })
            .collect(),
        frames: Vec::new(),
    };
    let known = |node: &str| node == NO_NODE || dbc.nodes.iter().any(|n| n.0 == node);
    for t in &dbc.message_transmitters {
        if t.transmitter.len() > 1 {
            out.push(Error::new(
                format!(
                    "message {:#x} has {} transmitters: a frame has one sender here",
                    t.message_id.raw(),
                    t.transmitter.len()
                ),
                &[&format!("{source}: BO_TX_BU_ {}", t.message_id.raw())],
            ));
        }
    }
    for t in dbc.signal_extended_value_type_list.iter().filter(|t| {
        t.signal_extended_value_type != can_dbc::SignalExtendedValueType::SignedOrUnsignedInteger
    }) {
        out.push(Error::new(
            format!(
                "signal {} is a float: only integer signals are mapped",
                t.signal_name
            ),
            &[&format!(
                "{source}: SIG_VALTYPE_ {} {}",
                t.message_id.raw(),
                t.signal_name
            )],
        ));
    }
    for m in &dbc.messages {
        let (id, extended) = id_of(m.id);
        let raw = written
            .get(m.name.as_str())
            .copied()
            .unwrap_or_else(|| u64::from(m.id.raw()));
        let at = format!("{source}: BO_ {raw} {}", m.name);
        if raw == INDEPENDENT_SIGNALS {
            notes.push(format!(
                "{at}: the pseudo-message of signals no message carries is not a frame"
            ));
            continue;
        }
        let standard = raw & 1 << 31 == 0;
        if (standard && raw > 0x7FF) || (!standard && raw & !(1 << 31) > 0x1FFF_FFFF) {
            out.push(Error::new(
                format!(
                    "message {}'s identifier {raw} is out of a{} identifier's range",
                    m.name,
                    if standard {
                        " standard (11-bit)"
                    } else {
                        "n extended (29-bit)"
                    }
                ),
                &[&at],
            ));
            continue;
        }
        let Some(length) = u8::try_from(m.size)
            .ok()
            .filter(|l| DLC_LENGTHS.contains(l))
        else {
            out.push(Error::new(
                format!(
                    "message {} is {} bytes long: no CAN frame has that length",
                    m.name, m.size
                ),
                &[&at],
            ));
            continue;
        };
        if let Some(first) = system
            .frames
            .iter()
            .find(|f| (f.id, f.extended) == (id, extended))
        {
            out.push(Error::new(
                format!(
                    "messages {} and {} have one identifier, {raw}",
                    first.name, m.name
                ),
                &[&at],
            ));
            continue;
        }
        // A transmitter given in BO_TX_BU_ alone is the sender.
        let listed = dbc
            .message_transmitters
            .iter()
            .find(|t| t.message_id == m.id)
            .and_then(|t| t.transmitter.first())
            .cloned();
        let sender = match (m.transmitter.clone().filter(|t| t != NO_NODE), listed) {
            (Some(a), Some(b)) if a != b => {
                out.push(Error::new(
                    format!(
                        "message {} is sent by {a} and, in BO_TX_BU_, by {b}: a frame has one sender here",
                        m.name
                    ),
                    &[&at],
                ));
                continue;
            }
            (a, b) => a.or(b),
        };
        for node in sender
            .iter()
            .chain(m.signals.iter().flat_map(|s| s.receivers.iter()))
        {
            if !known(node) {
                out.push(Error::new(
                    format!("node {node} of message {} is not one of BU_'s", m.name),
                    &[&at],
                ));
            }
        }
        let mut frame = Frame {
            name: m.name.clone(),
            id,
            extended,
            length,
            sender,
            comment: comment((Some((id, extended)), String::new())),
            signals: Vec::new(),
        };
        places.add_frame(&m.name, &at);
        for s in &m.signals {
            let at = format!("{at}, SG_ {}", s.name);
            places.add_signal(&m.name, &s.name, &at);
            if s.multiplexer_indicator != can_dbc::MultiplexIndicator::Plain {
                out.push(Error::new(
                    format!(
                        "signal {}.{} is multiplexed: multiplexing is not mapped",
                        m.name, s.name
                    ),
                    &[&at],
                ));
                continue;
            }
            let (Ok(start_bit), Ok(length)) = (u16::try_from(s.start_bit), u16::try_from(s.size))
            else {
                out.push(Error::new(
                    format!("signal {}.{} is out of any frame", m.name, s.name),
                    &[&at],
                ));
                continue;
            };
            if s.factor == 0.0 || !s.factor.is_finite() || !s.offset.is_finite() {
                out.push(Error::new(
                    format!(
                        "signal {}.{} has the factor {}: a raw value must give one physical value",
                        m.name, s.name, s.factor
                    ),
                    &[&at],
                ));
                continue;
            }
            let number = |v: can_dbc::NumericValue| match v {
                can_dbc::NumericValue::Uint(v) => v as f64,
                can_dbc::NumericValue::Int(v) => v as f64,
                can_dbc::NumericValue::Double(v) => v,
            };
            let values = dbc
                .value_descriptions
                .iter()
                .find_map(|v| match v {
                    can_dbc::ValueDescription::Signal {
                        message_id,
                        name,
                        value_descriptions,
                    } if *message_id == m.id && name == &s.name => Some(
                        value_descriptions
                            .iter()
                            .map(|d| (d.id, unescaped(&d.description)))
                            .collect(),
                    ),
                    _ => None,
                })
                .unwrap_or_default();
            frame.signals.push(Signal {
                name: s.name.clone(),
                start_bit,
                length,
                big_endian: s.byte_order == can_dbc::ByteOrder::BigEndian,
                signed: s.value_type == can_dbc::ValueType::Signed,
                factor: s.factor,
                offset: s.offset,
                // `[0|0]` is a DBC's "no range".
                range: Some((number(s.min), number(s.max))).filter(|&r| r != (0.0, 0.0)),
                unit: unescaped(&s.unit),
                values,
                receivers: s
                    .receivers
                    .iter()
                    .filter(|r| *r != NO_NODE)
                    .cloned()
                    .collect(),
                comment: comment((Some((id, extended)), s.name.clone())),
            });
        }
        out.extend(layout_errors(&frame, &at));
        system.frames.push(frame);
    }
    out.extend(duplicate_errors(&system, &places));
    if out.is_empty() {
        Ok(Read {
            system,
            notes,
            places,
        })
    } else {
        Err(out)
    }
}

/// Two frames of one identifier or one name, or two signals of one name in a frame: the
/// bus would be ambiguous (which one a node sends, which one a name means).
fn duplicate_errors(system: &System, places: &Places) -> Vec<Error> {
    let mut out = Vec::new();
    for (k, f) in system.frames.iter().enumerate() {
        let earlier = system.frames.iter().take(k);
        if let Some(first) = earlier
            .clone()
            .find(|g| (g.id, g.extended) == (f.id, f.extended))
        {
            out.push(Error::new(
                format!(
                    "frames {} and {} have one identifier, {:#x}",
                    first.name, f.name, f.id
                ),
                &[&places.frame(&f.name), &places.frame(&first.name)],
            ));
        } else if earlier.clone().any(|g| g.name == f.name) {
            out.push(Error::new(
                format!("two frames are named {}", f.name),
                &[&places.frame(&f.name)],
            ));
        }
        for (j, sig) in f.signals.iter().enumerate() {
            if f.signals.iter().take(j).any(|t| t.name == sig.name) {
                out.push(Error::new(
                    format!("frame {} has two signals named {}", f.name, sig.name),
                    &[&places.signal(&f.name, &sig.name)],
                ));
            }
        }
    }
    out
}

/// The identifier of a DBC's pseudo-message for the signals no message carries
/// (`VECTOR__INDEPENDENT_SIG_MSG`).
const INDEPENDENT_SIGNALS: u64 = 0xC000_0000;

/// The lengths a CAN frame has: 0 to 8 bytes, and CAN FD's 12 to 64.
const DLC_LENGTHS: [u8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// A DBC string as it is meant: `\"` is a quote, `\\` a backslash.
fn unescaped(s: &str) -> String {
    s.replace("\\\"", "\"").replace("\\\\", "\\")
}

/// Each signal of `frame` outside it, and each pair sharing a bit, as an error at `at`.
pub fn layout_errors(frame: &Frame, at: &str) -> Vec<Error> {
    use crate::model::Endianness;
    let mut out = Vec::new();
    let mut taken: Vec<(u64, &str)> = Vec::new();
    for s in &frame.signals {
        let order = if s.big_endian {
            Endianness::Big
        } else {
            Endianness::Little
        };
        let Some(bits) = crate::validate::signal_bits(
            u64::from(s.start_bit),
            u64::from(s.length),
            order,
            u64::from(frame.length),
        ) else {
            out.push(Error::new(
                format!(
                    "signal {}.{} (start bit {}, {} bits, {}) does not fit in its {}-byte frame",
                    frame.name,
                    s.name,
                    s.start_bit,
                    s.length,
                    order_name(s.big_endian),
                    frame.length
                ),
                &[at],
            ));
            continue;
        };
        if let Some((_, other)) = taken.iter().find(|(b, _)| bits.contains(b)) {
            out.push(Error::new(
                format!(
                    "signals {}.{other} and {}.{} share bits",
                    frame.name, frame.name, s.name
                ),
                &[at],
            ));
        }
        taken.extend(bits.into_iter().map(|b| (b, s.name.as_str())));
    }
    out
}

/// A quoted DBC string.
fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// The system as a DBC's text (nodes, messages, signals, comments, value tables).
pub fn to_dbc(system: &System) -> String {
    let mut s =
        String::from("VERSION \"\"\n\nNS_ :\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\nBS_:\n\nBU_:");
    for n in &system.nodes {
        let _ = write!(s, " {}", n.name);
    }
    s.push_str("\n\n");
    let raw_id = |f: &Frame| if f.extended { f.id | 1 << 31 } else { f.id };
    for f in &system.frames {
        let _ = writeln!(
            s,
            "BO_ {} {}: {} {}",
            raw_id(f),
            f.name,
            f.length,
            f.sender.as_deref().unwrap_or(NO_NODE)
        );
        for g in &f.signals {
            let (min, max) = g.range.unwrap_or((0.0, 0.0));
            let receivers = if g.receivers.is_empty() {
                NO_NODE.to_string()
            } else {
                g.receivers.join(",")
            };
            let _ = writeln!(
                s,
                " SG_ {} : {}|{}@{}{} ({},{}) [{}|{}] {} {}",
                g.name,
                g.start_bit,
                g.length,
                if g.big_endian { 0 } else { 1 },
                if g.signed { '-' } else { '+' },
                g.factor,
                g.offset,
                min,
                max,
                quoted(&g.unit),
                receivers
            );
        }
        s.push('\n');
    }
    for n in system.nodes.iter().filter(|n| !n.comment.is_empty()) {
        let _ = writeln!(s, "CM_ BU_ {} {};", n.name, quoted(&n.comment));
    }
    for f in &system.frames {
        if !f.comment.is_empty() {
            let _ = writeln!(s, "CM_ BO_ {} {};", raw_id(f), quoted(&f.comment));
        }
        for g in f.signals.iter().filter(|g| !g.comment.is_empty()) {
            let _ = writeln!(
                s,
                "CM_ SG_ {} {} {};",
                raw_id(f),
                g.name,
                quoted(&g.comment)
            );
        }
    }
    for f in &system.frames {
        for g in f.signals.iter().filter(|g| !g.values.is_empty()) {
            let _ = write!(s, "VAL_ {} {}", raw_id(f), g.name);
            for (v, name) in &g.values {
                let _ = write!(s, " {v} {}", quoted(name));
            }
            s.push_str(" ;\n");
        }
    }
    s
}

/// Element kinds of a system description that this model cannot carry: refused.
const REFUSED: &[(ElementName, &str)] = &[
    (ElementName::MultiplexedIPdu, "a multiplexed I-PDU"),
    (ElementName::ContainerIPdu, "a container I-PDU"),
    (ElementName::SecuredIPdu, "a secured I-PDU"),
    (ElementName::FlexrayCluster, "a FlexRay cluster"),
    (ElementName::EthernetCluster, "an Ethernet cluster"),
    (ElementName::LinCluster, "a LIN cluster"),
    (ElementName::ISignalGroup, "a signal group"),
];

/// Element kinds read but without a place in the model: a note each.
const NOTED: &[(ElementName, &str)] = &[
    (ElementName::ISignalIPduGroup, "an I-PDU group"),
    (ElementName::SystemSignalGroup, "a system signal group"),
    (ElementName::CanCommunicationController, "a CAN controller"),
];

/// `e`'s description (`DESC`, its first `L-2`), as written.
fn doc(e: &Element) -> String {
    e.get_sub_element(ElementName::Desc)
        .and_then(|d| d.get_sub_element(ElementName::L2))
        .and_then(|l| l.character_data())
        .map(|c| c.to_string())
        .unwrap_or_default()
}

/// The element `e`'s reference `n` points to; an error naming `e` if it points nowhere.
fn reference(e: &Element, n: ElementName, out: &mut Vec<Error>) -> Option<Element> {
    crate::rte::target(e, n, out)
}

fn number(e: &Element, n: ElementName, out: &mut Vec<Error>) -> Option<f64> {
    let t = text(e, n)?;
    match t.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Some(v),
        _ => {
            out.push(Error::new(
                format!("{n} `{t}` is not a number"),
                &[&path_of(e)],
            ));
            None
        }
    }
}

fn integer(e: &Element, n: ElementName, out: &mut Vec<Error>) -> Option<u64> {
    let t = text(e, n);
    match t.as_deref().and_then(crate::arxml::parse_int) {
        Some(v) => Some(v),
        None => {
            out.push(Error::new(
                format!("{n} `{}` is not a whole number", t.unwrap_or_default()),
                &[&path_of(e)],
            ));
            None
        }
    }
}

/// The ECU instance a port belongs to, and the port's direction (`OUT` is true).
fn port_of(port: &Element) -> Option<(String, bool)> {
    let mut up = port.parent().ok().flatten();
    while let Some(e) = up {
        if e.element_name() == ElementName::EcuInstance {
            let out = text(port, ElementName::CommunicationDirection).as_deref() == Some("OUT");
            return Some((e.item_name()?, out));
        }
        up = e.parent().ok().flatten();
    }
    None
}

/// The ports a list of port references reaches: ECU and direction each.
fn ports(e: &Element, list: ElementName, out: &mut Vec<Error>) -> Vec<(String, bool)> {
    let mut found = Vec::new();
    for r in e
        .get_sub_element(list)
        .iter()
        .flat_map(Element::sub_elements)
    {
        match r.get_reference_target().ok().as_ref().and_then(port_of) {
            Some(p) => found.push(p),
            None => out.push(Error::new(
                format!(
                    "{} {} is no port of an ECU instance",
                    r.element_name(),
                    r.character_data()
                        .map(|c| c.to_string())
                        .unwrap_or_default()
                ),
                &[&path_of(e)],
            )),
        }
    }
    found
}

/// The compu method's factor, offset, physical range and named values.
#[allow(clippy::type_complexity)]
fn compu(
    m: &Element,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) -> (f64, f64, Option<(f64, f64)>, Vec<(i64, String)>) {
    let (mut factor, mut offset, mut raw_range) = (1.0, 0.0, None);
    let mut values = Vec::new();
    let mut linear_scales = 0;
    // canmatrix writes no category for a table of named values.
    let category = text(m, ElementName::Category);
    if !matches!(
        category.as_deref(),
        None | Some(
            "IDENTICAL" | "LINEAR" | "SCALE_LINEAR" | "TEXTTABLE" | "SCALE_LINEAR_AND_TEXTTABLE"
        )
    ) {
        out.push(Error::new(
            format!(
                "COMPU-METHOD category {}: a signal's scaling is linear, a table of named values, or both",
                category.unwrap_or_default()
            ),
            &[&path_of(m)],
        ));
    }
    let scales = m
        .get_sub_element(ElementName::CompuInternalToPhys)
        .and_then(|c| c.get_sub_element(ElementName::CompuScales));
    for scale in scales.iter().flat_map(Element::sub_elements) {
        let at = path_of(m);
        if let Some(coeffs) = scale.get_sub_element(ElementName::CompuRationalCoeffs) {
            linear_scales += 1;
            if linear_scales == 2 {
                out.push(Error::new(
                    "two linear scales: a signal's scaling is one",
                    &[&at],
                ));
            }
            let vs = |n: ElementName| -> Vec<f64> {
                coeffs
                    .get_sub_element(n)
                    .iter()
                    .flat_map(Element::sub_elements)
                    .filter_map(|v| v.character_data()?.to_string().trim().parse().ok())
                    .collect()
            };
            match (vs(ElementName::CompuNumerator).as_slice(), vs(ElementName::CompuDenominator).as_slice()) {
                ([o, f], [d]) if *d != 0.0 && *f != 0.0 => {
                    offset = o / d;
                    factor = f / d;
                }
                _ => out.push(Error::new(
                    "a linear scale is its offset and a non-zero factor over a non-zero denominator"
                        .to_string(),
                    &[&at],
                )),
            }
            let low = number(&scale, ElementName::LowerLimit, out);
            let high = number(&scale, ElementName::UpperLimit, out);
            if let (Some(l), Some(h)) = (low, high) {
                raw_range = Some((l, h));
                notes.push(format!(
                    "{at}: the linear scale's limits are read as raw values, as AUTOSAR gives them (canmatrix writes physical ones: the two agree where the factor is 1 and the offset 0)"
                ));
            }
        } else if let Some(vt) = scale
            .get_sub_element(ElementName::CompuConst)
            .and_then(|c| c.get_sub_element(ElementName::Vt))
            .and_then(|v| v.character_data())
        {
            let low = number(&scale, ElementName::LowerLimit, out);
            let high = number(&scale, ElementName::UpperLimit, out);
            let vt = vt.to_string();
            // canmatrix writes the DBC's name in the scale's DESC and a mangled one
            // (`cm_0_Off`) as the VT.
            let desc = doc(&scale);
            let name = if vt.starts_with("cm_") && !desc.is_empty() {
                notes.push(format!("{at}: the value name `{desc}` is read from DESC, not the VT `{vt}` (canmatrix's export)"));
                desc
            } else {
                vt
            };
            match (low, high) {
                (Some(l), Some(h)) if l == h && l.fract() == 0.0 && l.abs() < 9.2e18 => {
                    values.push((l as i64, name));
                }
                _ => out.push(Error::new(
                    format!("the value `{name}` is not one whole raw value (its limits differ)"),
                    &[&at],
                )),
            }
        }
    }
    let range = raw_range.map(|(l, h)| (l * factor + offset, h * factor + offset));
    (factor, offset, range, values)
}

/// The system description in an ARXML file (`file_name` names it in errors): its one CAN
/// cluster's frames, their signals and senders and receivers, and the ECU instances.
///
/// # Errors
/// The file does not parse, has no CAN cluster or several, or holds what the model cannot
/// carry, each with its path.
pub fn read(bytes: &[u8], file_name: &str) -> Result<Read, Vec<Error>> {
    let mut notes = Vec::new();
    let bytes = utf8_declared(bytes, file_name, &mut notes).map_err(|e| vec![e])?;
    let bytes = known_schema(bytes, file_name, &mut notes);
    let model = crate::arxml::load(&bytes, file_name)?;
    let mut out = Vec::new();
    let mut places = Places::default();
    let mut clusters = Vec::new();
    let mut nodes = Vec::new();
    for (_, e) in model.elements_dfs() {
        let kind = e.element_name();
        if let Some((_, what)) = REFUSED.iter().find(|(k, _)| *k == kind) {
            out.push(Error::new(
                format!("{what} cannot be mapped to a DBC's frames"),
                &[&path_of(&e)],
            ));
        }
        if let Some((_, what)) = NOTED.iter().find(|(k, _)| *k == kind) {
            notes.push(format!("{}: {what} is not used", path_of(&e)));
        }
        match kind {
            ElementName::CanCluster => clusters.push(e),
            ElementName::EcuInstance => nodes.push(Node {
                name: e.item_name().unwrap_or_default(),
                comment: doc(&e),
            }),
            _ => {}
        }
    }
    let cluster = match clusters.as_slice() {
        [one] => one.clone(),
        [] => {
            out.push(Error::new(
                "no CAN-CLUSTER: the description has no CAN bus",
                &[file_name],
            ));
            return Err(out);
        }
        [first, second, ..] => {
            out.push(Error::new(
                "two CAN clusters: a DBC describes one bus",
                &[&path_of(first), &path_of(second)],
            ));
            return Err(out);
        }
    };
    let mut system = System {
        bus: cluster.item_name().unwrap_or_default(),
        nodes,
        frames: Vec::new(),
    };
    let channels: Vec<Element> = cluster
        .get_sub_element(ElementName::CanClusterVariants)
        .iter()
        .flat_map(Element::sub_elements)
        .filter_map(|c| c.get_sub_element(ElementName::PhysicalChannels))
        .flat_map(|p| p.sub_elements().collect::<Vec<_>>())
        .collect();
    for channel in &channels {
        let signal_triggerings: Vec<Element> = channel
            .get_sub_element(ElementName::ISignalTriggerings)
            .iter()
            .flat_map(Element::sub_elements)
            .collect();
        for t in channel
            .get_sub_element(ElementName::FrameTriggerings)
            .iter()
            .flat_map(Element::sub_elements)
        {
            if let Some(f) = read_frame(&t, &signal_triggerings, &mut out, &mut notes, &mut places)
            {
                system.frames.push(f);
            }
        }
    }
    out.extend(duplicate_errors(&system, &places));
    if out.is_empty() {
        Ok(Read {
            system,
            notes,
            places,
        })
    } else {
        Err(out)
    }
}

/// The XML declaration ARXML files have (`autosar-data` reads no other).
const DECLARATION: &str = "<?xml version=\"1.0\" encoding=\"utf-8\"?>";

/// `bytes` with the XML declaration `autosar-data` reads: another one that declares ASCII
/// or UTF-8 (canmatrix writes `<?xml version='1.0' encoding='ASCII'?>`) is replaced, with a
/// note, where the bytes are that; any other encoding is refused.
fn utf8_declared<'b>(
    bytes: &'b [u8],
    file_name: &str,
    notes: &mut Vec<String>,
) -> Result<std::borrow::Cow<'b, [u8]>, Error> {
    let Some(rest) = bytes.strip_prefix(b"<?xml") else {
        return Ok(bytes.into());
    };
    let Some(end) = rest.windows(2).position(|w| w == b"?>") else {
        return Ok(bytes.into());
    };
    let declared = String::from_utf8_lossy(bytes.get(..end + 7).unwrap_or_default()).into_owned();
    if declared == DECLARATION {
        return Ok(bytes.into());
    }
    let lower = declared.to_ascii_lowercase().replace('\'', "\"");
    let ascii = lower.contains("encoding=\"ascii\"") || lower.contains("encoding=\"us-ascii\"");
    let utf8 = lower.contains("encoding=\"utf-8\"") || !lower.contains("encoding=");
    let body = bytes.get(end + 7..).unwrap_or_default();
    let fits = if ascii {
        body.is_ascii()
    } else {
        utf8 && std::str::from_utf8(body).is_ok()
    };
    if !lower.contains("version=\"1.0\"") || !fits {
        return Err(Error::new(
            format!("the XML declaration `{declared}`: an ARXML file is UTF-8 (or ASCII)"),
            &[file_name],
        ));
    }
    notes.push(format!(
        "{file_name}: the XML declaration `{declared}` is read as `{DECLARATION}`"
    ));
    let mut fixed = DECLARATION.as_bytes().to_vec();
    fixed.extend_from_slice(body);
    Ok(fixed.into())
}

/// Schema files that no AUTOSAR release has, as tools name them, and the release read for
/// each: canmatrix names `AUTOSAR_4-1-0.xsd`; 4.1.1 is the first release of 4.1.
const SCHEMAS_READ_AS: [(&str, &str); 1] = [("AUTOSAR_4-1-0.xsd", "AUTOSAR_4-1-1.xsd")];

/// `bytes` with a schema no release has, in the root element's `xsi:schemaLocation`,
/// replaced by the release read for it, with a note.
fn known_schema<'b>(
    bytes: std::borrow::Cow<'b, [u8]>,
    file_name: &str,
    notes: &mut Vec<String>,
) -> std::borrow::Cow<'b, [u8]> {
    // The root element's start tag is within the file's first kilobyte.
    let head = bytes.get(..bytes.len().min(1024)).unwrap_or_default();
    for (unknown, known) in SCHEMAS_READ_AS {
        let Some(at) = head
            .windows(unknown.len())
            .position(|w| w == unknown.as_bytes())
        else {
            continue;
        };
        notes.push(format!(
            "{file_name}: the schema {unknown}, which no AUTOSAR release has, is read as {known}"
        ));
        let mut fixed = bytes.get(..at).unwrap_or_default().to_vec();
        fixed.extend_from_slice(known.as_bytes());
        fixed.extend_from_slice(bytes.get(at + unknown.len()..).unwrap_or_default());
        return fixed.into();
    }
    bytes
}

fn read_frame(
    t: &Element,
    signal_triggerings: &[Element],
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
    places: &mut Places,
) -> Option<Frame> {
    let at = path_of(t);
    let id = integer(t, ElementName::Identifier, out)?;
    let extended = match text(t, ElementName::CanAddressingMode).as_deref() {
        None | Some("STANDARD") => false,
        Some("EXTENDED") => true,
        Some(other) => {
            out.push(Error::new(format!("CAN-ADDRESSING-MODE {other}"), &[&at]));
            false
        }
    };
    let limit = if extended { 0x1FFF_FFFF } else { 0x7FF };
    let Some(id) = u32::try_from(id).ok().filter(|&i| i <= limit) else {
        out.push(Error::new(
            format!("identifier {id} is out of its range (at most {limit:#x})"),
            &[&at],
        ));
        return None;
    };
    // The frame's I-PDU is read from its PDU-TO-FRAME-MAPPING; a PDU triggering it names
    // that is not there (canmatrix writes the path one level short) is noted.
    for r in t
        .get_sub_element(ElementName::PduTriggerings)
        .iter()
        .flat_map(Element::sub_elements)
        .filter_map(|c| c.get_sub_element(ElementName::PduTriggeringRef))
    {
        if r.get_reference_target().is_err() {
            notes.push(format!(
                "{at}: PDU-TRIGGERING-REF {} refers to nothing; the frame's I-PDU is read from its PDU-TO-FRAME-MAPPING",
                r.character_data().map(|c| c.to_string()).unwrap_or_default()
            ));
        }
    }
    let frame = reference(t, ElementName::FrameRef, out)?;
    let length = integer(&frame, ElementName::FrameLength, out)?;
    let Some(length) = u8::try_from(length)
        .ok()
        .filter(|l| DLC_LENGTHS.contains(l))
    else {
        out.push(Error::new(
            format!("a frame of {length} bytes: no CAN frame has that length"),
            &[&path_of(&frame)],
        ));
        return None;
    };
    let senders: Vec<String> = ports(t, ElementName::FramePortRefs, out)
        .into_iter()
        .filter(|(_, o)| *o)
        .map(|(ecu, _)| ecu)
        .collect();
    if senders.len() > 1 {
        out.push(Error::new(
            format!(
                "{} ECUs send the frame: a frame has one sender here",
                senders.len()
            ),
            &[&at],
        ));
    }
    let mappings: Vec<Element> = frame
        .get_sub_element(ElementName::PduToFrameMappings)
        .iter()
        .flat_map(Element::sub_elements)
        .collect();
    let [mapping] = mappings.as_slice() else {
        out.push(Error::new(
            format!(
                "the frame holds {} I-PDUs: one, at byte 0, is mapped",
                mappings.len()
            ),
            &[&path_of(&frame)],
        ));
        return None;
    };
    if integer(mapping, ElementName::StartPosition, out) != Some(0) {
        out.push(Error::new(
            "the I-PDU does not start at the frame's bit 0",
            &[&path_of(mapping)],
        ));
    }
    let pdu = reference(mapping, ElementName::PduRef, out)?;
    if pdu.element_name() != ElementName::ISignalIPdu {
        out.push(Error::new(
            format!(
                "a {} cannot be mapped to a DBC's message",
                pdu.element_name()
            ),
            &[&path_of(&pdu)],
        ));
        return None;
    }
    let mut f = Frame {
        name: t.item_name().unwrap_or_default(),
        id,
        extended,
        length,
        sender: senders.into_iter().next(),
        comment: doc(&frame),
        signals: Vec::new(),
    };
    for m in pdu
        .get_sub_element(ElementName::ISignalToPduMappings)
        .iter()
        .flat_map(Element::sub_elements)
    {
        if let Some(s) = read_signal(&m, signal_triggerings, out, notes) {
            places.add_signal(&f.name, &s.name, &path_of(&m));
            f.signals.push(s);
        }
    }
    out.extend(layout_errors(&f, &at));
    places.add_frame(&f.name, &at);
    Some(f)
}

fn read_signal(
    m: &Element,
    signal_triggerings: &[Element],
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) -> Option<Signal> {
    let at = path_of(m);
    let signal = reference(m, ElementName::ISignalRef, out)?;
    let start = integer(m, ElementName::StartPosition, out)?;
    let big_endian = match text(m, ElementName::PackingByteOrder).as_deref() {
        Some("MOST-SIGNIFICANT-BYTE-FIRST") => true,
        Some("MOST-SIGNIFICANT-BYTE-LAST" | "OPAQUE") | None => false,
        Some(other) => {
            out.push(Error::new(format!("PACKING-BYTE-ORDER {other}"), &[&at]));
            false
        }
    };
    let length = integer(&signal, ElementName::Length, out)?;
    let (Ok(start_bit), Ok(length)) = (u16::try_from(start), u16::try_from(length)) else {
        out.push(Error::new("the signal is out of any frame", &[&at]));
        return None;
    };
    let props = signal
        .get_sub_element(ElementName::NetworkRepresentationProps)
        .and_then(|p| p.get_sub_element(ElementName::SwDataDefPropsVariants))
        .and_then(|v| v.get_sub_element(ElementName::SwDataDefPropsConditional));
    let mut s = Signal {
        // The mapping's name: a signal's name in its frame (an I-SIGNAL's is unique in
        // its package, so a writer may qualify it).
        name: m.item_name().unwrap_or_default(),
        start_bit,
        length,
        big_endian,
        factor: 1.0,
        comment: signal
            .get_sub_element(ElementName::SystemSignalRef)
            .and_then(|r| r.get_reference_target().ok())
            .map(|sys| doc(&sys))
            .unwrap_or_default(),
        ..Signal::default()
    };
    if let Some(props) = props {
        if props.get_sub_element(ElementName::BaseTypeRef).is_some() {
            if let Some(base) = reference(&props, ElementName::BaseTypeRef, out) {
                let name = base.item_name().unwrap_or_default();
                match text(&base, ElementName::BaseTypeEncoding).as_deref() {
                    Some("2C") => s.signed = true,
                    Some("NONE" | "BOOLEAN") => {}
                    None if name.starts_with("sint") => {
                        s.signed = true;
                        notes.push(format!(
                            "{}: no BASE-TYPE-ENCODING; `{name}` is read as two's complement by its name (canmatrix's export)",
                            path_of(&base)
                        ));
                    }
                    None => {}
                    Some(other) => out.push(Error::new(
                        format!("BASE-TYPE-ENCODING {other}: only integer signals are mapped"),
                        &[&path_of(&base)],
                    )),
                }
            }
        }
        if props.get_sub_element(ElementName::CompuMethodRef).is_some() {
            if let Some(method) = reference(&props, ElementName::CompuMethodRef, out) {
                (s.factor, s.offset, s.range, s.values) = compu(&method, out, notes);
            }
        }
        if props.get_sub_element(ElementName::DataConstrRef).is_some() {
            if let Some(constr) = reference(&props, ElementName::DataConstrRef, out) {
                let phys = constr
                    .get_sub_element(ElementName::DataConstrRules)
                    .and_then(|r| r.get_sub_element(ElementName::DataConstrRule))
                    .and_then(|r| r.get_sub_element(ElementName::PhysConstrs));
                if let Some(phys) = phys {
                    let low = number(&phys, ElementName::LowerLimit, out);
                    let high = number(&phys, ElementName::UpperLimit, out);
                    if let (Some(l), Some(h)) = (low, high) {
                        s.range = Some((l, h));
                    }
                }
            }
        }
        if props.get_sub_element(ElementName::UnitRef).is_some() {
            if let Some(unit) = reference(&props, ElementName::UnitRef, out) {
                s.unit = text(&unit, ElementName::DisplayName).unwrap_or_default();
            }
        }
    }
    let signal_path = path_of(&signal);
    for t in signal_triggerings {
        let targets = t
            .get_sub_element(ElementName::ISignalRef)
            .and_then(|r| r.get_reference_target().ok())
            .is_some_and(|target| path_of(&target) == signal_path);
        if targets {
            for (ecu, sends) in ports(t, ElementName::ISignalPortRefs, out) {
                if !sends && !s.receivers.contains(&ecu) {
                    s.receivers.push(ecu);
                }
            }
        }
    }
    Some(s)
}

/// The system as ARXML (AUTOSAR [`crate::arxml::VERSION`]), in packages below
/// `/{package}/Communication`: `Ecus`, `Clusters`, `Frames`, `Pdus`, `Signals`,
/// `SystemSignals`, `BaseTypes`, `CompuMethods`, `Units`, `DataConstrs`.
///
/// # Errors
/// A name the schema refuses (not an identifier), or two items of one kind with one name.
pub fn write(system: &System, package: &str) -> Result<String, Error> {
    let fail = |e: autosar_data::AutosarDataError| Error::new(e.to_string(), &[package]);
    let model = AutosarModel::new();
    let file = model
        .create_file("system.arxml", crate::arxml::VERSION)
        .map_err(fail)?;
    build(&model, system, package).map_err(fail)?;
    file.serialize().map_err(fail)
}

fn set_text(
    parent: &Element,
    n: ElementName,
    value: &str,
) -> Result<Element, autosar_data::AutosarDataError> {
    let e = parent.create_sub_element(n)?;
    e.set_character_data(value)?;
    Ok(e)
}

fn set_desc(e: &Element, text: &str) -> Result<(), autosar_data::AutosarDataError> {
    if text.is_empty() {
        return Ok(());
    }
    let l2 = e
        .create_sub_element(ElementName::Desc)?
        .create_sub_element(ElementName::L2)?;
    l2.set_attribute(AttributeName::L, EnumItem::ForAll)?;
    l2.set_character_data(text)?;
    Ok(())
}

fn link(
    parent: &Element,
    n: ElementName,
    target: &Element,
) -> Result<(), autosar_data::AutosarDataError> {
    parent.create_sub_element(n)?.set_reference_target(target)?;
    Ok(())
}

/// A number as ARXML writes it: whole numbers without a point.
fn num(v: f64) -> String {
    format!("{v}")
}

#[allow(clippy::too_many_lines)]
fn build(
    model: &AutosarModel,
    system: &System,
    package: &str,
) -> Result<(), autosar_data::AutosarDataError> {
    let top = model
        .root_element()
        .get_or_create_sub_element(ElementName::ArPackages)?
        .create_named_sub_element(ElementName::ArPackage, package)?
        .create_sub_element(ElementName::ArPackages)?
        .create_named_sub_element(ElementName::ArPackage, "Communication")?
        .create_sub_element(ElementName::ArPackages)?;
    let pkg = |name: &str| -> Result<Element, autosar_data::AutosarDataError> {
        top.create_named_sub_element(ElementName::ArPackage, name)?
            .create_sub_element(ElementName::Elements)
    };
    let (ecus, clusters, frames, pdus) =
        (pkg("Ecus")?, pkg("Clusters")?, pkg("Frames")?, pkg("Pdus")?);
    let (signals, system_signals, base_types) =
        (pkg("Signals")?, pkg("SystemSignals")?, pkg("BaseTypes")?);
    let (compu_methods, units, data_constrs) =
        (pkg("CompuMethods")?, pkg("Units")?, pkg("DataConstrs")?);

    // Each ECU's connector, where its ports go.
    let mut connectors: HashMap<&str, Element> = HashMap::new();
    for n in &system.nodes {
        let ecu = ecus.create_named_sub_element(ElementName::EcuInstance, &n.name)?;
        set_desc(&ecu, &n.comment)?;
        let c = ecu
            .create_sub_element(ElementName::Connectors)?
            .create_named_sub_element(
                ElementName::CanCommunicationConnector,
                &format!("{}Connector", n.name),
            )?;
        connectors.insert(n.name.as_str(), c);
    }
    let port = |ecu: &str,
                kind: ElementName,
                name: &str,
                out: bool|
     -> Result<Option<Element>, autosar_data::AutosarDataError> {
        let Some(c) = connectors.get(ecu) else {
            return Ok(None);
        };
        // One port per direction: an ECU may receive a signal of a frame it sends.
        let p = c
            .get_or_create_sub_element(ElementName::EcuCommPortInstances)?
            .create_named_sub_element(kind, &format!("{name}_{}", if out { "Tx" } else { "Rx" }))?;
        p.create_sub_element(ElementName::CommunicationDirection)?
            .set_character_data(if out { EnumItem::Out } else { EnumItem::In })?;
        Ok(Some(p))
    };
    let channel = clusters
        .create_named_sub_element(ElementName::CanCluster, &system.bus)?
        .create_sub_element(ElementName::CanClusterVariants)?
        .create_sub_element(ElementName::CanClusterConditional)?
        .create_sub_element(ElementName::PhysicalChannels)?
        .create_named_sub_element(
            ElementName::CanPhysicalChannel,
            &format!("{}Channel", system.bus),
        )?;
    let mut bases: HashMap<String, Element> = HashMap::new();
    for f in &system.frames {
        let frame = frames.create_named_sub_element(ElementName::CanFrame, &f.name)?;
        set_desc(&frame, &f.comment)?;
        set_text(&frame, ElementName::FrameLength, &f.length.to_string())?;
        let pdu = pdus.create_named_sub_element(ElementName::ISignalIPdu, &f.name)?;
        set_text(&pdu, ElementName::Length, &f.length.to_string())?;
        let ptf = frame
            .create_sub_element(ElementName::PduToFrameMappings)?
            .create_named_sub_element(ElementName::PduToFrameMapping, &f.name)?;
        ptf.create_sub_element(ElementName::PackingByteOrder)?
            .set_character_data(EnumItem::MostSignificantByteLast)?;
        link(&ptf, ElementName::PduRef, &pdu)?;
        set_text(&ptf, ElementName::StartPosition, "0")?;

        let pdu_triggering = channel
            .get_or_create_sub_element(ElementName::PduTriggerings)?
            .create_named_sub_element(
                ElementName::PduTriggering,
                &format!("{}PduTriggering", f.name),
            )?;
        let trig = channel
            .get_or_create_sub_element(ElementName::FrameTriggerings)?
            .create_named_sub_element(ElementName::CanFrameTriggering, &f.name)?;
        let mut frame_ecus: Vec<(&str, bool)> = Vec::new();
        if let Some(sender) = &f.sender {
            frame_ecus.push((sender, true));
        }
        for g in &f.signals {
            for r in &g.receivers {
                if !frame_ecus.iter().any(|(e, _)| e == r) {
                    frame_ecus.push((r, false));
                }
            }
        }
        for (ecu, out) in &frame_ecus {
            if let Some(p) = port(
                ecu,
                ElementName::FramePort,
                &format!("{}_Frame", f.name),
                *out,
            )? {
                link(
                    &trig.get_or_create_sub_element(ElementName::FramePortRefs)?,
                    ElementName::FramePortRef,
                    &p,
                )?;
            }
            if let Some(p) = port(ecu, ElementName::IPduPort, &format!("{}_Pdu", f.name), *out)? {
                link(
                    &pdu_triggering.get_or_create_sub_element(ElementName::IPduPortRefs)?,
                    ElementName::IPduPortRef,
                    &p,
                )?;
            }
        }
        link(&trig, ElementName::FrameRef, &frame)?;
        link(
            &trig
                .create_sub_element(ElementName::PduTriggerings)?
                .create_sub_element(ElementName::PduTriggeringRefConditional)?,
            ElementName::PduTriggeringRef,
            &pdu_triggering,
        )?;
        trig.create_sub_element(ElementName::CanAddressingMode)?
            .set_character_data(if f.extended {
                EnumItem::Extended
            } else {
                EnumItem::Standard
            })?;
        set_text(&trig, ElementName::Identifier, &f.id.to_string())?;
        link(&pdu_triggering, ElementName::IPduRef, &pdu)?;

        let mappings = pdu.create_sub_element(ElementName::ISignalToPduMappings)?;
        for g in &f.signals {
            // The signal's name, and the frame's before it where another frame has a
            // signal of that name (an I-SIGNAL's name is one in its package; other
            // tools, canmatrix among them, take it as the DBC signal's name).
            let shared = system
                .frames
                .iter()
                .filter(|other| other.signals.iter().any(|o| o.name == g.name))
                .count()
                > 1;
            let name = if shared {
                format!("{}_{}", f.name, g.name)
            } else {
                g.name.clone()
            };
            let sys = system_signals.create_named_sub_element(ElementName::SystemSignal, &name)?;
            set_desc(&sys, &g.comment)?;
            let signal = signals.create_named_sub_element(ElementName::ISignal, &name)?;
            set_text(&signal, ElementName::Length, &g.length.to_string())?;
            let props = signal
                .create_sub_element(ElementName::NetworkRepresentationProps)?
                .create_sub_element(ElementName::SwDataDefPropsVariants)?
                .create_sub_element(ElementName::SwDataDefPropsConditional)?;
            let width = [8u16, 16, 32, 64]
                .into_iter()
                .find(|w| *w >= g.length)
                .unwrap_or(64);
            let base_name = format!("{}int{width}", if g.signed { 's' } else { 'u' });
            let base = match bases.get(&base_name) {
                Some(b) => b.clone(),
                None => {
                    let b =
                        base_types.create_named_sub_element(ElementName::SwBaseType, &base_name)?;
                    set_text(&b, ElementName::Category, "FIXED_LENGTH")?;
                    set_text(&b, ElementName::BaseTypeSize, &width.to_string())?;
                    set_text(
                        &b,
                        ElementName::BaseTypeEncoding,
                        if g.signed { "2C" } else { "NONE" },
                    )?;
                    bases.insert(base_name, b.clone());
                    b
                }
            };
            link(&props, ElementName::BaseTypeRef, &base)?;
            let method = compu_methods.create_named_sub_element(ElementName::CompuMethod, &name)?;
            set_text(
                &method,
                ElementName::Category,
                if g.values.is_empty() {
                    "LINEAR"
                } else {
                    "SCALE_LINEAR_AND_TEXTTABLE"
                },
            )?;
            let scales = method
                .create_sub_element(ElementName::CompuInternalToPhys)?
                .create_sub_element(ElementName::CompuScales)?;
            let linear = scales.create_sub_element(ElementName::CompuScale)?;
            let coeffs = linear.create_sub_element(ElementName::CompuRationalCoeffs)?;
            let numerator = coeffs.create_sub_element(ElementName::CompuNumerator)?;
            set_text(&numerator, ElementName::V, &num(g.offset))?;
            set_text(&numerator, ElementName::V, &num(g.factor))?;
            set_text(
                &coeffs.create_sub_element(ElementName::CompuDenominator)?,
                ElementName::V,
                "1",
            )?;
            for (v, text) in &g.values {
                let scale = scales.create_sub_element(ElementName::CompuScale)?;
                set_text(&scale, ElementName::LowerLimit, &v.to_string())?;
                set_text(&scale, ElementName::UpperLimit, &v.to_string())?;
                set_text(
                    &scale.create_sub_element(ElementName::CompuConst)?,
                    ElementName::Vt,
                    text,
                )?;
            }
            link(&props, ElementName::CompuMethodRef, &method)?;
            if let Some((min, max)) = g.range {
                let constr =
                    data_constrs.create_named_sub_element(ElementName::DataConstr, &name)?;
                let phys = constr
                    .create_sub_element(ElementName::DataConstrRules)?
                    .create_sub_element(ElementName::DataConstrRule)?
                    .create_sub_element(ElementName::PhysConstrs)?;
                for (n, v) in [
                    (ElementName::LowerLimit, min),
                    (ElementName::UpperLimit, max),
                ] {
                    let limit = set_text(&phys, n, &num(v))?;
                    limit.set_attribute(AttributeName::IntervalType, EnumItem::Closed)?;
                }
                link(&props, ElementName::DataConstrRef, &constr)?;
            }
            let unit = units.create_named_sub_element(ElementName::Unit, &name)?;
            set_text(&unit, ElementName::DisplayName, &g.unit)?;
            link(&props, ElementName::UnitRef, &unit)?;
            link(&signal, ElementName::SystemSignalRef, &sys)?;

            let m =
                mappings.create_named_sub_element(ElementName::ISignalToIPduMapping, &g.name)?;
            link(&m, ElementName::ISignalRef, &signal)?;
            m.create_sub_element(ElementName::PackingByteOrder)?
                .set_character_data(if g.big_endian {
                    EnumItem::MostSignificantByteFirst
                } else {
                    EnumItem::MostSignificantByteLast
                })?;
            set_text(&m, ElementName::StartPosition, &g.start_bit.to_string())?;

            let st = channel
                .get_or_create_sub_element(ElementName::ISignalTriggerings)?
                .create_named_sub_element(ElementName::ISignalTriggering, &name)?;
            let mut signal_ecus: Vec<(&str, bool)> = Vec::new();
            if let Some(sender) = &f.sender {
                signal_ecus.push((sender, true));
            }
            signal_ecus.extend(g.receivers.iter().map(|r| (r.as_str(), false)));
            for (ecu, out) in signal_ecus {
                if let Some(p) = port(
                    ecu,
                    ElementName::ISignalPort,
                    &format!("{}_{}", f.name, g.name),
                    out,
                )? {
                    link(
                        &st.get_or_create_sub_element(ElementName::ISignalPortRefs)?,
                        ElementName::ISignalPortRef,
                        &p,
                    )?;
                }
            }
            link(&st, ElementName::ISignalRef, &signal)?;
            link(
                &pdu_triggering
                    .get_or_create_sub_element(ElementName::ISignalTriggerings)?
                    .create_sub_element(ElementName::ISignalTriggeringRefConditional)?,
                ElementName::ISignalTriggeringRef,
                &st,
            )?;
        }
    }
    Ok(())
}

/// What `arxml` (a description read from ARXML) says otherwise than `dbc` (the DBC's):
/// one line per difference, naming the frame and signal; and one line per range `arxml`
/// does not give (canmatrix exports none for a signal with named values), which is not a
/// difference.
pub fn differences(dbc: &System, arxml: &System) -> (Vec<String>, Vec<String>) {
    let mut out = Vec::new();
    let mut unchecked = Vec::new();
    let names = |s: &System| -> Vec<String> {
        let mut n: Vec<String> = s.nodes.iter().map(|n| n.name.clone()).collect();
        n.sort();
        n
    };
    if names(dbc) != names(arxml) {
        out.push(format!("the ECUs: {:?} and {:?}", names(dbc), names(arxml)));
    }
    for n in &dbc.nodes {
        if let Some(m) = arxml.nodes.iter().find(|m| m.name == n.name) {
            if m.comment != n.comment {
                out.push(format!(
                    "ECU {}: the comment `{}` and `{}`",
                    n.name, n.comment, m.comment
                ));
            }
        }
    }
    for f in &dbc.frames {
        let Some(g) = arxml.frames.iter().find(|g| g.name == f.name) else {
            out.push(format!("frame {} is missing", f.name));
            continue;
        };
        let frame =
            |what: &str, a: String, b: String| format!("frame {}: {what} {a} and {b}", f.name);
        if (f.id, f.extended) != (g.id, g.extended) {
            out.push(frame(
                "the identifier",
                format!(
                    "{:#x} ({})",
                    f.id,
                    if f.extended { "extended" } else { "standard" }
                ),
                format!(
                    "{:#x} ({})",
                    g.id,
                    if g.extended { "extended" } else { "standard" }
                ),
            ));
        }
        if f.length != g.length {
            out.push(frame(
                "the length",
                f.length.to_string(),
                g.length.to_string(),
            ));
        }
        if f.sender != g.sender {
            out.push(frame(
                "the sender",
                format!("{:?}", f.sender),
                format!("{:?}", g.sender),
            ));
        }
        if f.comment != g.comment {
            out.push(frame(
                "the comment",
                format!("`{}`", f.comment),
                format!("`{}`", g.comment),
            ));
        }
        for a in &f.signals {
            let Some(b) = g.signals.iter().find(|b| b.name == a.name) else {
                out.push(format!("signal {}.{} is missing", f.name, a.name));
                continue;
            };
            let mut differ = |what: &str, x: String, y: String| {
                if x != y {
                    out.push(format!("signal {}.{}: {what} {x} and {y}", f.name, a.name));
                }
            };
            differ(
                "the start bit",
                a.start_bit.to_string(),
                b.start_bit.to_string(),
            );
            differ("the length", a.length.to_string(), b.length.to_string());
            differ(
                "the byte order",
                order_name(a.big_endian).to_string(),
                order_name(b.big_endian).to_string(),
            );
            differ(
                "the signedness",
                sign(a.signed).to_string(),
                sign(b.signed).to_string(),
            );
            differ("the factor", a.factor.to_string(), b.factor.to_string());
            differ("the offset", a.offset.to_string(), b.offset.to_string());
            differ("the unit", format!("`{}`", a.unit), format!("`{}`", b.unit));
            differ(
                "the named values",
                format!("{:?}", a.values),
                format!("{:?}", b.values),
            );
            let mut ra = a.receivers.clone();
            let mut rb = b.receivers.clone();
            ra.sort();
            rb.sort();
            differ("the receivers", format!("{ra:?}"), format!("{rb:?}"));
            differ(
                "the comment",
                format!("`{}`", a.comment),
                format!("`{}`", b.comment),
            );
            match (a.range, b.range) {
                (Some(x), Some(y)) => differ("the range", format!("{x:?}"), format!("{y:?}")),
                (Some(x), None) => unchecked.push(format!(
                    "signal {}.{}: the range {x:?} is not in the description",
                    f.name, a.name
                )),
                (None, Some(y)) => differ("the range", "none".to_string(), format!("{y:?}")),
                (None, None) => {}
            }
        }
        for b in &g.signals {
            if !f.signals.iter().any(|a| a.name == b.name) {
                out.push(format!("signal {}.{} is not in the DBC", f.name, b.name));
            }
        }
    }
    for g in &arxml.frames {
        if !dbc.frames.iter().any(|f| f.name == g.name) {
            out.push(format!("frame {} is not in the DBC", g.name));
        }
    }
    (out, unchecked)
}

fn order_name(big_endian: bool) -> &'static str {
    if big_endian {
        "Motorola"
    } else {
        "Intel"
    }
}

fn sign(signed: bool) -> &'static str {
    if signed {
        "signed"
    } else {
        "unsigned"
    }
}
