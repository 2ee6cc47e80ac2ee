//! The checks made before anything is generated. Each error names the ARXML path of every
//! item involved, so that a user finds both ends of a bad reference or both signals that
//! overlap; all errors are reported at once, not only the first.

use std::collections::HashMap;
use std::fmt;

use crate::model::{AlarmAction, Direction, Ecu, Endianness, Signal, TxModeMode};

/// One thing wrong with the description.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    /// What is wrong, in words.
    pub what: String,
    /// The ARXML paths of the items involved, first the one that is wrong.
    pub paths: Vec<String>,
}

impl Error {
    /// An error about the items at `paths`.
    pub fn new(what: impl Into<String>, paths: &[&str]) -> Self {
        Self {
            what: what.into(),
            paths: paths.iter().map(|p| (*p).to_string()).collect(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.what)?;
        for (i, p) in self.paths.iter().enumerate() {
            f.write_str(if i == 0 { "\n  at " } else { "\n  and " })?;
            f.write_str(p)?;
        }
        Ok(())
    }
}

impl std::error::Error for Error {}

/// The largest priority a task may have (the kernel's `MAX_PRIORITY`).
pub const MAX_TASK_PRIORITY: u64 = cw_core::os::MAX_PRIORITY as u64;
/// The interrupt priorities the Cortex-M port expresses, in OSEK's order (a higher number
/// is more urgent): `cw_bsp::cortex_m::ISR_PRIORITIES`, three NVIC priority bits less the
/// faults' level and PendSV's.
pub const ISR_PRIORITIES: std::ops::RangeInclusive<u64> = 1..=6;
/// The CAN bit rates the controller takes, kbit/s.
pub const BAUD_KBPS: std::ops::RangeInclusive<u64> = 1..=1000;
/// Time quanta in one CAN bit (ISO 11898-1: 8 to 25).
pub const BIT_QUANTA: std::ops::RangeInclusive<u64> = 8..=25;
/// The largest Com I-PDU or CAN frame the ECU handles (classic CAN).
pub const MAX_PDU_LENGTH: u64 = 8;

/// Finds an item by name in `items`, with its index.
pub(crate) fn find<'a, T>(
    items: &'a [T],
    name: &str,
    name_of: impl Fn(&T) -> &str,
) -> Option<(usize, &'a T)> {
    items.iter().enumerate().find(|(_, t)| name_of(t) == name)
}

/// Two items of one kind with one name.
fn duplicates<T>(
    out: &mut Vec<Error>,
    kind: &str,
    items: &[T],
    name_of: impl Fn(&T) -> (&str, &str),
) {
    let mut seen: HashMap<&str, &str> = HashMap::new();
    for item in items {
        let (name, path) = name_of(item);
        if let Some(first) = seen.insert(name, path) {
            out.push(Error::new(
                format!("two {kind}s are named {name}"),
                &[path, first],
            ));
        }
    }
}

/// The PDU bits (`byte * 8 + bit`) a Com signal of `bit_size` bits at `bit_position`
/// occupies, from its most significant bit, or `None` if it does not fit `length` bytes
/// (1 to 64 bytes, 1 to 64 bits, as Com takes them). Little endian: the position is
/// the least significant bit and the signal grows to higher bits; big endian: the position
/// is the most significant bit (AUTOSAR's and the DBC's "sawtooth" numbering) and the
/// signal grows towards the next byte's lower bits.
pub fn signal_bits(
    bit_position: u64,
    bit_size: u64,
    endianness: Endianness,
    length: u64,
) -> Option<Vec<u64>> {
    // Com's own arithmetic (`cw_core::com::signal::spec`), which the core's codec is proved
    // against: a layout the generator accepts is one the core's `SignalLayout` takes.
    use cw_core::com::signal::{spec, ByteOrder};
    let order = match endianness {
        Endianness::Little => ByteOrder::Intel,
        Endianness::Big => ByteOrder::Motorola,
    };
    let start = u16::try_from(bit_position).ok()?;
    let size = u8::try_from(bit_size).ok()?;
    let pdu_len = usize::try_from(length).ok()?;
    if !spec::layout_fits(pdu_len, start, size, order) {
        return None;
    }
    Some(
        (0..size)
            .rev()
            .map(|i| spec::bit_position(start, size, order, i) as u64)
            .collect(),
    )
}

/// Every check; empty when the description can be generated.
pub fn check(ecu: &Ecu) -> Vec<Error> {
    let mut out = Vec::new();
    check_os(ecu, &mut out);
    check_com(ecu, &mut out);
    check_routes_and_canif(ecu, &mut out);
    check_can(ecu, &mut out);
    check_constants(ecu, &mut out);
    out
}

/// The CAN controller's bit rate and segments.
fn check_can(ecu: &Ecu, out: &mut Vec<Error>) {
    let c = &ecu.can;
    if !BAUD_KBPS.contains(&c.baud_kbps) {
        out.push(Error::new(
            format!(
                "CAN controller {} at {} kbit/s: {}..={} can be configured",
                c.name,
                c.baud_kbps,
                BAUD_KBPS.start(),
                BAUD_KBPS.end()
            ),
            &[&c.path],
        ));
    }
    let quanta = c
        .prop_seg
        .checked_add(c.seg1)
        .and_then(|q| q.checked_add(c.seg2))
        .and_then(|q| q.checked_add(1));
    if c.prop_seg == 0
        || c.seg1 == 0
        || c.seg2 == 0
        || !quanta.is_some_and(|q| BIT_QUANTA.contains(&q))
    {
        out.push(Error::new(
            format!(
                "CAN controller {}: segments {}+{}+{} tq and the synchronisation quantum: each segment at least 1, the bit {}..={} tq",
                c.name,
                c.prop_seg,
                c.seg1,
                c.seg2,
                BIT_QUANTA.start(),
                BIT_QUANTA.end()
            ),
            &[&c.path],
        ));
    }
}

/// Two items that the generated code would name with one constant.
fn check_constants(ecu: &Ecu, out: &mut Vec<Error>) {
    let constant = crate::rust::constant;
    let reserved = |names: &[&str]| -> Vec<(String, String)> {
        names
            .iter()
            .map(|n| ((*n).to_string(), "(generated)".to_string()))
            .collect()
    };
    let os = &ecu.os;
    let mut names = reserved(&[
        "TASKS",
        "COUNTERS",
        "ALARMS",
        "ISRS",
        "QUEUE",
        "RESOURCES",
        "PERIOD_TICKS",
        "DESCRIPTION",
    ]);
    names.extend(os.tasks.iter().map(|t| (constant(&t.name), t.path.clone())));
    names.extend(
        os.resources
            .iter()
            .map(|t| (constant(&t.name), t.path.clone())),
    );
    names.extend(
        os.events
            .iter()
            .map(|t| (constant(&t.name), t.path.clone())),
    );
    names.extend(
        os.counters
            .iter()
            .map(|t| (constant(&t.name), t.path.clone())),
    );
    names.extend(os.isrs.iter().map(|t| (constant(&t.name), t.path.clone())));
    let mut com = reserved(&[
        "MAIN_PERIOD_MS",
        "PDU_BYTES",
        "TX",
        "RX",
        "SIGNALS",
        "CONFIG",
    ]);
    com.extend(
        ecu.com
            .ipdus
            .iter()
            .map(|t| (constant(&t.name), t.path.clone())),
    );
    for sig in &ecu.com.signals {
        com.push((constant(&sig.name), sig.path.clone()));
        if sig.invalid.is_some() {
            com.push((format!("{}_INVALID", constant(&sig.name)), sig.path.clone()));
        }
    }
    let mut canif = reserved(&["TX", "RX", "CONFIG"]);
    for l in ecu.canif.tx.iter().chain(&ecu.canif.rx) {
        canif.push((constant(&l.name), l.path.clone()));
        canif.push((format!("{}_ID", constant(&l.name)), l.path.clone()));
    }
    for (module, list) in [("os", names), ("com", com), ("canif", canif)] {
        let mut seen: HashMap<&str, &str> = HashMap::new();
        for (name, path) in &list {
            if let Some(first) = seen.insert(name, path) {
                out.push(Error::new(
                    format!(
                        "two items of {module} would both be generated as the constant {name}: rename one"
                    ),
                    &[path, first],
                ));
            }
        }
    }
}

fn check_os(ecu: &Ecu, out: &mut Vec<Error>) {
    let os = &ecu.os;
    duplicates(out, "task", &os.tasks, |t| (&t.name, &t.path));
    duplicates(out, "resource", &os.resources, |t| (&t.name, &t.path));
    duplicates(out, "event", &os.events, |t| (&t.name, &t.path));
    duplicates(out, "counter", &os.counters, |t| (&t.name, &t.path));
    duplicates(out, "alarm", &os.alarms, |t| (&t.name, &t.path));
    duplicates(out, "ISR", &os.isrs, |t| (&t.name, &t.path));
    if os.tasks.is_empty() {
        out.push(Error::new("the OS has no task", &[&os.path]));
    }
    if os.resources.len() > 32 {
        out.push(Error::new(
            format!(
                "{} resources: the kernel takes at most 32",
                os.resources.len()
            ),
            &[&os.path],
        ));
    }
    for task in &os.tasks {
        if task.priority > MAX_TASK_PRIORITY {
            out.push(Error::new(
                format!(
                    "task {} has priority {}, above the kernel's {MAX_TASK_PRIORITY}",
                    task.name, task.priority
                ),
                &[&task.path],
            ));
        }
        if task.activations == 0 || task.activations > 255 {
            out.push(Error::new(
                format!(
                    "task {} allows {} activations; 1 to 255 can be queued",
                    task.name, task.activations
                ),
                &[&task.path],
            ));
        }
        for r in &task.resources {
            if find(&os.resources, r, |x| &x.name).is_none() {
                out.push(Error::new(
                    format!(
                        "task {} uses resource {r}, which the OS does not have",
                        task.name
                    ),
                    &[&task.path],
                ));
            }
        }
        for e in &task.events {
            if find(&os.events, e, |x| &x.name).is_none() {
                out.push(Error::new(
                    format!(
                        "task {} waits for event {e}, which the OS does not have",
                        task.name
                    ),
                    &[&task.path],
                ));
            }
        }
    }
    let mut by_priority: HashMap<u64, &str> = HashMap::new();
    for task in &os.tasks {
        if let Some(other) = by_priority.insert(task.priority, &task.path) {
            out.push(Error::new(
                format!(
                    "two tasks have priority {}: the generator gives each task a priority of its own",
                    task.priority
                ),
                &[&task.path, other],
            ));
        }
        if !task.events.is_empty() && task.activations != 1 {
            out.push(Error::new(
                format!(
                    "extended task {} allows {} activations: an extended task has one",
                    task.name, task.activations
                ),
                &[&task.path],
            ));
        }
        let mut masks: HashMap<u64, &str> = HashMap::new();
        for e in &task.events {
            if let Some((_, ev)) = find(&os.events, e, |x| &x.name) {
                if let Some(other) = masks.insert(ev.mask, &ev.path) {
                    out.push(Error::new(
                        format!(
                            "task {} waits for two events of mask {:#x}",
                            task.name, ev.mask
                        ),
                        &[&task.path, &ev.path, other],
                    ));
                }
            }
        }
        // One cyclic alarm gives a task its period.
        let cyclic: Vec<&str> = os
            .alarms
            .iter()
            .filter(|a| {
                let target = match &a.action {
                    AlarmAction::ActivateTask(t) | AlarmAction::SetEvent(t, _) => t,
                };
                *target == task.name && a.autostart.is_some_and(|(_, cycle)| cycle > 0)
            })
            .map(|a| a.path.as_str())
            .collect();
        if cyclic.len() > 1 {
            let mut paths = vec![task.path.as_str()];
            paths.extend(cyclic);
            out.push(Error::new(
                format!(
                    "task {} is driven by two cyclic alarms: one gives it its period",
                    task.name
                ),
                &paths,
            ));
        }
    }
    // Category-1 ISRs run above every category-2 ISR (the OS never masks them).
    let lowest_cat1 = os
        .isrs
        .iter()
        .filter(|i| i.category == 1)
        .min_by_key(|i| i.priority);
    if let Some(c1) = lowest_cat1 {
        for i in os
            .isrs
            .iter()
            .filter(|i| i.category == 2 && i.priority >= c1.priority)
        {
            out.push(Error::new(
                format!(
                    "category-1 ISR {} (priority {}) is not above category-2 ISR {} (priority {})",
                    c1.name, c1.priority, i.name, i.priority
                ),
                &[&c1.path, &i.path],
            ));
        }
    }
    for event in &os.events {
        if event.mask == 0 || event.mask > u64::from(u32::MAX) || !event.mask.is_power_of_two() {
            out.push(Error::new(
                format!(
                    "event {} has mask {:#x}: one bit of 32 is needed",
                    event.name, event.mask
                ),
                &[&event.path],
            ));
        }
    }
    for counter in &os.counters {
        let max = u64::from(u32::MAX) - 1;
        if counter.max_allowed_value == 0 || counter.max_allowed_value > max {
            out.push(Error::new(
                format!(
                    "counter {} counts to {}: 1 to {max} is possible",
                    counter.name, counter.max_allowed_value
                ),
                &[&counter.path],
            ));
        }
        if counter.ticks_per_base == 0 || counter.ticks_per_base > u64::from(u32::MAX) {
            out.push(Error::new(
                format!(
                    "counter {} has {} ticks per base: 1 or more, within 32 bits",
                    counter.name, counter.ticks_per_base
                ),
                &[&counter.path],
            ));
        }
        if counter.min_cycle == 0 || counter.min_cycle > counter.max_allowed_value {
            out.push(Error::new(
                format!(
                    "counter {}'s minimum cycle {} is outside 1..={}",
                    counter.name, counter.min_cycle, counter.max_allowed_value
                ),
                &[&counter.path],
            ));
        }
    }
    for alarm in &os.alarms {
        let counter = find(&os.counters, &alarm.counter, |c| &c.name);
        if counter.is_none() {
            out.push(Error::new(
                format!(
                    "alarm {} counts on counter {}, which the OS does not have",
                    alarm.name, alarm.counter
                ),
                &[&alarm.path],
            ));
        }
        let (task, event) = match &alarm.action {
            AlarmAction::ActivateTask(t) => (t, None),
            AlarmAction::SetEvent(t, e) => (t, Some(e)),
        };
        match find(&os.tasks, task, |t| &t.name) {
            None => out.push(Error::new(
                format!(
                    "alarm {} acts on task {task}, which the OS does not have",
                    alarm.name
                ),
                &[&alarm.path],
            )),
            Some((_, t)) => {
                if let Some(e) = event {
                    if !t.events.contains(e) {
                        out.push(Error::new(
                            format!(
                                "alarm {} sets event {e} on task {task}, which does not wait for it",
                                alarm.name
                            ),
                            &[&alarm.path, &t.path],
                        ));
                    }
                }
            }
        }
        if let (Some((start, cycle)), Some((_, c))) = (alarm.autostart, counter) {
            if start == 0
                || start > c.max_allowed_value
                || (cycle != 0 && (cycle < c.min_cycle || cycle > c.max_allowed_value))
            {
                out.push(Error::new(
                    format!(
                        "alarm {} starts after {start} and cycles every {cycle} ticks: counter {} takes 1..={} for the start and {}..={} for a cycle",
                        alarm.name, c.name, c.max_allowed_value, c.min_cycle, c.max_allowed_value
                    ),
                    &[&alarm.path, &c.path],
                ));
            }
        }
    }
    for isr in &os.isrs {
        if !matches!(isr.category, 1 | 2) {
            out.push(Error::new(
                format!("ISR {} is of category {}: 1 or 2", isr.name, isr.category),
                &[&isr.path],
            ));
        }
        if !ISR_PRIORITIES.contains(&isr.priority) {
            out.push(Error::new(
                format!(
                    "ISR {} has priority {}, outside the port's {}..={}",
                    isr.name,
                    isr.priority,
                    ISR_PRIORITIES.start(),
                    ISR_PRIORITIES.end()
                ),
                &[&isr.path],
            ));
        }
        for r in &isr.resources {
            if find(&os.resources, r, |x| &x.name).is_none() {
                out.push(Error::new(
                    format!(
                        "ISR {} uses resource {r}, which the OS does not have",
                        isr.name
                    ),
                    &[&isr.path],
                ));
            }
        }
    }
}

fn check_com(ecu: &Ecu, out: &mut Vec<Error>) {
    let com = &ecu.com;
    duplicates(out, "Com I-PDU", &com.ipdus, |t| (&t.name, &t.path));
    duplicates(out, "Com signal", &com.signals, |t| (&t.name, &t.path));
    duplicates(out, "PDU", &ecu.pdus, |t| (&t.name, &t.path));
    if com.main_period_ms == 0 {
        out.push(Error::new(
            "Com's main function period is 0 ms",
            &[&com.path],
        ));
    }
    // Each signal in exactly one I-PDU.
    let mut owner: HashMap<&str, &str> = HashMap::new();
    for ipdu in &com.ipdus {
        let pdu = find(&ecu.pdus, &ipdu.pdu, |p| &p.name);
        let length = match pdu {
            None => {
                out.push(Error::new(
                    format!(
                        "I-PDU {} refers to PDU {}, which EcuC does not have",
                        ipdu.name, ipdu.pdu
                    ),
                    &[&ipdu.path],
                ));
                None
            }
            Some((_, p)) if p.length == 0 || p.length > MAX_PDU_LENGTH => {
                out.push(Error::new(
                    format!(
                        "PDU {} is {} bytes long: 1 to {MAX_PDU_LENGTH} (classic CAN)",
                        p.name, p.length
                    ),
                    &[&p.path, &ipdu.path],
                ));
                None
            }
            Some((_, p)) => Some(p.length),
        };
        let mut placed: Vec<(&Signal, Vec<u64>)> = Vec::new();
        for name in &ipdu.signals {
            let Some((_, signal)) = find(&com.signals, name, |s| &s.name) else {
                out.push(Error::new(
                    format!(
                        "I-PDU {} carries signal {name}, which Com does not have",
                        ipdu.name
                    ),
                    &[&ipdu.path],
                ));
                continue;
            };
            if let Some(first) = owner.insert(&signal.name, &ipdu.path) {
                out.push(Error::new(
                    format!("signal {} is in two I-PDUs", signal.name),
                    &[&signal.path, first, &ipdu.path],
                ));
            }
            let Some(length) = length else { continue };
            let Some(mut bits) = signal_bits(
                signal.bit_position,
                signal.bit_size,
                signal.endianness,
                length,
            ) else {
                out.push(Error::new(
                    format!(
                        "signal {} ({} bits at bit {}) does not fit I-PDU {}'s {length} bytes",
                        signal.name, signal.bit_size, signal.bit_position, ipdu.name
                    ),
                    &[&signal.path, &ipdu.path],
                ));
                continue;
            };
            if let Some(u) = signal.update_bit {
                if u >= length * 8 {
                    out.push(Error::new(
                        format!(
                            "signal {}'s update bit {u} is outside I-PDU {}'s {length} bytes",
                            signal.name, ipdu.name
                        ),
                        &[&signal.path, &ipdu.path],
                    ));
                } else {
                    bits.push(u);
                }
            }
            for (other, other_bits) in &placed {
                if bits.iter().any(|b| other_bits.contains(b)) {
                    out.push(Error::new(
                        format!(
                            "signals {} and {} of I-PDU {} share bits",
                            other.name, signal.name, ipdu.name
                        ),
                        &[&signal.path, &other.path, &ipdu.path],
                    ));
                }
            }
            placed.push((signal, bits));
        }
        let base = com.main_period_ms.max(1);
        let whole = |ms: u64| ms % base == 0;
        let timing_error = |what: &str| {
            Error::new(
                format!(
                    "I-PDU {}'s {what} is not a whole number of Com's {} ms main periods",
                    ipdu.name, com.main_period_ms
                ),
                &[&ipdu.path],
            )
        };
        match &ipdu.direction {
            Direction::Send(tx) => {
                let periodic = matches!(tx.mode, TxModeMode::Periodic | TxModeMode::Mixed);
                if !whole(tx.mdt_ms) {
                    out.push(timing_error("minimum delay time"));
                }
                if periodic && (tx.period_ms == 0 || !whole(tx.period_ms) || !whole(tx.offset_ms)) {
                    out.push(timing_error("period (not 0) or offset"));
                }
                if tx.repetitions > 0
                    && (tx.repetition_period_ms == 0 || !whole(tx.repetition_period_ms))
                {
                    out.push(timing_error("repetition period (not 0)"));
                }
            }
            Direction::Receive { deadline_ms } => {
                if !whole(*deadline_ms) {
                    out.push(timing_error("deadline (ComTimeout)"));
                }
            }
        }
        if let Direction::Send(tx) = &ipdu.direction {
            if tx.repetitions > 255 {
                out.push(Error::new(
                    format!(
                        "I-PDU {} repeats {} times: at most 255",
                        ipdu.name, tx.repetitions
                    ),
                    &[&ipdu.path],
                ));
            }
        }
    }
    for signal in &com.signals {
        // The signal's bits within its type's (`ComSignalType`: BOOLEAN is one bit).
        if signal.bit_size > signal.type_bits {
            out.push(Error::new(
                format!(
                    "signal {} has {} bits, more than its ComSignalType's {}",
                    signal.name, signal.bit_size, signal.type_bits
                ),
                &[&signal.path],
            ));
        }
        // Init and invalid values within the signal's bits (signed ones as the two's
        // complement of 64 bits).
        for (what, v) in [
            ("ComSignalInitValue", Some(signal.init)),
            ("ComSignalDataInvalidValue", signal.invalid),
        ] {
            let Some(v) = v else { continue };
            let fits = match (signal.bit_size, signal.signed) {
                (64.., _) => true,
                (n, false) => v < 1 << n,
                (n, true) => {
                    let x = v as i64;
                    let half = 1i64 << n.saturating_sub(1);
                    -half <= x && x < half
                }
            };
            if !fits {
                out.push(Error::new(
                    format!(
                        "signal {}'s {what} {} does not fit its {} bits",
                        signal.name,
                        if signal.signed {
                            (v as i64).to_string()
                        } else {
                            v.to_string()
                        },
                        signal.bit_size
                    ),
                    &[&signal.path],
                ));
            }
        }
        if !owner.contains_key(signal.name.as_str()) {
            out.push(Error::new(
                format!("signal {} is in no I-PDU", signal.name),
                &[&signal.path],
            ));
        }
    }
}

fn check_routes_and_canif(ecu: &Ecu, out: &mut Vec<Error>) {
    duplicates(out, "routing path", &ecu.routes, |t| (&t.name, &t.path));
    duplicates(out, "CanIf TX PDU", &ecu.canif.tx, |t| (&t.name, &t.path));
    duplicates(out, "CanIf RX PDU", &ecu.canif.rx, |t| (&t.name, &t.path));
    for route in &ecu.routes {
        let src = find(&ecu.pdus, &route.src, |p| &p.name);
        for end in std::iter::once(&route.src).chain(&route.dests) {
            match find(&ecu.pdus, end, |p| &p.name) {
                None => out.push(Error::new(
                    format!(
                        "routing path {} refers to PDU {end}, which EcuC does not have",
                        route.name
                    ),
                    &[&route.path],
                )),
                Some((_, p)) => {
                    if let Some((_, s)) = src {
                        if p.length != s.length {
                            out.push(Error::new(
                                format!(
                                    "routing path {} joins PDU {} of {} bytes to PDU {} of {}: both ends have one length",
                                    route.name, s.name, s.length, p.name, p.length
                                ),
                                &[&route.path, &s.path, &p.path],
                            ));
                        }
                    }
                }
            }
        }
    }
    // One Com I-PDU per global PDU.
    let mut pdu_owner: HashMap<&str, &str> = HashMap::new();
    for ipdu in &ecu.com.ipdus {
        if let Some(other) = pdu_owner.insert(&ipdu.pdu, &ipdu.path) {
            out.push(Error::new(
                format!("two Com I-PDUs refer to PDU {}", ipdu.pdu),
                &[&ipdu.path, other],
            ));
        }
    }
    for (kind, lpdus) in [("TX", &ecu.canif.tx), ("RX", &ecu.canif.rx)] {
        let mut ids: HashMap<(u64, bool), &str> = HashMap::new();
        for l in lpdus {
            let bits = if l.extended { 29 } else { 11 };
            if l.can_id >= 1 << bits {
                out.push(Error::new(
                    format!(
                        "CanIf {kind} PDU {} has CAN id {:#x}, more than {bits} bits",
                        l.name, l.can_id
                    ),
                    &[&l.path],
                ));
            }
            if let Some(other) = ids.insert((l.can_id, l.extended), &l.path) {
                out.push(Error::new(
                    format!("two CanIf {kind} PDUs have CAN id {:#x}", l.can_id),
                    &[&l.path, other],
                ));
            }
            match find(&ecu.pdus, &l.pdu, |p| &p.name) {
                None => out.push(Error::new(
                    format!(
                        "CanIf {kind} PDU {} refers to PDU {}, which EcuC does not have",
                        l.name, l.pdu
                    ),
                    &[&l.path],
                )),
                Some((_, p)) => {
                    let dlc = l.dlc.unwrap_or(p.length);
                    if dlc < p.length || dlc > MAX_PDU_LENGTH {
                        out.push(Error::new(
                            format!(
                                "CanIf {kind} PDU {} has DLC {dlc} for PDU {} of {} bytes: the DLC must hold the PDU, up to {MAX_PDU_LENGTH}",
                                l.name, p.name, p.length
                            ),
                            &[&l.path, &p.path],
                        ));
                    }
                }
            }
        }
    }
    // Com's I-PDUs reach CanIf through PduR, one route each way.
    for ipdu in &ecu.com.ipdus {
        let sending = matches!(ipdu.direction, Direction::Send(_));
        let routes: Vec<_> = ecu
            .routes
            .iter()
            .filter(|r| {
                if sending {
                    r.src == ipdu.pdu
                } else {
                    r.dests.contains(&ipdu.pdu)
                }
            })
            .collect();
        if let (true, [r]) = (sending, routes.as_slice()) {
            if r.dests.len() != 1 {
                out.push(Error::new(
                    format!(
                        "routing path {} sends I-PDU {} to {} PDUs: the ECU's PduR sends each to one",
                        r.name,
                        ipdu.name,
                        r.dests.len()
                    ),
                    &[&r.path, &ipdu.path],
                ));
            }
        }
        let lower = |r: &&crate::model::Route| {
            if sending {
                r.dests.first().cloned().unwrap_or_default()
            } else {
                r.src.clone()
            }
        };
        match routes.as_slice() {
            [] => out.push(Error::new(
                format!(
                    "I-PDU {} ({}) has no PduR routing path {} CanIf",
                    ipdu.name,
                    ipdu.pdu,
                    if sending { "to" } else { "from" }
                ),
                &[&ipdu.path],
            )),
            [r] => {
                let pdu = lower(r);
                let lpdus = if sending {
                    &ecu.canif.tx
                } else {
                    &ecu.canif.rx
                };
                if find(lpdus, &pdu, |l| &l.pdu).is_none() {
                    out.push(Error::new(
                        format!(
                            "routing path {} leads I-PDU {} to PDU {pdu}, which no CanIf {} PDU carries",
                            r.name,
                            ipdu.name,
                            if sending { "TX" } else { "RX" }
                        ),
                        &[&r.path, &ipdu.path],
                    ));
                }
            }
            [a, b, ..] => out.push(Error::new(
                format!("I-PDU {} has two routing paths", ipdu.name),
                &[&ipdu.path, &a.path, &b.path],
            )),
        }
    }
}
