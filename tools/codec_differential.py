#!/usr/bin/env python3
"""Differential test of cw-core's Com signal codec against cantools.

Run by `cargo xtask differential` (use that: it generates the cases and checks the
reverse direction), as

    .venv/bin/python tools/codec_differential.py CASES.jsonl OUT.jsonl

CASES.jsonl holds one JSON object per line, written by xtask from a seeded PRNG:

    {"kind": "case", "id", "pdu_len", "start_bit", "length", "order": "intel"|"motorola",
     "signed", "value", "packed": hex of OUR packing into an all-zero PDU,
     "bg_packed": hex of OUR packing into a random background PDU}
    {"kind": "reject", "pdu_len", "start_bit", "length", "order"}  (a layout we refuse)

For every case this script builds the signal in a DBC (start|length@order sign, the DBC
convention shared by cantools and Arctic Core; PDUs above 8 bytes are CAN FD frames via the
`VFrameFormat` attribute, value 14 = StandardCAN_FD), then
  (a) encodes the value with cantools (raw, strict) and compares with our bytes;
  (b) decodes our background-packed bytes with cantools and compares with the value;
  (c) writes cantools' encoding to OUT.jsonl, which xtask unpacks with our codec.
Every "reject" layout must be refused by cantools too ("does not fit in message").
Exit status 0 only when everything agrees; otherwise the first mismatches are printed in
full.

Hand-checked examples (DBC bit numbering: bit b is bit b % 8 of byte b // 8, LSB = 0),
also asserted at start-up by `hand_checks()`:

  * Intel (@1), start bit 0, 32 bits, value 0x12345678: the start bit is the LSB, the
    signal grows upward through bytes 0..3, least significant byte first:
        78 56 34 12 00 00 00 00
  * Motorola (@0), start bit 7, 16 bits, value 0xABCD: the start bit is the MSB (byte 0
    bit 7); the sawtooth walks byte 0 bits 7..0 (the high byte 0xAB), then byte 1 bits
    7..0 (0xCD):
        AB CD 00 00 00 00 00 00
  * Motorola, start bit 3, 12 bits, signed, value -2: two's complement in 12 bits is
    0xFFE; the MSB is byte 0 bit 3, so byte 0 bits 3..0 take the top nibble 0xF and
    byte 1 takes the low byte 0xFE; byte 0 bits 7..4 are not part of the signal:
        0F FE 00 00 00 00 00 00
"""

import json
import sys

import cantools

# Messages per generated DBC (distinct standard frame ids 1..BATCH).
BATCH = 400
# Mismatches printed in full.
SHOW = 5

DBC_HEADER = """VERSION ""

NS_ :

BS_:

BU_:

"""

# The attribute cantools reads to mark a message as CAN FD (dbc_loader.py,
# ATTRIBUTE_DEFINITION_VFRAMEFORMAT: index 14 is StandardCAN_FD).
VFRAMEFORMAT_DEF = (
    'BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","reserved","J1939PG",'
    '"reserved","reserved","reserved","reserved","reserved","reserved","reserved",'
    '"reserved","reserved","reserved","StandardCAN_FD","ExtendedCAN_FD";\n'
    'BA_DEF_DEF_ "VFrameFormat" "StandardCAN";\n'
)
STANDARD_CAN_FD = 14


def dbc_text(messages):
    """DBC text for [(frame_id, pdu_len, start_bit, length, order, signed)], one signal S
    per message."""
    parts = [DBC_HEADER]
    for frame_id, pdu_len, start, length, order, signed in messages:
        order_digit = 1 if order == "intel" else 0
        sign = "-" if signed else "+"
        parts.append(
            f"BO_ {frame_id} M{frame_id}: {pdu_len} Vector__XXX\n"
            f' SG_ S : {start}|{length}@{order_digit}{sign} (1,0) [0|0] "" Vector__XXX\n\n'
        )
    parts.append(VFRAMEFORMAT_DEF)
    for frame_id, pdu_len, *_ in messages:
        if pdu_len > 8:
            parts.append(f'BA_ "VFrameFormat" BO_ {frame_id} {STANDARD_CAN_FD};\n')
    return "".join(parts)


def load(messages):
    return cantools.database.load_string(dbc_text(messages), "dbc", strict=True)


def spaced(data):
    return " ".join(f"{b:02X}" for b in data)


def encode(msg, value):
    return msg.encode({"S": value}, scaling=False, strict=True)


def decode(msg, data):
    return msg.decode(data, decode_choices=False, scaling=False)["S"]


def hand_checks():
    """The three examples of the module docstring, through the same path as the cases."""
    examples = [
        ((1, 8, 0, 32, "intel", False), 0x12345678, "78 56 34 12 00 00 00 00"),
        ((2, 8, 7, 16, "motorola", False), 0xABCD, "AB CD 00 00 00 00 00 00"),
        ((3, 8, 3, 12, "motorola", True), -2, "0F FE 00 00 00 00 00 00"),
    ]
    db = load([layout for layout, _, _ in examples])
    for layout, value, expected in examples:
        msg = db.get_message_by_frame_id(layout[0])
        got = encode(msg, value)
        if spaced(got) != expected or decode(msg, got) != value:
            sys.exit(f"hand check failed for {layout}: cantools gives {spaced(got)}, expected {expected}")
    print("hand checks: Intel 0x12345678 -> 78 56 34 12 ..., Motorola 0xABCD -> AB CD ..., "
          "Motorola signed -2 -> 0F FE ...: cantools agrees")


def describe(case):
    return (f"case {case['id']}: PDU {case['pdu_len']} bytes, start bit {case['start_bit']}, "
            f"{case['length']} bits, {case['order']}, {'signed' if case['signed'] else 'unsigned'}, "
            f"value {case['value']}")


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    cases, rejects = [], []
    with open(argv[1], encoding="utf-8") as f:
        for line in f:
            obj = json.loads(line)
            (cases if obj["kind"] == "case" else rejects).append(obj)

    hand_checks()

    mismatches = []
    encode_ok = decode_ok = 0
    with open(argv[2], "w", encoding="utf-8") as out:
        for first in range(0, len(cases), BATCH):
            batch = cases[first:first + BATCH]
            db = load([(i + 1, c["pdu_len"], c["start_bit"], c["length"], c["order"], c["signed"])
                       for i, c in enumerate(batch)])
            for i, case in enumerate(batch):
                msg = db.get_message_by_frame_id(i + 1)
                sig = msg.signals[0]
                wanted = (case["pdu_len"], case["pdu_len"] > 8, case["start_bit"], case["length"],
                          "little_endian" if case["order"] == "intel" else "big_endian", case["signed"])
                loaded = (msg.length, msg.is_fd, sig.start, sig.length, sig.byte_order, sig.is_signed)
                if loaded != wanted:
                    mismatches.append(f"{describe(case)}\n  the DBC loaded as {loaded}, wanted {wanted}")
                    continue
                ours = bytes.fromhex(case["packed"])
                background = bytes.fromhex(case["bg_packed"])
                try:
                    theirs = encode(msg, case["value"])
                except Exception as e:  # noqa: BLE001 - any refusal is a finding
                    mismatches.append(f"{describe(case)}\n  cantools refused to encode it: {e!r}")
                    continue
                try:
                    decoded = decode(msg, background)
                except Exception as e:  # noqa: BLE001
                    decoded = f"error {e!r}"
                problems = []
                if theirs == ours:
                    encode_ok += 1
                else:
                    problems.append("encode differs")
                if decoded == case["value"]:
                    decode_ok += 1
                else:
                    problems.append("decode differs")
                if problems:
                    mismatches.append(
                        f"{describe(case)}: {', '.join(problems)}\n"
                        f"  ours     (zero PDU):        {spaced(ours)}\n"
                        f"  cantools (zero PDU):        {spaced(theirs)}\n"
                        f"  ours     (background PDU):  {spaced(background)}\n"
                        f"  cantools decodes that as:   {decoded}")
                out.write(json.dumps({"kind": "encoded", "id": case["id"], "cantools": theirs.hex()}) + "\n")

        refused = 0
        for r in rejects:
            layout = (1, r["pdu_len"], r["start_bit"], r["length"], r["order"], False)
            try:
                load([layout])
            except Exception as e:  # noqa: BLE001
                if "does not fit" in str(e):
                    refused += 1
                    continue
                mismatches.append(f"refused layout {r}: cantools fails differently: {e!r}")
                continue
            mismatches.append(f"layout {r}: we refuse it, cantools accepts it")

        out.write(json.dumps({"kind": "summary", "encode": encode_ok, "decode": decode_ok,
                              "refused": refused}) + "\n")

    n = len(cases)
    print(f"cantools {cantools.__version__}: encode {encode_ok}/{n} equal to ours, "
          f"decode {decode_ok}/{n} equal to the value, {refused}/{len(rejects)} refused layouts refused")
    if mismatches:
        print(f"{len(mismatches)} mismatch(es); the first {min(SHOW, len(mismatches))}:")
        for m in mismatches[:SHOW]:
            print(m)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
