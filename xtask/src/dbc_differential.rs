//! `cargo xtask dbc-differential`: `cw-can`'s DBC decoding and encoding against cantools,
//! on DBCs generated at random from a seeded generator (replay a run with its printed
//! seed).
//!
//! Each DBC holds messages of 1 to 64 bytes (classic and FD), with 11- and 29-bit ids,
//! signals of both byte orders, signed and unsigned, integer and IEEE float and double,
//! factors and offsets (integer and fractional), `[min|max]` ranges, value tables, and
//! multiplexing: none, simple (`M`, `mN`), or extended (`SG_MUL_VAL_` value ranges and a
//! nested multiplexer). For every message, frames:
//! - decode: random bytes (most with a multiplexer value that selects signals, some
//!   shorter than the message, some longer); cantools and `cw-can` must both refuse, or
//!   give the same signals with the same values (value-table names where there are);
//! - encode: values for the signals the frame carries, chosen from each signal's raw range
//!   (some by value-table name, some just outside the range or the bits, some with a
//!   signal missing); both must refuse, or give the same bytes.
//!
//! `tools/dbc_differential.py` runs cantools on the cases; this module generates them,
//! computes `cw-can`'s answers (the library the command uses), and compares.

use crate::process::target_dir;
use crate::rng::Rng;
use crate::Result;
use cw_can::codec::{self, Input, Physical};
use cw_can::dbc::{Database, MessageDef, Strictness};
use cw_can::report::hex;
use cw_core::com::signal::spec::{bit_position, layout_fits};
use cw_core::com::signal::ByteOrder;
use std::fmt::Write as _;

/// Messages per generated DBC.
const MESSAGES_PER_DBC: usize = 12;
/// Frames per message (half decoded, half encoded).
const FRAMES_PER_MESSAGE: usize = 20;
/// Message sizes drawn (classic CAN more often).
const SIZES: &[usize] = &[1, 2, 3, 4, 5, 6, 7, 8, 8, 8, 8, 12, 16, 20, 24, 32, 48, 64];
/// Integer conversions `(factor, offset)` as written in the DBC.
const INT_CONVERSIONS: &[(&str, &str)] = &[
    ("1", "0"),
    ("1", "0"),
    ("2", "-100"),
    ("3", "7"),
    ("-1", "0"),
    ("0.5", "0"),
    ("0.1", "-40"),
    ("0.001", "0.5"),
    ("0.25", "1.5"),
    ("0.01", "0"),
];
/// Float signal conversions.
const FLOAT_CONVERSIONS: &[(&str, &str)] = &[("1", "0"), ("2", "1"), ("0.5", "-3")];
/// How many disagreements to print in full.
const SHOW: usize = 5;

/// The default `--frames`.
const FRAMES: u64 = 12_000;

/// Options of `cargo xtask dbc-differential`.
#[derive(clap::Args)]
pub struct Options {
    /// At least this many frames (decoded and encoded)
    #[arg(long, default_value_t = FRAMES, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: u64,
    #[command(flatten)]
    pub seed: crate::rng::Seed,
    /// Also compare on these DBC files (a public corpus such as opendbc's), both sides
    /// loading them leniently (cantools' `strict=False`, `cw-can --no-strict`): whether
    /// each loads, then random frames of every message decoded
    #[arg(long = "dbc", value_name = "FILE")]
    pub corpus: Vec<std::path::PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            frames: FRAMES,
            seed: crate::rng::Seed::default(),
            corpus: Vec::new(),
        }
    }
}

/// Every third generated DBC is loaded leniently, with faults in its messages.
const LENIENT_EVERY: usize = 3;

/// Where a generated signal hangs in the multiplexing.
#[derive(Clone)]
enum Mux {
    Plain,
    /// The message's multiplexer (`M`).
    Root,
    /// `mN`, simple multiplexing.
    Simple(u64),
    /// Extended: `m{first}` or `m{first}M`, and `SG_MUL_VAL_ sig by ranges`.
    Extended {
        by: String,
        ranges: Vec<(u64, u64)>,
        is_mux: bool,
    },
    /// A lone lower-case `m` (as opendbc's `vw_pq.dbc` writes `MO2_Mp_Code`): not a
    /// multiplexer, though `SG_MUL_VAL_` lines hang signals from it.
    LoneM,
}

struct Sig {
    name: String,
    start: u16,
    len: u8,
    order: ByteOrder,
    signed: bool,
    /// 0 integer, 1 IEEE float, 2 IEEE double.
    float: u8,
    factor: &'static str,
    offset: &'static str,
    range: Option<(String, String)>,
    /// The raw values at the ends of `range`.
    range_raw: Option<(i128, i128)>,
    mux: Mux,
    choices: Vec<(i64, String)>,
}

struct Msg {
    name: String,
    /// As written after `BO_` (bit 31 for a 29-bit id).
    dbc_id: u32,
    size: usize,
    sigs: Vec<Sig>,
}

type Bits = [u64; 8];

fn bits_of(start: u16, len: u8, order: ByteOrder) -> Bits {
    let mut set = [0u64; 8];
    for i in 0..len {
        let p = bit_position(start, len, order, i);
        if let Some(w) = set.get_mut(p / 64) {
            *w |= 1 << (p % 64);
        }
    }
    set
}

fn overlaps(a: &Bits, b: &Bits) -> bool {
    a.iter().zip(b).any(|(x, y)| x & y != 0)
}

fn add(a: &mut Bits, b: &Bits) {
    for (x, y) in a.iter_mut().zip(b) {
        *x |= y;
    }
}

/// A free place for a signal of `len` bits (any start bit, either order) in `size` bytes.
fn place(rng: &mut Rng, occupied: &mut Bits, size: usize, len: u8) -> Option<(u16, ByteOrder)> {
    for _ in 0..40 {
        let order = if rng.one_in(2) {
            ByteOrder::Intel
        } else {
            ByteOrder::Motorola
        };
        let start = rng.below(size as u64 * 8) as u16;
        if !layout_fits(size, start, len, order) {
            continue;
        }
        let bits = bits_of(start, len, order);
        if !overlaps(occupied, &bits) {
            add(occupied, &bits);
            return Some((start, order));
        }
    }
    None
}

fn int_len(rng: &mut Rng, size: usize) -> u8 {
    let most = (size * 8).min(64) as u64;
    if rng.one_in(3) {
        rng.pick(&[1u8, 2, 7, 8, 9, 15, 16, 17, 31, 32, 33, 63, 64], 8)
            .min(most as u8)
    } else {
        (1 + rng.below(most.min(24))) as u8
    }
}

/// A data signal (not a multiplexer) placed in `occupied`, or `None` if nothing fits.
fn data_signal(
    rng: &mut Rng,
    occupied: &mut Bits,
    size: usize,
    name: String,
    mux: Mux,
) -> Option<Sig> {
    let float = if rng.one_in(6) {
        if rng.one_in(2) {
            1
        } else {
            2
        }
    } else {
        0
    };
    let len = match float {
        1 => 32,
        2 => 64,
        _ => int_len(rng, size),
    };
    let (start, order) = place(rng, occupied, size, len)?;
    let signed = rng.one_in(2);
    let (factor, offset) = if float > 0 {
        rng.pick(FLOAT_CONVERSIONS, ("1", "0"))
    } else {
        rng.pick(INT_CONVERSIONS, ("1", "0"))
    };
    let mut sig = Sig {
        name,
        start,
        len,
        order,
        signed,
        float,
        factor,
        offset,
        range: None,
        range_raw: None,
        mux,
        choices: Vec::new(),
    };
    if float == 0 && len <= 32 {
        let (lo, hi) = raw_range(&sig);
        if rng.one_in(3) {
            // A range inside the raw range, so that encoding meets it.
            let a = lo + i128::from(rng.below((hi - lo + 1) as u64 / 2 + 1));
            let b = hi - i128::from(rng.below((hi - lo + 1) as u64 / 2 + 1));
            let (pa, pb) = (physical_text(&sig, a), physical_text(&sig, b));
            let (fa, fb) = (
                pa.parse::<f64>().unwrap_or(0.0),
                pb.parse::<f64>().unwrap_or(0.0),
            );
            sig.range = Some(if fa <= fb { (pa, pb) } else { (pb, pa) });
            sig.range_raw = Some((a.min(b), a.max(b)));
        }
        if rng.one_in(4) && len <= 16 {
            let mut used = Vec::new();
            for k in 0..1 + rng.below(3) {
                let v = lo + i128::from(rng.below((hi - lo + 1) as u64));
                if !used.contains(&v) {
                    used.push(v);
                    sig.choices.push((v as i64, format!("Choice{k}")));
                }
            }
        }
    }
    Some(sig)
}

fn raw_range(sig: &Sig) -> (i128, i128) {
    if sig.signed {
        (-(1i128 << (sig.len - 1)), (1i128 << (sig.len - 1)) - 1)
    } else {
        (0, (1i128 << sig.len) - 1)
    }
}

fn integral(text: &str) -> Option<i128> {
    text.parse::<i128>().ok()
}

/// The physical value of raw `r` as text: an exact integer for integer conversions (as
/// cantools computes it), else Python's float arithmetic `r * factor + offset`.
fn physical_text(sig: &Sig, r: i128) -> String {
    match (integral(sig.factor), integral(sig.offset)) {
        (Some(f), Some(o)) => format!("{}", r * f + o),
        _ => {
            let f: f64 = sig.factor.parse().unwrap_or(1.0);
            let o: f64 = sig.offset.parse().unwrap_or(0.0);
            format!("{:?}", r as f64 * f + o)
        }
    }
}

/// A multiplexer signal: unsigned, factor 1, offset 0, no range or table.
fn multiplexer(name: &str, start: u16, len: u8, order: ByteOrder, mux: Mux) -> Sig {
    Sig {
        name: name.into(),
        start,
        len,
        order,
        signed: false,
        float: 0,
        factor: "1",
        offset: "0",
        range: None,
        range_raw: None,
        mux,
        choices: Vec::new(),
    }
}

/// Signals a lenient DBC adds to a message without looking where the others are: most
/// share bits with some (of either byte order, at the message's level or a multiplexed
/// one), some lie beyond the message (within 64 bytes).
fn stray_signals(rng: &mut Rng, msg: &mut Msg) {
    for k in 0..1 + rng.below(2) {
        let len = int_len(rng, msg.size.min(8));
        let order = if rng.one_in(2) {
            ByteOrder::Intel
        } else {
            ByteOrder::Motorola
        };
        let span = ((msg.size + 2).min(64) * 8) as u64;
        let Some(start) = (0..20)
            .map(|_| rng.below(span) as u16)
            .find(|start| layout_fits(64, *start, len, order))
        else {
            continue;
        };
        // At the message's level, or beside a multiplexed signal.
        let mux = match msg.sigs.get(rng.below(msg.sigs.len() as u64 + 1) as usize) {
            Some(Sig {
                mux: Mux::Simple(v),
                ..
            }) => Mux::Simple(*v),
            Some(Sig {
                mux: Mux::Extended { by, ranges, .. },
                ..
            }) => Mux::Extended {
                by: by.clone(),
                ranges: ranges.clone(),
                is_mux: false,
            },
            _ => Mux::Plain,
        };
        let mut sig = multiplexer(&format!("X{k}"), start, len, order, mux);
        sig.signed = rng.one_in(2);
        msg.sigs.push(sig);
    }
    // A lone `m` with signals hung from it, now and then, in a message without `M` (as
    // in `vw_pq.dbc`; beside an `M`, cantools reads the lone `m` as `m<id>` and refuses
    // the DBC).
    let has_m = msg.sigs.iter().any(|s| matches!(s.mux, Mux::Root));
    if !has_m && rng.one_in(6) {
        let (start, order) = (0, ByteOrder::Intel);
        msg.sigs
            .push(multiplexer("Code", start, 2, order, Mux::LoneM));
        let by = Mux::Extended {
            by: "Code".into(),
            ranges: vec![(1, 1)],
            is_mux: false,
        };
        msg.sigs.push(multiplexer("ByCode", 2, 4, order, by));
    }
}

fn gen_message(rng: &mut Rng, index: usize, used_ids: &mut Vec<u32>) -> Msg {
    let size = rng.pick(SIZES, 8);
    let extended = rng.one_in(3);
    let dbc_id = loop {
        let id = if extended {
            (rng.below(1 << 29) as u32) | 1 << 31
        } else {
            rng.below(0x800) as u32
        };
        if !used_ids.contains(&id) {
            used_ids.push(id);
            break id;
        }
    };
    let mut base: Bits = [0; 8];
    let mut sigs = Vec::new();
    let mode = if size * 8 < 16 { 0 } else { rng.below(4) };
    let mut sel = None;
    if mode >= 2 {
        let len = (2 + rng.below(5)) as u8;
        if let Some((start, order)) = place(rng, &mut base, size, len) {
            sel = Some(sigs.len());
            sigs.push(multiplexer("Sel", start, len, order, Mux::Root));
        }
    }
    for k in 0..1 + rng.below(3) {
        if let Some(s) = data_signal(rng, &mut base, size, format!("P{k}"), Mux::Plain) {
            sigs.push(s);
        }
    }
    if let Some(sel) = sel.and_then(|i| sigs.get(i)).map(|s| s.len) {
        let top = (1u64 << sel) - 1;
        // Names for some of the selector's values, selecting signals or not (a named value
        // that selects none decodes as the multiplexer alone).
        if rng.one_in(3) {
            if let Some(s) = sigs.iter_mut().find(|s| matches!(s.mux, Mux::Root)) {
                for k in 0..1 + rng.below(3) {
                    let v = rng.below(top + 1) as i64;
                    if !s.choices.iter().any(|(c, _)| *c == v) {
                        s.choices.push((v, format!("Kind{k}")));
                    }
                }
            }
        }
        if mode == 2 {
            // Simple: a few distinct selector values, each with its own signals.
            let mut values: Vec<u64> = Vec::new();
            for _ in 0..1 + rng.below(3) {
                let v = rng.below(top + 1);
                if !values.contains(&v) {
                    values.push(v);
                }
            }
            for v in values {
                let mut occ = base;
                for k in 0..1 + rng.below(2) {
                    let name = format!("G{v}S{k}");
                    if let Some(s) = data_signal(rng, &mut occ, size, name, Mux::Simple(v)) {
                        sigs.push(s);
                    }
                }
            }
        } else {
            // Extended: disjoint value ranges of Sel; the first group also holds a nested
            // multiplexer `Sub` with signals of its own.
            let mut cuts: Vec<u64> = (0..2 + rng.below(3)).map(|_| rng.below(top + 1)).collect();
            cuts.sort_unstable();
            cuts.dedup();
            let ranges: Vec<(u64, u64)> = cuts
                .windows(2)
                .map(|w| (w[0], w[1].saturating_sub(1).max(w[0])))
                .chain(cuts.last().map(|l| (*l, *l)))
                .collect();
            let mut ranges = ranges;
            ranges.dedup();
            ranges.retain(|(lo, hi)| lo <= hi);
            for (g, (lo, hi)) in ranges.iter().enumerate() {
                let mut occ = base;
                let by = || Mux::Extended {
                    by: "Sel".into(),
                    ranges: vec![(*lo, *hi)],
                    is_mux: false,
                };
                if let Some(s) = data_signal(rng, &mut occ, size, format!("R{g}"), by()) {
                    sigs.push(s);
                }
                if g == 0 {
                    let len = (1 + rng.below(3)) as u8;
                    if let Some((start, order)) = place(rng, &mut occ, size, len) {
                        let mux = Mux::Extended {
                            by: "Sel".into(),
                            ranges: vec![(*lo, *hi)],
                            is_mux: true,
                        };
                        sigs.push(multiplexer("Sub", start, len, order, mux));
                        for v in 0..(1u64 << len).min(3) {
                            let mut inner = occ;
                            let mux = Mux::Extended {
                                by: "Sub".into(),
                                ranges: vec![(v, v)],
                                is_mux: false,
                            };
                            if let Some(s) =
                                data_signal(rng, &mut inner, size, format!("N{v}"), mux)
                            {
                                sigs.push(s);
                            }
                        }
                    }
                }
            }
        }
    }
    Msg {
        name: format!("M{index}"),
        dbc_id,
        size,
        sigs,
    }
}

fn dbc_text(messages: &[Msg]) -> String {
    let mut t = String::from("VERSION \"\"\n\n\nNS_ :\n\nBS_:\n\nBU_: N\n\n");
    for m in messages {
        let _ = writeln!(t, "BO_ {} {}: {} N", m.dbc_id, m.name, m.size);
        for s in &m.sigs {
            let ind = match &s.mux {
                Mux::Plain => String::new(),
                Mux::Root => " M".into(),
                Mux::LoneM => " m".into(),
                Mux::Simple(v) => format!(" m{v}"),
                Mux::Extended { ranges, is_mux, .. } => format!(
                    " m{}{}",
                    ranges.first().map_or(0, |r| r.0),
                    if *is_mux { "M" } else { "" }
                ),
            };
            let (min, max) = s.range.clone().unwrap_or(("0".into(), "0".into()));
            let _ = writeln!(
                t,
                " SG_ {}{ind} : {}|{}@{}{} ({},{}) [{min}|{max}] \"\" N",
                s.name,
                s.start,
                s.len,
                if s.order == ByteOrder::Intel { 1 } else { 0 },
                if s.signed { "-" } else { "+" },
                s.factor,
                s.offset,
            );
        }
        t.push('\n');
    }
    t.push_str(concat!(
        "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\",",
        "\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",",
        "\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\",\"ExtendedCAN_FD\";\n",
        "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n"
    ));
    for m in messages.iter().filter(|m| m.size > 8) {
        let fd = if m.dbc_id & 1 << 31 != 0 { 15 } else { 14 };
        let _ = writeln!(t, "BA_ \"VFrameFormat\" BO_ {} {fd};", m.dbc_id);
    }
    for m in messages {
        for s in m.sigs.iter().filter(|s| !s.choices.is_empty()) {
            let _ = write!(t, "VAL_ {} {}", m.dbc_id, s.name);
            for (v, n) in &s.choices {
                let _ = write!(t, " {v} \"{n}\"");
            }
            t.push_str(" ;\n");
        }
    }
    for m in messages {
        for s in m.sigs.iter().filter(|s| s.float > 0) {
            let _ = writeln!(t, "SIG_VALTYPE_ {} {} : {};", m.dbc_id, s.name, s.float);
        }
    }
    for m in messages {
        for s in &m.sigs {
            if let Mux::Extended { by, ranges, .. } = &s.mux {
                let list: Vec<String> = ranges.iter().map(|(l, h)| format!("{l}-{h}")).collect();
                let _ = writeln!(
                    t,
                    "SG_MUL_VAL_ {} {} {by} {};",
                    m.dbc_id,
                    s.name,
                    list.join(", ")
                );
            }
        }
    }
    t
}

/// One case for both implementations.
enum Op {
    Decode(Vec<u8>),
    Encode(Vec<(String, String)>),
    /// Whether the DBC loads at all (corpus files).
    Load,
}

struct Case {
    id: usize,
    dbc: usize,
    message: String,
    op: Op,
}

/// A multiplexer value for each multiplexer of `m` that selects something (the frame's
/// signals then follow), by index; `None` to leave the frame's bits as they are.
fn choose_mux(rng: &mut Rng, m: &MessageDef) -> Vec<(usize, u64)> {
    let mut out = Vec::new();
    for (i, s) in m
        .signals
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_multiplexer)
    {
        let mut options = Vec::new();
        for t in &m.signals {
            if let cw_can::dbc::Muxing::When {
                multiplexer,
                values,
            } = &t.muxing
            {
                if *multiplexer == i {
                    options.extend(values.iter().copied());
                }
            }
        }
        // Now and then a value the multiplexer's value table names, which may select
        // nothing.
        let named: Vec<(u64, u64)> = s
            .choices
            .iter()
            .filter_map(|(v, _)| u64::try_from(*v).ok().map(|v| (v, v)))
            .collect();
        if !named.is_empty() && (options.is_empty() || rng.one_in(3)) {
            options = named;
        }
        let (lo, hi) = rng.pick(&options, (0, 0));
        out.push((i, lo + rng.below(hi - lo + 1)));
    }
    out
}

/// Frames of every message of `db`: decoded and encoded where the generator's messages
/// `msgs` say what values to encode, else only decoded.
fn gen_cases(
    rng: &mut Rng,
    dbc: usize,
    db: &Database,
    msgs: Option<&[Msg]>,
    next_id: &mut usize,
) -> Vec<Case> {
    let mut cases = Vec::new();
    for (n, m) in db.messages().iter().enumerate() {
        let gen = msgs.and_then(|msgs| msgs.get(n));
        for k in 0..FRAMES_PER_MESSAGE {
            let id = *next_id;
            *next_id += 1;
            let mux = choose_mux(rng, m);
            // A message with faults a lenient load kept is only decoded: `cw-can` refuses
            // to encode signals that share bits, where cantools packs them at shifted
            // places.
            let op = if k % 2 == 0 || !m.faults.is_empty() || gen.is_none() {
                let mut pdu = [0u8; 64];
                rng.fill(&mut pdu);
                if !rng.one_in(5) {
                    for (i, v) in &mux {
                        if let Some(s) = m.signals.get(*i) {
                            s.layout.pack_masked(&mut pdu, *v);
                        }
                    }
                }
                let len = match rng.below(10) {
                    0 => rng.below(m.size as u64 + 1) as usize,
                    1 => (m.size + 1 + rng.below(4) as usize).min(64),
                    _ => m.size,
                };
                Op::Decode(pdu.get(..len).unwrap_or(&pdu).to_vec())
            } else {
                let mux_raw = |j: usize| {
                    mux.iter()
                        .find(|(i, _)| *i == j)
                        .map_or(-1, |(_, v)| i128::from(*v))
                };
                let mut values = Vec::new();
                for (i, s) in m.signals.iter().enumerate() {
                    if !m.present(i, &mux_raw) {
                        continue;
                    }
                    let Some(g) = gen.and_then(|gen| gen.sigs.iter().find(|g| g.name == s.name))
                    else {
                        continue;
                    };
                    let text = if let Some((_, v)) = mux.iter().find(|(j, _)| *j == i) {
                        v.to_string()
                    } else {
                        value_text(rng, g)
                    };
                    values.push((s.name.clone(), text));
                }
                if rng.one_in(20) && !values.is_empty() {
                    let at = rng.below(values.len() as u64) as usize;
                    values.remove(at);
                }
                Op::Encode(values)
            };
            cases.push(Case {
                id,
                dbc,
                message: m.name.clone(),
                op,
            });
        }
    }
    cases
}

/// A value for a data signal: most within its raw range, some by value-table name, some
/// one raw step outside or beyond its `[min|max]`.
fn value_text(rng: &mut Rng, s: &Sig) -> String {
    if s.float == 1 {
        let raw = (rng.next_u64() as i64 % 2_000_000) as f64 / 64.0;
        return format!("{:?}", raw * s.factor.parse::<f64>().unwrap_or(1.0));
    }
    if s.float == 2 {
        let raw = (rng.next_u64() as i64) as f64 / 1024.0;
        return format!("{:?}", raw);
    }
    if !s.choices.is_empty() && rng.one_in(3) {
        let k = rng.below(s.choices.len() as u64) as usize;
        return s.choices.get(k).map_or("0".into(), |(_, n)| n.clone());
    }
    let (lo, hi) = match s.range_raw {
        Some(inside) if !rng.one_in(4) => inside,
        _ => raw_range(s),
    };
    let raw = match rng.below(12) {
        0 => lo,
        1 => hi,
        2 => lo - 1,
        3 => hi + 1,
        _ => {
            let span = (hi - lo) as u128 + 1;
            lo + ((u128::from(rng.next_u64()) << 64 | u128::from(rng.next_u64())) % span) as i128
        }
    };
    if let (Some((min, _)), true) = (&s.range, rng.one_in(8)) {
        let f: f64 = s.factor.parse().unwrap_or(1.0);
        let m: f64 = min.parse().unwrap_or(0.0);
        return format!("{:?}", m - f.abs() * 0.5);
    }
    physical_text(s, raw)
}

/// Our verdict, in the same terms as the script's.
fn ours(db: &Database, case: &Case) -> std::result::Result<String, ()> {
    if let Op::Load = case.op {
        return Ok("loaded".into());
    }
    let m = db.by_name(&case.message).ok_or(())?;
    match &case.op {
        Op::Load => Ok("loaded".into()),
        Op::Decode(data) => {
            let signals = codec::decode(m, data).map_err(|_| ())?;
            let mut parts: Vec<String> = signals
                .iter()
                .map(|d| match (d.choice, d.physical) {
                    (Some(c), _) => format!("{}=choice:{c}", d.signal.name),
                    (None, Physical::Int(v)) => format!("{}={v}", d.signal.name),
                    (None, Physical::Float(x)) => format!("{}={}", d.signal.name, float_key(x)),
                })
                .collect();
            parts.sort();
            Ok(parts.join(" "))
        }
        Op::Encode(values) => {
            let values: std::result::Result<Vec<_>, String> = values
                .iter()
                .map(|(n, v)| Input::parse(v).map(|i| (n.clone(), i)))
                .collect();
            let data = codec::encode(m, &values.map_err(|_| ())?).map_err(|_| ())?;
            Ok(hex(&data))
        }
    }
}

/// A float as a key both sides write alike: integers without a fraction, NaN as `nan`.
fn float_key(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.fract() == 0.0 && x.abs() < 1e300 {
        format!("{}", x as i128)
    } else {
        format!("{:e}", x)
    }
}

/// cantools' verdict from one line of the script's output.
fn theirs(obj: &serde_json::Value) -> std::result::Result<String, ()> {
    if obj.get("ok").and_then(serde_json::Value::as_bool) != Some(true) {
        return Err(());
    }
    if let Some(data) = obj.get("data").and_then(serde_json::Value::as_str) {
        return Ok(data.to_string());
    }
    if obj.get("loaded").and_then(serde_json::Value::as_bool) == Some(true) {
        return Ok("loaded".into());
    }
    let signals = obj
        .get("signals")
        .and_then(serde_json::Value::as_object)
        .ok_or(())?;
    let mut parts: Vec<String> = signals
        .iter()
        .map(|(name, v)| {
            let kind = v.get(0).and_then(serde_json::Value::as_str).unwrap_or("");
            let text = v.get(1).and_then(serde_json::Value::as_str).unwrap_or("");
            match kind {
                "choice" => format!("{name}=choice:{text}"),
                "int" => format!("{name}={text}"),
                _ => format!(
                    "{name}={}",
                    float_key(text.parse::<f64>().unwrap_or(f64::NAN))
                ),
            }
        })
        .collect();
    parts.sort();
    Ok(parts.join(" "))
}

/// Generates, runs cantools, compares; fails on any disagreement.
pub fn run(options: &Options) -> Result {
    let seed = options.seed.or_fresh();
    println!("dbc-differential: seed {seed} (replay with --seed {seed})");
    let mut rng = Rng::new(seed);
    let dir = target_dir().join("xtask-dbc-differential");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    // Each DBC: its path, whether it is read strict, and what `cw-can` made of it.
    let mut dbs: Vec<(
        std::path::PathBuf,
        Strictness,
        std::result::Result<Database, String>,
    )> = Vec::new();
    let mut cases = Vec::new();
    let mut next_id = 0;
    let mut total_signals = 0;
    let mut faults = 0;
    while (cases.len() as u64) < options.frames {
        let lenient = dbs.len() % LENIENT_EVERY == LENIENT_EVERY - 1;
        let mut used = Vec::new();
        let msgs: Vec<Msg> = (0..MESSAGES_PER_DBC)
            .map(|i| {
                let mut m = gen_message(&mut rng, i, &mut used);
                if lenient {
                    stray_signals(&mut rng, &mut m);
                }
                m
            })
            .collect();
        let text = dbc_text(&msgs);
        let (strictness, kind) = if lenient {
            (Strictness::Lenient, "lenient")
        } else {
            (Strictness::Strict, "gen")
        };
        let path = dir.join(format!("{kind}{}.dbc", dbs.len()));
        std::fs::write(&path, &text).map_err(|e| format!("writing {}: {e}", path.display()))?;
        let db = Database::from_text_with(&text, strictness).map_err(|e| {
            format!(
                "{}: cw-can refuses a generated DBC: {e} (seed {seed})",
                path.display()
            )
        })?;
        total_signals += msgs.iter().map(|m| m.sigs.len()).sum::<usize>();
        faults += db.warnings().len();
        cases.extend(gen_cases(
            &mut rng,
            dbs.len(),
            &db,
            Some(&msgs),
            &mut next_id,
        ));
        dbs.push((path, strictness, Ok(db)));
    }
    let generated = dbs.len();
    for path in &options.corpus {
        let db = Database::load_with(path, Strictness::Lenient);
        cases.push(Case {
            id: next_id,
            dbc: dbs.len(),
            message: String::new(),
            op: Op::Load,
        });
        next_id += 1;
        if let Ok(db) = &db {
            total_signals += db.messages().iter().map(|m| m.signals.len()).sum::<usize>();
            faults += db.warnings().len();
            cases.extend(gen_cases(&mut rng, dbs.len(), db, None, &mut next_id));
        }
        dbs.push((path.clone(), Strictness::Lenient, db));
    }
    let cases_path = dir.join("cases.jsonl");
    let out_path = dir.join("cantools.jsonl");
    let mut text = String::new();
    for c in &cases {
        let mut obj = serde_json::json!({
            "id": c.id,
            "dbc": dbs.get(c.dbc).map(|(p, _, _)| p.display().to_string()),
            "strict": dbs.get(c.dbc).is_some_and(|(_, s, _)| *s == Strictness::Strict),
            "message": c.message,
        });
        match &c.op {
            Op::Decode(data) => {
                obj["op"] = "decode".into();
                obj["data"] = hex(data).into();
            }
            Op::Load => obj["op"] = "load".into(),
            Op::Encode(values) => {
                obj["op"] = "encode".into();
                obj["values"] = values
                    .iter()
                    .map(|(n, v)| (n.clone(), serde_json::Value::from(v.as_str())))
                    .collect::<serde_json::Map<_, _>>()
                    .into();
            }
        }
        text.push_str(&obj.to_string());
        text.push('\n');
    }
    std::fs::write(&cases_path, text)
        .map_err(|e| format!("writing {}: {e}", cases_path.display()))?;
    let _ = std::fs::remove_file(&out_path);
    crate::setup::run_python_tool("dbc_differential.py", &[&cases_path, &out_path])?;
    let out = std::fs::read_to_string(&out_path)
        .map_err(|e| format!("reading {}: {e}", out_path.display()))?;
    let mut results = std::collections::HashMap::new();
    for (n, line) in out.lines().enumerate() {
        let obj: serde_json::Value = serde_json::from_str(line)
            .map_err(|e| format!("{}:{}: {e}", out_path.display(), n + 1))?;
        let id = obj
            .get("id")
            .and_then(serde_json::Value::as_u64)
            .unwrap_or(u64::MAX);
        results.insert(id as usize, obj);
    }
    let (mut decodes, mut encodes, mut loads, mut refused) = (0, 0, 0, 0);
    let mut mismatches = Vec::new();
    for c in &cases {
        let Some((path, _, db)) = dbs.get(c.dbc) else {
            continue;
        };
        let Some(obj) = results.get(&c.id) else {
            return Err(format!("cantools wrote no result for case {}", c.id));
        };
        let (a, b) = match (db, &c.op) {
            (Ok(db), _) => (ours(db, c), theirs(obj)),
            (Err(_), _) => (Err(()), theirs(obj)),
        };
        match &c.op {
            Op::Decode(_) => decodes += 1,
            Op::Encode(_) => encodes += 1,
            Op::Load => loads += 1,
        }
        if a.is_err() && b.is_err() {
            refused += 1;
        }
        if a != b {
            let what = match &c.op {
                Op::Decode(d) => format!("decode {}", hex(d)),
                Op::Encode(v) => format!("encode {v:?}"),
                Op::Load => match db {
                    Ok(_) => "load".into(),
                    Err(e) => format!("load ({e})"),
                },
            };
            mismatches.push(format!(
                "case {}: {} {} {what}\n  cw-can:   {a:?}\n  cantools: {:?} {}",
                c.id,
                path.display(),
                c.message,
                b,
                obj.get("error")
                    .and_then(serde_json::Value::as_str)
                    .unwrap_or("")
            ));
        }
    }
    let messages: usize = dbs
        .iter()
        .filter_map(|(_, _, db)| db.as_ref().ok())
        .map(|db| db.messages().len())
        .sum();
    let lenient = generated / LENIENT_EVERY;
    let (given, loaded) = match dbs.len() - generated {
        0 => (String::new(), String::new()),
        n => (format!(", {n} given"), format!("{loads} loads, ")),
    };
    println!(
        "dbc-differential: {generated} generated DBCs ({lenient} lenient){given}; {messages} messages, {total_signals} signals, {faults} faults kept leniently; {} cases: {loaded}{decodes} frames decoded, {encodes} encoded, {refused} refused by both; {} disagreements",
        cases.len(),
        mismatches.len()
    );
    let all_path = dir.join("disagreements.txt");
    std::fs::write(&all_path, mismatches.join("\n"))
        .map_err(|e| format!("writing {}: {e}", all_path.display()))?;
    if mismatches.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "cw-can and cantools disagree on {} of {} cases (seed {seed}; all in {}); the first {}:\n{}",
            mismatches.len(),
            cases.len(),
            all_path.display(),
            SHOW.min(mismatches.len()),
            mismatches
                .iter()
                .take(SHOW)
                .cloned()
                .collect::<Vec<_>>()
                .join("\n")
        ))
    }
}
