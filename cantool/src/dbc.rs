//! A DBC file made ready to decode and encode: every message and signal checked once at
//! load (ids, sizes up to 64 bytes, layouts, float lengths, multiplexers), so that decoding
//! a frame cannot meet a layout it does not know how to read.
//!
//! The bit layout is the ECU's own codec (`cw_core::com::signal`), proved by Kani for
//! every layout of PDUs up to 64 bytes; factor, offset, value tables, IEEE floats and
//! multiplexing (simple, and the extended `SG_MUL_VAL_` form) are applied here, with the
//! semantics cantools gives them.
//!
//! A DBC loads strict ([`Strictness::Strict`], the default: what cantools' `strict=True`
//! refuses is refused) or lenient ([`Strictness::Lenient`], cantools' `strict=False`, the
//! `--no-strict` of `cw-can`): two signals that share bits, or a signal beyond its
//! message, are then kept as a [`LayoutFault`] of the message, reported by
//! [`Database::warnings`], and a frame whose decoding meets one is refused as cantools
//! refuses it (see [`MessageDef::fault_in`]).

use std::collections::HashMap;
use std::fmt;

use can_dbc::{
    AttributeDefinition, AttributeValue, AttributeValueType, ByteOrder as DbcOrder, Dbc, MessageId,
    MultiplexIndicator, NumericValue, SignalExtendedValueType, ValueDescription, ValueType,
};
use cw_core::com::signal::spec::{bit_position, layout_fits};
use cw_core::com::signal::{ByteOrder, SignalLayout, Signedness};

/// How a signal's raw bits are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Two's complement or unsigned integer of the signal's length.
    Integer(Signedness),
    /// IEEE 754 single precision (`SIG_VALTYPE_ ... : 1`), 32 bits.
    Float32,
    /// IEEE 754 double precision (`SIG_VALTYPE_ ... : 2`), 64 bits.
    Float64,
}

/// Where a signal sits in its message's multiplexing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Muxing {
    /// Always present.
    Always,
    /// Present when the multiplexer signal (an index into the message's signals) holds a
    /// raw value in one of the inclusive ranges.
    When {
        /// Index of the multiplexer signal.
        multiplexer: usize,
        /// Inclusive ranges of the multiplexer's raw value.
        values: Vec<(u64, u64)>,
    },
}

/// How a DBC's layout faults are taken (cantools' `strict` argument).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Strictness {
    /// Two signals that can be in one frame sharing bits, or a signal beyond its message,
    /// refuse the DBC.
    #[default]
    Strict,
    /// Such a message is kept with its [`LayoutFault`]s: each is a warning, and only the
    /// frames whose decoding meets one are refused.
    Lenient,
}

/// A layout that strict loading refuses and lenient loading keeps (signals by index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutFault {
    /// Two signals that can be in one frame share bits.
    Overlap(usize, usize),
    /// A signal's bits fall outside the message's bytes.
    Outside(usize),
    /// A signal hangs from a multiplexer that is not an integer multiplexer signal (`M`):
    /// no frame selects it (cantools' lenient load keeps it and never decodes it).
    Unselectable(usize),
}

/// One signal, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalDef {
    /// Name.
    pub name: String,
    /// Bit layout (in a PDU of up to 64 bytes; checked against the message size).
    pub layout: SignalLayout<64>,
    /// Integer or IEEE float.
    pub encoding: Encoding,
    /// Physical = raw * factor + offset.
    pub factor: f64,
    /// See `factor`.
    pub offset: f64,
    /// The DBC's `[min|max]`, or `None` where it is `[0|0]` (no range, as cantools reads it).
    pub range: Option<(f64, f64)>,
    /// Unit.
    pub unit: String,
    /// Value table: raw value and name.
    pub choices: Vec<(i64, String)>,
    /// This signal selects others (`M`, or `mN M`).
    pub is_multiplexer: bool,
    /// When the signal is present.
    pub muxing: Muxing,
}

impl SignalDef {
    /// The value table's name for a raw value.
    pub fn choice_name(&self, raw: i128) -> Option<&str> {
        self.choices
            .iter()
            .find(|(v, _)| i128::from(*v) == raw)
            .map(|(_, n)| n.as_str())
    }

    /// The raw value of a value table name.
    pub fn choice_value(&self, name: &str) -> Option<i64> {
        self.choices
            .iter()
            .find(|(_, n)| n == name)
            .map(|(v, _)| *v)
    }
}

/// One message, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageDef {
    /// Name.
    pub name: String,
    /// Identifier: 11 bits, or 29 when `extended`.
    pub id: u32,
    /// A 29-bit identifier (the DBC id has bit 31 set).
    pub extended: bool,
    /// Length in bytes (0 to 64).
    pub size: usize,
    /// Sent as a CAN FD frame: the DBC's `VFrameFormat` says so (`StandardCAN_FD`,
    /// `ExtendedCAN_FD`), or the message is longer than 8 bytes.
    pub fd: bool,
    /// Signals in DBC order.
    pub signals: Vec<SignalDef>,
    /// What a lenient load kept that a strict one refuses (always empty when strict).
    pub faults: Vec<LayoutFault>,
}

impl MessageDef {
    /// Whether signal `i` is present in a PDU, given its multiplexers' raw values as
    /// `raw(j)`. A signal is present when its multiplexer is present and holds a selecting
    /// value; the load refused cycles, so the walk ends (and is bounded anyway).
    pub fn present(&self, i: usize, raw: &impl Fn(usize) -> i128) -> bool {
        let mut at = i;
        for _ in 0..=self.signals.len() {
            let Some(signal) = self.signals.get(at) else {
                return false;
            };
            match &signal.muxing {
                Muxing::Always => return true,
                Muxing::When {
                    multiplexer,
                    values,
                } => {
                    let v = raw(*multiplexer);
                    if !values
                        .iter()
                        .any(|(lo, hi)| i128::from(*lo) <= v && v <= i128::from(*hi))
                    {
                        return false;
                    }
                    at = *multiplexer;
                }
            }
        }
        false
    }
}

impl MessageDef {
    /// Whether the multiplexer signal `m` holding `value` selects any signal.
    pub fn selects(&self, m: usize, value: i128) -> bool {
        self.signals.iter().any(|s| match &s.muxing {
            Muxing::When {
                multiplexer,
                values,
            } => {
                *multiplexer == m
                    && values
                        .iter()
                        .any(|(lo, hi)| i128::from(*lo) <= value && value <= i128::from(*hi))
            }
            Muxing::Always => false,
        })
    }

    /// Whether any signal hangs from the multiplexer signal `m`.
    pub fn has_children(&self, m: usize) -> bool {
        self.signals
            .iter()
            .any(|s| matches!(&s.muxing, Muxing::When { multiplexer, .. } if *multiplexer == m))
    }

    /// Whether the multiplexer signal `m` may hold `value` in a frame, as cantools decides:
    /// its known values are those that select a signal and those its value table names
    /// (a named value may select nothing: the frame then carries the multiplexer alone);
    /// a multiplexer with neither may hold any value.
    pub fn mux_value_known(&self, m: usize, value: i128) -> bool {
        let named = self
            .signals
            .get(m)
            .map_or(&[][..], |s| s.choices.as_slice());
        (!self.has_children(m) && named.is_empty())
            || self.selects(m, value)
            || named.iter().any(|(v, _)| i128::from(*v) == value)
    }

    /// The first of the message's [`LayoutFault`]s that a frame carrying the signals
    /// `present` says are there meets, as cantools' decoding meets it: it reads each
    /// multiplexing level (the signals always there, or those one multiplexer value
    /// selects) in one pass per byte order, which cannot place a signal beyond the message
    /// nor two that share bits ("unpacking failed"). Two signals of different byte
    /// orders, or of different levels, that share bits are each read from their own bits.
    pub fn fault_in(&self, present: &impl Fn(usize) -> bool) -> Option<&LayoutFault> {
        let parent = |i: usize| match self.signals.get(i).map(|s| &s.muxing) {
            Some(Muxing::When { multiplexer, .. }) => Some(*multiplexer),
            _ => None,
        };
        let order = |i: usize| self.signals.get(i).map(|s| s.layout.byte_order());
        self.faults.iter().find(|f| match **f {
            LayoutFault::Outside(i) => present(i),
            LayoutFault::Unselectable(_) => false,
            LayoutFault::Overlap(a, b) => {
                present(a) && present(b) && parent(a) == parent(b) && order(a) == order(b)
            }
        })
    }

    /// A fault in words, with the signals' names.
    pub fn describe(&self, fault: &LayoutFault) -> String {
        let name = |i: usize| self.signals.get(i).map_or("?", |s| s.name.as_str());
        match *fault {
            LayoutFault::Overlap(a, b) => {
                format!(
                    "message {}: signals {} and {} share bits",
                    self.name,
                    name(a),
                    name(b)
                )
            }
            LayoutFault::Outside(i) => {
                let (start, len, order) = self.signals.get(i).map_or((0, 0, 1), |s| {
                    let l = &s.layout;
                    let order = u8::from(l.byte_order() == ByteOrder::Intel);
                    (l.start_bit(), l.length_bits(), order)
                });
                format!(
                    "message {}: signal {}: bits {start}|{len}@{order} fall outside the message's {} bytes",
                    self.name,
                    name(i),
                    self.size
                )
            }
            LayoutFault::Unselectable(i) => {
                let by = match self.signals.get(i).map(|s| &s.muxing) {
                    Some(Muxing::When { multiplexer, .. }) => name(*multiplexer),
                    _ => "?",
                };
                format!(
                    "message {}: signal {}: its multiplexer {by} is not an integer multiplexer signal (M): no frame carries it",
                    self.name,
                    name(i)
                )
            }
        }
    }

    /// Whether signals `a` and `b` can be in one frame: not when both hang, through
    /// their chains of multiplexers, from one multiplexer under values that never meet.
    pub fn can_coexist(&self, a: usize, b: usize) -> bool {
        let chain = |mut at: usize| {
            let mut links = Vec::new();
            for _ in 0..=self.signals.len() {
                match self.signals.get(at).map(|s| &s.muxing) {
                    Some(Muxing::When {
                        multiplexer,
                        values,
                    }) => {
                        links.push((*multiplexer, values.clone()));
                        at = *multiplexer;
                    }
                    _ => break,
                }
            }
            links
        };
        let (ca, cb) = (chain(a), chain(b));
        !ca.iter().any(|(ma, va)| {
            cb.iter().any(|(mb, vb)| {
                ma == mb
                    && !va
                        .iter()
                        .any(|(l1, h1)| vb.iter().any(|(l2, h2)| l1 <= h2 && l2 <= h1))
            })
        })
    }
}

/// The PDU bits (`byte * 8 + bit`) a signal occupies.
fn bits_of(layout: &SignalLayout<64>) -> [u64; 8] {
    let mut set = [0u64; 8];
    for i in 0..layout.length_bits() {
        let p = bit_position(
            layout.start_bit(),
            layout.length_bits(),
            layout.byte_order(),
            i,
        );
        if let Some(word) = set.get_mut(p / 64) {
            *word |= 1 << (p % 64);
        }
    }
    set
}

/// Why a DBC was refused: the message and signal, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DbcError(pub String);

impl fmt::Display for DbcError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DbcError {}

/// A loaded DBC: its messages, found by id or by name.
#[derive(Debug, Clone)]
pub struct Database {
    messages: Vec<MessageDef>,
    by_id: HashMap<(u32, bool), usize>,
}

fn number(v: &NumericValue) -> f64 {
    match v {
        NumericValue::Uint(u) => *u as f64,
        NumericValue::Int(i) => *i as f64,
        NumericValue::Double(d) => *d,
    }
}

fn is_plain_zero(v: &NumericValue) -> bool {
    matches!(v, NumericValue::Uint(0) | NumericValue::Int(0))
}

/// The DBC ids as written after `BO_`, in file order: `can-dbc` truncates an 11-bit id
/// written above 0x7FF, so the text is asked what it said.
fn written_ids(text: &str) -> Vec<u64> {
    text.lines()
        .filter_map(|line| {
            let rest = line.trim_start().strip_prefix("BO_ ")?;
            rest.split_whitespace().next()?.parse::<u64>().ok()
        })
        .collect()
}

/// Decodes a DBC file's bytes: UTF-8 (with or without a byte order mark), else
/// Windows-1252, the encoding CANdb++ writes.
pub fn text_of(bytes: &[u8]) -> String {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(text) => text.to_string(),
        Err(_) => can_dbc::decode_cp1252(bytes)
            .map(|t| t.into_owned())
            // Windows-1252 leaves five bytes undefined; keep what can be read.
            .unwrap_or_else(|| String::from_utf8_lossy(bytes).into_owned()),
    }
}

impl Database {
    /// Reads and loads a DBC file.
    ///
    /// # Errors
    /// The file cannot be read, or [`Self::from_bytes`] refuses it; the sentence names the
    /// file.
    pub fn load(path: &std::path::Path) -> Result<Self, String> {
        Self::load_with(path, Strictness::Strict)
    }

    /// Reads and loads a DBC file, strict or lenient.
    ///
    /// # Errors
    /// As [`Self::load`].
    pub fn load_with(path: &std::path::Path, strictness: Strictness) -> Result<Self, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Self::from_text_with(&text_of(&bytes), strictness)
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Loads a DBC file's bytes (see [`text_of`] for the encodings).
    ///
    /// # Errors
    /// The parser's complaint, or the first message or signal that cannot be decoded,
    /// named: a size above 64 bytes, a standard id above 0x7FF, a signal outside its
    /// message, a float of the wrong length, an unknown multiplexer, no message at all.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DbcError> {
        Self::from_text(&text_of(bytes))
    }

    /// Loads a DBC's text.
    ///
    /// # Errors
    /// As [`Self::from_bytes`].
    pub fn from_text(text: &str) -> Result<Self, DbcError> {
        Self::from_text_with(text, Strictness::Strict)
    }

    /// Loads a DBC's text, strict or lenient.
    ///
    /// # Errors
    /// As [`Self::from_bytes`]; lenient, a signal beyond its message or two signals that
    /// share bits are kept as [`LayoutFault`]s instead.
    pub fn from_text_with(text: &str, strictness: Strictness) -> Result<Self, DbcError> {
        let dbc = Dbc::try_from(text).map_err(|e| DbcError(format!("does not parse: {e}")))?;
        let written = written_ids(text);
        let mut messages = Vec::new();
        for (n, message) in dbc.messages.iter().enumerate() {
            // `VECTOR__INDEPENDENT_SIG_MSG` holds signals of no message (CANdb++'s
            // pseudo-message, id 0xC0000000): no frame carries it.
            if message.name == "VECTOR__INDEPENDENT_SIG_MSG" {
                continue;
            }
            if let Some(w) = written.get(n) {
                if *w < 1 << 31 && *w > 0x7FF {
                    return Err(DbcError(format!(
                        "message {}: id {w} (0x{w:X}) is more than 11 bits but has no extended flag (bit 31: write it as {})",
                        message.name,
                        w | 1 << 31
                    )));
                }
            }
            messages.push(load_message(&dbc, message, strictness)?);
        }
        if messages.is_empty() {
            return Err(DbcError("holds no message (BO_)".into()));
        }
        let mut by_id = HashMap::new();
        for (i, m) in messages.iter().enumerate() {
            if let Some(j) = by_id.insert((m.id, m.extended), i) {
                let other = messages.get(j).map_or("", |o| o.name.as_str());
                return Err(DbcError(format!(
                    "messages {other} and {} have the same id 0x{:X}",
                    m.name, m.id
                )));
            }
        }
        Ok(Self { messages, by_id })
    }

    /// What a lenient load kept that a strict one refuses, one sentence per fault naming
    /// message and signals (empty when strict).
    pub fn warnings(&self) -> Vec<String> {
        self.messages
            .iter()
            .flat_map(|m| m.faults.iter().map(|f| m.describe(f)))
            .collect()
    }

    /// Every message, in DBC order.
    pub fn messages(&self) -> &[MessageDef] {
        &self.messages
    }

    /// The message of an id.
    pub fn by_id(&self, id: u32, extended: bool) -> Option<&MessageDef> {
        self.by_id
            .get(&(id, extended))
            .and_then(|i| self.messages.get(*i))
    }

    /// The message of a name.
    pub fn by_name(&self, name: &str) -> Option<&MessageDef> {
        self.messages.iter().find(|m| m.name == name)
    }
}

/// Whether the DBC's `VFrameFormat` attribute makes a message a CAN FD frame. The value is
/// an index into the attribute's enumeration (CANdb++ lists `StandardCAN_FD` at 14 and
/// `ExtendedCAN_FD` at 15), or the name itself.
fn fd_by_attribute(dbc: &Dbc, id: MessageId) -> bool {
    let names: Option<&Vec<String>> = dbc.attribute_definitions.iter().find_map(|d| match d {
        AttributeDefinition::Message(name, AttributeValueType::Enum(values))
            if name == "VFrameFormat" =>
        {
            Some(values)
        }
        _ => None,
    });
    let is_fd = |name: &str| name.ends_with("_FD");
    dbc.attribute_values_message
        .iter()
        .find(|a| a.name == "VFrameFormat" && a.message_id == id)
        .is_some_and(|a| {
            // An enumeration's value is an index into its names; without the definition,
            // 14 and 15 are CANoe's `CAN_FD` and `CAN_FD_BRS`.
            let index = match &a.value {
                AttributeValue::String(name) => return is_fd(name),
                AttributeValue::Uint(i) => i128::from(*i),
                AttributeValue::Int(i) => i128::from(*i),
                AttributeValue::Double(_) => return false,
            };
            match names {
                Some(names) => usize::try_from(index)
                    .ok()
                    .and_then(|i| names.get(i))
                    .is_some_and(|n| is_fd(n)),
                None => matches!(index, 14 | 15),
            }
        })
}

fn load_message(
    dbc: &Dbc,
    message: &can_dbc::Message,
    strictness: Strictness,
) -> Result<MessageDef, DbcError> {
    let name = &message.name;
    let err = |what: String| DbcError(format!("message {name}: {what}"));
    let (id, extended) = match message.id {
        MessageId::Standard(id) => (u32::from(id), false),
        MessageId::Extended(id) => (id, true),
    };
    let size = usize::try_from(message.size)
        .ok()
        .filter(|s| *s <= 64)
        .ok_or_else(|| {
            err(format!(
                "{} bytes; a CAN FD frame holds at most 64",
                message.size
            ))
        })?;
    let names: Vec<&str> = message.signals.iter().map(|s| s.name.as_str()).collect();
    let simple_mux = message
        .signals
        .iter()
        .position(|s| s.multiplexer_indicator == MultiplexIndicator::Multiplexor);
    let extended_mux: Vec<_> = dbc
        .extended_multiplex
        .iter()
        .filter(|x| x.message_id == message.id)
        .collect();
    let mut signals = Vec::new();
    let mut faults = Vec::new();
    for s in &message.signals {
        let serr = |what: String| err(format!("signal {}: {what}", s.name));
        let order = match s.byte_order {
            DbcOrder::LittleEndian => ByteOrder::Intel,
            DbcOrder::BigEndian => ByteOrder::Motorola,
        };
        let sign = match s.value_type {
            ValueType::Signed => Signedness::Signed,
            ValueType::Unsigned => Signedness::Unsigned,
        };
        let start = u16::try_from(s.start_bit).map_err(|_| serr("start bit too large".into()))?;
        let len = u8::try_from(s.size)
            .ok()
            .filter(|l| (1..=64).contains(l))
            .ok_or_else(|| serr(format!("{} bits; a signal has 1 to 64", s.size)))?;
        let outside = || {
            serr(format!(
                "bits {start}|{len}@{} fall outside the message's {size} bytes",
                u8::from(order == ByteOrder::Intel)
            ))
        };
        if !layout_fits(size.max(1), start, len, order) || size == 0 {
            // Lenient, a signal beyond its message is kept where a frame of 64 bytes
            // would hold it; beyond that, no frame does.
            if strictness == Strictness::Strict || !layout_fits(64, start, len, order) {
                return Err(outside());
            }
            faults.push(LayoutFault::Outside(signals.len()));
        }
        let layout =
            SignalLayout::<64>::new(start, len, order, sign).map_err(|e| serr(format!("{e:?}")))?;
        let encoding = match dbc
            .signal_extended_value_type_list
            .iter()
            .find(|t| t.message_id == message.id && t.signal_name == s.name)
            .map(|t| t.signal_extended_value_type)
        {
            None | Some(SignalExtendedValueType::SignedOrUnsignedInteger) => {
                Encoding::Integer(sign)
            }
            Some(SignalExtendedValueType::IEEEfloat32Bit) if len == 32 => Encoding::Float32,
            Some(SignalExtendedValueType::IEEEdouble64bit) if len == 64 => Encoding::Float64,
            Some(t) => return Err(serr(format!("{t:?} needs 32 or 64 bits, has {len}"))),
        };
        if !s.factor.is_finite() || s.factor == 0.0 || !s.offset.is_finite() {
            return Err(serr(format!(
                "factor {} and offset {}: the factor must be finite and not 0",
                s.factor, s.offset
            )));
        }
        let range = (!(is_plain_zero(&s.min) && is_plain_zero(&s.max)))
            .then(|| (number(&s.min), number(&s.max)));
        let choices = dbc
            .value_descriptions
            .iter()
            .find_map(|d| match d {
                ValueDescription::Signal {
                    message_id,
                    name,
                    value_descriptions,
                } if *message_id == message.id && *name == s.name => Some(
                    value_descriptions
                        .iter()
                        .map(|v| (v.id, v.description.clone()))
                        .collect(),
                ),
                _ => None,
            })
            .unwrap_or_default();
        let is_multiplexer = matches!(
            s.multiplexer_indicator,
            MultiplexIndicator::Multiplexor
                | MultiplexIndicator::MultiplexorAndMultiplexedSignal(_)
        );
        let index_of = |n: &str| {
            names
                .iter()
                .position(|x| *x == n)
                .ok_or_else(|| serr(format!("multiplexed by `{n}`, which is not in the message")))
        };
        let muxing = if let Some(x) = extended_mux.iter().find(|x| x.signal_name == s.name) {
            Muxing::When {
                multiplexer: index_of(&x.multiplexor_signal_name)?,
                values: x
                    .mappings
                    .iter()
                    .map(|m| (m.min_value, m.max_value))
                    .collect(),
            }
        } else {
            match s.multiplexer_indicator {
                MultiplexIndicator::Plain | MultiplexIndicator::Multiplexor => Muxing::Always,
                MultiplexIndicator::MultiplexedSignal(v)
                | MultiplexIndicator::MultiplexorAndMultiplexedSignal(v) => Muxing::When {
                    multiplexer: simple_mux.ok_or_else(|| {
                        serr(format!(
                            "multiplexed (m{v}) but the message has no multiplexer (M)"
                        ))
                    })?,
                    values: vec![(v, v)],
                },
            }
        };
        signals.push(SignalDef {
            name: s.name.clone(),
            layout,
            encoding,
            factor: s.factor,
            offset: s.offset,
            range,
            unit: s.unit.clone(),
            choices,
            is_multiplexer,
            muxing,
        });
    }
    // Every multiplexer must be an integer multiplexer signal (lenient: a signal that
    // hangs from another kind is never selected), and the chains must end.
    let mut unselectable = Vec::new();
    for (i, s) in signals.iter().enumerate() {
        if let Muxing::When { multiplexer, .. } = s.muxing {
            let m = signals.get(multiplexer);
            if !m.is_some_and(|m| m.is_multiplexer && matches!(m.encoding, Encoding::Integer(_))) {
                if strictness == Strictness::Lenient && m.is_some() {
                    unselectable.push(i);
                    continue;
                }
                return Err(err(format!(
                    "signal {}: its multiplexer {} is not an integer multiplexer signal (M)",
                    s.name,
                    m.map_or("?", |m| m.name.as_str())
                )));
            }
        }
        let mut at = i;
        let mut steps = 0;
        while let Some(Muxing::When { multiplexer, .. }) = signals.get(at).map(|s| &s.muxing) {
            at = *multiplexer;
            steps += 1;
            if steps > signals.len() {
                return Err(err(format!(
                    "signal {}: its multiplexers form a cycle",
                    s.name
                )));
            }
        }
    }
    for i in unselectable {
        if let Some(Muxing::When { values, .. }) = signals.get_mut(i).map(|s| &mut s.muxing) {
            values.clear();
        }
        faults.push(LayoutFault::Unselectable(i));
    }
    let mut message = MessageDef {
        name: name.clone(),
        id,
        extended,
        size,
        fd: size > 8 || fd_by_attribute(dbc, message.id),
        signals,
        faults,
    };
    // Two signals that can be in one frame must not share a bit (cantools refuses them too).
    let bits: Vec<_> = message.signals.iter().map(|s| bits_of(&s.layout)).collect();
    let mut overlaps = Vec::new();
    for (i, (a, bits_a)) in message.signals.iter().zip(&bits).enumerate() {
        for (j, (b, bits_b)) in message.signals.iter().zip(&bits).enumerate().skip(i + 1) {
            let shared = bits_a.iter().zip(bits_b).any(|(x, y)| x & y != 0);
            if shared && message.can_coexist(i, j) {
                if strictness == Strictness::Strict {
                    return Err(err(format!("signals {} and {} share bits", a.name, b.name)));
                }
                overlaps.push(LayoutFault::Overlap(i, j));
            }
        }
    }
    message.faults.append(&mut overlaps);
    Ok(message)
}
