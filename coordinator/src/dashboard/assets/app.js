// The Amorph dashboard: polls /api/status (docs/reference/dashboard.md) and draws it. No library,
// no network beyond this coordinator: a cluster may be offline.
"use strict";

const POLL_MS = 2000;
const ISLAND_COLOURS = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"];
const SVG = "http://www.w3.org/2000/svg";
const token = new URLSearchParams(location.search).get("token");
let xAxis = "evaluations";
let last = null;
let pictureTask = null;

const $ = (id) => document.getElementById(id);

function fmt(v, digits = 4) {
  if (v === null || v === undefined || !Number.isFinite(v)) return "–";
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e6)) return v.toExponential(2);
  return Number(v.toPrecision(digits)).toString();
}

function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return "–";
  s = Math.round(s);
  const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = s % 60;
  return h > 0 ? `${h} h ${m} min` : m > 0 ? `${m} min ${sec} s` : `${sec} s`;
}

function withToken(url) {
  return token ? url + (url.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token) : url;
}

function el(tag, attrs = {}, text) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// Ticks for a linear axis: about `n` round values across [lo, hi].
function linearTicks(lo, hi, n) {
  const step0 = (hi - lo) / n, mag = Math.pow(10, Math.floor(Math.log10(step0)));
  const step = [1, 2, 5, 10].map((k) => k * mag).find((s) => s >= step0) || mag;
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) ticks.push(t);
  return ticks;
}

// Draws `series` ([{label, colour, points: [[x, y]]}]) into `svg`; `refs` are horizontal dashed
// lines ({y, label, colour}). Sets data-points to the number of points drawn.
function plot(svg, series, { logY = false, xLabel = "", yLabel = "", refs = [], equal = false } = {}) {
  svg.replaceChildren();
  const vb = svg.viewBox.baseVal, W = vb.width, H = vb.height;
  const m = { l: 62, r: 12, t: 12, b: 40 };
  const ok = (p) => Number.isFinite(p[0]) && Number.isFinite(p[1]) && (!logY || p[1] > 0);
  const drawn = series.map((s) => ({ ...s, points: s.points.filter(ok) }));
  const all = drawn.flatMap((s) => s.points);
  svg.dataset.points = String(all.length);
  if (all.length === 0) {
    svg.append(el("text", { x: W / 2, y: H / 2, "text-anchor": "middle" }, "no data yet"));
    return;
  }
  const ty = (y) => (logY ? Math.log10(y) : y);
  const ys = all.map((p) => ty(p[1])).concat(refs.filter((r) => !logY || r.y > 0).map((r) => ty(r.y)));
  let [x0, x1] = [Math.min(...all.map((p) => p[0])), Math.max(...all.map((p) => p[0]))];
  let [y0, y1] = [Math.min(...ys), Math.max(...ys)];
  if (x1 === x0) { x0 -= 1; x1 += 1; }
  if (y1 === y0) { y0 -= logY ? 0.5 : Math.abs(y0) * 0.1 + 1e-9; y1 += logY ? 0.5 : Math.abs(y1) * 0.1 + 1e-9; }
  const pad = (y1 - y0) * 0.05; y0 -= pad; y1 += pad;
  if (equal) {
    // Same scale on both axes (a robot's track seen from above).
    const sx = (W - m.l - m.r) / (x1 - x0), sy = (H - m.t - m.b) / (y1 - y0);
    if (sx < sy) { const c = (y0 + y1) / 2, h = (H - m.t - m.b) / sx / 2; y0 = c - h; y1 = c + h; }
    else { const c = (x0 + x1) / 2, h = (W - m.l - m.r) / sy / 2; x0 = c - h; x1 = c + h; }
  }
  const X = (x) => m.l + ((x - x0) / (x1 - x0)) * (W - m.l - m.r);
  const Y = (y) => H - m.b - ((ty(y) - y0) / (y1 - y0)) * (H - m.t - m.b);
  const Yt = (t) => H - m.b - ((t - y0) / (y1 - y0)) * (H - m.t - m.b);
  for (const t of linearTicks(x0, x1, 6)) {
    svg.append(el("line", { class: "grid", x1: X(t), x2: X(t), y1: m.t, y2: H - m.b }));
    svg.append(el("text", { x: X(t), y: H - m.b + 14, "text-anchor": "middle" }, fmt(t, 3)));
  }
  const yTicks = logY
    ? linearTicks(Math.floor(y0), Math.ceil(y1), Math.max(1, Math.min(6, Math.ceil(y1) - Math.floor(y0)))).filter((t) => t >= y0 && t <= y1 && Number.isInteger(t))
    : linearTicks(y0, y1, 5);
  for (const t of yTicks) {
    svg.append(el("line", { class: "grid", x1: m.l, x2: W - m.r, y1: Yt(t), y2: Yt(t) }));
    svg.append(el("text", { x: m.l - 6, y: Yt(t) + 4, "text-anchor": "end" }, fmt(logY ? Math.pow(10, t) : t, 3)));
  }
  svg.append(el("line", { class: "axis", x1: m.l, x2: W - m.r, y1: H - m.b, y2: H - m.b }));
  svg.append(el("line", { class: "axis", x1: m.l, x2: m.l, y1: m.t, y2: H - m.b }));
  svg.append(el("text", { x: (m.l + W - m.r) / 2, y: H - 6, "text-anchor": "middle" }, xLabel));
  svg.append(el("text", { x: 12, y: (m.t + H - m.b) / 2, "text-anchor": "middle", transform: `rotate(-90 12 ${(m.t + H - m.b) / 2})` }, yLabel));
  for (const r of refs) {
    if (logY && !(r.y > 0)) continue;
    svg.append(el("line", { class: "ref", stroke: r.colour, x1: m.l, x2: W - m.r, y1: Y(r.y), y2: Y(r.y) }));
    svg.append(el("text", { x: W - m.r - 4, y: Y(r.y) - 4, "text-anchor": "end" }, r.label));
  }
  let legendY = m.t + 12;
  for (const s of drawn) {
    if (s.points.length === 0) continue;
    const line = el("polyline", { stroke: s.colour, points: s.points.map((p) => `${X(p[0]).toFixed(1)},${Y(p[1]).toFixed(1)}`).join(" ") });
    line.dataset.series = s.label;
    svg.append(line);
    if (s.points.length === 1) svg.append(el("circle", { cx: X(s.points[0][0]), cy: Y(s.points[0][1]), r: 3, fill: s.colour }));
    if (s.label) {
      svg.append(el("text", { x: W - m.r - 4, y: legendY, "text-anchor": "end", fill: s.colour }, s.label));
      legendY += 14;
    }
  }
}

function historyPlot(status) {
  const byIsland = new Map();
  for (const h of status.history) {
    if (!byIsland.has(h.island)) byIsland.set(h.island, []);
    byIsland.get(h.island).push([xAxis === "evaluations" ? h.evaluations : h.wall_seconds, h.best_figure]);
  }
  const series = [...byIsland.entries()].map(([island, points]) => ({
    label: byIsland.size > 1 ? `island ${island}` : "best",
    colour: ISLAND_COLOURS[island % ISLAND_COLOURS.length],
    points,
  }));
  const refs = [];
  if (status.run.paper_figure !== null) refs.push({ y: status.run.paper_figure, label: `paper ${fmt(status.run.paper_figure)}`, colour: "#6b7280" });
  if (status.run.target_figure !== null && status.run.target_figure !== status.run.paper_figure) refs.push({ y: status.run.target_figure, label: `target ${fmt(status.run.target_figure)}`, colour: "#2563eb" });
  plot($("history-plot"), series, {
    logY: status.run.figure_log,
    xLabel: xAxis === "evaluations" ? "evaluations" : "wall time (s)",
    yLabel: status.run.figure_axis.toLowerCase(),
    refs,
  });
}

function metricsOf(best) {
  const e = best && best.outcome && best.outcome.evaluated;
  return e ? Object.values(e.metrics)[0] : null;
}

function detailPlot(status) {
  const svg = $("detail-plot"), m = metricsOf(status.best);
  if (m && Array.isArray(m.profile)) {
    plot(svg, [
      { label: "target", colour: "#6b7280", points: m.profile.map((p) => [p[0], p[2]]) },
      { label: "simulated", colour: "#d62728", points: m.profile.map((p) => [p[0], p[1]]) },
    ], { xLabel: "position along the beam (clamp 0, tip 1)", yLabel: "deflection / tip" });
    $("detail-caption").textContent = "The top surface of the best beam against its target.";
  } else if (m && Array.isArray(m.centre_of_mass_trace)) {
    const mm = m.centre_of_mass_trace.map((p) => [1e3 * p[0], 1e3 * p[1]]);
    plot(svg, [{ label: "", colour: "#d62728", points: mm }], { xLabel: "x (mm)", yLabel: "y (mm)", equal: true });
    $("detail-caption").textContent = "The best robot's centre of mass after settling and after each cycle, seen from above.";
  } else {
    svg.replaceChildren();
    $("detail-caption").textContent = "";
  }
}

function bestCard(status) {
  const b = status.best;
  if (!b) return;
  $("best-headline").textContent = b.headline || "failed";
  const s = b.summary || {};
  const paper = [];
  if (s.speed_percent_body_length_per_cycle !== undefined && s.speed_percent_body_length_per_cycle !== null)
    paper.push(`speed ${fmt(s.speed_percent_body_length_per_cycle, 3)} % of body length per cycle (paper ${s.paper_speed_percent_body_length_per_cycle} %)`);
  if (s.voxels !== undefined && s.voxels !== null) paper.push(`${s.voxels} voxels`);
  $("best-paper").textContent = paper.join(" · ");
  $("best-where").textContent = `evaluation ${b.task_id} · island ${b.island} · epoch ${b.evaluated_in_epoch} · ${b.resolution}`;
  if (pictureTask !== b.task_id) {
    pictureTask = b.task_id;
    $("best-picture").src = withToken(`api/design.png?task=${b.task_id}`);
  }
}

function row(cells, numeric = []) {
  const tr = document.createElement("tr");
  cells.forEach((c, i) => {
    const td = document.createElement("td");
    td.textContent = c;
    if (numeric.includes(i)) td.className = "num";
    tr.append(td);
  });
  return tr;
}

function tables(status) {
  $("islands").tBodies[0].replaceChildren(...status.islands.map((i) =>
    row([i.island, i.population, fmt(i.best_figure), i.emigrants, i.immigrants], [1, 2, 3, 4])));
  $("migrations").replaceChildren(...status.migrations.slice(0, 8).map((m) => {
    const li = document.createElement("li");
    li.textContent = `epoch ${m.epoch}: island ${m.from_island} → ${m.to_island} (evaluation ${m.task_id})`;
    return li;
  }));
  if (status.migrations.length === 0) $("migrations").replaceChildren(Object.assign(document.createElement("li"), { textContent: "none yet" }));
  $("workers").tBodies[0].replaceChildren(...status.workers.map((w) => {
    const m = /^(.*?)(?: @(\S+))? \(([^()]*)\)$/.exec(w.label);
    const name = m ? `${m[1]} (${m[3]})` : w.label, address = m && m[2] ? m[2] : "–";
    const r = w.registered;
    const state = w.quarantined ? "quarantined" : r ? (r.trusted ? "trusted" : "checked") : status.live ? "gone" : "";
    const tr = row([name, address, r ? r.threads : "–", w.evaluations, fmt(w.evaluations_per_second, 3), r ? r.leases : "–", w.checks, state], [2, 3, 4, 5, 6]);
    if (w.quarantined) tr.lastChild.className = "bad";
    return tr;
  }));
  const q = status.queue, v = status.verification;
  const lines = [];
  if (q) lines.push(["workers registered", q.workers], ["tasks queued", q.queued], ["tasks leased", q.leased], ["expired leases", q.expired_leases], ["worker errors", q.worker_errors]);
  else lines.push(["queue", "not running (read from the store)"]);
  lines.push(["claims checked", v.checks], ["disagreements", v.disagreements], ["workers quarantined", v.quarantined_workers], ["claims awaiting a check", v.unchecked_claims]);
  $("queue").tBodies[0].replaceChildren(...lines.map(([k, val]) => row([k, val], [1])));
}

function header(status) {
  const r = status.run, p = status.progress;
  document.title = `${r.name} · Amorph`;
  $("run-name").textContent = r.name;
  $("run-task").textContent = r.task;
  $("run-mode").textContent = status.live ? "live" : "from the store";
  $("run-mode").className = status.live ? "tag live" : "tag";
  const budget = r.budget_evaluations;
  $("progress-bar").style.width = budget ? `${Math.min(100, (100 * p.evaluations) / budget)}%` : "0";
  const parts = [`${p.evaluations}${budget ? " / " + budget : ""} evaluations`, `epoch ${p.epochs}`];
  if (p.resolution) parts.push(p.resolution);
  parts.push(`${duration(p.wall_seconds)} of wall time`);
  if (p.evaluations_per_second) parts.push(`${fmt(p.evaluations_per_second, 3)} evaluations/s`);
  if (status.live && p.seconds_left !== null) parts.push(`about ${duration(p.seconds_left)} to the budget`);
  $("progress-text").textContent = parts.join(" · ");
  $("progress-text").dataset.evaluations = String(p.evaluations);
}

// The plots are redrawn only when what they show changed (a new epoch, a new best), so a page
// left open costs the machine it runs on little between epochs.
let drawnHistory = -1, drawnBest = null;

function draw(status) {
  header(status);
  bestCard(status);
  if (status.history.length !== drawnHistory) {
    drawnHistory = status.history.length;
    historyPlot(status);
  }
  const best = status.best ? status.best.task_id : null;
  if (best !== drawnBest) {
    drawnBest = best;
    detailPlot(status);
  }
  tables(status);
  $("updated").textContent = "updated " + new Date().toLocaleTimeString();
}

async function poll() {
  try {
    const response = await fetch("api/status", { headers: token ? { Authorization: "Bearer " + token } : {}, cache: "no-store" });
    if (!response.ok) throw new Error(`${response.status}: ${(await response.text()).trim()}`);
    last = await response.json();
    $("error").hidden = true;
    draw(last);
  } catch (e) {
    $("error").hidden = false;
    $("error").textContent = `cannot read the run's status (${e.message}); retrying`;
  }
  setTimeout(poll, POLL_MS);
}

for (const [id, axis] of [["x-evaluations", "evaluations"], ["x-wall", "wall"]]) {
  $(id).addEventListener("click", () => {
    xAxis = axis;
    $("x-evaluations").classList.toggle("on", axis === "evaluations");
    $("x-wall").classList.toggle("on", axis === "wall");
    if (last) historyPlot(last);
  });
}
poll();
