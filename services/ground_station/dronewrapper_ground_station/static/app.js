// The ground station page: telemetry and video over WebSockets, commands over HTTP.
"use strict";

const $ = (id) => document.getElementById(id);
const TELEOP_HZ = 20, OBJECT_HZ = 10, TRAIL = 900;

const station = {
  token: "", role: "observer", limits: null, ns: null, camera: "frontal",
  tele: null, drone: null, offset: 0, trails: {}, goal: null,
  teleopActive: false, objectActive: false, frameAges: [], frames: 0,
};
window.station = station; // read by the tests and the benchmark

// ---- the token (kept for this tab only, removed from the address bar)
(function takeToken() {
  const url = new URL(location.href);
  const t = url.searchParams.get("token");
  if (t) { sessionStorage.setItem("station-token", t); url.searchParams.delete("token"); history.replaceState(null, "", url); }
  station.token = sessionStorage.getItem("station-token") || "";
})();

function wsUrl(path) {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  return `${proto}//${location.host}${path}${station.token ? "?token=" + encodeURIComponent(station.token) : ""}`;
}

function logLine(text, cls = "station", time = new Date().toTimeString().slice(0, 8)) {  // HH:MM:SS, as the autopilot's lines
  const li = document.createElement("li");
  li.className = cls; li.textContent = `${time}  ${text}`;
  const log = $("log"); log.prepend(li);
  while (log.children.length > 200) log.lastChild.remove();
}

// ---- commands (HTTP): refusals are shown with the autopilot's reason
async function command(name, body = {}) {
  if (!station.ns) return;
  const el = $("result"); el.className = "result"; el.textContent = `${name}…`; $("busy").textContent = name;
  try {
    const r = await fetch(`/api/drones/${encodeURIComponent(station.ns)}/${name}`, {
      method: "POST", headers: { "Content-Type": "application/json", "X-Station-Token": station.token },
      body: JSON.stringify(body),
    });
    const reply = await r.json();
    if (reply.ok) { el.className = "result ok"; el.textContent = `${name}: done`; logLine(`${station.ns}: ${name} done`); }
    else { el.className = "result bad"; el.textContent = reply.error; logLine(`${station.ns}: ${reply.error}`, "error"); }
  } catch (err) {
    el.className = "result bad"; el.textContent = `${name}: ${err}`;
  } finally { $("busy").textContent = ""; }
}

// ---- every drone at once: land all (each drone's outcome in the log)
async function landAll() {
  const el = $("result"); el.className = "result"; el.textContent = "landing all…";
  try {
    const r = await fetch("/api/fleet/land", {
      method: "POST", headers: { "Content-Type": "application/json", "X-Station-Token": station.token },
    });
    const reply = await r.json();
    for (const [ns, what] of Object.entries(reply.drones || {})) logLine(`${ns}: ${what}`, what === "landed" ? "station" : "error");
    el.className = reply.ok ? "result ok" : "result bad";
    el.textContent = reply.ok ? "all landed" : (reply.error || "some did not land: see the log");
  } catch (err) { el.className = "result bad"; el.textContent = `land all: ${err}`; }
}

// ---- the simulator's world: which scenario runs; load another or reset it
async function refreshWorld() {
  const r = await fetch("/api/world");
  const sel = $("scenario-select");
  const world = r.ok ? await r.json() : { simulator: false };
  if (!world.simulator) { $("world-state").textContent = "no simulator"; sel.hidden = true; return null; }
  sel.hidden = false;
  const rebuilt = sel.dataset.sig !== world.available.join();
  if (rebuilt) {
    sel.replaceChildren(...world.available.map((n) => { const o = document.createElement("option"); o.value = o.textContent = n; return o; }));
    sel.dataset.sig = world.available.join();
  }
  // show the running scenario when it changes, never undo an operator's pick on each poll
  if (rebuilt || sel.dataset.running !== world.scenario) {
    sel.value = world.scenario;
    sel.dataset.running = world.scenario;
  }
  $("world-state").textContent = `running ${world.scenario} (${world.objects.length} objects)`;
  return world;
}
async function loadWorld(scenario) {
  const el = $("result");
  const r = await fetch("/api/world", {
    method: "POST", headers: { "Content-Type": "application/json", "X-Station-Token": station.token },
    body: JSON.stringify({ scenario }),
  });
  const reply = await r.json();
  if (reply.ok) { el.className = "result ok"; el.textContent = `world: ${reply.scenario} loaded`; logLine(`world: ${reply.scenario} loaded`); }
  else { el.className = "result bad"; el.textContent = reply.error; logLine(`world: ${reply.error}`, "error"); }
  await refreshWorld();
}

// ---- telemetry socket (also carries teleop)
let teleSocket = null;
function connectTelemetry() {
  const ws = new WebSocket(wsUrl("/ws/telemetry"));
  ws.binaryType = "arraybuffer";
  ws.onopen = () => { $("link").textContent = "connected"; $("link").className = "badge ok"; };
  ws.onclose = () => {
    $("link").textContent = "disconnected"; $("link").className = "badge bad"; teleSocket = null;
    setTimeout(connectTelemetry, 1000);
  };
  ws.onmessage = (ev) => {
    const msg = JSON.parse(typeof ev.data === "string" ? ev.data : new TextDecoder().decode(ev.data));
    if (msg.type === "error") { logLine(msg.error, "error"); return; }
    if (msg.type === "telemetry") onTelemetry(msg);
  };
  teleSocket = ws;
}
function send(msg) { if (teleSocket && teleSocket.readyState === WebSocket.OPEN) teleSocket.send(JSON.stringify(msg)); }

const seenLog = new Set();
function onTelemetry(msg) {
  station.tele = msg; station.offset = msg.t - Date.now() / 1000;
  if (msg.role !== station.role) setRole(msg.role);
  renderLink(msg.router);
  renderDrones(msg.fleet, msg.router);
  if (!station.ns && msg.fleet.length) selectDrone(msg.fleet[0].ns);
  station.drone = msg.drones[station.ns] || null;
  const now = Date.now() / 1000;
  for (const [ns, d] of Object.entries(msg.drones)) {
    if (!d.pose) continue;
    const trail = (station.trails[ns] ||= []);
    const last = trail[trail.length - 1];
    if (!last || Math.hypot(d.pose.x - last[0], d.pose.y - last[1]) > 0.05) trail.push([d.pose.x, d.pose.y]);
    if (trail.length > TRAIL) trail.shift();
  }
  const d = station.drone;
  if (d) {
    for (const e of d.log) {
      const key = `${e.stamp}|${e.text}`;
      if (!seenLog.has(key)) { seenLog.add(key); logLine(`${station.ns}: ${e.text}`, e.severity, e.time); }
    }
    plots.alt.push(0, now, d.pose && d.pose.z); plots.alt.push(1, now, d.ground_truth && d.ground_truth.z);
    const c = d.controller && !d.controller.stale ? d.controller : null;
    plots.err.push(0, now, c && c.error_x); plots.err.push(1, now, c && c.error_z / 100); plots.err.push(2, now, c && c.error_yaw / 100);
    const cmd = d.command && d.command.what === "velocity" ? d.command : null;
    plots.cmd.push(0, now, c ? c.cmd_vx : cmd ? cmd.vx : 0);
    plots.cmd.push(1, now, c ? c.cmd_vz : cmd ? cmd.vz : 0);
    plots.cmd.push(2, now, c ? c.cmd_yaw_rate : cmd ? cmd.yaw_rate : 0);
    plots.cmd.push(3, now, d.velocity_body && d.velocity_body.vx);
  }
  renderTelemetry(d);
  renderRefusals(d);
  renderObjects(msg.objects);
}

// ---- what the bridge refused of this station's commands (beside the buttons, and logged)
const seenRefusals = new Set();
function renderRefusals(d) {
  const list = $("refusals"), refusals = (d && d.refusals) || [];
  list.replaceChildren(...refusals.slice().reverse().map((r) => {
    const li = document.createElement("li"); li.textContent = `${r.time}  ${r.text}`; return li;
  }));
  for (const r of refusals) {
    const key = `${r.stamp}|${r.text}`;
    if (!seenRefusals.has(key)) { seenRefusals.add(key); logLine(`${station.ns}: ${r.text}`, "error", r.time); }
  }
}

function setRole(role) {
  station.role = role;
  $("role").textContent = role; $("role").className = `badge ${role === "operator" ? "ok" : ""}`;
  $("readonly").hidden = role === "operator";
  for (const el of document.querySelectorAll(".cmd, #mode-select, #takeoff-height, #object-select, #scenario-select")) el.disabled = role !== "operator";
  for (const s of sticks) s.enabled = role === "operator";
}

function renderLink(router) {  // the page's socket is open: is the station's router linked?
  const linked = !router || router.linked;
  $("link").textContent = linked ? "connected" : "router unreachable";
  $("link").className = `badge ${linked ? "ok" : "bad"}`;
  $("link").title = router ? `station's router: ${router.endpoint}` : "";
}

function renderDrones(fleet, router) {
  const nav = $("drones");
  const unreachable = router && !router.linked;
  const sig = JSON.stringify(fleet.map((d) => [d.ns, d.health])) + station.ns + unreachable;
  if (nav.dataset.sig === sig) return;
  nav.dataset.sig = sig; nav.textContent = "";
  for (const d of fleet) {
    const b = document.createElement("button");
    b.id = `drone-${d.ns}`; b.title = `${d.health}: ${d.services.join(", ")}`;
    b.className = d.ns === station.ns ? "selected" : "";
    const dot = document.createElement("span"); dot.className = `dot ${d.health}`;
    b.append(dot, document.createTextNode(d.ns));
    b.onclick = () => selectDrone(d.ns);
    nav.append(b);
  }
  if (unreachable) nav.textContent = `router ${router.endpoint} unreachable: no drone can be seen`;
  else if (!fleet.length) nav.textContent = "no drone online";
}

function selectDrone(ns) {
  if (ns === station.ns) return;
  if (station.teleopActive) stopTeleop();
  station.ns = ns; station.goal = null;
  for (const p of Object.values(plots)) p.clear();
  $("drones").dataset.sig = "";
  connectVideo();
}

const fmt = (v, n = 2) => (typeof v === "number" && Number.isFinite(v) ? v.toFixed(n) : "–");
const deg = (r) => fmt((r * 180) / Math.PI, 1) + "°";
function renderTelemetry(d) {
  const rows = [];
  const row = (label, sec, text, alert = false) =>
    rows.push([label, text, sec ? sec.age : null, !sec || sec.stale, alert]);
  if (d) {
    const s = d.state, p = d.pose, v = d.velocity, b = d.battery, g = d.gps, c = d.controller;
    row("link", s, s ? (s.connected ? `connected (${s.autopilot})` : "no autopilot") : "no bridge", s && !s.connected);
    row("mode", s, s ? s.mode : "–");
    row("armed", s, s ? (s.armed ? "ARMED" : "disarmed") : "–", s && s.armed);
    row("landed", d.landed, d.landed ? d.landed.landed_state.replace("_", " ") : "–");
    row("battery", b, b ? `${fmt(b.percentage * 100, 0)} %  ${fmt(b.voltage, 1)} V` : "–", b && b.percentage < 0.2);
    row("position", p, p ? `x ${fmt(p.x)}  y ${fmt(p.y)}  z ${fmt(p.z)} m` : "–");
    row("altitude", p, p ? `${fmt(p.z)} m` : "–");
    row("velocity", v, v ? `${fmt(v.vx)}  ${fmt(v.vy)}  ${fmt(v.vz)} m/s` : "–");
    row("attitude", p, p ? `roll ${deg(p.roll)}  pitch ${deg(p.pitch)}  yaw ${deg(p.yaw)}` : "–");
    if (g) row("GPS", g, `${fmt(g.latitude, 6)}, ${fmt(g.longitude, 6)}  ${fmt(g.altitude, 1)} m`);
    if (d.ground_truth) row("true z (sim)", d.ground_truth, `${fmt(d.ground_truth.z)} m`);
    row("controller", c, c ? `${c.state} · ${c.mode}${c.target_visible ? " · target " + c.target_id : ""}` : "not running");
    if (s && s.failsafe) row("failsafe", s, s.failsafe, true);
    const cmd = d.command;
    rows.push(["station cmd", cmd ? cmd.what : "none", null, false, false]);
  }
  const body = $("telemetry").tBodies[0];
  while (body.rows.length > rows.length) body.deleteRow(-1);
  rows.forEach(([label, text, age, stale, alert], i) => {
    const tr = body.rows[i] || body.insertRow();
    if (tr.cells.length !== 3) { tr.textContent = ""; for (let k = 0; k < 3; k++) tr.insertCell(); tr.cells[2].className = "age"; }
    tr.id = `tm-${label.replace(/\W+/g, "-")}`;
    tr.className = (stale ? "stale" : "") + (alert ? " alert" : "");
    tr.cells[0].textContent = label; tr.cells[1].textContent = text;
    tr.cells[2].textContent = age == null ? "" : age < 1 ? `${Math.round(age * 1000)} ms` : `${age.toFixed(1)} s`;
  });
}

function renderObjects(objects) {
  const sel = $("object-select");
  const names = Object.keys(objects || {});
  if (sel.dataset.sig !== names.join(",")) {
    const keep = sel.value; sel.dataset.sig = names.join(","); sel.textContent = "";
    for (const n of names) { const o = document.createElement("option"); o.value = o.textContent = n; sel.append(o); }
    if (names.includes(keep)) sel.value = keep;
    if (!names.length) { const o = document.createElement("option"); o.textContent = "no simulated objects"; o.value = ""; sel.append(o); }
  }
}

// ---- video socket: one frame in flight, acknowledged once drawn
let videoSocket = null;
function connectVideo() {
  if (videoSocket) { videoSocket.onclose = null; videoSocket.close(); videoSocket = null; }
  if (!station.ns) return;
  const ns = station.ns, camera = station.camera;
  const ws = new WebSocket(wsUrl(`/ws/video/${encodeURIComponent(ns)}/${camera}`));
  ws.binaryType = "arraybuffer";
  ws.onmessage = async (ev) => {
    const buf = ev.data, view = new DataView(buf), n = view.getUint32(0);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
    try {
      const bitmap = await createImageBitmap(new Blob([new Uint8Array(buf, 4 + n)], { type: "image/jpeg" }));
      drawFrame(bitmap, header); bitmap.close();
    } finally { if (ws.readyState === WebSocket.OPEN) ws.send("ack"); }
  };
  ws.onclose = () => { if (videoSocket === ws) setTimeout(() => videoSocket === ws && connectVideo(), 1000); };
  videoSocket = ws;
}

function drawFrame(bitmap, header) {
  const canvas = $("video"), ctx = canvas.getContext("2d");
  if (canvas.width !== bitmap.width || canvas.height !== bitmap.height) { canvas.width = bitmap.width; canvas.height = bitmap.height; }
  ctx.drawImage(bitmap, 0, 0);
  const w = canvas.width, h = canvas.height, d = station.drone;
  const det = d && d.detections && !d.detections.stale && d.detections.camera.endsWith(station.camera) ? d.detections : null;
  if (det) {
    ctx.lineWidth = 2; ctx.font = "13px system-ui, sans-serif";
    for (const b of det.boxes) {
      ctx.strokeStyle = b.target ? "#ffd33d" : "#4cc2ff"; ctx.lineWidth = b.target ? 3 : 2;
      ctx.strokeRect(b.x * w, b.y * h, b.w * w, b.h * h);
      ctx.fillStyle = ctx.strokeStyle;
      ctx.fillText(`${b.label}${b.id ? " #" + b.id : ""} ${(b.score * 100).toFixed(0)}%${b.target ? " target" : ""}`, b.x * w + 2, Math.max(12, b.y * h - 4));
    }
  }
  const c = d && d.controller && !d.controller.stale ? d.controller : null;
  if (c && station.camera === "frontal") { // the controller steers the target to the centre
    ctx.strokeStyle = "#ffd33d"; ctx.lineWidth = 1;
    ctx.beginPath(); ctx.moveTo(w / 2 - 12, h / 2); ctx.lineTo(w / 2 + 12, h / 2); ctx.moveTo(w / 2, h / 2 - 12); ctx.lineTo(w / 2, h / 2 + 12); ctx.stroke();
  }
  const age = Date.now() / 1000 + station.offset - header.stamp;
  station.frames += 1; station.lastFrame = header;
  station.frameAges.push(Date.now() / 1000 - header.stamp); // page clock vs capture stamp (benchmark)
  if (station.frameAges.length > 300) station.frameAges.shift();
  $("frame-age").textContent = `${Math.round(age * 1000)} ms`;
  ctx.fillStyle = "rgba(0,0,0,.55)"; ctx.fillRect(0, h - 20, 220, 20);
  ctx.fillStyle = "#e6edf3"; ctx.font = "12px monospace";
  ctx.fillText(`${header.ns} ${header.camera} #${header.seq} age ${Math.round(age * 1000)} ms`, 4, h - 6);
}

// ---- map: top-down local ENU, north up; click = go there
const map = { scale: 12 };
function mapView() {
  const canvas = $("map"), d = station.drone, p = d && d.pose;
  return { canvas, cx: p ? p.x : 0, cy: p ? p.y : 0, s: map.scale };
}
function drawMap() {
  const { canvas, cx, cy, s } = mapView(), ctx = canvas.getContext("2d"), w = canvas.width, h = canvas.height;
  const sx = (x) => w / 2 + (x - cx) * s, sy = (y) => h / 2 - (y - cy) * s;
  ctx.clearRect(0, 0, w, h);
  const step = s > 20 ? 1 : s > 6 ? 5 : 10;
  ctx.strokeStyle = "#1e2731"; ctx.lineWidth = 1; ctx.beginPath();
  for (let x = Math.floor((cx - w / 2 / s) / step) * step; x < cx + w / 2 / s; x += step) { ctx.moveTo(sx(x), 0); ctx.lineTo(sx(x), h); }
  for (let y = Math.floor((cy - h / 2 / s) / step) * step; y < cy + h / 2 / s; y += step) { ctx.moveTo(0, sy(y)); ctx.lineTo(w, sy(y)); }
  ctx.stroke();
  ctx.strokeStyle = "#4a5866"; ctx.beginPath(); ctx.moveTo(sx(-1), sy(0)); ctx.lineTo(sx(1), sy(0)); ctx.moveTo(sx(0), sy(-1)); ctx.lineTo(sx(0), sy(1)); ctx.stroke();
  ctx.fillStyle = "#8b98a5"; ctx.font = "11px system-ui, sans-serif";
  ctx.fillText(`grid ${step} m`, 6, h - 6); ctx.fillText("N ↑", w - 30, 14);
  const tele = station.tele;
  for (const [name, o] of Object.entries((tele && tele.objects) || {})) {
    ctx.fillStyle = name === "target" ? "#f85149" : "#d29922";
    ctx.beginPath(); ctx.arc(sx(o.x), sy(o.y), 5, 0, 2 * Math.PI); ctx.fill();
    ctx.fillText(name, sx(o.x) + 7, sy(o.y) + 4);
  }
  for (const [ns, trail] of Object.entries(station.trails)) {
    ctx.strokeStyle = ns === station.ns ? "rgba(76,194,255,.7)" : "rgba(139,152,165,.5)"; ctx.lineWidth = 1.5; ctx.beginPath();
    trail.forEach(([x, y], k) => (k ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y)))); ctx.stroke();
  }
  if (station.goal) {
    const [gx, gy] = station.goal; ctx.strokeStyle = "#3fb950"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.arc(sx(gx), sy(gy), 8, 0, 2 * Math.PI); ctx.moveTo(sx(gx) - 12, sy(gy)); ctx.lineTo(sx(gx) + 12, sy(gy));
    ctx.moveTo(sx(gx), sy(gy) - 12); ctx.lineTo(sx(gx), sy(gy) + 12); ctx.stroke();
  }
  drawMissionAndFence(ctx, sx, sy, s);
  const drones = Object.entries((tele && tele.drones) || {});
  drones.sort(([a], [b]) => (a === station.ns) - (b === station.ns)); // the picked one on top
  for (const [ns, d] of drones) {
    if (!d.pose) continue;
    const x = sx(d.pose.x), y = sy(d.pose.y), a = -d.pose.yaw;
    ctx.fillStyle = ns === station.ns ? "#4cc2ff" : "#8b98a5";
    ctx.save(); ctx.translate(x, y); ctx.rotate(a);
    ctx.beginPath(); ctx.moveTo(12, 0); ctx.lineTo(-8, 7); ctx.lineTo(-4, 0); ctx.lineTo(-8, -7); ctx.closePath(); ctx.fill();
    ctx.restore(); ctx.fillText(ns, x + 10, y - 8);
  }
}
// mission items (lat/lon, or local ENU from home) and the envelope (ENU from home) in local ENU
const EARTH_RADIUS_M = 6378137;
function homeLocal(d) { return d.home ? [d.home.x, d.home.y] : [0, 0]; }
function itemLocal(d, item) {
  const [hx, hy] = homeLocal(d);
  if (item.frame === 4) return [hx + item.x, hy + item.y];
  if (!d.home || d.home.latitude === null) return null;
  const lat0 = d.home.latitude * Math.PI / 180;
  const north = (item.x - d.home.latitude) * Math.PI / 180 * EARTH_RADIUS_M;
  const east = (item.y - d.home.longitude) * Math.PI / 180 * EARTH_RADIUS_M * Math.cos(lat0);
  return [hx + east, hy + north];
}
function drawMissionAndFence(ctx, sx, sy, s) {
  const d = station.drone;
  if (!d) return;
  const [hx, hy] = homeLocal(d);
  const env = d.envelope;
  if (env) {
    ctx.strokeStyle = "rgba(248,81,73,.8)"; ctx.lineWidth = 1.5; ctx.setLineDash([6, 4]);
    ctx.beginPath(); ctx.arc(sx(hx), sy(hy), env.max_distance * s, 0, 2 * Math.PI); ctx.stroke();
    for (const polygon of [env.fence, ...env.exclusions]) {
      if (!polygon.length) continue;
      ctx.beginPath();
      polygon.forEach(([x, y], k) => (k ? ctx.lineTo(sx(hx + x), sy(hy + y)) : ctx.moveTo(sx(hx + x), sy(hy + y))));
      ctx.closePath(); ctx.stroke();
    }
    ctx.setLineDash([]);
  }
  const mission = d.mission;
  if (!mission || !mission.items.length) return;
  const points = mission.items.map((item) => itemLocal(d, item)).filter((p) => p);
  ctx.strokeStyle = "rgba(210,153,34,.9)"; ctx.lineWidth = 1.5; ctx.beginPath();
  points.forEach(([x, y], k) => (k ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y)))); ctx.stroke();
  points.forEach(([x, y], k) => {
    ctx.fillStyle = k === mission.current ? "#3fb950" : "#d29922";
    ctx.beginPath(); ctx.arc(sx(x), sy(y), 6, 0, 2 * Math.PI); ctx.fill();
    ctx.fillStyle = "#0d1117"; ctx.fillText(String(k + 1), sx(x) - 3, sy(y) + 4);
  });
}
async function uploadPlan() {
  const file = $("plan-file").files[0];
  if (!file) { $("result").className = "result bad"; $("result").textContent = "pick a .plan file first"; return; }
  let plan;
  try { plan = JSON.parse(await file.text()); } catch (err) {
    $("result").className = "result bad"; $("result").textContent = `${file.name}: not JSON (${err})`; return;
  }
  command("upload_plan", { plan });
}
function onMapClick(e) {
  if (station.role !== "operator" || !station.drone || !station.drone.pose) return;
  const { canvas, cx, cy, s } = mapView(), r = canvas.getBoundingClientRect();
  const px = ((e.clientX - r.left) / r.width) * canvas.width, py = ((e.clientY - r.top) / r.height) * canvas.height;
  const x = cx + (px - canvas.width / 2) / s, y = cy - (py - canvas.height / 2) / s;
  station.goal = [x, y];
  if (station.teleopActive) stopTeleop();
  command("goto", { x, y });
}

// ---- teleop loop: steady rate while held; release, hidden tab or lost link -> stop
const sticks = [];
const keyboard = new Keyboard();
function readSticks() {
  const [left, right] = sticks;
  let out = null;
  const add = (v) => { out = out || { forward: 0, left: 0, up: 0, turn: 0 }; for (const k in v) out[k] += v[k]; };
  if (left.active || right.active) add({ forward: -right.y, left: -right.x, up: -left.y, turn: -left.x });
  const keys = keyboard.sum(TELEOP_KEYS); if (Object.keys(keys).length) add(keys);
  const pad = gamepadSticks();
  $("gamepad").textContent = pad.present ? (pad.sticks ? "gamepad: driving" : "gamepad: hold LB") : "no gamepad";
  if (pad.sticks) add(pad.sticks);
  if (out) for (const k in out) out[k] = Math.max(-1, Math.min(1, out[k]));
  return out;
}
function stopTeleop() {
  if (station.teleopActive && station.ns) send({ type: "teleop_release", ns: station.ns });
  station.teleopActive = false; $("teleop-state").textContent = "idle";
}
function teleopTick() {
  if (station.role !== "operator" || !station.ns || document.hidden) { stopTeleop(); return; }
  const s = readSticks();
  if (!s) { stopTeleop(); return; }
  station.teleopActive = true; station.goal = null;
  $("teleop-state").textContent = `fwd ${s.forward.toFixed(2)} left ${s.left.toFixed(2)} up ${s.up.toFixed(2)} turn ${s.turn.toFixed(2)}`;
  send({ type: "teleop", ns: station.ns, ...s });
}
function objectTick() {
  const name = $("object-select").value, v = keyboard.sum(OBJECT_KEYS);
  const moving = Object.keys(v).length > 0;
  if (station.role !== "operator" || !name || document.hidden) return;
  if (moving || station.objectActive) send({ type: "object", name, east: Math.max(-1, Math.min(1, v.east || 0)), north: Math.max(-1, Math.min(1, v.north || 0)) });
  station.objectActive = moving;
}

// ---- start
const plots = {};
async function start() {
  plots.alt = new TimePlot($("plot-alt"), [{ name: "altitude", color: "#4cc2ff" }, { name: "true (sim)", color: "#3fb950" }]);
  plots.err = new TimePlot($("plot-err"), [{ name: "e_x", color: "#ffd33d" }, { name: "e_z /100 px", color: "#4cc2ff" }, { name: "e_yaw /100 px", color: "#f778ba" }]);
  plots.cmd = new TimePlot($("plot-cmd"), [{ name: "vx", color: "#4cc2ff" }, { name: "vz", color: "#3fb950" }, { name: "yaw rate", color: "#f778ba" }, { name: "vx measured", color: "#8b98a5" }]);
  sticks.push(new Stick($("stick-left")), new Stick($("stick-right")));
  const info = await (await fetch("/api/session", { headers: { "X-Station-Token": station.token } })).json();
  station.limits = info.limits; $("takeoff-height").max = info.takeoff_max;
  for (const m of info.modes) { const o = document.createElement("option"); o.value = o.textContent = m; $("mode-select").append(o); }
  setRole(info.role);
  $("btn-arm").onclick = () => command("arm");
  $("btn-disarm").onclick = () => command("disarm");
  $("btn-takeoff").onclick = () => command("takeoff", { height: Number($("takeoff-height").value) });
  $("btn-land").onclick = () => { stopTeleop(); command("land"); };
  $("btn-hold").onclick = () => { stopTeleop(); command("hold"); };
  $("btn-plan").onclick = uploadPlan;
  $("btn-mission-start").onclick = () => { stopTeleop(); command("start_mission"); };
  $("btn-mission-pause").onclick = () => command("pause_mission");
  $("btn-rtl").onclick = () => { stopTeleop(); command("rtl"); };
  $("btn-reset").onclick = () => { stopTeleop(); command("reset"); };
  $("btn-land-all").onclick = () => { stopTeleop(); landAll(); };
  $("btn-mode").onclick = () => command("mode", { mode: $("mode-select").value });
  for (const b of document.querySelectorAll(".seg button")) b.onclick = () => {
    station.camera = b.dataset.camera;
    for (const o of document.querySelectorAll(".seg button")) o.classList.toggle("on", o === b);
    connectVideo();
  };
  $("btn-world-load").onclick = () => loadWorld($("scenario-select").value);
  $("btn-world-reset").onclick = async () => { const w = await refreshWorld(); if (w) loadWorld(w.scenario); };
  refreshWorld();
  setInterval(refreshWorld, 5000);
  $("map").addEventListener("click", onMapClick);
  $("map").addEventListener("wheel", (e) => { e.preventDefault(); map.scale = Math.max(2, Math.min(80, map.scale * (e.deltaY < 0 ? 1.2 : 1 / 1.2))); }, { passive: false });
  document.addEventListener("visibilitychange", () => { if (document.hidden) { for (const s of sticks) s.release(); keyboard.down.clear(); stopTeleop(); } });
  connectTelemetry();
  setInterval(teleopTick, 1000 / TELEOP_HZ);
  setInterval(objectTick, 1000 / OBJECT_HZ);
  const frame = () => { const now = Date.now() / 1000; for (const p of Object.values(plots)) p.draw(now); drawMap(); requestAnimationFrame(frame); };
  requestAnimationFrame(frame);
}
start();
