//! A message's signals read from a frame's bytes and written into them, with the
//! semantics cantools gives a DBC: raw values exact for every 64-bit integer; physical
//! values `raw * factor + offset`, integers where factor and offset are; encoding rounds
//! half to even (Python's `round`), checks the DBC's `[min|max]` (unless the value is a
//! value table entry), and needs every signal the frame carries.

use std::fmt;

use cw_core::com::signal::{spec::value_range, Signedness};

use crate::dbc::{Encoding, LayoutFault, MessageDef, SignalDef};
use crate::frame::{Frame, FrameKind};

/// A signal's raw value: the integer its bits hold, or the IEEE value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Raw {
    /// An integer signal.
    Int(i128),
    /// An IEEE float or double signal.
    Float(f64),
}

/// A physical value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Physical {
    /// Exact: an integer signal with an integer factor and offset.
    Int(i128),
    /// Otherwise.
    Float(f64),
}

/// Integers as they are; floats with a point or an exponent, in the shortest form that
/// reads back as the same value (`980.0`, `1.46`, `-4.152327929361858e-21`), as cantools
/// (Python's `repr`) writes them.
impl fmt::Display for Physical {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(v) => write!(f, "{v}"),
            Self::Float(v) => write!(f, "{v:?}"),
        }
    }
}

/// As [`Physical`]'s.
impl fmt::Display for Raw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(v) => write!(f, "{v}"),
            Self::Float(v) => write!(f, "{v:?}"),
        }
    }
}

/// One decoded signal.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded<'a> {
    /// The signal's definition.
    pub signal: &'a SignalDef,
    /// Its raw value.
    pub raw: Raw,
    /// Its bits as read, zero-extended.
    pub bits: u64,
    /// Its physical value.
    pub physical: Physical,
    /// The value table's name of the raw value.
    pub choice: Option<&'a str>,
}

/// Why a frame was not decoded with its message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DecodeError {
    /// Fewer bytes than the message has (cantools refuses these too).
    Short {
        /// Bytes in the frame.
        len: usize,
        /// The message's size.
        size: usize,
    },
    /// A present multiplexer holds a value that selects no signal and that its value
    /// table does not name (cantools refuses these too).
    UnknownMux {
        /// The multiplexer signal.
        signal: String,
        /// Its raw value.
        value: i128,
    },
    /// The frame carries signals that a lenient DBC placed where they cannot be read
    /// together: two of one byte order and multiplexing level that share bits, or one
    /// beyond the message (cantools' `strict=False` refuses these frames too: "unpacking
    /// failed").
    Unplaceable(String),
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Short { len, size } => write!(
                f,
                "{len} data bytes, but the message has {size}: the frame is too short"
            ),
            Self::UnknownMux { signal, value } => write!(
                f,
                "multiplexer {signal} = {value} selects no signal of the message"
            ),
            Self::Unplaceable(fault) => write!(
                f,
                "{fault} (kept by --no-strict): the frame carries them and cannot be decoded"
            ),
        }
    }
}

impl std::error::Error for DecodeError {}

fn integral(x: f64) -> Option<i128> {
    (x.is_finite() && x.fract() == 0.0 && x.abs() < 2f64.powi(100)).then_some(x as i128)
}

fn raw_of(signal: &SignalDef, pdu: &[u8; 64], bits: u64) -> Raw {
    match signal.encoding {
        Encoding::Integer(_) => Raw::Int(signal.layout.unpack(pdu).as_i128()),
        Encoding::Float32 => Raw::Float(f64::from(f32::from_bits(bits as u32))),
        Encoding::Float64 => Raw::Float(f64::from_bits(bits)),
    }
}

fn physical_of(signal: &SignalDef, raw: Raw) -> Physical {
    match raw {
        Raw::Int(r) => match (integral(signal.factor), integral(signal.offset)) {
            (Some(f), Some(o)) => r.checked_mul(f).and_then(|v| v.checked_add(o)).map_or(
                Physical::Float(r as f64 * signal.factor + signal.offset),
                Physical::Int,
            ),
            _ => Physical::Float(r as f64 * signal.factor + signal.offset),
        },
        Raw::Float(r) => Physical::Float(r * signal.factor + signal.offset),
    }
}

/// A PDU of 64 bytes holding `data` (at most 64 of its bytes) from the start.
fn pdu_of(data: &[u8]) -> [u8; 64] {
    let mut pdu = [0u8; 64];
    for (to, from) in pdu.iter_mut().zip(data) {
        *to = *from;
    }
    pdu
}

/// Decodes a frame's data with its message: the signals the frame carries (for a
/// multiplexed message, those its multiplexers select), in DBC order. Bytes beyond the
/// message's size are not read (as cantools, which allows them); see [`excess`].
///
/// # Errors
/// [`DecodeError::Short`] when the frame has fewer bytes than the message.
pub fn decode<'a>(message: &'a MessageDef, data: &[u8]) -> Result<Vec<Decoded<'a>>, DecodeError> {
    if data.len() < message.size {
        return Err(DecodeError::Short {
            len: data.len(),
            size: message.size,
        });
    }
    let pdu = pdu_of(data.get(..message.size).unwrap_or(data));
    // Every signal's bits, unpacked once: the multiplexers read them to decide which
    // signals the frame carries, and the output reads them again.
    let unpacked: Vec<(u64, Raw)> = message
        .signals
        .iter()
        .map(|s| {
            let bits = s.layout.unpack_raw(&pdu);
            (bits, raw_of(s, &pdu, bits))
        })
        .collect();
    let raw_int = |j: usize| match unpacked.get(j) {
        Some((_, Raw::Int(v))) => *v,
        _ => -1,
    };
    let present = |i: usize| message.present(i, &raw_int);
    if let Some(fault) = message.fault_in(&present) {
        return Err(DecodeError::Unplaceable(message.describe(fault)));
    }
    let mut out = Vec::new();
    for (i, (signal, &(bits, raw))) in message.signals.iter().zip(&unpacked).enumerate() {
        if !present(i) {
            continue;
        }
        if let (true, Raw::Int(v)) = (signal.is_multiplexer, raw) {
            if !message.mux_value_known(i, v) {
                return Err(DecodeError::UnknownMux {
                    signal: signal.name.clone(),
                    value: v,
                });
            }
        }
        let choice = match raw {
            Raw::Int(r) => signal.choice_name(r),
            Raw::Float(_) => None,
        };
        out.push(Decoded {
            signal,
            raw,
            bits,
            physical: physical_of(signal, raw),
            choice,
        });
    }
    Ok(out)
}

/// How many bytes a frame has beyond its message's size (0 if none).
pub fn excess(message: &MessageDef, data: &[u8]) -> usize {
    data.len().saturating_sub(message.size)
}

/// A value to encode, as an engineer writes it.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// An integer, kept exact.
    Int(i128),
    /// A finite number with a fraction or an exponent.
    Float(f64),
    /// A value table name.
    Name(String),
}

impl Input {
    /// Reads `500`, `-3`, `0.25`, `1e3`, or a name from the signal's value table.
    ///
    /// # Errors
    /// `nan` and infinities, which no signal can hold.
    pub fn parse(text: &str) -> Result<Self, String> {
        if let Ok(v) = text.parse::<i128>() {
            return Ok(Self::Int(v));
        }
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Self::Float(v)),
            Ok(_) => Err(format!("`{text}` is not a finite number")),
            Err(_) => Ok(Self::Name(text.to_string())),
        }
    }

    fn as_f64(&self) -> Option<f64> {
        match self {
            Self::Int(v) => Some(*v as f64),
            Self::Float(v) => Some(*v),
            Self::Name(_) => None,
        }
    }
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(v) => write!(f, "{v}"),
            Self::Float(v) => write!(f, "{v}"),
            Self::Name(n) => f.write_str(n),
        }
    }
}

/// Python's `round` of a float: half to even; `None` when not finite or beyond i128.
fn round_even(x: f64) -> Option<i128> {
    let r = x.round_ties_even();
    (r.is_finite() && r.abs() < 2f64.powi(126)).then_some(r as i128)
}

/// The raw value cantools computes for a physical value (`numeric_scaled_to_raw`).
fn to_raw(signal: &SignalDef, value: &Input) -> Result<Raw, String> {
    let name = &signal.name;
    if let Input::Name(n) = value {
        return match (signal.choice_value(n), signal.encoding) {
            (Some(v), Encoding::Integer(_)) => Ok(Raw::Int(i128::from(v))),
            _ => Err(format!(
                "{name} = `{n}` is neither a number nor a name in the signal's value table"
            )),
        };
    }
    let (f, o) = (signal.factor, signal.offset);
    let identity = f == 1.0 && o == 0.0;
    match signal.encoding {
        Encoding::Float32 | Encoding::Float64 => {
            let x = value.as_f64().unwrap_or(0.0);
            Ok(Raw::Float(if identity { x } else { (x - o) / f }))
        }
        Encoding::Integer(_) => {
            let inexact = || format!("{name} = {value} has no raw value");
            let raw = match (value, integral(f), integral(o)) {
                (Input::Int(v), _, _) if identity => Some(*v),
                // cantools' LinearIntegerConversion: exact when the division is.
                (Input::Int(v), Some(fi), Some(oi)) => match v.checked_sub(oi) {
                    Some(d) if d.checked_rem_euclid(fi) == Some(0) => d.checked_div(fi),
                    Some(d) => round_even(d as f64 / fi as f64),
                    None => None,
                },
                _ => round_even((value.as_f64().unwrap_or(0.0) - o) / f),
            };
            raw.map(Raw::Int).ok_or_else(inexact)
        }
    }
}

/// The frame that carries `values` in `message`: its data as [`encode`] packs it, its id,
/// and CAN FD when the DBC makes the message an FD frame.
///
/// # Errors
/// As [`encode`].
pub fn encode_frame(message: &MessageDef, values: &[(String, Input)]) -> Result<Frame, String> {
    let data = encode(message, values)?;
    Ok(Frame {
        kind: if message.fd {
            FrameKind::Fd {
                brs: false,
                esi: false,
            }
        } else {
            FrameKind::Classic
        },
        ..Frame::classic(message.id, message.extended, &data)
    })
}

/// Encodes physical values into the data of `message` (its size in bytes, the bits no
/// signal covers 0).
///
/// # Errors
/// A sentence naming the signal: not in the message, given twice, missing though the
/// frame carries it, given though its multiplexer deselects it, outside `[min|max]`, not
/// fitting its bits, or a name not in its value table.
pub fn encode(message: &MessageDef, values: &[(String, Input)]) -> Result<Vec<u8>, String> {
    let mname = &message.name;
    let mut given: Vec<Option<(&Input, Raw)>> = vec![None; message.signals.len()];
    for (name, value) in values {
        let i = message
            .signals
            .iter()
            .position(|s| &s.name == name)
            .ok_or_else(|| format!("no signal `{name}` in {mname}"))?;
        let (Some(slot), Some(signal)) = (given.get_mut(i), message.signals.get(i)) else {
            return Err(format!("no signal `{name}` in {mname}"));
        };
        if slot.is_some() {
            return Err(format!("{name} is given twice"));
        }
        let raw = to_raw(signal, value)?;
        let in_table = matches!(raw, Raw::Int(r) if signal.choice_name(r).is_some());
        if let (Some((min, max)), Some(x), false) = (signal.range, value.as_f64(), in_table) {
            let slack = signal.factor.abs() * 1e-6;
            if x < min - slack || x > max + slack {
                return Err(format!(
                    "{name} = {value} is outside the signal's range [{min}|{max}]"
                ));
            }
        }
        *slot = Some((value, raw));
    }
    let mux_raw = |j: usize| match given.get(j) {
        Some(Some((_, Raw::Int(r)))) => *r,
        _ => -1,
    };
    let present = |i: usize| message.present(i, &mux_raw);
    // Lenient faults among the frame's signals: whatever their level or byte order, two
    // signals that share bits cannot both be written.
    if let Some(fault) = message.faults.iter().find(|f| match **f {
        LayoutFault::Outside(i) => present(i),
        LayoutFault::Overlap(a, b) => present(a) && present(b),
        LayoutFault::Unselectable(_) => false,
    }) {
        return Err(format!(
            "{} (kept by --no-strict): a frame that carries them cannot be encoded",
            message.describe(fault)
        ));
    }
    let mut pdu = [0u8; 64];
    for (i, signal) in message.signals.iter().enumerate() {
        let present = present(i);
        let name = &signal.name;
        match (given.get(i).copied().flatten(), present) {
            (None, false) => {}
            (None, true) => {
                return Err(format!(
                    "{name} is missing: every signal of {mname} the frame carries needs a value"
                ))
            }
            (Some(_), false) => {
                return Err(format!(
                    "{name} is not in the frame: its multiplexer does not select it"
                ))
            }
            (Some((value, raw)), true) => {
                if let (true, Raw::Int(v)) = (signal.is_multiplexer, raw) {
                    if !message.mux_value_known(i, v) {
                        return Err(format!(
                            "{name} = {value} selects no signal of {mname} and its value table does not name it"
                        ));
                    }
                }
                pack(signal, raw, value, &mut pdu)?
            }
        }
    }
    Ok(pdu.get(..message.size).unwrap_or(&pdu).to_vec())
}

/// Encodes decoded signals again from their raw values (integers through the signed or
/// unsigned packing, floats by their bits), without scaling or range checks: the inverse
/// of [`decode`] on the bits the signals cover.
///
/// # Errors
/// An integer raw value that does not fit its signal.
pub fn encode_raw(message: &MessageDef, signals: &[Decoded<'_>]) -> Result<Vec<u8>, String> {
    let mut pdu = [0u8; 64];
    for d in signals {
        let value = match d.raw {
            Raw::Int(r) => Input::Int(r),
            Raw::Float(x) => Input::Float(x),
        };
        match d.raw {
            Raw::Int(_) => pack(d.signal, d.raw, &value, &mut pdu)?,
            Raw::Float(_) => d.signal.layout.pack_masked(&mut pdu, d.bits),
        }
    }
    Ok(pdu.get(..message.size).unwrap_or(&pdu).to_vec())
}

fn pack(signal: &SignalDef, raw: Raw, value: &Input, pdu: &mut [u8; 64]) -> Result<(), String> {
    let layout = signal.layout;
    let bits = match (signal.encoding, raw) {
        (Encoding::Float32, Raw::Float(x)) => {
            let single = x as f32;
            if x.is_finite() && !single.is_finite() {
                return Err(format!("{} = {value} does not fit a float", signal.name));
            }
            u64::from(single.to_bits())
        }
        (Encoding::Float64, Raw::Float(x)) => x.to_bits(),
        (Encoding::Integer(sign), Raw::Int(r)) => {
            let (lo, hi) = value_range(layout.length_bits(), sign);
            if r < lo || r > hi {
                return Err(format!(
                    "{} = {value} is raw {r}, which does not fit {} {} bits",
                    signal.name,
                    layout.length_bits(),
                    if sign == Signedness::Signed {
                        "signed"
                    } else {
                        "unsigned"
                    }
                ));
            }
            r as u64
        }
        _ => {
            return Err(format!(
                "{} = {value} does not match the signal's type",
                signal.name
            ))
        }
    };
    layout.pack_masked(pdu, bits);
    Ok(())
}
