// Moving obstacles: the discs of the scene, and the playback of an episode run by the server.

import { el } from "./forms.js";

export class Scene {
  constructor(onChange) {
    this.obstacles = [];   // scenario obstacle specs, as in a scenario file
    this.extra = {};       // the other scenario keys of a loaded scenario (seed, stall_time, ...)
    this.name = "playground";
    this.onChange = onChange;
    this.check = () => "";  // (spec, i) -> "" or why the disc cannot be there (set by the page)
    this.onError = () => {};
    this.beforeChange = () => {};  // called before every change (the page's undo)
  }

  add(spec) {
    const why = this.check(spec, this.obstacles.length);
    if (why) { this.onError(why); return false; }
    this.beforeChange();
    this.obstacles.push(spec); this.onChange(); return true;
  }
  remove(i) { this.beforeChange(); this.obstacles.splice(i, 1); this.onChange(); }
  clear() {
    if (!this.obstacles.length) return;
    this.beforeChange(); this.obstacles = []; this.onChange();
  }

  // replace disc i by spec when it is valid there; returns "" or the reason it is not
  replace(i, spec) {
    const why = this.check(spec, i);
    if (why) { this.onError(why); return why; }
    this.beforeChange();
    this.obstacles[i] = spec; this.onChange(); return "";
  }

  // where each disc starts, and its velocity arrow when it has one
  starts() {
    return this.obstacles.map((o) => {
      if (o.position) return { p: o.position, v: o.velocity, r: o.radius };
      if (o.waypoints) return { p: o.waypoints[0], r: o.radius, way: o.waypoints };
      if (o.random_walk) return { p: o.random_walk.position, r: o.radius, walk: true };
      return null;
    });
  }

  // the disc part under world point w (scale: pixels per metre): its velocity arrow's head,
  // its rim or its inside, the topmost (last placed) first
  hit(w, scale) {
    const st = this.starts();
    for (let i = st.length - 1; i >= 0; i--) {
      const s = st[i];
      if (!s) continue;
      if (s.v) {
        const hx = s.p[0] + s.v[0], hy = s.p[1] + s.v[1];
        if (Math.hypot(w[0] - hx, w[1] - hy) * scale < 9) return { i, part: "head" };
      }
      const d = Math.hypot(w[0] - s.p[0], w[1] - s.p[1]);
      if (Math.abs(d - s.r) * scale < 6 && s.r * scale >= 8) return { i, part: "rim" };
      if (d < s.r || d * scale < 8) return { i, part: "centre" };
    }
    return null;
  }

  // a copy of disc spec o moved by (dx, dy), with radius r, velocity v (when given)
  static edited(o, { dx = 0, dy = 0, r = null, v = null } = {}) {
    const q = JSON.parse(JSON.stringify(o));
    const mv = (p) => [round(p[0] + dx), round(p[1] + dy)];
    if (q.position) q.position = mv(q.position);
    if (q.waypoints) q.waypoints = q.waypoints.map(mv);
    if (q.random_walk && q.random_walk.position) q.random_walk.position = mv(q.random_walk.position);
    if (r != null) q.radius = round(r);
    if (v != null && q.velocity) q.velocity = [round(v[0]), round(v[1])];
    return q;
  }

  // problems: per disc, "" or why it cannot be where it is (after an edit of the map)
  renderList(box, problems = []) {
    box.replaceChildren();
    this.obstacles.forEach((o, i) => {
      let text;
      const f = (v) => Number(v).toFixed(2);
      const v = o.velocity || [0, 0];
      if (o.position) text = `disc ${i}: (${f(o.position[0])}, ${f(o.position[1])}) v (${f(v[0])}, ${f(v[1])}) m/s`;
      else if (o.waypoints) text = `disc ${i}: patrol of ${o.waypoints.length} points at ${f(o.speed)} m/s`;
      else text = `disc ${i}: random walk at ${f(o.random_walk.speed)} m/s`;
      const r = el("input", { type: "number", min: "0.01", step: "0.05", value: o.radius,
                              title: "radius (m)", "aria-label": `disc ${i} radius` });
      r.addEventListener("change", () => {
        const raw = r.value, v = Number(raw);
        if (!(v > 0)) {
          this.onError(`obstacles[${i}].radius: must be a number > 0, got ${JSON.stringify(raw)}`);
          r.value = o.radius;
        } else if (this.replace(i, Scene.edited(o, { r: v }))) r.value = o.radius;
      });
      const del = el("button", { text: "×", title: "remove this disc", "aria-label": `remove disc ${i}` });
      del.addEventListener("click", () => this.remove(i));
      const row = el("div", { className: "disc" }, el("span", { text }),
        el("label", { className: "inline", text: "r " }, r), del);
      if (problems[i]) {
        row.classList.add("bad");
        row.append(el("div", { className: "error small", text: problems[i] }));
      }
      box.append(row);
    });
  }
}

function round(v) { return Math.round(v * 1000) / 1000; }

// playback of an episode (the answer of POST /api/simulate) at real time x speed
export class Player {
  constructor(view, ui, onTick) {
    this.view = view; this.ui = ui; this.onTick = onTick;
    this.ep = null; this.tick = 0; this.playing = false;
    this.last = null; this.acc = 0; this.frameTimes = [];
    this.stats = null;
    ui.play.addEventListener("click", () => (this.playing ? this.pause() : this.play()));
    ui.time.addEventListener("input", () => { this.pause(); this.seek(Number(ui.time.value)); });
  }

  load(ep) {
    this.ep = ep; this.tick = 0; this.playing = false;
    this.ui.time.max = ep.n_ticks; this.ui.time.value = 0;
    this.ui.time.disabled = false; this.ui.play.disabled = false;
    this.ui.play.textContent = "Play";
    this.onTick(0);
    this.view.redraw();
  }

  unload() {
    this.pause();
    this.ep = null;
    this.onTick(0);
    this.ui.time.disabled = true; this.ui.play.disabled = true;
    this.view.redraw();
  }

  seek(k) {
    if (!this.ep) return;
    this.tick = Math.min(Math.max(k, 0), this.ep.n_ticks);
    this.ui.time.value = this.tick;
    this.onTick(this.tick);
    this.view.redraw();
  }

  play() {
    if (!this.ep) return;
    if (this.tick >= this.ep.n_ticks) this.seek(0);
    this.playing = true; this.last = null; this.acc = 0; this.frameTimes = [];
    this.ui.play.textContent = "Pause";
    const step = (t) => {
      if (!this.playing) return;
      this.frameTimes.push(t);
      if (this.last !== null) {
        this.acc += ((t - this.last) / 1000) * Number(this.ui.speed.value);
        const dt = this.ep.dt;
        const n = Math.floor(this.acc / dt);
        if (n > 0) { this.acc -= n * dt; this.seek(this.tick + n); }
      }
      this.last = t;
      if (this.tick >= this.ep.n_ticks) { this.finish(); return; }
      this.view.redraw();
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  }

  finish() {
    this.playing = false;
    this.ui.play.textContent = "Play";
    const ft = this.frameTimes;
    if (ft.length > 2) {
      const gaps = ft.slice(1).map((t, i) => t - ft[i]).sort((a, b) => a - b);
      const dur = (ft[ft.length - 1] - ft[0]) / 1000;
      this.stats = {
        frames: ft.length, seconds: dur, fps: (ft.length - 1) / dur,
        median_frame_ms: gaps[Math.floor(gaps.length / 2)],
        p95_frame_ms: gaps[Math.floor(gaps.length * 0.95)],
        max_frame_ms: gaps[gaps.length - 1],
        discs: this.ep.obstacle_radii.length,
      };
    }
    document.body.dataset.playback = "ended";
  }

  pause() {
    this.playing = false;
    this.ui.play.textContent = "Play";
  }

  // draw the episode at the current tick (called by the view in world coordinates)
  draw(ctx, v) {
    const ep = this.ep;
    if (!ep) return;
    const k = this.tick;
    const pos = ep.positions, obs = ep.obstacle_positions, radii = ep.obstacle_radii;
    if (ep.global_path) v.polyline(ctx, ep.global_path, "rgba(37,99,235,.55)", 1.5, [5, 4]);
    // disc trails, then discs
    for (let j = 0; j < radii.length; j++) {
      ctx.beginPath();
      const k0 = Math.max(0, k - 400);
      ctx.moveTo(obs[k0][j][0], obs[k0][j][1]);
      for (let i = k0 + 1; i <= k; i++) ctx.lineTo(obs[i][j][0], obs[i][j][1]);
      ctx.strokeStyle = "rgba(217,119,6,.5)"; ctx.lineWidth = v.px(1.5); ctx.stroke();
      const seen = ep.sensed && ep.sensed[k] && ep.sensed[k][j];
      v.disc(ctx, obs[k][j][0], obs[k][j][1], radii[j], seen ? "rgba(220,38,38,.75)" : "rgba(217,119,6,.7)", "#7c2d12", 1);
    }
    // robot trail, sensing circle, robot
    v.polyline(ctx, pos.slice(0, k + 1), "#16a34a", 2);
    const [x, y] = pos[k];
    v.disc(ctx, x, y, ep.robot.sensing_radius, "rgba(22,163,74,.06)", "rgba(22,163,74,.5)", 1);
    v.disc(ctx, x, y, Math.max(ep.robot.radius, v.px(3)), "#16a34a", "#052e16", 1);
  }
}
