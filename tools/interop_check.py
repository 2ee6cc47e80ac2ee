#!/usr/bin/env python3
"""Interop check: the ECU's CAN log, read by python-can and decoded by cantools with
firmware/ecu.dbc, must agree with the ECU's own trace.

    .venv/bin/python tools/interop_check.py ECU.dbc CAN.log TRACE.csv

CAN.log is the candump log `cw-ecu --can-log` writes; TRACE.csv the `--trace` CSV
(time_ms,true_distance_mm,measured_distance_mm,level,red,yellow,measurement). For every DistanceFrame the
decoded Distance must equal the distance the ECU measured at that sonar sample (the trace
row of the same 10 ms step): a number when there was one, 4294967294 for nothing in range
and 4294967295 (invalid) on a sensor fault. Run by `cargo xtask ci` (stage `interop`).
"""

import csv
import sys

import can
import cantools

EPOCH_S = 1700000000
NOTHING_IN_RANGE = 4294967294
INVALID = 4294967295


def main(dbc_path, log_path, trace_path):
    db = cantools.database.load_file(dbc_path)
    distance_frame = db.get_message_by_name("DistanceFrame")

    with open(trace_path, newline="") as f:
        rows = {int(r["time_ms"]): r for r in csv.DictReader(f)}

    frames = list(can.LogReader(log_path))
    if not frames:
        sys.exit(f"interop: python-can read no frame from {log_path}")
    checked = 0
    mismatches = []
    for msg in frames:
        if msg.arbitration_id != distance_frame.frame_id:
            continue
        decoded = db.decode_message(msg.arbitration_id, msg.data, decode_choices=False, scaling=False)
        t_ms = round((msg.timestamp - EPOCH_S) * 1000, 3)
        row = rows.get(int(t_ms // 10) * 10)
        if row is None:
            mismatches.append(f"no trace row for the frame at {t_ms} ms")
            continue
        kind = row["measurement"]
        if kind == "distance":
            expected = int(row["measured_distance_mm"])
        elif kind == "invalid":
            expected = INVALID
        else:
            expected = NOTHING_IN_RANGE
        if decoded["Distance"] != expected:
            mismatches.append(f"{t_ms} ms: CAN says {decoded['Distance']}, trace says {expected} ({row})")
        if decoded["WarningLevel"] not in (0, 1, 2, 3):
            mismatches.append(f"{t_ms} ms: WarningLevel {decoded['WarningLevel']} is not in the DBC's table")
        checked += 1
    if checked == 0:
        sys.exit("interop: no DistanceFrame in the log")
    if mismatches:
        print("\n".join(mismatches[:10]))
        sys.exit(f"interop: {len(mismatches)} of {checked} DistanceFrames disagree with the trace")
    print(
        f"interop: python-can read {len(frames)} frames from {log_path}; cantools decoded "
        f"{checked} DistanceFrames with {dbc_path}; every distance equals the trace"
    )


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
