"use strict";
// The live page: the scene once (/api/scene), then snapshots over /ws. Plain SVG in metres:
// x = east, y = -north (north up). No library, nothing fetched from elsewhere (tiles only
// from a template the user gave).
const NS = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const LABELS = { pause: "Pause", resume: "Resume", abort: "Abort (RTL)", land: "Land" };
const ZOOM_STEP = 1.5; // per button click; the wheel zooms by 1.2 a notch
// How far inside the map's border (px: left, top, right, bottom) an off-view marker stays:
// clear of the zoom buttons' column, the fence note and the scale bar.
const EDGE_PX = [64, 34, 14, 50];
let scene = null;
let socket = null;
let view = null; // [x, y, w, h] of the SVG viewBox
let home = null; // the view that fits the area and the fence
const tracks = new Map(); // vehicle -> [[north, east], ...], the newest scene.track_kept
let last = null; // the latest snapshot
let drawnMarks = -1; // detections + confirmations drawn
let selected = null; // the vehicle highlighted in the map and the table (a string) or null
let logShown = 0; // entries in the event log panel

function el(tag, attrs, parent) {
  const e = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
const color = (i) => `hsl(${(i * 137.5) % 360}, 70%, 40%)`;
const pt = (n, e) => `${e.toFixed(1)},${(-n).toFixed(1)}`;
const fmt = (v, d) => (v === null || v === undefined ? "-" : typeof v === "number" ? v.toFixed(d) : String(v));
const mapSize = () => [Math.max(1, $("map").clientWidth), Math.max(1, $("map").clientHeight)];
const metresPerPixel = () => { const [w, h] = mapSize(); return Math.max(view[2] / w, view[3] / h); };

// What the map shows: the viewBox, widened on one side to the map's shape (SVG's "meet").
function visible() {
  const [w, h] = mapSize();
  const px = metresPerPixel();
  const cx = view[0] + view[2] / 2, cy = view[1] + view[3] / 2;
  return [cx - (w * px) / 2, cy - (h * px) / 2, cx + (w * px) / 2, cy + (h * px) / 2];
}

function token() {
  const typed = $("token").value.trim();
  if (typed) return typed;
  const m = location.hash.match(/token=([^&]+)/);
  return m ? decodeURIComponent(m[1]) : "";
}

function niceStep(extent, parts) {
  const raw = extent / parts;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  return [1, 2, 5, 10].map((k) => k * p).find((s) => s >= raw);
}
const metres = (m) => (m >= 1000 ? `${+(m / 1000).toFixed(2)} km` : `${+m.toFixed(1)} m`);

function drawScene() {
  const { north, east } = scene.area;
  const pad = 0.05 * Math.max(north, east);
  let [n0, n1, e0, e1] = [0, north, 0, east];
  for (const [n, e] of scene.fence) { n0 = Math.min(n0, n); n1 = Math.max(n1, n); e0 = Math.min(e0, e); e1 = Math.max(e1, e); }
  home = [e0 - pad, -n1 - pad, e1 - e0 + 2 * pad, n1 - n0 + 2 * pad];
  view = [...home];
  el("rect", { x: 0, y: -north, width: east, height: north, fill: "rgba(80,140,80,0.08)", stroke: "#484",
    "stroke-width": 2, "vector-effect": "non-scaling-stroke", id: "search-area" }, $("area"));
  el("polygon", { points: scene.fence.map(([n, e]) => pt(n, e)).join(" "), fill: "none", stroke: "#c33",
    "stroke-dasharray": "8 5", "stroke-width": 2, "vector-effect": "non-scaling-stroke", id: "fence" }, $("area"));
  scene.targets.forEach((t, k) => {
    el("text", { x: t.east, y: -t.north, class: "target", "data-target": k, fill: t.false_target ? "#888" : "#c00",
      "text-anchor": "middle", "dominant-baseline": "central" }, $("targets")).textContent = "\u2715";
  });
  const ceiling = scene.ceiling === null ? "" : ` \u00b7 ceiling ${scene.ceiling.toFixed(0)} m above take-off`;
  $("map-info").textContent = `fence: dashed red${ceiling}`;
  applyView();
}

// The metric grid over what is visible, its labels along the top and left edges, inside.
function drawGrid() {
  const grid = $("grid");
  grid.replaceChildren();
  const [x0, y0, x1, y1] = visible();
  const px = metresPerPixel();
  const step = niceStep(Math.max(x1 - x0, y1 - y0), 8);
  for (let x = Math.ceil(x0 / step) * step; x <= x1; x += step) {
    el("line", { x1: x, x2: x, y1: y0, y2: y1, stroke: "#ccd", "vector-effect": "non-scaling-stroke" }, grid);
    el("text", { x: x + 3 * px, y: y0 + 3 * px, class: "gridlabel", fill: "#778", "font-size": 10 * px,
      "dominant-baseline": "hanging" }, grid).textContent = `${+x.toFixed(1)} E`;
  }
  for (let y = Math.ceil(y0 / step) * step; y <= y1; y += step) {
    el("line", { x1: x0, x2: x1, y1: y, y2: y, stroke: "#ccd", "vector-effect": "non-scaling-stroke" }, grid);
    el("text", { x: x0 + 3 * px, y: y - 3 * px, class: "gridlabel", fill: "#778", "font-size": 10 * px }, grid)
      .textContent = `${+(-y).toFixed(1)} N`;
  }
}

// A scale bar of a round length about a sixth of the map's width.
function drawScale() {
  const px = metresPerPixel();
  const length = niceStep(mapSize()[0] * px, 6);
  $("scale-bar").style.width = `${(length / px).toFixed(0)}px`;
  $("scale-text").textContent = metres(length);
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
  const [x0v, y0v, x1v, y1v] = visible();
  const [latN, lonW] = toLatLon(-y0v, x0v);
  const [latS, lonE] = toLatLon(-y1v, x1v);
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
  $("map").setAttribute("viewBox", view.map((v) => v.toFixed(2)).join(" "));
  if (scene.tiles) drawTiles();
  drawGrid();
  drawScale();
  const px = metresPerPixel();
  for (const t of document.querySelectorAll("#targets text")) t.setAttribute("font-size", 16 * px);
  if (last) drawMarks(last);
  for (const g of document.querySelectorAll("#vehicles g")) placeMarker(g);
}

// A marker's size in pixels whatever the zoom; its label on the side that keeps it inside the
// map; a vehicle outside the view drawn at the edge, towards where it is (class "offview").
function placeMarker(g) {
  const px = metresPerPixel();
  const [x0, y0, x1, y1] = visible();
  const [left, top, right, bottom] = EDGE_PX.map((p) => p * px);
  const x = Number(g.dataset.east), y = -Number(g.dataset.north);
  const cx = Math.min(Math.max(x, x0 + left), x1 - right);
  const cy = Math.min(Math.max(y, y0 + top), y1 - bottom);
  const off = cx !== x || cy !== y;
  const where = `translate(${cx.toFixed(1)},${cy.toFixed(1)})`;
  if (g.getAttribute("transform") !== where) g.setAttribute("transform", where);
  g.classList.toggle("offview", off);
  const big = g.dataset.vehicle === selected ? 1.5 : 1;
  g.querySelector("circle").setAttribute("r", (off ? 5 : 7) * big * px);
  const label = g.querySelector("text");
  label.setAttribute("font-size", 12 * px);
  const flip = cx + 60 * px > x1; // no room for the label on the right
  label.setAttribute("text-anchor", flip ? "end" : "start");
  label.setAttribute("dx", (flip ? -10 : 10) * big * px);
  label.setAttribute("dy", (cy - 12 * px < y0 ? 12 : cy + 12 * px > y1 ? -6 : 4) * px);
}

function vehicleMarker(v) {
  let g = document.querySelector(`#vehicles g[data-vehicle="${v.vehicle}"]`);
  if (!g) {
    g = el("g", { "data-vehicle": v.vehicle, class: "vehicle" }, $("vehicles"));
    el("circle", { cx: 0, cy: 0, fill: color(v.vehicle), stroke: "#fff", "stroke-width": 1.5, "vector-effect": "non-scaling-stroke" }, g);
    el("text", { x: 0, y: 0, fill: "#000" }, g).textContent = `uav${v.vehicle}`;
    g.addEventListener("click", (ev) => { ev.stopPropagation(); select(String(v.vehicle)); });
  }
  return g;
}

// In level 2 and above: the vehicle's detection and confirmation discs (first and last sensor).
function drawDiscs(s) {
  const layer = $("discs");
  layer.replaceChildren();
  if (scene.sensors.length < 2) return;
  const [detect, confirm] = [scene.sensors[0], scene.sensors[scene.sensors.length - 1]];
  for (const v of s.vehicles) {
    if (v.level === null || v.level < 1 || v.north === null || v.stale || v.end) continue;
    const at = { cx: v.east, cy: -v.north, "data-vehicle": v.vehicle, "vector-effect": "non-scaling-stroke" };
    el("circle", { ...at, r: detect.radius, class: "disc detection-disc", fill: "rgba(230,130,0,0.06)",
      stroke: "#e80", "stroke-dasharray": "6 4" }, layer);
    el("circle", { ...at, r: confirm.radius, class: "disc confirmation-disc", fill: "rgba(0,150,0,0.12)",
      stroke: "#090" }, layer);
  }
}

function update(s) {
  if (s.reset) { tracks.clear(); $("tracks").replaceChildren(); clearLog(); }
  last = s;
  $("clock").textContent = s.clock.toFixed(1);
  $("tnc").textContent = `${s.tnc} of ${scene.real_targets}`;
  for (const v of s.vehicles) {
    let track = tracks.get(v.vehicle) || [];
    track.push(...v.track);
    if (track.length > scene.track_kept) track = track.slice(track.length - scene.track_kept);
    tracks.set(v.vehicle, track);
    let line = document.querySelector(`#tracks polyline[data-vehicle="${v.vehicle}"]`);
    if (!line) line = el("polyline", { "data-vehicle": v.vehicle, fill: "none", stroke: color(v.vehicle),
      "stroke-width": 1.5, "vector-effect": "non-scaling-stroke", opacity: 0.7 }, $("tracks"));
    if (v.track.length || s.reset) line.setAttribute("points", track.map(([n, e]) => pt(n, e)).join(" "));
    if (v.north === null || v.east === null) continue;
    const g = vehicleMarker(v);
    g.dataset.north = v.north;
    g.dataset.east = v.east;
    placeMarker(g);
    g.classList.toggle("stale", v.stale);
    g.querySelector("circle").setAttribute("fill", v.stale ? "#999" : color(v.vehicle));
  }
  drawDiscs(s);
  const marks = s.detections.length + s.confirmations.length;
  if (marks !== drawnMarks || s.reset) drawMarks(s);
  drawTable(s);
  drawCommands(s.commands);
  addLog(s.log);
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
    b.addEventListener("click", (ev) => { ev.stopPropagation(); ask(vehicle, c); });
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
      row.addEventListener("click", () => select(String(v.vehicle)));
      const rows = [...body.children];
      body.insertBefore(row, rows.find((r) => Number(r.dataset.vehicle) > v.vehicle) || null);
      const option = document.createElement("option");
      option.value = v.vehicle;
      option.textContent = `uav${v.vehicle}`;
      $("log-filter").appendChild(option);
    }
    const level = v.level === null ? "-" : String(v.level + 1);
    const armed = v.armed === null ? "-" : v.armed ? "yes" : "no";
    const phase = v.end ? `${v.phase} (${v.end})` : v.phase;
    const cells = [`uav${v.vehicle}`, v.mode, armed, phase, level, fmt(v.ci, 3), v.found,
      fmt(v.alt, 1), fmt(v.battery, 0), scene.replay ? "-" : fmt(v.age, 1)];
    cells.forEach((text, k) => { row.children[k].textContent = text === null ? "-" : text; });
    row.children[3].title = phase || "";
    const over = scene.ceiling !== null && v.alt !== null && v.alt > scene.ceiling;
    row.children[7].classList.toggle("over", over);
    row.children[7].title = over ? `above the ceiling, ${scene.ceiling} m` : "";
    row.children[0].style.color = color(v.vehicle);
    row.classList.toggle("stale", v.stale);
    row.classList.toggle("selected", String(v.vehicle) === selected);
    commandButtons(row.lastChild, String(v.vehicle));
  }
}

// One vehicle picked (a marker or a row clicked): larger on the map, its track bold, its row
// marked; the same click again unpicks it.
function select(vehicle) {
  selected = selected === vehicle ? null : vehicle;
  for (const g of document.querySelectorAll("#vehicles g")) {
    g.classList.toggle("selected", g.dataset.vehicle === selected);
    placeMarker(g);
  }
  for (const line of document.querySelectorAll("#tracks polyline")) {
    line.setAttribute("stroke-width", line.dataset.vehicle === selected ? 3.5 : 1.5);
    line.setAttribute("opacity", selected === null || line.dataset.vehicle === selected ? 0.8 : 0.35);
  }
  for (const row of document.querySelectorAll("#team tbody tr")) row.classList.toggle("selected", row.dataset.vehicle === selected);
  $("centre").disabled = selected === null;
}

function drawCommands(list) {
  const ul = $("commands");
  ul.replaceChildren();
  if (!list.length) {
    const li = document.createElement("li");
    li.className = "none";
    li.textContent = scene.replay ? "(a replay sends no commands)" : "none sent from this page yet";
    ul.appendChild(li);
  }
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

// The event log: newest on top, each line once; the filter shows one vehicle's (and the lines
// for every vehicle, such as a command to all).
function clearLog() { $("log").replaceChildren(); logShown = 0; }

function logVisible(li) {
  const want = $("log-filter").value;
  return want === "" || li.dataset.vehicle === want || li.dataset.vehicle === "all";
}

function addLog(entries) {
  const list = $("log");
  for (const e of entries) {
    const li = document.createElement("li");
    li.className = `log-${e.severity}`;
    li.dataset.kind = e.kind;
    li.dataset.vehicle = e.vehicle === null ? "all" : String(e.vehicle);
    const when = document.createElement("span");
    when.className = "t";
    when.textContent = e.t === null ? "" : `t=${e.t.toFixed(1)}`;
    const who = document.createElement("b");
    who.textContent = e.vehicle === null ? "all" : `uav${e.vehicle}`;
    if (e.vehicle !== null) who.style.color = color(e.vehicle);
    li.append(when, " ", who, ` ${e.text}`);
    li.hidden = !logVisible(li);
    list.prepend(li);
    logShown += 1;
  }
  while (list.childElementCount > scene.log_kept) list.lastChild.remove();
  $("log-count").textContent = `${logShown} event${logShown === 1 ? "" : "s"}`;
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

// Zoom by k (> 1: out) about the map's pixel (fx, fy) as fractions of its size.
function zoom(k, fx = 0.5, fy = 0.5) {
  const [x, y, w, h] = view;
  view = [x + fx * w * (1 - k), y + fy * h * (1 - k), w * k, h * k];
  applyView();
}

function centreOn(vehicle) {
  const g = document.querySelector(`#vehicles g[data-vehicle="${vehicle}"]`);
  if (!g) return;
  view = [Number(g.dataset.east) - view[2] / 2, -Number(g.dataset.north) - view[3] / 2, view[2], view[3]];
  applyView();
}

function setupPanZoom() {
  const svg = $("map");
  svg.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    const r = svg.getBoundingClientRect();
    // the pixel's fraction of the viewBox, which "meet" centres in the map
    const px = metresPerPixel();
    const [x0, y0] = visible();
    const fx = (x0 + (ev.clientX - r.left) * px - view[0]) / view[2];
    const fy = (y0 + (ev.clientY - r.top) * px - view[1]) / view[3];
    zoom(ev.deltaY > 0 ? 1.2 : 1 / 1.2, fx, fy);
  }, { passive: false });
  let drag = null;
  svg.addEventListener("mousedown", (ev) => { drag = [ev.clientX, ev.clientY, view[0], view[1]]; svg.classList.add("dragging"); });
  window.addEventListener("mouseup", () => { drag = null; svg.classList.remove("dragging"); });
  window.addEventListener("mousemove", (ev) => {
    if (!drag) return;
    const px = metresPerPixel();
    view = [drag[2] - (ev.clientX - drag[0]) * px, drag[3] - (ev.clientY - drag[1]) * px, view[2], view[3]];
    applyView();
  });
  $("zoom-in").addEventListener("click", () => zoom(1 / ZOOM_STEP));
  $("zoom-out").addEventListener("click", () => zoom(ZOOM_STEP));
  $("fit").addEventListener("click", () => { view = [...home]; applyView(); });
  $("centre").addEventListener("click", () => { if (selected !== null) centreOn(selected); });
  window.addEventListener("keydown", (ev) => {
    if (ev.target instanceof HTMLInputElement || ev.target instanceof HTMLSelectElement) return;
    if (ev.key === "+" || ev.key === "=") zoom(1 / ZOOM_STEP);
    else if (ev.key === "-") zoom(ZOOM_STEP);
    else if (ev.key === "0") { view = [...home]; applyView(); }
  });
}

async function start() {
  scene = await (await fetch("/api/scene")).json();
  $("title").textContent = `MDM team: ${scene.profile} (${scene.vehicles} vehicles)`;
  $("broker").textContent = scene.broker ? `MQTT ${scene.broker}` : "";
  $("token-box").hidden = !scene.token_required || /token=/.test(location.hash);
  if (scene.read_only) document.body.classList.add("read-only");
  else commandButtons(document.querySelector("#row-all td.cmd"), "all");
  $("log-filter").addEventListener("change", () => { for (const li of $("log").children) li.hidden = !logVisible(li); });
  drawScene();
  setupPanZoom();
  window.addEventListener("resize", applyView);
  if (scene.replay) setupReplay();
  drawCommands([]);
  connect();
}
start();
