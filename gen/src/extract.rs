//! The ECU extract's communication: what the bus's system description asks of one ECU (the
//! frames it sends, the signals it receives, their identifiers, lengths and layouts),
//! checked against that ECU's ECUC values (the CanIf L-PDUs, their global PDUs, PduR's
//! routes and the Com I-PDUs and signals behind them). An AUTOSAR tool derives the second
//! from the first; here both are written, and generation stops where they disagree, each
//! error naming the ECUC path and the place in the system description (or the DBC) it
//! was read from.
//!
//! A frame is the ECU's to send when the description names it the frame's sender, and to
//! receive when it is a receiver of one of the frame's signals. The Com I-PDUs behind a
//! sent frame's L-PDU carry every signal of the frame; those behind a received one, at
//! least the signals the ECU receives. Com names a signal as the bus does (the DBC's `SG_`
//! name), or, where two of the ECU's frames have a signal of one name, as the frame's
//! name and the signal's joined by `_` (`DistanceFrame_Crc`, as the system description's
//! `I-SIGNAL` is then named). The bus has no update bits: a Com signal's update bit must
//! lie outside every signal of its frame.

use crate::model::{Direction, Ecu, Endianness, IPdu, LPdu};
use crate::system::{Frame, Read, Signal};
use crate::validate::Error;

/// What agreed: the frames and signals of the bus the ECU's communication was checked on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Agreed {
    /// Frames the ECU sends.
    pub sent: usize,
    /// Frames the ECU receives.
    pub received: usize,
    /// Com signals held to the bus's.
    pub signals: usize,
}

/// A frame's identifier as the user reads it: its kind and its value.
fn identifier(id: u64, extended: bool) -> String {
    format!(
        "{} identifier {id:#x}",
        if extended { "extended" } else { "standard" }
    )
}

/// The frame's signal that the Com signal `com` is: of its name, or of the frame's name and
/// its own joined by `_`.
fn named<'f>(frame: &'f Frame, com: &str) -> Option<&'f Signal> {
    frame.signals.iter().find(|s| s.name == com).or_else(|| {
        frame.signals.iter().find(|s| {
            com.strip_prefix(&frame.name)
                .and_then(|r| r.strip_prefix('_'))
                == Some(&s.name)
        })
    })
}

/// Checks the communication of `ecu` against what `bus` (read from `source`) asks of the
/// node `node`.
///
/// # Errors
/// Every disagreement, each naming the ECUC item and the bus's frame or signal: a node
/// not on the bus; a CanIf L-PDU whose identifier no frame has, or a frame the node sends
/// or receives that no L-PDU carries; a frame sent by another node, or received with none
/// of its signals for the node; a PDU or a CanIf data length other than its frame's; a
/// Com I-PDU of the other direction, or two sent in one frame; a Com signal the frame
/// does not hold, or holds at another position, length, byte order or signedness, or
/// whose update bit lies in one of the frame's signals; a signal of the frame the node
/// sends or receives that no Com I-PDU behind the L-PDU holds.
pub fn check(bus: &Read, source: &str, node: &str, ecu: &Ecu) -> Result<Agreed, Vec<Error>> {
    let mut out = Vec::new();
    let mut agreed = Agreed::default();
    if !bus.system.nodes.iter().any(|n| n.name == node) {
        out.push(Error::new(
            format!("the bus has no node {node}: the ECU's communication cannot be checked"),
            &[source],
        ));
        return Err(out);
    }
    let receives = |f: &Frame| {
        f.signals
            .iter()
            .any(|s| s.receivers.iter().any(|r| r == node))
    };
    let sends = |f: &Frame| f.sender.as_deref() == Some(node);
    for (lpdus, sent) in [(&ecu.canif.tx, true), (&ecu.canif.rx, false)] {
        let verb = if sent { "sends" } else { "receives" };
        for lpdu in lpdus {
            let frame = bus
                .system
                .frames
                .iter()
                .find(|f| (u64::from(f.id), f.extended) == (lpdu.can_id, lpdu.extended));
            let Some(frame) = frame else {
                // The same number of the other kind is a likely slip: say so.
                let other = bus
                    .system
                    .frames
                    .iter()
                    .find(|f| (u64::from(f.id), f.extended) == (lpdu.can_id, !lpdu.extended));
                out.push(Error::new(
                    format!(
                        "CanIf {verb} the {}, which no frame of the bus has{}",
                        identifier(lpdu.can_id, lpdu.extended),
                        other.map_or(String::new(), |f| format!(
                            " (frame {} has the {})",
                            f.name,
                            identifier(u64::from(f.id), f.extended)
                        ))
                    ),
                    &[&lpdu.path, source],
                ));
                continue;
            };
            let at = bus.places.frame(&frame.name);
            if sent && !sends(frame) {
                out.push(Error::new(
                    format!(
                        "CanIf sends frame {}, which the bus has {}",
                        frame.name,
                        frame
                            .sender
                            .as_deref()
                            .map_or("sent by no node".to_string(), |s| format!("sent by {s}"))
                    ),
                    &[&lpdu.path, &at],
                ));
            }
            if !sent && !receives(frame) {
                out.push(Error::new(
                    format!(
                        "CanIf receives frame {}, none of whose signals the bus gives {node}",
                        frame.name
                    ),
                    &[&lpdu.path, &at],
                ));
            }
            length(ecu, &lpdu.pdu, frame, &at, &mut out);
            // A sent frame goes with the length CanIf gives it; a received one shorter
            // than CanIf's data length check is dropped (and a shorter check is refused
            // by the ECU's own checks, the PDU being the frame's length).
            if let Some(dlc) = lpdu.dlc.filter(|&d| d != u64::from(frame.length)) {
                out.push(Error::new(
                    format!(
                        "CanIf's data length for frame {} is {dlc} bytes, and the frame has {}",
                        frame.name, frame.length
                    ),
                    &[&lpdu.path, &at],
                ));
            }
            let ipdus = com_ipdus(ecu, lpdu, sent);
            if let [first, second, ..] = ipdus.as_slice() {
                if sent {
                    out.push(Error::new(
                        format!(
                            "Com I-PDUs {} and {} are both sent in frame {}",
                            first.name, second.name, frame.name
                        ),
                        &[&first.path, &second.path, &at],
                    ));
                }
            }
            for ipdu in &ipdus {
                if matches!(ipdu.direction, Direction::Send(_)) != sent {
                    out.push(Error::new(
                        format!(
                            "Com I-PDU {} is {}, and CanIf {verb} its frame {}",
                            ipdu.name,
                            if sent { "received" } else { "sent" },
                            frame.name
                        ),
                        &[&ipdu.path, &lpdu.path],
                    ));
                }
                length(ecu, &ipdu.pdu, frame, &at, &mut out);
                agreed.signals += signals(bus, ecu, ipdu, frame, &mut out);
            }
            // The signals the node sends or receives, in the I-PDUs together.
            let missing: Vec<&Signal> = frame
                .signals
                .iter()
                .filter(|s| sent || s.receivers.iter().any(|r| r == node))
                .filter(|s| {
                    !ipdus.iter().any(|i| {
                        i.signals
                            .iter()
                            .any(|c| named(frame, c).is_some_and(|f| f.name == s.name))
                    })
                })
                .collect();
            if !missing.is_empty() {
                let names: Vec<&str> = missing.iter().map(|s| s.name.as_str()).collect();
                let places: Vec<String> = missing
                    .iter()
                    .map(|s| bus.places.signal(&frame.name, &s.name))
                    .collect();
                let mut paths = vec![lpdu.path.as_str()];
                paths.extend(ipdus.iter().map(|i| i.path.as_str()));
                paths.extend(places.iter().map(String::as_str));
                out.push(Error::new(
                    format!(
                        "{node} {verb} frame {} with signal(s) {} on the bus, and no Com I-PDU it {} holds them",
                        frame.name,
                        names.join(", "),
                        if sent {
                            "sends as the frame"
                        } else {
                            "routes the frame into"
                        }
                    ),
                    &paths,
                ));
            }
        }
    }
    for frame in &bus.system.frames {
        let carried = |lpdus: &[LPdu]| {
            lpdus
                .iter()
                .any(|l| (l.can_id, l.extended) == (u64::from(frame.id), frame.extended))
        };
        for (ours, lpdus, verb, kind) in [
            (sends(frame), &ecu.canif.tx, "sends", "CanIfTxPduCfg"),
            (receives(frame), &ecu.canif.rx, "receives", "CanIfRxPduCfg"),
        ] {
            if !ours {
                continue;
            }
            if carried(lpdus) {
                if verb == "sends" {
                    agreed.sent += 1;
                } else {
                    agreed.received += 1;
                }
            } else {
                out.push(Error::new(
                    format!(
                        "{node} {verb} frame {} ({}) on the bus, and no {kind} carries it",
                        frame.name,
                        identifier(u64::from(frame.id), frame.extended)
                    ),
                    &[&bus.places.frame(&frame.name), &ecu.canif.path],
                ));
            }
        }
    }
    if out.is_empty() {
        Ok(agreed)
    } else {
        Err(out)
    }
}

/// The global PDU `pdu`'s length against the frame's.
fn length(ecu: &Ecu, pdu: &str, frame: &Frame, at: &str, out: &mut Vec<Error>) {
    if let Some(p) = ecu.pdus.iter().find(|p| p.name == pdu) {
        if p.length != u64::from(frame.length) {
            out.push(Error::new(
                format!(
                    "PDU {} is {} bytes long, its frame {} {}",
                    p.name, p.length, frame.name, frame.length
                ),
                &[&p.path, at],
            ));
        }
    }
}

/// The Com I-PDUs PduR routes to a sent L-PDU or from a received one.
fn com_ipdus<'e>(ecu: &'e Ecu, lpdu: &LPdu, sent: bool) -> Vec<&'e IPdu> {
    let names: Vec<&str> = ecu
        .routes
        .iter()
        .flat_map(|r| {
            if sent {
                if r.dests.contains(&lpdu.pdu) {
                    vec![r.src.as_str()]
                } else {
                    Vec::new()
                }
            } else if r.src == lpdu.pdu {
                r.dests.iter().map(String::as_str).collect()
            } else {
                Vec::new()
            }
        })
        .collect();
    ecu.com
        .ipdus
        .iter()
        .filter(|i| names.contains(&i.pdu.as_str()))
        .collect()
}

/// The I-PDU's Com signals against the frame's; the number that agreed.
fn signals(bus: &Read, ecu: &Ecu, ipdu: &IPdu, frame: &Frame, out: &mut Vec<Error>) -> usize {
    let mut agreed = 0;
    for name in &ipdu.signals {
        let Some(com) = ecu.com.signals.iter().find(|s| s.name == *name) else {
            // A reference to no signal: the ECU's own checks name it.
            continue;
        };
        let Some(theirs) = named(frame, name) else {
            out.push(Error::new(
                format!(
                    "Com signal {name} of I-PDU {} is not a signal of frame {} on the bus",
                    ipdu.name, frame.name
                ),
                &[&com.path, &bus.places.frame(&frame.name)],
            ));
            continue;
        };
        let big = com.endianness == Endianness::Big;
        let order = |big: bool| if big { "big endian" } else { "little endian" };
        let sign = |signed: bool| if signed { "signed" } else { "unsigned" };
        let differences: Vec<String> = [
            (com.bit_position != u64::from(theirs.start_bit)).then(|| {
                format!(
                    "bit position {} where the bus has {}",
                    com.bit_position, theirs.start_bit
                )
            }),
            (com.bit_size != u64::from(theirs.length))
                .then(|| format!("{} bits where the bus has {}", com.bit_size, theirs.length)),
            (big != theirs.big_endian).then(|| {
                format!(
                    "{} where the bus has {}",
                    order(big),
                    order(theirs.big_endian)
                )
            }),
            (com.signed != theirs.signed).then(|| {
                format!(
                    "{} where the bus has {}",
                    sign(com.signed),
                    sign(theirs.signed)
                )
            }),
        ]
        .into_iter()
        .flatten()
        .collect();
        if differences.is_empty() {
            agreed += 1;
        } else {
            out.push(Error::new(
                format!("Com signal {name}: {}", differences.join(", ")),
                &[&com.path, &bus.places.signal(&frame.name, &theirs.name)],
            ));
        }
        // The bus has no update bits: one inside a signal of the frame would be that
        // signal's bit to the other nodes.
        if let Some(bit) = com.update_bit {
            let over = frame.signals.iter().find(|s| {
                let order = if s.big_endian {
                    Endianness::Big
                } else {
                    Endianness::Little
                };
                crate::validate::signal_bits(
                    u64::from(s.start_bit),
                    u64::from(s.length),
                    order,
                    u64::from(frame.length),
                )
                .is_some_and(|bits| bits.contains(&bit))
            });
            if let Some(s) = over {
                out.push(Error::new(
                    format!(
                        "Com signal {name}'s update bit {bit} lies in the bus's signal {} of frame {}",
                        s.name, frame.name
                    ),
                    &[&com.path, &bus.places.signal(&frame.name, &s.name)],
                ));
            }
        }
    }
    agreed
}
