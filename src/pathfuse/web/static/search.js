// The animated search: the A* closed set growing in the order the search expanded its cells
// (POST /api/plan with layers ["closed"] gives that order), with the open set around it.
//
// The open set after k expansions is exactly the free neighbours (in the c-space, under the
// planner's corner rule) of the first k closed cells that are not closed themselves: every
// expansion puts each such neighbour on the open list.  So it is computed here from the
// order, not sent.

const OPEN = [244, 180, 40, 210];   // amber: on the open list
const MOVES = [[0, 1], [0, -1], [1, 0], [-1, 0], [1, 1], [1, -1], [-1, 1], [-1, -1]];

// expansions per second of the speed slider's value (0..100, logarithmic: 3 .. 100,000 / s)
export function speedOf(v) { return Math.round(10 ** (0.5 + 4.5 * Number(v) / 100)); }
export function sliderOf(eps) {
  return Math.min(100, Math.max(0, ((Math.log10(Math.max(eps, 1)) - 0.5) / 4.5) * 100));
}

export class SearchAnimation {
  // ui: {play, speed, step, info}; onState(name) is called with "playing", "paused", "done"
  // or "" (cleared)
  constructor(view, ui, onState) {
    this.view = view; this.ui = ui; this.onState = onState;
    this.k = 0; this.n = 0; this.playing = false; this.anim = null;
    this.userSpeed = false;
    ui.play.addEventListener("click", () => {
      if (!this.anim) return;
      if (this.playing) this.pause(); else this.play();
    });
    ui.speed.addEventListener("input", () => { this.userSpeed = true; this.showInfo(); });
    ui.step.addEventListener("input", () => { this.pause(); this.seek(Number(ui.step.value)); });
  }

  get active() { return this.anim !== null; }

  // a: {name, order (Int32Array of row-major cells), blocked (Uint8Array, 1 = not free in the
  // c-space), map, cutting (bool), color ([r, g, b]), result (the plan answer)}
  load(a) {
    this.stop();
    const m = a.map, W = m.width, H = m.height;
    const canvas = document.createElement("canvas");
    canvas.width = W; canvas.height = H;
    const g = canvas.getContext("2d");
    this.anim = { ...a, W, H, canvas, g, img: g.createImageData(W, H),
                  closed: new Uint8Array(W * H), open: new Uint8Array(W * H),
                  closedRGBA: [...a.color, 120] };
    this.n = a.order.length; this.k = 0;
    this.ui.step.max = this.n; this.ui.step.value = 0; this.ui.step.disabled = false;
    this.ui.play.disabled = false;
    if (!this.userSpeed) this.ui.speed.value = sliderOf(Math.max(this.n / 6, 3));  // about 6 s
    this.view.setOverlay("search", { canvas, x0: m.origin[0], y0: m.origin[1],
                                     w: W * m.resolution, h: H * m.resolution, alpha: 1 });
    this.showInfo();
  }

  // remove the animation (an edit made it stale, or the user closed it)
  clear() {
    this.stop();
    this.anim = null; this.n = 0; this.k = 0;
    this.ui.step.disabled = true; this.ui.play.disabled = true;
    this.ui.play.textContent = "Play";
    this.view.setOverlay("search", null);
    this.showInfo();
    this.onState("");
  }

  stop() { this.playing = false; }

  pause() {
    if (!this.anim) return;
    this.playing = false;
    this.ui.play.textContent = "Play";
    this.onState(this.k >= this.n ? "done" : "paused");
  }

  play() {
    const a = this.anim;
    if (!a) return;
    if (this.k >= this.n) this.seek(0);
    this.playing = true;
    this.ui.play.textContent = "Pause";
    this.onState("playing");
    let last = null, acc = 0;
    const step = (t) => {
      if (!this.playing || this.anim !== a) return;
      if (last !== null) {
        acc += ((t - last) / 1000) * speedOf(this.ui.speed.value);
        const n = Math.floor(acc);
        if (n > 0) { acc -= n; this.advance(n); }
      }
      last = t;
      if (this.k >= this.n) {
        this.playing = false;
        this.ui.play.textContent = "Play";
        this.onState("done");
        this.view.redraw();
        return;
      }
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  }

  // show the search after k expansions
  seek(k) {
    const a = this.anim;
    if (!a) return;
    k = Math.min(Math.max(Math.round(k), 0), this.n);
    if (k < this.k) {
      a.closed.fill(0); a.open.fill(0); a.img.data.fill(0);
      a.g.putImageData(a.img, 0, 0);
      this.k = 0;
    }
    this.advance(k - this.k);
    if (!this.playing) this.onState(this.k >= this.n ? "done" : "paused");
  }

  advance(count) {
    const a = this.anim;
    if (!a || count <= 0) return;
    const { W, H, order, closed, open, blocked, cutting } = a;
    const d = a.img.data;
    let r0 = H, r1 = -1, c0 = W, c1 = -1;
    const paint = (cell, rgba) => {
      const r = Math.floor(cell / W), c = cell - r * W, o = ((H - 1 - r) * W + c) * 4;
      d[o] = rgba[0]; d[o + 1] = rgba[1]; d[o + 2] = rgba[2]; d[o + 3] = rgba[3];
      if (r < r0) r0 = r;
      if (r > r1) r1 = r;
      if (c < c0) c0 = c;
      if (c > c1) c1 = c;
    };
    const free = (r, c) => r >= 0 && c >= 0 && r < H && c < W && !blocked[r * W + c];
    const end = Math.min(this.n, this.k + count);
    for (let i = this.k; i < end; i++) {
      const cell = order[i];
      closed[cell] = 1;
      paint(cell, a.closedRGBA);
      const r = Math.floor(cell / W), c = cell - r * W;
      for (const [dr, dc] of MOVES) {
        const rr = r + dr, cc = c + dc;
        if (!free(rr, cc)) continue;
        if (dr && dc && !cutting && !(free(r + dr, c) && free(r, c + dc))) continue;
        const q = rr * W + cc;
        if (!closed[q] && !open[q]) { open[q] = 1; paint(q, OPEN); }
      }
    }
    this.k = end;
    if (r1 >= 0) {
      a.g.putImageData(a.img, 0, 0, c0, H - 1 - r1, c1 - c0 + 1, r1 - r0 + 1);
    }
    this.ui.step.value = this.k;
    this.showInfo();
    this.view.redraw();
  }

  // the cells closed and open now (for the tests and the curious)
  counts() {
    const a = this.anim;
    if (!a) return { closed: 0, open: 0 };
    let o = 0;
    for (let i = 0; i < a.open.length; i++) if (a.open[i] && !a.closed[i]) o++;
    return { closed: this.k, open: o };
  }

  showInfo() {
    const eps = speedOf(this.ui.speed.value);
    this.ui.info.textContent = this.anim
      ? `${this.anim.name}: ${this.k} / ${this.n} expansions, ${eps} / s`
      : `${eps} expansions / s`;
  }

  // the path, once the search has reached the goal (drawn by the page's drawer)
  finishedPath() {
    return this.anim && this.k >= this.n ? this.anim.result.path : null;
  }
}
