#!/usr/bin/env python3
"""python-can's side of the log-format check (`cargo xtask log-formats`).

    .venv/bin/python tools/log_formats.py FRAMES.jsonl DIR

FRAMES.jsonl holds one frame per line:

    {"timestamp": float, "channel": int (python-can's, from 0), "id": int,
     "extended": bool, "kind": "classic"|"fd"|"remote"|"error", "brs": bool,
     "esi": bool, "dlc": int (remote frames), "data": hex}

The frames are written with python-can's writers to DIR/frames.asc, DIR/frames.blf and
DIR/frames.log (candump), then read back with python-can's readers; what the readers give
is written to DIR/<format>.jsonl in the same form (time stamps as Python's repr, so that
they compare exactly), for `cw-can`'s readings to be compared with.
"""

import json
import sys

import can


def message(f):
    kind = f["kind"]
    return can.Message(
        timestamp=f["timestamp"],
        channel=f["channel"],
        arbitration_id=f["id"],
        is_extended_id=f["extended"],
        is_remote_frame=kind == "remote",
        is_error_frame=kind == "error",
        is_fd=kind == "fd",
        bitrate_switch=f.get("brs", False),
        error_state_indicator=f.get("esi", False),
        dlc=f["dlc"] if kind == "remote" else None,
        data=bytes.fromhex(f["data"]),
    )


def record(m):
    kind = ("error" if m.is_error_frame else "remote" if m.is_remote_frame
            else "fd" if m.is_fd else "classic")
    return {
        "timestamp": repr(m.timestamp),
        "channel": m.channel,
        "id": m.arbitration_id,
        "extended": m.is_extended_id,
        "kind": kind,
        "brs": m.bitrate_switch,
        "esi": m.error_state_indicator,
        "dlc": m.dlc,
        "data": m.data.hex().upper(),
    }


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    with open(argv[1], encoding="utf-8") as f:
        frames = [message(json.loads(line)) for line in f if line.strip()]
    out = argv[2]
    writers = {
        "asc": can.ASCWriter,
        "blf": can.BLFWriter,
        "log": can.CanutilsLogWriter,
    }
    for ext, writer in writers.items():
        w = writer(f"{out}/frames.{ext}")
        for m in frames:
            w.on_message_received(m)
        w.stop()
    readers = {
        "asc": can.ASCReader,
        "blf": can.BLFReader,
        "log": can.CanutilsLogReader,
    }
    for ext, reader in readers.items():
        with open(f"{out}/{ext}.jsonl", "w", encoding="utf-8") as f:
            for m in reader(f"{out}/frames.{ext}"):
                f.write(json.dumps(record(m)) + "\n")
    print(f"python-can {can.__version__} wrote and read back {len(frames)} frames as ASC, BLF and candump")


if __name__ == "__main__":
    main(sys.argv)
