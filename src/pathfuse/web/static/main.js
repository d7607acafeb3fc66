// The pathfuse playground: wires the map, the planners, the layers, the animated search, the
// episodes, undo and the shareable link together.

import { ApiError, float32s, getJSON, int32s, isAbort, packBits, postFiles, postJSON,
  unpackBits } from "./api.js";
import { Player, Scene } from "./episode.js";
import { el, PALETTE, plannerForm } from "./forms.js";
import { History } from "./history.js";
import { maze } from "./maze.js";
import { SearchAnimation } from "./search.js";
import { decodeState, encodeState } from "./share.js";
import { makeImage, ramp, View } from "./view.js";

const $ = (id) => document.getElementById(id);
const AUTO_CELLS = 256 * 256;  // re-plan on every edit up to this many cells
const REST_MS = 200;           // while dragging, re-plan once the pointer rests this long
const EDIT_MS = 30;            // after an edit, gather the edits of this long into one round
const SLOW_MS = 300;           // a planner whose last answer took longer waits for the release

const state = {
  map: null,            // {id, name, width, height, resolution, origin, occ, spec, dirty}
  start: null, goal: null,
  forms: [],            // one generated form per registered planner
  results: new Map(),   // planner -> plan answer (or {error}); .stale once the scene changed
  took: new Map(),      // planner -> milliseconds its last answer took (the slow ones wait)
  only: null,           // the planner whose path is shown alone (click a row or a path)
  field: null,
  planSeq: 0, fieldSeq: 0,
  sent: 0,              // plan requests sent (for the tests and the curious)
};
const view = new View($("canvas"));
const history = new History();
const scene = new Scene(() => {});
const player = new Player(view, { play: $("play"), time: $("time"), speed: $("play-speed") },
  (k) => {
    const ep = player.ep;
    $("time-label").textContent = ep ? `${(k * ep.dt).toFixed(1)} / ${(ep.n_ticks * ep.dt).toFixed(1)} s` : "";
  });
const search = new SearchAnimation(view, { play: $("search-play"), speed: $("search-speed"),
  step: $("search-step"), info: $("search-info") }, (s) => {
  if (s) document.body.dataset.search = s; else delete document.body.dataset.search;
  updateLayers();
  view.redraw();
});
window.pathfuse = { state, view, scene, player, search, history, idle: () => idle() };  // for the tests

function setStatus(text) { $("status").textContent = text; }
function indexOf(name) { return state.forms.findIndex((f) => f.name === name); }
function colorOf(name) {
  const i = indexOf(name);
  return PALETTE[(i < 0 ? 0 : i) % PALETTE.length];
}
function dashOf(name) { return indexOf(name) >= PALETTE.length ? [8, 4] : null; }
function robotRadius() { return Math.max(0, Number($("robot-radius").value) || 0); }
function hexRgb(hex) {
  const n = parseInt(hex.slice(1), 16);
  return [(n >> 16) & 255, (n >> 8) & 255, n & 255];
}
function short(v) { return String(Number(Number(v).toPrecision(6))); }

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

// everything of the episodes that belongs to the old map: the discs, the played episode, its
// outcome and the exported YAML
function clearEpisodeState() {
  scene.obstacles = []; scene.extra = {}; scene.name = "playground";
  player.unload();
  $("outcome").textContent = ""; $("outcome").className = "muted";
  $("sim-error").textContent = "";
  $("export-yaml").textContent = ""; $("export-box").open = false;
  delete document.body.dataset.episode;
  delete document.body.dataset.playback;
  renderDiscs();
}

// d: a map answer of the API (bits), or {occ, ...} built here (local: no server id, sent as a
// grid); a new map clears the episode state and the results
function setMap(d, { keepPoints = false, local = false } = {}) {
  const m = { id: local ? null : d.id, name: d.name, width: d.width, height: d.height,
              resolution: d.resolution, origin: d.origin, spec: local ? null : d.spec || null,
              dirty: local, occ: d.occ || unpackBits(d.bits, d.width * d.height) };
  state.map = m;
  if (!keepPoints || !inside(m, state.start) || !inside(m, state.goal)) {
    const paper = m.spec && m.spec.paper;
    state.start = paper ? [1, 1] : firstFree(m, false);
    state.goal = paper ? [11, 11] : firstFree(m, true);
  }
  abortRound();
  state.results.clear();
  state.only = null;
  state.field = null;
  search.clear();
  clearEpisodeState();
  view.setMap(m);
  view.fit();
  ["closed", "cspace", "heat"].forEach((k) => view.setOverlay(k, null));
  showMapInfo();
  $("map-error").textContent = "";
  renderTable();
  edited();
}

function showMapInfo() {
  const m = state.map;
  $("map-info").textContent = `${m.name}: ${m.width} × ${m.height} cells of ${m.resolution} m` +
    (m.dirty ? " (edited)" : "");
}

// a new map replaces the current one: undo brings the old one back
async function newMap(load) {
  const before = state.map ? snapshot() : null;
  try {
    const d = await load();
    if (!d) return;
    if (before) history.push(before);
  } catch (e) {
    $("map-error").textContent = e.message;
    setStatus("");
  }
}

function loadSelectedMap() {
  const id = $("map-select").value;
  return newMap(async () => {
    setStatus("loading map…");
    const d = id === "paper"
      ? await postJSON("/api/map", { map: "paper", seed: Number($("map-seed").value) || 0 })
      : await getJSON(`/api/maps/${id.split("/").map(encodeURIComponent).join("/")}`);
    setMap(d);
    setStatus("");
    return d;
  });
}

function blankMap() {
  return newMap(async () => {
    const d = await postJSON("/api/map", { map: { blank: {
      size: [Number($("blank-w").value), Number($("blank-h").value)],
      resolution: Number($("blank-res").value) } } });
    setMap(d);
    return d;
  });
}

function randomSeed() { return Math.floor(Math.random() * 1e6); }

// random walls over the current map's size, the start and the goal kept free and connected
function randomMap() {
  const m = state.map;
  return newMap(async () => {
    const seed = randomSeed();
    const d = await postJSON("/api/map", { map: { random: {
      size: [m.width * m.resolution, m.height * m.resolution], resolution: m.resolution,
      origin: m.origin, density: Math.min(Math.max(Number($("random-density").value) || 0, 0), 0.6),
      seed, keep_free: [state.start, state.goal], connect: [[state.start, state.goal]] } } });
    setMap(d, { keepPoints: true });
    return d;
  });
}

// a maze over the current map's size, its corridors wide enough for the robot
function mazeMap() {
  const m = state.map;
  return newMap(async () => {
    const corridor = Math.max(1, Math.ceil(2 * robotRadius() / m.resolution + 0.5));
    const seed = randomSeed();
    const z = maze(m.width, m.height, corridor, seed);
    if (!z) throw new Error(`a maze needs room for 2 × 2 corridors of ${corridor} cells: this map is too small`);
    const d = { name: `maze-${m.width}x${m.height}-s${seed}`, width: m.width, height: m.height,
                resolution: m.resolution, origin: m.origin, occ: z.occ };
    state.start = cellCentre(m, ...z.start);
    state.goal = cellCentre(m, ...z.goal);
    setMap(d, { keepPoints: true, local: true });
    return d;
  });
}

function clearWalls() {
  const m = state.map;
  if (!m || !m.occ.some((v) => v)) return;
  history.push(snapshot());
  m.occ.fill(0);
  m.dirty = true;
  view.paintAll();
  showMapInfo();
  edited();
}

async function uploadMap() {
  const files = [...$("map-file").files];
  if (!files.length) return;
  setStatus("uploading…");
  await newMap(async () => {
    try {
      const d = await postFiles("/api/maps", files, { resolution: $("upload-res").value });
      setMap(d);
      setStatus(`uploaded ${d.name}`);
      return d;
    } catch (e) { setStatus("upload failed"); throw e; }
  });
  $("map-file").value = "";
}

// ---------------------------------------------------------------- undo
let lastRadius = null;

function snapshot(over = {}) {
  const m = state.map;
  return { map: m, occ: m.occ.slice(), dirty: m.dirty, start: [...state.start],
           goal: [...state.goal], radius: lastRadius ?? $("robot-radius").value,
           obstacles: JSON.parse(JSON.stringify(scene.obstacles)), ...over };
}

function restore(s) {
  const m = s.map;
  const other = m !== state.map;
  m.occ = s.occ; m.dirty = s.dirty;
  state.map = m;
  state.start = s.start; state.goal = s.goal;
  $("robot-radius").value = s.radius; lastRadius = s.radius;
  if (other) {
    abortRound();
    state.results.clear(); state.only = null; state.field = null;
    ["closed", "cspace", "heat"].forEach((k) => view.setOverlay(k, null));
    view.setMap(m); view.fit();
  } else view.paintAll();
  scene.obstacles = s.obstacles;
  player.unload();
  showMapInfo();
  renderTable();
  edited();
}

function undo() {
  if (drag) return;
  const s = history.undo(snapshot());
  if (s) restore(s);
}
function redo() {
  if (drag) return;
  const s = history.redo(snapshot());
  if (s) restore(s);
}
history.onChange = () => {
  $("undo").disabled = !history.done.length;
  $("redo").disabled = !history.undone.length;
};

// ---------------------------------------------------------------- planning
function selected() { return state.forms.filter((f) => f.check.checked); }
function autoPlans() {
  const m = state.map;
  return m && $("auto-plan").checked && m.width * m.height <= AUTO_CELLS;
}
function isSlow(name) { return (state.took.get(name) || 0) > SLOW_MS; }

// after an edit (a drag let go, a painted stroke, a parameter, the radius, a new map)
function edited() {
  const m = state.map;
  if (!m) return;
  search.clear();
  requestPlan("edit");
  if ($("layer-heat").checked || $("layer-arrows").checked) scheduleField();
  renderDiscs();
  scheduleShare();
  view.redraw();
}

let planTimer = null;
let inFlight = null;  // {seq, ctrl}: the round of requests in flight

function abortRound() {
  clearTimeout(planTimer);
  planTimer = null;
  if (inFlight) { inFlight.ctrl.abort(); inFlight = null; }
}

function markStale() {
  for (const r of state.results.values()) { r.stale = true; r.held = false; }
}

// kind: "live" (a drag in progress: wait for the pointer to rest, leave out the slow planners),
// "edit" (an edit is done) or "now" (the Plan button).  Whatever was in flight is stale:
// its requests are aborted at once, so the server stops computing them.
function requestPlan(kind) {
  abortRound();
  markStale();
  if (kind !== "now" && !autoPlans()) {
    const m = state.map;
    setStatus(`${m.width} × ${m.height} cells: press Plan to plan (re-planning on every edit is for maps up to 256 × 256)`);
    renderTable();
    return;
  }
  if (kind === "now") { planRound(false); return; }
  if (kind === "live") renderTable();
  planTimer = setTimeout(() => { planTimer = null; planRound(kind === "live"); },
                         kind === "live" ? REST_MS : EDIT_MS);
}

// nothing waiting or in flight, every answer for the current scene (for the tests)
function idle() {
  return !planTimer && !inFlight && [...state.results.values()].every((r) => !r.stale);
}

function layersWanted() {
  const out = [];
  if ($("layer-closed").checked) out.push("closed");
  if ($("layer-cspace").checked) out.push("cspace");
  if ($("layer-attract").checked) out.push("attractors");
  return out;
}

async function planRound(live) {
  const m = state.map;
  if (!m) return;
  abortRound();
  const seq = ++state.planSeq;
  const ctrl = new AbortController();
  inFlight = { seq, ctrl };
  const forms = selected();
  const names = new Set(forms.map((f) => f.name));
  for (const k of [...state.results.keys()]) if (!names.has(k)) state.results.delete(k);
  if (state.only && !names.has(state.only)) state.only = null;
  const run = live ? forms.filter((f) => !isSlow(f.name)) : forms;
  const held = forms.filter((f) => !run.includes(f)).map((f) => f.name);
  for (const name of held) { const r = state.results.get(name); if (r) r.held = true; }
  const ref = mapRef();
  const radius = robotRadius();
  const layers = layersWanted();
  const start = [...state.start], goal = [...state.goal];
  setStatus(run.length ? `planning with ${run.map((f) => f.name).join(", ")}` +
    (held.length ? ` (${held.join(", ")} when you let go)` : "") + "…" : "choose a planner");
  renderTable();
  const one = async (f) => {
    let params;
    try { params = f.params(); } catch (e) {
      state.results.set(f.name, { error: e.message });
      return;
    }
    const t0 = performance.now();
    try {
      state.sent++;
      const d = await postJSON("/api/plan", { map: ref, start, goal, planner: f.name, params,
        robot_radius: radius, extras: true,
        layers: layers.filter((l) => l === "cspace" || f.planner.layers.includes(l)) },
      { signal: ctrl.signal });
      state.took.set(f.name, performance.now() - t0);
      f.markBad("");
      if (seq !== state.planSeq) return;
      state.results.set(f.name, d);
    } catch (e) {
      if (isAbort(e)) {
        // it ran at least this long: slow enough to wait for the release?
        const t = performance.now() - t0;
        if (t > (state.took.get(f.name) || 0)) state.took.set(f.name, t);
        return;
      }
      f.markBad(e.message);
      if (seq !== state.planSeq) return;
      state.results.set(f.name, { error: e.message });
    }
    updateLayers();
    renderTable();
    view.redraw();
  };
  await Promise.all(run.map(one));
  if (seq !== state.planSeq) return;
  inFlight = null;
  setStatus(forms.length ? `planned ${m.width} × ${m.height} cells` +
    (held.length ? `; ${held.join(", ")} when you let go` : "") : "choose a planner");
  updateLayers();
  renderTable();
  view.redraw();
  document.body.dataset.planned = String(seq);
}

function fmt(v, digits) { return v == null ? "–" : Number(v).toFixed(digits); }

function toggleOnly(name) {
  state.only = state.only === name ? null : name;
  renderTable();
  view.redraw();
  scheduleShare();
}

function renderTable() {
  const tb = $("results").querySelector("tbody");
  tb.replaceChildren();
  for (const f of state.forms) {
    const name = f.name, r = state.results.get(name);
    if (!r) continue;
    const sw = el("span", { className: "swatch", style: `background:${colorOf(name)}` });
    const tr = el("tr", { tabIndex: 0 });
    tr.dataset.planner = name;
    tr.setAttribute("aria-pressed", String(state.only === name));
    tr.classList.toggle("isolated", state.only === name);
    tr.classList.toggle("dimmed", !!state.only && state.only !== name);
    tr.classList.toggle("stale", !!r.stale);
    if (r.error) {
      tr.append(el("td", {}, sw), el("td", { text: name }),
        el("td", { className: "fail status", colSpan: 6, text: r.error }));
    } else {
      const ok = r.status === "SUCCESS";
      const ex = r.extras || {};
      const note = !r.stale ? "" : r.held ? " (plans when you let go)"
        : autoPlans() ? " (re-planning)" : " (out of date: press Plan)";
      tr.append(el("td", {}, sw), el("td", { text: name }),
        el("td", { className: (ok ? "" : "fail ") + "status", text: r.status + note, title: r.message }),
        el("td", { className: "length", text: ok ? fmt(r.length, 3) : "–" }),
        el("td", { text: fmt(r.time_s * 1e3, 3) }), el("td", { text: String(r.expansions) }),
        el("td", { text: String(r.iterations) }),
        el("td", { text: fmt(ex.min_clearance_m, 3) }));
    }
    tr.addEventListener("click", () => toggleOnly(name));
    tr.addEventListener("keydown", (e) => {
      if (e.key === "Enter" || e.key === " ") { e.preventDefault(); toggleOnly(name); }
    });
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

function updateLayers() {
  const m = state.map;
  if (!m) return;
  let closed = null, cspace = null, attract = null;
  for (const f of state.forms) {
    const r = state.results.get(f.name);
    if (!r || r.stale) continue;
    const ex = r.extras || {};
    if (!closed && ex.closed && $("layer-closed").checked) closed = [f.name, ex.closed];
    if (!cspace && ex.cspace && $("layer-cspace").checked) cspace = ex.cspace;
    if (!attract && ex.attractors && $("layer-attract").checked) attract = [f.name, r];
  }
  if (search.active) closed = null;  // the animated search shows it cell by cell
  view.setOverlay("closed", closed ? maskOverlay(closed[1].bits, [...hexRgb(colorOf(closed[0])), 255], 0.28) : null);
  if (cspace) {
    const mask = unpackBits(cspace.bits, m.width * m.height);
    const W = m.width, H = m.height;
    view.setOverlay("cspace", { canvas: makeImage(W, H, (i, j) => {
      const k = (H - 1 - i) * W + j;
      return mask[k] && !m.occ[k] ? [249, 115, 22, 255] : null;
    }), x0: m.origin[0], y0: m.origin[1], w: W * m.resolution, h: H * m.resolution, alpha: 0.45 });
  } else if (!$("layer-cspace").checked) view.setOverlay("cspace", null);
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

let fieldTimer = null, fieldCtrl = null;
function scheduleField() {
  clearTimeout(fieldTimer);
  if (fieldCtrl) fieldCtrl.abort();
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
  if (fieldCtrl) fieldCtrl.abort();
  fieldCtrl = new AbortController();
  const f = fieldPlanner();
  let params = {};
  try { params = f ? f.params() : {}; } catch (e) { params = {}; }
  try {
    const d = await postJSON("/api/field", { map: mapRef(), goal: state.goal,
      planner: f ? f.name : undefined, params }, { signal: fieldCtrl.signal });
    if (seq !== state.fieldSeq) return;
    state.field = d;
    $("field-info").textContent = `APF of ${d.planner}: K_att ${d.params.k_att}, K_rep ${d.params.k_rep}, ρ0 ${d.params.rho0_m} m; colour = log(1 + U)`;
    drawHeat();
    document.body.dataset.field = String(seq);
  } catch (e) { if (!isAbort(e)) $("field-info").textContent = e.message; }
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

// ---------------------------------------------------------------- the animated search
let searchCtrl = null;

// on a phone the controls are below the map: bring the map back into view to watch
function showMap() {
  const r = canvas.getBoundingClientRect();
  if (r.top < -r.height / 2 || r.top > window.innerHeight / 2) {
    $("stage").scrollIntoView({ block: "start" });
  }
}

function searchPlanners() { return state.forms.filter((f) => f.planner.layers.includes("closed")); }

function cornerCutting(f) {
  const p = f.planner.params.find((q) => q.name === "corner_cutting");
  if (!p) return false;
  const inp = f.box.querySelector(`[name="${f.name}.corner_cutting"]`);
  return inp ? !!inp.checked : !!p.default;
}

async function startSearch() {
  const m = state.map;
  const f = state.forms.find((x) => x.name === $("search-planner").value);
  if (!m || !f) return;
  let params;
  try { params = f.params(); } catch (e) { $("search-info").textContent = e.message; return; }
  if (searchCtrl) searchCtrl.abort();
  searchCtrl = new AbortController();
  search.clear();
  $("search-info").textContent = `searching with ${f.name}…`;
  try {
    const d = await postJSON("/api/plan", { map: mapRef(), start: state.start, goal: state.goal,
      planner: f.name, params, robot_radius: robotRadius(), layers: ["closed", "cspace"] },
    { signal: searchCtrl.signal });
    const closed = d.extras && d.extras.closed;
    if (!closed || !closed.order) {
      $("search-info").textContent = `${f.name}: ${d.status}: ${d.message} (no search to show)`;
      return;
    }
    search.load({ name: f.name, order: int32s(closed.order),
                  blocked: unpackBits(d.extras.cspace.bits, m.width * m.height), map: m,
                  cutting: cornerCutting(f), color: hexRgb(colorOf(f.name)), result: d });
    showMap();
    search.play();
  } catch (e) {
    if (!isAbort(e)) $("search-info").textContent = e.message;
  }
}

// ---------------------------------------------------------------- discs
// the checks of a scenario file's discs (pathfuse.world.scenario), made when a disc is placed,
// moved or resized rather than at Run: inside the map, clear of walls and of the map's edge
// by its radius, and not overlapping the robot at the start
function discClear(m, p, r) {
  const res = m.resolution, [ox, oy] = m.origin;
  const edge = Math.min(p[0] - ox, ox + m.width * res - p[0], p[1] - oy, oy + m.height * res - p[1]);
  if (!(edge > 0) || edge < r) return false;
  const c0 = Math.max(0, Math.floor((p[0] - r - ox) / res)), c1 = Math.min(m.width - 1, Math.floor((p[0] + r - ox) / res));
  const r0 = Math.max(0, Math.floor((p[1] - r - oy) / res)), r1 = Math.min(m.height - 1, Math.floor((p[1] + r - oy) / res));
  for (let i = r0; i <= r1; i++) {
    for (let j = c0; j <= c1; j++) {
      if (!m.occ[i * m.width + j]) continue;
      const x0 = ox + j * res, y0 = oy + i * res;
      const dx = Math.max(x0 - p[0], 0, p[0] - (x0 + res)), dy = Math.max(y0 - p[1], 0, p[1] - (y0 + res));
      if (Math.hypot(dx, dy) < r) return false;
    }
  }
  return true;
}

function checkDisc(o, i) {
  const m = state.map, key = `obstacles[${i}]`;
  if (!(Number(o.radius) > 0)) return `${key}.radius: must be a number > 0, got ${JSON.stringify(o.radius)}`;
  const pts = o.position ? [[o.position, `${key}.position`]]
    : o.waypoints ? o.waypoints.map((w, j) => [w, `${key}.waypoints[${j}]`])
      : o.random_walk ? [[o.random_walk.position, `${key}.random_walk.position`]] : [];
  const [x0, y0] = m.origin, x1 = x0 + m.width * m.resolution, y1 = y0 + m.height * m.resolution;
  for (const [p, k] of pts) {
    if (!(x0 <= p[0] && p[0] < x1 && y0 <= p[1] && p[1] < y1)) {
      return `${k}: (${short(p[0])}, ${short(p[1])}) lies outside the map [${short(x0)}, ${short(x1)}] x [${short(y0)}, ${short(y1)}]`;
    }
    if (!discClear(m, p, o.radius)) {
      return `${k}: the disc (radius ${short(o.radius)} m) at (${short(p[0])}, ${short(p[1])}) overlaps an occupied cell or the map's edge`;
    }
  }
  if (pts.length) {
    const c = pts[0][0];
    const gap = Math.hypot(c[0] - state.start[0], c[1] - state.start[1]) - o.radius - robotRadius();
    if (gap < 0) return `${key}: overlaps the robot at the start (by ${Number((-gap).toPrecision(3))} m)`;
  }
  return "";
}

function renderDiscs() {
  const problems = state.map ? scene.obstacles.map((o, i) => checkDisc(o, i)) : [];
  scene.renderList($("discs"), problems);
}

scene.check = (o, i) => (state.map ? checkDisc(o, i) : "");
scene.onError = (why) => { $("sim-error").textContent = why; };
scene.beforeChange = () => history.push(snapshot());

// ---------------------------------------------------------------- drawing
view.drawers.push(drawArrows);
view.drawers.push((ctx, v) => {
  if (search.active) {  // the search alone, then its path
    const p = search.finishedPath();
    if (p) v.polyline(ctx, p, colorOf(search.anim.name), 3);
    return;
  }
  for (const f of state.forms) {
    const name = f.name, r = state.results.get(name);
    if (!r || r.error || !r.path || (state.only && state.only !== name)) continue;
    const c = colorOf(name);
    if (r.extras && r.extras.astar_path && r.planner !== "astar") {
      v.polyline(ctx, r.extras.astar_path, c + "66", 1, [3, 3]);
    }
    // an answer for an older scene: faded and dashed until the new one comes
    if (r.stale) v.polyline(ctx, r.path, c + "70", 2, [6, 5]);
    else v.polyline(ctx, r.path, c, 2.5, dashOf(name));
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
  const st = scene.starts();
  st.forEach((s, i) => {
    if (!s) return;
    let { p, r } = s, vel = s.v, way = s.way;
    if (drag && drag.kind === "disc-edit" && drag.i === i) {  // the disc being edited
      const q = drag.preview;
      p = q.position || (q.waypoints && q.waypoints[0]) || q.random_walk.position;
      r = q.radius; vel = q.velocity; way = q.waypoints;
    }
    const bad = drag && drag.kind === "disc-edit" && drag.i === i ? drag.why : checkDisc(scene.obstacles[i], i);
    v.disc(ctx, p[0], p[1], r, bad ? "rgba(180,35,24,.35)" : "rgba(217,119,6,.35)",
           bad ? "#b42318" : "#b45309", bad ? 2.5 : 1.5);
    if (vel) v.arrow(ctx, p[0], p[1], vel[0], vel[1], "#b45309", 2);
    if (way) v.polyline(ctx, way, "rgba(180,83,9,.6)", 1, [4, 3]);
  });
  if (drag && drag.kind === "disc") {
    const r = newDiscRadius();
    v.disc(ctx, drag.p[0], drag.p[1], r, "rgba(217,119,6,.25)", drag.why ? "#b42318" : "#b45309", 1.5);
    v.arrow(ctx, drag.p[0], drag.p[1], drag.q[0] - drag.p[0], drag.q[1] - drag.p[1], "#b45309", 2);
  }
});
view.drawers.push((ctx, v) => player.draw(ctx, v));
view.drawers.push((ctx, v) => {
  if (!state.start) return;
  const rr = robotRadius();
  const marks = [[state.start, "#15803d", "S"], [state.goal, "#c2410c", "G"]];
  for (const [p, fill] of marks) {
    if (rr > 0) v.disc(ctx, p[0], p[1], rr, null, fill, 1);
    v.disc(ctx, p[0], p[1], v.px(8), fill, "#fff", 2);
  }
  // the letters, upright: in CSS pixels
  const dpr = view.dpr;
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.font = "bold 10px system-ui, sans-serif";
  ctx.textAlign = "center"; ctx.textBaseline = "middle"; ctx.fillStyle = "#fff";
  for (const [p, , letter] of marks) {
    const [px, py] = v.toScreen(p[0], p[1]);
    ctx.fillText(letter, px, py + 0.5);
  }
});

// ---------------------------------------------------------------- pointer
let drag = null;
const pointers = new Map();  // pointer id -> [clientX, clientY], for a pinch
const canvas = $("canvas");
const tool = () => document.querySelector("input[name=tool]:checked").value;

function eventWorld(e) {
  const r = canvas.getBoundingClientRect();
  return view.toWorld(e.clientX - r.left, e.clientY - r.top);
}

function near(p, w) {
  return p && Math.hypot(p[0] - w[0], p[1] - w[1]) * view.scale < 12;
}

function newDiscRadius() { return Math.round(Math.min(Math.max(0.6 * state.map.resolution, 0.2), 1.0) * 1000) / 1000; }

function paintAt(w) {
  const m = state.map;
  const [r, c] = view.cellAt(w[0], w[1]);
  const b = Math.max(1, Number($("brush").value) || 1), h = Math.floor((b - 1) / 2);
  const val = tool() === "paint" ? 1 : 0;
  const r0 = Math.max(0, r - h), r1 = Math.min(m.height, r - h + b);
  const c0 = Math.max(0, c - h), c1 = Math.min(m.width, c - h + b);
  if (r0 >= r1 || c0 >= c1) return false;
  let changed = false;
  for (let i = r0; i < r1; i++) {
    for (let j = c0; j < c1; j++) {
      if (m.occ[i * m.width + j] !== val) { m.occ[i * m.width + j] = val; changed = true; }
    }
  }
  if (!changed) return false;
  m.dirty = true;
  view.paintRect(c0, r0, c1, r1);
  return true;
}

// the planner whose path passes within 8 pixels of screen point (px, py), or null
function pathAt(px, py) {
  let best = null, bestD = 8;
  for (const f of state.forms) {
    const r = state.results.get(f.name);
    if (!r || r.error || !r.path || (state.only && state.only !== f.name)) continue;
    const pts = r.path.map((q) => view.toScreen(q[0], q[1]));
    for (let k = 1; k < pts.length; k++) {
      const [ax, ay] = pts[k - 1], [bx, by] = pts[k];
      const L = (bx - ax) ** 2 + (by - ay) ** 2;
      const t = L ? Math.min(1, Math.max(0, ((px - ax) * (bx - ax) + (py - ay) * (by - ay)) / L)) : 0;
      const d = Math.hypot(px - ax - t * (bx - ax), py - ay - t * (by - ay));
      if (d < bestD) { bestD = d; best = f.name; }
    }
  }
  return best;
}

function pinchInfo() {
  const [a, b] = [...pointers.values()];
  const r = canvas.getBoundingClientRect();
  return { d: Math.hypot(a[0] - b[0], a[1] - b[1]), x: (a[0] + b[0]) / 2 - r.left, y: (a[1] + b[1]) / 2 - r.top };
}

// give up the one-finger drag a second finger interrupts
function cancelDrag() {
  if (!drag) return;
  if ((drag.kind === "start" || drag.kind === "goal") && drag.from) {
    state[drag.kind] = drag.from;
  }
  if (drag.kind === "paint" && drag.changed) { restore(drag.snap); }
  drag = null;
  view.redraw();
}

canvas.addEventListener("contextmenu", (e) => e.preventDefault());
canvas.addEventListener("pointerdown", (e) => {
  if (!state.map) return;
  canvas.setPointerCapture(e.pointerId);
  pointers.set(e.pointerId, [e.clientX, e.clientY]);
  if (pointers.size === 2) {
    cancelDrag();
    drag = { kind: "pinch", ...pinchInfo() };
    return;
  }
  if (pointers.size > 2) return;
  const w = eventWorld(e);
  if (e.button === 1 || e.button === 2 || e.shiftKey) {
    drag = { kind: "pan", x: e.clientX, y: e.clientY };
    return;
  }
  const t = tool();
  let hit;
  if (near(state.goal, w)) drag = { kind: "goal", from: [...state.goal], snap: snapshot() };
  else if (near(state.start, w)) drag = { kind: "start", from: [...state.start], snap: snapshot() };
  else if (t === "paint" || t === "erase") {
    drag = { kind: "paint", snap: snapshot(), changed: false };
    drag.changed = paintAt(w);
  } else if ((t === "disc" || t === "move") && !player.ep && (hit = scene.hit(w, view.scale))) {
    const o = scene.obstacles[hit.i];
    drag = { kind: "disc-edit", i: hit.i, part: hit.part, w0: w, spec0: o, preview: o, why: "" };
  } else if (t === "disc") drag = { kind: "disc", p: w, q: w, why: checkDisc({ position: w, radius: newDiscRadius() }, scene.obstacles.length) };
  else drag = { kind: "pan", x: e.clientX, y: e.clientY, x0: e.clientX, y0: e.clientY, click: true };
});
canvas.addEventListener("pointermove", (e) => {
  const w = eventWorld(e);
  if (pointers.has(e.pointerId)) pointers.set(e.pointerId, [e.clientX, e.clientY]);
  if (state.map) {
    const [r, c] = view.cellAt(w[0], w[1]);
    const m = state.map;
    const inMap = r >= 0 && c >= 0 && r < m.height && c < m.width;
    $("legend").textContent = `x ${w[0].toFixed(2)} m, y ${w[1].toFixed(2)} m` +
      (inMap ? `, cell (${r}, ${c})${m.occ[r * m.width + c] ? " occupied" : ""}` : "");
  }
  if (!drag) return;
  if (drag.kind === "pinch") {
    if (pointers.size < 2) return;
    const p = pinchInfo();
    view.panBy(p.x - drag.x, p.y - drag.y);
    if (drag.d > 0 && p.d > 0) view.zoomAt(p.x, p.y, p.d / drag.d);
    Object.assign(drag, p);
  } else if (drag.kind === "pan") {
    view.panBy(e.clientX - drag.x, e.clientY - drag.y);
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.click && Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0) > 4) drag.click = false;
  } else if (drag.kind === "start" || drag.kind === "goal") {
    state[drag.kind] = w;
    search.clear();
    view.redraw();
    requestPlan("live");
  } else if (drag.kind === "paint") {
    if (paintAt(w)) drag.changed = true;
  } else if (drag.kind === "disc") {
    drag.q = w; view.redraw();
  } else if (drag.kind === "disc-edit") {
    const o = drag.spec0, s = scene.starts()[drag.i];
    if (drag.part === "centre") drag.preview = Scene.edited(o, { dx: w[0] - drag.w0[0], dy: w[1] - drag.w0[1] });
    else if (drag.part === "rim") drag.preview = Scene.edited(o, { r: Math.max(0.01, Math.hypot(w[0] - s.p[0], w[1] - s.p[1])) });
    else drag.preview = Scene.edited(o, { v: [w[0] - s.p[0], w[1] - s.p[1]] });
    drag.why = checkDisc(drag.preview, drag.i);
    view.redraw();
  }
});
function pointerEnd(e) {
  pointers.delete(e.pointerId);
  if (!drag) return;
  if (drag.kind === "pinch") { if (pointers.size < 2) drag = null; return; }
  const d = drag;
  drag = null;
  if (d.kind === "start" || d.kind === "goal") {
    const moved = d.from[0] !== state[d.kind][0] || d.from[1] !== state[d.kind][1];
    if (moved) { history.push(d.snap); edited(); }
  } else if (d.kind === "paint") {
    if (d.changed) { history.push(d.snap); showMapInfo(); edited(); }
  } else if (d.kind === "disc") {
    if (e.type === "pointercancel") { view.redraw(); return; }
    $("sim-error").textContent = "";
    scene.add({ position: [round(d.p[0]), round(d.p[1])],
                velocity: [round(d.q[0] - d.p[0]), round(d.q[1] - d.p[1])], radius: newDiscRadius() });
    view.redraw();
  } else if (d.kind === "disc-edit") {
    if (JSON.stringify(d.preview) !== JSON.stringify(d.spec0) && e.type !== "pointercancel") {
      $("sim-error").textContent = "";
      scene.replace(d.i, d.preview);  // refused (with the reason shown) when it is not valid
    }
    view.redraw();
  } else if (d.kind === "pan" && d.click) {
    const r = canvas.getBoundingClientRect();
    const name = pathAt(e.clientX - r.left, e.clientY - r.top);
    if (name) toggleOnly(name);
    else if (state.only) toggleOnly(state.only);
  }
}
canvas.addEventListener("pointerup", pointerEnd);
canvas.addEventListener("pointercancel", pointerEnd);
// while a drag lasts, a resize of the canvas (the table's rows change) does not re-fit the map
canvas.addEventListener("pointerdown", () => { view.holding = true; }, true);
for (const type of ["pointerup", "pointercancel"]) {
  canvas.addEventListener(type, () => {
    if (!pointers.size) { view.holding = false; if (view.fitted) view.fit(); }
  });
}
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
  return {
    ...scene.extra,
    name: scene.name, map: mapRef(), start: state.start, goal: state.goal,
    robot: { radius: robotRadius(), max_speed: Number($("sim-speed").value),
             sensing_radius: Number($("sim-sense").value) },
    dt: Number($("sim-dt").value), time_limit: Number($("sim-limit").value),
    obstacles: scene.obstacles,
    planner: { name: $("sim-planner").value, params },
  };
}

async function runEpisode() {
  $("sim-error").textContent = "";
  $("outcome").textContent = "running…";
  $("outcome").className = "muted";
  delete document.body.dataset.playback;
  delete document.body.dataset.episode;
  const map = state.map;
  try {
    const ep = await postJSON("/api/simulate", { scenario: sceneDoc() });
    if (map !== state.map) return;  // the map changed meanwhile: this episode is not of it
    player.load(ep);
    const ok = ep.status === "SUCCESS";
    $("outcome").className = ok ? "success" : "fail";
    $("outcome").textContent = `${ep.planner}: ${ep.status} — ${ep.message}; path ${ep.path_length_m.toFixed(2)} m, ` +
      `least gap ${ep.min_distance_m == null ? "–" : ep.min_distance_m.toFixed(3)} m, ${ep.n_ticks} ticks`;
    document.body.dataset.episode = ep.status;
    showMap();
    player.play();
  } catch (e) {
    if (map !== state.map) return;
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
    download(new Blob([d.yaml], { type: "text/yaml" }), d.filename);
  } catch (e) { $("sim-error").textContent = e.message; }
}

function download(blob, filename) {
  const a = el("a", { href: URL.createObjectURL(blob), download: filename });
  document.body.append(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

function useScenario(d) {
  const sc = d.scenario;
  const before = state.map ? snapshot() : null;
  setMap(d.map);
  if (before) history.push(before);
  state.map.spec = null;
  state.start = sc.start; state.goal = sc.goal;
  scene.obstacles = sc.obstacles || [];
  scene.name = sc.name || "scenario";
  scene.extra = { seed: sc.seed, stall_time: sc.stall_time, stall_radius: sc.stall_radius,
                  goal_tolerance: sc.goal_tolerance };
  $("sim-dt").value = sc.dt; $("sim-limit").value = sc.time_limit;
  $("robot-radius").value = sc.robot.radius; lastRadius = $("robot-radius").value;
  $("sim-speed").value = sc.robot.max_speed;
  $("sim-sense").value = sc.robot.sensing_radius;
  if (sc.planner) {
    $("sim-planner").value = sc.planner.name;
    const f = state.forms.find((x) => x.name === sc.planner.name);
    if (f) f.set(sc.planner.params);
  }
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

// ---------------------------------------------------------------- the link
// The state in the URL after "#": the map (its spec, its catalog id, or its cells when edited,
// built here or uploaded), start, goal, robot radius, the ticked planners and their changed
// parameters, the path shown alone, the discs, the episode settings and the layers.
const SIM_FIELDS = ["sim-planner", "sim-dt", "sim-limit", "sim-speed", "sim-sense"];
const LAYER_FIELDS = ["layer-heat", "layer-arrows", "layer-closed", "layer-cspace", "layer-attract"];
let restoring = false, shareTimer = null, lastHash = "";

function shareDoc() {
  const m = state.map;
  let map;
  if (!m.dirty && m.spec && (m.spec.paper || m.spec.random)) map = { spec: m.spec };
  else if (!m.dirty && m.id && !m.id.startsWith("upload-")) map = { id: m.id };
  else {
    map = { grid: { width: m.width, height: m.height, resolution: m.resolution,
                    origin: m.origin, name: m.name, bits: packBits(m.occ) } };
  }
  const planners = {};
  for (const f of selected()) {
    try { planners[f.name] = f.params(); } catch (e) { planners[f.name] = {}; }
  }
  return {
    v: 1, map, start: state.start, goal: state.goal, radius: robotRadius(), planners,
    only: state.only, obstacles: scene.obstacles, scene: { name: scene.name, extra: scene.extra },
    sim: Object.fromEntries(SIM_FIELDS.map((id) => [id, $(id).value])),
    layers: LAYER_FIELDS.filter((id) => $(id).checked),
  };
}

// a disc of a link has the shape of a scenario's disc (its values are checked as any disc's)
function plausibleDisc(o) {
  const pt = (p) => Array.isArray(p) && p.length === 2 && p.every(Number.isFinite);
  if (!o || typeof o !== "object" || !Number.isFinite(o.radius)) return false;
  if (o.position) return pt(o.position) && pt(o.velocity || [0, 0]);
  if (o.waypoints) return Array.isArray(o.waypoints) && o.waypoints.length > 0 && o.waypoints.every(pt);
  return !!(o.random_walk && pt(o.random_walk.position));
}

function scheduleShare() {
  if (restoring || !state.map) return;
  clearTimeout(shareTimer);
  shareTimer = setTimeout(async () => {
    const h = "#" + await encodeState(shareDoc());
    lastHash = h;
    if (location.hash !== h) window.history.replaceState(null, "", h);
    document.body.dataset.shared = String((Number(document.body.dataset.shared) || 0) + 1);
  }, 300);
}

async function copyLink() {
  clearTimeout(shareTimer);
  const h = "#" + await encodeState(shareDoc());
  lastHash = h;
  window.history.replaceState(null, "", h);
  try {
    await navigator.clipboard.writeText(location.href);
    setStatus("link copied: it restores this map, the start and goal, the planners and the discs");
  } catch (e) {
    setStatus("the address bar holds the link (the clipboard is not available here)");
  }
}

async function restoreLink(doc) {
  restoring = true;
  try {
    const mp = doc.map || {};
    let d;
    if (mp.spec) d = await postJSON("/api/map", { map: mp.spec });
    else if (mp.id) d = await getJSON(`/api/maps/${String(mp.id).split("/").map(encodeURIComponent).join("/")}`);
    else if (mp.grid) {
      const g = mp.grid;
      d = { ...g, occ: unpackBits(g.bits, g.width * g.height) };
    } else throw new Error("the link has no map");
    setMap(d, { local: !!mp.grid });
    if (mp.spec && mp.spec.paper) {
      $("map-select").value = "paper"; $("map-seed").value = mp.spec.paper.seed ?? 0;
    } else if (mp.id) $("map-select").value = mp.id;
    if (inside(state.map, doc.start)) state.start = doc.start;
    if (inside(state.map, doc.goal)) state.goal = doc.goal;
    $("robot-radius").value = doc.radius ?? 0.2; lastRadius = $("robot-radius").value;
    const planners = doc.planners || {};
    for (const f of state.forms) {
      f.reset();
      f.check.checked = Object.hasOwn(planners, f.name);
      if (f.check.checked) f.set(planners[f.name]);
    }
    for (const [id, v] of Object.entries(doc.sim || {})) if (SIM_FIELDS.includes(id)) $(id).value = v;
    for (const id of LAYER_FIELDS) $(id).checked = (doc.layers || []).includes(id);
    scene.obstacles = Array.isArray(doc.obstacles) ? doc.obstacles.filter(plausibleDisc) : [];
    if (doc.scene) { scene.name = doc.scene.name || "playground"; scene.extra = doc.scene.extra || {}; }
    state.only = doc.only && Object.hasOwn(planners, doc.only) ? doc.only : null;
    history.done = []; history.undone = []; history.onChange();
  } finally {
    restoring = false;
  }
  renderDiscs();
  renderTable();
  search.clear();
  requestPlan("now");
  if ($("layer-heat").checked || $("layer-arrows").checked) scheduleField();
  view.redraw();
  document.body.dataset.restored = String((Number(document.body.dataset.restored) || 0) + 1);
}

window.addEventListener("hashchange", async () => {
  if (location.hash === lastHash) return;
  try {
    const doc = await decodeState(location.hash);
    if (doc) { lastHash = location.hash; await restoreLink(doc); }
  } catch (e) { $("map-error").textContent = `link: ${e.message}`; }
});

// ---------------------------------------------------------------- PNG
// the view as it is, and beside it a legend of the paths shown (colour, planner, length)
function exportPNG() {
  const c = $("canvas"), dpr = view.dpr;
  const rows = [];
  for (const f of state.forms) {
    const r = state.results.get(f.name);
    if (!r || (state.only && state.only !== f.name) || search.active) continue;
    const text = r.error ? `${f.name}: error` : r.status === "SUCCESS"
      ? `${f.name}: ${r.length.toFixed(2)} m` : `${f.name}: ${r.status}`;
    rows.push([colorOf(f.name), text]);
  }
  if (search.active) {
    rows.push([colorOf(search.anim.name), `${search.anim.name}: A* search, ${search.k} / ${search.n} cells expanded`]);
  }
  const m = state.map;
  const lines = [m.name, `${m.width} × ${m.height} cells of ${m.resolution} m`];
  const probe = document.createElement("canvas").getContext("2d");
  probe.font = "12px system-ui, sans-serif";
  const wText = Math.max(...lines.map((t) => probe.measureText(t).width),
                         ...rows.map((r) => probe.measureText(r[1]).width + 22));
  const panel = Math.ceil(wText + 24);  // CSS pixels
  const out = document.createElement("canvas");
  out.width = c.width + Math.round(panel * dpr); out.height = c.height;
  const g = out.getContext("2d");
  g.fillStyle = "#e9ecef"; g.fillRect(0, 0, c.width, c.height);
  g.drawImage(c, 0, 0);
  g.scale(dpr, dpr);
  const x0 = c.width / dpr;
  g.fillStyle = "#fff"; g.fillRect(x0, 0, panel, c.height / dpr);
  g.fillStyle = "#d8dde3"; g.fillRect(x0, 0, 1, c.height / dpr);
  g.font = "12px system-ui, sans-serif"; g.textBaseline = "middle"; g.fillStyle = "#1d232b";
  lines.forEach((t, i) => g.fillText(t, x0 + 12, 16 + 16 * i));
  rows.forEach(([col, text], i) => {
    const y = 58 + 18 * i;
    g.strokeStyle = col; g.lineWidth = 3;
    g.beginPath(); g.moveTo(x0 + 12, y); g.lineTo(x0 + 28, y); g.stroke();
    g.fillStyle = "#1d232b"; g.fillText(text, x0 + 34, y);
  });
  out.toBlob((blob) => download(blob, `pathfuse-${m.name.replace(/[^\w.-]+/g, "_")}.png`), "image/png");
}

// ---------------------------------------------------------------- the results table's height
function setupSplitter() {
  const split = $("split"), box = $("results-box"), stage = $("stage");
  const maxH = () => Math.max(40, stage.getBoundingClientRect().height - 160);
  const setH = (h) => {
    h = Math.round(Math.min(Math.max(h, 0), maxH()));
    box.style.height = `${h}px`;
    box.classList.add("sized");
    split.setAttribute("aria-valuenow", String(h));
  };
  let y0 = null, h0 = 0;
  split.addEventListener("pointerdown", (e) => {
    split.setPointerCapture(e.pointerId);
    y0 = e.clientY; h0 = box.getBoundingClientRect().height;
  });
  split.addEventListener("pointermove", (e) => { if (y0 !== null) setH(h0 - (e.clientY - y0)); });
  const end = () => { y0 = null; };
  split.addEventListener("pointerup", end);
  split.addEventListener("pointercancel", end);
  split.addEventListener("keydown", (e) => {
    const h = box.getBoundingClientRect().height;
    if (e.key === "ArrowUp") setH(h + 24);
    else if (e.key === "ArrowDown") setH(h - 24);
    else if (e.key === "End") setH(maxH());
    else if (e.key === "Home") setH(0);
    else return;
    e.preventDefault();
  });
  // a double click: every row, or back to the automatic height
  split.addEventListener("dblclick", () => {
    if (box.classList.contains("sized")) { box.classList.remove("sized"); box.style.height = ""; }
    else setH($("results").getBoundingClientRect().height);
  });
}

// ---------------------------------------------------------------- start
async function init() {
  const [planners, maps, scenarios] = await Promise.all([
    getJSON("/api/planners"), getJSON("/api/maps"), getJSON("/api/scenarios")]);
  const box = $("planners");
  planners.forEach((p, i) => {
    const f = plannerForm(p, PALETTE[i % PALETTE.length], () => {
      if (restoring) return;
      edited();
    });
    if (p.name === "astar" || p.name === "fusion") f.check.checked = true;
    state.forms.push(f);
    box.append(f.box);
  });
  for (const p of planners.filter((x) => x.online)) {
    $("sim-planner").append(el("option", { value: p.name, text: p.name, selected: p.name === "fusion" }));
  }
  for (const f of searchPlanners()) {
    $("search-planner").append(el("option", { value: f.name, text: f.name, selected: f.name === "astar" }));
  }
  for (const m of maps.maps) $("map-select").append(el("option", { value: m.id, text: m.id === "paper" ? m.name : m.id }));
  $("scenario-select").append(el("option", { value: "", text: "scenario…" }));
  for (const s of scenarios.scenarios) $("scenario-select").append(el("option", { value: s.id, text: s.id }));
  $("map-seed").value = 5;
  $("map-load").addEventListener("click", loadSelectedMap);
  $("map-select").addEventListener("change", loadSelectedMap);
  $("blank-make").addEventListener("click", blankMap);
  $("map-file").addEventListener("change", uploadMap);
  $("plan-btn").addEventListener("click", () => requestPlan("now"));
  lastRadius = $("robot-radius").value;
  $("robot-radius").addEventListener("change", () => {
    history.push(snapshot({ radius: lastRadius }));
    lastRadius = $("robot-radius").value;
    edited();
  });
  $("auto-plan").addEventListener("change", () => { if ($("auto-plan").checked) edited(); });
  for (const id of ["layer-closed", "layer-cspace", "layer-attract"]) {
    $(id).addEventListener("change", () => { updateLayers(); requestPlan("now"); scheduleShare(); });
  }
  $("layer-heat").addEventListener("change", () => { if (state.field) drawHeat(); loadField(); scheduleShare(); });
  $("layer-arrows").addEventListener("change", () => { loadField(); scheduleShare(); });
  $("heat-kind").addEventListener("change", drawHeat);
  $("attract-step").addEventListener("input", showAttractInfo);
  $("sim-run").addEventListener("click", runEpisode);
  $("sim-export").addEventListener("click", exportScene);
  $("discs-clear").addEventListener("click", () => { scene.clear(); player.unload(); });
  for (const id of SIM_FIELDS) $(id).addEventListener("change", scheduleShare);
  scene.onChange = () => { renderDiscs(); player.unload(); scheduleShare(); view.redraw(); };
  $("scenario-load").addEventListener("click", loadScenario);
  $("scenario-file").addEventListener("change", uploadScenario);
  $("search-start").addEventListener("click", startSearch);
  $("search-close").addEventListener("click", () => { if (searchCtrl) searchCtrl.abort(); search.clear(); });
  $("undo").addEventListener("click", undo);
  $("redo").addEventListener("click", redo);
  $("fit").addEventListener("click", () => view.fit());
  $("clear-walls").addEventListener("click", clearWalls);
  $("random-map").addEventListener("click", randomMap);
  $("maze-map").addEventListener("click", mazeMap);
  $("png").addEventListener("click", exportPNG);
  $("share").addEventListener("click", copyLink);
  document.addEventListener("keydown", (e) => {
    const t = e.target;  // a text field keeps its own undo
    const typing = t && (t.tagName === "TEXTAREA" || t.isContentEditable ||
      (t.tagName === "INPUT" && !["radio", "checkbox", "range", "button", "file"].includes(t.type)));
    if (typing) return;
    if (!(e.ctrlKey || e.metaKey)) return;
    const k = e.key.toLowerCase();
    if (k === "z" && !e.shiftKey) { e.preventDefault(); undo(); }
    else if ((k === "z" && e.shiftKey) || k === "y") { e.preventDefault(); redo(); }
  });
  setupSplitter();
  search.showInfo();
  let doc = null;
  try { doc = await decodeState(location.hash); } catch (e) { $("map-error").textContent = `link: ${e.message}`; }
  if (doc) {
    lastHash = location.hash;
    try { await restoreLink(doc); } catch (e) {
      $("map-error").textContent = `link: ${e.message}`;
      await loadSelectedMap();
    }
  } else await loadSelectedMap();
  history.done = []; history.undone = []; history.onChange();
  document.body.dataset.ready = "1";
}

init().catch((e) => { setStatus(e instanceof ApiError ? e.message : String(e)); });
