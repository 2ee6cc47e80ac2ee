#!/usr/bin/env python3
"""Differential test of cw-can's DBC decoding and encoding against cantools.

Run by `cargo xtask dbc-differential` (use that: it generates the DBCs and cases from a
seeded generator and compares), as

    .venv/bin/python tools/dbc_differential.py CASES.jsonl OUT.jsonl

CASES.jsonl holds one JSON object per line:

    {"id", "dbc": path of a DBC file, "strict": bool, "message": name, "op": "decode",
     "data": hex}
    {"id", "dbc", "strict", "message", "op": "encode", "values": {signal: text}}
    {"id", "dbc", "strict", "op": "load"}

A value's text is an integer, a float (Python's repr) or a value-table name. For each case
cantools (loaded strict, as `cantools decode` does, or with `strict=False` where the case
says so, as `cantools decode --no-strict` does) decodes the bytes (scaled, with value
table names, no truncated frames) or encodes the values (scaled, strict: ranges checked,
every signal needed). OUT.jsonl gets one object per case:

    {"id", "ok": true, "signals": {name: ["int", "123"] | ["float", repr] | ["choice", name]}}
    {"id", "ok": true, "data": hex}
    {"id", "ok": true, "loaded": true}
    {"id", "ok": false, "error": text}

Numbers travel as text so that 64-bit integers and NaN survive JSON.
"""

import json
import sys

import cantools
from cantools.database.namedsignalvalue import NamedSignalValue


def value_of(text):
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def number(v):
    if isinstance(v, NamedSignalValue):
        return ["choice", v.name]
    if isinstance(v, bool):
        return ["int", str(int(v))]
    if isinstance(v, int):
        return ["int", str(v)]
    return ["float", repr(float(v))]


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    dbs = {}
    out = []
    with open(argv[1], encoding="utf-8") as f:
        for line in f:
            case = json.loads(line)
            key = (case["dbc"], case.get("strict", True))
            if key not in dbs:
                try:
                    dbs[key] = cantools.database.load_file(key[0], strict=key[1])
                except Exception as e:  # noqa: BLE001 - a refused DBC is a verdict too
                    dbs[key] = e
            db = dbs[key]
            result = {"id": case["id"]}
            try:
                if isinstance(db, Exception):
                    raise db
                if case["op"] == "load":
                    result["loaded"] = True
                elif case["op"] == "decode":
                    msg = db.get_message_by_name(case["message"])
                    decoded = msg.decode(bytes.fromhex(case["data"]), decode_choices=True,
                                         scaling=True, allow_truncated=False)
                    result["signals"] = {k: number(v) for k, v in decoded.items()}
                else:
                    msg = db.get_message_by_name(case["message"])
                    values = {k: value_of(v) for k, v in case["values"].items()}
                    result["data"] = msg.encode(values, scaling=True, strict=True).hex().upper()
                result["ok"] = True
            except Exception as e:  # noqa: BLE001 - every refusal is a verdict to compare
                result["ok"] = False
                result["error"] = f"{type(e).__name__}: {e}"
            out.append(json.dumps(result))
    with open(argv[2], "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv)
