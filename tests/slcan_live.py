#!/usr/bin/env python3
"""Live interop test: python-can's `slcan` interface against the ECU's Cortex-M4 image
running in QEMU, whose UART0 speaks SLCAN on a TCP port.

    .venv/bin/python tests/slcan_live.py PORT firmware/ecu.dbc

Run by `cargo xtask qemu --live` (and by the check command's `qemu` stage), which starts
QEMU with `-serial tcp:127.0.0.1:PORT,server=on,wait=on` first. Both directions:

1. receive: DistanceFrames arrive live; cantools decodes each with the DBC and its
   WarningLevel must be the level the default thresholds (red < 1000 mm, yellow < 2000 mm)
   give the Distance of the sample before (the frame leaves when the distance is written,
   ObstacleDetection runs after);
2. malformed input: lines a faulty PC could send (unknown command, bad hex, non-ASCII,
   an endless line, a remote frame) go out right before a good frame;
3. transmit: a ThresholdConfig frame (encoded by cantools) chosen so that the level of
   the distance now measured changes; every DistanceFrame after it must carry the level
   the new thresholds give, so the ECU applied the frame sent after the garbage (sent
   10 times, 20 ms apart, so that the image measures its receive path on several frames).

Prints one line for the caller: `slcan-live: sent MALFORMED malformed lines and FRAMES
frames`, which `cargo xtask qemu --live` checks against the image's own counts.
"""

import sys
import time

import can
import cantools

FRAMES = 10
NOTHING_IN_RANGE = 4294967294
INVALID = 4294967295
LEVEL_OFF, LEVEL_YELLOW, LEVEL_RED, LEVEL_FAULT = 0, 1, 2, 3

# Lines a faulty PC might send, each ended by a carriage return: every one must be refused
# (and answered with BEL) without costing the good frame that follows.
MALFORMED = [
    b"x123\r",
    b"t2004F401ZZ03\r",
    b"\xff\xfe\xfd\r",
    b"t20" + b"9" * 100 + b"\r",
    b"r2004\r",
    b"t8000\r",
]


def expected_level(distance, red_below, yellow_below):
    if distance == INVALID:
        return LEVEL_FAULT
    if distance == NOTHING_IN_RANGE:
        return LEVEL_OFF
    if distance < red_below:
        return LEVEL_RED
    if distance < yellow_below:
        return LEVEL_YELLOW
    return LEVEL_OFF


def connect(port):
    deadline = time.monotonic() + 20
    while True:
        try:
            return can.Bus(interface="slcan", channel=f"socket://127.0.0.1:{port}", bitrate=500000)
        except can.CanError as e:
            if time.monotonic() > deadline:
                sys.exit(f"slcan-live: cannot open socket://127.0.0.1:{port}: {e}")
            time.sleep(0.2)


def distance_frames(bus, db, seconds, minimum):
    """The (Distance, WarningLevel) of every DistanceFrame received for `seconds`."""
    frame = db.get_message_by_name("DistanceFrame")
    got = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        msg = bus.recv(timeout=0.1)
        if msg is None or msg.arbitration_id != frame.frame_id or msg.is_extended_id:
            continue
        decoded = db.decode_message(msg.arbitration_id, msg.data, decode_choices=False, scaling=False)
        got.append((decoded["Distance"], decoded["WarningLevel"]))
    if len(got) < minimum:
        sys.exit(f"slcan-live: {len(got)} DistanceFrames in {seconds} s, expected at least {minimum}")
    return got


def check_levels(frames, red_below, yellow_below, what):
    # The distance triggers the frame as the sonar task writes it; ObstacleDetection runs
    # after, so each frame carries the level of the previous sample's distance.
    for (distance, _), (_, level) in zip(frames, frames[1:]):
        want = expected_level(distance, red_below, yellow_below)
        if level != want:
            sys.exit(
                f"slcan-live: {what}: Distance {distance} mm came with WarningLevel {level}, "
                f"thresholds red < {red_below}, yellow < {yellow_below} give {want}"
            )


def main(port, dbc_path):
    db = cantools.database.load_file(dbc_path)
    config = db.get_message_by_name("ThresholdConfig")
    bus = connect(port)
    try:
        # 1. Receive, under the default thresholds. One sample per 40 ms.
        before = distance_frames(bus, db, 1.0, 10)
        check_levels(before, 1000, 2000, "default thresholds")

        # 3. Thresholds that change the level of the distance now measured.
        distance = before[-1][0]
        if distance < 1000:
            red, yellow = 1, 2  # everything is Off
        else:
            red, yellow = distance + 1000, distance + 2000  # Red
        if expected_level(distance, red, yellow) == expected_level(distance, 1000, 2000):
            sys.exit("slcan-live: the new thresholds would not change the level; test broken")

        # 2. Malformed lines, straight before the good frame.
        raw = bus.serialPortOrig
        for line in MALFORMED:
            raw.write(line)
        raw.flush()
        data = config.encode({"RedBelow": red, "YellowBelow": yellow})
        # The same frame several times, 20 ms apart: each is applied again, and the image
        # measures its receive path once per frame.
        for _ in range(FRAMES):
            bus.send(can.Message(arbitration_id=config.frame_id, data=data, is_extended_id=False))
            time.sleep(0.02)

        # Let the sample in flight and the next one pass, then every frame must agree.
        after = distance_frames(bus, db, 1.5, 15)
        settled = after[3:]  # the frames in flight while the thresholds arrived
        check_levels(settled, red, yellow, "after ThresholdConfig")
        print(
            f"slcan-live: received {len(before)} DistanceFrames (levels of red < 1000, yellow < 2000), "
            f"sent ThresholdConfig RedBelow={red} YellowBelow={yellow} after {len(MALFORMED)} malformed "
            f"lines, then {len(settled)} DistanceFrames all with the new thresholds' levels"
        )
        print(f"slcan-live: sent {len(MALFORMED)} malformed lines and {FRAMES} frames")
    finally:
        bus.shutdown()


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
