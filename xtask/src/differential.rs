//! `cargo xtask differential`: the Com signal codec (`cw_core::com::signal`) against
//! cantools, an independent implementation of the same DBC bit numbering.
//!
//! 1. Here: random cases from a printed seed: a PDU length (classic CAN 1..=8 bytes and
//!    the CAN FD lengths up to 64), a layout `SignalLayout::<N>::new` accepts, an in-range
//!    value biased toward the boundaries, a random background PDU. We pack the value into
//!    an all-zero PDU and into the background, and check that we unpack it again. Layouts
//!    we refuse are kept too (some of them), with our acceptance checked against
//!    `spec::layout_fits` for every attempt.
//! 2. `tools/codec_differential.py` (in `.venv`): cantools encodes each value into a zero
//!    PDU (compared with our bytes), decodes our background-packed PDU (compared with the
//!    value), refuses the layouts we refuse, and writes its encoded bytes back.
//! 3. Here again: we unpack cantools' bytes and pack the value into them (no change).

use crate::process::target_dir;
use crate::rng::Rng;
use crate::Result;
use cw_core::com::signal::{spec, ByteOrder, SignalLayout, Signedness};
use std::collections::HashMap;
use std::fmt::Write as _;

/// PDU lengths under test: classic CAN and the CAN FD data lengths.
const PDU_LENGTHS: &[usize] = &[1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// Signal lengths drawn more often than the rest (byte and word boundaries, +-1).
const EDGE_LENGTHS: &[u8] = &[1, 2, 7, 8, 9, 15, 16, 17, 24, 31, 32, 33, 48, 63, 64];

/// How many cases to report in full when something differs.
const SHOW_MISMATCHES: usize = 5;

/// The default `--cases`.
const CASES: u64 = 20_000;

/// Options of `cargo xtask differential`.
#[derive(clap::Args)]
pub struct Options {
    /// Number of accepted-layout cases
    #[arg(long, default_value_t = CASES, value_parser = clap::value_parser!(u64).range(1..))]
    pub cases: u64,
    #[command(flatten)]
    pub seed: crate::rng::Seed,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            cases: CASES,
            seed: crate::rng::Seed::default(),
        }
    }
}

/// One accepted layout with a value.
struct Case {
    id: usize,
    pdu_len: usize,
    start_bit: u16,
    length_bits: u8,
    order: ByteOrder,
    signedness: Signedness,
    value: i128,
    /// Our packing of `value` into an all-zero PDU.
    packed: Vec<u8>,
    /// Our packing of `value` into a random background PDU.
    bg_packed: Vec<u8>,
}

/// A layout we refuse (cantools must refuse it too).
struct Reject {
    pdu_len: usize,
    start_bit: u16,
    length_bits: u8,
    order: ByteOrder,
}

/// Calls `$f::<N>(args)` with the const generic `N` equal to the runtime PDU length.
macro_rules! with_pdu_len {
    ($len:expr, $f:ident ( $($arg:expr),* )) => {
        match $len {
            1 => $f::<1>($($arg),*),
            2 => $f::<2>($($arg),*),
            3 => $f::<3>($($arg),*),
            4 => $f::<4>($($arg),*),
            5 => $f::<5>($($arg),*),
            6 => $f::<6>($($arg),*),
            7 => $f::<7>($($arg),*),
            8 => $f::<8>($($arg),*),
            12 => $f::<12>($($arg),*),
            16 => $f::<16>($($arg),*),
            20 => $f::<20>($($arg),*),
            24 => $f::<24>($($arg),*),
            32 => $f::<32>($($arg),*),
            48 => $f::<48>($($arg),*),
            64 => $f::<64>($($arg),*),
            other => Err(format!("PDU length {other} is not one of the lengths under test")),
        }
    };
}

fn order_name(order: ByteOrder) -> &'static str {
    match order {
        ByteOrder::Intel => "intel",
        ByteOrder::Motorola => "motorola",
    }
}

fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(2 * bytes.len());
    for b in bytes {
        let _ = write!(s, "{b:02x}");
    }
    s
}

fn spaced_hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn unhex(s: &str) -> Result<Vec<u8>> {
    if s.len() % 2 != 0 {
        return Err(format!("odd-length hex string `{s}`"));
    }
    (0..s.len())
        .step_by(2)
        .map(|i| {
            s.get(i..i + 2)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("bad hex string `{s}`"))
        })
        .collect()
}

impl Case {
    fn describe(&self) -> String {
        format!(
            "case {}: PDU {} bytes, start bit {}, {} bits, {}, {}, value {} (0x{:X})\n  ours (zero PDU):       {}\n  ours (background PDU): {}",
            self.id,
            self.pdu_len,
            self.start_bit,
            self.length_bits,
            order_name(self.order),
            match self.signedness {
                Signedness::Unsigned => "unsigned",
                Signedness::Signed => "signed",
            },
            self.value,
            self.value as u128 & (u128::from(u64::MAX) >> (64 - u32::from(self.length_bits))),
            spaced_hex(&self.packed),
            spaced_hex(&self.bg_packed),
        )
    }
}

fn pack<const N: usize>(layout: &SignalLayout<N>, pdu: &mut [u8; N], value: i128) -> Result {
    let r = match layout.signedness() {
        Signedness::Unsigned => {
            let v = u64::try_from(value).map_err(|_| format!("value {value} is not a u64"))?;
            layout.pack_u64(pdu, v)
        }
        Signedness::Signed => {
            let v = i64::try_from(value).map_err(|_| format!("value {value} is not an i64"))?;
            layout.pack_i64(pdu, v)
        }
    };
    r.map_err(|e| format!("our codec refused in-range value {value} for {layout:?}: {e:?}"))
}

/// An in-range value for the signal, often a boundary.
fn random_value(rng: &mut Rng, length_bits: u8, signedness: Signedness) -> i128 {
    let (lo, hi) = spec::value_range(length_bits, signedness);
    let signed = signedness == Signedness::Signed;
    match rng.below(12) {
        0 => lo,
        1 => hi,
        2 => 0,
        3 => {
            if signed {
                -1
            } else {
                hi.min(1)
            }
        }
        4 => (lo + 1).min(hi),
        5 => (hi - 1).max(lo),
        _ => {
            // Random bits, sometimes shifted down to give small magnitudes too.
            let bits = length_bits as u32;
            let mask = u64::MAX >> (64 - bits);
            let raw = (rng.next_u64() >> rng.below(64)) & mask;
            if signed && raw >> (bits - 1) & 1 == 1 {
                i128::from(raw) - (1i128 << bits)
            } else {
                i128::from(raw)
            }
        }
    }
}

/// Draws layouts for an `N`-byte PDU until one is accepted; returns the case and the
/// refused attempts.
fn gen_case<const N: usize>(rng: &mut Rng, id: usize) -> Result<(Case, Vec<Reject>)> {
    let max_len = (8 * N).min(64) as u64;
    let mut rejects = Vec::new();
    for _ in 0..100_000 {
        let start_bit = rng.below(8 * N as u64) as u16;
        let length_bits = if rng.one_in(4) {
            rng.pick(EDGE_LENGTHS, 8).min(max_len as u8)
        } else {
            1 + rng.below(max_len) as u8
        };
        let order = if rng.one_in(2) {
            ByteOrder::Intel
        } else {
            ByteOrder::Motorola
        };
        let signedness = if rng.one_in(2) {
            Signedness::Unsigned
        } else {
            Signedness::Signed
        };
        let made = SignalLayout::<N>::new(start_bit, length_bits, order, signedness);
        let fits = spec::layout_fits(N, start_bit, length_bits, order);
        if made.is_ok() != fits {
            return Err(format!(
                "SignalLayout::<{N}>::new({start_bit}, {length_bits}, {order:?}, {signedness:?}) is {made:?} \
                 but spec::layout_fits says {fits}"
            ));
        }
        let Ok(layout) = made else {
            rejects.push(Reject {
                pdu_len: N,
                start_bit,
                length_bits,
                order,
            });
            continue;
        };
        let value = random_value(rng, length_bits, signedness);
        let mut packed = [0u8; N];
        pack(&layout, &mut packed, value)?;
        let mut bg_packed = [0u8; N];
        rng.fill(&mut bg_packed);
        pack(&layout, &mut bg_packed, value)?;
        let case = Case {
            id,
            pdu_len: N,
            start_bit,
            length_bits,
            order,
            signedness,
            value,
            packed: packed.to_vec(),
            bg_packed: bg_packed.to_vec(),
        };
        let back = layout.unpack(&bg_packed).as_i128();
        if back != value {
            return Err(format!(
                "our codec does not read back its own packing: unpacked {back}\n{}",
                case.describe()
            ));
        }
        return Ok((case, rejects));
    }
    Err(format!(
        "no valid layout found for a {N}-byte PDU after 100000 draws"
    ))
}

/// Our unpacking of cantools' encoding, and our packing into it (which must not change it).
/// Returns a description of the mismatch, if any.
fn reverse<const N: usize>(case: &Case, cantools: &[u8]) -> Result<Option<String>> {
    let layout = SignalLayout::<N>::new(
        case.start_bit,
        case.length_bits,
        case.order,
        case.signedness,
    )
    .map_err(|e| format!("case {}: layout no longer accepted: {e:?}", case.id))?;
    let pdu: [u8; N] = cantools.try_into().map_err(|_| {
        format!(
            "case {}: cantools wrote {} bytes for a {N}-byte PDU",
            case.id,
            cantools.len()
        )
    })?;
    let got = layout.unpack(&pdu).as_i128();
    let mut repacked = pdu;
    pack(&layout, &mut repacked, case.value)?;
    if got != case.value || repacked != pdu {
        return Ok(Some(format!(
            "{}\n  cantools (zero PDU):   {}\n  our unpack of cantools' bytes: {got}; our pack into them: {}",
            case.describe(),
            spaced_hex(cantools),
            spaced_hex(&repacked)
        )));
    }
    Ok(None)
}

/// Runs the differential test.
pub fn run(options: &Options) -> Result {
    let seed = options.seed.or_fresh();
    println!(
        "codec differential: {} cases, seed {seed} (replay: cargo xtask differential --cases {} --seed {seed})",
        options.cases, options.cases
    );
    let mut rng = Rng::new(seed);
    let mut cases = Vec::with_capacity(options.cases as usize);
    let mut rejects = Vec::new();
    let max_rejects = (options.cases as usize / 10).max(1);
    for id in 0..options.cases as usize {
        let len = rng.pick(PDU_LENGTHS, 8);
        let (case, refused) = with_pdu_len!(len, gen_case(&mut rng, id))?;
        cases.push(case);
        for r in refused {
            if rejects.len() < max_rejects && rng.one_in(4) {
                rejects.push(r);
            }
        }
    }

    let dir = target_dir().join("xtask-differential");
    std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let cases_path = dir.join("cases.jsonl");
    let out_path = dir.join("cantools.jsonl");
    /// One line of the cases file (see `tools/codec_differential.py`).
    #[derive(serde::Serialize)]
    #[serde(tag = "kind", rename_all = "snake_case")]
    enum Line<'a> {
        Case {
            id: usize,
            pdu_len: usize,
            start_bit: u16,
            length: u8,
            order: &'a str,
            signed: bool,
            value: i128,
            packed: String,
            bg_packed: String,
        },
        Reject {
            pdu_len: usize,
            start_bit: u16,
            length: u8,
            order: &'a str,
        },
    }
    let lines = cases
        .iter()
        .map(|c| Line::Case {
            id: c.id,
            pdu_len: c.pdu_len,
            start_bit: c.start_bit,
            length: c.length_bits,
            order: order_name(c.order),
            signed: c.signedness == Signedness::Signed,
            value: c.value,
            packed: hex(&c.packed),
            bg_packed: hex(&c.bg_packed),
        })
        .chain(rejects.iter().map(|r| Line::Reject {
            pdu_len: r.pdu_len,
            start_bit: r.start_bit,
            length: r.length_bits,
            order: order_name(r.order),
        }));
    let mut text = String::new();
    for line in lines {
        text.push_str(&serde_json::to_string(&line).map_err(|e| format!("a case as JSON: {e}"))?);
        text.push('\n');
    }
    std::fs::write(&cases_path, text)
        .map_err(|e| format!("writing {}: {e}", cases_path.display()))?;
    let _ = std::fs::remove_file(&out_path);

    crate::setup::run_python_tool("codec_differential.py", &[&cases_path, &out_path]).map_err(
        |e| {
            format!(
                "{e}\ncantools disagrees with our codec (seed {seed}; cases in {})",
                cases_path.display()
            )
        },
    )?;

    // Reverse direction: cantools' bytes through our codec.
    let out = std::fs::read_to_string(&out_path)
        .map_err(|e| format!("reading {}: {e}", out_path.display()))?;
    let mut encoded: HashMap<usize, Vec<u8>> = HashMap::new();
    let mut counts = (0i128, 0i128, 0i128);
    for (n, line) in out.lines().enumerate() {
        let at = || format!("{}:{}", out_path.display(), n + 1);
        let obj: serde_json::Value =
            serde_json::from_str(line).map_err(|e| format!("{}: {e}", at()))?;
        let int = |key: &str| {
            obj.get(key)
                .and_then(serde_json::Value::as_i64)
                .ok_or_else(|| format!("{}: no integer `{key}`", at()))
        };
        let text = |key: &str| {
            obj.get(key)
                .and_then(serde_json::Value::as_str)
                .ok_or_else(|| format!("{}: no string `{key}`", at()))
        };
        match text("kind")? {
            "encoded" => {
                encoded.insert(
                    usize::try_from(int("id")?).unwrap_or(usize::MAX),
                    unhex(text("cantools")?)?,
                );
            }
            "summary" => {
                counts = (
                    i128::from(int("encode")?),
                    i128::from(int("decode")?),
                    i128::from(int("refused")?),
                )
            }
            other => return Err(format!("{}: unknown kind `{other}`", at())),
        }
    }
    let mut mismatches = Vec::new();
    let mut reversed = 0usize;
    for case in &cases {
        let bytes = encoded
            .get(&case.id)
            .ok_or_else(|| format!("cantools wrote no encoding for case {}", case.id))?;
        if let Some(m) = with_pdu_len!(case.pdu_len, reverse(case, bytes))? {
            mismatches.push(m);
        }
        reversed += 1;
    }
    if !mismatches.is_empty() {
        println!(
            "{} case(s) where our codec does not read back cantools' encoding; the first {}:",
            mismatches.len(),
            SHOW_MISMATCHES.min(mismatches.len())
        );
        for m in mismatches.iter().take(SHOW_MISMATCHES) {
            println!("{m}");
        }
        return Err(format!(
            "codec differential: {} reverse mismatch(es) (seed {seed}; cases in {})",
            mismatches.len(),
            cases_path.display()
        ));
    }
    let n = cases.len();
    if counts.0 != n as i128 || counts.1 != n as i128 {
        return Err(format!(
            "cantools checked encode {} / decode {} of {n} cases",
            counts.0, counts.1
        ));
    }
    if counts.2 != rejects.len() as i128 {
        return Err(format!(
            "cantools refused {} of the {} layouts we refuse",
            counts.2,
            rejects.len()
        ));
    }
    println!(
        "refused layouts: cantools refuses all {} sampled layouts that we refuse",
        rejects.len()
    );
    println!(
        "codec differential vs cantools: {n} cases, 0 mismatches (encode {}, decode {}, reverse {reversed})",
        counts.0, counts.1
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-checked examples of `tools/codec_differential.py`, through our codec.
    #[test]
    fn hand_checked_examples() -> Result {
        let intel = SignalLayout::<8>::new(0, 32, ByteOrder::Intel, Signedness::Unsigned)
            .map_err(|e| format!("{e:?}"))?;
        let mut pdu = [0u8; 8];
        pack(&intel, &mut pdu, 0x1234_5678)?;
        assert_eq!(pdu, [0x78, 0x56, 0x34, 0x12, 0, 0, 0, 0]);

        let moto = SignalLayout::<8>::new(7, 16, ByteOrder::Motorola, Signedness::Unsigned)
            .map_err(|e| format!("{e:?}"))?;
        let mut pdu = [0u8; 8];
        pack(&moto, &mut pdu, 0xABCD)?;
        assert_eq!(pdu, [0xAB, 0xCD, 0, 0, 0, 0, 0, 0]);

        let signed = SignalLayout::<8>::new(3, 12, ByteOrder::Motorola, Signedness::Signed)
            .map_err(|e| format!("{e:?}"))?;
        let mut pdu = [0u8; 8];
        pack(&signed, &mut pdu, -2)?;
        assert_eq!(pdu, [0x0F, 0xFE, 0, 0, 0, 0, 0, 0]);
        Ok(())
    }

    #[test]
    fn hex_round_trip() -> Result {
        assert_eq!(unhex(&hex(&[0, 0xAB, 0xFF]))?, vec![0, 0xAB, 0xFF]);
        assert!(unhex("abc").is_err());
        assert!(unhex("zz").is_err());
        Ok(())
    }

    #[test]
    fn random_values_stay_in_range() {
        let mut rng = Rng::new(1);
        for length in 1..=64u8 {
            for sign in [Signedness::Unsigned, Signedness::Signed] {
                let (lo, hi) = spec::value_range(length, sign);
                for _ in 0..200 {
                    let v = random_value(&mut rng, length, sign);
                    assert!(lo <= v && v <= hi, "{length} {sign:?} {v}");
                }
            }
        }
    }
}
