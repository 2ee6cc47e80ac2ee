//! The description in ARXML (AUTOSAR 4, read and written with `autosar-data`): the ECUC
//! values of the basic software modules (`ECUC-MODULE-CONFIGURATION-VALUES`).
//!
//! Reading goes in two steps. First every module's containers become a plain tree
//! ([`Container`]: its path, its definition, its parameters, references and
//! sub-containers), whatever definition paths the file uses: the standard module
//! definitions (`/AUTOSAR/EcucDefs/Os/OsTask/OsTaskPriority`) or a vendor's
//! (`/MICROSAR/Os/OsTask/OsTaskPriority`, `/ArcCore/Os/...`): a definition is known by the
//! last segments of its path, below its module's. Then each known container is mapped onto
//! [`crate::model`]. What cannot be mapped is refused with its path: an unknown module,
//! container, parameter or reference, a value of the wrong form, a reference to nothing.
//! Standard parameters, references and containers that this ECU has no use for are read
//! and reported as notes with their paths, never silently dropped.

use autosar_data::{AttributeName, AutosarModel, AutosarVersion, Element, ElementName, EnumItem};

use crate::model::{
    Alarm, AlarmAction, CanController, CanIf, Com, Counter, Direction, Ecu, Endianness, Event,
    Hooks, IPdu, Isr, LPdu, Named, Os, Pdu, Route, Signal, Status, Task, Timing, Transfer, TxIPdu,
    TxModeMode,
};
use crate::validate::Error;

/// The AUTOSAR version the description is written in (R21-11, `AUTOSAR_00050.xsd`).
pub const VERSION: AutosarVersion = AutosarVersion::Autosar_00050;
/// Where the standard module definitions live.
pub const STANDARD_DEFS: &str = "/AUTOSAR/EcucDefs";

/// Top-level containers of the standard definitions that this ECU does not use: reading one
/// gives a note, not an error (the parameters and references it does not use are noted
/// where their container is read).
pub const UNUSED: &[&str] = &[
    "ComGeneral",
    "CanIfPublicCfg",
    "CanIfPrivateCfg",
    "CanIfCtrlDrvCfg",
    "PduRGeneral",
    "PduRBswModules",
    "CanGeneral",
];

/// A parameter's value as written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Param {
    /// The definition's last segment (`OsTaskPriority`).
    pub def: String,
    /// The value's text.
    pub value: String,
}

/// A reference: its definition's last segment, the path it points to and what is there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ref {
    /// The definition's last segment (`OsTaskResourceRef`).
    pub def: String,
    /// The target's ARXML path.
    pub target: String,
    /// The target's definition's last segment (`OsResource`), or its element's name where
    /// it is not an ECUC container.
    pub target_def: String,
}

/// An ECUC container value, read generically.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Container {
    /// Its ARXML path.
    pub path: String,
    /// Its definition below the module's (`OsTask`, `OsAlarm/OsAlarmAutostart`).
    pub def: String,
    /// Parameter values.
    pub params: Vec<Param>,
    /// Reference values.
    pub refs: Vec<Ref>,
    /// Sub-containers.
    pub subs: Vec<Container>,
}

/// One module's values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Module {
    /// Its ARXML path.
    pub path: String,
    /// The module's name: its definition's last segment (`Os`).
    pub name: String,
    /// Its definition path (`/AUTOSAR/EcucDefs/Os`).
    pub def_path: String,
    /// Its containers.
    pub containers: Vec<Container>,
}

/// A description read: the model, and notes on what was read but has no use here.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Read {
    /// The ECU.
    pub ecu: Ecu,
    /// One sentence per parameter or container of [`UNUSED`] met, with its path.
    pub notes: Vec<String>,
}

fn text(e: &Element, name: ElementName) -> Option<String> {
    e.get_sub_element(name)
        .and_then(|s| s.character_data())
        .map(|c| c.to_string())
}

fn path_of(e: &Element) -> String {
    e.path()
        .unwrap_or_else(|_| format!("<{}>", e.element_name()))
}

/// The definition of `e` below `module_def`, or an error naming `at`.
fn def_below(e: &Element, module_def: &str, at: &str) -> Result<String, Error> {
    let def = text(e, ElementName::DefinitionRef)
        .ok_or_else(|| Error::new("no DEFINITION-REF", &[at]))?;
    def.strip_prefix(module_def)
        .and_then(|rest| rest.strip_prefix('/'))
        .map(str::to_string)
        .ok_or_else(|| {
            Error::new(
                format!("definition {def} is not below the module's {module_def}"),
                &[at],
            )
        })
}

fn read_container(e: &Element, module_def: &str, out: &mut Vec<Error>) -> Option<Container> {
    let path = path_of(e);
    let def = match def_below(e, module_def, &path) {
        Ok(d) => d,
        Err(err) => {
            out.push(err);
            return None;
        }
    };
    let last = |d: &str| d.rsplit('/').next().unwrap_or(d).to_string();
    let mut params = Vec::new();
    for p in e
        .get_sub_element(ElementName::ParameterValues)
        .iter()
        .flat_map(Element::sub_elements)
    {
        let Some(d) = text(&p, ElementName::DefinitionRef) else {
            out.push(Error::new(
                "a parameter value without DEFINITION-REF",
                &[&path],
            ));
            continue;
        };
        let Some(value) = text(&p, ElementName::Value) else {
            out.push(Error::new(
                format!("parameter {} has no VALUE", last(&d)),
                &[&path],
            ));
            continue;
        };
        params.push(Param {
            def: last(&d),
            value: value.trim().to_string(),
        });
    }
    let mut refs = Vec::new();
    for r in e
        .get_sub_element(ElementName::ReferenceValues)
        .iter()
        .flat_map(Element::sub_elements)
    {
        let Some(d) = text(&r, ElementName::DefinitionRef) else {
            out.push(Error::new(
                "a reference value without DEFINITION-REF",
                &[&path],
            ));
            continue;
        };
        let (target, target_def) = match r.get_sub_element(ElementName::ValueRef) {
            Some(v) => match v.get_reference_target() {
                Ok(t) => {
                    let def = text(&t, ElementName::DefinitionRef).map_or_else(
                        || t.element_name().to_string(),
                        |d| d.rsplit('/').next().unwrap_or(&d).to_string(),
                    );
                    (path_of(&t), def)
                }
                Err(_) => {
                    out.push(Error::new(
                        format!(
                            "reference {} points to {}, which the description does not have",
                            last(&d),
                            text(&r, ElementName::ValueRef).unwrap_or_default()
                        ),
                        &[&path],
                    ));
                    continue;
                }
            },
            None => {
                out.push(Error::new(
                    format!("reference {} has no VALUE-REF", last(&d)),
                    &[&path],
                ));
                continue;
            }
        };
        refs.push(Ref {
            def: last(&d),
            target,
            target_def,
        });
    }
    let subs = e
        .get_sub_element(ElementName::SubContainers)
        .iter()
        .flat_map(Element::sub_elements)
        .filter_map(|s| read_container(&s, module_def, out))
        .collect();
    Some(Container {
        path,
        def,
        params,
        refs,
        subs,
    })
}

/// An ARXML file's bytes loaded, strictly (valid against the schema), into a new model.
///
/// # Errors
/// The file does not parse: the library's message (with its line), naming the file.
pub fn load(bytes: &[u8], file_name: &str) -> Result<AutosarModel, Vec<Error>> {
    let model = AutosarModel::new();
    // `autosar-data` 0.23.0 panics on some malformed input (`<?>`: a slice out of range in
    // its lexer, found by this crate's bolero harness): its panic is this file's error.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        model.load_buffer(bytes, file_name, true)
    }));
    match loaded {
        Ok(Ok(_)) => Ok(model),
        Ok(Err(e)) => Err(vec![Error::new(e.to_string(), &[file_name])]),
        Err(_) => Err(vec![Error::new(
            "the ARXML library failed on this file (it is not well-formed XML)",
            &[file_name],
        )]),
    }
}

/// Every module's values in an ARXML file, as generic trees.
///
/// # Errors
/// The file does not parse as AUTOSAR 4 ARXML (with its line), or a container has no
/// definition below its module's, or a reference points to nothing.
pub fn modules(bytes: &[u8], file_name: &str) -> Result<Vec<Module>, Vec<Error>> {
    let model = load(bytes, file_name)?;
    let mut out = Vec::new();
    let mut modules = Vec::new();
    for (_, e) in model.elements_dfs() {
        if e.element_name() != ElementName::EcucModuleConfigurationValues {
            continue;
        }
        let path = path_of(&e);
        let Some(def_path) = text(&e, ElementName::DefinitionRef) else {
            out.push(Error::new("a module without DEFINITION-REF", &[&path]));
            continue;
        };
        let name = def_path.rsplit('/').next().unwrap_or(&def_path).to_string();
        let containers = e
            .get_sub_element(ElementName::Containers)
            .iter()
            .flat_map(Element::sub_elements)
            .filter_map(|c| read_container(&c, &def_path, &mut out))
            .collect();
        modules.push(Module {
            path,
            name,
            def_path,
            containers,
        });
    }
    if out.is_empty() {
        Ok(modules)
    } else {
        Err(out)
    }
}

/// A container being mapped: what has been taken from it, so that what is left over is
/// refused (or noted, for [`UNUSED`]).
struct Take<'a> {
    c: &'a Container,
    /// A mapping function took this (top-level) container.
    touched: bool,
    params: Vec<bool>,
    refs: Vec<bool>,
    subs: Vec<bool>,
}

/// Numbers as ECUC writes them: decimal, `0x` hex, `0b` binary, `0` octal.
pub fn parse_int(text: &str) -> Option<u64> {
    let t = text.strip_prefix('+').unwrap_or(text);
    if let Some(h) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        u64::from_str_radix(h, 16).ok()
    } else if let Some(b) = t.strip_prefix("0b").or_else(|| t.strip_prefix("0B")) {
        u64::from_str_radix(b, 2).ok()
    } else if t.len() > 1 && t.starts_with('0') {
        u64::from_str_radix(&t[1..], 8).ok()
    } else {
        t.parse().ok()
    }
}

/// A time in seconds (ECUC's unit for times, an `xsd:double` literal: `0.01`, `1.5E-2`) as
/// whole milliseconds, up to `u32::MAX`; read exactly from its decimal digits, so a time
/// that is not a whole number of milliseconds (`0.0205`) is `None` at any size.
pub fn parse_exact_ms(text: &str) -> Option<u64> {
    exact_units(text, 3)
}

/// A time in seconds as whole microseconds, up to `u32::MAX`, as [`parse_exact_ms`] reads
/// milliseconds.
pub fn parse_exact_us(text: &str) -> Option<u64> {
    exact_units(text, 6)
}

/// [`parse_exact_us`], or a double that a tool printed with all its 17 digits
/// (`1.4999999999999999E-4` for 150 µs) within a nanosecond of a whole microsecond.
pub fn parse_us(text: &str) -> Option<u64> {
    parse_exact_us(text).or_else(|| near_whole(text, 1e6, 1e-3))
}

/// `text` (seconds) in units of `1 / per_second` s, where a double is within `tolerance`
/// units (or its last digit's precision) of a whole number of them, up to `u32::MAX`.
fn near_whole(text: &str, per_second: f64, tolerance: f64) -> Option<u64> {
    let s: f64 = text.trim().parse().ok()?;
    let units = (s * per_second).round();
    let near = (s * per_second - units).abs() <= tolerance.max(units * 1e-15);
    (s.is_finite() && near && (0.0..=f64::from(u32::MAX)).contains(&units)).then_some(units as u64)
}

/// A time in seconds as a whole number of `10^-power` s, up to `u32::MAX`, read exactly
/// from its decimal digits.
fn exact_units(text: &str, power: i32) -> Option<u64> {
    let text = text.trim();
    let text = text.strip_prefix('+').unwrap_or(text);
    let (mantissa, exponent) = match text.find(['e', 'E']) {
        Some(at) => (text.get(..at)?, text.get(at + 1..)?.parse::<i32>().ok()?),
        None => (text, 0),
    };
    let (whole, fraction) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    if whole.is_empty() && fraction.is_empty()
        || !whole
            .chars()
            .chain(fraction.chars())
            .all(|c| c.is_ascii_digit())
    {
        return None;
    }
    // The digits as one integer, and the power of ten that makes them milliseconds.
    let digits = format!("{whole}{fraction}");
    let digits = digits.trim_start_matches('0');
    let fraction_len = i32::try_from(fraction.len()).ok()?;
    let mut shift = exponent.checked_add(power)?.checked_sub(fraction_len)?;
    let mut digits = digits.to_string();
    while shift < 0 && digits.ends_with('0') {
        digits.pop();
        shift += 1;
    }
    if digits.is_empty() {
        return Some(0);
    }
    if shift < 0 || digits.len() > 20 {
        return None;
    }
    let mut ms: u64 = digits.parse().ok()?;
    for _ in 0..shift {
        ms = ms.checked_mul(10)?;
    }
    (ms <= u64::from(u32::MAX)).then_some(ms)
}

/// [`parse_exact_ms`], or a double that a tool printed with all its 17 digits
/// (`0.10000000000000001` for 0.1 s) within a nanosecond of a whole millisecond.
pub fn parse_ms(text: &str) -> Option<u64> {
    parse_exact_ms(text).or_else(|| near_whole(text, 1000.0, 1e-6))
}

impl<'a> Take<'a> {
    fn new(c: &'a Container) -> Self {
        Self {
            c,
            touched: false,
            params: vec![false; c.params.len()],
            refs: vec![false; c.refs.len()],
            subs: vec![false; c.subs.len()],
        }
    }

    fn last(&self) -> &str {
        self.c.def.rsplit('/').next().unwrap_or(&self.c.def)
    }

    /// The value of parameter `def`, taken.
    fn param(&mut self, def: &str) -> Option<&'a str> {
        let i = self.c.params.iter().position(|p| p.def == def)?;
        if let Some(t) = self.params.get_mut(i) {
            *t = true;
        }
        self.c.params.get(i).map(|p| p.value.as_str())
    }

    /// The value of parameter `def` read by `parse`; where it does not read, an error
    /// saying it is not `what`.
    fn parsed(
        &mut self,
        def: &str,
        parse: fn(&str) -> Option<u64>,
        what: &str,
        out: &mut Vec<Error>,
    ) -> Option<u64> {
        let v = self.param(def)?;
        let parsed = parse(v);
        if parsed.is_none() {
            out.push(Error::new(
                format!("{def} = `{v}` is not {what}"),
                &[&self.c.path],
            ));
        }
        parsed
    }

    fn int(&mut self, def: &str, out: &mut Vec<Error>) -> Option<u64> {
        self.parsed(def, parse_int, "an integer", out)
    }

    fn required_int(&mut self, def: &str, out: &mut Vec<Error>) -> u64 {
        if self.c.params.iter().all(|p| p.def != def) {
            out.push(Error::new(
                format!("{} {} has no {def}", self.last(), self.name()),
                &[&self.c.path],
            ));
            return 0;
        }
        self.int(def, out).unwrap_or(0)
    }

    /// A signal value as ECUC writes it (a string: decimal or `0x` hex, negative for
    /// signed signals), as the raw bits of a 64-bit two's complement.
    fn value(&mut self, def: &str, out: &mut Vec<Error>) -> Option<u64> {
        let v = self.param(def)?;
        let parsed = match v.strip_prefix('-') {
            Some(magnitude) => parse_int(magnitude)
                .and_then(|m| i64::try_from(m).ok())
                .map(|m| m.wrapping_neg() as u64),
            None => parse_int(v),
        };
        if parsed.is_none() {
            out.push(Error::new(
                format!("{def} = `{v}` is not an integer"),
                &[&self.c.path],
            ));
        }
        parsed
    }

    fn ms(&mut self, def: &str, out: &mut Vec<Error>) -> Option<u64> {
        let what = "a whole number of milliseconds (in seconds)";
        self.parsed(def, parse_ms, what, out)
    }

    fn us(&mut self, def: &str, out: &mut Vec<Error>) -> Option<u64> {
        let what = "a whole number of microseconds (in seconds)";
        self.parsed(def, parse_us, what, out)
    }

    /// The `OsTaskTimingProtection` or `OsIsrTimingProtection` (`kind` `Task` or `Isr`)
    /// of this task or ISR: its execution budget and time frame; its lock budgets are
    /// notes.
    fn timing(
        &mut self,
        kind: &str,
        out: &mut Vec<Error>,
        notes: &mut Vec<String>,
    ) -> Option<Timing> {
        let c = self.single(&format!("Os{kind}TimingProtection"), out)?;
        let mut t = Take::new(c);
        let timing = Timing {
            path: c.path.clone(),
            budget_us: t.us(&format!("Os{kind}ExecutionBudget"), out),
            time_frame_us: t.us(&format!("Os{kind}TimeFrame"), out),
        };
        // A lock budget declares a section that blocks interrupts: the analysis does not
        // model one, so only 0 (none) is taken.
        for lock in ["AllInterruptLockBudget", "OsInterruptLockBudget"] {
            let def = format!("Os{kind}{lock}");
            if let Some(us) = t.us(&def, out).filter(|&us| us > 0) {
                out.push(Error::new(
                    format!("{def} = {us} µs: interrupt lock sections are not in the task set's analysis (0 or none is taken)"),
                    &[&c.path],
                ));
            }
        }
        for sub in t.subs(&format!("Os{kind}ResourceLock")) {
            notes.push(format!(
                "{}: a resource's lock budget is not used by this ECU",
                sub.path
            ));
        }
        t.finish(out, notes);
        Some(timing)
    }

    fn boolean(&mut self, def: &str, out: &mut Vec<Error>) -> Option<bool> {
        let v = self.param(def)?;
        match v {
            "true" | "1" => Some(true),
            "false" | "0" => Some(false),
            _ => {
                out.push(Error::new(
                    format!("{def} = `{v}` is not a boolean"),
                    &[&self.c.path],
                ));
                None
            }
        }
    }

    /// An enumeration's literal, taken, and mapped by `literals`.
    fn literal<T: Copy>(
        &mut self,
        def: &str,
        literals: &[(&str, T)],
        out: &mut Vec<Error>,
    ) -> Option<T> {
        let v = self.param(def)?;
        let found = literals.iter().find(|(l, _)| *l == v).map(|(_, t)| *t);
        if found.is_none() {
            let names: Vec<&str> = literals.iter().map(|(l, _)| *l).collect();
            out.push(Error::new(
                format!("{def} = `{v}`: one of {}", names.join(", ")),
                &[&self.c.path],
            ));
        }
        found
    }

    /// The targets' short names of every reference `def`, taken; each must point to a
    /// container of definition `kind` (its last segment).
    fn refs(&mut self, def: &str, kind: &str, out: &mut Vec<Error>) -> Vec<String> {
        let mut names = Vec::new();
        for (i, r) in self.c.refs.iter().enumerate() {
            if r.def == def {
                if let Some(t) = self.refs.get_mut(i) {
                    *t = true;
                }
                if r.target_def != kind {
                    out.push(Error::new(
                        format!(
                            "{def} points to {}, whose definition is {}: it must be {kind}",
                            r.target, r.target_def
                        ),
                        &[&self.c.path],
                    ));
                    continue;
                }
                names.push(r.target.rsplit('/').next().unwrap_or(&r.target).to_string());
            }
        }
        names
    }

    /// The one target of reference `def` (see [`Self::refs`]).
    fn one_ref(&mut self, def: &str, kind: &str, out: &mut Vec<Error>) -> String {
        let count = self.c.refs.iter().filter(|r| r.def == def).count();
        let mut names = self.refs(def, kind, out);
        if count != 1 {
            out.push(Error::new(
                format!(
                    "{} {} has {count} {def}: exactly one is needed",
                    self.last(),
                    self.name()
                ),
                &[&self.c.path],
            ));
        }
        names.pop().unwrap_or_default()
    }

    /// Takes parameter and references `def` that the ECU has no use for, each a note.
    fn unused(&mut self, def: &str, notes: &mut Vec<String>) {
        for (i, p) in self.c.params.iter().enumerate() {
            if p.def == def {
                if let Some(t) = self.params.get_mut(i) {
                    *t = true;
                }
                notes.push(format!(
                    "{}: parameter {def} = {} is not used by this ECU",
                    self.c.path, p.value
                ));
            }
        }
        for (i, r) in self.c.refs.iter().enumerate() {
            if r.def == def {
                if let Some(t) = self.refs.get_mut(i) {
                    *t = true;
                }
                notes.push(format!(
                    "{}: reference {def} to {} is not used by this ECU",
                    self.c.path, r.target
                ));
            }
        }
    }

    /// The sub-container of definition `def` where there may be one at most: a second is
    /// refused.
    fn single(&mut self, def: &str, out: &mut Vec<Error>) -> Option<&'a Container> {
        let found = self.subs(def);
        if let [first, second, ..] = found.as_slice() {
            out.push(Error::new(
                format!("two {def} where there may be one"),
                &[&second.path, &first.path],
            ));
        }
        found.first().copied()
    }

    /// The sub-containers of definition `def` (its last segment), taken.
    fn subs(&mut self, def: &str) -> Vec<&'a Container> {
        let mut found = Vec::new();
        for (i, s) in self.c.subs.iter().enumerate() {
            if s.def.rsplit('/').next() == Some(def) {
                if let Some(t) = self.subs.get_mut(i) {
                    *t = true;
                }
                found.push(s);
            }
        }
        found
    }

    fn name(&self) -> &str {
        self.c.path.rsplit('/').next().unwrap_or(&self.c.path)
    }

    /// Refuses (or notes) everything not taken.
    fn finish(self, out: &mut Vec<Error>, notes: &mut Vec<String>) {
        let c = self.c;
        let mut left = |def: String, what: &str| {
            if UNUSED
                .iter()
                .any(|u| *u == def || def.starts_with(&format!("{u}/")))
            {
                notes.push(format!(
                    "{c_path}: {what} {def} is not used by this ECU",
                    c_path = c.path
                ));
            } else {
                out.push(Error::new(
                    format!("{what} {def} cannot be mapped onto the ECU"),
                    &[&c.path],
                ));
            }
        };
        for (p, taken) in c.params.iter().zip(&self.params) {
            if !taken {
                left(format!("{}/{}", c.def, p.def), "parameter");
            }
        }
        for (r, taken) in c.refs.iter().zip(&self.refs) {
            if !taken {
                left(format!("{}/{}", c.def, r.def), "reference");
            }
        }
        for (s, taken) in c.subs.iter().zip(&self.subs) {
            if !taken {
                if UNUSED.contains(&s.def.as_str()) {
                    notes.push(format!(
                        "{}: container {} is not used by this ECU",
                        s.path, s.def
                    ));
                } else {
                    out.push(Error::new(
                        format!("container {} cannot be mapped onto the ECU", s.def),
                        &[&s.path],
                    ));
                }
            }
        }
    }
}

/// Maps every module onto the model.
///
/// # Errors
/// Everything that cannot be mapped, each with its path.
pub fn map(modules: &[Module]) -> Result<Read, Vec<Error>> {
    let mut ecu = Ecu::default();
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let mut seen: Vec<(&str, &str)> = Vec::new();
    for m in modules {
        if let Some((_, first)) = seen.iter().find(|(n, _)| *n == m.name) {
            out.push(Error::new(
                format!("two {} modules", m.name),
                &[&m.path, first],
            ));
            continue;
        }
        seen.push((&m.name, &m.path));
        let mut top = Vec::new();
        for c in &m.containers {
            top.push(Take::new(c));
        }
        match m.name.as_str() {
            "Os" => map_os(m, &mut top, &mut ecu.os, &mut out, &mut notes),
            "EcuC" => map_ecuc(&mut top, &mut ecu.pdus, &mut out, &mut notes),
            "Com" => map_com(m, &mut top, &mut ecu.com, &mut out, &mut notes),
            "PduR" => map_pdur(&mut top, &mut ecu.routes, &mut out, &mut notes),
            "CanIf" => map_canif(m, &mut top, &mut ecu.canif, &mut out, &mut notes),
            "Can" => map_can(&mut top, &mut ecu.can, &mut out, &mut notes),
            other => {
                out.push(Error::new(
                    format!("module {other} cannot be mapped onto the ECU (Os, EcuC, Com, PduR, CanIf and Can can)"),
                    &[&m.path],
                ));
                continue;
            }
        }
        for t in top {
            if t.touched {
                t.finish(&mut out, &mut notes);
            } else if UNUSED.contains(&t.c.def.as_str()) {
                notes.push(format!(
                    "{}: container {} is not used by this ECU",
                    t.c.path, t.c.def
                ));
            } else {
                out.push(Error::new(
                    format!("container {} cannot be mapped onto the ECU", t.c.def),
                    &[&t.c.path],
                ));
            }
        }
    }
    for needed in ["Os", "EcuC", "Com", "PduR", "CanIf", "Can"] {
        if !seen.iter().any(|(n, _)| *n == needed) {
            out.push(Error::new(
                format!("the description has no {needed} module"),
                &[],
            ));
        }
    }
    if out.is_empty() {
        Ok(Read { ecu, notes })
    } else {
        Err(out)
    }
}

/// Reads an ARXML file's bytes into the model.
///
/// # Errors
/// As [`modules`] and [`map`].
pub fn read(bytes: &[u8], file_name: &str) -> Result<Read, Vec<Error>> {
    map(&modules(bytes, file_name)?)
}

fn top_level<'t, 'a>(top: &'t mut [Take<'a>], def: &str) -> Vec<&'t mut Take<'a>> {
    let mut found = Vec::new();
    for t in top.iter_mut().filter(|t| t.c.def == def) {
        t.touched = true;
        found.push(t);
    }
    found
}

fn name_of(c: &Container) -> String {
    c.path.rsplit('/').next().unwrap_or(&c.path).to_string()
}

fn map_os(
    m: &Module,
    top: &mut [Take<'_>],
    os: &mut Os,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    os.path = m.path.clone();
    let osos = top_level(top, "OsOS");
    if let [first, second, ..] = osos.as_slice() {
        out.push(Error::new(
            "two OsOS where there may be one",
            &[&second.c.path, &first.c.path],
        ));
    }
    for t in osos {
        os.status = t
            .literal(
                "OsStatus",
                &[
                    ("STANDARD", Status::Standard),
                    ("EXTENDED", Status::Extended),
                ],
                out,
            )
            .unwrap_or_default();
        for u in [
            "OsScalabilityClass",
            "OsStackMonitoring",
            "OsUseGetServiceId",
            "OsUseParameterAccess",
            "OsUseResScheduler",
        ] {
            t.unused(u, notes);
        }
        if let Some(h) = t.single("OsHooks", out) {
            let mut h = Take::new(h);
            os.hooks = Hooks {
                error: h.boolean("OsErrorHook", out).unwrap_or(false),
                shutdown: h.boolean("OsShutdownHook", out).unwrap_or(false),
                startup: h.boolean("OsStartupHook", out).unwrap_or(false),
                pre_task: h.boolean("OsPreTaskHook", out).unwrap_or(false),
                post_task: h.boolean("OsPostTaskHook", out).unwrap_or(false),
            };
            h.unused("OsProtectionHook", notes);
            h.finish(out, notes);
        }
    }
    // One application mode: the kernel's OSDEFAULTAPPMODE.
    let modes = top_level(top, "OsAppMode");
    if modes.len() > 1 {
        let paths: Vec<&str> = modes.iter().map(|t| t.c.path.as_str()).collect();
        out.push(Error::new(
            format!("{} application modes: the ECU has one", modes.len()),
            &paths,
        ));
    }
    for t in top_level(top, "OsTask") {
        let autostart = t.single("OsTaskAutostart", out);
        if let Some(a) = autostart {
            let mut a = Take::new(a);
            a.refs("OsTaskAppModeRef", "OsAppMode", out);
            a.finish(out, notes);
        }
        for u in [
            "OsTaskAccessingApplication",
            "OsTaskStackSize",
            "ArcCoreOsTaskStackSize",
        ] {
            t.unused(u, notes);
        }
        os.tasks.push(Task {
            path: t.c.path.clone(),
            name: name_of(t.c),
            priority: t.required_int("OsTaskPriority", out),
            preemptive: t
                .literal("OsTaskSchedule", &[("FULL", true), ("NON", false)], out)
                .unwrap_or(true),
            activations: t.int("OsTaskActivation", out).unwrap_or(1),
            autostart: autostart.is_some(),
            resources: t.refs("OsTaskResourceRef", "OsResource", out),
            events: t.refs("OsTaskEventRef", "OsEvent", out),
            timing: t.timing("Task", out, notes),
        });
    }
    for t in top_level(top, "OsEvent") {
        os.events.push(Event {
            path: t.c.path.clone(),
            name: name_of(t.c),
            mask: t.required_int("OsEventMask", out),
        });
    }
    for t in top_level(top, "OsResource") {
        // Linked and internal resources are not in the kernel.
        t.literal("OsResourceProperty", &[("STANDARD", ())], out);
        t.unused("OsResourceAccessingApplication", notes);
        os.resources.push(Named {
            path: t.c.path.clone(),
            name: name_of(t.c),
        });
    }
    for t in top_level(top, "OsCounter") {
        // The kernel drives its counters from the system timer.
        t.literal("OsCounterType", &[("HARDWARE", ())], out);
        t.unused("OsCounterAccessingApplication", notes);
        os.counters.push(Counter {
            path: t.c.path.clone(),
            name: name_of(t.c),
            max_allowed_value: t.required_int("OsCounterMaxAllowedValue", out),
            ticks_per_base: t.required_int("OsCounterTicksPerBase", out),
            min_cycle: t.required_int("OsCounterMinCycle", out),
        });
    }
    for t in top_level(top, "OsAlarm") {
        let counter = t.one_ref("OsAlarmCounterRef", "OsCounter", out);
        t.unused("OsAlarmAccessingApplication", notes);
        let mut action = None;
        if let Some(a) = t.single("OsAlarmAction", out) {
            let mut a = Take::new(a);
            for x in a.subs("OsAlarmActivateTask") {
                let mut x = Take::new(x);
                let task = x.one_ref("OsAlarmActivateTaskRef", "OsTask", out);
                action = Some(AlarmAction::ActivateTask(task));
                x.finish(out, notes);
            }
            for x in a.subs("OsAlarmSetEvent") {
                let mut x = Take::new(x);
                let task = x.one_ref("OsAlarmSetEventTaskRef", "OsTask", out);
                let event = x.one_ref("OsAlarmSetEventRef", "OsEvent", out);
                if action.is_some() {
                    out.push(Error::new(
                        "an alarm does one thing: two actions",
                        &[&a.c.path],
                    ));
                }
                action = Some(AlarmAction::SetEvent(task, event));
                x.finish(out, notes);
            }
            a.finish(out, notes);
        }
        let mut autostart = None;
        if let Some(a) = t.single("OsAlarmAutostart", out) {
            let mut a = Take::new(a);
            a.literal("OsAlarmAutostartType", &[("RELATIVE", ())], out);
            autostart = Some((
                a.required_int("OsAlarmAlarmTime", out),
                a.int("OsAlarmCycleTime", out).unwrap_or(0),
            ));
            a.refs("OsAlarmAppModeRef", "OsAppMode", out);
            a.finish(out, notes);
        }
        let Some(action) = action else {
            out.push(Error::new(
                format!(
                    "alarm {} has no OsAlarmAction this ECU maps (OsAlarmActivateTask, OsAlarmSetEvent)",
                    name_of(t.c)
                ),
                &[&t.c.path],
            ));
            continue;
        };
        os.alarms.push(Alarm {
            path: t.c.path.clone(),
            name: name_of(t.c),
            counter,
            action,
            autostart,
        });
    }
    for t in top_level(top, "OsIsr") {
        let category = t
            .literal(
                "OsIsrCategory",
                &[("CATEGORY_1", 1), ("CATEGORY_2", 2)],
                out,
            )
            .unwrap_or(2);
        let resources = t.refs("OsIsrResourceRef", "OsResource", out);
        let timing = t.timing("Isr", out, notes);
        // The interrupt priority is the port's, in OSEK's order (a higher number is more
        // urgent), as MICROSAR and TOPPERS name it, or as Arctic Core does.
        let has = |t: &Take<'_>, def: &str| t.c.params.iter().any(|p| p.def == def);
        let def = if has(t, "OsIsrInterruptPriority") || !has(t, "ArcOsIsrPriority") {
            "OsIsrInterruptPriority"
        } else {
            "ArcOsIsrPriority"
        };
        if !has(t, def) {
            out.push(Error::new(
                format!(
                    "ISR {} has no priority (OsIsrInterruptPriority or ArcOsIsrPriority)",
                    name_of(t.c)
                ),
                &[&t.c.path],
            ));
            continue;
        }
        let Some(priority) = t.int(def, out) else {
            continue;
        };
        os.isrs.push(Isr {
            path: t.c.path.clone(),
            name: name_of(t.c),
            category,
            priority,
            resources,
            timing,
        });
    }
}

fn map_ecuc(
    top: &mut [Take<'_>],
    pdus: &mut Vec<Pdu>,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    fn collection(
        t: &mut Take<'_>,
        pdus: &mut Vec<Pdu>,
        out: &mut Vec<Error>,
        notes: &mut Vec<String>,
    ) {
        for p in t.subs("Pdu") {
            let mut p = Take::new(p);
            pdus.push(Pdu {
                path: p.c.path.clone(),
                name: name_of(p.c),
                length: p.required_int("PduLength", out),
            });
            p.finish(out, notes);
        }
        t.unused("PduIdTypeEnum", notes);
        t.unused("PduLengthTypeEnum", notes);
    }
    // R4.2.1 and later: `EcucConfigSet/EcucPduCollection`; before: `EcucPduCollection`.
    for t in top_level(top, "EcucConfigSet") {
        for c in t.subs("EcucPduCollection") {
            let mut c = Take::new(c);
            collection(&mut c, pdus, out, notes);
            c.finish(out, notes);
        }
    }
    for t in top_level(top, "EcucPduCollection") {
        collection(t, pdus, out, notes);
    }
}

fn map_com(
    m: &Module,
    top: &mut [Take<'_>],
    com: &mut Com,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    com.path = m.path.clone();
    for t in top_level(top, "ComConfig") {
        com.path = t.c.path.clone();
        if let Some(f) = t.single("ComTimeBase", out) {
            let mut f = Take::new(f);
            com.main_period_ms = f.ms("ComTxTimeBase", out).unwrap_or(0);
            // Both main functions run in one task, at one period.
            if let Some(rx) = f.ms("ComRxTimeBase", out) {
                if rx != com.main_period_ms {
                    out.push(Error::new(
                        format!(
                            "ComRxTimeBase {rx} ms differs from ComTxTimeBase {} ms: the ECU runs both main functions in one task",
                            com.main_period_ms
                        ),
                        &[&f.c.path],
                    ));
                }
            }
            f.unused("ComGwTimeBase", notes);
            f.finish(out, notes);
        }
        let mut timeouts: Vec<(String, u64, String)> = Vec::new();
        for s in t.subs("ComSignal") {
            let mut s = Take::new(s);
            if s.c.params.iter().all(|p| p.def != "ComSignalType") {
                out.push(Error::new(
                    format!("{} {} has no ComSignalType", s.last(), s.name()),
                    &[&s.c.path],
                ));
            }
            let (signed, type_bits) = s
                .literal(
                    "ComSignalType",
                    &[
                        ("BOOLEAN", (false, 1)),
                        ("UINT8", (false, 8)),
                        ("UINT16", (false, 16)),
                        ("UINT32", (false, 32)),
                        ("UINT64", (false, 64)),
                        ("SINT8", (true, 8)),
                        ("SINT16", (true, 16)),
                        ("SINT32", (true, 32)),
                        ("SINT64", (true, 64)),
                    ],
                    out,
                )
                .unwrap_or((false, 64));
            let signal = Signal {
                path: s.c.path.clone(),
                name: name_of(s.c),
                bit_position: s.required_int("ComBitPosition", out),
                bit_size: s.required_int("ComBitSize", out),
                endianness: s
                    .literal(
                        "ComSignalEndianness",
                        &[
                            ("LITTLE_ENDIAN", Endianness::Little),
                            ("BIG_ENDIAN", Endianness::Big),
                        ],
                        out,
                    )
                    .unwrap_or(Endianness::Little),
                signed,
                type_bits,
                init: s.value("ComSignalInitValue", out).unwrap_or(0),
                invalid: s.value("ComSignalDataInvalidValue", out),
                transfer: s.literal(
                    "ComTransferProperty",
                    &[
                        ("PENDING", Transfer::Pending),
                        ("TRIGGERED", Transfer::Triggered),
                        ("TRIGGERED_ON_CHANGE", Transfer::TriggeredOnChange),
                        (
                            "TRIGGERED_WITHOUT_REPETITION",
                            Transfer::TriggeredWithoutRepetition,
                        ),
                        (
                            "TRIGGERED_ON_CHANGE_WITHOUT_REPETITION",
                            Transfer::TriggeredOnChangeWithoutRepetition,
                        ),
                    ],
                    out,
                ),
                update_bit: s.int("ComUpdateBitPosition", out),
            };
            if let Some(t) = s.ms("ComTimeout", out) {
                timeouts.push((signal.name.clone(), t, signal.path.clone()));
            }
            for u in ["ComHandleId", "ComSignalLength", "ComNotification"] {
                s.unused(u, notes);
            }
            s.unused("ComSystemTemplateSystemSignalRef", notes);
            com.signals.push(signal);
            s.finish(out, notes);
        }
        for i in t.subs("ComIPdu") {
            let mut i = Take::new(i);
            let send = i.literal(
                "ComIPduDirection",
                &[("SEND", true), ("RECEIVE", false)],
                out,
            );
            let pdu = i.one_ref("ComPduIdRef", "Pdu", out);
            let signals = i.refs("ComIPduSignalRef", "ComSignal", out);
            for u in [
                "ComIPduCallout",
                "ComIPduHandleId",
                "ComIPduSignalProcessing",
                "ComIPduType",
            ] {
                i.unused(u, notes);
            }
            // The ECU monitors deadlines per received I-PDU: its signals' `ComTimeout`,
            // which must agree; a sent I-PDU's are not monitored.
            let own: Vec<&(String, u64, String)> = timeouts
                .iter()
                .filter(|(n, _, _)| signals.contains(n))
                .collect();
            let deadline = own.first().map_or(0, |(_, t, _)| *t);
            if own.iter().any(|(_, t, _)| *t != deadline) {
                out.push(Error::new(
                    format!(
                        "the signals of I-PDU {} have different ComTimeout: the ECU monitors one deadline per I-PDU",
                        name_of(i.c)
                    ),
                    &[&i.c.path],
                ));
            }
            let mut tx = None;
            if let Some(x) = i.single("ComTxIPdu", out) {
                let mut x = Take::new(x);
                let mdt_ms = x.ms("ComMinimumDelayTime", out).unwrap_or(0);
                if let Some(m) = x.single("ComTxModeTrue", out) {
                    let mut m = Take::new(m);
                    if let Some(mode) = m.single("ComTxMode", out) {
                        let mut mode = Take::new(mode);
                        tx = Some(TxIPdu {
                            mode: mode
                                .literal(
                                    "ComTxModeMode",
                                    &[
                                        ("NONE", TxModeMode::None),
                                        ("PERIODIC", TxModeMode::Periodic),
                                        ("DIRECT", TxModeMode::Direct),
                                        ("MIXED", TxModeMode::Mixed),
                                    ],
                                    out,
                                )
                                .unwrap_or(TxModeMode::None),
                            period_ms: mode.ms("ComTxModeTimePeriod", out).unwrap_or(0),
                            offset_ms: mode.ms("ComTxModeTimeOffset", out).unwrap_or(0),
                            repetitions: mode.int("ComTxModeNumberOfRepetitions", out).unwrap_or(0),
                            repetition_period_ms: mode
                                .ms("ComTxModeRepetitionPeriod", out)
                                .unwrap_or(0),
                            mdt_ms,
                        });
                        mode.finish(out, notes);
                    }
                    m.finish(out, notes);
                }
                x.finish(out, notes);
            }
            let direction = match (send, tx) {
                (Some(true), Some(tx)) => {
                    if let Some((n, _, p)) = own.first() {
                        out.push(Error::new(
                            format!(
                                "signal {n} of sent I-PDU {} has a ComTimeout: the ECU monitors the deadlines of received I-PDUs only",
                                name_of(i.c)
                            ),
                            &[p, &i.c.path],
                        ));
                    }
                    Direction::Send(tx)
                }
                (Some(true), None) => {
                    out.push(Error::new(
                        format!(
                            "sent I-PDU {} has no ComTxIPdu/ComTxModeTrue/ComTxMode",
                            name_of(i.c)
                        ),
                        &[&i.c.path],
                    ));
                    i.finish(out, notes);
                    continue;
                }
                (Some(false), tx) => {
                    if tx.is_some() {
                        out.push(Error::new(
                            format!("received I-PDU {} has a ComTxIPdu", name_of(i.c)),
                            &[&i.c.path],
                        ));
                    }
                    Direction::Receive {
                        deadline_ms: deadline,
                    }
                }
                (None, _) => {
                    if i.c.params.iter().all(|p| p.def != "ComIPduDirection") {
                        out.push(Error::new(
                            format!("I-PDU {} has no ComIPduDirection", name_of(i.c)),
                            &[&i.c.path],
                        ));
                    }
                    i.finish(out, notes);
                    continue;
                }
            };
            com.ipdus.push(IPdu {
                path: i.c.path.clone(),
                name: name_of(i.c),
                pdu,
                direction,
                signals,
            });
            i.finish(out, notes);
        }
    }
    // A received signal's transfer property is read, not used: it says when a sent
    // signal's write triggers a transmission.
    for ipdu in com
        .ipdus
        .iter()
        .filter(|i| matches!(i.direction, Direction::Receive { .. }))
    {
        for signal in com
            .signals
            .iter()
            .filter(|s| s.transfer.is_some() && ipdu.signals.contains(&s.name))
        {
            notes.push(format!(
                "{}: parameter ComTransferProperty is not used: {} is received (in I-PDU {}), and the property applies to sent signals",
                signal.path, signal.name, ipdu.name
            ));
        }
    }
}

fn map_pdur(
    top: &mut [Take<'_>],
    routes: &mut Vec<Route>,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    fn path(r: &Container, routes: &mut Vec<Route>, out: &mut Vec<Error>, notes: &mut Vec<String>) {
        let mut r = Take::new(r);
        let mut src = String::new();
        if let Some(s) = r.single("PduRSrcPdu", out) {
            let mut s = Take::new(s);
            src = s.one_ref("PduRSrcPduRef", "Pdu", out);
            s.unused("PduRSourcePduHandleId", notes);
            s.finish(out, notes);
        }
        let mut dests = Vec::new();
        for d in r.subs("PduRDestPdu") {
            let mut d = Take::new(d);
            dests.push(d.one_ref("PduRDestPduRef", "Pdu", out));
            d.unused("PduRDestPduHandleId", notes);
            // Direct data provision is the only one the ECU's PduR has.
            d.literal("PduRDestPduDataProvision", &[("PDUR_DIRECT", ())], out);
            d.finish(out, notes);
        }
        if dests.is_empty() {
            out.push(Error::new(
                format!("routing path {} has no PduRDestPdu", name_of(r.c)),
                &[&r.c.path],
            ));
        }
        routes.push(Route {
            path: r.c.path.clone(),
            name: name_of(r.c),
            src,
            dests,
        });
        r.finish(out, notes);
    }
    // R4.3 and later: `PduRRoutingPaths/PduRRoutingPath`; before:
    // `PduRRoutingTables/PduRRoutingTable/PduRRoutingPath`.
    for t in top_level(top, "PduRRoutingPaths") {
        for r in t.subs("PduRRoutingPath") {
            path(r, routes, out, notes);
        }
    }
    for t in top_level(top, "PduRRoutingTables") {
        for table in t.subs("PduRRoutingTable") {
            let mut table = Take::new(table);
            for r in table.subs("PduRRoutingPath") {
                path(r, routes, out, notes);
            }
            table.finish(out, notes);
        }
    }
}

fn map_canif(
    m: &Module,
    top: &mut [Take<'_>],
    canif: &mut CanIf,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    canif.path = m.path.clone();
    for t in top_level(top, "CanIfInitCfg") {
        canif.path = t.c.path.clone();
        // Hardware objects by name, in order, per kind; the Can driver's objects and
        // controller they stand for are the board's (config::CAN_FILTERS).
        let mut hths = Vec::new();
        let mut hrhs = Vec::new();
        for h in t.subs("CanIfInitHohCfg") {
            let mut h = Take::new(h);
            for (kind, list) in [("Hth", &mut hths), ("Hrh", &mut hrhs)] {
                for x in h.subs(&format!("CanIf{kind}Cfg")) {
                    let mut x = Take::new(x);
                    x.unused(&format!("CanIf{kind}CanCtrlIdRef"), notes);
                    x.unused(&format!("CanIf{kind}IdSymRef"), notes);
                    list.push(name_of(x.c));
                    x.finish(out, notes);
                }
            }
            h.finish(out, notes);
        }
        // Transmit buffers, each on one HTH.
        let mut buffers: Vec<(String, usize)> = Vec::new();
        for b in t.subs("CanIfBufferCfg") {
            let mut b = Take::new(b);
            let hth = b.one_ref("CanIfBufferHthRef", "CanIfHthCfg", out);
            if b.int("CanIfBufferSize", out) == Some(0) {
                out.push(Error::new(
                    "CanIfBufferSize 0: the ECU's CanIf buffers one PDU per transmit PDU",
                    &[&b.c.path],
                ));
            }
            if let Some(k) = hths.iter().position(|h| *h == hth) {
                buffers.push((name_of(b.c), k));
            }
            b.finish(out, notes);
        }
        let id_type = |x: &mut Take<'_>, def: &str, out: &mut Vec<Error>| {
            x.literal(
                def,
                &[
                    ("STANDARD_CAN", false),
                    ("EXTENDED_CAN", true),
                    ("STANDARD_NO_FD_CAN", false),
                    ("EXTENDED_NO_FD_CAN", true),
                ],
                out,
            )
            .unwrap_or(false)
        };
        // The DLC, as R4.3 names it or as earlier releases did.
        let dlc = |x: &mut Take<'_>, kind: &str, out: &mut Vec<Error>| {
            let long = format!("CanIf{kind}PduDataLength");
            let short = format!("CanIf{kind}PduDlc");
            x.int(&long, out).or_else(|| x.int(&short, out))
        };
        for x in t.subs("CanIfTxPduCfg") {
            let mut x = Take::new(x);
            let buffer = x.one_ref("CanIfTxPduBufferRef", "CanIfBufferCfg", out);
            let hth = match buffers.iter().find(|(b, _)| *b == buffer) {
                Some((_, k)) => *k as u64,
                None => {
                    out.push(Error::new(
                        format!(
                            "CanIfTxPduBufferRef points to {buffer}, which is on no HTH of CanIf"
                        ),
                        &[&x.c.path],
                    ));
                    0
                }
            };
            for u in [
                "CanIfTxPduType",
                "CanIfTxPduUserTxConfirmationUL",
                "CanIfTxPduId",
                "CanIfTxPduUserTxConfirmationName",
                "CanIfTxPduReadNotifyStatus",
            ] {
                x.unused(u, notes);
            }
            let lpdu = LPdu {
                path: x.c.path.clone(),
                name: name_of(x.c),
                can_id: x.required_int("CanIfTxPduCanId", out),
                extended: id_type(&mut x, "CanIfTxPduCanIdType", out),
                dlc: dlc(&mut x, "Tx", out),
                pdu: x.one_ref("CanIfTxPduRef", "Pdu", out),
                hoh: hth,
            };
            canif.tx.push(lpdu);
            x.finish(out, notes);
        }
        for x in t.subs("CanIfRxPduCfg") {
            let mut x = Take::new(x);
            if !x
                .c
                .params
                .iter()
                .any(|p| p.def == "CanIfRxPduDataLength" || p.def == "CanIfRxPduDlc")
            {
                out.push(Error::new(
                    format!("CanIf RX PDU {} has no CanIfRxPduDataLength", name_of(x.c)),
                    &[&x.c.path],
                ));
            }
            let hrh_name = x.one_ref("CanIfRxPduHrhIdRef", "CanIfHrhCfg", out);
            let hrh = match hrhs.iter().position(|h| *h == hrh_name) {
                Some(k) => k as u64,
                None => {
                    out.push(Error::new(
                        format!("CanIfRxPduHrhIdRef points to {hrh_name}, which is not in CanIfInitHohCfg"),
                        &[&x.c.path],
                    ));
                    0
                }
            };
            for u in [
                "CanIfRxPduUserRxIndicationUL",
                "CanIfRxPduId",
                "CanIfRxPduUserRxIndicationName",
                "CanIfRxPduReadNotifyStatus",
                "CanIfRxPduReadData",
                "CanIfRxPduDlcCheck",
            ] {
                x.unused(u, notes);
            }
            let lpdu = LPdu {
                path: x.c.path.clone(),
                name: name_of(x.c),
                can_id: x.required_int("CanIfRxPduCanId", out),
                extended: id_type(&mut x, "CanIfRxPduCanIdType", out),
                dlc: dlc(&mut x, "Rx", out),
                pdu: x.one_ref("CanIfRxPduRef", "Pdu", out),
                hoh: hrh,
            };
            canif.rx.push(lpdu);
            x.finish(out, notes);
        }
    }
}

fn map_can(
    top: &mut [Take<'_>],
    can: &mut CanController,
    out: &mut Vec<Error>,
    notes: &mut Vec<String>,
) {
    for t in top_level(top, "CanConfigSet") {
        let controllers = t.subs("CanController");
        if controllers.len() != 1 {
            out.push(Error::new(
                format!("{} CAN controllers: the ECU has one", controllers.len()),
                &[&t.c.path],
            ));
        }
        for c in controllers {
            let mut c = Take::new(c);
            can.path = c.c.path.clone();
            can.name = name_of(c.c);
            for u in [
                "CanControllerId",
                "CanCpuClockRef",
                "CanControllerDefaultBaudrate",
            ] {
                c.unused(u, notes);
            }
            // The driver derives its time quanta from the bit rate and the sample point.
            if let Some(b) = c.single("CanControllerBaudrateConfig", out) {
                let mut b = Take::new(b);
                can.baud_kbps = b.required_int("CanControllerBaudRate", out);
                can.prop_seg = b.required_int("CanControllerPropSeg", out);
                can.seg1 = b.required_int("CanControllerSeg1", out);
                can.seg2 = b.required_int("CanControllerSeg2", out);
                b.unused("CanControllerSyncJumpWidth", notes);
                b.unused("CanControllerBaudRateConfigID", notes);
                b.finish(out, notes);
            }
            c.finish(out, notes);
        }
        // The board's message buffers are its own (config::CAN_FILTERS).
        for h in t.subs("CanHardwareObject") {
            let mut h = Take::new(h);
            for p in [
                "CanObjectType",
                "CanIdType",
                "CanHandleType",
                "CanObjectId",
                "CanIdValue",
                "CanControllerRef",
            ] {
                h.unused(p, notes);
            }
            h.finish(out, notes);
        }
    }
}

/// Writes the model as ARXML (AUTOSAR [`VERSION`]): one package `/{package}/EcucValues`
/// with one `ECUC-MODULE-CONFIGURATION-VALUES` per module, against the standard
/// definitions ([`STANDARD_DEFS`]).
///
/// # Errors
/// The model holds what the schema refuses (a name that is not an identifier), or a
/// reference to an item it does not have.
pub fn write(ecu: &Ecu, package: &str) -> Result<String, Error> {
    let fail = |e: autosar_data::AutosarDataError| Error::new(e.to_string(), &[package]);
    let model = AutosarModel::new();
    let file = model.create_file("ecu.arxml", VERSION).map_err(fail)?;
    let w = Writer { model: &model };
    w.build(ecu, package).map_err(|e| match e {
        WriteError::Arxml(e) => fail(e),
        WriteError::Model(e) => e,
    })?;
    file.serialize().map_err(fail)
}

enum WriteError {
    Arxml(autosar_data::AutosarDataError),
    Model(Error),
}

impl From<autosar_data::AutosarDataError> for WriteError {
    fn from(e: autosar_data::AutosarDataError) -> Self {
        Self::Arxml(e)
    }
}

struct Writer<'m> {
    model: &'m AutosarModel,
}

/// A parameter's kind, for its value element and its definition's DEST.
#[derive(Clone, Copy)]
enum Kind {
    Int,
    Bool,
    Enum,
    Float,
    Text,
}

impl Writer<'_> {
    fn def_ref(e: &Element, dest: &str, path: &str) -> Result<(), WriteError> {
        let r = e.get_or_create_sub_element(ElementName::DefinitionRef)?;
        r.set_attribute_string(AttributeName::Dest, dest)?;
        r.set_character_data(path)?;
        Ok(())
    }

    fn container(
        parent: &Element,
        name: &str,
        def: &str,
        sub: bool,
    ) -> Result<Element, WriteError> {
        let list = parent.get_or_create_sub_element(if sub {
            ElementName::SubContainers
        } else {
            ElementName::Containers
        })?;
        let c = list.create_named_sub_element(ElementName::EcucContainerValue, name)?;
        Self::def_ref(&c, "ECUC-PARAM-CONF-CONTAINER-DEF", def)?;
        Ok(c)
    }

    /// A task's or ISR's (`kind`) timing protection, under `c` of definition `d`.
    fn timing(c: &Element, d: &str, kind: &str, timing: Option<&Timing>) -> Result<(), WriteError> {
        let Some(timing) = timing else {
            return Ok(());
        };
        let def = format!("{d}/Os{kind}TimingProtection");
        // The container's own short name, as it was read.
        let name = timing
            .path
            .rsplit('/')
            .next()
            .filter(|n| !n.is_empty())
            .map_or_else(|| format!("Os{kind}TimingProtection"), str::to_string);
        let t = Self::container(c, &name, &def, true)?;
        for (param, us) in [
            ("ExecutionBudget", timing.budget_us),
            ("TimeFrame", timing.time_frame_us),
        ] {
            if let Some(us) = us {
                Self::param(
                    &t,
                    &format!("{def}/Os{kind}{param}"),
                    Kind::Float,
                    &format!("{}", us as f64 / 1e6),
                )?;
            }
        }
        Ok(())
    }

    fn param(c: &Element, def: &str, kind: Kind, value: &str) -> Result<(), WriteError> {
        let list = c.get_or_create_sub_element(ElementName::ParameterValues)?;
        let (element, dest) = match kind {
            Kind::Int => (
                ElementName::EcucNumericalParamValue,
                "ECUC-INTEGER-PARAM-DEF",
            ),
            Kind::Bool => (
                ElementName::EcucNumericalParamValue,
                "ECUC-BOOLEAN-PARAM-DEF",
            ),
            Kind::Float => (ElementName::EcucNumericalParamValue, "ECUC-FLOAT-PARAM-DEF"),
            Kind::Enum => (
                ElementName::EcucTextualParamValue,
                "ECUC-ENUMERATION-PARAM-DEF",
            ),
            Kind::Text => (ElementName::EcucTextualParamValue, "ECUC-STRING-PARAM-DEF"),
        };
        let p = list.create_sub_element(element)?;
        Self::def_ref(&p, dest, def)?;
        p.create_sub_element(ElementName::Value)?
            .set_character_data(value)?;
        Ok(())
    }

    fn reference(c: &Element, def: &str, target: &Element) -> Result<(), WriteError> {
        let list = c.get_or_create_sub_element(ElementName::ReferenceValues)?;
        let r = list.create_sub_element(ElementName::EcucReferenceValue)?;
        Self::def_ref(&r, "ECUC-REFERENCE-DEF", def)?;
        r.create_sub_element(ElementName::ValueRef)?
            .set_reference_target(target)?;
        Ok(())
    }

    fn seconds(ms: u64) -> String {
        format!("{}", ms as f64 / 1000.0)
    }

    fn build(&self, ecu: &Ecu, package: &str) -> Result<(), WriteError> {
        let pkgs = self
            .model
            .root_element()
            .get_or_create_sub_element(ElementName::ArPackages)?;
        let elements = pkgs
            .create_named_sub_element(ElementName::ArPackage, package)?
            .create_sub_element(ElementName::ArPackages)?
            .create_named_sub_element(ElementName::ArPackage, "EcucValues")?
            .create_sub_element(ElementName::Elements)?;
        let module = |name: &str| -> Result<(Element, String), WriteError> {
            let m = elements
                .create_named_sub_element(ElementName::EcucModuleConfigurationValues, name)?;
            let def = format!("{STANDARD_DEFS}/{name}");
            Self::def_ref(&m, "ECUC-MODULE-DEF", &def)?;
            m.create_sub_element(ElementName::ImplementationConfigVariant)?
                .set_character_data(EnumItem::VariantPreCompile)?;
            Ok((m, def))
        };
        let missing = |what: &str, name: &str, at: &str| {
            WriteError::Model(Error::new(format!("{what} {name} does not exist"), &[at]))
        };
        let find = |list: &[(String, Element)], name: &str| {
            list.iter().find(|(n, _)| n == name).map(|(_, e)| e.clone())
        };

        // EcuC: the global PDUs.
        let (ecuc, def) = module("EcuC")?;
        let set = Self::container(
            &ecuc,
            "EcucConfigSet",
            &format!("{def}/EcucConfigSet"),
            false,
        )?;
        let d = format!("{def}/EcucConfigSet/EcucPduCollection");
        let coll = Self::container(&set, "EcucPduCollection", &d, true)?;
        let mut pdus = Vec::new();
        for p in &ecu.pdus {
            let c = Self::container(&coll, &p.name, &format!("{d}/Pdu"), true)?;
            Self::param(
                &c,
                &format!("{d}/Pdu/PduLength"),
                Kind::Int,
                &p.length.to_string(),
            )?;
            pdus.push((p.name.clone(), c));
        }

        // Os.
        let os = &ecu.os;
        let (m, def) = module("Os")?;
        let mut resources = Vec::new();
        for r in &os.resources {
            let c = Self::container(&m, &r.name, &format!("{def}/OsResource"), false)?;
            Self::param(
                &c,
                &format!("{def}/OsResource/OsResourceProperty"),
                Kind::Enum,
                "STANDARD",
            )?;
            resources.push((r.name.clone(), c));
        }
        let mut events = Vec::new();
        for e in &os.events {
            let c = Self::container(&m, &e.name, &format!("{def}/OsEvent"), false)?;
            Self::param(
                &c,
                &format!("{def}/OsEvent/OsEventMask"),
                Kind::Int,
                &format!("{:#x}", e.mask),
            )?;
            events.push((e.name.clone(), c));
        }
        let app_mode = Self::container(&m, "OSDEFAULTAPPMODE", &format!("{def}/OsAppMode"), false)?;
        let mut tasks = Vec::new();
        for t in &os.tasks {
            let c = Self::container(&m, &t.name, &format!("{def}/OsTask"), false)?;
            let d = format!("{def}/OsTask");
            Self::param(
                &c,
                &format!("{d}/OsTaskActivation"),
                Kind::Int,
                &t.activations.to_string(),
            )?;
            Self::param(
                &c,
                &format!("{d}/OsTaskPriority"),
                Kind::Int,
                &t.priority.to_string(),
            )?;
            Self::param(
                &c,
                &format!("{d}/OsTaskSchedule"),
                Kind::Enum,
                if t.preemptive { "FULL" } else { "NON" },
            )?;
            for r in &t.resources {
                let target = find(&resources, r).ok_or_else(|| missing("resource", r, &t.path))?;
                Self::reference(&c, &format!("{d}/OsTaskResourceRef"), &target)?;
            }
            for e in &t.events {
                let target = find(&events, e).ok_or_else(|| missing("event", e, &t.path))?;
                Self::reference(&c, &format!("{d}/OsTaskEventRef"), &target)?;
            }
            if t.autostart {
                let a =
                    Self::container(&c, "OsTaskAutostart", &format!("{d}/OsTaskAutostart"), true)?;
                Self::reference(
                    &a,
                    &format!("{d}/OsTaskAutostart/OsTaskAppModeRef"),
                    &app_mode,
                )?;
            }
            Self::timing(&c, &d, "Task", t.timing.as_ref())?;
            tasks.push((t.name.clone(), c));
        }
        let mut counters = Vec::new();
        for k in &os.counters {
            let c = Self::container(&m, &k.name, &format!("{def}/OsCounter"), false)?;
            let d = format!("{def}/OsCounter");
            Self::param(
                &c,
                &format!("{d}/OsCounterMaxAllowedValue"),
                Kind::Int,
                &format!("{:#x}", k.max_allowed_value),
            )?;
            Self::param(
                &c,
                &format!("{d}/OsCounterMinCycle"),
                Kind::Int,
                &k.min_cycle.to_string(),
            )?;
            Self::param(
                &c,
                &format!("{d}/OsCounterTicksPerBase"),
                Kind::Int,
                &k.ticks_per_base.to_string(),
            )?;
            Self::param(&c, &format!("{d}/OsCounterType"), Kind::Enum, "HARDWARE")?;
            counters.push((k.name.clone(), c));
        }
        for a in &os.alarms {
            let c = Self::container(&m, &a.name, &format!("{def}/OsAlarm"), false)?;
            let d = format!("{def}/OsAlarm");
            let counter = find(&counters, &a.counter)
                .ok_or_else(|| missing("counter", &a.counter, &a.path))?;
            Self::reference(&c, &format!("{d}/OsAlarmCounterRef"), &counter)?;
            let action = Self::container(&c, "OsAlarmAction", &format!("{d}/OsAlarmAction"), true)?;
            Self::def_ref(
                &action,
                "ECUC-CHOICE-CONTAINER-DEF",
                &format!("{d}/OsAlarmAction"),
            )?;
            match &a.action {
                AlarmAction::ActivateTask(t) => {
                    let x = Self::container(
                        &action,
                        "OsAlarmActivateTask",
                        &format!("{d}/OsAlarmAction/OsAlarmActivateTask"),
                        true,
                    )?;
                    let task = find(&tasks, t).ok_or_else(|| missing("task", t, &a.path))?;
                    Self::reference(
                        &x,
                        &format!("{d}/OsAlarmAction/OsAlarmActivateTask/OsAlarmActivateTaskRef"),
                        &task,
                    )?;
                }
                AlarmAction::SetEvent(t, e) => {
                    let x = Self::container(
                        &action,
                        "OsAlarmSetEvent",
                        &format!("{d}/OsAlarmAction/OsAlarmSetEvent"),
                        true,
                    )?;
                    let event = find(&events, e).ok_or_else(|| missing("event", e, &a.path))?;
                    let task = find(&tasks, t).ok_or_else(|| missing("task", t, &a.path))?;
                    Self::reference(
                        &x,
                        &format!("{d}/OsAlarmAction/OsAlarmSetEvent/OsAlarmSetEventRef"),
                        &event,
                    )?;
                    Self::reference(
                        &x,
                        &format!("{d}/OsAlarmAction/OsAlarmSetEvent/OsAlarmSetEventTaskRef"),
                        &task,
                    )?;
                }
            }
            if let Some((start, cycle)) = a.autostart {
                let x = Self::container(
                    &c,
                    "OsAlarmAutostart",
                    &format!("{d}/OsAlarmAutostart"),
                    true,
                )?;
                Self::param(
                    &x,
                    &format!("{d}/OsAlarmAutostart/OsAlarmAlarmTime"),
                    Kind::Int,
                    &start.to_string(),
                )?;
                Self::param(
                    &x,
                    &format!("{d}/OsAlarmAutostart/OsAlarmAutostartType"),
                    Kind::Enum,
                    "RELATIVE",
                )?;
                Self::param(
                    &x,
                    &format!("{d}/OsAlarmAutostart/OsAlarmCycleTime"),
                    Kind::Int,
                    &cycle.to_string(),
                )?;
                Self::reference(
                    &x,
                    &format!("{d}/OsAlarmAutostart/OsAlarmAppModeRef"),
                    &app_mode,
                )?;
            }
        }
        for i in &os.isrs {
            let c = Self::container(&m, &i.name, &format!("{def}/OsIsr"), false)?;
            let d = format!("{def}/OsIsr");
            Self::param(
                &c,
                &format!("{d}/OsIsrCategory"),
                Kind::Enum,
                if i.category == 1 {
                    "CATEGORY_1"
                } else {
                    "CATEGORY_2"
                },
            )?;
            Self::param(
                &c,
                &format!("{d}/OsIsrInterruptPriority"),
                Kind::Int,
                &i.priority.to_string(),
            )?;
            for r in &i.resources {
                let target = find(&resources, r).ok_or_else(|| missing("resource", r, &i.path))?;
                Self::reference(&c, &format!("{d}/OsIsrResourceRef"), &target)?;
            }
            Self::timing(&c, &d, "Isr", i.timing.as_ref())?;
        }
        let osos = Self::container(&m, "OsOS", &format!("{def}/OsOS"), false)?;
        Self::param(
            &osos,
            &format!("{def}/OsOS/OsStatus"),
            Kind::Enum,
            match os.status {
                Status::Standard => "STANDARD",
                Status::Extended => "EXTENDED",
            },
        )?;
        let hooks = Self::container(&osos, "OsHooks", &format!("{def}/OsOS/OsHooks"), true)?;
        let h = os.hooks;
        for (name, on) in [
            ("OsErrorHook", h.error),
            ("OsPostTaskHook", h.post_task),
            ("OsPreTaskHook", h.pre_task),
            ("OsShutdownHook", h.shutdown),
            ("OsStartupHook", h.startup),
        ] {
            Self::param(
                &hooks,
                &format!("{def}/OsOS/OsHooks/{name}"),
                Kind::Bool,
                if on { "true" } else { "false" },
            )?;
        }

        // Com.
        let com = &ecu.com;
        let (m, def) = module("Com")?;
        let cfg = Self::container(&m, "ComConfig", &format!("{def}/ComConfig"), false)?;
        let d = format!("{def}/ComConfig");
        let tb = Self::container(&cfg, "ComTimeBase", &format!("{d}/ComTimeBase"), true)?;
        Self::param(
            &tb,
            &format!("{d}/ComTimeBase/ComRxTimeBase"),
            Kind::Float,
            &Self::seconds(com.main_period_ms),
        )?;
        Self::param(
            &tb,
            &format!("{d}/ComTimeBase/ComTxTimeBase"),
            Kind::Float,
            &Self::seconds(com.main_period_ms),
        )?;
        let mut signals = Vec::new();
        for s in &com.signals {
            let c = Self::container(&cfg, &s.name, &format!("{d}/ComSignal"), true)?;
            let sd = format!("{d}/ComSignal");
            Self::param(
                &c,
                &format!("{sd}/ComBitPosition"),
                Kind::Int,
                &s.bit_position.to_string(),
            )?;
            Self::param(
                &c,
                &format!("{sd}/ComBitSize"),
                Kind::Int,
                &s.bit_size.to_string(),
            )?;
            if let Some(v) = s.invalid {
                Self::param(
                    &c,
                    &format!("{sd}/ComSignalDataInvalidValue"),
                    Kind::Text,
                    &v.to_string(),
                )?;
            }
            Self::param(
                &c,
                &format!("{sd}/ComSignalEndianness"),
                Kind::Enum,
                match s.endianness {
                    Endianness::Little => "LITTLE_ENDIAN",
                    Endianness::Big => "BIG_ENDIAN",
                },
            )?;
            Self::param(
                &c,
                &format!("{sd}/ComSignalInitValue"),
                Kind::Text,
                &s.init.to_string(),
            )?;
            let signal_type = match (s.type_bits, s.signed) {
                (1, _) => "BOOLEAN".to_string(),
                (width, signed) => format!("{}INT{width}", if signed { "S" } else { "U" }),
            };
            Self::param(&c, &format!("{sd}/ComSignalType"), Kind::Enum, &signal_type)?;
            if let Some(transfer) = s.transfer {
                Self::param(
                    &c,
                    &format!("{sd}/ComTransferProperty"),
                    Kind::Enum,
                    match transfer {
                        Transfer::Pending => "PENDING",
                        Transfer::Triggered => "TRIGGERED",
                        Transfer::TriggeredOnChange => "TRIGGERED_ON_CHANGE",
                        Transfer::TriggeredWithoutRepetition => "TRIGGERED_WITHOUT_REPETITION",
                        Transfer::TriggeredOnChangeWithoutRepetition => {
                            "TRIGGERED_ON_CHANGE_WITHOUT_REPETITION"
                        }
                    },
                )?;
            }
            let deadline = com.ipdus.iter().find_map(|i| match i.direction {
                Direction::Receive { deadline_ms }
                    if deadline_ms > 0 && i.signals.contains(&s.name) =>
                {
                    Some(deadline_ms)
                }
                _ => None,
            });
            if let Some(ms) = deadline {
                Self::param(
                    &c,
                    &format!("{sd}/ComTimeout"),
                    Kind::Float,
                    &Self::seconds(ms),
                )?;
            }
            if let Some(u) = s.update_bit {
                Self::param(
                    &c,
                    &format!("{sd}/ComUpdateBitPosition"),
                    Kind::Int,
                    &u.to_string(),
                )?;
            }
            signals.push((s.name.clone(), c));
        }
        for i in &com.ipdus {
            let c = Self::container(&cfg, &i.name, &format!("{d}/ComIPdu"), true)?;
            let id = format!("{d}/ComIPdu");
            let sending = matches!(i.direction, Direction::Send(_));
            Self::param(
                &c,
                &format!("{id}/ComIPduDirection"),
                Kind::Enum,
                if sending { "SEND" } else { "RECEIVE" },
            )?;
            let pdu = find(&pdus, &i.pdu).ok_or_else(|| missing("PDU", &i.pdu, &i.path))?;
            Self::reference(&c, &format!("{id}/ComPduIdRef"), &pdu)?;
            for s in &i.signals {
                let target = find(&signals, s).ok_or_else(|| missing("signal", s, &i.path))?;
                Self::reference(&c, &format!("{id}/ComIPduSignalRef"), &target)?;
            }
            if let Direction::Send(tx) = &i.direction {
                let x = Self::container(&c, "ComTxIPdu", &format!("{id}/ComTxIPdu"), true)?;
                let xd = format!("{id}/ComTxIPdu");
                Self::param(
                    &x,
                    &format!("{xd}/ComMinimumDelayTime"),
                    Kind::Float,
                    &Self::seconds(tx.mdt_ms),
                )?;
                let t = Self::container(&x, "ComTxModeTrue", &format!("{xd}/ComTxModeTrue"), true)?;
                let mode = Self::container(
                    &t,
                    "ComTxMode",
                    &format!("{xd}/ComTxModeTrue/ComTxMode"),
                    true,
                )?;
                let md = format!("{xd}/ComTxModeTrue/ComTxMode");
                Self::param(
                    &mode,
                    &format!("{md}/ComTxModeMode"),
                    Kind::Enum,
                    match tx.mode {
                        TxModeMode::None => "NONE",
                        TxModeMode::Periodic => "PERIODIC",
                        TxModeMode::Direct => "DIRECT",
                        TxModeMode::Mixed => "MIXED",
                    },
                )?;
                Self::param(
                    &mode,
                    &format!("{md}/ComTxModeNumberOfRepetitions"),
                    Kind::Int,
                    &tx.repetitions.to_string(),
                )?;
                Self::param(
                    &mode,
                    &format!("{md}/ComTxModeRepetitionPeriod"),
                    Kind::Float,
                    &Self::seconds(tx.repetition_period_ms),
                )?;
                Self::param(
                    &mode,
                    &format!("{md}/ComTxModeTimeOffset"),
                    Kind::Float,
                    &Self::seconds(tx.offset_ms),
                )?;
                Self::param(
                    &mode,
                    &format!("{md}/ComTxModeTimePeriod"),
                    Kind::Float,
                    &Self::seconds(tx.period_ms),
                )?;
            }
        }

        // PduR.
        let (m, def) = module("PduR")?;
        let paths = Self::container(
            &m,
            "PduRRoutingPaths",
            &format!("{def}/PduRRoutingPaths"),
            false,
        )?;
        let d = format!("{def}/PduRRoutingPaths/PduRRoutingPath");
        for r in &ecu.routes {
            let c = Self::container(&paths, &r.name, &d, true)?;
            let src = Self::container(
                &c,
                &format!("{}_Src", r.name),
                &format!("{d}/PduRSrcPdu"),
                true,
            )?;
            let target = find(&pdus, &r.src).ok_or_else(|| missing("PDU", &r.src, &r.path))?;
            Self::reference(&src, &format!("{d}/PduRSrcPdu/PduRSrcPduRef"), &target)?;
            for (k, dest_pdu) in r.dests.iter().enumerate() {
                let name = match k {
                    0 => format!("{}_Dest", r.name),
                    k => format!("{}_Dest{k}", r.name),
                };
                let dest = Self::container(&c, &name, &format!("{d}/PduRDestPdu"), true)?;
                let target =
                    find(&pdus, dest_pdu).ok_or_else(|| missing("PDU", dest_pdu, &r.path))?;
                Self::reference(&dest, &format!("{d}/PduRDestPdu/PduRDestPduRef"), &target)?;
            }
        }

        // Can: the controller, then CanIf, whose hardware objects refer to it.
        let can = &ecu.can;
        let (m, def) = module("Can")?;
        let set = Self::container(&m, "CanConfigSet", &format!("{def}/CanConfigSet"), false)?;
        let d = format!("{def}/CanConfigSet/CanController");
        let ctrl = Self::container(&set, &can.name, &d, true)?;
        let rate = Self::container(
            &ctrl,
            "CanControllerBaudrateConfig",
            &format!("{d}/CanControllerBaudrateConfig"),
            true,
        )?;
        let rd = format!("{d}/CanControllerBaudrateConfig");
        Self::param(
            &rate,
            &format!("{rd}/CanControllerBaudRate"),
            Kind::Int,
            &can.baud_kbps.to_string(),
        )?;
        Self::param(
            &rate,
            &format!("{rd}/CanControllerPropSeg"),
            Kind::Int,
            &can.prop_seg.to_string(),
        )?;
        Self::param(
            &rate,
            &format!("{rd}/CanControllerSeg1"),
            Kind::Int,
            &can.seg1.to_string(),
        )?;
        Self::param(
            &rate,
            &format!("{rd}/CanControllerSeg2"),
            Kind::Int,
            &can.seg2.to_string(),
        )?;

        let canif = &ecu.canif;
        let (m, def) = module("CanIf")?;
        let init = Self::container(&m, "CanIfInitCfg", &format!("{def}/CanIfInitCfg"), false)?;
        let d = format!("{def}/CanIfInitCfg");
        let hoh = Self::container(
            &init,
            "CanIfInitHohCfg",
            &format!("{d}/CanIfInitHohCfg"),
            true,
        )?;
        let count = |list: &[LPdu]| list.iter().map(|l| l.hoh + 1).max().unwrap_or(0);
        let mut hths = Vec::new();
        for k in 0..count(&canif.tx) {
            hths.push(Self::container(
                &hoh,
                &format!("Hth{k}"),
                &format!("{d}/CanIfInitHohCfg/CanIfHthCfg"),
                true,
            )?);
        }
        let mut hrhs = Vec::new();
        for k in 0..count(&canif.rx) {
            hrhs.push(Self::container(
                &hoh,
                &format!("Hrh{k}"),
                &format!("{d}/CanIfInitHohCfg/CanIfHrhCfg"),
                true,
            )?);
        }
        // One transmit buffer per HTH.
        let mut buffers = Vec::new();
        for (k, hth) in hths.iter().enumerate() {
            let b = Self::container(
                &init,
                &format!("Buffer{k}"),
                &format!("{d}/CanIfBufferCfg"),
                true,
            )?;
            Self::param(
                &b,
                &format!("{d}/CanIfBufferCfg/CanIfBufferSize"),
                Kind::Int,
                "1",
            )?;
            Self::reference(&b, &format!("{d}/CanIfBufferCfg/CanIfBufferHthRef"), hth)?;
            buffers.push(b);
        }
        for (kind, list, hohs) in [("Tx", &canif.tx, &buffers), ("Rx", &canif.rx, &hrhs)] {
            let cd = format!("{d}/CanIf{kind}PduCfg");
            for l in list {
                let c = Self::container(&init, &l.name, &cd, true)?;
                Self::param(
                    &c,
                    &format!("{cd}/CanIf{kind}PduCanId"),
                    Kind::Int,
                    &format!("{:#x}", l.can_id),
                )?;
                Self::param(
                    &c,
                    &format!("{cd}/CanIf{kind}PduCanIdType"),
                    Kind::Enum,
                    if l.extended {
                        "EXTENDED_CAN"
                    } else {
                        "STANDARD_CAN"
                    },
                )?;
                if let Some(dlc) = l.dlc {
                    let name = if kind == "Tx" {
                        "CanIfTxPduDlc"
                    } else {
                        "CanIfRxPduDataLength"
                    };
                    Self::param(&c, &format!("{cd}/{name}"), Kind::Int, &dlc.to_string())?;
                }
                let target = find(&pdus, &l.pdu).ok_or_else(|| missing("PDU", &l.pdu, &l.path))?;
                Self::reference(&c, &format!("{cd}/CanIf{kind}PduRef"), &target)?;
                let hoh = usize::try_from(l.hoh)
                    .ok()
                    .and_then(|k| hohs.get(k))
                    .ok_or_else(|| missing("hardware object", &l.hoh.to_string(), &l.path))?;
                let def = if kind == "Tx" {
                    format!("{cd}/CanIfTxPduBufferRef")
                } else {
                    format!("{cd}/CanIfRxPduHrhIdRef")
                };
                Self::reference(&c, &def, hoh)?;
            }
        }
        Ok(())
    }
}
