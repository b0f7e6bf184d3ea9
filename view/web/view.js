// shapeform view: draws the frames that shapeform_view streams (Server-Sent Events on /events). Every
// coordinate comes from the server, the commanded shape too (sampled with the project's curve code):
// this page only draws. The stream starts with a full frame and goes on with what changed (view/scene.hpp
// documents the frame): the page keeps the agents, trails, centre path and charts itself, and draws the
// newest state once per animation frame. What it drew is exposed as window.shapeformDrawn for tests.
"use strict";

const COLOURS = { alive: "#1565c0", stale: "#ef6c00", dead: "#9e9e9e" };
const canvas = document.getElementById("canvas");
const ctx = canvas.getContext("2d");
const tip = document.getElementById("tip");
let view = null;        // {cx, cy, half}: the world square shown, eased from frame to frame
let last = null;        // the newest state drawn (kept(): the frame as the drawing functions read it)
let frames = 0;         // frames drawn
let received = 0;       // frames received
let bytes = 0;          // their characters
let resyncs = 0;        // gaps seen (the stream started anew)
const arrivals = [];    // arrival times of recent frames (ms), for the frame rate shown
const draws = [];       // times of recent draws (ms)
const TABLE_ROWS = 100; // the agent table shows the first rows by id ...
const TABLE_EVERY_MS = 500;  // ... rebuilt at most twice a second
let table_at = -Infinity;
const LOG_MAX = 5000;   // entries of window.shapeformLog
window.shapeformLog = [];

window.shapeformDrawn = { agents: [], outline_points: 0, chart_points: 0, chart_model_time: null, model_time: null,
  frames: 0, received: 0, bytes: 0, resyncs: 0, mode: null, replay: null, zones: 0, separation_points: 0, separation_run_points: 0,
  separation_limit: null, safety_shown: false, blocked_mark: false, fence_points: 0 };

// The safety line's counts: [key of the frame's "safety", label].
const SAFETY_COUNTS = [["filter_interventions", "interventions"], ["deadlock_sidesteps", "sidesteps"],
  ["promises_broken", "broken promises"], ["agents_blocked", "agents blocked"], ["fence_breaches", "fence breaches"],
  ["agents_beyond_fence", "beyond the fence now"]];

function fmt(v, digits) {
  return v === null || v === undefined ? "–" : Number(v).toFixed(digits);
}

// The corners of a keep-out zone's bounding box ({circle: [cx, cy, r]} or {polygon: [[x, y], ...]}).
function zone_extent(z) {
  if (z.circle) { const [x, y, r] = z.circle; return [[x - r, y - r], [x + r, y + r]]; }
  return z.polygon;
}

// The world square to show: alive agents, a closed outline, keep-out zones, the centre and its path.
function target_view(f) {
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  const add = (x, y) => { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); };
  for (const a of f.agents) if (a.state !== "dead") add(a.x1, a.x2);
  if (f.outline && f.outline.closed) for (const p of f.outline.points) add(p[0], p[1]);
  for (const z of f.keep_out || []) for (const p of zone_extent(z)) add(p[0], p[1]);
  if (f.fence) for (const p of f.fence.polygon) add(p[0], p[1]);
  if (f.centre) add(f.centre[0], f.centre[1]);
  for (const p of f.centre_path) add(p[0], p[1]);
  if (x0 > x1) return { cx: 0, cy: 0, half: 10 };
  return { cx: (x0 + x1) / 2, cy: (y0 + y1) / 2, half: Math.max(1, 0.55 * Math.max(x1 - x0, y1 - y0) + 1) };
}

function ease(v, t) {
  if (!v) return t;
  const k = 0.25;
  return { cx: v.cx + k * (t.cx - v.cx), cy: v.cy + k * (t.cy - v.cy), half: v.half + k * (t.half - v.half) };
}

function to_px(x, y) {
  const s = canvas.width / (2 * view.half);
  return [(x - view.cx) * s + canvas.width / 2, canvas.height / 2 - (y - view.cy) * s];
}

function polyline(points, closed) {
  ctx.beginPath();
  points.forEach((p, i) => {
    const [u, v] = to_px(p[0], p[1]);
    if (i === 0) ctx.moveTo(u, v); else ctx.lineTo(u, v);
  });
  if (closed) ctx.closePath();
  ctx.stroke();
}

// A red hatch for keep-out zones, made once.
let hatch = null;
function zone_fill() {
  if (hatch) return hatch;
  const tile = document.createElement("canvas");
  tile.width = tile.height = 8;
  const g = tile.getContext("2d");
  g.fillStyle = "rgba(198, 40, 40, 0.10)"; g.fillRect(0, 0, 8, 8);
  g.strokeStyle = "rgba(198, 40, 40, 0.45)"; g.lineWidth = 1;
  g.beginPath();  // one diagonal, continued across the tile's corners so that tiles join
  g.moveTo(0, 8); g.lineTo(8, 0); g.moveTo(-2, 2); g.lineTo(2, -2); g.moveTo(6, 10); g.lineTo(10, 6);
  g.stroke();
  hatch = ctx.createPattern(tile, "repeat");
  return hatch;
}

// The command's keep-out zones: hatched, outlined in red. Returns how many were drawn.
function draw_zones(zones) {
  let n = 0;
  ctx.setLineDash([]); ctx.lineWidth = 1.5; ctx.strokeStyle = "#c62828"; ctx.fillStyle = zone_fill();
  for (const z of zones) {
    ctx.beginPath();
    if (z.circle) {
      const [x, y, r] = z.circle;
      const [u, v] = to_px(x, y);
      ctx.arc(u, v, (r * canvas.width) / (2 * view.half), 0, 2 * Math.PI);
    } else if (z.polygon && z.polygon.length >= 3) {
      z.polygon.forEach((p, i) => {
        const [u, v] = to_px(p[0], p[1]);
        if (i === 0) ctx.moveTo(u, v); else ctx.lineTo(u, v);
      });
      ctx.closePath();
    } else {
      continue;
    }
    ctx.fill(); ctx.stroke();
    n += 1;
  }
  return n;
}

function draw_scene(f) {
  view = ease(view, target_view(f));
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  // Grid: one line per unit when it is not too dense.
  ctx.strokeStyle = "#eceff1"; ctx.lineWidth = 1; ctx.setLineDash([]);
  const step = Math.pow(10, Math.floor(Math.log10(view.half)));
  for (let g = Math.ceil((view.cx - view.half) / step) * step; g <= view.cx + view.half; g += step) {
    polyline([[g, view.cy - view.half], [g, view.cy + view.half]], false);
  }
  for (let g = Math.ceil((view.cy - view.half) / step) * step; g <= view.cy + view.half; g += step) {
    polyline([[view.cx - view.half, g], [view.cx + view.half, g]], false);
  }
  // Under everything else: the safety filter's constraints, the fence (safety.fence) and the zones.
  if (f.fence) {
    ctx.strokeStyle = "#ef6c00"; ctx.lineWidth = 2;
    polyline(f.fence.polygon, true);
  }
  const zones = draw_zones(f.keep_out || []);
  let outline_points = 0;
  if (f.outline) {
    ctx.strokeStyle = "#2e7d32"; ctx.lineWidth = 2; ctx.setLineDash([8, 6]);
    polyline(f.outline.points, f.outline.closed);
    ctx.setLineDash([]);
    outline_points = f.outline.points.length;
  }
  // Every trail in one path (one stroke for a thousand agents); a trail point is [t, x1, x2].
  ctx.lineWidth = 1; ctx.strokeStyle = "rgba(21, 101, 192, 0.25)";
  ctx.beginPath();
  for (const pts of f.trails.values()) {
    if (pts.length < 2) continue;
    for (let i = 0; i < pts.length; ++i) {
      const [u, v] = to_px(pts[i][1], pts[i][2]);
      if (i === 0) ctx.moveTo(u, v); else ctx.lineTo(u, v);
    }
  }
  ctx.stroke();
  if (f.centre_path.length > 1) {
    ctx.strokeStyle = "rgba(198, 40, 40, 0.5)";
    polyline(f.centre_path, false);
  }
  if (f.centre) {
    const [u, v] = to_px(f.centre[0], f.centre[1]);
    ctx.strokeStyle = "#c62828"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.moveTo(u - 7, v); ctx.lineTo(u + 7, v); ctx.moveTo(u, v - 7); ctx.lineTo(u, v + 7); ctx.stroke();
  }
  const drawn = [];
  // With a separation d, each live agent's disc of radius d / 2: two discs that touch are at the limit.
  const d = f.min_separation || 0;
  if (d > 0) {
    ctx.strokeStyle = "rgba(21, 101, 192, 0.35)"; ctx.lineWidth = 1; ctx.setLineDash([2, 3]);
    const r = (0.5 * d * canvas.width) / (2 * view.half);
    ctx.beginPath();
    for (const a of f.agents) {
      if (a.state === "dead" || r < 2) continue;
      const [u, v] = to_px(a.x1, a.x2);
      ctx.moveTo(u + r, v); ctx.arc(u, v, r, 0, 2 * Math.PI);
    }
    ctx.stroke();
    ctx.setLineDash([]);
  }
  // The agents, one path per state (and one for the dead marks, one per state for the headings).
  const discs = { alive: new Path2D(), stale: new Path2D(), dead: new Path2D() };
  const ticks = { alive: new Path2D(), stale: new Path2D(), dead: new Path2D() };
  const crosses = new Path2D();
  for (const a of f.agents) {
    const [u, v] = to_px(a.x1, a.x2);
    const state = COLOURS[a.state] ? a.state : "dead";
    discs[state].moveTo(u + 6, v); discs[state].arc(u, v, 6, 0, 2 * Math.PI);
    if (state === "dead") {
      crosses.moveTo(u - 3, v - 3); crosses.lineTo(u + 3, v + 3); crosses.moveTo(u + 3, v - 3); crosses.lineTo(u - 3, v + 3);
    }
    const heading = a.heading === undefined ? null : a.heading;
    if (heading !== null) {
      // The vehicle's heading: a tick from the agent's edge outward (screen y points down).
      const c = Math.cos(heading), s = -Math.sin(heading);
      ticks[state].moveTo(u + 6 * c, v + 6 * s); ticks[state].lineTo(u + 16 * c, v + 16 * s);
    }
    drawn.push({ id: a.id, x1: a.x1, x2: a.x2, state: a.state, model_time: a.model_time, heading: heading, u: u, v: v });
  }
  ctx.lineWidth = 2;
  for (const state of ["dead", "stale", "alive"]) {
    ctx.strokeStyle = COLOURS[state]; ctx.fillStyle = COLOURS[state];
    if (state === "stale") ctx.stroke(discs[state]); else ctx.fill(discs[state]);
    ctx.stroke(ticks[state]);
  }
  ctx.strokeStyle = "#fff"; ctx.stroke(crosses);
  // Agents held by the safety filter: the frame counts them but does not say which, so the mark is the
  // scene's, not an agent's.
  const blocked = f.safety ? f.safety.agents_blocked || 0 : 0;
  if (blocked > 0) {
    const text = blocked === 1 ? "1 agent held by the safety filter" : blocked + " agents held by the safety filter";
    ctx.font = "bold 13px sans-serif";
    const w = ctx.measureText(text).width + 16;
    ctx.fillStyle = "rgba(198, 40, 40, 0.9)"; ctx.fillRect(8, 8, w, 22);
    ctx.fillStyle = "#fff"; ctx.fillText(text, 16, 24);
  }
  return { drawn: drawn, outline_points: outline_points, zones: zones, blocked_mark: blocked > 0 };
}

// One chart of model time: `series` = [{column, colour}, ...] of f.chart, `level` a dashed horizontal
// line (null: none). Returns the points drawn of each series.
function draw_series(id, f, series, level) {
  const c = document.getElementById(id), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const lines = series.map((s) => {
    const k = f.chart.columns.indexOf(s.column);
    const pts = k < 0 ? [] : f.chart.points.filter((p) => Number.isFinite(p[0]) && Number.isFinite(p[k]));
    return { k: k, colour: s.colour, pts: pts };
  });
  const all = lines.flatMap((l) => l.pts);
  if (all.length === 0) return lines.map(() => 0);
  let t0 = Infinity, t1 = -Infinity, lo = 0, hi = 0;
  for (const l of lines) {
    for (const p of l.pts) {
      t0 = Math.min(t0, p[0]); t1 = Math.max(t1, p[0]); lo = Math.min(lo, p[l.k]); hi = Math.max(hi, p[l.k]);
    }
  }
  if (level !== null) { lo = Math.min(lo, level); hi = Math.max(hi, 1.1 * level); }
  t1 = Math.max(t1, t0 + 1e-9);
  if (hi <= lo) hi = lo + 1;
  const L = 40, R = 8, T = 8, B = 18, w = c.width - L - R, h = c.height - T - B;
  const y = (value) => T + h - (h * (value - lo)) / (hi - lo);
  g.strokeStyle = "#b0bec5"; g.lineWidth = 1; g.setLineDash([]);
  g.strokeRect(L, T, w, h);
  g.fillStyle = "#555"; g.font = "10px sans-serif";
  g.fillText(hi.toPrecision(3), 2, T + 8); g.fillText(lo.toPrecision(3), 2, T + h);
  g.fillText(t0.toFixed(0), L, c.height - 4); g.fillText(t1.toFixed(0), L + w - 24, c.height - 4);
  if (level !== null) {
    g.strokeStyle = "#c62828"; g.lineWidth = 1; g.setLineDash([5, 4]);
    g.beginPath(); g.moveTo(L, y(level)); g.lineTo(L + w, y(level)); g.stroke();
    g.setLineDash([]);
  }
  for (const l of lines) {
    g.strokeStyle = l.colour; g.lineWidth = 1.5;
    g.beginPath();
    l.pts.forEach((p, i) => {
      const u = L + (w * (p[0] - t0)) / (t1 - t0);
      if (i === 0) g.moveTo(u, y(p[l.k])); else g.lineTo(u, y(p[l.k]));
    });
    g.stroke();
  }
  return lines.map((l) => l.pts.length);
}

function draw_chart(id, f, column) {
  return draw_series(id, f, [{ column: column, colour: "#1565c0" }], null)[0];
}

// The safety line: shown when the command filters (a separation or a zone) or a figure is non-zero.
function fill_safety(f) {
  const box = document.getElementById("safety");
  const s = f.safety || {};
  const filters = (f.min_separation || 0) > 0 || (f.keep_out || []).length > 0 || !!f.fence;
  const shown = filters || SAFETY_COUNTS.some(([k]) => s[k]);
  box.hidden = !shown;
  if (!shown) return false;
  const parts = SAFETY_COUNTS.map(([k, label]) =>
    `<span class="${s[k] ? "nonzero" : ""}">${label} <b>${s[k] === null || s[k] === undefined ? "–" : s[k]}</b></span>`);
  const run = s.min_separation_run === null || s.min_separation_run === undefined ? "–" :
    `${fmt(s.min_separation_run, 3)} (t = ${fmt(s.min_separation_run_time, 1)})`;
  box.innerHTML = `<span>safety: d = <b>${fmt(f.min_separation || 0, 3)}</b>, ${(f.keep_out || []).length} zone(s)` +
    (f.fence ? `, fence of ${f.fence.polygon.length} sides (margin ${fmt(f.fence.margin, 3)}, on breach ${f.fence.action})` : "") + "; " +
    `closest <b>${run}</b></span> ` + parts.join(" ");
  return true;
}

// The agent table: the first TABLE_ROWS agents by id, rebuilt at most every TABLE_EVERY_MS (a thousand
// rows rebuilt fifteen times a second would cost more than drawing the scene).
function fill_table(f) {
  const now = performance.now();
  if (now - table_at < TABLE_EVERY_MS) return;
  table_at = now;
  const body = document.querySelector("#agents tbody");
  const rows = f.agents.slice(0, TABLE_ROWS).map((a) =>
    `<tr class="${a.state}"><td>${a.id}</td><td>${a.state}</td><td>${fmt(a.x1, 3)}</td><td>${fmt(a.x2, 3)}</td>` +
    `<td>${a.heading === null || a.heading === undefined ? "–" : fmt((a.heading * 180) / Math.PI, 0)}</td>` +
    `<td>${a.heard === null ? "–" : a.heard}</td><td>${a.epoch}</td><td>${fmt(a.lateness_us, 0)}</td></tr>`);
  if (f.agents.length > TABLE_ROWS) {
    rows.push(`<tr class="more"><td colspan="8">the first ${TABLE_ROWS} of ${f.agents.length} agents</td></tr>`);
  }
  body.innerHTML = rows.join("");
}

function fill_header(f) {
  const alive = f.agents.filter((a) => a.state === "alive").length;
  document.getElementById("mode").textContent = f.mode;
  document.getElementById("model-time").textContent = fmt(f.model_time, 1);
  document.getElementById("epoch").textContent = f.epoch;
  document.getElementById("alive").textContent = alive + " alive of " + f.agents.length;
  const conv = document.getElementById("converged");
  conv.textContent = f.converged ? "converged" : "";
  conv.className = f.converged ? "yes" : "";
  const now = performance.now();
  draws.push(now);
  while (draws.length > 0 && draws[0] < now - 2000) draws.shift();
  while (arrivals.length > 0 && arrivals[0] < now - 2000) arrivals.shift();
  document.getElementById("fps").textContent = (draws.length / 2).toFixed(0) + " frames/s drawn, " +
    (arrivals.length / 2).toFixed(0) + " received";
}

let seeking = false;
function fill_replay(f) {
  const box = document.getElementById("replay");
  if (f.mode !== "replay") { box.hidden = true; return; }
  box.hidden = false;
  const r = f.replay;
  document.getElementById("play").textContent = r.playing ? "pause" : "play";
  const seek = document.getElementById("seek");
  seek.max = r.end_s;
  if (!seeking) seek.value = r.position_s;
  document.getElementById("position").textContent = fmt(r.position_s, 1) + " / " + fmt(r.end_s, 1) + " s";
}

function control(action, value) {
  const q = "action=" + encodeURIComponent(action) + (value === undefined ? "" : "&value=" + encodeURIComponent(value));
  return fetch("/control?" + q, { method: "POST" });
}
document.getElementById("play").addEventListener("click", () => {
  control(last && last.replay && last.replay.playing ? "pause" : "play");
});
document.getElementById("speed").addEventListener("change", (e) => control("speed", e.target.value));
const seek = document.getElementById("seek");
seek.addEventListener("input", () => { seeking = true; });
seek.addEventListener("change", () => { control("seek", seek.value).finally(() => { seeking = false; }); });

// What the page keeps (view/scene.hpp: a full frame replaces it, a delta updates it).
let kept = null;

function apply(f) {
  if (f.full) {
    kept = { seq: 0, agents: new Map(), sorted: null, trails: new Map(), centre_path: [], chart_points: [],
      outline: null, keep_out: [], fence: null, min_separation: 0 };
  } else if (!kept || f.seq !== kept.seq + 1) {
    // A frame missed (the server sends every one in order, so this is a bug or a lost connection):
    // start the stream anew, which begins with a full frame.
    resyncs += 1;
    kept = null;
    queue.length = 0;
    connect();
    return;
  }
  kept.seq = f.seq;
  const col = {};
  f.agent_columns.forEach((c, i) => { col[c] = i; });
  for (const r of f.agents) {
    const id = r[col.id];
    if (!kept.agents.has(id)) kept.sorted = null;
    kept.agents.set(id, { id: id, x1: r[col.x1], x2: r[col.x2], state: r[col.state], model_time: r[col.model_time],
      epoch: r[col.epoch], heard: r[col.heard], lateness_us: r[col.lateness_us], heading: r[col.heading] });
  }
  const t = f.trails;
  for (let k = 0; k < t.length; k += 4) {
    let pts = kept.trails.get(t[k]);
    if (!pts) { pts = []; kept.trails.set(t[k], pts); }
    pts.push([t[k + 1], t[k + 2], t[k + 3]]);
  }
  // The server's rule (view/scene.cpp): a point older than now_s - trail_s goes.
  const oldest = f.now_s - f.trail_s;
  for (const pts of kept.trails.values()) {
    let n = 0;
    while (n < pts.length && pts[n][0] < oldest) n += 1;
    if (n > 0) pts.splice(0, n);
  }
  if (f.centre_path.replace) kept.centre_path = [];
  for (const p of f.centre_path.points) kept.centre_path.push(p);
  if (f.chart.replace) kept.chart_points = [];
  for (const p of f.chart.points) kept.chart_points.push(p);
  kept.chart_columns = f.chart.columns;
  for (const key of ["outline", "keep_out", "fence", "min_separation"]) if (key in f) kept[key] = f[key];
  for (const key of ["now_s", "model_time", "epoch", "converged", "centre", "metrics", "safety", "mode"]) kept[key] = f[key];
  kept.replay = f.replay || null;
}

// What the page keeps, as plain JSON (for the browser test, which compares it with a snapshot of GET
// /frame): {seq, agents: [{id, ...}] by id, trails: {id: [[t, x1, x2], ...]}, centre_path, chart_points,
// outline, keep_out, fence, min_separation}; null before the first frame.
window.shapeformKept = () => {
  if (!kept) return null;
  const trails = {};
  for (const [id, pts] of kept.trails) trails[id] = pts;
  return { seq: kept.seq, agents: scene_of(kept).agents, trails: trails, centre_path: kept.centre_path,
    chart_points: kept.chart_points, outline: kept.outline, keep_out: kept.keep_out, fence: kept.fence,
    min_separation: kept.min_separation };
};

// The kept state as the drawing functions read it.
function scene_of(k) {
  if (!k.sorted) k.sorted = [...k.agents.keys()].sort((a, b) => a - b);
  return { agents: k.sorted.map((id) => k.agents.get(id)), trails: k.trails, centre_path: k.centre_path,
    chart: { columns: k.chart_columns, points: k.chart_points }, outline: k.outline, keep_out: k.keep_out,
    fence: k.fence, min_separation: k.min_separation, centre: k.centre, now_s: k.now_s, model_time: k.model_time,
    epoch: k.epoch, converged: k.converged, metrics: k.metrics, safety: k.safety, mode: k.mode, replay: k.replay };
}

let draw_ms = 0;       // how long the latest draw took
function draw() {
  const started = performance.now();
  const f = scene_of(kept);
  last = f;
  frames += 1;
  const s = draw_scene(f);
  const chart_points = draw_chart("chart-error", f, "shape_error_mean") + draw_chart("chart-gap", f, "gap_cv") +
    draw_chart("chart-alive", f, "agents_alive");
  const d = f.min_separation || 0;
  const [separation_points, separation_run_points] = draw_series("chart-separation", f,
    [{ column: "min_separation", colour: "#1565c0" }, { column: "min_separation_run", colour: "#c62828" }],
    d > 0 ? d : null);
  const safety_shown = fill_safety(f);
  fill_table(f);
  fill_header(f);
  fill_replay(f);
  window.shapeformDrawn = {
    agents: s.drawn.map((a) => ({ id: a.id, x1: a.x1, x2: a.x2, state: a.state, model_time: a.model_time,
      heading: a.heading })),
    outline_points: s.outline_points,
    chart_points: chart_points,
    chart_model_time: f.chart.points.length ? f.chart.points[f.chart.points.length - 1][0] : null,
    model_time: f.model_time,
    epoch: f.epoch,
    frames: frames,
    received: received,
    bytes: bytes,
    resyncs: resyncs,
    mode: f.mode,
    replay: f.replay || null,
    zones: s.zones,
    separation_points: separation_points,
    separation_run_points: separation_run_points,
    separation_limit: d > 0 ? d : null,
    safety_shown: safety_shown,
    blocked_mark: s.blocked_mark,
    fence_points: f.fence ? f.fence.polygon.length : 0,
  };
  window._shapeformPx = s.drawn;
  // Every alive agent state drawn, [id, model_time, x1, x2], for a test that reads (and empties) it now
  // and then: what was drawn between its reads, not only what it caught (bounded: the newest LOG_MAX).
  const log = window.shapeformLog;
  for (const a of s.drawn) if (a.state === "alive") log.push([a.id, a.model_time, a.x1, a.x2]);
  if (log.length > LOG_MAX) log.splice(0, log.length - LOG_MAX);
  draw_ms = performance.now() - started;
  window.shapeformDrawn.draw_ms = draw_ms;
}

// Frames are drawn one per animation frame, in order: two that arrive within one display refresh are
// shown on consecutive refreshes, not merged, and a page held up for a moment (a busy host) catches up
// at the display's rate. A page more than MAX_QUEUED frames (0.4 s at 15 frames/s) behind applies the
// older ones without drawing them: it never falls further behind the stream.
const MAX_QUEUED = 6;
const queue = [];
let draw_pending = false;
function on_frame(text) {
  received += 1;
  bytes += text.length;
  arrivals.push(performance.now());
  queue.push(JSON.parse(text));
  schedule();
}

function schedule() {
  if (draw_pending || queue.length === 0) return;
  draw_pending = true;
  requestAnimationFrame(() => {
    draw_pending = false;
    while (queue.length > MAX_QUEUED) apply(queue.shift());
    if (queue.length > 0) apply(queue.shift());
    if (kept) draw();
    schedule();
  });
}

canvas.addEventListener("mousemove", (e) => {
  const px = window._shapeformPx || [];
  const r = canvas.getBoundingClientRect();
  const u = ((e.clientX - r.left) * canvas.width) / r.width, v = ((e.clientY - r.top) * canvas.height) / r.height;
  let best = null, bestd = 10;
  for (const a of px) {
    const d = Math.hypot(a.u - u, a.v - v);
    if (d < bestd) { best = a; bestd = d; }
  }
  if (!best) { tip.hidden = true; return; }
  tip.hidden = false;
  tip.textContent = `agent ${best.id} (${best.state}) x = (${fmt(best.x1, 3)}, ${fmt(best.x2, 3)})` +
    (best.heading === null ? "" : `, heading ${fmt((best.heading * 180) / Math.PI, 0)}°`);
  tip.style.left = (e.clientX - r.left + 12) + "px";
  tip.style.top = (e.clientY - r.top + 12) + "px";
});
canvas.addEventListener("mouseleave", () => { tip.hidden = true; });

let events = null;
function connect() {
  if (events) events.close();
  events = new EventSource("/events");
  events.onmessage = (e) => on_frame(e.data);
  events.onerror = () => { document.getElementById("mode").textContent = "disconnected (retrying)"; kept = null; queue.length = 0; };
}
connect();
