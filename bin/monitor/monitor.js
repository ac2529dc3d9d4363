// vrpn_monitor's page: reads snapshots from /events (server-sent events, 30 a second) and
// shows each device. Every value is text in the DOM; the 3D views are drawn on 2D canvases.
"use strict";

const TRAIL = 90;            // points kept per sensor (snapshots, so about 3 s)
const devices = new Map();   // name -> view state
const $devices = document.getElementById("devices");
const $status = document.getElementById("status");

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

const fmt = (v, d) => (v === null || v === undefined || !isFinite(v)) ? "–" : v.toFixed(d);
const ms = (s) => (s === null || s === undefined) ? "–" : (s * 1000).toFixed(2) + " ms";
const idOf = (s) => s.replace(/[^A-Za-z0-9_-]/g, "_");

// ---------------------------------------------------------------- 3D view

// Rotates vector v by unit quaternion q = [x, y, z, w].
function rotate(q, v) {
  const [x, y, z, w] = q;
  const tx = 2 * (y * v[2] - z * v[1]), ty = 2 * (z * v[0] - x * v[2]), tz = 2 * (x * v[1] - y * v[0]);
  return [v[0] + w * tx + (y * tz - z * ty), v[1] + w * ty + (z * tx - x * tz), v[2] + w * tz + (x * ty - y * tx)];
}

class View {
  constructor(canvas) {
    this.c = canvas;
    this.g = canvas.getContext("2d");
    this.yaw = -0.6; this.pitch = 0.45; this.zoom = 1; this.scale = 0.5;
    let drag = null;
    canvas.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; });
    window.addEventListener("mouseup", () => { drag = null; });
    window.addEventListener("mousemove", (e) => {
      if (!drag) return;
      this.yaw += (e.clientX - drag[0]) * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY];
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.zoom *= e.deltaY > 0 ? 0.9 : 1.1;
    }, { passive: false });
  }

  // World (x, y, z up) to screen, with the centre `o` of the scene.
  project(p) {
    const s = this.scale, o = this.centre;
    const x = (p[0] - o[0]) / s, y = (p[1] - o[1]) / s, z = (p[2] - o[2]) / s;
    const cy = Math.cos(this.yaw), sy = Math.sin(this.yaw), cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    const x1 = cy * x - sy * y, y1 = sy * x + cy * y;          // turn about z
    const depth = cp * y1 + sp * z, up = -sp * y1 + cp * z;     // tilt
    const f = 3.2 / (4 + depth) * this.zoom;
    const w = this.c.width, h = this.c.height, k = Math.min(w, h) * 0.42;
    return [w / 2 + x1 * f * k, h / 2 - up * f * k];
  }

  line(a, b, colour, width) {
    const g = this.g, p = this.project(a), q = this.project(b);
    g.strokeStyle = colour; g.lineWidth = width || 1;
    g.beginPath(); g.moveTo(p[0], p[1]); g.lineTo(q[0], q[1]); g.stroke();
  }

  draw(sensors) {
    const g = this.g, w = this.c.width, h = this.c.height;
    // Fit the scene: centre and size from every trail, eased so the view does not jump.
    let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const s of sensors) for (const p of s.trail) for (let i = 0; i < 3; i++) {
      lo[i] = Math.min(lo[i], p[i]); hi[i] = Math.max(hi[i], p[i]);
    }
    if (!isFinite(lo[0])) { lo = [0, 0, 0]; hi = [0, 0, 0]; }
    const centre = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
    const size = Math.max(0.2, ...[0, 1, 2].map((i) => (hi[i] - lo[i]) / 2)) * 1.3;
    this.centre = this.centre ? this.centre.map((c, i) => c + (centre[i] - c) * 0.1) : centre;
    this.scale += (size - this.scale) * 0.1;
    g.clearRect(0, 0, w, h);
    // Floor grid at the lowest point, in steps that suit the scale.
    const step = Math.pow(10, Math.floor(Math.log10(this.scale))) / 2;
    const n = Math.ceil(this.scale / step), z0 = this.centre[2] - this.scale;
    const gx = Math.round(this.centre[0] / step) * step, gy = Math.round(this.centre[1] / step) * step;
    for (let i = -n; i <= n; i++) {
      this.line([gx + i * step, gy - n * step, z0], [gx + i * step, gy + n * step, z0], "#242a33");
      this.line([gx - n * step, gy + i * step, z0], [gx + n * step, gy + i * step, z0], "#242a33");
    }
    // The tracker's origin axes, when near.
    const a = this.scale * 0.35;
    this.line([0, 0, 0], [a, 0, 0], "#803a3a"); this.line([0, 0, 0], [0, a, 0], "#3a803a");
    this.line([0, 0, 0], [0, 0, a], "#3a5a9a");
    g.fillStyle = "#8a96a3"; g.font = "11px sans-serif";
    g.fillText("grid " + step.toPrecision(2) + " m", 6, h - 6);
    for (const s of sensors) {
      // Trail, older points fainter.
      for (let i = 1; i < s.trail.length; i++) {
        const alpha = (i / s.trail.length).toFixed(2);
        this.line(s.trail[i - 1], s.trail[i], `rgba(255,179,71,${alpha})`, 1.5);
      }
      const p = s.pos, len = this.scale * 0.22;
      const axes = [[1, 0, 0, "#ff5a5a"], [0, 1, 0, "#5ad35a"], [0, 0, 1, "#5a9aff"]];
      for (const [x, y, z, colour] of axes) {
        const d = rotate(s.quat, [x * len, y * len, z * len]);
        this.line(p, [p[0] + d[0], p[1] + d[1], p[2] + d[2]], colour, 2.5);
      }
      const q = this.project(p);
      g.fillStyle = "#ffffff"; g.beginPath(); g.arc(q[0], q[1], 3, 0, 7); g.fill();
      g.fillText(String(s.id), q[0] + 6, q[1] - 6);
    }
  }
}

// ---------------------------------------------------------------- one device

function makeDevice(d) {
  const root = el("section", "device");
  root.id = "dev-" + idOf(d.name);
  const h = el("h2");
  h.append(el("span", "name", d.name), el("span", "loc", "@" + d.location));
  const link = el("div", "link");
  const state = el("span", "state");
  const reconnects = el("span", "reconnects");
  const clock = el("span", "clock");
  link.append("connection: ", state, " · reconnects: ", reconnects, " · clock: ", clock);
  const waiting = el("div", "waiting", "waiting for reports…");
  root.append(h, link, waiting);
  $devices.append(root);
  return { root, state, reconnects, clock, waiting, sensors: new Map() };
}

function section(v, key, title) {
  if (!v[key]) {
    const s = el("div", "section " + key);
    s.append(el("h3", null, title));
    v.root.append(s);
    v[key] = s;
  }
  return v[key];
}

function showTracker(v, d) {
  const sec = section(v, "trackerSec", "tracker");
  if (!v.view) {
    const box = el("div", "tracker");
    const canvas = el("canvas", "view");
    canvas.width = 420; canvas.height = 300;
    const table = el("table", "sensors");
    const head = el("tr");
    for (const t of ["sensor", "x", "y", "z", "qx", "qy", "qz", "qw", "rate", "reports", "age", "latency"])
      head.append(el("th", null, t));
    table.append(head);
    box.append(canvas, table);
    sec.append(box);
    v.view = new View(canvas);
    v.root.classList.add("wide");
    v.table = table;
  }
  for (const s of d.sensors) {
    let row = v.sensors.get(s.id);
    if (!row) {
      const tr = el("tr");
      tr.id = `dev-${idOf(d.name)}-sensor-${s.id}`;
      const cells = {};
      for (const k of ["sid", "x", "y", "z", "qx", "qy", "qz", "qw", "rate", "count", "age", "latency"]) {
        cells[k] = el("td", k === "sid" ? "sid" : "v " + k);
        tr.append(cells[k]);
      }
      v.table.append(tr);
      row = { cells, trail: [] };
      v.sensors.set(s.id, row);
    }
    const c = row.cells;
    c.sid.textContent = s.id;
    ["x", "y", "z"].forEach((k, i) => { c[k].textContent = fmt(s.pos[i], 4); });
    ["qx", "qy", "qz", "qw"].forEach((k, i) => { c[k].textContent = fmt(s.quat[i], 4); });
    c.rate.textContent = fmt(s.rate, 1) + " Hz";
    c.count.textContent = s.count;
    c.age.textContent = ms(s.age);
    c.latency.textContent = s.latency === null ? "no sync" : ms(s.latency);
    const last = row.trail[row.trail.length - 1];
    if (!last || last[0] !== s.pos[0] || last[1] !== s.pos[1] || last[2] !== s.pos[2]) {
      row.trail.push(s.pos.slice());
      if (row.trail.length > TRAIL) row.trail.shift();
    }
    row.pos = s.pos; row.quat = s.quat; row.id = s.id;
  }
  v.view.draw([...v.sensors.values()]);
}

function showButtons(v, b) {
  const sec = section(v, "buttonSec", "buttons");
  if (!v.keys) { v.keys = el("div", "keys"); sec.append(v.keys); }
  while (v.keys.children.length < b.states.length) {
    const i = v.keys.children.length;
    const k = el("div", "key");
    k.append(el("b", null, String(i)), el("span", "presses"));
    v.keys.append(k);
  }
  b.states.forEach((on, i) => {
    const k = v.keys.children[i];
    k.classList.toggle("on", on);
    k.querySelector(".presses").textContent = "×" + b.presses[i];
    k.title = `button ${i}: ${on ? "pressed" : "released"}, pressed ${b.presses[i]} times`;
  });
}

function showAnalog(v, a) {
  const sec = section(v, "analogSec", "analog");
  if (!v.bars) {
    v.bars = el("div", "bars"); v.rate = el("div", "link");
    sec.append(v.bars, v.rate); v.range = [];
  }
  while (v.bars.children.length < a.channels.length) {
    const i = v.bars.children.length;
    const row = el("div", "bar");
    const track = el("div", "track");
    track.append(el("div", "zero"), el("div", "fill"));
    row.append(el("span", null, "ch" + i), track, el("span", "val"));
    v.bars.append(row);
  }
  a.channels.forEach((x, i) => {
    const row = v.bars.children[i];
    v.range[i] = Math.max(v.range[i] || 1, Math.abs(x));
    const f = Math.max(-1, Math.min(1, x / v.range[i]));
    const fill = row.querySelector(".fill");
    fill.style.left = (f < 0 ? 50 + f * 50 : 50) + "%";
    fill.style.width = Math.abs(f * 50) + "%";
    row.querySelector(".val").textContent = fmt(x, 4);
  });
  v.rate.textContent = `${a.count} reports · ${fmt(a.rate, 1)} Hz`;
}

function showDials(v, d) {
  const sec = section(v, "dialSec", "dials");
  if (!v.dials) { v.dials = el("div", "dials"); sec.append(v.dials); }
  while (v.dials.children.length < d.totals.length) {
    const box = el("div", "dial"), face = el("div", "face");
    face.append(el("div", "needle"));
    box.append(face, el("span", "val"));
    v.dials.append(box);
  }
  d.totals.forEach((t, i) => {
    const box = v.dials.children[i];
    box.querySelector(".needle").style.transform = `rotate(${t * 360}deg)`;
    box.querySelector(".val").textContent = `dial ${i}: ${fmt(t, 3)} rev`;
  });
}

function showTexts(v, texts) {
  const sec = section(v, "textSec", "messages");
  if (!v.texts) { v.texts = el("ul", "texts"); sec.append(v.texts); }
  const key = texts.map((t) => t.time + t.text).join("|");
  if (key === v.textKey) return;
  v.textKey = key;
  v.texts.replaceChildren(...texts.slice().reverse().map((t) => {
    const when = new Date(t.time * 1000).toLocaleTimeString();
    return el("li", t.severity, `${when} [${t.severity}] ${t.text}`);
  }));
}

function show(d) {
  let v = devices.get(d.name);
  if (!v) { v = makeDevice(d); devices.set(d.name, v); }
  v.state.textContent = d.state;
  v.state.className = "state " + d.state;
  v.reconnects.textContent = d.reconnects;
  v.clock.textContent = d.clock
    ? `synchronised (offset ${(d.clock.offset * 1e3).toFixed(3)} ± ${(d.clock.uncertainty * 1e3).toFixed(3)} ms)`
    : "not synchronised";
  const any = d.sensors.length || d.buttons || d.analog || d.dials || d.texts.length;
  v.waiting.hidden = !!any;
  if (d.sensors.length) showTracker(v, d);
  if (d.buttons) showButtons(v, d.buttons);
  if (d.analog) showAnalog(v, d.analog);
  if (d.dials) showDials(v, d.dials);
  if (d.texts.length) showTexts(v, d.texts);
}

// ---------------------------------------------------------------- the stream

let updates = 0;
function connect() {
  const events = new EventSource("/events");
  events.onmessage = (m) => {
    const snap = JSON.parse(m.data);
    if (!snap || !snap.devices) return;
    updates++;
    snap.devices.forEach(show);
    const list = snap.list ? ` · listing ${snap.list.location} (${snap.list.state})` : "";
    $status.textContent = `${snap.devices.length} device(s) · update ${updates} · ` +
      new Date(snap.time * 1000).toLocaleTimeString() + list;
  };
  events.onerror = () => { $status.textContent = "monitor unreachable, retrying…"; };
}
connect();
