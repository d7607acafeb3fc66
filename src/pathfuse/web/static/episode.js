// Moving obstacles: the discs of the scene, and the playback of an episode run by the server.

import { el } from "./forms.js";

export class Scene {
  constructor(onChange) {
    this.obstacles = [];   // scenario obstacle specs, as in a scenario file
    this.extra = {};       // the other scenario keys of a loaded scenario (seed, stall_time, ...)
    this.name = "playground";
    this.onChange = onChange;
  }

  add(spec) { this.obstacles.push(spec); this.onChange(); }
  remove(i) { this.obstacles.splice(i, 1); this.onChange(); }
  clear() { this.obstacles = []; this.onChange(); }

  // where each disc starts, and its velocity arrow when it has one
  starts() {
    return this.obstacles.map((o) => {
      if (o.position) return { p: o.position, v: o.velocity, r: o.radius };
      if (o.waypoints) return { p: o.waypoints[0], r: o.radius, way: o.waypoints };
      if (o.random_walk) return { p: o.random_walk.position, r: o.radius, walk: true };
      return null;
    }).filter(Boolean);
  }

  renderList(box) {
    box.replaceChildren();
    this.obstacles.forEach((o, i) => {
      let text;
      const f = (v) => Number(v).toFixed(2);
      if (o.position) text = `disc ${i}: (${f(o.position[0])}, ${f(o.position[1])}) v (${f(o.velocity[0])}, ${f(o.velocity[1])}) m/s r ${f(o.radius)} m`;
      else if (o.waypoints) text = `disc ${i}: patrol of ${o.waypoints.length} points at ${f(o.speed)} m/s r ${f(o.radius)} m`;
      else text = `disc ${i}: random walk at ${f(o.random_walk.speed)} m/s r ${f(o.radius)} m`;
      const del = el("button", { text: "×", title: "remove this disc" });
      del.addEventListener("click", () => this.remove(i));
      box.append(el("div", { className: "disc" }, el("span", { text }), del));
    });
  }
}

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
