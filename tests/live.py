#!/usr/bin/env python3
"""Live test of the ECU's Cortex-M4 image running in QEMU in real time: python-can's `slcan`
interface on the CAN side (UART0), and a simulated A02YYUW ultrasonic ranging module on
the sensor side (UART1), each on a TCP port.

    .venv/bin/python tests/live.py CAN_PORT SENSOR_PORT firmware/ecu.dbc

Run by `cargo xtask qemu --live` (and by the check command's `qemu` stage), which starts
QEMU with `-serial tcp:127.0.0.1:CAN_PORT,server=on,wait=on -serial
tcp:127.0.0.1:SENSOR_PORT,server=on,wait=on` and the image's `--sensor uart` first.

The sensor sends a frame (0xFF, distance high byte, low byte, checksum) every 100 ms, as
the module does in its real-time mode, with the faults a harness and a module give:

- distances falling from 2.5 m to 0.6 m (the warning levels off, yellow, red);
- one frame with a bad checksum, one after line noise, one inside the module's 30 mm
  blind zone, one beyond the ECU's 4 m range;
- 1.2 s of silence (an unplugged sensor), then 1.5 m held.

On the CAN side, every DistanceFrame is decoded with the DBC (cantools) and must carry:

1. a Distance the sensor sent, `NothingInRange` (for the frame beyond the range) or the
   invalid value, which may appear only before the sensor's first frame and while it is
   silent: the bad checksum and the blind-zone reading are bad samples that UltraSonic
   holds over;
2. the WarningLevel the thresholds give the distance of the sample before (the frame
   leaves when the distance is written; ObstacleDetection runs after);
3. after malformed SLCAN lines (unknown command, bad hex, non-ASCII, an endless line, a
   remote frame) and a ThresholdConfig frame (encoded by cantools, sent 10 times 20 ms
   apart) chosen to change the level of the 1.5 m now measured: the new thresholds'
   levels, so the ECU applied the frame sent after the garbage.

Prints two lines for the caller, which checks them against the image's own counts:
`live: sent MALFORMED malformed lines and FRAMES frames` and `live: sensor sent FRAMES
frames, BAD bad checksums, BLIND in the blind zone, STRAY stray bytes`.
"""

import socket
import sys
import time

import can
import cantools

FRAMES = 10
NOTHING_IN_RANGE = 4294967294
INVALID = 4294967295
LEVEL_OFF, LEVEL_YELLOW, LEVEL_RED, LEVEL_FAULT = 0, 1, 2, 3
SENSOR_PERIOD = 0.1
SILENCE = (2.05, 3.25)  # after the last falling distance's frame, at 2.0 s
THRESHOLDS_AT = 5.0
END = 7.0
HOLD_MM = 1500

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


def sensor_frame(mm):
    hi, lo = mm >> 8, mm & 0xFF
    return bytes([0xFF, hi, lo, (0xFF + hi + lo) & 0xFF])


def sensor_script():
    """(time, bytes, what) for every write to the sensor's UART, and the counts the image
    must report: good frames, bad checksums, blind-zone readings, stray bytes."""
    writes = []
    counts = {"frames": 0, "bad": 0, "blind": 0, "stray": 0}
    sent_mm = set()
    t = SENSOR_PERIOD
    for i, mm in enumerate(range(2500, 500, -100)):
        frame = sensor_frame(mm)
        if i == 5:
            frame = frame[:3] + bytes([(frame[3] + 1) & 0xFF])
            if 0xFF in frame[1:]:
                sys.exit("live: the bad frame holds a header byte; test broken")
            counts["bad"] += 1
            counts["stray"] += 3  # its bytes after the header start no frame
        elif i == 8:
            noise = b"\x00\x13\x37"
            frame = noise + frame
            counts["stray"] += len(noise)
            counts["frames"] += 1
            sent_mm.add(mm)
        elif i == 11:
            frame = sensor_frame(20)
            counts["frames"] += 1
            counts["blind"] += 1
        elif i == 14:
            frame = sensor_frame(5000)
            counts["frames"] += 1
        else:
            counts["frames"] += 1
            sent_mm.add(mm)
        writes.append((t, frame))
        t += SENSOR_PERIOD
    if writes[-1][0] > SILENCE[0]:
        sys.exit("live: the falling distances overrun the silence; test broken")
    t = SILENCE[1]
    while t < END:
        writes.append((t, sensor_frame(HOLD_MM)))
        counts["frames"] += 1
        t += SENSOR_PERIOD
    sent_mm.add(HOLD_MM)
    return writes, counts, sent_mm


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


def connect_can(port):
    deadline = time.monotonic() + 20
    while True:
        try:
            return can.Bus(interface="slcan", channel=f"socket://127.0.0.1:{port}", bitrate=500000)
        except can.CanError as e:
            if time.monotonic() > deadline:
                sys.exit(f"live: cannot open socket://127.0.0.1:{port}: {e}")
            time.sleep(0.2)


def connect_sensor(port):
    deadline = time.monotonic() + 20
    while True:
        try:
            return socket.create_connection(("127.0.0.1", port))
        except OSError as e:
            if time.monotonic() > deadline:
                sys.exit(f"live: cannot connect to the sensor's UART on port {port}: {e}")
            time.sleep(0.2)


def check_levels(frames, red_below, yellow_below, what):
    # The distance triggers the frame as the sonar task writes it; ObstacleDetection runs
    # after, so each frame carries the level of the previous sample's distance.
    for (_, distance, _), (_, _, level) in zip(frames, frames[1:]):
        want = expected_level(distance, red_below, yellow_below)
        if level != want:
            sys.exit(
                f"live: {what}: Distance {distance} mm came with WarningLevel {level}, "
                f"thresholds red < {red_below}, yellow < {yellow_below} give {want}"
            )


def run(bus, sensor, db, red, yellow):
    """Plays the sensor's script and the PC's sends against the clock; returns every
    DistanceFrame received as (seconds since start, Distance, WarningLevel)."""
    frame = db.get_message_by_name("DistanceFrame")
    config = db.get_message_by_name("ThresholdConfig")
    writes, _, _ = sensor_script()
    actions = [(t, lambda b=b: sensor.sendall(b)) for t, b in writes]

    def malformed():
        raw = bus.serialPortOrig
        for line in MALFORMED:
            raw.write(line)
        raw.flush()

    data = config.encode({"RedBelow": red, "YellowBelow": yellow})
    actions.append((THRESHOLDS_AT, malformed))
    for i in range(FRAMES):
        # The same frame several times, 20 ms apart: each is applied again, and the image
        # measures its receive path once per frame.
        message = can.Message(arbitration_id=config.frame_id, data=data, is_extended_id=False)
        actions.append((THRESHOLDS_AT + 0.001 + 0.02 * i, lambda m=message: bus.send(m)))
    actions.sort(key=lambda a: a[0])

    got = []
    t0 = time.monotonic()
    while True:
        now = time.monotonic() - t0
        while actions and actions[0][0] <= now:
            actions.pop(0)[1]()
        if now >= END:
            return got
        wait = (actions[0][0] if actions else END) - now
        msg = bus.recv(timeout=max(0.0, min(wait, 0.05)))
        if msg is None or msg.arbitration_id != frame.frame_id or msg.is_extended_id:
            continue
        decoded = db.decode_message(msg.arbitration_id, msg.data, decode_choices=False, scaling=False)
        got.append((time.monotonic() - t0, decoded["Distance"], decoded["WarningLevel"]))


def main(can_port, sensor_port, dbc_path):
    db = cantools.database.load_file(dbc_path)
    # Thresholds that change the level of the distance held at the end: Red instead of
    # Yellow.
    red, yellow = HOLD_MM + 1000, HOLD_MM + 2000
    if expected_level(HOLD_MM, red, yellow) == expected_level(HOLD_MM, 1000, 2000):
        sys.exit("live: the new thresholds would not change the level; test broken")
    bus = connect_can(can_port)
    sensor = connect_sensor(sensor_port)
    try:
        frames = run(bus, sensor, db, red, yellow)
    finally:
        sensor.close()
        bus.shutdown()

    # One frame per 40 ms sample; QEMU's clock may lag the host's on a loaded machine.
    minimum = int(END / 0.04 / 2)
    if len(frames) < minimum:
        sys.exit(f"live: {len(frames)} DistanceFrames in {END} s, expected at least {minimum}")
    _, counts, sent_mm = sensor_script()

    # 1. Distances: what the sensor sent, nothing in range, or invalid while it is silent.
    first_frame = SENSOR_PERIOD
    for t, distance, _ in frames:
        if distance == INVALID:
            before_first = t < first_frame + 0.15
            silent = SILENCE[0] + 0.25 < t < SILENCE[1] + 0.35
            if not (before_first or silent):
                sys.exit(f"live: an invalid distance at {t:.3f} s, while the sensor was sending")
        elif distance != NOTHING_IN_RANGE and distance not in sent_mm:
            sys.exit(f"live: Distance {distance} mm at {t:.3f} s was never sent by the sensor")
    silent = [f for f in frames if f[1] == INVALID and SILENCE[0] < f[0]]
    if len(silent) < 5:
        sys.exit(f"live: {len(silent)} invalid distances while the sensor was silent, expected at least 5")
    if not any(d == NOTHING_IN_RANGE for _, d, _ in frames):
        sys.exit("live: the reading beyond the range never came out as NothingInRange")

    # 2. and 3. Levels, under the default thresholds and then the ones sent.
    before = [f for f in frames if f[0] < THRESHOLDS_AT]
    after = [f for f in frames if f[0] > THRESHOLDS_AT + 0.3]
    check_levels(before, 1000, 2000, "default thresholds")
    check_levels(after, red, yellow, "after ThresholdConfig")
    if not all(d == HOLD_MM for _, d, _ in after):
        sys.exit("live: the held distance did not come through unchanged")
    print(
        f"live: received {len(frames)} DistanceFrames: distances the sensor sent, "
        f"{len(silent)} invalid while it was silent; levels of red < 1000, yellow < 2000 on "
        f"{len(before)}, then of ThresholdConfig RedBelow={red} YellowBelow={yellow} (sent after "
        f"{len(MALFORMED)} malformed lines) on {len(after)}"
    )
    print(f"live: sent {len(MALFORMED)} malformed lines and {FRAMES} frames")
    print(
        f"live: sensor sent {counts['frames']} frames, {counts['bad']} bad checksums, "
        f"{counts['blind']} in the blind zone, {counts['stray']} stray bytes"
    )


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])
