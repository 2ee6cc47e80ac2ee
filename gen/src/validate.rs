//! The checks made before anything is generated. Each error names the ARXML path of every
//! item involved, so that a user finds both ends of a bad reference or both signals that
//! overlap; all errors are reported at once, not only the first.

use std::collections::HashMap;
use std::fmt;

use crate::model::{AlarmAction, Direction, Ecu, Endianness, Signal};

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

/// The largest priority a task may have (the kernel keeps priorities in a byte).
pub const MAX_TASK_PRIORITY: u64 = 255;
/// The interrupt priorities the ports take (`IsrConfig::priority`: 1 is the lowest).
pub const ISR_PRIORITIES: std::ops::RangeInclusive<u64> = 1..=15;
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
/// occupies, or `None` if it does not fit `length` bytes. Little endian: the position is
/// the least significant bit and the signal grows to higher bits; big endian: the position
/// is the most significant bit (AUTOSAR's and the DBC's "sawtooth" numbering) and the
/// signal grows towards the next byte's lower bits.
pub fn signal_bits(
    bit_position: u64,
    bit_size: u64,
    endianness: Endianness,
    length: u64,
) -> Option<Vec<u64>> {
    let total = length.checked_mul(8)?;
    if bit_size == 0 || bit_size > 64 || bit_position >= total {
        return None;
    }
    let mut bits = Vec::new();
    let mut at = bit_position;
    for _ in 0..bit_size {
        if at >= total {
            return None;
        }
        bits.push(at);
        at = match endianness {
            Endianness::Little => at + 1,
            Endianness::Big if at % 8 == 0 => at.checked_add(15)?,
            Endianness::Big => at - 1,
        };
    }
    Some(bits)
}

/// Every check; empty when the description can be generated.
pub fn check(ecu: &Ecu) -> Vec<Error> {
    let mut out = Vec::new();
    check_os(ecu, &mut out);
    check_com(ecu, &mut out);
    check_routes_and_canif(ecu, &mut out);
    out
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
                    "two tasks have priority {}: the ECU's OS runs one task per priority (BCC1, ECC1)",
                    task.priority
                ),
                &[&task.path, other],
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
        if counter.max_allowed_value == 0 || counter.max_allowed_value > u64::from(u32::MAX) {
            out.push(Error::new(
                format!(
                    "counter {} counts to {}: 1 to {} is possible",
                    counter.name,
                    counter.max_allowed_value,
                    u32::MAX
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
            if start > c.max_allowed_value
                || (cycle != 0 && (cycle < c.min_cycle || cycle > c.max_allowed_value))
            {
                out.push(Error::new(
                    format!(
                        "alarm {} starts after {start} and cycles every {cycle} ticks, outside counter {}'s {}..={}",
                        alarm.name, c.name, c.min_cycle, c.max_allowed_value
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
        for end in [&route.src, &route.dest] {
            if find(&ecu.pdus, end, |p| &p.name).is_none() {
                out.push(Error::new(
                    format!(
                        "routing path {} refers to PDU {end}, which EcuC does not have",
                        route.name
                    ),
                    &[&route.path],
                ));
            }
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
                    r.dest == ipdu.pdu
                }
            })
            .collect();
        let lower = |r: &&crate::model::Route| {
            if sending {
                r.dest.clone()
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
