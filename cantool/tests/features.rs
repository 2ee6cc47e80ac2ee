//! Every feature of `tests/data/features.dbc` decoded and encoded. The expected values are
//! what cantools 45.1.0 gives for the same DBC and bytes (its `decode_message` and
//! `encode_message`), written down here.

use cw_can::codec::{decode, encode, DecodeError, Input, Physical, Raw};
use cw_can::dbc::{Database, MessageDef, Strictness};

fn db() -> Database {
    Database::from_bytes(include_bytes!("data/features.dbc")).expect("features.dbc loads")
}

fn message<'a>(db: &'a Database, name: &str) -> &'a MessageDef {
    db.by_name(name).expect("message in features.dbc")
}

fn bytes(hex: &str) -> Vec<u8> {
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).expect("hex"))
        .collect()
}

/// `name=value` of every present signal, the value table's name where there is one.
fn decoded(db: &Database, name: &str, hex: &str) -> Result<Vec<String>, DecodeError> {
    Ok(decode(message(db, name), &bytes(hex))?
        .iter()
        .map(|d| match d.choice {
            Some(c) => format!("{}={c}", d.signal.name),
            None => format!("{}={}", d.signal.name, d.physical),
        })
        .collect())
}

fn encoded(db: &Database, name: &str, values: &[(&str, &str)]) -> Result<String, String> {
    let values: Vec<_> = values
        .iter()
        .map(|(n, v)| (n.to_string(), Input::parse(v).expect("a value")))
        .collect();
    encode(message(db, name), &values).map(|data| data.iter().map(|b| format!("{b:02x}")).collect())
}

#[test]
fn ids_sizes_and_kinds_of_message_load() {
    let db = db();
    let ext = message(&db, "Ext");
    assert_eq!((ext.id, ext.extended, ext.size), (0x18FF_0001, true, 8));
    assert_eq!(message(&db, "Fd64").size, 64);
    assert!(db.by_id(0x18FF_0001, true).is_some());
    assert!(db.by_id(0x18FF_0001, false).is_none());
    assert!(db.by_id(0x100, true).is_none());
    // CAN FD by the DBC's VFrameFormat attribute (4 bytes), or by size.
    assert!(message(&db, "SmallFd").fd);
    assert!(message(&db, "Floaty").fd);
    assert!(!message(&db, "Plain").fd);
}

#[test]
fn integers_factors_offsets_and_value_tables_decode_as_cantools() {
    let db = db();
    assert_eq!(
        decoded(&db, "Plain", "E8030000027F8012"),
        Ok(vec![
            "Distance=1000".into(),
            "Level=Red".into(),
            "Temp=980.0".into(),
            "Ratio=0.18".into()
        ])
    );
    // Every 64-bit raw value is exact.
    let big = decode(message(&db, "Ext"), &bytes("FFFFFFFFFFFFFFFF")).expect("decodes");
    assert_eq!(big[0].raw, Raw::Int(18_446_744_073_709_551_615));
    assert_eq!(big[0].physical, Physical::Int(18_446_744_073_709_551_615));
}

#[test]
fn ieee_floats_and_doubles_decode_as_floats() {
    let db = db();
    assert_eq!(
        decoded(&db, "Floaty", "0000C03F000000000000F03F"),
        Ok(vec!["Single=1.5".into(), "Double=3.0".into()])
    );
}

#[test]
fn fd_messages_of_64_bytes_decode_in_both_byte_orders() {
    let db = db();
    let mut data = [0u8; 64];
    data[0] = 0x12;
    data[1] = 0x34;
    data[55] = 0x80;
    data[59] = 0x01;
    data[63] = 0x99;
    let hex: String = data.iter().map(|b| format!("{b:02X}")).collect();
    assert_eq!(
        decoded(&db, "Fd64", &hex),
        Ok(vec![
            "Head=4660".into(),
            "Tail=153".into(),
            "Signed=-4294967296".into()
        ])
    );
}

#[test]
fn only_the_signals_the_multiplexers_select_are_decoded() {
    let db = db();
    assert_eq!(
        decoded(&db, "Mux", "00AABBCC000000EE"),
        Ok(vec!["Sel=0".into(), "A=48042".into(), "Common=238".into()])
    );
    assert_eq!(
        decoded(&db, "Mux", "01AABBCC000000EE"),
        Ok(vec![
            "Sel=1".into(),
            "B=170".into(),
            "C=-69".into(),
            "Common=238".into()
        ])
    );
    assert_eq!(
        decoded(&db, "Mux", "02AABBCC000000EE"),
        Err(DecodeError::UnknownMux {
            signal: "Sel".into(),
            value: 2
        })
    );
    // SG_MUL_VAL_: nested multiplexers and value ranges.
    assert_eq!(
        decoded(&db, "ExtMux", "0102030400000000"),
        Ok(vec!["Sel=1".into(), "Sub=2".into(), "Deep=3".into()])
    );
    assert_eq!(
        decoded(&db, "ExtMux", "0402030400000000"),
        Ok(vec!["Sel=4".into(), "Wide=4".into()])
    );
    assert_eq!(
        decoded(&db, "ExtMux", "0602030400000000"),
        Err(DecodeError::UnknownMux {
            signal: "Sel".into(),
            value: 6
        })
    );
}

#[test]
fn short_frames_are_refused_and_longer_ones_decoded_without_their_excess() {
    let db = db();
    assert_eq!(
        decoded(&db, "Plain", "E803"),
        Err(DecodeError::Short { len: 2, size: 8 })
    );
    assert_eq!(
        decoded(&db, "Plain", "E8030000027F801200"),
        decoded(&db, "Plain", "E8030000027F8012")
    );
}

#[test]
fn encoding_rounds_half_to_even_takes_names_and_is_exact() {
    let db = db();
    let plain = [("Distance", "1000"), ("Level", "Red"), ("Temp", "23.75")];
    let with = |ratio: &'static str| {
        let mut v = plain.to_vec();
        v.push(("Ratio", ratio));
        encoded(&db, "Plain", &v)
    };
    assert_eq!(with("0.125"), Ok("e80300000208000c".into()));
    assert_eq!(with("0.135"), Ok("e80300000208000e".into()));
    assert_eq!(
        encoded(&db, "Ext", &[("Big", "18446744073709551615")]),
        Ok("ffffffffffffffff".into())
    );
    assert_eq!(
        encoded(
            &db,
            "Mux",
            &[("Sel", "1"), ("B", "5"), ("C", "-2"), ("Common", "9")]
        ),
        Ok("0105fe0000000009".into())
    );
    // The values decode back.
    assert_eq!(
        decoded(&db, "Mux", "0105fe0000000009"),
        Ok(vec![
            "Sel=1".into(),
            "B=5".into(),
            "C=-2".into(),
            "Common=9".into()
        ])
    );
}

#[test]
fn what_cannot_be_encoded_is_named() {
    let db = db();
    let full = |temp: &'static str| {
        encoded(
            &db,
            "Plain",
            &[
                ("Distance", "1"),
                ("Level", "0"),
                ("Temp", temp),
                ("Ratio", "0"),
            ],
        )
    };
    assert_eq!(
        full("200"),
        Err("Temp = 200 is outside the signal's range [-100|100]".into())
    );
    assert_eq!(
        encoded(&db, "Mux", &[("Sel", "1"), ("B", "5"), ("Common", "9")]),
        Err("C is missing: every signal of Mux the frame carries needs a value".into())
    );
    assert_eq!(
        encoded(
            &db,
            "Mux",
            &[("Sel", "0"), ("A", "1"), ("B", "5"), ("Common", "9")]
        ),
        Err("B is not in the frame: its multiplexer does not select it".into())
    );
    assert_eq!(
        encoded(&db, "Mux", &[("Sel", "0"), ("A", "65536"), ("Common", "9")]),
        Err("A = 65536 is raw 65536, which does not fit 16 unsigned bits".into())
    );
    assert_eq!(
        encoded(&db, "Ext", &[("Big", "1e20")]),
        Err("Big = 100000000000000000000 is raw 100000000000000000000, which does not fit 64 unsigned bits".into())
    );
    assert_eq!(
        encoded(&db, "Plain", &[("Nope", "1")]),
        Err("no signal `Nope` in Plain".into())
    );
    assert_eq!(
        encoded(&db, "Plain", &[("Level", "Blue")]),
        Err("Level = `Blue` is neither a number nor a name in the signal's value table".into())
    );
    assert!(Input::parse("nan").is_err());
    assert!(Input::parse("inf").is_err());
    assert!(Input::parse("-infinity").is_err());
}

#[test]
fn dbcs_that_cannot_be_decoded_are_refused_with_the_reason() {
    let head = "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_: A\n\n";
    let refused = |body: &str| {
        Database::from_text(&format!("{head}{body}\n"))
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    assert_eq!(refused(""), Err("holds no message (BO_)".into()));
    assert_eq!(
        refused("BO_ 419430400 J1939: 8 A\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" A\n"),
        Err("message J1939: id 419430400 (0x19000000) is more than 11 bits but has no extended flag (bit 31: write it as 2566914048)".into())
    );
    assert_eq!(
        refused("BO_ 1 M: 8 A\n SG_ S : 60|8@1+ (1,0) [0|0] \"\" A\n"),
        Err("message M: signal S: bits 60|8@1 fall outside the message's 8 bytes".into())
    );
    assert_eq!(
        refused("BO_ 1 M: 8 A\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" A\n SG_ T : 4|8@1+ (1,0) [0|0] \"\" A\n"),
        Err("message M: signals S and T share bits".into())
    );
    assert_eq!(
        refused("BO_ 1 M: 8 A\n SG_ S : 0|16@1+ (1,0) [0|0] \"\" A\n\nSIG_VALTYPE_ 1 S : 1;\n"),
        Err("message M: signal S: IEEEfloat32Bit needs 32 or 64 bits, has 16".into())
    );
    assert_eq!(
        refused("BO_ 1 M: 8 A\n SG_ S m1 : 0|8@1+ (1,0) [0|0] \"\" A\n"),
        Err("message M: signal S: multiplexed (m1) but the message has no multiplexer (M)".into())
    );
    assert_eq!(
        refused("BO_ 1 M: 8 A\n SG_ S : 0|8@1+ (0,0) [0|0] \"\" A\n"),
        Err(
            "message M: signal S: factor 0 and offset 0: the factor must be finite and not 0"
                .into()
        )
    );
    assert!(
        refused("BO_ 1 M: 8 A\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" A\nBO_ 1 N: 8 A\n")
            .is_err_and(|e| e.contains("same id"))
    );
    assert!(refused("this is not a DBC").is_err_and(|e| e.starts_with("does not parse")));
}

#[test]
fn a_windows_1252_dbc_reads_as_candb_wrote_it() {
    let utf8 = include_str!("data/features.dbc").replace(
        "CM_ SG_ 256 Temp \"Coolant temperature in degC\";",
        "CM_ SG_ 256 Temp \"K\u{fc}hlmitteltemperatur in \u{b0}C\";",
    );
    // The same text as CANdb++ writes it: ü and ° as single Windows-1252 bytes.
    let cp1252: Vec<u8> = utf8
        .chars()
        .map(|c| match c {
            '\u{fc}' => 0xFC,
            '\u{b0}' => 0xB0,
            c => u8::try_from(c).expect("ASCII otherwise"),
        })
        .collect();
    assert!(std::str::from_utf8(&cp1252).is_err());
    let db = Database::from_bytes(&cp1252).expect("Windows-1252 DBC loads");
    assert_eq!(db.messages().len(), 7);
    assert_eq!(
        cw_can::dbc::text_of(&cp1252),
        utf8,
        "decoded as Windows-1252"
    );
}

/// A DBC with the faults opendbc's production DBCs have (`vw_mqb`, `vw_pq`,
/// `nissan_xterra_2011`, ...): signals that share bits, a signal beyond its message, a
/// lone `m` with signals hung from it; and a multiplexer value that its value table names
/// but that selects no signal (`tesla_model3_vehicle.dbc`'s `VCLEFT_switchStatusIndex`).
/// The expected answers are cantools 45.1.0's with `strict=False`.
const FAULTY: &str = include_str!("data/opendbc-faults.dbc");

fn lenient() -> Database {
    Database::from_text_with(FAULTY, Strictness::Lenient).expect("loads leniently")
}

#[test]
fn strict_refuses_what_lenient_keeps_as_warnings_naming_message_and_signals() {
    assert_eq!(
        Database::from_text(FAULTY)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        Err("message Overlap: signals S and T share bits".into())
    );
    assert_eq!(
        lenient().warnings(),
        [
            "message Overlap: signals S and T share bits",
            "message Orders: signals L and B share bits",
            "message Beyond: signal Out: bits 12|8@1 fall outside the message's 2 bytes",
            "message Levels: signals Two and Two2 share bits",
            "message LoneM: signal ByCode: its multiplexer Code is not an integer multiplexer signal (M): no frame carries it",
        ]
    );
    // Beyond 64 bytes no frame holds a signal: refused even leniently.
    let far = "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_: A\n\nBO_ 1 M: 8 A\n SG_ S : 600|8@1+ (1,0) [0|0] \"\" A\n";
    assert!(Database::from_text_with(far, Strictness::Lenient)
        .is_err_and(|e| e.to_string().contains("fall outside")));
}

#[test]
fn lenient_frames_decode_as_cantools_no_strict_decodes_them() {
    let db = lenient();
    let unplaceable =
        |name: &str, hex: &str| matches!(decoded(&db, name, hex), Err(DecodeError::Unplaceable(_)));
    // Signals of one byte order and level that share bits: "unpacking failed".
    assert!(unplaceable("Overlap", "1234"));
    // Of different byte orders: each read from its own bits.
    assert_eq!(
        decoded(&db, "Orders", "1234"),
        Ok(vec!["L=18".into(), "B=18".into()])
    );
    // A signal beyond the message: no frame of it decodes.
    assert!(unplaceable("Beyond", "1234"));
    // Sharing bits only under a value the frame does not select: decodes.
    assert_eq!(
        decoded(&db, "Levels", "01AB"),
        Ok(vec!["Sel=1".into(), "One=171".into()])
    );
    assert!(unplaceable("Levels", "02AB"));
    // A signal hung from a lone `m` is never carried.
    assert_eq!(decoded(&db, "LoneM", "05"), Ok(vec!["Code=1".into()]));
}

#[test]
fn a_named_multiplexer_value_that_selects_nothing_decodes_the_multiplexer_alone() {
    let db = lenient();
    assert_eq!(
        decoded(&db, "Named", "0105"),
        Ok(vec!["Index=one".into(), "X=5".into()])
    );
    assert_eq!(decoded(&db, "Named", "0205"), Ok(vec!["Index=two".into()]));
    assert_eq!(
        decoded(&db, "Named", "0305"),
        Err(DecodeError::UnknownMux {
            signal: "Index".into(),
            value: 3
        })
    );
    assert_eq!(
        encoded(&db, "Named", &[("Index", "two")]),
        Ok("0200".into())
    );
    assert!(
        encoded(&db, "Named", &[("Index", "3")]).is_err_and(|e| e.contains("selects no signal"))
    );
}

#[test]
fn lenient_signals_that_share_bits_are_not_encoded() {
    let db = lenient();
    assert_eq!(
        encoded(&db, "Overlap", &[("S", "1"), ("T", "2")]),
        Err("message Overlap: signals S and T share bits (kept by --no-strict): a frame that carries them cannot be encoded".into())
    );
    assert_eq!(
        encoded(&db, "Levels", &[("Sel", "1"), ("One", "7")]),
        Ok("0107".into())
    );
}
