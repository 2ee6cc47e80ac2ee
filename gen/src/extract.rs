//! The ECU extract's communication: what the bus's system description asks of one ECU (the
//! frames it sends, the signals it receives, their identifiers, lengths and layouts),
//! checked against that ECU's ECUC values (the CanIf L-PDUs, their global PDUs, PduR's
//! routes and the Com I-PDUs and signals behind them). An AUTOSAR tool derives the second
//! from the first; here both are written, and generation stops where they disagree, each
//! error naming the ECUC path and the place in the system description (or the DBC) it
//! was read from.
//!
//! A frame is the ECU's to send when the description names it the frame's sender, and to
//! receive when it is a receiver of one of the frame's signals. A sent frame's I-PDU
//! carries every signal of the frame; a received one carries at least those the ECU
//! receives. Com and the bus name a signal alike (the DBC's `SG_` name is the
//! `ComSignal`'s short name).

use crate::model::{Ecu, Endianness, IPdu, LPdu};
use crate::system::{Frame, Read};
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

/// Checks the communication of `ecu` against what `bus` (read from `source`) asks of the
/// node `node`.
///
/// # Errors
/// Every disagreement, each naming the ECUC item and the bus's frame or signal: a node
/// not on the bus; a CanIf L-PDU whose identifier no frame has, or a frame the node sends
/// or receives that no L-PDU carries; a frame sent by another node; a PDU of another
/// length than its frame, a data length CanIf sends other than the frame's or checks
/// beyond it; a Com signal the frame does not hold, or holds at another
/// position, length, byte order or signedness; a signal of the frame the I-PDU leaves out
/// (every one, for a sent frame; those the node receives, for a received one).
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
        for lpdu in lpdus {
            let frame = bus
                .system
                .frames
                .iter()
                .find(|f| (u64::from(f.id), f.extended) == (lpdu.can_id, lpdu.extended));
            let Some(frame) = frame else {
                out.push(Error::new(
                    format!(
                        "CanIf {} the {} identifier {:#x}, which no frame of the bus has",
                        if sent { "sends" } else { "receives" },
                        if lpdu.extended {
                            "extended"
                        } else {
                            "standard"
                        },
                        lpdu.can_id
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
            // A received frame shorter than CanIf's data length check is dropped; a sent
            // one is sent with the length CanIf gives it.
            if let Some(dlc) = lpdu.dlc {
                let frame_length = u64::from(frame.length);
                if (sent && dlc != frame_length) || (!sent && dlc > frame_length) {
                    out.push(Error::new(
                        format!(
                            "CanIf {} frame {} with {dlc} bytes, and the bus's frame has {}{}",
                            if sent { "sends" } else { "takes" },
                            frame.name,
                            frame.length,
                            if sent {
                                ""
                            } else {
                                ": every one would be dropped"
                            }
                        ),
                        &[&lpdu.path, &at],
                    ));
                }
            }
            for ipdu in com_ipdus(ecu, lpdu, sent) {
                length(ecu, &ipdu.pdu, frame, &at, &mut out);
                agreed.signals += signals(bus, node, ecu, ipdu, frame, sent, &mut out);
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
                        "{node} {verb} frame {} ({:#x}) on the bus, and no {kind} carries it",
                        frame.name, frame.id
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
fn signals(
    bus: &Read,
    node: &str,
    ecu: &Ecu,
    ipdu: &IPdu,
    frame: &Frame,
    sent: bool,
    out: &mut Vec<Error>,
) -> usize {
    let mut agreed = 0;
    for name in &ipdu.signals {
        let Some(com) = ecu.com.signals.iter().find(|s| s.name == *name) else {
            // A reference to no signal: the ECU's own checks name it.
            continue;
        };
        let Some(theirs) = frame.signals.iter().find(|s| s.name == *name) else {
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
                &[&com.path, &bus.places.signal(&frame.name, name)],
            ));
        }
    }
    for theirs in &frame.signals {
        let needed = sent || theirs.receivers.iter().any(|r| r == node);
        if needed && !ipdu.signals.contains(&theirs.name) {
            out.push(Error::new(
                if sent {
                    format!(
                        "I-PDU {} lacks the bus's signal {} of frame {}, which {node} sends",
                        ipdu.name, theirs.name, frame.name
                    )
                } else {
                    format!(
                        "I-PDU {} lacks the bus's signal {} of frame {}, which {node} receives",
                        ipdu.name, theirs.name, frame.name
                    )
                },
                &[&ipdu.path, &bus.places.signal(&frame.name, &theirs.name)],
            ));
        }
    }
    agreed
}
