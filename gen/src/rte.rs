//! The software components and their RTE (paper §3.1, steps 1 and 3): the description's
//! data types, sender-receiver interfaces, component types with their ports, runnables and
//! events, and the composition that connects them (`firmware/swc.arxml`), read with
//! `autosar-data`, checked, and generated into the RTE's typed connections
//! (`firmware/src/rte.rs`).
//!
//! The RTE keeps one buffer per sender port for the receivers that read the newest value
//! (last-is-best), one more for each receiver whose runnable a data-received event starts
//! (it notes that new data came), and one queue per receiver of a queued data element. A
//! data type names the Rust type that carries it in the SDG `cw-gen`, `RustType` of its
//! `ADMIN-DATA`, the extension point AUTOSAR gives tools; an init value is a text value
//! naming one of that type's constants (`Invalid`: `Measurement::Invalid`).

use std::collections::HashMap;
use std::fmt::Write as _;

use autosar_data::{AttributeName, Element, ElementName};

use crate::validate::Error;

/// Where an item came from: its ARXML path.
pub type Path = String;

/// An `RteEventToTaskMapping`: one RTE event of one prototype, run in a task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mapping {
    /// Its path.
    pub path: Path,
    /// The prototype (`RteSoftwareComponentInstanceRef` of its instance), by name.
    pub prototype: String,
    /// The event's path (`RteEventRef`).
    pub event: Path,
    /// The task's path (`RteMappedToTaskRef`), in the ECU's OS description.
    pub task: Path,
    /// `RtePositionInTask`.
    pub position: u64,
}

/// The software components' description.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Software {
    /// The RTE's ECUC values: each prototype's events mapped to tasks.
    pub mappings: Vec<Mapping>,
    /// The `Rte` module's path (empty: the description has none).
    pub rte_path: Path,
    /// One sentence per element read but not used, with its path.
    pub notes: Vec<String>,
    /// `IMPLEMENTATION-DATA-TYPE`s.
    pub types: Vec<DataType>,
    /// `SENDER-RECEIVER-INTERFACE`s.
    pub interfaces: Vec<Interface>,
    /// Application and service component types.
    pub components: Vec<ComponentType>,
    /// The composition (one).
    pub composition: Composition,
}

/// A data type and the Rust type that carries it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataType {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// The Rust type's path (`cw_core::warning::Measurement`).
    pub rust: String,
}

/// A sender-receiver interface of one data element.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Interface {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// Its description (`DESC`), one line.
    pub doc: String,
    /// The data element's short name.
    pub element: String,
    /// The data element's type (a [`DataType`]'s name).
    pub data_type: String,
    /// `SW-IMPL-POLICY` `QUEUED`: every value is received once, in order.
    pub queued: bool,
}

/// A port of a component type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// A provided (`P-PORT-PROTOTYPE`) port, else a required one.
    pub provided: bool,
    /// Its interface's name.
    pub interface: String,
    /// The com spec's init value (non-queued), as written.
    pub init: Option<String>,
    /// The receiver's queue length (queued).
    pub queue_length: Option<u64>,
    /// The com spec's kind: `Some(true)` for a queued one, `Some(false)` for a non-queued
    /// one, `None` without a com spec.
    pub queued_spec: Option<bool>,
}

/// What starts a runnable.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EventKind {
    /// A `TIMING-EVENT` of this period, ms.
    Timing {
        /// The period, ms.
        period_ms: u64,
    },
    /// A `DATA-RECEIVED-EVENT` on this required port.
    DataReceived {
        /// The port's name.
        port: String,
    },
}

/// An RTE event of a component's internal behaviour.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RteEvent {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// The runnable it starts (its name).
    pub runnable: String,
    /// What it is.
    pub kind: EventKind,
}

/// A component type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ComponentType {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// A `SERVICE-SW-COMPONENT-TYPE` (the basic software's side of a port).
    pub service: bool,
    /// Its ports.
    pub ports: Vec<Port>,
    /// Its runnables: name and path.
    pub runnables: Vec<(String, Path)>,
    /// Its events.
    pub events: Vec<RteEvent>,
}

/// A component prototype of the composition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Prototype {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// Its component type's name.
    pub component: String,
}

/// One end of a connector: a prototype and a port of its type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct End {
    /// The prototype's name.
    pub prototype: String,
    /// The port's name.
    pub port: String,
    /// The port's path as referenced.
    pub port_path: Path,
}

/// An `ASSEMBLY-SW-CONNECTOR`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connector {
    /// Its path.
    pub path: Path,
    /// The provided port's end.
    pub provider: End,
    /// The required port's end.
    pub requester: End,
}

/// The composition.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Composition {
    /// Its path.
    pub path: Path,
    /// Its short name.
    pub name: String,
    /// Its description, one line.
    pub doc: String,
    /// Its component prototypes.
    pub prototypes: Vec<Prototype>,
    /// Its connectors.
    pub connectors: Vec<Connector>,
}

/// `e`'s path; for an element without a short name (a connector's end, an event's data
/// reference), its nearest named parent's path and the element's name.
pub(crate) fn path_of(e: &Element) -> String {
    e.path().unwrap_or_else(
        |_| match e.named_parent().ok().flatten().and_then(|p| p.path().ok()) {
            Some(parent) => format!("{parent} ({})", e.element_name()),
            None => format!("<{}>", e.element_name()),
        },
    )
}

fn name(e: &Element) -> String {
    e.item_name().unwrap_or_default()
}

pub(crate) fn text(e: &Element, n: ElementName) -> Option<String> {
    e.get_sub_element(n)
        .and_then(|s| s.character_data())
        .map(|c| c.to_string())
}

fn doc(e: &Element) -> String {
    e.get_sub_element(ElementName::Desc)
        .and_then(|d| d.get_sub_element(ElementName::L2))
        .and_then(|l| l.character_data())
        .map(|c| {
            c.to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
        })
        .unwrap_or_default()
}

/// The element a reference sub-element `n` of `e` points to, or an error naming `e`.
pub(crate) fn target(e: &Element, n: ElementName, out: &mut Vec<Error>) -> Option<Element> {
    let at = path_of(e);
    let Some(r) = e.get_sub_element(n) else {
        out.push(Error::new(format!("no {n}"), &[&at]));
        return None;
    };
    match r.get_reference_target() {
        Ok(t) => Some(t),
        Err(_) => {
            let dest = r
                .character_data()
                .map(|c| c.to_string())
                .unwrap_or_default();
            out.push(Error::new(
                format!("{n} {dest} refers to nothing in the description"),
                &[&at],
            ));
            None
        }
    }
}

/// Notes for `e`'s sub-elements other than `used` (and `SHORT-NAME`, `DESC`), and for
/// those of `defaults` whose text is not the default given: read, not used.
fn note_unused(
    e: &Element,
    used: &[ElementName],
    defaults: &[(ElementName, &str)],
    notes: &mut Vec<String>,
) {
    for sub in e.sub_elements() {
        let n = sub.element_name();
        if [ElementName::ShortName, ElementName::Desc].contains(&n) || used.contains(&n) {
            continue;
        }
        let default = defaults.iter().find(|(d, _)| *d == n).map(|(_, v)| *v);
        let value = sub.character_data().map(|c| c.to_string());
        if default.is_some() && value.as_deref() == default {
            continue;
        }
        notes.push(format!(
            "{}: {n}{} is not used by the generated RTE",
            path_of(e),
            value.map(|v| format!(" `{v}`")).unwrap_or_default()
        ));
    }
}

/// Elements below `e`'s sub-element `list`.
fn each(e: &Element, list: ElementName) -> Vec<Element> {
    e.get_sub_element(list)
        .map(|l| l.sub_elements().collect())
        .unwrap_or_default()
}

fn read_type(e: &Element, out: &mut Vec<Error>) -> Option<DataType> {
    let path = path_of(e);
    let rust = e
        .get_sub_element(ElementName::AdminData)
        .into_iter()
        .flat_map(|a| each(&a, ElementName::Sdgs))
        .filter(|sdg| {
            sdg.attribute_value(AttributeName::Gid)
                .is_some_and(|g| g.to_string() == "cw-gen")
        })
        .flat_map(|sdg| sdg.sub_elements().collect::<Vec<_>>())
        .find(|sd| {
            sd.element_name() == ElementName::Sd
                && sd
                    .attribute_value(AttributeName::Gid)
                    .is_some_and(|g| g.to_string() == "RustType")
        })
        .and_then(|sd| sd.character_data())
        .map(|c| c.to_string().trim().to_string());
    let Some(rust) = rust else {
        out.push(Error::new(
            "data type without the Rust type that carries it (ADMIN-DATA, SDG cw-gen, SD RustType)",
            &[&path],
        ));
        return None;
    };
    let valid = !rust.is_empty()
        && rust.split("::").all(|segment| {
            let mut chars = segment.chars();
            chars
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        });
    if !valid {
        out.push(Error::new(
            format!("data type's Rust type `{rust}` is not a Rust path"),
            &[&path],
        ));
        return None;
    }
    Some(DataType {
        name: name(e),
        path,
        rust,
    })
}

fn read_interface(e: &Element, out: &mut Vec<Error>) -> Option<Interface> {
    let path = path_of(e);
    let elements = each(e, ElementName::DataElements);
    let [element] = elements.as_slice() else {
        out.push(Error::new(
            format!(
                "sender-receiver interface with {} data elements: one per interface can be generated",
                elements.len()
            ),
            &[&path],
        ));
        return None;
    };
    let data_type = target(element, ElementName::TypeTref, out)?;
    if data_type.element_name() != ElementName::ImplementationDataType {
        out.push(Error::new(
            format!(
                "data element typed by a {}: an IMPLEMENTATION-DATA-TYPE can be generated",
                data_type.element_name()
            ),
            &[&path_of(element)],
        ));
        return None;
    }
    let policy = element
        .get_sub_element(ElementName::SwDataDefProps)
        .and_then(|p| p.get_sub_element(ElementName::SwDataDefPropsVariants))
        .and_then(|v| v.get_sub_element(ElementName::SwDataDefPropsConditional))
        .and_then(|c| text(&c, ElementName::SwImplPolicy));
    let queued = match policy.as_deref() {
        None | Some("STANDARD") => false,
        Some("QUEUED") => true,
        Some(other) => {
            out.push(Error::new(
                format!("SW-IMPL-POLICY {other}: STANDARD and QUEUED can be generated"),
                &[&path_of(element)],
            ));
            return None;
        }
    };
    Some(Interface {
        doc: doc(e),
        name: name(e),
        element: name(element),
        data_type: name(&data_type),
        queued,
        path,
    })
}

fn read_port(e: &Element, out: &mut Vec<Error>, notes: &mut Vec<String>) -> Option<Port> {
    let path = path_of(e);
    let (provided, tref, specs) = match e.element_name() {
        ElementName::PPortPrototype => (
            true,
            ElementName::ProvidedInterfaceTref,
            ElementName::ProvidedComSpecs,
        ),
        ElementName::RPortPrototype => (
            false,
            ElementName::RequiredInterfaceTref,
            ElementName::RequiredComSpecs,
        ),
        other => {
            out.push(Error::new(
                format!("{other}: P-PORT-PROTOTYPE and R-PORT-PROTOTYPE can be generated"),
                &[&path],
            ));
            return None;
        }
    };
    let interface = target(e, tref, out)?;
    if interface.element_name() != ElementName::SenderReceiverInterface {
        out.push(Error::new(
            format!(
                "port typed by a {}: sender-receiver interfaces can be generated",
                interface.element_name()
            ),
            &[&path],
        ));
        return None;
    }
    let specs = each(e, specs);
    if specs.len() > 1 {
        out.push(Error::new(
            format!(
                "{} com specs: one (the interface's one data element) can be generated",
                specs.len()
            ),
            &[&path],
        ));
        return None;
    }
    let mut init = None;
    let mut queue_length = None;
    let mut queued_spec = None;
    if let Some(spec) = specs.first() {
        queued_spec = match spec.element_name() {
            ElementName::QueuedSenderComSpec | ElementName::QueuedReceiverComSpec => Some(true),
            ElementName::NonqueuedSenderComSpec | ElementName::NonqueuedReceiverComSpec => {
                Some(false)
            }
            other => {
                out.push(Error::new(
                    format!(
                        "{other}: sender and receiver com specs, queued or not, can be generated"
                    ),
                    &[&path],
                ));
                return None;
            }
        };
        note_unused(
            spec,
            &[
                ElementName::DataElementRef,
                ElementName::InitValue,
                ElementName::QueueLength,
            ],
            &[],
            notes,
        );
        init = spec
            .get_sub_element(ElementName::InitValue)
            .and_then(|v| v.get_sub_element(ElementName::TextValueSpecification))
            .and_then(|t| text(&t, ElementName::Value));
        if let Some(q) = text(spec, ElementName::QueueLength) {
            match crate::arxml::parse_int(&q) {
                Some(n) => queue_length = Some(n),
                None => {
                    out.push(Error::new(
                        format!("QUEUE-LENGTH {q} is not a number"),
                        &[&path],
                    ));
                    return None;
                }
            }
        }
        if spec.get_sub_element(ElementName::InitValue).is_some() && init.is_none() {
            out.push(Error::new(
                "an init value other than a TEXT-VALUE-SPECIFICATION naming a constant of the data type",
                &[&path],
            ));
            return None;
        }
    }
    Some(Port {
        name: name(e),
        path,
        provided,
        interface: name(&interface),
        init,
        queue_length,
        queued_spec,
    })
}

fn read_component(
    e: &Element,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) -> Option<ComponentType> {
    let path = path_of(e);
    let ports: Vec<Port> = each(e, ElementName::Ports)
        .iter()
        .filter_map(|p| read_port(p, out, notes))
        .collect();
    let mut runnables = Vec::new();
    let mut events = Vec::new();
    let behaviors = each(e, ElementName::InternalBehaviors);
    if behaviors.len() > 1 {
        out.push(Error::new(
            format!(
                "{} internal behaviours: one can be generated",
                behaviors.len()
            ),
            &[&path],
        ));
    }
    for b in behaviors.iter().take(1) {
        let behavior = path_of(b);
        note_unused(
            b,
            &[ElementName::Events, ElementName::Runnables],
            &[],
            notes,
        );
        for r in each(b, ElementName::Runnables) {
            // The RTE runs each runnable from one task, never two jobs at once, with no
            // minimum interval: those defaults need no note.
            note_unused(
                &r,
                &[ElementName::Symbol],
                &[
                    (ElementName::MinimumStartInterval, "0"),
                    (ElementName::CanBeInvokedConcurrently, "false"),
                ],
                notes,
            );
            runnables.push((name(&r), path_of(&r)));
        }
        for ev in each(b, ElementName::Events) {
            let at = path_of(&ev);
            note_unused(
                &ev,
                &[
                    ElementName::StartOnEventRef,
                    ElementName::Period,
                    ElementName::DataIref,
                ],
                &[],
                notes,
            );
            let Some(runnable) = target(&ev, ElementName::StartOnEventRef, out) else {
                continue;
            };
            if runnable.element_name() != ElementName::RunnableEntity
                || !path_of(&runnable).starts_with(&format!("{behavior}/"))
            {
                out.push(Error::new(
                    format!(
                        "the event starts {}, which is not a runnable of its component's behaviour",
                        path_of(&runnable)
                    ),
                    &[&at],
                ));
                continue;
            }
            let kind = match ev.element_name() {
                ElementName::TimingEvent => {
                    let period = text(&ev, ElementName::Period).unwrap_or_default();
                    match crate::arxml::parse_ms(&period) {
                        Some(ms) if ms > 0 => EventKind::Timing { period_ms: ms },
                        _ => {
                            out.push(Error::new(
                                format!("timing event period `{period}`: a whole number of ms above 0, in seconds, can be generated"),
                                &[&at],
                            ));
                            continue;
                        }
                    }
                }
                ElementName::DataReceivedEvent => {
                    let Some(iref) = ev.get_sub_element(ElementName::DataIref) else {
                        out.push(Error::new(
                            "a data-received event without DATA-IREF",
                            &[&at],
                        ));
                        continue;
                    };
                    let Some(port) = target(&iref, ElementName::ContextRPortRef, out) else {
                        continue;
                    };
                    if port.element_name() != ElementName::RPortPrototype
                        || !path_of(&port).starts_with(&format!("{path}/"))
                    {
                        out.push(Error::new(
                            format!(
                                "the data-received event is on {}, which is not a required port of its component",
                                path_of(&port)
                            ),
                            &[&at],
                        ));
                        continue;
                    }
                    EventKind::DataReceived { port: name(&port) }
                }
                other => {
                    out.push(Error::new(
                        format!("{other}: timing and data-received events can be generated"),
                        &[&at],
                    ));
                    continue;
                }
            };
            events.push(RteEvent {
                name: name(&ev),
                path: at,
                runnable: name(&runnable),
                kind,
            });
        }
    }
    Some(ComponentType {
        name: name(e),
        service: e.element_name() == ElementName::ServiceSwComponentType,
        path,
        ports,
        runnables,
        events,
    })
}

fn read_end(e: &Element, port_ref: ElementName, out: &mut Vec<Error>) -> Option<End> {
    let prototype = target(e, ElementName::ContextComponentRef, out)?;
    if prototype.element_name() != ElementName::SwComponentPrototype {
        out.push(Error::new(
            format!(
                "CONTEXT-COMPONENT-REF points to a {}: a component prototype of the composition",
                prototype.element_name()
            ),
            &[&path_of(e)],
        ));
        return None;
    }
    let port = target(e, port_ref, out)?;
    Some(End {
        prototype: name(&prototype),
        port: name(&port),
        port_path: path_of(&port),
    })
}

fn read_composition(e: &Element, out: &mut Vec<Error>) -> Composition {
    let mut prototypes = Vec::new();
    for p in each(e, ElementName::Components) {
        if let Some(t) = target(&p, ElementName::TypeTref, out) {
            if ![
                ElementName::ApplicationSwComponentType,
                ElementName::ServiceSwComponentType,
            ]
            .contains(&t.element_name())
            {
                out.push(Error::new(
                    format!(
                        "prototype of a {}: application and service component types can be generated",
                        t.element_name()
                    ),
                    &[&path_of(&p)],
                ));
                continue;
            }
            prototypes.push(Prototype {
                path: path_of(&p),
                name: name(&p),
                component: name(&t),
            });
        }
    }
    let mut connectors = Vec::new();
    for c in each(e, ElementName::Connectors) {
        let at = path_of(&c);
        if c.element_name() != ElementName::AssemblySwConnector {
            out.push(Error::new(
                format!("{}: assembly connectors can be generated", c.element_name()),
                &[&at],
            ));
            continue;
        }
        let provider = c
            .get_sub_element(ElementName::ProviderIref)
            .and_then(|p| read_end(&p, ElementName::TargetPPortRef, out));
        let requester = c
            .get_sub_element(ElementName::RequesterIref)
            .and_then(|r| read_end(&r, ElementName::TargetRPortRef, out));
        match (provider, requester) {
            (Some(provider), Some(requester)) => connectors.push(Connector {
                path: at,
                provider,
                requester,
            }),
            _ => out.push(Error::new(
                "a connector without both its provider and its requester",
                &[&at],
            )),
        }
    }
    Composition {
        path: path_of(e),
        name: name(e),
        doc: doc(e),
        prototypes,
        connectors,
    }
}

/// The last segment of `e`'s definition.
fn def_of(e: &Element) -> String {
    text(e, ElementName::DefinitionRef)
        .and_then(|d| d.rsplit('/').next().map(str::to_string))
        .unwrap_or_default()
}

/// The `Rte` module's instances and their event-to-task mappings.
fn read_rte(module: &Element, mappings: &mut Vec<Mapping>, out: &mut Vec<Error>) {
    for instance in each(module, ElementName::Containers) {
        let at = path_of(&instance);
        if def_of(&instance) != "RteSwComponentInstance" {
            out.push(Error::new(
                format!(
                    "container {} cannot be mapped onto the RTE (RteSwComponentInstance can)",
                    def_of(&instance)
                ),
                &[&at],
            ));
            continue;
        }
        let mut prototype = None;
        for r in each(&instance, ElementName::ReferenceValues) {
            match def_of(&r).as_str() {
                "RteSoftwareComponentInstanceRef" => match target(&r, ElementName::ValueRef, out) {
                    Some(p) if p.element_name() == ElementName::SwComponentPrototype => {
                        let first = prototype.replace(name(&p));
                        if first.is_some() {
                            out.push(Error::new(
                                "a second RteSoftwareComponentInstanceRef",
                                &[&at],
                            ));
                        }
                    }
                    Some(p) => out.push(Error::new(
                        format!(
                            "RteSoftwareComponentInstanceRef points to a {}: a component prototype",
                            p.element_name()
                        ),
                        &[&at],
                    )),
                    None => {}
                },
                other => out.push(Error::new(
                    format!("reference {other} cannot be mapped onto the RTE"),
                    &[&at],
                )),
            }
        }
        let Some(prototype) = prototype else {
            out.push(Error::new(
                "an RteSwComponentInstance without its RteSoftwareComponentInstanceRef",
                &[&at],
            ));
            continue;
        };
        for m in each(&instance, ElementName::SubContainers) {
            let at = path_of(&m);
            if def_of(&m) != "RteEventToTaskMapping" {
                out.push(Error::new(
                    format!(
                        "container {} cannot be mapped onto the RTE (RteEventToTaskMapping can)",
                        def_of(&m)
                    ),
                    &[&at],
                ));
                continue;
            }
            let mut position = None;
            for p in each(&m, ElementName::ParameterValues) {
                let value = text(&p, ElementName::Value).unwrap_or_default();
                match (def_of(&p).as_str(), crate::arxml::parse_int(&value)) {
                    ("RtePositionInTask", Some(n)) => position = Some(n),
                    ("RtePositionInTask", None) => out.push(Error::new(
                        format!("RtePositionInTask = `{value}` is not a number"),
                        &[&at],
                    )),
                    (other, _) => out.push(Error::new(
                        format!("parameter {other} cannot be mapped onto the RTE"),
                        &[&at],
                    )),
                }
            }
            let (mut event, mut task) = (None, None);
            for r in each(&m, ElementName::ReferenceValues) {
                match def_of(&r).as_str() {
                    "RteEventRef" => {
                        event = target(&r, ElementName::ValueRef, out).map(|e| path_of(&e))
                    }
                    // The task is in the OS's description, another file: kept as its path.
                    "RteMappedToTaskRef" => task = text(&r, ElementName::ValueRef),
                    other => out.push(Error::new(
                        format!("reference {other} cannot be mapped onto the RTE"),
                        &[&at],
                    )),
                }
            }
            match (event, task, position) {
                (Some(event), Some(task), Some(position)) => mappings.push(Mapping {
                    path: at,
                    prototype: prototype.clone(),
                    event,
                    task,
                    position,
                }),
                _ => out.push(Error::new(
                    "an RteEventToTaskMapping needs its RteEventRef, RteMappedToTaskRef and RtePositionInTask",
                    &[&at],
                )),
            }
        }
    }
}

/// Reads the software components' description from an ARXML file's bytes.
///
/// # Errors
/// The file does not parse, or an element cannot be mapped: each error with its path.
pub fn read(bytes: &[u8], file_name: &str) -> Result<Software, Vec<Error>> {
    let model = crate::arxml::load(bytes, file_name)?;
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let mut sw = Software::default();
    let mut compositions = Vec::new();
    for (_, e) in model.elements_dfs() {
        if e.parent().ok().flatten().map(|p| p.element_name()) != Some(ElementName::Elements) {
            continue;
        }
        match e.element_name() {
            ElementName::ImplementationDataType => {
                sw.types.extend(read_type(&e, &mut out));
            }
            ElementName::SenderReceiverInterface => {
                sw.interfaces.extend(read_interface(&e, &mut out));
            }
            ElementName::ApplicationSwComponentType | ElementName::ServiceSwComponentType => {
                sw.components
                    .extend(read_component(&e, &mut out, &mut notes));
            }
            ElementName::CompositionSwComponentType => {
                compositions.push(read_composition(&e, &mut out));
            }
            ElementName::EcucModuleConfigurationValues
                if text(&e, ElementName::DefinitionRef).is_some_and(|d| d.ends_with("/Rte")) =>
            {
                if sw.rte_path.is_empty() {
                    sw.rte_path = path_of(&e);
                    read_rte(&e, &mut sw.mappings, &mut out);
                } else {
                    out.push(Error::new(
                        "a second Rte module",
                        &[&path_of(&e), &sw.rte_path],
                    ));
                }
            }
            other => out.push(Error::new(
                format!("{other} cannot be mapped onto the ECU's components"),
                &[&path_of(&e)],
            )),
        }
    }
    sw.notes = notes;
    if sw.rte_path.is_empty() {
        out.push(Error::new(
            "the description has no Rte module: no runnable is mapped to a task",
            &[file_name],
        ));
    }
    match compositions.len() {
        1 => {
            if let Some(c) = compositions.pop() {
                sw.composition = c;
            }
        }
        0 => out.push(Error::new(
            "the description has no composition",
            &[file_name],
        )),
        _ => {
            let paths: Vec<&str> = compositions.iter().map(|c| c.path.as_str()).collect();
            out.push(Error::new(
                "the description has several compositions: one is the ECU's",
                &paths,
            ));
        }
    }
    if out.is_empty() {
        Ok(sw)
    } else {
        Err(out)
    }
}

fn find<'a, T>(items: &'a [T], wanted: &str, name: impl Fn(&T) -> &str) -> Option<&'a T> {
    items.iter().find(|i| name(i) == wanted)
}

/// The largest queue a receiver may have (the core's `Queued` takes any; the RAM is the
/// ECU's).
pub const MAX_QUEUE_LENGTH: u64 = 64;

/// The port's OS tick, ms: an alarm's cycle in ticks of the system counter is this many
/// milliseconds (SysTick every millisecond on every board).
pub const TICK_MS: u64 = 1;

/// The cycle, ms, of the autostarted cyclic alarm that activates `task` or sets its event
/// (the first, if several: the ECUC checks refuse two).
pub fn task_period_ms(ecu: &crate::model::Ecu, task: &str) -> Option<u64> {
    use crate::model::AlarmAction;
    ecu.os.alarms.iter().find_map(|a| {
        let target = match &a.action {
            AlarmAction::ActivateTask(t) | AlarmAction::SetEvent(t, _) => t,
        };
        match a.autostart {
            Some((_, cycle)) if cycle > 0 && target == task => Some(cycle * TICK_MS),
            _ => None,
        }
    })
}

/// The mappings of events to tasks against the components and the OS: every event of every
/// application prototype mapped once, to a task of the OS; a timing event to a task its
/// alarm runs at the event's period; a data-received event to a task no alarm runs (the
/// RTE activates it); one runnable per position in a task.
fn check_mappings(sw: &Software, ecu: &crate::model::Ecu, out: &mut Vec<Error>) {
    let comp = &sw.composition;
    for m in &sw.mappings {
        let Some(proto) = find(&comp.prototypes, &m.prototype, |p| &p.name) else {
            out.push(Error::new(
                format!(
                    "mapping of prototype {}, which the composition does not have",
                    m.prototype
                ),
                &[&m.path],
            ));
            continue;
        };
        let Some(c) = find(&sw.components, &proto.component, |c| &c.name) else {
            continue;
        };
        let Some(event) = c.events.iter().find(|e| e.path == m.event) else {
            out.push(Error::new(
                format!(
                    "event {} is not an event of {}'s component type {}",
                    m.event, proto.name, c.name
                ),
                &[&m.path, &proto.path],
            ));
            continue;
        };
        let Some(task) = ecu.os.tasks.iter().find(|t| t.path == m.task) else {
            out.push(Error::new(
                format!(
                    "RteMappedToTaskRef {} is not a task of the OS's description",
                    m.task
                ),
                &[&m.path],
            ));
            continue;
        };
        let period = task_period_ms(ecu, &task.name);
        match (&event.kind, period) {
            (EventKind::Timing { period_ms }, Some(p)) if *period_ms == p => {}
            (EventKind::Timing { period_ms }, _) => out.push(Error::new(
                format!(
                    "runnable {}.{} runs every {period_ms} ms ({}), but task {} {}",
                    proto.name,
                    event.runnable,
                    event.name,
                    task.name,
                    period.map_or("is run by no cyclic alarm".to_string(), |p| format!("runs every {p} ms"))
                ),
                &[&m.path, &event.path, &task.path],
            )),
            (EventKind::DataReceived { port }, Some(p)) => out.push(Error::new(
                format!(
                    "runnable {}.{} runs when {port} receives data, but task {} runs every {p} ms: the RTE activates a data-received event's task",
                    proto.name, event.runnable, task.name
                ),
                &[&m.path, &event.path, &task.path],
            )),
            (EventKind::DataReceived { .. }, None) => {}
        }
    }
    // Every event of every application prototype mapped once.
    for proto in &comp.prototypes {
        let Some(c) = find(&sw.components, &proto.component, |c| &c.name) else {
            continue;
        };
        if c.service {
            continue;
        }
        for event in &c.events {
            let mapped: Vec<&Mapping> = sw
                .mappings
                .iter()
                .filter(|m| m.prototype == proto.name && m.event == event.path)
                .collect();
            match mapped.as_slice() {
                [] => out.push(Error::new(
                    format!(
                        "runnable {}.{} ({}) is mapped to no task: it would never run",
                        proto.name, event.runnable, event.name
                    ),
                    &[&event.path, &proto.path, &sw.rte_path],
                )),
                [_] => {}
                [first, second, ..] => out.push(Error::new(
                    format!(
                        "runnable {}.{} ({}) is mapped twice: an event runs its runnable in one task, once",
                        proto.name, event.runnable, event.name
                    ),
                    &[&first.path, &second.path],
                )),
            }
        }
    }
    // One runnable per position in a task.
    for (i, a) in sw.mappings.iter().enumerate() {
        if let Some(b) = sw
            .mappings
            .iter()
            .skip(i + 1)
            .find(|b| b.task == a.task && b.position == a.position)
        {
            out.push(Error::new(
                format!(
                    "two runnables at position {} of task {}",
                    a.position, a.task
                ),
                &[&b.path, &a.path],
            ));
        }
    }
}

/// Rust's keywords (strict and reserved, 2021): a generated method or field cannot be one.
const KEYWORDS: [&str; 51] = [
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "union",
];

/// Names the generated module already uses: an interface or a context cannot take them.
const RESERVED_TYPES: [&str; 16] = [
    "Rte",
    "Released",
    "LastIsBest",
    "Queued",
    "SenderReceiverInterface",
    "RteError",
    "TaskId",
    "tasks",
    // The prelude's items the generated code uses.
    "Ok",
    "Err",
    "Result",
    "Option",
    "Some",
    "None",
    "Iterator",
    "Default",
];

/// Every name the generated Rust gives an item is one Rust item: two prototypes, two ports
/// of one type, two buffers or two interfaces that would be generated as one name, or a
/// name that is a keyword or one the module already uses, are refused with both paths.
fn check_names(sw: &Software, out: &mut Vec<Error>) {
    let comp = &sw.composition;
    // Prototypes: the accessor `rte.red_led()` and the context `RedLedPorts`.
    let mut seen: HashMap<String, &str> = HashMap::new();
    for p in &comp.prototypes {
        let method = snake(&p.name);
        if KEYWORDS.contains(&method.as_str())
            || ["new", "default", "rte", "released", "ports"].contains(&method.as_str())
            || method.starts_with("peek_")
        {
            out.push(Error::new(
                format!("prototype {} would be generated as `rte.{method}()`, a name Rust or the RTE already has", p.name),
                &[&p.path],
            ));
        }
        if let Some(first) = seen.insert(method.clone(), &p.path) {
            out.push(Error::new(
                format!("two prototypes would be generated as `rte.{method}()`"),
                &[&p.path, first],
            ));
        }
    }
    // Contexts: one struct each.
    let mut contexts: HashMap<String, &str> = HashMap::new();
    for p in &comp.prototypes {
        if let Some(first) = contexts.insert(context(p), &p.path) {
            out.push(Error::new(
                format!(
                    "two prototypes would be generated as one context `{}`",
                    context(p)
                ),
                &[&p.path, first],
            ));
        }
    }
    // Types: a ports trait and a runnables trait each, a context per prototype.
    let mut traits: HashMap<String, &str> = HashMap::new();
    for c in &sw.components {
        if let Some(first) = traits.insert(ports_trait(c), &c.path) {
            out.push(Error::new(
                format!(
                    "two component types would be generated as one trait `{}`",
                    ports_trait(c)
                ),
                &[&c.path, first],
            ));
        }
        let mut runnables: HashMap<String, &str> = HashMap::new();
        for (r, path) in &c.runnables {
            let method = snake(r);
            if KEYWORDS.contains(&method.as_str()) {
                out.push(Error::new(
                    format!(
                        "runnable {} of {} would be generated as the keyword `{method}`",
                        r, c.name
                    ),
                    &[path],
                ));
            }
            if let Some(first) = runnables.insert(method.clone(), path) {
                out.push(Error::new(
                    format!(
                        "two runnables of {} would be generated as one method `{method}`",
                        c.name
                    ),
                    &[path, first],
                ));
            }
        }
    }
    let generated: Vec<String> = comp
        .prototypes
        .iter()
        .map(context)
        .chain(
            sw.components
                .iter()
                .flat_map(|c| [ports_trait(c), runnables_trait(c)]),
        )
        .collect();
    for i in &sw.interfaces {
        if RESERVED_TYPES.contains(&i.name.as_str()) || generated.contains(&i.name) {
            out.push(Error::new(
                format!(
                    "interface {} has the name of an item the generated RTE defines or uses",
                    i.name
                ),
                &[&i.path],
            ));
        }
    }
    // Ports of one type: one method each.
    for c in &sw.components {
        let mut methods: HashMap<String, &str> = HashMap::new();
        for port in &c.ports {
            if let Some(first) = methods.insert(snake(&port.name), &port.path) {
                out.push(Error::new(
                    format!(
                        "two ports of {} would be generated as one method (`{}`)",
                        c.name,
                        snake(&port.name)
                    ),
                    &[&port.path, first],
                ));
            }
        }
    }
    // Buffers: one field each, and one constant for each data-received event's task.
    let bufs = buffers(sw);
    let mut constants: HashMap<String, &str> = HashMap::new();
    for b in &bufs {
        let Some((receiver, port)) = &b.receiver else {
            continue;
        };
        let name = crate::rust::constant(&format!("{receiver}{port}"));
        let path = b.carries.first().map_or("", |(_, p)| p.as_str());
        if name == "RELEASED_BY" {
            out.push(Error::new(
                format!("{receiver}.{port}'s task would be generated as `RELEASED_BY`, which the RTE already has"),
                &[path],
            ));
        }
        if let Some(first) = constants.insert(name.clone(), path) {
            out.push(Error::new(
                format!(
                    "two data-received events' tasks would be generated as one constant `{name}`"
                ),
                &[path, first],
            ));
        }
    }
    if bufs.iter().filter(|b| b.notify).count() > 32 {
        out.push(Error::new(
            "more than 32 data-received events: a job's fired events are one 32-bit word"
                .to_string(),
            &[&comp.path],
        ));
    }
    // The task bodies: a function each.
    let mut tasks: Vec<&str> = sw.mappings.iter().map(|m| m.task.as_str()).collect();
    tasks.sort_unstable();
    tasks.dedup();
    let mut bodies: HashMap<String, &str> = HashMap::new();
    for task in tasks {
        let name = snake(task.rsplit('/').next().unwrap_or(task));
        if let Some(first) = bodies.insert(name.clone(), task) {
            out.push(Error::new(
                format!("two tasks' bodies would be generated as one function `{name}`"),
                &[task, first],
            ));
        }
        if KEYWORDS.contains(&name.as_str()) {
            out.push(Error::new(
                format!("a task's body would be generated as the keyword `{name}`"),
                &[task],
            ));
        }
    }
    for (i, a) in bufs.iter().enumerate() {
        if let Some(b) = bufs.iter().skip(i + 1).find(|b| b.field == a.field) {
            let path = |x: &Buffer| {
                x.carries
                    .first()
                    .map(|(_, p)| p.clone())
                    .unwrap_or_default()
            };
            out.push(Error::new(
                format!(
                    "the buffers of {} and {} would be generated as one field `{}`",
                    a.owner, b.owner, a.field
                ),
                &[&path(b), &path(a)],
            ));
        }
        if KEYWORDS.contains(&a.field.as_str()) {
            out.push(Error::new(
                format!(
                    "the buffer of {} would be generated as the keyword `{}`",
                    a.owner, a.field
                ),
                &[&a.carries
                    .first()
                    .map(|(_, p)| p.clone())
                    .unwrap_or_default()],
            ));
        }
    }
}

/// Every check; empty when the components can be generated for the ECU whose OS `ecu`
/// describes.
pub fn check(sw: &Software, ecu: &crate::model::Ecu) -> Vec<Error> {
    let mut out = Vec::new();
    let mut names: HashMap<String, &str> = HashMap::new();
    for (kind, n, p) in sw
        .types
        .iter()
        .map(|t| ("data type", &t.name, &t.path))
        .chain(
            sw.interfaces
                .iter()
                .map(|i| ("interface", &i.name, &i.path)),
        )
        .chain(
            sw.components
                .iter()
                .map(|c| ("component type", &c.name, &c.path)),
        )
    {
        if let Some(first) = names.insert(format!("{kind} {n}"), p) {
            out.push(Error::new(
                format!("two {kind}s are named {n}"),
                &[p, first],
            ));
        }
    }
    for i in &sw.interfaces {
        if find(&sw.types, &i.data_type, |t| &t.name).is_none() {
            out.push(Error::new(
                format!(
                    "interface {}'s data type {} does not exist",
                    i.name, i.data_type
                ),
                &[&i.path],
            ));
        }
    }
    for c in &sw.components {
        check_component(sw, c, &mut out);
    }
    check_composition(sw, &mut out);
    check_names(sw, &mut out);
    check_mappings(sw, ecu, &mut out);
    out
}

fn check_component(sw: &Software, c: &ComponentType, out: &mut Vec<Error>) {
    for p in &c.ports {
        let Some(i) = find(&sw.interfaces, &p.interface, |i| &i.name) else {
            continue;
        };
        if p.queued_spec.is_some_and(|q| q != i.queued) {
            out.push(Error::new(
                format!(
                    "port {}.{} has a {}queued com spec for the {} data of interface {}",
                    c.name,
                    p.name,
                    if i.queued { "non-" } else { "" },
                    if i.queued { "queued" } else { "non-queued" },
                    i.name
                ),
                &[&p.path, &i.path],
            ));
        }
        match (i.queued, p.provided) {
            (false, _) if p.init.is_none() => out.push(Error::new(
                format!(
                    "port {}.{} of non-queued interface {} has no init value",
                    c.name, p.name, i.name
                ),
                &[&p.path, &i.path],
            )),
            (true, false) => match p.queue_length {
                Some(1..=MAX_QUEUE_LENGTH) => {}
                other => out.push(Error::new(
                    format!(
                        "queued port {}.{}: a QUEUE-LENGTH of 1..={MAX_QUEUE_LENGTH} is needed (it has {})",
                        c.name,
                        p.name,
                        other.map_or("none".to_string(), |n| n.to_string())
                    ),
                    &[&p.path, &i.path],
                )),
            },
            _ => {}
        }
        if let Some(init) = &p.init {
            let constant = !init.is_empty()
                && init
                    .chars()
                    .all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
                && init
                    .chars()
                    .next()
                    .is_some_and(|ch| ch.is_ascii_alphabetic());
            if !constant {
                out.push(Error::new(
                    format!(
                        "port {}.{}'s init value `{init}` does not name a constant",
                        c.name, p.name
                    ),
                    &[&p.path],
                ));
            }
        }
    }
    for (r, path) in &c.runnables {
        if !c.events.iter().any(|e| &e.runnable == r) {
            out.push(Error::new(
                format!(
                    "runnable {}.{r} is started by no event: it would never run",
                    c.name
                ),
                &[path],
            ));
        }
    }
    let mut received: HashMap<&str, &str> = HashMap::new();
    for e in &c.events {
        if let EventKind::DataReceived { port } = &e.kind {
            if let Some(first) = received.insert(port, &e.path) {
                out.push(Error::new(
                    format!(
                        "two data-received events on {}.{port}: one buffer notes new data, for one event",
                        c.name
                    ),
                    &[&e.path, first],
                ));
            }
            let required = c.ports.iter().find(|p| &p.name == port && !p.provided);
            let queued = required
                .and_then(|p| find(&sw.interfaces, &p.interface, |i| &i.name))
                .is_some_and(|i| i.queued);
            if required.is_none() || queued {
                out.push(Error::new(
                    format!(
                        "data-received event {} is on {}.{port}: a non-queued required port of the component can start a runnable",
                        e.name, c.name
                    ),
                    &[&e.path],
                ));
            }
        }
    }
}

fn check_composition(sw: &Software, out: &mut Vec<Error>) {
    let comp = &sw.composition;
    let mut names: HashMap<&str, &str> = HashMap::new();
    for p in &comp.prototypes {
        if let Some(first) = names.insert(&p.name, &p.path) {
            out.push(Error::new(
                format!("two component prototypes are named {}", p.name),
                &[&p.path, first],
            ));
        }
        if find(&sw.components, &p.component, |c| &c.name).is_none() {
            out.push(Error::new(
                format!(
                    "prototype {} is of an unknown component type {}",
                    p.name, p.component
                ),
                &[&p.path],
            ));
        }
    }
    // Each connector's ends: a prototype of the composition and a port of its type, of
    // the right direction; both ports of one interface.
    let port_of = |end: &End, provided: bool| -> Option<(&ComponentType, &Port)> {
        let proto = find(&comp.prototypes, &end.prototype, |p| &p.name)?;
        let c = find(&sw.components, &proto.component, |c| &c.name)?;
        let port = c
            .ports
            .iter()
            .find(|p| p.path == end.port_path && p.provided == provided)?;
        Some((c, port))
    };
    for k in &comp.connectors {
        let p = port_of(&k.provider, true);
        let r = port_of(&k.requester, false);
        for (end, found, what) in [(&k.provider, p, "provided"), (&k.requester, r, "required")] {
            if found.is_none() {
                out.push(Error::new(
                    format!(
                        "connector's {what} port {} is not a {what} port of prototype {}",
                        end.port_path, end.prototype
                    ),
                    &[&k.path, &end.port_path],
                ));
            }
        }
        if let (Some((_, pp)), Some((rc, rp))) = (p, r) {
            let queued = find(&sw.interfaces, &pp.interface, |i| &i.name).is_some_and(|i| i.queued);
            let event = rc
                .events
                .iter()
                .any(|e| matches!(&e.kind, EventKind::DataReceived { port } if port == &rp.name));
            if !queued && !event && pp.init != rp.init {
                out.push(Error::new(
                    format!(
                        "{}.{} and {}.{} share the sender's buffer but not its init value ({} and {})",
                        k.provider.prototype,
                        pp.name,
                        k.requester.prototype,
                        rp.name,
                        pp.init.as_deref().unwrap_or("none"),
                        rp.init.as_deref().unwrap_or("none")
                    ),
                    &[&rp.path, &pp.path, &k.path],
                ));
            }
            if pp.interface != rp.interface {
                out.push(Error::new(
                    format!(
                        "connector joins {}.{} ({}) to {}.{} ({}): a connector joins ports of one interface",
                        k.provider.prototype,
                        pp.name,
                        pp.interface,
                        k.requester.prototype,
                        rp.name,
                        rp.interface
                    ),
                    &[&k.path, &pp.path, &rp.path],
                ));
            }
        }
    }
    // Every required port connected, once where its data is not queued.
    for proto in &comp.prototypes {
        let Some(c) = find(&sw.components, &proto.component, |c| &c.name) else {
            continue;
        };
        for port in c.ports.iter().filter(|p| !p.provided) {
            let into: Vec<&Connector> = comp
                .connectors
                .iter()
                .filter(|k| {
                    k.requester.prototype == proto.name && k.requester.port_path == port.path
                })
                .collect();
            let queued =
                find(&sw.interfaces, &port.interface, |i| &i.name).is_some_and(|i| i.queued);
            match into.as_slice() {
                [] => out.push(Error::new(
                    format!(
                        "required port {}.{} is connected to nothing",
                        proto.name, port.name
                    ),
                    &[&port.path, &proto.path],
                )),
                [_] => {}
                [first, second, ..] if !queued => out.push(Error::new(
                    format!(
                        "required port {}.{} has two writers, {}.{} and {}.{}: a non-queued port has one",
                        proto.name,
                        port.name,
                        first.provider.prototype,
                        first.provider.port,
                        second.provider.prototype,
                        second.provider.port
                    ),
                    &[&port.path, &first.path, &second.path],
                )),
                _ => {}
            }
        }
    }
}

/// A word of a CamelCase name, lower case, joined by `_`: `UltraSonic` is `ultra_sonic`,
/// `LEDActuator` `led_actuator`, `BswM` `bswm` (a capital alone at the end stays with its
/// word).
pub fn snake(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut s = String::new();
    for (i, &c) in chars.iter().enumerate() {
        let prev = i.checked_sub(1).and_then(|j| chars.get(j)).copied();
        let next = chars.get(i + 1).copied();
        let starts_word = c.is_ascii_uppercase()
            && i > 0
            && next.is_some()
            && (prev.is_some_and(|p| p.is_ascii_lowercase() || p.is_ascii_digit())
                || (prev.is_some_and(|p| p.is_ascii_uppercase())
                    && next.is_some_and(|n| n.is_ascii_lowercase())));
        if starts_word {
            s.push('_');
        }
        s.push(c.to_ascii_lowercase());
    }
    s
}

/// One buffer of the generated RTE.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Buffer {
    /// The field's name.
    pub field: String,
    /// The interface's name.
    pub interface: String,
    /// A queue of this length, else last-is-best.
    pub queue: Option<u64>,
    /// The init value (last-is-best).
    pub init: Option<String>,
    /// A data-received event reads it: a write notes new data.
    pub notify: bool,
    /// The connections it carries: `Sender.Port -> Receiver.Port`, with the connector's
    /// path.
    pub carries: Vec<(String, Path)>,
    /// The sending prototype.
    pub sender: String,
    /// For a buffer a data-received event reads: the receiving prototype and its port.
    pub receiver: Option<(String, String)>,
    /// Whose buffer it is: the sender's port (`Sender.Port`, the receivers that read the
    /// newest value share it) or the receiver's (`Receiver.Port`, a data-received event's or
    /// a queue).
    pub owner: String,
}

/// The RTE's buffers, in the order of the connectors that first need them.
pub fn buffers(sw: &Software) -> Vec<Buffer> {
    let comp = &sw.composition;
    let mut out: Vec<Buffer> = Vec::new();
    let port = |proto: &str, port_path: &str| {
        find(&comp.prototypes, proto, |p| &p.name)
            .and_then(|p| find(&sw.components, &p.component, |c| &c.name))
            .and_then(|c| c.ports.iter().find(|p| p.path == port_path).map(|p| (c, p)))
    };
    for k in &comp.connectors {
        let (Some((_, pp)), Some((rc, rp))) = (
            port(&k.provider.prototype, &k.provider.port_path),
            port(&k.requester.prototype, &k.requester.port_path),
        ) else {
            continue;
        };
        let Some(i) = find(&sw.interfaces, &pp.interface, |i| &i.name) else {
            continue;
        };
        let carries = (
            format!(
                "{}.{} -> {}.{}",
                k.provider.prototype, pp.name, k.requester.prototype, rp.name
            ),
            k.path.clone(),
        );
        let event = rc
            .events
            .iter()
            .any(|e| matches!(&e.kind, EventKind::DataReceived { port } if port == &rp.name));
        let receiver = format!("{}.{}", k.requester.prototype, rp.name);
        let sender = format!("{}.{}", k.provider.prototype, pp.name);
        let (owner, queue, init, notify) = if i.queued {
            (receiver, rp.queue_length, None, false)
        } else if event {
            (receiver, None, rp.init.clone(), true)
        } else {
            (sender, None, pp.init.clone(), false)
        };
        let field = match owner.split_once('.') {
            Some((proto, port)) => format!("{}_{}", snake(proto), snake(port)),
            None => snake(&owner),
        };
        match out.iter_mut().find(|b| b.owner == owner) {
            Some(b) => b.carries.push(carries),
            None => out.push(Buffer {
                field,
                interface: i.name.clone(),
                queue,
                init,
                notify,
                carries: vec![carries],
                sender: k.provider.prototype.clone(),
                receiver: notify.then(|| (k.requester.prototype.clone(), rp.name.clone())),
                owner,
            }),
        }
    }
    out
}

/// The task a prototype's event is mapped to (its short name), if mapped.
fn task_of<'a>(
    sw: &Software,
    ecu: &'a crate::model::Ecu,
    prototype: &str,
    event: impl Fn(&RteEvent) -> bool,
) -> Option<&'a crate::model::Task> {
    let proto = find(&sw.composition.prototypes, prototype, |p| &p.name)?;
    let c = find(&sw.components, &proto.component, |c| &c.name)?;
    let m = sw.mappings.iter().find(|m| {
        m.prototype == prototype && c.events.iter().any(|e| e.path == m.event && event(e))
    })?;
    ecu.os.tasks.iter().find(|t| t.path == m.task)
}

/// The `tasks` module: the runnables each task runs, the task each data-received event
/// activates, and which task's write releases it.
fn emit_tasks(sw: &Software, ecu: &crate::model::Ecu, s: &mut String) -> Result<(), Error> {
    let _ = writeln!(
        s,
        "/// The runnables each task runs, in order (`RtePositionInTask`), as the RTE's ECUC \
         values ({}) map the prototypes' events:\n///\n/// | task | runnables |\n/// |---|---|",
        sw.rte_path
    );
    for task in &ecu.os.tasks {
        let mut runs: Vec<(u64, String)> = Vec::new();
        for m in sw.mappings.iter().filter(|m| m.task == task.path) {
            let event = find(&sw.composition.prototypes, &m.prototype, |p| &p.name)
                .and_then(|p| find(&sw.components, &p.component, |c| &c.name))
                .and_then(|c| c.events.iter().find(|e| e.path == m.event));
            if let Some(e) = event {
                let when = match &e.kind {
                    EventKind::Timing { period_ms } => format!("every {period_ms} ms"),
                    EventKind::DataReceived { port } => format!("on data received on {port}"),
                };
                runs.push((
                    m.position,
                    format!("{}.{} ({when})", m.prototype, e.runnable),
                ));
            }
        }
        if runs.is_empty() {
            continue;
        }
        runs.sort();
        let list: Vec<String> = runs.into_iter().map(|(_, r)| r).collect();
        let _ = writeln!(s, "/// | `{}` | {} |", task.name, list.join(", "));
    }
    let mut body = String::new();
    let mut released = Vec::new();
    let (events, activated, _) = activations(sw, ecu)?;
    for Activation {
        buffer: b,
        receiver,
        port,
        task,
    } in &events
    {
        let activated_task = *task;
        let writer = writer_of(sw, ecu, &b.sender, activated_task)?;
        let _ = writeln!(
            body,
            "    /// `{receiver}.{port}`'s data-received event runs in `{}` ({}): a write into \
             the buffer `{}` activates it.\n    pub const {}: TaskId = os::{};\n",
            activated_task.name,
            activated_task.path,
            b.field,
            crate::rust::constant(&format!("{receiver}{port}")),
            crate::rust::constant(&activated_task.name)
        );
        released.push((
            crate::rust::constant(&activated_task.name),
            crate::rust::constant(&writer.name),
            writer.name.clone(),
            b.sender.clone(),
        ));
    }
    let (bodies, mut uses) = emit_bodies(sw, ecu)?;
    if !released.is_empty() {
        uses.push("crate::generated::os".to_string());
    }
    uses.push("cw_core::os::TaskId".to_string());
    let _ = writeln!(s, "pub mod tasks {{");
    let (parent, others): (Vec<String>, Vec<String>) =
        uses.into_iter().partition(|u| u.starts_with("super::"));
    if !parent.is_empty() {
        let names: Vec<&str> = parent
            .iter()
            .filter_map(|u| u.strip_prefix("super::"))
            .collect();
        let _ = writeln!(s, "    use super::{{{}}};", names.join(", "));
    }
    for u in &others {
        let _ = writeln!(s, "    use {u};");
    }
    let _ = writeln!(
        s,
        "\n{body}    /// The tasks the data-received events activate, each once, in the order of \
         [`Released`]'s bits.\n    pub const ACTIVATED: [TaskId; {}] = [{}];\n",
        activated.len(),
        activated
            .iter()
            .map(|t| format!("os::{}", crate::rust::constant(&t.name)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        s,
        "    /// Each task a write activates, and the task whose runnable writes (activated, \
         writer): {}.\n    pub const RELEASED_BY: [(TaskId, TaskId); {}] = [{}];\n{bodies}}}\n",
        released
            .iter()
            .map(|(_, _, w, sender)| format!("{sender}'s runnable in `{w}`"))
            .collect::<Vec<_>>()
            .join(", "),
        released.len(),
        released
            .iter()
            .map(|(a, w, _, _)| format!("(os::{a}, os::{w})"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// The task whose job's write activates `activated`: the one task the runnables of the
/// sender's prototype `sender` are mapped to.
fn writer_of<'e>(
    sw: &Software,
    ecu: &'e crate::model::Ecu,
    sender: &str,
    activated: &crate::model::Task,
) -> Result<&'e crate::model::Task, Error> {
    let mut writers: Vec<&crate::model::Task> = Vec::new();
    for m in sw.mappings.iter().filter(|m| m.prototype == sender) {
        if let Some(t) = ecu.os.tasks.iter().find(|t| t.path == m.task) {
            if !writers.iter().any(|w| w.path == t.path) {
                writers.push(t);
            }
        }
    }
    match writers.as_slice() {
        [writer] => Ok(writer),
        _ => Err(Error::new(
            format!(
                "{sender}'s runnables run in {} tasks: which one's write activates {} cannot be told (one task can be generated)",
                writers.len(),
                activated.name
            ),
            &[&sw.rte_path],
        )),
    }
}

/// Each task a data-received event activates and the task whose job's write does, by
/// name (the generated `RELEASED_BY`), for the task set's analysis.
///
/// # Errors
/// An event mapped to no task, or a sender whose runnables run in more than one task.
pub fn released_by(sw: &Software, ecu: &crate::model::Ecu) -> Result<Vec<(String, String)>, Error> {
    let (events, _, _) = activations(sw, ecu)?;
    events
        .iter()
        .map(|a| {
            Ok((
                a.task.name.clone(),
                writer_of(sw, ecu, &a.buffer.sender, a.task)?.name.clone(),
            ))
        })
        .collect()
}

/// A data-received event's buffer and the task its event runs in.
struct Activation<'e> {
    buffer: Buffer,
    receiver: String,
    port: String,
    task: &'e crate::model::Task,
}

/// Each data-received event's buffer with its task, in the order of the buffers; the tasks
/// they activate, each once, in that order; and each buffer's bit in `Released` (its task's
/// place there).
#[allow(clippy::type_complexity)]
fn activations<'e>(
    sw: &Software,
    ecu: &'e crate::model::Ecu,
) -> Result<
    (
        Vec<Activation<'e>>,
        Vec<&'e crate::model::Task>,
        HashMap<String, usize>,
    ),
    Error,
> {
    let mut events = Vec::new();
    let mut tasks: Vec<&crate::model::Task> = Vec::new();
    let mut bits = HashMap::new();
    for b in sw.buffers_with_events() {
        let Some((receiver, port)) = b.receiver.clone() else {
            continue;
        };
        let task = task_of(
            sw,
            ecu,
            &receiver,
            |e| matches!(&e.kind, EventKind::DataReceived { port: p } if *p == port),
        )
        .ok_or_else(|| {
            Error::new(
                format!("{receiver}.{port}'s data-received event is mapped to no task"),
                &[&sw.rte_path],
            )
        })?;
        let bit = match tasks.iter().position(|t| t.path == task.path) {
            Some(i) => i,
            None => {
                tasks.push(task);
                tasks.len() - 1
            }
        };
        bits.insert(b.field.clone(), bit);
        events.push(Activation {
            buffer: b,
            receiver,
            port,
            task,
        });
    }
    Ok((events, tasks, bits))
}

/// A task body per task that runs runnables: each runnable, in the order of its position
/// in the task, called on its prototype's component with that prototype's context; the
/// data-received events the job's writes fired returned. And what the bodies use.
fn emit_bodies(sw: &Software, ecu: &crate::model::Ecu) -> Result<(String, Vec<String>), Error> {
    let bufs = buffers(sw);
    let mut out = String::new();
    let mut uses: Vec<String> = Vec::new();
    for task in &ecu.os.tasks {
        let mut runs: Vec<&Mapping> = sw.mappings.iter().filter(|m| m.task == task.path).collect();
        if runs.is_empty() {
            continue;
        }
        runs.sort_by_key(|m| m.position);
        let mut params: Vec<(String, String)> = Vec::new();
        let mut calls = String::new();
        let mut listed = Vec::new();
        let mut any_fires = false;
        for m in runs {
            let proto =
                find(&sw.composition.prototypes, &m.prototype, |p| &p.name).ok_or_else(|| {
                    Error::new(
                        format!("prototype {} does not exist", m.prototype),
                        &[&m.path],
                    )
                })?;
            let c = find(&sw.components, &proto.component, |c| &c.name).ok_or_else(|| {
                Error::new(
                    format!("component type {} does not exist", proto.component),
                    &[&proto.path],
                )
            })?;
            let e = c.events.iter().find(|e| e.path == m.event).ok_or_else(|| {
                Error::new(format!("event {} is not {}'s", m.event, c.name), &[&m.path])
            })?;
            let param = snake(&proto.name);
            let bound = runnables_trait(c);
            if !params.iter().any(|(p, _)| p == &param) {
                params.push((param.clone(), bound.clone()));
            }
            if !uses.contains(&format!("super::{bound}")) {
                uses.push(format!("super::{bound}"));
            }
            listed.push(format!(
                "{}.{} (position {})",
                proto.name, e.runnable, m.position
            ));
            let method = snake(&e.runnable);
            if fires(sw, &bufs, proto) {
                any_fires = true;
                let _ = writeln!(
                    calls,
                    "        let mut ports = rte.{param}();\n        {param}.{method}(&mut ports);\n        released.0 |= ports.released.0;"
                );
            } else {
                let _ = writeln!(calls, "        {param}.{method}(&mut rte.{param}());");
            }
        }
        let (start, end) = if any_fires {
            (
                "        let mut released = Released::NONE;\n",
                "        released\n",
            )
        } else {
            ("", "        Released::NONE\n")
        };
        let _ = writeln!(
            out,
            "\n    /// `{}` ({}): {}, each with its prototype's context; the data-received events \
             its writes fired.\n    #[must_use = \"the tasks of the data-received events a job fired must be activated\"]\n    pub fn {}(\n        rte: &mut Rte,\n{}    ) -> Released {{\n{start}{calls}{end}    }}",
            task.name,
            task.path,
            listed.join(", then "),
            snake(&task.name),
            params
                .iter()
                .map(|(p, b)| format!("        {p}: &mut impl {b},\n"))
                .collect::<String>()
        );
    }
    if !out.is_empty() {
        uses.push("super::Released".to_string());
        uses.push("super::Rte".to_string());
    }
    uses.sort();
    Ok((out, uses))
}

impl Software {
    /// The RTE's buffers ([`buffers`]) that a data-received event reads.
    fn buffers_with_events(&self) -> Vec<Buffer> {
        buffers(self).into_iter().filter(|b| b.notify).collect()
    }
}

/// The generated RTE module's text (before `rustfmt`).
///
/// # Errors
/// An item the checks passed refers to something missing (a broken invariant, named).
pub fn emit(
    sw: &Software,
    ecu: &crate::model::Ecu,
    source: &str,
    digest: &str,
) -> Result<String, Error> {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "//! The RTE of this ECU: the interfaces and the connections between its software \
         components, generated by `cargo xtask generate` from `{source}` (ARXML, AUTOSAR 4). \
         Do not edit: change the description and generate again; the check command fails \
         when this file and the description disagree.\n//!\n//! Each connection is a typed \
         buffer from `cw_core::rte`. A component implements its type's runnables trait \
         against its type's ports trait; the task bodies in [`tasks`] call each runnable with \
         its prototype's context, which reaches exactly that prototype's connections, so a \
         component that uses a port it does not have, in the wrong direction or with the wrong \
         data does not compile. Each item names the ARXML path it came from; the tasks are the \
         OS's of the ECU's description.\n//!\n//! Description digest: {digest}\n"
    );
    // What the generated items use, and nothing else (an unused import is a warning).
    let bufs = buffers(sw);
    // A port's method returns `RteError` unless it writes or reads last-is-best data.
    let mut queued_or_taken = false;
    for c in &sw.components {
        for p in &c.ports {
            if let Ok((kind, _, _)) = access(sw, c, p) {
                queued_or_taken |= !matches!(kind, Access::Write | Access::Read);
            }
        }
    }
    let mut uses = vec!["SenderReceiverInterface"];
    if bufs.iter().any(|b| b.queue.is_none()) {
        uses.push("LastIsBest");
    }
    if bufs.iter().any(|b| b.queue.is_some()) {
        uses.push("Queued");
    }
    if queued_or_taken {
        uses.push("RteError");
    }
    uses.sort_unstable();
    let _ = writeln!(s, "use cw_core::rte::{{{}}};\n", uses.join(", "));
    for i in &sw.interfaces {
        let t = find(&sw.types, &i.data_type, |t| &t.name).ok_or_else(|| {
            Error::new(
                format!("data type {} does not exist", i.data_type),
                &[&i.path],
            )
        })?;
        let _ = writeln!(
            s,
            "/// `{}` ({}): {} Its data element `{}` is a `{}` ({}).\npub struct {};\nimpl SenderReceiverInterface for {} {{\n    type Data = {};\n    const NAME: &'static str = \"{}\";\n}}\n",
            i.name, i.path, i.doc, i.element, t.name, t.path, i.name, i.name, t.rust, i.name
        );
    }
    let _ = writeln!(
        s,
        "/// All connections of `{}` ({}): {}\n///\n/// Its buffers are private: each prototype \
         reaches them through its ports (`Rte::ultra_sonic()`, ...), typed by their direction \
         and data.\npub struct Rte {{",
        sw.composition.name, sw.composition.path, sw.composition.doc
    );
    for b in &bufs {
        for (what, path) in &b.carries {
            let _ = writeln!(s, "    /// {what} ({path})");
        }
        if b.notify {
            let _ = writeln!(
                s,
                "    ///\n    /// A data-received event reads it: a write notes new data."
            );
        }
        let ty = match b.queue {
            Some(n) => format!("Queued<{}, {n}>", b.interface),
            None => format!("LastIsBest<{}>", b.interface),
        };
        let _ = writeln!(s, "    {}: {ty},", b.field);
    }
    let _ = writeln!(
        s,
        "}}\n\nimpl Rte {{\n    /// The connections before any write: each holds its init value.\n    pub const fn new() -> Self {{\n        Self {{"
    );
    for b in &bufs {
        let value = match (b.queue, &b.init) {
            (Some(_), _) => "Queued::new()".to_string(),
            (None, Some(init)) => {
                let rust = find(&sw.interfaces, &b.interface, |i| &i.name)
                    .and_then(|i| find(&sw.types, &i.data_type, |t| &t.name))
                    .map(|t| t.rust.clone())
                    .ok_or_else(|| {
                        Error::new(
                            format!("interface {} has no data type", b.interface),
                            &[&sw.composition.path],
                        )
                    })?;
                format!("LastIsBest::new({rust}::{init}, {})", b.notify)
            }
            (None, None) => {
                return Err(Error::new(
                    format!("buffer {} has no init value", b.field),
                    &[&sw.composition.path],
                ))
            }
        };
        let _ = writeln!(s, "            {}: {value},", b.field);
    }
    let _ = writeln!(
        s,
        "        }}\n    }}\n}}\n\nimpl Default for Rte {{\n    fn default() -> Self {{\n        Self::new()\n    }}\n}}\n"
    );
    let (_, activated, bits) = activations(sw, ecu)?;
    emit_components(sw, &activated, &bits, &mut s)?;
    emit_tasks(sw, ecu, &mut s)?;
    Ok(s)
}

/// `snake`'s words joined in CamelCase: `red_led` is `RedLed`.
fn camel(snake_name: &str) -> String {
    snake_name
        .split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// The generated names of a component type's traits and a prototype's context.
fn ports_trait(c: &ComponentType) -> String {
    format!("{}Ports", camel(&snake(&c.name)))
}

fn runnables_trait(c: &ComponentType) -> String {
    format!("{}Runnables", camel(&snake(&c.name)))
}

fn context(p: &Prototype) -> String {
    format!("{}Context", camel(&snake(&p.name)))
}

/// How a runnable reaches a port: the port's direction, its interface's policy and, for a
/// required port, whether a data-received event of the component reads it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Access {
    Write,
    Send,
    Receive,
    Take,
    Read,
}

/// The port's access, its method's name and the Rust type of its data.
fn access(
    sw: &Software,
    c: &ComponentType,
    port: &Port,
) -> Result<(Access, String, String), Error> {
    let i = find(&sw.interfaces, &port.interface, |i| &i.name).ok_or_else(|| {
        Error::new(
            format!("interface {} does not exist", port.interface),
            &[&port.path],
        )
    })?;
    let data = find(&sw.types, &i.data_type, |t| &t.name)
        .map(|t| t.rust.clone())
        .ok_or_else(|| {
            Error::new(
                format!("data type {} does not exist", i.data_type),
                &[&i.path],
            )
        })?;
    let event = c
        .events
        .iter()
        .any(|e| matches!(&e.kind, EventKind::DataReceived { port: p } if p == &port.name));
    let (kind, verb) = match (port.provided, i.queued, event) {
        (true, false, _) => (Access::Write, "write"),
        (true, true, _) => (Access::Send, "send"),
        (false, true, _) => (Access::Receive, "receive"),
        (false, false, true) => (Access::Take, "take"),
        (false, false, false) => (Access::Read, "read"),
    };
    Ok((kind, format!("{verb}_{}", snake(&port.name)), data))
}

/// The buffers a prototype's port writes into (provided) or reads (required).
fn connected<'a>(bufs: &'a [Buffer], proto: &Prototype, port: &Port) -> Vec<&'a Buffer> {
    let end = format!("{}.{}", proto.name, port.name);
    bufs.iter()
        .filter(|b| {
            b.carries.iter().any(|(what, _)| {
                let (from, to) = what.split_once(" -> ").unwrap_or((what, ""));
                if port.provided {
                    from == end
                } else {
                    to == end
                }
            })
        })
        .collect()
}

/// Whether a write of the prototype can fire a data-received event: its context then
/// notes the events it fired.
fn fires(sw: &Software, bufs: &[Buffer], proto: &Prototype) -> bool {
    find(&sw.components, &proto.component, |c| &c.name).is_some_and(|c| {
        c.ports
            .iter()
            .filter(|p| p.provided)
            .any(|p| connected(bufs, proto, p).iter().any(|b| b.notify))
    })
}

/// Whether the prototype's events run in a task: its context is then made by the generated
/// task bodies alone.
fn mapped(sw: &Software, proto: &Prototype) -> bool {
    sw.mappings.iter().any(|m| m.prototype == proto.name)
}

/// The component types' contracts and the prototypes' contexts:
/// - per component type, a trait of its ports (`LedActuatorPorts`), a method per port in
///   its direction, typed by its interface's data, and a trait of its runnables
///   (`LedActuatorRunnables`), a method each, taking the ports;
/// - per prototype, its context (`RedLedContext`), which implements its type's ports on
///   the buffers its connectors use and nothing else.
///
/// A component written against its traits that uses a port its type does not have, in the
/// wrong direction or with another type of data does not compile.
fn emit_components(
    sw: &Software,
    activated: &[&crate::model::Task],
    bits: &HashMap<String, usize>,
    s: &mut String,
) -> Result<(), Error> {
    let comp = &sw.composition;
    let bufs = buffers(sw);
    let mut calls = String::new();
    for (k, task) in activated.iter().enumerate() {
        let _ = writeln!(
            calls,
            "        if self.0 & {:#x} != 0 {{\n            activate(crate::generated::os::{});\n        }}",
            1u64 << k,
            crate::rust::constant(&task.name)
        );
    }
    if activated.is_empty() {
        calls.push_str("        let _ = &mut activate;\n");
    }
    let _ = writeln!(
        s,
        "/// The tasks whose data-received events a job's writes fired, a bit each in the \
         order of [`tasks::ACTIVATED`]: to activate once the job has left the RTE.\n\
         #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]\n\
         #[must_use = \"the tasks of the data-received events a job fired must be activated\"]\n\
         pub struct Released(u32);\n\n\
         impl Released {{\n    /// No event fired.\n    pub const NONE: Self = Self(0);\n\n    \
         /// The tasks to activate, each once.\n    pub fn tasks(self) -> \
         impl Iterator<Item = cw_core::os::TaskId> {{\n        tasks::ACTIVATED\n            \
         .into_iter()\n            .enumerate()\n            .filter(move |&(i, _)| (self.0 >> (i & 31)) & 1 == 1)\n            \
         .map(|(_, task)| task)\n    }}\n\n    \
         /// Calls `activate` with each task to activate, once, in the order of \
         [`tasks::ACTIVATED`] (a test of a constant bit and a call with a constant task \
         each).\n    pub fn activate(self, mut activate: impl FnMut(cw_core::os::TaskId)) {{\n{}    }}\n}}\n",
        calls
    );
    for c in &sw.components {
        let _ = writeln!(
            s,
            "/// The ports of component type `{}` ({}), as its runnables reach them whichever \
             prototype they run as: each prototype's context implements it on its own connections.\npub trait {} {{",
            c.name,
            c.path,
            ports_trait(c)
        );
        for port in &c.ports {
            let (kind, method, data) = access(sw, c, port)?;
            let what = match kind {
                Access::Write => "writes the value to every receiver connected.",
                Access::Send => "sends the value into every receiver's queue; refused when a queue is full (a queue after it then does not get it).",
                Access::Receive => "the oldest value in the queue, or `RteError::NoData`.",
                Access::Take => "the value if it is new since the last take (its data-received event), else `RteError::NoData`.",
                Access::Read => "the newest value its sender wrote (its init value before).",
            };
            let sig = match kind {
                Access::Write => format!("fn {method}(&mut self, value: {data})"),
                Access::Send => {
                    format!("fn {method}(&mut self, value: {data}) -> Result<(), RteError>")
                }
                Access::Receive | Access::Take => {
                    format!("fn {method}(&mut self) -> Result<{data}, RteError>")
                }
                Access::Read => format!("fn {method}(&self) -> {data}"),
            };
            let _ = writeln!(
                s,
                "    /// `{}` ({}, {}): {what}\n    {sig};\n",
                port.name,
                if port.provided {
                    "provided"
                } else {
                    "required"
                },
                port.path
            );
        }
        let _ = writeln!(s, "}}\n");
        if c.runnables.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            "/// The runnables of component type `{}` ({}): the type that implements it is the \
             component. The task bodies in [`tasks`] call each runnable with its prototype's \
             context, in the task its event is mapped to.\npub trait {} {{",
            c.name,
            c.path,
            runnables_trait(c)
        );
        for (r, path) in &c.runnables {
            let started: Vec<String> = c
                .events
                .iter()
                .filter(|e| &e.runnable == r)
                .map(|e| match &e.kind {
                    EventKind::Timing { period_ms } => format!("every {period_ms} ms ({})", e.path),
                    EventKind::DataReceived { port } => {
                        format!("on data received on {port} ({})", e.path)
                    }
                })
                .collect();
            let _ = writeln!(
                s,
                "    /// `{r}` ({path}): {}.\n    fn {}(&mut self, ports: &mut impl {});\n",
                started.join(", "),
                snake(r),
                ports_trait(c)
            );
        }
        let _ = writeln!(s, "}}\n");
    }
    let mut accessors = String::new();
    for proto in &comp.prototypes {
        let c = find(&sw.components, &proto.component, |c| &c.name).ok_or_else(|| {
            Error::new(
                format!("component type {} does not exist", proto.component),
                &[&proto.path],
            )
        })?;
        let ty = context(proto);
        let fires = fires(sw, &bufs, proto);
        let reaches = c
            .ports
            .iter()
            .any(|p| !connected(&bufs, proto, p).is_empty());
        let (visibility, by) = if mapped(sw, proto) {
            ("", "the task bodies in [`tasks`] alone")
        } else {
            ("pub ", "the basic software")
        };
        let _ = writeln!(
            accessors,
            "    /// The context of `{}` ({}), of component type `{}`, for {by}.\n    {visibility}fn {}(&mut self) -> {ty}<'_> {{\n        {ty} {{ rte: self{} }}\n    }}\n",
            proto.name,
            proto.path,
            c.name,
            snake(&proto.name),
            if fires { ", released: Released::NONE" } else { "" }
        );
        let _ = writeln!(
            s,
            "/// The context of `{}` ({}), of component type `{}` ({}): its ports on its \
             connections.\npub struct {ty}<'a> {{\n{}    rte: &'a mut Rte,{}\n}}\n\nimpl {} for {ty}<'_> {{",
            proto.name,
            proto.path,
            c.name,
            c.path,
            if reaches {
                ""
            } else {
                "    /// No port of it reaches a connection.\n    #[allow(dead_code)]\n"
            },
            if fires {
                "\n    /// The data-received events its writes fired.\n    released: Released,"
            } else {
                ""
            },
            ports_trait(c)
        );
        for port in &c.ports {
            let (kind, method, data) = access(sw, c, port)?;
            let used = connected(&bufs, proto, port);
            let fields: Vec<&str> = used.iter().map(|b| b.field.as_str()).collect();
            let verb = match kind {
                Access::Write => "Writes",
                Access::Send => "Sends into",
                Access::Receive => "Receives from",
                Access::Take => "Takes from",
                Access::Read => "Reads",
            };
            let _ = writeln!(s, "    /// {verb} `{}`.", fields.join("`, `"));
            match kind {
                Access::Write => {
                    let _ = writeln!(s, "    fn {method}(&mut self, value: {data}) {{");
                    for b in &used {
                        match bits.get(&b.field) {
                            Some(k) if b.notify => {
                                let _ = writeln!(
                                    s,
                                    "        if self.rte.{}.write(value).0 {{\n            self.released.0 |= {:#x};\n        }}",
                                    b.field,
                                    1u64 << *k
                                );
                            }
                            _ => {
                                let _ = writeln!(
                                    s,
                                    "        let _ = self.rte.{}.write(value);",
                                    b.field
                                );
                            }
                        }
                    }
                    if used.is_empty() {
                        let _ = writeln!(s, "        let _ = value;");
                    }
                    let _ = writeln!(s, "    }}\n");
                }
                Access::Send => {
                    let _ = writeln!(
                        s,
                        "    fn {method}(&mut self, value: {data}) -> Result<(), RteError> {{"
                    );
                    for f in &fields {
                        let _ = writeln!(s, "        let _ = self.rte.{f}.send(value)?;");
                    }
                    if used.is_empty() {
                        let _ = writeln!(s, "        let _ = value;");
                    }
                    let _ = writeln!(s, "        Ok(())\n    }}\n");
                }
                Access::Receive | Access::Take | Access::Read => {
                    let [b] = used.as_slice() else {
                        return Err(Error::new(
                            format!(
                                "required port {}.{} is connected to {} buffers: one is generated",
                                proto.name,
                                port.name,
                                used.len()
                            ),
                            &[&port.path, &proto.path],
                        ));
                    };
                    let (sig, call) = match kind {
                        Access::Read => (format!("(&self) -> {data}"), "read"),
                        Access::Take => {
                            (format!("(&mut self) -> Result<{data}, RteError>"), "take")
                        }
                        _ => (
                            format!("(&mut self) -> Result<{data}, RteError>"),
                            "receive",
                        ),
                    };
                    let _ = writeln!(
                        s,
                        "    fn {method}{sig} {{\n        self.rte.{}.{call}()\n    }}\n",
                        b.field
                    );
                }
            }
        }
        let _ = writeln!(s, "}}\n");
    }
    let mut peeks = String::new();
    for b in bufs.iter().filter(|b| b.queue.is_none()) {
        let data = find(&sw.interfaces, &b.interface, |i| &i.name)
            .and_then(|i| find(&sw.types, &i.data_type, |t| &t.name))
            .map(|t| t.rust.clone())
            .ok_or_else(|| {
                Error::new(
                    format!("interface {} has no data type", b.interface),
                    &[&comp.path],
                )
            })?;
        let _ = writeln!(
            peeks,
            "    /// The value `{}` holds now, not taken ({}): to measure and test; a component \
             reaches it through its ports.\n    pub fn peek_{}(&self) -> {data} {{\n        self.{}.read()\n    }}\n",
            b.field,
            b.carries
                .iter()
                .map(|(what, _)| what.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            b.field,
            b.field
        );
    }
    let _ = writeln!(
        s,
        "/// Each prototype's context (it borrows the connections for as long as it is used), \
         and each last-is-best buffer's value.\nimpl Rte {{\n{accessors}{peeks}}}\n"
    );
    Ok(())
}
