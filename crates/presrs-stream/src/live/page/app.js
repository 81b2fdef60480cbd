// The live view: server-sent events from /events drawn on canvases. No libraries, no build step.
"use strict";

const TRACE_FRAMES = 600;   // frames of the load trace shown
const LOG_ENTRIES = 200;    // decision log entries kept

const body = document.body;
const image = document.getElementById("image");
const trace = document.getElementById("trace");
const colorbar = document.getElementById("colorbar");
const terrain = document.getElementById("terrain");
const logList = document.getElementById("log");

let info = { units: "", classes: [] };
let session = -1;
let loads = [];        // [index, load] of the current session
let stances = [];      // {start, end|null} in frame numbers
let framesDrawn = 0;
let labels = [];

// A perceptual colour map (viridis, 9 stops), interpolated into a 256-entry table.
const STOPS = [[68,1,84],[72,40,120],[62,74,137],[49,104,142],[38,130,142],[31,158,137],[53,183,121],[110,206,88],[253,231,37]];
const LUT = [];
for (let i = 0; i < 255; i++) {
  const x = i / 254 * (STOPS.length - 1), k = Math.min(Math.floor(x), STOPS.length - 2), f = x - k;
  LUT.push(STOPS[k].map((c, j) => Math.round(c + f * (STOPS[k + 1][j] - c))));
}
LUT.push([128, 128, 128]);  // 255: absent sensel

function fmt(x) {
  if (!isFinite(x)) return "—";
  const a = Math.abs(x);
  return a >= 1000 ? x.toFixed(0) : a >= 10 ? x.toFixed(1) : x.toFixed(2);
}

function drawColorbar(top) {
  const ctx = colorbar.getContext("2d"), h = colorbar.height;
  for (let y = 0; y < h; y++) {
    const c = LUT[Math.round((1 - y / (h - 1)) * 254)];
    ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
    ctx.fillRect(0, y, colorbar.width, 1);
  }
  document.getElementById("scale-top").textContent = fmt(top);
  document.getElementById("scale-bottom").textContent = "0";
  document.getElementById("units").textContent = info.units;
}

function drawFrame(f) {
  const bytes = Uint8Array.from(atob(f.q), c => c.charCodeAt(0));
  const small = new ImageData(f.cols, f.rows);
  for (let i = 0; i < bytes.length; i++) {
    const c = LUT[bytes[i]];
    small.data[4 * i] = c[0]; small.data[4 * i + 1] = c[1]; small.data[4 * i + 2] = c[2]; small.data[4 * i + 3] = 255;
  }
  const scale = Math.max(1, Math.floor(440 / Math.max(f.rows, f.cols)));
  if (image.width !== f.cols * scale || image.height !== f.rows * scale) {
    image.width = f.cols * scale; image.height = f.rows * scale;
  }
  const off = document.createElement("canvas");
  off.width = f.cols; off.height = f.rows;
  off.getContext("2d").putImageData(small, 0, 0);
  const ctx = image.getContext("2d");
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(off, 0, 0, image.width, image.height);
  drawColorbar(f.top);
  document.getElementById("frame-index").textContent = `frame ${f.index}`;
  document.getElementById("peak").textContent = `peak ${fmt(f.peak)} ${info.units}`;
  framesDrawn++;
  body.dataset.framesDrawn = framesDrawn;
  body.dataset.image = `${f.rows}x${f.cols}`;
  image.dataset.rows = f.rows; image.dataset.cols = f.cols;
}

function newSession(s) {
  session = s; loads = []; stances = [];
}

function addLoads(points) {
  for (const [s, index, load] of points) {
    if (s !== session) newSession(s);
    loads.push([index, load]);
  }
  if (loads.length > TRACE_FRAMES) loads.splice(0, loads.length - TRACE_FRAMES);
  drawTrace();
}

function drawTrace() {
  const ctx = trace.getContext("2d"), w = trace.width, h = trace.height;
  ctx.clearRect(0, 0, w, h);
  if (loads.length < 2) return;
  const first = loads[0][0], last = loads[loads.length - 1][0];
  const span = Math.max(last - first, TRACE_FRAMES - 1);
  const x = i => (i - first) / span * (w - 50) + 45;
  const max = Math.max(...loads.map(p => p[1]), 1e-9);
  const y = v => h - 15 - v / max * (h - 25);
  ctx.fillStyle = "#ffcc8055";
  for (const st of stances) {
    const end = st.end === null ? last : st.end;
    if (end < first) continue;
    ctx.fillRect(x(Math.max(st.start, first)), 0, x(end) - x(Math.max(st.start, first)), h - 15);
  }
  ctx.strokeStyle = "#1565c0"; ctx.lineWidth = 1.5; ctx.beginPath();
  loads.forEach(([i, v], k) => k ? ctx.lineTo(x(i), y(v)) : ctx.moveTo(x(i), y(v)));
  ctx.stroke();
  ctx.fillStyle = "#444"; ctx.font = "11px sans-serif";
  ctx.fillText(fmt(max), 2, 12); ctx.fillText("0", 2, h - 15);
  ctx.fillText(`frame ${first}`, 45, h - 2); ctx.fillText(`${last}`, Math.min(x(last) - 10, w - 40), h - 2);
  ctx.fillText(`sum of sensels (${info.units})`, 60, 12);
}

function log(text, kind) {
  const li = document.createElement("li");
  li.textContent = text; li.className = kind;
  logList.prepend(li);
  while (logList.children.length > LOG_ENTRIES) logList.lastChild.remove();
}

function onLine(line) {
  const e = JSON.parse(line);
  switch (e.event) {
    case "touchdown":
      stances.push({ start: e.touchdown_frame, end: null, id: e.stance });
      log(`touchdown: stance ${e.stance} at frame ${e.touchdown_frame}`, "touchdown");
      break;
    case "liftoff": {
      const st = stances.find(s => s.id === e.stance);
      if (st) st.end = e.end_frame; else stances.push({ start: e.touchdown_frame, end: e.end_frame, id: e.stance });
      log(`liftoff: stance ${e.stance}, frames ${e.touchdown_frame}–${e.end_frame}`, "liftoff");
      break;
    }
    case "classification":
      showDecision(e);
      log(`${e.kind} decision: stance ${e.stance} is ${e.label}` +
          (e.unknown ? ` (nearest ${e.nearest}, confidence ${e.confidence.toFixed(2)}, novelty ${e.novelty.toFixed(2)})`
                     : ` (confidence ${e.confidence.toFixed(2)})`) +
          (e.decided_at ? `, at ${e.decided_at} (frame ${e.decided_at_frame}${e.cut ? ", cut" : ""})` : "") +
          (e.gait ? `, gait ${e.gait}` : ""), "classification");
      break;
    case "error":
      log(`error: ${e.message}`, "error");
      break;
    case "end":
      log(`end: ${e.frames} frames, ${e.stances} stances, ${e.decisions} decisions`, "end");
      break;
  }
  drawTrace();
}

function showDecision(e) {
  terrain.textContent = e.label;
  terrain.dataset.label = e.label;
  body.dataset.label = e.label;
  if (labels[labels.length - 1] !== e.label) labels.push(e.label);
  body.dataset.labels = labels.join(",");
  document.getElementById("confidence").textContent = e.confidence.toFixed(3);
  document.getElementById("confidence-bar").value = e.confidence;
  document.getElementById("gait").textContent = e.gait || "—";
  // A model that scores novelty: the score, its threshold, and for an unknown terrain the nearest class.
  const novelty = document.getElementById("novelty");
  novelty.hidden = e.novelty === undefined;
  terrain.dataset.unknown = e.unknown ? "true" : "false";
  if (e.novelty !== undefined) {
    document.getElementById("novelty-score").textContent = e.novelty.toFixed(2);
    document.getElementById("novelty-threshold").textContent = e.novelty_threshold.toFixed(2);
    document.getElementById("nearest").textContent = e.unknown ? `; nearest: ${e.nearest}` : "";
  }
  const post = document.getElementById("posteriors");
  post.replaceChildren(...Object.entries(e.posteriors || {}).map(([name, p]) => {
    const row = document.createElement("div"), label = document.createElement("span"), m = document.createElement("meter");
    label.textContent = name; m.min = 0; m.max = 1; m.value = p;
    row.append(label, m, document.createTextNode(p.toFixed(3)));
    return row;
  }));
}

// For a headless browser that dumps the page once the network is idle (the tests):
// `?frames=N` closes the event stream after N frames drawn, `&until=LABEL` only once LABEL is shown.
const params = new URLSearchParams(location.search);
const closeAfter = Number(params.get("frames")) || 0;
const closeUntil = params.get("until");
function maybeClose() {
  if (closeAfter > 0 && framesDrawn >= closeAfter && (!closeUntil || body.dataset.label === closeUntil)) {
    events.close();
    body.dataset.connected = "closed";
    document.getElementById("status").textContent = "closed";
  }
}

const events = new EventSource("/events");
events.addEventListener("hello", m => {
  info = JSON.parse(m.data);
  document.getElementById("source").textContent = `${info.source} · ${info.units}` +
    (info.classes.length ? ` · classes: ${info.classes.join(", ")}` : " · no model");
});
events.addEventListener("frame", m => { drawFrame(JSON.parse(m.data)); maybeClose(); });
events.addEventListener("loads", m => addLoads(JSON.parse(m.data)));
events.addEventListener("line", m => { onLine(m.data); maybeClose(); });
events.onopen = () => { body.dataset.connected = "true"; document.getElementById("status").textContent = "live"; };
events.onerror = () => { body.dataset.connected = "false"; document.getElementById("status").textContent = "disconnected (retrying)"; };
