"use strict";
// The live page: the scene once (/api/scene), then snapshots over /ws. Plain SVG in metres:
// x = east, y = -north (north up). No library, nothing fetched from elsewhere.
const NS = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const LABELS = { pause: "Pause", resume: "Resume", abort: "Abort (RTL)", land: "Land" };
let scene = null;
let socket = null;
let view = null; // [x, y, w, h] of the SVG viewBox
const tracks = new Map(); // vehicle -> [[north, east], ...]
let last = null; // the latest snapshot
let drawnMarks = -1; // detections + confirmations drawn

function el(tag, attrs, parent) {
  const e = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
const color = (i) => `hsl(${(i * 137.5) % 360}, 70%, 40%)`;
const pt = (n, e) => `${e.toFixed(1)},${(-n).toFixed(1)}`;
const fmt = (v, d) => (v === null || v === undefined ? "-" : typeof v === "number" ? v.toFixed(d) : String(v));
const metresPerPixel = () => Math.max(view[2] / Math.max(1, $("map").clientWidth), view[3] / Math.max(1, $("map").clientHeight));

function token() {
  const typed = $("token").value.trim();
  if (typed) return typed;
  const m = location.hash.match(/token=([^&]+)/);
  return m ? decodeURIComponent(m[1]) : "";
}

function niceStep(extent) {
  const raw = extent / 8;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  return [1, 2, 5, 10].map((k) => k * p).find((s) => s >= raw);
}

function drawScene() {
  const { north, east } = scene.area;
  const pad = 0.05 * Math.max(north, east);
  let [n0, n1, e0, e1] = [0, north, 0, east];
  for (const [n, e] of scene.fence) { n0 = Math.min(n0, n); n1 = Math.max(n1, n); e0 = Math.min(e0, e); e1 = Math.max(e1, e); }
  view = [e0 - pad, -n1 - pad, e1 - e0 + 2 * pad, n1 - n0 + 2 * pad];
  const grid = $("grid");
  const step = niceStep(Math.max(north, east));
  for (let x = Math.floor(e0 / step) * step; x <= e1; x += step) {
    el("line", { x1: x, x2: x, y1: -n1, y2: -n0, stroke: "#ccd", "vector-effect": "non-scaling-stroke" }, grid);
    // below the southern edge, apart from the north labels that stand above their lines
    el("text", { x: x, y: -n0, class: "gridlabel", fill: "#889", "dominant-baseline": "hanging" }, grid).textContent = `${x} E`;
  }
  for (let y = Math.floor(n0 / step) * step; y <= n1; y += step) {
    el("line", { x1: e0, x2: e1, y1: -y, y2: -y, stroke: "#ccd", "vector-effect": "non-scaling-stroke" }, grid);
    el("text", { x: e0, y: -y, class: "gridlabel", fill: "#889" }, grid).textContent = `${y} N`;
  }
  el("rect", { x: 0, y: -north, width: east, height: north, fill: "rgba(80,140,80,0.08)", stroke: "#484",
    "stroke-width": 2, "vector-effect": "non-scaling-stroke", id: "search-area" }, $("area"));
  el("polygon", { points: scene.fence.map(([n, e]) => pt(n, e)).join(" "), fill: "none", stroke: "#c33",
    "stroke-dasharray": "8 5", "stroke-width": 2, "vector-effect": "non-scaling-stroke", id: "fence" }, $("area"));
  scene.targets.forEach((t, k) => {
    el("text", { x: t.east, y: -t.north, class: "target", "data-target": k, fill: t.false_target ? "#888" : "#c00",
      "text-anchor": "middle", "dominant-baseline": "central" }, $("targets")).textContent = "\u2715";
  });
  applyView();
}

// Optional map tiles (--web-tiles): Web Mercator tiles placed in the local metric frame by an
// equirectangular approximation around the origin (good to a few metres over tens of km).
const R = 6378137;
const toLatLon = (n, e) => [scene.origin.lat + (n / R) * 180 / Math.PI,
  scene.origin.lon + (e / (R * Math.cos(scene.origin.lat * Math.PI / 180))) * 180 / Math.PI];
const toLocal = (lat, lon) => [(lat - scene.origin.lat) * Math.PI / 180 * R,
  (lon - scene.origin.lon) * Math.PI / 180 * R * Math.cos(scene.origin.lat * Math.PI / 180)];
const tileLon = (x, z) => x / 2 ** z * 360 - 180;
const tileLat = (y, z) => Math.atan(Math.sinh(Math.PI * (1 - 2 * y / 2 ** z))) * 180 / Math.PI;

function drawTiles() {
  const layer = $("tiles");
  layer.replaceChildren();
  const lat0 = scene.origin.lat * Math.PI / 180;
  const z = Math.max(0, Math.min(19, Math.round(Math.log2(156543.03 * Math.cos(lat0) / metresPerPixel()))));
  const [x, y, w, h] = view;
  const [latN, lonW] = toLatLon(-y, x);
  const [latS, lonE] = toLatLon(-(y + h), x + w);
  const tx = (lon) => Math.floor((lon + 180) / 360 * 2 ** z);
  const ty = (lat) => Math.floor((1 - Math.log(Math.tan(lat * Math.PI / 180) + 1 / Math.cos(lat * Math.PI / 180)) / Math.PI) / 2 * 2 ** z);
  const [x0, x1, y0, y1] = [tx(lonW), tx(lonE), ty(latN), ty(latS)];
  if ((x1 - x0 + 1) * (y1 - y0 + 1) > 100) return; // zoomed far out: no tiles
  for (let i = x0; i <= x1; i++) {
    for (let j = y0; j <= y1; j++) {
      const [n0, e0] = toLocal(tileLat(j, z), tileLon(i, z));
      const [n1, e1] = toLocal(tileLat(j + 1, z), tileLon(i + 1, z));
      const href = scene.tiles.replace("{z}", z).replace("{x}", i).replace("{y}", j);
      el("image", { href, x: e0, y: -n0, width: e1 - e0, height: n0 - n1, preserveAspectRatio: "none",
        class: "tile" }, layer);
    }
  }
}

function applyView() {
  $("map").setAttribute("viewBox", view.join(" "));
  if (scene.tiles) drawTiles();
  const px = metresPerPixel();
  for (const t of document.querySelectorAll("#grid text")) t.setAttribute("font-size", 10 * px);
  for (const t of document.querySelectorAll("#targets text")) t.setAttribute("font-size", 16 * px);
  if (last) drawMarks(last);
  for (const g of document.querySelectorAll("#vehicles g")) sizeMarker(g);
}

function sizeMarker(g) {
  const px = metresPerPixel();
  g.querySelector("circle").setAttribute("r", 7 * px);
  const label = g.querySelector("text");
  label.setAttribute("font-size", 12 * px);
  label.setAttribute("dx", 9 * px);
}

function vehicleMarker(v) {
  let g = document.querySelector(`#vehicles g[data-vehicle="${v.vehicle}"]`);
  if (!g) {
    g = el("g", { "data-vehicle": v.vehicle, class: "vehicle" }, $("vehicles"));
    el("circle", { cx: 0, cy: 0, fill: color(v.vehicle), stroke: "#fff", "stroke-width": 1.5, "vector-effect": "non-scaling-stroke" }, g);
    el("text", { x: 0, y: 0, fill: "#000" }, g).textContent = `uav${v.vehicle}`;
    sizeMarker(g);
  }
  return g;
}

function update(s) {
  if (s.reset) { tracks.clear(); $("tracks").replaceChildren(); }
  last = s;
  $("clock").textContent = s.clock.toFixed(1);
  $("tnc").textContent = `${s.tnc} of ${scene.real_targets}`;
  for (const v of s.vehicles) {
    const track = tracks.get(v.vehicle) || [];
    track.length = v.track_from;
    track.push(...v.track);
    tracks.set(v.vehicle, track);
    let line = document.querySelector(`#tracks polyline[data-vehicle="${v.vehicle}"]`);
    if (!line) line = el("polyline", { "data-vehicle": v.vehicle, fill: "none", stroke: color(v.vehicle),
      "stroke-width": 1.5, "vector-effect": "non-scaling-stroke", opacity: 0.7 }, $("tracks"));
    if (v.track.length || s.reset) line.setAttribute("points", track.map(([n, e]) => pt(n, e)).join(" "));
    if (v.north === null || v.east === null) continue;
    const g = vehicleMarker(v);
    const where = `translate(${pt(v.north, v.east)})`;
    if (g.getAttribute("transform") !== where) g.setAttribute("transform", where);
    g.dataset.north = v.north;
    g.dataset.east = v.east;
    g.classList.toggle("stale", v.stale);
    g.querySelector("circle").setAttribute("fill", v.stale ? "#999" : color(v.vehicle));
  }
  const marks = s.detections.length + s.confirmations.length;
  if (marks !== drawnMarks || s.reset) drawMarks(s);
  drawTable(s);
  drawCommands(s.commands);
}

function drawMarks(s) {
  drawnMarks = s.detections.length + s.confirmations.length;
  const px = metresPerPixel();
  const marks = $("marks");
  marks.replaceChildren();
  const put = (m, cls, glyph, fill) => {
    const t = el("text", { x: m.east, y: -m.north, class: cls, "data-vehicle": m.vehicle, fill: fill,
      "font-size": 16 * px, "text-anchor": "middle", "dominant-baseline": "central" }, marks);
    t.textContent = glyph;
    el("title", {}, t).textContent = `uav${m.vehicle} ${cls} t=${m.t.toFixed(1)} s level ${m.level + 1}`;
  };
  s.detections.forEach((m) => put(m, "detection", "\u25B2", "#e80"));
  s.confirmations.forEach((m) => put(m, "confirmation", "\u2605", "#090"));
}

function commandButtons(cell, vehicle) {
  if (cell.childElementCount || scene.read_only) return;
  for (const c of scene.commands) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = c;
    b.dataset.command = c;
    b.dataset.vehicle = vehicle;
    b.addEventListener("click", () => ask(vehicle, c));
    cell.appendChild(b);
  }
}

function drawTable(s) {
  const body = document.querySelector("#team tbody");
  for (const v of s.vehicles) {
    let row = body.querySelector(`tr[data-vehicle="${v.vehicle}"]`);
    if (!row) {
      row = document.createElement("tr");
      row.dataset.vehicle = v.vehicle;
      for (let k = 0; k < 11; k++) row.appendChild(document.createElement("td"));
      row.lastChild.className = "cmd";
      const rows = [...body.children];
      body.insertBefore(row, rows.find((r) => Number(r.dataset.vehicle) > v.vehicle) || null);
    }
    const level = v.level === null ? "-" : String(v.level + 1);
    const armed = v.armed === null ? "-" : v.armed ? "yes" : "no";
    const phase = v.end ? `${v.phase} (${v.end})` : v.phase;
    const cells = [`uav${v.vehicle}`, v.mode, armed, phase, level, fmt(v.ci, 3), v.found,
      fmt(v.alt, 1), fmt(v.battery, 0), scene.replay ? "-" : fmt(v.age, 1)];
    cells.forEach((text, k) => { row.children[k].textContent = text === null ? "-" : text; });
    row.children[3].title = phase || "";
    row.children[0].style.color = color(v.vehicle);
    row.classList.toggle("stale", v.stale);
    commandButtons(row.lastChild, String(v.vehicle));
  }
}

function drawCommands(list) {
  const ul = $("commands");
  ul.replaceChildren();
  for (const c of list) {
    const li = document.createElement("li");
    li.dataset.id = c.id;
    const answers = Object.entries(c.answers).map(([v, a]) => {
      const span = document.createElement("span");
      span.className = a.startsWith("refused") ? "refused" : "accepted";
      span.textContent = ` uav${v}: ${a};`;
      return span;
    });
    li.append(`${c.command} -> ${c.target}: `, ...(c.error ? [c.error] : answers.length ? answers : ["sent, no answer yet"]));
    ul.appendChild(li);
  }
}

function ask(vehicle, command) {
  const who = vehicle === "all" ? "EVERY vehicle" : `uav${vehicle}`;
  $("confirm-text").textContent = `${LABELS[command]}: ${who}?`;
  $("confirm").hidden = false;
  $("confirm-yes").onclick = () => { $("confirm").hidden = true; send(vehicle, command); };
  $("confirm-no").onclick = () => { $("confirm").hidden = true; };
}

async function send(vehicle, command) {
  const headers = { "Content-Type": "application/json" };
  if (token()) headers.Authorization = `Bearer ${token()}`;
  const body = JSON.stringify({ vehicle: vehicle === "all" ? "all" : Number(vehicle), command });
  try {
    const r = await fetch("/api/command", { method: "POST", headers, body });
    const answer = await r.json();
    $("message").textContent = r.ok ? "" : `refused (${r.status}): ${answer.error}`;
    $("message").dataset.status = r.status;
  } catch (err) {
    $("message").textContent = `not sent: ${err}`;
  }
}

function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  socket = new WebSocket(`${proto}//${location.host}/ws`);
  socket.onopen = () => {
    $("link").textContent = scene.replay ? "replay" : "live"; $("link").className = "good";
    if (scene.replay) seek(Number($("slider").value));
  };
  socket.onclose = () => { $("link").textContent = "disconnected: retrying"; $("link").className = "bad"; setTimeout(connect, 1000); };
  socket.onmessage = (m) => {
    const s = JSON.parse(m.data);
    if (s.type === "error") { $("message").textContent = s.error; return; }
    if (s.type === "snapshot") {
      update(s);
      if (!scene.replay) socket.send("ack"); // drawn: the server may send the next
    }
    if (s.at !== undefined) $("at").textContent = s.at.toFixed(0);
  };
}

function seek(t) { if (socket && socket.readyState === 1) socket.send(JSON.stringify({ seek: t })); }

function setupReplay() {
  $("replay").hidden = false;
  $("link").textContent = "replay";
  const slider = $("slider");
  slider.max = Math.ceil(scene.replay.end);
  $("end").textContent = slider.max;
  slider.addEventListener("input", () => seek(Number(slider.value)));
  let timer = null;
  $("play").addEventListener("click", () => {
    if (timer) { clearInterval(timer); timer = null; $("play").textContent = "play"; return; }
    $("play").textContent = "pause";
    timer = setInterval(() => {
      const next = Math.min(Number(slider.max), Number(slider.value) + 0.2 * Number($("speed").value));
      slider.value = next;
      seek(next);
      if (next >= Number(slider.max)) { clearInterval(timer); timer = null; $("play").textContent = "play"; }
    }, 200);
  });
}

function setupPanZoom() {
  const svg = $("map");
  svg.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    const k = ev.deltaY > 0 ? 1.2 : 1 / 1.2;
    const r = svg.getBoundingClientRect();
    const fx = (ev.clientX - r.left) / r.width, fy = (ev.clientY - r.top) / r.height;
    const [x, y, w, h] = view;
    view = [x + fx * w * (1 - k), y + fy * h * (1 - k), w * k, h * k];
    applyView();
  }, { passive: false });
  let drag = null;
  svg.addEventListener("mousedown", (ev) => { drag = [ev.clientX, ev.clientY, view[0], view[1]]; });
  window.addEventListener("mouseup", () => { drag = null; });
  window.addEventListener("mousemove", (ev) => {
    if (!drag) return;
    const px = metresPerPixel();
    view = [drag[2] - (ev.clientX - drag[0]) * px, drag[3] - (ev.clientY - drag[1]) * px, view[2], view[3]];
    applyView();
  });
}

async function start() {
  scene = await (await fetch("/api/scene")).json();
  $("title").textContent = `MDM team: ${scene.profile} (${scene.vehicles} vehicles)`;
  $("token-box").hidden = !scene.token_required || /token=/.test(location.hash);
  if (scene.read_only) document.body.classList.add("read-only");
  else commandButtons(document.querySelector("#row-all td.cmd"), "all");
  drawScene();
  setupPanZoom();
  window.addEventListener("resize", applyView);
  if (scene.replay) setupReplay();
  connect();
}
start();
