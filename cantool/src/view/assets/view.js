// The page of `cw-can view`: draws each snapshot the server streams (/events). Every
// number shown comes from the bus: the distance and the warning level of the newest
// DistanceFrame, decoded with the DBC by the server. Nothing is computed here but the
// drawing.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
// The scenes: the sensor (the vehicle's front) at x = 150, 180 px per metre, floor to 4 m
// (the sensor's range) in 0.5 m tiles.
const SENSOR_X = 150;
const PX_PER_M = 180;
const FLOOR_M = 4;
const TILE_M = 0.5;
// The chart: 10 s across 840 px, 0 to 4 m over 160 px.
const CHART = { left: 60, right: 900, top: 30, bottom: 190, seconds: 10, metres: 4 };
// The view's rule: no frame for 200 ms is "no signal".
const NO_SIGNAL_S = 0.2;

const $ = (id) => document.getElementById(id);

function el(name, attrs, text) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

function xAt(metres) {
  return SENSOR_X + metres * PX_PER_M;
}

// The floors' tiles and the metre marks, drawn once.
function drawFloors() {
  const tiles = FLOOR_M / TILE_M;
  for (let i = 0; i < tiles; i++) {
    const x = xAt(i * TILE_M);
    const w = TILE_M * PX_PER_M;
    for (let row = 0; row < 2; row++) {
      $("top-floor").appendChild(el("rect", {
        x, y: 30 + row * w, width: w, height: w,
        class: (i + row) % 2 ? "tile dark" : "tile",
      }));
    }
    $("side-floor").appendChild(el("rect", {
      x, y: 160, width: w, height: 12, class: i % 2 ? "tile dark" : "tile",
    }));
  }
  for (let m = 0; m <= FLOOR_M; m++) {
    const x = xAt(m);
    for (const [g, y] of [["top-ticks", 210], ["side-ticks", 172]]) {
      $(g).appendChild(el("line", { x1: x, x2: x, y1: y, y2: y + 10, "data-m": m }));
      $(g).appendChild(el("text", { x, y: y + 26, "data-m": m }, `${m} m`));
    }
  }
}

function chartY(mm) {
  const m = Math.min(mm / 1000, CHART.metres);
  return CHART.bottom - (m / CHART.metres) * (CHART.bottom - CHART.top);
}

function chartX(ago) {
  return CHART.right - (ago / CHART.seconds) * (CHART.right - CHART.left);
}

// The chart's axes; the threshold lines are placed by each snapshot.
function drawGrid() {
  const g = $("chart-grid");
  for (let m = 0; m <= CHART.metres; m++) {
    const y = chartY(m * 1000);
    g.appendChild(el("line", { x1: CHART.left, x2: CHART.right, y1: y, y2: y }));
    g.appendChild(el("text", { x: CHART.left - 8, y: y + 4, class: "y" }, `${m} m`));
  }
  for (let s = 0; s <= CHART.seconds; s += 2) {
    const x = chartX(s);
    g.appendChild(el("text", { x, y: CHART.bottom + 36, class: "x" }, s ? `-${s} s` : "now"));
  }
  for (const cls of ["red", "yellow"]) {
    g.appendChild(el("line", { id: `threshold-${cls}`, x1: CHART.left, x2: CHART.right, class: `threshold ${cls}` }));
    g.appendChild(el("text", { id: `threshold-${cls}-label`, x: CHART.left + 6, class: `threshold-label ${cls}` }));
  }
}

// The thresholds of the newest ThresholdConfig on the bus, or the paper's before any.
function drawThresholds(t) {
  const from = t.t === null ? "the paper's" : "from the bus";
  for (const [cls, mm] of [["red", t.red_below_mm], ["yellow", t.yellow_below_mm]]) {
    const y = chartY(mm);
    const line = $(`threshold-${cls}`);
    // Above the chart's 4 m: the line sits on its top edge and its label says so.
    const above = mm > CHART.metres * 1000;
    line.setAttribute("y1", y);
    line.setAttribute("y2", y);
    line.dataset.mm = mm;
    const label = $(`threshold-${cls}-label`);
    label.setAttribute("y", y - 5);
    label.textContent = `${cls} below ${(mm / 1000).toFixed(mm % 100 ? 3 : 1)} m (${from}${above ? ", above the chart" : ""})`;
    // The yellow label goes under its line when the two lines are close.
    if (cls === "yellow" && Math.abs(chartY(t.red_below_mm) - y) < 16) label.setAttribute("y", y + 14);
  }
}

function drawChart(points) {
  let d = "";
  let pen = false;
  const levels = $("chart-levels");
  levels.replaceChildren();
  let run = null;
  const flush = (end) => {
    if (run) {
      levels.appendChild(el("rect", {
        x: chartX(run.from), y: CHART.bottom + 8, width: Math.max(1, chartX(end) - chartX(run.from)),
        height: 10, class: `level l${run.level}`,
      }));
    }
  };
  let previous = null;
  for (const [ago, mm, level] of points) {
    if (ago > CHART.seconds) continue;
    // 200 ms without a frame is "no signal": the line and the band stop there.
    if (previous !== null && previous - ago > NO_SIGNAL_S) {
      flush(previous - NO_SIGNAL_S);
      run = null;
      pen = false;
    }
    previous = ago;
    if (mm === null) {
      pen = false;
    } else {
      d += `${pen ? "L" : "M"}${chartX(ago).toFixed(1)} ${chartY(mm).toFixed(1)} `;
      pen = true;
    }
    if (!run || run.level !== level) {
      flush(ago);
      run = { from: ago, level };
    }
  }
  const last = points.length ? points[points.length - 1][0] : 0;
  flush(last);
  $("chart-distance").setAttribute("d", d.trim());
}

function setLed(id, on, blink) {
  const led = $(id);
  led.dataset.on = on;
  led.dataset.blink = blink;
  led.classList.toggle("on", on);
  led.classList.toggle("blink", blink);
}

function setObstacle(mm) {
  const top = $("top-obstacle");
  const side = $("side-obstacle");
  const beams = [$("top-beam"), $("side-beam")];
  if (mm === null) {
    $("beyond").style.display = "none";
    for (const e of [top, side, ...beams]) e.style.display = "none";
    top.dataset.distanceMm = side.dataset.distanceMm = "";
    return;
  }
  // Beyond the floor (the sensor's 4 m): the obstacle waits at its end, marked.
  const beyond = mm > FLOOR_M * 1000;
  $("beyond").style.display = beyond ? "" : "none";
  const x = xAt(Math.min(mm, FLOOR_M * 1000) / 1000);
  const r = Number(top.getAttribute("r"));
  top.setAttribute("cx", x + r);
  side.setAttribute("x", x);
  top.dataset.distanceMm = side.dataset.distanceMm = mm;
  $("top-beam").setAttribute("points", `${SENSOR_X},120 ${x},${120 - r} ${x},${120 + r}`);
  $("side-beam").setAttribute("points", `${SENSOR_X},122 ${x},100 ${x},150`);
  for (const e of [top, side, ...beams]) e.style.display = "";
}

const STATUS_TEXT = { NoSignal: "no signal", Fault: "Fault", Live: "live" };

function describe(reading) {
  switch (reading.kind) {
    case "Distance": return `${(reading.mm / 1000).toFixed(3)} m`;
    case "NothingInRange": return "nothing in range";
    default: return "invalid";
  }
}

let seeking = false;

function render(s) {
  const shown = s.shown;
  document.body.dataset.status = shown.status;
  document.body.dataset.now = s.now;
  $("status").textContent = STATUS_TEXT[shown.status];
  $("status").className = `status ${shown.status}`;
  $("source").textContent = `${s.source}: ${s.name.split("/").pop()}`;
  $("source").title = s.name;
  setLed("led-red", shown.red, shown.blinking);
  setLed("led-yellow", shown.yellow, shown.blinking);
  const sample = shown.sample;
  const mm = sample && sample.reading.kind === "Distance" ? sample.reading.mm : null;
  setObstacle(mm);
  $("readout").textContent = sample ? describe(sample.reading) : "\u2014";
  $("level").textContent = sample ? sample.level : "\u2014";
  // A replay's frames by their time in the log, a simulation's by its time; an adapter's
  // by the time of day they arrived.
  $("frame-time").textContent = !sample ? "\u2014"
    : s.origin !== null ? `${(sample.t - s.origin).toFixed(3)} s`
    : new Date(sample.t * 1000).toISOString().slice(11, 23);
  $("bad-count").textContent = s.bad_count;
  $("bad").replaceChildren(...s.bad.map((b) => {
    const li = document.createElement("li");
    li.textContent = b;
    return li;
  }));
  drawChart(s.chart);
  drawThresholds(s.thresholds);
  const clock = s.clock;
  $("controls").hidden = !clock;
  if (clock) {
    document.body.dataset.position = clock.position;
    $("play").textContent = clock.playing ? "Pause" : "Play";
    $("play").dataset.playing = clock.playing;
    $("seek").max = clock.duration;
    if (!seeking) $("seek").value = clock.position;
    $("time").textContent = `${clock.position.toFixed(2)} / ${clock.duration.toFixed(2)} s`;
    const speed = String(clock.speed);
    if (![...$("speed").options].some((o) => o.value === speed)) {
      $("speed").appendChild(new Option(speed, speed));
    }
    if (document.activeElement !== $("speed")) $("speed").value = speed;
  }
  $("send").disabled = !s.can_send;
  $("send").title = s.can_send ? "" : s.clock ? "a replayed log has no bus to send to" : "no bus to send to";
}

async function post(path, body) {
  const r = await fetch(path, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  });
  const text = await r.text();
  if (!r.ok) throw new Error(text);
  return text;
}

// Without the server the page knows nothing of the bus: it shows nothing, not the last
// picture.
function disconnected() {
  document.body.dataset.status = "NoSignal";
  $("status").textContent = "no connection to cw-can";
  $("status").className = "status NoSignal";
  setLed("led-red", false, false);
  setLed("led-yellow", false, false);
  setObstacle(null);
  for (const id of ["readout", "level", "frame-time"]) $(id).textContent = "\u2014";
  drawChart([]);
}

function connect() {
  const events = new EventSource("/events");
  events.onmessage = (e) => render(JSON.parse(e.data));
  events.onerror = () => {
    disconnected();
    // The browser retries by itself, except after an answer that is not a stream (503
    // when the server has too many): then the page tries again in a while.
    if (events.readyState === EventSource.CLOSED) setTimeout(connect, 2000);
  };
}

// A refused control is shown, not lost.
function report(promise) {
  promise.then(() => { $("control-result").textContent = ""; })
    .catch((err) => { $("control-result").textContent = err.message; });
}

function wire() {
  $("play").onclick = () => report(post("/control", { play: $("play").dataset.playing !== "true" }));
  $("speed").onchange = () => report(post("/control", { speed: Number($("speed").value) }));
  $("seek").oninput = () => { seeking = true; };
  $("seek").onchange = () => {
    report(post("/control", { seek: Number($("seek").value) }).finally(() => { seeking = false; }));
  };
  $("send-form").onsubmit = (e) => {
    e.preventDefault();
    const body = {
      red_below_mm: Number($("red-below").value),
      yellow_below_mm: Number($("yellow-below").value),
    };
    post("/send", body)
      .then(() => { $("send-result").textContent = `sent: red below ${body.red_below_mm} mm, yellow below ${body.yellow_below_mm} mm`; })
      .catch((err) => { $("send-result").textContent = `not sent: ${err.message}`; });
  };
}

drawFloors();
drawGrid();
wire();
connect();
