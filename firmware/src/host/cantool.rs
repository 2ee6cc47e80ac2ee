//! The engineer's side of the bus (paper §4.4): decode a candump log into signal values
//! with a DBC, and encode signal values into a frame. The `cw-can` tool wraps this.
//!
//! Decoding uses the ECU's own codec (`cw_core::com::signal`), so a frame reads back
//! exactly as Com packed it; DBC factor, offset, unit and value tables are applied on top.

use can_dbc::{ByteOrder as DbcOrder, Dbc, Message, MessageId, ValueType};
use cw_core::can::{CanFrame, CanId};
use cw_core::com::signal::{ByteOrder, SignalLayout, SignalValue, Signedness};

/// One decoded signal.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedSignal {
    /// Signal name.
    pub name: String,
    /// Raw value as packed.
    pub raw: i128,
    /// Physical value, `raw * factor + offset`.
    pub physical: f64,
    /// Unit from the DBC.
    pub unit: String,
    /// The DBC value-table entry for the raw value, if any.
    pub label: Option<String>,
}

/// A candump log line: time stamp, interface, frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LogLine {
    /// Seconds since the epoch.
    pub timestamp: f64,
    /// Interface name (`can0`).
    pub interface: String,
    /// The frame.
    pub frame: CanFrame,
}

/// Reads one `(1700000000.123456) can0 100#DEADBEEF` line.
///
/// # Errors
/// A sentence naming what is malformed.
pub fn parse_log_line(line: &str) -> Result<LogLine, String> {
    let mut parts = line.split_whitespace();
    let (Some(stamp), Some(interface), Some(frame), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(format!(
            "`{line}` is not a candump log line: (SECONDS) IFACE ID#DATA"
        ));
    };
    let timestamp = stamp
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| format!("`{stamp}` is not a (seconds) time stamp"))?;
    Ok(LogLine {
        timestamp,
        interface: interface.to_string(),
        frame: parse_frame(frame)?,
    })
}

/// Reads `ID#HEX`: 3 hex digits for a standard id, 8 for an extended one.
///
/// # Errors
/// A sentence naming what is malformed.
pub fn parse_frame(text: &str) -> Result<CanFrame, String> {
    cw_core::can::text::parse_frame(text).map_err(|e| e.to_string())
}

/// Formats a frame as `ID#HEX`.
pub fn format_frame(frame: &CanFrame) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail.
    let _ = cw_core::can::text::write_frame(frame, &mut out);
    out
}

/// Reads a DBC file's text.
///
/// # Errors
/// The parser's complaint.
pub fn load_dbc(text: &str) -> Result<Dbc, String> {
    Dbc::try_from(text).map_err(|e| format!("the DBC does not parse: {e:?}"))
}

fn message_id(id: CanId) -> MessageId {
    if id.is_extended() {
        MessageId::Extended(id.raw())
    } else {
        MessageId::Standard(id.raw() as u16)
    }
}

fn layout(signal: &can_dbc::Signal) -> Result<SignalLayout<8>, String> {
    let order = match signal.byte_order {
        DbcOrder::LittleEndian => ByteOrder::Intel,
        DbcOrder::BigEndian => ByteOrder::Motorola,
    };
    let sign = match signal.value_type {
        ValueType::Signed => Signedness::Signed,
        ValueType::Unsigned => Signedness::Unsigned,
    };
    let start = u16::try_from(signal.start_bit)
        .map_err(|_| format!("{}: start bit too large", signal.name))?;
    let len =
        u8::try_from(signal.size).map_err(|_| format!("{}: length too large", signal.name))?;
    SignalLayout::new(start, len, order, sign).map_err(|e| format!("{}: {e:?}", signal.name))
}

/// The DBC message of a frame and its decoded signals; `None` if the DBC does not know
/// the id.
///
/// # Errors
/// A signal that does not fit an 8-byte frame.
pub fn decode<'a>(
    dbc: &'a Dbc,
    frame: &CanFrame,
) -> Result<Option<(&'a Message, Vec<DecodedSignal>)>, String> {
    let id = message_id(frame.can_id());
    let Some(message) = dbc.messages.iter().find(|m| m.id == id) else {
        return Ok(None);
    };
    let mut pdu = [0u8; 8];
    pdu[..frame.bytes().len()].copy_from_slice(frame.bytes());
    let mut signals = Vec::new();
    for s in &message.signals {
        let raw = layout(s)?.unpack(&pdu).as_i128();
        let label = dbc
            .value_descriptions_for_signal(id, &s.name)
            .and_then(|table| table.iter().find(|d| i128::from(d.id) == raw))
            .map(|d| d.description.clone());
        signals.push(DecodedSignal {
            name: s.name.clone(),
            raw,
            physical: raw as f64 * s.factor + s.offset,
            unit: s.unit.clone(),
            label,
        });
    }
    Ok(Some((message, signals)))
}

/// Encodes `name=value` physical values into a frame of message `message_name`; signals
/// not given are 0.
///
/// # Errors
/// Unknown message or signal, a value that is not a number, or one out of the signal's
/// range (never truncated).
pub fn encode(dbc: &Dbc, message_name: &str, values: &[(String, f64)]) -> Result<CanFrame, String> {
    let message = dbc
        .messages
        .iter()
        .find(|m| m.name == message_name)
        .ok_or_else(|| format!("no message `{message_name}` in the DBC"))?;
    let mut pdu = [0u8; 8];
    for (name, physical) in values {
        let s = message
            .signals
            .iter()
            .find(|s| &s.name == name)
            .ok_or_else(|| format!("no signal `{name}` in {message_name}"))?;
        let raw = ((physical - s.offset) / s.factor).round();
        let l = layout(s)?;
        let value = if l.signedness() == Signedness::Signed {
            SignalValue::Signed(raw as i64)
        } else if raw < 0.0 {
            return Err(format!("{name} = {physical} is below the signal's range"));
        } else {
            SignalValue::Unsigned(raw as u64)
        };
        l.pack(&mut pdu, value)
            .map_err(|_| format!("{name} = {physical} does not fit {} bits", l.length_bits()))?;
    }
    let (id, len) = match message.id {
        MessageId::Standard(raw) => (CanId::standard(raw), message.size),
        MessageId::Extended(raw) => (CanId::extended(raw), message.size),
    };
    let id = id.ok_or_else(|| format!("{message_name}: id out of range"))?;
    let len = usize::try_from(len)
        .ok()
        .filter(|l| *l <= 8)
        .ok_or_else(|| format!("{message_name}: more than 8 bytes"))?;
    CanFrame::from_parts(id, &pdu[..len])
        .ok_or_else(|| format!("{message_name}: more than 8 bytes"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dbc() -> Dbc {
        load_dbc(include_str!("../../ecu.dbc")).expect("ecu.dbc parses")
    }

    #[test]
    fn encode_then_decode_round_trips() {
        let dbc = dbc();
        let frame = encode(
            &dbc,
            "ThresholdConfig",
            &[("RedBelow".into(), 500.0), ("YellowBelow".into(), 1000.0)],
        )
        .expect("valid values");
        assert_eq!(format_frame(&frame), "200#F401E803");
        let (msg, signals) = decode(&dbc, &frame).expect("decodes").expect("known id");
        assert_eq!(msg.name, "ThresholdConfig");
        assert_eq!(
            signals.iter().map(|s| s.raw).collect::<Vec<_>>(),
            [500, 1000]
        );
    }

    #[test]
    fn decode_uses_value_tables_and_reports_unknown_ids() {
        let dbc = dbc();
        let line =
            parse_log_line("(1700000000.040240) can0 100#FFFFFFFF03000000").expect("valid line");
        assert_eq!(line.interface, "can0");
        let (_, signals) = decode(&dbc, &line.frame)
            .expect("decodes")
            .expect("known id");
        assert_eq!(signals[0].label.as_deref(), Some("Invalid"));
        assert_eq!(signals[1].label.as_deref(), Some("Fault"));
        let unknown = parse_frame("7FF#00").expect("valid frame");
        assert_eq!(decode(&dbc, &unknown), Ok(None));
    }

    #[test]
    fn bad_input_gets_a_clear_error() {
        let dbc = dbc();
        assert_eq!(
            encode(&dbc, "ThresholdConfig", &[("RedBelow".into(), 70000.0)]),
            Err("RedBelow = 70000 does not fit 16 bits".into())
        );
        assert_eq!(
            encode(&dbc, "Nope", &[]),
            Err("no message `Nope` in the DBC".into())
        );
        assert!(parse_log_line("garbage").is_err());
        assert!(parse_log_line("(x) can0 100#00").is_err());
        // Non-ASCII data is refused, not sliced through a character; signs are no digits.
        assert!(parse_frame("100#0é0").is_err());
        assert!(parse_frame("100#é").is_err());
        assert!(parse_frame("100#+F").is_err());
        assert!(parse_frame("+10#00").is_err());
        assert!(parse_frame("100#0").is_err());
        assert_eq!(
            parse_frame("100#0aFF").map(|f| format_frame(&f)),
            Ok("100#0AFF".into())
        );
    }
}
