// The pathfuse playground: wires the map, the planners, the layers and the episodes together.

import { ApiError, float32s, getJSON, packBits, postFiles, postJSON, unpackBits } from "./api.js";
import { Player, Scene } from "./episode.js";
import { el, PALETTE, plannerForm } from "./forms.js";
import { makeImage, ramp, View } from "./view.js";

const $ = (id) => document.getElementById(id);
const AUTO_CELLS = 256 * 256;  // re-plan on every edit up to this many cells

const state = {
  map: null,            // {id, name, width, height, resolution, origin, occ, spec, dirty}
  start: null, goal: null,
  forms: [],            // one generated form per registered planner
  results: new Map(),   // planner -> plan answer (or {error})
  field: null,
  planSeq: 0, fieldSeq: 0,
};
const view = new View($("canvas"));
const scene = new Scene(() => { scene.renderList($("discs")); view.redraw(); });
const player = new Player(view, { play: $("play"), time: $("time"), speed: $("play-speed") },
  (k) => {
    const ep = player.ep;
    $("time-label").textContent = ep ? `${(k * ep.dt).toFixed(1)} / ${(ep.n_ticks * ep.dt).toFixed(1)} s` : "";
  });
window.pathfuse = { state, view, scene, player };  // for the browser tests and the curious

function setStatus(text) { $("status").textContent = text; }
function colorOf(name) {
  const i = state.forms.findIndex((f) => f.name === name);
  return PALETTE[(i < 0 ? 0 : i) % PALETTE.length];
}

// ---------------------------------------------------------------- maps
function mapRef() {
  const m = state.map;
  if (m.id && !m.dirty) return { id: m.id };
  return { grid: { width: m.width, height: m.height, resolution: m.resolution, origin: m.origin,
                   name: m.name, bits: packBits(m.occ) } };
}

function cellCentre(m, r, c) {
  return [m.origin[0] + (c + 0.5) * m.resolution, m.origin[1] + (r + 0.5) * m.resolution];
}

function firstFree(m, fromTop) {
  const W = m.width, H = m.height;
  for (let k = 0; k < W + H; k++) {
    for (let i = 0; i <= k; i++) {
      let r = i, c = k - i;
      if (fromTop) { r = H - 1 - r; c = W - 1 - c; }
      if (r >= 0 && r < H && c >= 0 && c < W && !m.occ[r * W + c]) return cellCentre(m, r, c);
    }
  }
  return cellCentre(m, 0, 0);
}

function inside(m, p) {
  return p && p[0] > m.origin[0] && p[1] > m.origin[1] &&
    p[0] < m.origin[0] + m.width * m.resolution && p[1] < m.origin[1] + m.height * m.resolution;
}

function setMap(d, keepPoints = false) {
  const m = { id: d.id, name: d.name, width: d.width, height: d.height, resolution: d.resolution,
              origin: d.origin, spec: d.spec || null, dirty: false,
              occ: unpackBits(d.bits, d.width * d.height) };
  state.map = m;
  if (!keepPoints || !inside(m, state.start) || !inside(m, state.goal)) {
    const paper = d.spec && d.spec.paper;
    state.start = paper ? [1, 1] : firstFree(m, false);
    state.goal = paper ? [11, 11] : firstFree(m, true);
  }
  state.results.clear();
  state.field = null;
  player.unload();
  view.setMap(m);
  view.fit();
  ["closed", "cspace", "heat"].forEach((k) => view.setOverlay(k, null));
  $("map-info").textContent = `${m.name}: ${m.width} × ${m.height} cells of ${m.resolution} m`;
  $("map-error").textContent = "";
  renderTable();
  edited();
}

async function loadSelectedMap() {
  const id = $("map-select").value;
  try {
    setStatus("loading map…");
    const d = id === "paper"
      ? await postJSON("/api/map", { map: "paper", seed: Number($("map-seed").value) || 0 })
      : await getJSON(`/api/maps/${id.split("/").map(encodeURIComponent).join("/")}`);
    setMap(d);
    setStatus("");
  } catch (e) { $("map-error").textContent = e.message; setStatus(""); }
}

async function blankMap() {
  try {
    const d = await postJSON("/api/map", { map: { blank: {
      size: [Number($("blank-w").value), Number($("blank-h").value)],
      resolution: Number($("blank-res").value) } } });
    setMap(d);
  } catch (e) { $("map-error").textContent = e.message; }
}

async function uploadMap() {
  const files = [...$("map-file").files];
  if (!files.length) return;
  setStatus("uploading…");
  try {
    const d = await postFiles("/api/maps", files, { resolution: $("upload-res").value });
    setMap(d);
    setStatus(`uploaded ${d.name}`);
  } catch (e) {
    $("map-error").textContent = e.message;
    setStatus("upload failed");
  }
  $("map-file").value = "";
}

// ---------------------------------------------------------------- planning
function selected() { return state.forms.filter((f) => f.check.checked); }

function edited() {
  const m = state.map;
  if (!m) return;
  if ($("auto-plan").checked && m.width * m.height <= AUTO_CELLS) schedulePlan();
  else setStatus(`${m.width} × ${m.height} cells: press Plan to plan (re-planning on every edit is for maps up to 256 × 256)`);
  if ($("layer-heat").checked || $("layer-arrows").checked) scheduleField();
  view.redraw();
}

let planTimer = null;
function schedulePlan() {
  clearTimeout(planTimer);
  planTimer = setTimeout(planAll, 60);
}

function layersWanted() {
  const out = [];
  if ($("layer-closed").checked) out.push("closed");
  if ($("layer-cspace").checked) out.push("cspace");
  if ($("layer-attract").checked) out.push("attractors");
  return out;
}

async function planAll() {
  const m = state.map;
  if (!m) return;
  const seq = ++state.planSeq;
  const forms = selected();
  const ref = mapRef();
  const radius = Number($("robot-radius").value) || 0;
  const layers = layersWanted();
  setStatus(`planning with ${forms.map((f) => f.name).join(", ") || "no planner"}…`);
  const jobs = forms.map(async (f) => {
    let params;
    try { params = f.params(); } catch (e) { return [f.name, { error: e.message }]; }
    try {
      const d = await postJSON("/api/plan", { map: ref, start: state.start, goal: state.goal,
        planner: f.name, params, robot_radius: radius, extras: true,
        layers: layers.filter((l) => l === "cspace" || f.planner.layers.includes(l)) });
      f.markBad("");
      return [f.name, d];
    } catch (e) {
      f.markBad(e.message);
      return [f.name, { error: e.message }];
    }
  });
  const done = await Promise.all(jobs);
  if (seq !== state.planSeq) return;  // a newer edit started another round
  state.results = new Map(done);
  setStatus(done.length ? `planned ${m.width} × ${m.height} cells` : "choose a planner");
  updateLayers();
  renderTable();
  view.redraw();
  document.body.dataset.planned = String(seq);
}

function fmt(v, digits) { return v == null ? "–" : Number(v).toFixed(digits); }

function renderTable() {
  const tb = $("results").querySelector("tbody");
  tb.replaceChildren();
  for (const [name, r] of state.results) {
    const sw = el("span", { className: "swatch", style: `background:${colorOf(name)}` });
    const tr = el("tr");
    tr.dataset.planner = name;
    if (r.error) {
      tr.append(el("td", {}, sw), el("td", { text: name }),
        el("td", { className: "fail status", colSpan: 6, text: r.error }));
    } else {
      const ok = r.status === "SUCCESS";
      const ex = r.extras || {};
      tr.append(el("td", {}, sw), el("td", { text: name }),
        el("td", { className: (ok ? "" : "fail ") + "status", text: r.status, title: r.message }),
        el("td", { className: "length", text: ok ? fmt(r.length, 3) : "–" }),
        el("td", { text: fmt(r.time_s * 1e3, 3) }), el("td", { text: String(r.expansions) }),
        el("td", { text: String(r.iterations) }),
        el("td", { text: fmt(ex.min_clearance_m, 3) }));
    }
    tb.append(tr);
  }
}

// ---------------------------------------------------------------- layers
function maskOverlay(bits, rgba, alpha) {
  const m = state.map;
  const mask = unpackBits(bits, m.width * m.height);
  const W = m.width, H = m.height;
  return { canvas: makeImage(W, H, (i, j) => (mask[(H - 1 - i) * W + j] ? rgba : null)),
           x0: m.origin[0], y0: m.origin[1], w: W * m.resolution, h: H * m.resolution, alpha };
}

function hexRgb(hex) {
  const n = parseInt(hex.slice(1), 16);
  return [(n >> 16) & 255, (n >> 8) & 255, n & 255];
}

function updateLayers() {
  const m = state.map;
  let closed = null, cspace = null, attract = null;
  for (const [name, r] of state.results) {
    const ex = r.extras || {};
    if (!closed && ex.closed && $("layer-closed").checked) closed = [name, ex.closed];
    if (!cspace && ex.cspace && $("layer-cspace").checked) cspace = ex.cspace;
    if (!attract && ex.attractors && $("layer-attract").checked) attract = [name, r];
  }
  view.setOverlay("closed", closed ? maskOverlay(closed[1].bits, [...hexRgb(colorOf(closed[0])), 255], 0.28) : null);
  if (cspace) {
    const mask = unpackBits(cspace.bits, m.width * m.height);
    const W = m.width, H = m.height;
    view.setOverlay("cspace", { canvas: makeImage(W, H, (i, j) => {
      const k = (H - 1 - i) * W + j;
      return mask[k] && !m.occ[k] ? [249, 115, 22, 255] : null;
    }), x0: m.origin[0], y0: m.origin[1], w: W * m.resolution, h: H * m.resolution, alpha: 0.45 });
  } else view.setOverlay("cspace", null);
  state.attract = attract;
  const slider = $("attract-step");
  if (attract) {
    const n = attract[1].extras.attractors.per_point.length;
    const keep = Number(slider.value);
    slider.max = Math.max(0, n - 1);
    if (keep >= n || keep === 0) slider.value = Math.floor(n / 3);
  }
  showAttractInfo();
}

function showAttractInfo() {
  const a = state.attract;
  if (!a) { $("attract-info").textContent = ""; return; }
  const i = Number($("attract-step").value);
  const pts = a[1].extras.attractors.per_point[i] || [];
  $("attract-info").textContent = `${a[0]} step ${i}: ${pts.length} A* point${pts.length === 1 ? "" : "s"} attract (r1 = ${a[1].extras.attractors.r1_m} m)`;
  view.redraw();
}

let fieldTimer = null;
function scheduleField() {
  clearTimeout(fieldTimer);
  fieldTimer = setTimeout(loadField, 120);
}

function fieldPlanner() {
  const withGains = (f) => f.planner.params.some((p) => p.name === "k_att");
  return selected().find(withGains) || state.forms.find(withGains);
}

async function loadField() {
  if (!state.map || !($("layer-heat").checked || $("layer-arrows").checked)) {
    view.setOverlay("heat", null);
    state.field = null;
    view.redraw();
    return;
  }
  const seq = ++state.fieldSeq;
  const f = fieldPlanner();
  let params = {};
  try { params = f ? f.params() : {}; } catch (e) { params = {}; }
  try {
    const d = await postJSON("/api/field", { map: mapRef(), goal: state.goal,
      planner: f ? f.name : undefined, params });
    if (seq !== state.fieldSeq) return;
    state.field = d;
    $("field-info").textContent = `APF of ${d.planner}: K_att ${d.params.k_att}, K_rep ${d.params.k_rep}, ρ0 ${d.params.rho0_m} m; colour = log(1 + U)`;
    drawHeat();
    document.body.dataset.field = String(seq);
  } catch (e) { $("field-info").textContent = e.message; }
}

function drawHeat() {
  const d = state.field;
  if (!d || !$("layer-heat").checked) { view.setOverlay("heat", null); return; }
  const [ny, nx] = d.heat.shape;
  const att = float32s(d.heat.attractive), rep = float32s(d.heat.repulsive);
  const kind = $("heat-kind").value;
  const val = (k) => (kind === "attractive" ? att[k] : kind === "repulsive" ? rep[k] : att[k] + rep[k]);
  let hi = 0;
  for (let k = 0; k < nx * ny; k++) { const v = val(k); if (v > hi) hi = v; }
  const lhi = Math.log1p(hi) || 1;
  const canvas = makeImage(nx, ny, (i, j) => {
    const v = val((ny - 1 - i) * nx + j);
    if (!Number.isFinite(v)) return null;
    const c = ramp(Math.log1p(v) / lhi);
    return [c[0], c[1], c[2], 255];
  });
  const m = state.map, xs = d.heat.xs, ys = d.heat.ys;
  // each sample stands for the block of cells around it
  const half = (a, i) => (a.length > 1 ? (a[Math.min(i + 1, a.length - 1)] - a[Math.max(i - 1, 0)]) / (Math.min(i + 1, a.length - 1) - Math.max(i - 1, 0)) / 2 : m.resolution / 2);
  const x0 = xs[0] - half(xs, 0), x1 = xs[xs.length - 1] + half(xs, xs.length - 1);
  const y0 = ys[0] - half(ys, 0), y1 = ys[ys.length - 1] + half(ys, ys.length - 1);
  view.setOverlay("heat", { canvas, x0, y0, w: x1 - x0, h: y1 - y0, alpha: 0.6 });
}

function drawArrows(ctx, v) {
  const d = state.field;
  if (!d || !$("layer-arrows").checked) return;
  const { xs, ys, fx, fy } = d.arrows;
  const sp = Math.min(xs.length > 1 ? xs[1] - xs[0] : state.map.resolution,
                      ys.length > 1 ? ys[1] - ys[0] : state.map.resolution) * 0.8;
  let hi = 0;
  for (let i = 0; i < ys.length; i++) for (let j = 0; j < xs.length; j++) {
    const a = fx[i][j], b = fy[i][j];
    if (a != null) hi = Math.max(hi, Math.log1p(Math.hypot(a, b)));
  }
  for (let i = 0; i < ys.length; i++) for (let j = 0; j < xs.length; j++) {
    const a = fx[i][j], b = fy[i][j];
    if (a == null) continue;
    const n = Math.hypot(a, b);
    if (!(n > 0)) continue;
    const len = sp * (0.35 + 0.65 * Math.log1p(n) / (hi || 1));
    v.arrow(ctx, xs[j] - (a / n) * len / 2, ys[i] - (b / n) * len / 2, (a / n) * len, (b / n) * len,
            "rgba(15,23,42,.75)", 1.2);
  }
}

// ---------------------------------------------------------------- drawing
view.drawers.push(drawArrows);
view.drawers.push((ctx, v) => {
  for (const [name, r] of state.results) {
    if (r.error || (state.only && state.only !== name)) continue;  // only: one path alone
    const c = colorOf(name);
    if (r.extras && r.extras.astar_path && r.planner !== "astar") {
      v.polyline(ctx, r.extras.astar_path, c + "66", 1, [3, 3]);
    }
    v.polyline(ctx, r.path, c, 2.5);
  }
});
view.drawers.push((ctx, v) => {
  const a = state.attract;
  if (!a || !$("layer-attract").checked) return;
  const r = a[1], at = r.extras.attractors, i = Number($("attract-step").value);
  const p = r.path[Math.min(i, r.path.length - 1)];
  if (!p) return;
  v.disc(ctx, p[0], p[1], at.r1_m, "rgba(147,51,234,.08)", "rgba(147,51,234,.9)", 1.5);
  for (const j of at.per_point[i] || []) {
    const q = at.waypoints[j];
    ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0], q[1]);
    ctx.strokeStyle = "rgba(147,51,234,.8)"; ctx.lineWidth = v.px(1); ctx.stroke();
    v.disc(ctx, q[0], q[1], v.px(4), "#9333ea", null);
  }
  v.disc(ctx, p[0], p[1], v.px(4), "#fff", "#9333ea", 2);
});
view.drawers.push((ctx, v) => {
  if (player.ep) return;  // the episode draws the discs where they are
  for (const s of scene.starts()) {
    v.disc(ctx, s.p[0], s.p[1], s.r, "rgba(217,119,6,.35)", "#b45309", 1.5);
    if (s.v) v.arrow(ctx, s.p[0], s.p[1], s.v[0], s.v[1], "#b45309", 2);
    if (s.way) v.polyline(ctx, s.way, "rgba(180,83,9,.6)", 1, [4, 3]);
  }
  if (drag && drag.kind === "disc") v.arrow(ctx, drag.p[0], drag.p[1], drag.q[0] - drag.p[0], drag.q[1] - drag.p[1], "#b45309", 2);
});
view.drawers.push((ctx, v) => player.draw(ctx, v));
view.drawers.push((ctx, v) => {
  if (!state.start) return;
  const rr = Number($("robot-radius").value) || 0;
  for (const [p, fill] of [[state.start, "#16a34a"], [state.goal, "#dc2626"]]) {
    if (rr > 0) v.disc(ctx, p[0], p[1], rr, null, fill, 1);
    v.disc(ctx, p[0], p[1], v.px(7), fill, "#fff", 2);
  }
});

// ---------------------------------------------------------------- mouse
let drag = null;
const canvas = $("canvas");
const tool = () => document.querySelector("input[name=tool]:checked").value;

function eventWorld(e) {
  const r = canvas.getBoundingClientRect();
  return view.toWorld(e.clientX - r.left, e.clientY - r.top);
}

function near(p, w) {
  return p && Math.hypot(p[0] - w[0], p[1] - w[1]) * view.scale < 12;
}

function paintAt(w) {
  const m = state.map;
  const [r, c] = view.cellAt(w[0], w[1]);
  const b = Math.max(1, Number($("brush").value) || 1), h = Math.floor((b - 1) / 2);
  const val = tool() === "paint" ? 1 : 0;
  const r0 = Math.max(0, r - h), r1 = Math.min(m.height, r - h + b);
  const c0 = Math.max(0, c - h), c1 = Math.min(m.width, c - h + b);
  if (r0 >= r1 || c0 >= c1) return;
  for (let i = r0; i < r1; i++) for (let j = c0; j < c1; j++) m.occ[i * m.width + j] = val;
  m.dirty = true;
  view.paintRect(c0, r0, c1, r1);
}

canvas.addEventListener("contextmenu", (e) => e.preventDefault());
canvas.addEventListener("pointerdown", (e) => {
  if (!state.map) return;
  canvas.setPointerCapture(e.pointerId);
  const w = eventWorld(e);
  if (e.button === 1 || e.button === 2 || e.shiftKey) {
    drag = { kind: "pan", x: e.clientX, y: e.clientY };
    return;
  }
  const t = tool();
  if (near(state.goal, w)) drag = { kind: "goal" };
  else if (near(state.start, w)) drag = { kind: "start" };
  else if (t === "paint" || t === "erase") { drag = { kind: "paint" }; paintAt(w); }
  else if (t === "disc") drag = { kind: "disc", p: w, q: w };
  else drag = { kind: "pan", x: e.clientX, y: e.clientY };
});
canvas.addEventListener("pointermove", (e) => {
  const w = eventWorld(e);
  if (state.map) {
    const [r, c] = view.cellAt(w[0], w[1]);
    const m = state.map;
    const inMap = r >= 0 && c >= 0 && r < m.height && c < m.width;
    $("legend").textContent = `x ${w[0].toFixed(2)} m, y ${w[1].toFixed(2)} m` +
      (inMap ? `, cell (${r}, ${c})${m.occ[r * m.width + c] ? " occupied" : ""}` : "");
  }
  if (!drag) return;
  if (drag.kind === "pan") {
    view.panBy(e.clientX - drag.x, e.clientY - drag.y);
    drag.x = e.clientX; drag.y = e.clientY;
  } else if (drag.kind === "start" || drag.kind === "goal") {
    state[drag.kind] = w;
    view.redraw();
    const m = state.map;
    if ($("auto-plan").checked && m.width * m.height <= AUTO_CELLS) schedulePlan();
  } else if (drag.kind === "paint") paintAt(w);
  else if (drag.kind === "disc") { drag.q = w; view.redraw(); }
});
canvas.addEventListener("pointerup", (e) => {
  if (!drag) return;
  const d = drag;
  drag = null;
  if (d.kind === "start" || d.kind === "goal" || d.kind === "paint") edited();
  if (d.kind === "disc") {
    const r = Math.min(Math.max(0.6 * state.map.resolution, 0.2), 1.0);
    scene.add({ position: [round(d.p[0]), round(d.p[1])],
                velocity: [round(d.q[0] - d.p[0]), round(d.q[1] - d.p[1])], radius: round(r) });
  }
});
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const r = canvas.getBoundingClientRect();
  view.zoomAt(e.clientX - r.left, e.clientY - r.top, Math.exp(-e.deltaY * 0.0015));
}, { passive: false });
function round(v) { return Math.round(v * 1000) / 1000; }

// ---------------------------------------------------------------- episodes
function sceneDoc() {
  const f = state.forms.find((x) => x.name === $("sim-planner").value);
  let params = {};
  if (f) params = f.params();
  const doc = {
    ...scene.extra,
    name: scene.name, map: mapRef(), start: state.start, goal: state.goal,
    robot: { radius: Number($("sim-radius").value), max_speed: Number($("sim-speed").value),
             sensing_radius: Number($("sim-sense").value) },
    dt: Number($("sim-dt").value), time_limit: Number($("sim-limit").value),
    obstacles: scene.obstacles,
    planner: { name: $("sim-planner").value, params },
  };
  return doc;
}

async function runEpisode() {
  $("sim-error").textContent = "";
  $("outcome").textContent = "running…";
  $("outcome").className = "muted";
  delete document.body.dataset.playback;
  try {
    const ep = await postJSON("/api/simulate", { scenario: sceneDoc() });
    player.load(ep);
    const ok = ep.status === "SUCCESS";
    $("outcome").className = ok ? "success" : "fail";
    $("outcome").textContent = `${ep.planner}: ${ep.status} — ${ep.message}; path ${ep.path_length_m.toFixed(2)} m, ` +
      `least gap ${ep.min_distance_m == null ? "–" : ep.min_distance_m.toFixed(3)} m, ${ep.n_ticks} ticks`;
    document.body.dataset.episode = ep.status;
    player.play();
  } catch (e) {
    $("sim-error").textContent = e.message;
    $("outcome").textContent = "";
  }
}

async function exportScene() {
  $("sim-error").textContent = "";
  try {
    const d = await postJSON("/api/scenario/export", { scenario: sceneDoc() });
    $("export-yaml").textContent = d.yaml;
    $("export-box").open = true;
    const a = el("a", { href: URL.createObjectURL(new Blob([d.yaml], { type: "text/yaml" })),
                        download: d.filename });
    document.body.append(a); a.click(); a.remove();
  } catch (e) { $("sim-error").textContent = e.message; }
}

function useScenario(d) {
  const sc = d.scenario;
  setMap(d.map);
  state.map.spec = null;
  state.start = sc.start; state.goal = sc.goal;
  scene.obstacles = sc.obstacles || [];
  scene.name = sc.name || "scenario";
  scene.extra = { seed: sc.seed, stall_time: sc.stall_time, stall_radius: sc.stall_radius,
                  goal_tolerance: sc.goal_tolerance };
  $("sim-dt").value = sc.dt; $("sim-limit").value = sc.time_limit;
  $("sim-radius").value = sc.robot.radius; $("sim-speed").value = sc.robot.max_speed;
  $("sim-sense").value = sc.robot.sensing_radius;
  if (sc.planner) {
    $("sim-planner").value = sc.planner.name;
    const f = state.forms.find((x) => x.name === sc.planner.name);
    if (f) f.set(sc.planner.params);
  }
  scene.renderList($("discs"));
  edited();
}

async function loadScenario() {
  $("sim-error").textContent = "";
  const id = $("scenario-select").value;
  if (!id) return;
  try { useScenario(await getJSON(`/api/scenarios/${id.split("/").map(encodeURIComponent).join("/")}`)); }
  catch (e) { $("sim-error").textContent = e.message; }
}

async function uploadScenario() {
  const files = [...$("scenario-file").files];
  if (!files.length) return;
  $("sim-error").textContent = "";
  try { useScenario(await postFiles("/api/scenarios", files)); }
  catch (e) { $("sim-error").textContent = e.message; }
  $("scenario-file").value = "";
}

// ---------------------------------------------------------------- start
async function init() {
  const [planners, maps, scenarios] = await Promise.all([
    getJSON("/api/planners"), getJSON("/api/maps"), getJSON("/api/scenarios")]);
  const box = $("planners");
  planners.forEach((p, i) => {
    const f = plannerForm(p, PALETTE[i % PALETTE.length], () => {
      const m = state.map;
      if (m && $("auto-plan").checked && m.width * m.height <= AUTO_CELLS) schedulePlan();
      scheduleField();
    });
    if (p.name === "astar" || p.name === "fusion") f.check.checked = true;
    state.forms.push(f);
    box.append(f.box);
  });
  for (const p of planners.filter((x) => x.online)) {
    $("sim-planner").append(el("option", { value: p.name, text: p.name, selected: p.name === "fusion" }));
  }
  for (const m of maps.maps) $("map-select").append(el("option", { value: m.id, text: m.id === "paper" ? m.name : m.id }));
  $("scenario-select").append(el("option", { value: "", text: "scenario…" }));
  for (const s of scenarios.scenarios) $("scenario-select").append(el("option", { value: s.id, text: s.id }));
  $("map-seed").value = 5;
  $("map-load").addEventListener("click", loadSelectedMap);
  $("map-select").addEventListener("change", loadSelectedMap);
  $("blank-make").addEventListener("click", blankMap);
  $("map-file").addEventListener("change", uploadMap);
  $("plan-btn").addEventListener("click", planAll);
  $("robot-radius").addEventListener("change", () => { planAll(); });
  for (const id of ["layer-closed", "layer-cspace", "layer-attract"]) {
    $(id).addEventListener("change", () => { updateLayers(); planAll(); });
  }
  $("layer-heat").addEventListener("change", () => { if (state.field) drawHeat(); loadField(); });
  $("layer-arrows").addEventListener("change", () => { loadField(); });
  $("heat-kind").addEventListener("change", drawHeat);
  $("attract-step").addEventListener("input", showAttractInfo);
  $("sim-run").addEventListener("click", runEpisode);
  $("sim-export").addEventListener("click", exportScene);
  $("discs-clear").addEventListener("click", () => { scene.clear(); player.unload(); });
  scene.onChange = () => { scene.renderList($("discs")); player.unload(); };
  $("scenario-load").addEventListener("click", loadScenario);
  $("scenario-file").addEventListener("change", uploadScenario);
  await loadSelectedMap();
  document.body.dataset.ready = "1";
}

init().catch((e) => { setStatus(e instanceof ApiError ? e.message : String(e)); });
