#!/usr/bin/env python3
"""The view of the bus as a person sees it: `cw-can view` replaying the ECU's Figure 7 log,
opened in headless Chromium (driven over the DevTools protocol), checked against the ECU's
trace, and its server tried with bad lines, many clients and a long replay.

    .venv/bin/python tools/view_check.py CW_CAN DBC FIGURE7.log FIGURE7.csv LONG.log SHOTS_DIR

CW_CAN is the `cw-can` binary; FIGURE7.log and .csv what `cw-ecu --scenario
scenarios/figure7.txt --can-log --trace` writes; LONG.log a 30-minute log of the ECU. The
four screenshots (the paper's Figure 8 a-d) are written to SHOTS_DIR. Run by `cargo xtask
ci` (stage `view`).

What is checked:
1. At the middle of each hold (0.5, 1.0, 1.5 and 2.0 m), paused there: the obstacle's near
   edge lies at the distance on the floor's metre marks (from above and from the side, to a
   pixel), the LEDs and the level are those of the trace, the readout is the trace's
   measured distance.
2. At the log's start, where the ECU reports a fault: "Fault", both LEDs blinking.
3. A log with bad lines and a second without frames: the bad lines are counted and named
   on the page, the rest plays; "no signal" in the gap, the obstacle gone, the LEDs off.
4. The host simulation live (`--simulate`), an obstacle at 0.8 m: thresholds typed into
   the sender panel reach the ECU and the LEDs on the page change; a pair the ECU would
   refuse is refused on the page.
5. Ten event streams at once, five of them cut mid-stream: the server goes on, lets go of
   the cut ones, the others keep receiving.
6. The 30-minute log replayed at 1000x with ten streams open: the server's resident
   memory stays flat (printed: before, during and after).
"""

import base64
import csv
import json
import os
import re
import select
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

import websocket

from interop_check import EPOCH_S

# The holds of scenarios/figure7.txt: (distance mm, start ms); each lasts 3 s.
HOLDS = [(500, 0), (1000, 3000), (1500, 6000), (2000, 9000)]
HOLD_MS = 3000
SHOT_NAMES = ["figure8-a-0.5m.png", "figure8-b-1.0m.png", "figure8-c-1.5m.png", "figure8-d-2.0m.png"]
WINDOW = (1300, 1000)
TIMEOUT_S = 10.0
# The memory check: how much the server's resident set may grow once the replay plays.
RSS_GROWTH_MAX_KIB = 1024


def fail(message):
    sys.exit(f"view: {message}")


class View:
    """A `cw-can view` process: replaying a log, paused, or on another source."""

    def __init__(self, cw_can, dbc, log, speed=1.0, source=None):
        source = source or ["--replay", log, "--paused", "--speed", str(speed)]
        self.proc = subprocess.Popen(
            [cw_can, "view", "--dbc", dbc, "--listen", "127.0.0.1:0", *source],
            stdout=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self.proc.stdout], [], [], TIMEOUT_S)
        line = self.proc.stdout.readline() if ready else ""
        match = re.search(r"http://(127\.0\.0\.1:\d+)/", line)
        if not match:
            self.proc.kill()
            fail(f"cw-can view did not print its address: {line!r}")
        self.addr = match.group(1)
        self.url = f"http://{self.addr}/"

    def get(self, path):
        with urllib.request.urlopen(self.url + path.lstrip("/"), timeout=TIMEOUT_S) as r:
            return r.read()

    def state(self):
        return json.loads(self.get("state"))

    def control(self, **body):
        req = urllib.request.Request(self.url + "control", data=json.dumps(body).encode(), method="POST",
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=TIMEOUT_S) as r:
                return r.read().decode()
        except urllib.error.HTTPError as e:
            fail(f"POST /control {body}: {e.code} {e.read().decode(errors='replace')}")

    def proc_status(self, field):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
        fail(f"no {field} in /proc/{self.proc.pid}/status")

    def close(self):
        self.proc.kill()
        self.proc.wait()


class Browser:
    """Headless Chromium and one page, over the DevTools protocol."""

    def __init__(self):
        chromium = shutil.which("chromium") or fail("chromium is not installed (cargo xtask setup installs it)")
        self.profile = tempfile.mkdtemp(prefix="cw-view-chromium-")
        self.proc = subprocess.Popen(
            [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
             "--no-first-run", "--hide-scrollbars", "--force-device-scale-factor=1",
             f"--window-size={WINDOW[0]},{WINDOW[1]}", f"--user-data-dir={self.profile}",
             "--remote-debugging-port=0", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = os.path.join(self.profile, "DevToolsActivePort")
        deadline = time.monotonic() + TIMEOUT_S
        while not (os.path.exists(port_file) and open(port_file).read().strip()):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                self.close()
                fail("chromium did not open its DevTools port")
            time.sleep(0.05)
        port = open(port_file).read().split()[0]
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=TIMEOUT_S) as r:
            pages = [t for t in json.load(r) if t.get("type") == "page"]
        if not pages:
            self.close()
            fail("chromium has no page")
        # Chromium refuses a DevTools connection that names an Origin.
        self.ws = websocket.create_connection(pages[0]["webSocketDebuggerUrl"], suppress_origin=True,
                                              timeout=TIMEOUT_S)
        self.next_id = 0
        self.call("Page.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=WINDOW[0], height=WINDOW[1],
                  deviceScaleFactor=1, mobile=False)

    def call(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            reply = json.loads(self.ws.recv())
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    fail(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def open(self, url):
        self.call("Page.navigate", url=url)
        self.wait("document.readyState === 'complete' && document.body.dataset.now !== undefined",
                  f"the page at {url} did not load and draw")

    def eval(self, expression):
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            fail(f"the page threw on {expression!r}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def wait(self, expression, what):
        deadline = time.monotonic() + TIMEOUT_S
        while not self.eval(expression):
            if time.monotonic() > deadline:
                fail(what)
            time.sleep(0.05)

    def screenshot(self, path):
        shot = self.call("Page.captureScreenshot", format="png")
        with open(path, "wb") as f:
            f.write(base64.b64decode(shot["data"]))

    def close(self):
        if getattr(self, "ws", None):
            self.ws.close()
        self.proc.kill()
        self.proc.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


# What the page shows, read from its document: the geometry of the drawing, not the
# script's variables.
PAGE_STATE = """(() => {
  const box = (sel) => { const e = document.querySelector(sel); const r = e.getBoundingClientRect();
    return { left: r.left, right: r.right, width: r.width, shown: getComputedStyle(e).display !== 'none' && r.width > 0 }; };
  const tick = (view, m) => box(`#${view}-ticks line[data-m="${m}"]`).left;
  const led = (id) => { const e = document.getElementById(id); return { on: e.dataset.on === 'true', blink: e.dataset.blink === 'true' }; };
  return {
    now: Number(document.body.dataset.now), status: document.getElementById('status').textContent,
    readout: document.getElementById('readout').textContent, level: document.getElementById('level').textContent,
    badCount: document.getElementById('bad-count').textContent,
    bad: [...document.querySelectorAll('#bad li')].map((li) => li.textContent),
    red: led('led-red'), yellow: led('led-yellow'),
    lines: ['red', 'yellow'].map((c) => document.getElementById(`threshold-${c}`).dataset.mm),
    top: { obstacle: box('#top-obstacle'), m0: tick('top', 0), m1: tick('top', 1) },
    side: { obstacle: box('#side-obstacle'), m0: tick('side', 0), m1: tick('side', 1) },
  };
})()"""


def paused_at(view, browser, position):
    """Pauses the replay at `position` s and waits until the page shows that moment."""
    view.control(play=False, seek=position)
    now = view.state()["now"]
    browser.wait(f"Math.abs(Number(document.body.dataset.now) - {now!r}) < 1e-6",
                 f"the page did not show the replay at {position} s")
    return browser.eval(PAGE_STATE)


def check_holds(view, browser, trace_path, shots_dir):
    with open(trace_path, newline="") as f:
        rows = {int(r["time_ms"]): r for r in csv.DictReader(f)}
    start = view.state()["clock"]["start"]
    checked = []
    for (mm, begin_ms), shot in zip(HOLDS, SHOT_NAMES):
        mid_ms = begin_ms + HOLD_MS // 2
        row = rows.get(mid_ms) or fail(f"the trace has no row at {mid_ms} ms")
        page = paused_at(view, browser, EPOCH_S + mid_ms / 1000 - start)
        where = f"at {mm / 1000:.1f} m ({mid_ms} ms)"
        expected_mm = int(row["measured_distance_mm"])
        if expected_mm != mm:
            fail(f"{where}: the trace measured {expected_mm} mm, not the hold's {mm} mm")
        if page["status"] != "live":
            fail(f"{where}: the page says {page['status']!r}, not live")
        if page["readout"] != f"{expected_mm / 1000:.3f} m":
            fail(f"{where}: the readout is {page['readout']!r}, the trace measured {expected_mm} mm")
        if page["level"] != row["level"]:
            fail(f"{where}: the page shows level {page['level']}, the trace {row['level']}")
        for led in ("red", "yellow"):
            if page[led]["on"] != (row[led] == "1") or page[led]["blink"]:
                fail(f"{where}: the {led} LED is {page[led]}, the trace drives it {row[led]}")
        if page["lines"] != ["1000", "2000"]:
            fail(f"{where}: the chart draws the thresholds at {page['lines']} mm, not the paper's")
        for view_name in ("top", "side"):
            g = page[view_name]
            px_per_m = g["m1"] - g["m0"]
            expected_x = g["m0"] + mm / 1000 * px_per_m
            if not g["obstacle"]["shown"] or abs(g["obstacle"]["left"] - expected_x) > 1.0:
                fail(f"{where}: from the {view_name}, the obstacle's near edge is at x = "
                     f"{g['obstacle']['left']:.1f} px, the floor puts {mm} mm at {expected_x:.1f} px")
        browser.screenshot(os.path.join(shots_dir, shot))
        leds = "+".join(led for led in ("red", "yellow") if page[led]["on"]) or "none"
        checked.append(f"{mm / 1000:.1f} m: {page['readout']}, {page['level']}, LEDs {leds}")
    print("view: " + "; ".join(checked) + f"; screenshots in {shots_dir}")


def check_fault(view, browser):
    page = paused_at(view, browser, 0.0)
    if page["status"] != "Fault" or not all(page[led]["on"] and page[led]["blink"] for led in ("red", "yellow")):
        fail(f"at the log's start the ECU reports a fault; the page shows {page['status']!r}, "
             f"red {page['red']}, yellow {page['yellow']}")
    print("view: a fault at the log's start: Fault, both LEDs blinking")


def damaged_log(figure7_log, path):
    """Figure 7's log with three bad lines, and without frames from 5.0 s to 6.0 s."""
    bad = ["(garbage", "(1700000004.000000) can0 100#F4010000030000000000", "not a log line at all"]
    lines = open(figure7_log).read().splitlines()
    out = []
    for i, line in enumerate(lines):
        stamp = float(line[1:line.index(")")])
        if EPOCH_S + 5.0 <= stamp < EPOCH_S + 6.0:
            continue
        out.append(line)
        if i in (10, 100, 200):
            out.append(bad[(10, 100, 200).index(i)])
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return len(bad)


def check_damage(view, browser, bad_lines):
    start = view.state()["clock"]["start"]
    page = paused_at(view, browser, EPOCH_S + 5.5 - start)
    if page["status"] != "no signal" or page["top"]["obstacle"]["shown"] or page["red"]["on"] or page["yellow"]["on"]:
        fail(f"in a second without frames the page shows {page['status']!r}, obstacle "
             f"{page['top']['obstacle']['shown']}, red {page['red']}, yellow {page['yellow']}")
    if page["badCount"] != str(bad_lines) or len(page["bad"]) != bad_lines:
        fail(f"{bad_lines} bad lines; the page counts {page['badCount']} and names {page['bad']}")
    page = paused_at(view, browser, EPOCH_S + 6.5 - start)
    if page["status"] != "live" or page["readout"] != "1.500 m":
        fail(f"after the gap the replay should go on at 1.5 m: {page['status']!r}, {page['readout']!r}")
    # The chart's line stops at the gap and starts again after it.
    pieces = browser.eval("document.getElementById('chart-distance').getAttribute('d').split('M').length - 1")
    if pieces != 2:
        fail(f"the chart draws the distance in {pieces} pieces across a second without frames, not 2")
    print(f"view: {bad_lines} bad lines counted and named, the rest played; 'no signal' "
          f"in a second without frames, the obstacle gone, the LEDs off, the chart's line broken")


def check_sender(cw_can, dbc, browser, tmp):
    """The host simulation live, an obstacle held at 0.8 m: red. The thresholds typed into
    the sender panel (red below 0.5 m, yellow below 1.0 m) reach the ECU over the bus, and
    the LEDs on the page turn yellow; a pair the ECU would refuse is refused on the page."""
    scenario = os.path.join(tmp, "hold.txt")
    with open(scenario, "w") as f:
        f.write("hold 800 120000\n")
    view = View(cw_can, dbc, None, source=["--simulate", scenario])
    try:
        browser.open(view.url)
        browser.wait("document.getElementById('readout').textContent === '0.800 m' && "
                     "document.getElementById('level').textContent === 'Red' && "
                     "!document.getElementById('send').disabled",
                     "the live simulation did not show 0.8 m, red, with the panel on")
        fill = """(() => {{ document.getElementById('red-below').value = '{}';
            document.getElementById('yellow-below').value = '{}';
            document.getElementById('send').click(); return true; }})()"""
        browser.eval(fill.format(500, 1000))
        browser.wait("document.getElementById('level').textContent === 'Yellow' && "
                     "document.getElementById('led-yellow').dataset.on === 'true' && "
                     "document.getElementById('led-red').dataset.on === 'false'",
                     "after sending red below 500 mm, yellow below 1000 mm, 0.8 m did not turn yellow")
        lines = browser.eval("[document.getElementById('threshold-red').dataset.mm, "
                             "document.getElementById('threshold-yellow').dataset.mm]")
        if lines != ["500", "1000"]:
            fail(f"the chart draws the thresholds at {lines} mm after 500/1000 mm went on the bus")
        said = browser.eval("document.getElementById('send-result').textContent")
        if not said.startswith("sent"):
            fail(f"the panel says {said!r} after a frame the ECU took")
        browser.eval(fill.format(900, 900))
        browser.wait("document.getElementById('send-result').textContent === "
                     "'not sent: red must be below yellow'",
                     "red below 900 mm, yellow below 900 mm was not refused on the page")
        sample = view.state()["shown"]["sample"] or {}
        if sample.get("level") != "Yellow":
            fail(f"after a refused pair the view shows {sample}, not the yellow level")
        # The server goes away: the page shows nothing of the bus, not its last picture.
        view.close()
        browser.wait("document.getElementById('status').textContent === 'no connection to cw-can' && "
                     "document.getElementById('led-red').dataset.on === 'false' && "
                     "document.getElementById('led-yellow').dataset.on === 'false' && "
                     "document.getElementById('readout').textContent === '\u2014'",
                     "with its server gone the page still shows a picture")
    finally:
        view.close()
    print("view: live simulation at 0.8 m, red; thresholds 500/1000 mm sent from the page: "
          "the LEDs turned yellow, the chart's lines moved to 0.5 and 1.0 m; 900/900 mm refused on the page; "
          "the server stopped: 'no connection', nothing shown")


def open_stream(view):
    s = socket.create_connection(tuple(view.addr.rsplit(":", 1)), timeout=TIMEOUT_S)
    s.sendall(f"GET /events HTTP/1.1\r\nHost: {view.addr}\r\n\r\n".encode())
    return s


def read_events(stream, count):
    """Reads until `count` events have arrived (the body is chunked: each event's line
    starts with `data:`)."""
    data = b""
    while data.count(b"data:") < count:
        chunk = stream.recv(65536)
        if not chunk:
            fail("an event stream ended")
        data += chunk
    return data


def streams_settle(view, expected):
    """Waits until the server counts `expected` event streams."""
    deadline = time.monotonic() + TIMEOUT_S
    while view.state()["streams"] != expected:
        if time.monotonic() > deadline:
            fail(f"the server sends {view.state()['streams']} event streams, expected {expected}")
        time.sleep(0.05)


def check_clients(view):
    streams = [open_stream(view) for _ in range(10)]
    for s in streams:
        read_events(s, 2)
    streams_settle(view, 10)
    # Five clients leave mid-stream, without reading what was sent to them.
    for s in streams[:5]:
        s.recv(100)
        s.close()
    streams_settle(view, 5)
    for s in streams[5:]:
        read_events(s, 3)
    for s in streams[5:]:
        s.close()
    streams_settle(view, 0)
    print("view: 10 event streams at once, 5 cut mid-stream: the server let go of them, the other 5 "
          "kept receiving, the server answered")


def check_memory(view):
    streams = [open_stream(view) for _ in range(10)]
    for s in streams:
        read_events(s, 1)
    rss = [view.proc_status("VmRSS")]
    duration = view.state()["clock"]["duration"]
    view.control(play=True)
    time.sleep(0.5)
    rss.append(view.proc_status("VmRSS"))
    while view.state()["clock"]["playing"]:
        for s in streams:
            s.setblocking(False)
            try:
                while s.recv(1 << 20):
                    pass
            except BlockingIOError:
                pass
        rss.append(view.proc_status("VmRSS"))
        time.sleep(0.1)
    for s in streams:
        s.close()
    growth = max(rss[1:]) - rss[1]
    print(f"view: a {duration / 60:.0f}-minute log replayed at 1000x with 10 streams: resident memory "
          f"{rss[0]} KiB paused, {rss[1]} KiB playing, at most {max(rss)} KiB over {len(rss)} samples "
          f"(+{growth} KiB)")
    if growth > RSS_GROWTH_MAX_KIB:
        fail(f"the server's memory grew by {growth} KiB during the replay")


def main(cw_can, dbc, figure7_log, figure7_trace, long_log, shots_dir):
    os.makedirs(shots_dir, exist_ok=True)
    browser = Browser()
    views = []
    try:
        view = View(cw_can, dbc, figure7_log)
        views.append(view)
        browser.open(view.url)
        check_holds(view, browser, figure7_trace, shots_dir)
        check_fault(view, browser)
        with tempfile.TemporaryDirectory() as tmp:
            damaged = os.path.join(tmp, "damaged.log")
            bad_lines = damaged_log(figure7_log, damaged)
            view = View(cw_can, dbc, damaged)
            views.append(view)
            browser.open(view.url)
            check_damage(view, browser, bad_lines)
            check_sender(cw_can, dbc, browser, tmp)
        check_clients(views[0])
        view = View(cw_can, dbc, long_log, speed=1000)
        views.append(view)
        check_memory(view)
    finally:
        for v in views:
            v.close()
        browser.close()


if __name__ == "__main__":
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    main(*sys.argv[1:])
