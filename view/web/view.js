// shapeform view: draws the frames that shapeform_view streams (Server-Sent Events on /events). Every
// coordinate comes from the server, the commanded shape too (sampled with the project's curve code):
// this page only draws. What it drew is exposed as window.shapeformDrawn for tests.
"use strict";

const COLOURS = { alive: "#1565c0", stale: "#ef6c00", dead: "#9e9e9e" };
const canvas = document.getElementById("canvas");
const ctx = canvas.getContext("2d");
const tip = document.getElementById("tip");
let view = null;        // {cx, cy, half}: the world square shown, eased from frame to frame
let last = null;        // the newest frame
let frames = 0;
const arrivals = [];    // arrival times of recent frames (ms), for the frame rate shown

window.shapeformDrawn = { agents: [], outline_points: 0, chart_points: 0, chart_model_time: null, model_time: null,
  frames: 0, mode: null, replay: null };

function fmt(v, digits) {
  return v === null || v === undefined ? "–" : Number(v).toFixed(digits);
}

// The world square to show: alive agents, a closed outline, the centre and its path.
function target_view(f) {
  const xs = [], ys = [];
  const add = (x, y) => { xs.push(x); ys.push(y); };
  for (const a of f.agents) if (a.state !== "dead") add(a.x1, a.x2);
  if (f.outline && f.outline.closed) for (const p of f.outline.points) add(p[0], p[1]);
  if (f.centre) add(f.centre[0], f.centre[1]);
  for (const p of f.centre_path) add(p[0], p[1]);
  if (xs.length === 0) return { cx: 0, cy: 0, half: 10 };
  const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
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
  let outline_points = 0;
  if (f.outline) {
    ctx.strokeStyle = "#2e7d32"; ctx.lineWidth = 2; ctx.setLineDash([8, 6]);
    polyline(f.outline.points, f.outline.closed);
    ctx.setLineDash([]);
    outline_points = f.outline.points.length;
  }
  ctx.lineWidth = 1;
  for (const t of f.trails) {
    if (t.points.length < 2) continue;
    ctx.strokeStyle = "rgba(21, 101, 192, 0.25)";
    polyline(t.points, false);
  }
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
  for (const a of f.agents) {
    const [u, v] = to_px(a.x1, a.x2);
    ctx.lineWidth = 2;
    ctx.strokeStyle = COLOURS[a.state]; ctx.fillStyle = COLOURS[a.state];
    ctx.beginPath(); ctx.arc(u, v, 6, 0, 2 * Math.PI);
    if (a.state === "stale") ctx.stroke(); else ctx.fill();
    if (a.state === "dead") {
      ctx.strokeStyle = "#fff";
      ctx.beginPath(); ctx.moveTo(u - 3, v - 3); ctx.lineTo(u + 3, v + 3); ctx.moveTo(u + 3, v - 3); ctx.lineTo(u - 3, v + 3); ctx.stroke();
    }
    const heading = a.heading === undefined ? null : a.heading;
    if (heading !== null) {
      // The vehicle's heading: a tick from the agent's edge outward (screen y points down).
      const c = Math.cos(heading), s = -Math.sin(heading);
      ctx.strokeStyle = COLOURS[a.state];
      ctx.beginPath(); ctx.moveTo(u + 6 * c, v + 6 * s); ctx.lineTo(u + 16 * c, v + 16 * s); ctx.stroke();
    }
    drawn.push({ id: a.id, x1: a.x1, x2: a.x2, state: a.state, model_time: a.model_time, heading: heading, u: u, v: v });
  }
  return { drawn: drawn, outline_points: outline_points };
}

function draw_chart(id, f, column) {
  const c = document.getElementById(id), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const k = f.chart.columns.indexOf(column);
  const pts = f.chart.points.filter((p) => Number.isFinite(p[0]) && Number.isFinite(p[k]));
  if (pts.length === 0) return 0;
  const t0 = pts[0][0], t1 = Math.max(pts[pts.length - 1][0], t0 + 1e-9);
  let lo = 0, hi = 0;
  for (const p of pts) { lo = Math.min(lo, p[k]); hi = Math.max(hi, p[k]); }
  if (hi <= lo) hi = lo + 1;
  const L = 40, R = 8, T = 8, B = 18, w = c.width - L - R, h = c.height - T - B;
  g.strokeStyle = "#b0bec5"; g.lineWidth = 1;
  g.strokeRect(L, T, w, h);
  g.fillStyle = "#555"; g.font = "10px sans-serif";
  g.fillText(hi.toPrecision(3), 2, T + 8); g.fillText(lo.toPrecision(3), 2, T + h);
  g.fillText(t0.toFixed(0), L, c.height - 4); g.fillText(t1.toFixed(0), L + w - 24, c.height - 4);
  g.strokeStyle = "#1565c0"; g.lineWidth = 1.5;
  g.beginPath();
  pts.forEach((p, i) => {
    const u = L + (w * (p[0] - t0)) / (t1 - t0), v = T + h - (h * (p[k] - lo)) / (hi - lo);
    if (i === 0) g.moveTo(u, v); else g.lineTo(u, v);
  });
  g.stroke();
  return pts.length;
}

function fill_table(f) {
  const body = document.querySelector("#agents tbody");
  const rows = f.agents.map((a) =>
    `<tr class="${a.state}"><td>${a.id}</td><td>${a.state}</td><td>${fmt(a.x1, 3)}</td><td>${fmt(a.x2, 3)}</td>` +
    `<td>${a.heading === null || a.heading === undefined ? "–" : fmt((a.heading * 180) / Math.PI, 0)}</td>` +
    `<td>${a.heard === null ? "–" : a.heard}</td><td>${a.epoch}</td><td>${fmt(a.lateness_us, 0)}</td></tr>`);
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
  arrivals.push(now);
  while (arrivals.length > 0 && arrivals[0] < now - 2000) arrivals.shift();
  document.getElementById("fps").textContent = (arrivals.length / 2).toFixed(0) + " frames/s";
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

function on_frame(f) {
  last = f;
  frames += 1;
  const s = draw_scene(f);
  const chart_points = draw_chart("chart-error", f, "shape_error_mean") + draw_chart("chart-gap", f, "gap_cv") +
    draw_chart("chart-alive", f, "agents_alive");
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
    mode: f.mode,
    replay: f.replay || null,
  };
  window._shapeformPx = s.drawn;
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

const events = new EventSource("/events");
events.onmessage = (e) => on_frame(JSON.parse(e.data));
events.onerror = () => { document.getElementById("mode").textContent = "disconnected (retrying)"; };
