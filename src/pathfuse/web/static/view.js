// The canvas: the map as an image (one pixel per cell), overlays in world metres,
// zoom and pan.  World y grows upwards (ROS convention); cell row 0 is the bottom row.

export class View {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.map = null;
    this.cx = 0; this.cy = 0; this.scale = 20;  // world centre of the view, pixels per metre
    this.mapCanvas = document.createElement("canvas");
    this.overlays = new Map();  // name -> {canvas, x0, y0, w, h, alpha}
    this.drawers = [];          // functions (ctx, view) drawing in world coordinates
    this.pending = false;
    this.holding = false;  // set while the pointer drags something on the canvas
    this.onFrame = null;
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  resize() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    this.canvas.width = Math.max(1, Math.round(r.width * dpr));
    this.canvas.height = Math.max(1, Math.round(r.height * dpr));
    this.dpr = dpr;
    // a drag in progress keeps the world where it is under the pointer
    if (this.fitted && !this.holding) this.fit(); else this.redraw();
  }

  setMap(map) {
    this.map = map;
    const c = this.mapCanvas;
    c.width = map.width; c.height = map.height;
    const g = c.getContext("2d");
    this.mapImage = g.createImageData(map.width, map.height);
    this.paintAll();
  }

  paintAll() {
    this.paintRect(0, 0, this.map.width, this.map.height);
  }

  // refresh the cells of rows r0..r1-1, cols c0..c1-1 of the map image
  paintRect(c0, r0, c1, r1) {
    const m = this.map, d = this.mapImage.data, W = m.width, H = m.height;
    for (let r = r0; r < r1; r++) {
      const py = H - 1 - r;
      for (let c = c0; c < c1; c++) {
        const o = (py * W + c) * 4, v = m.occ[r * W + c] ? 38 : 255;
        d[o] = v; d[o + 1] = v; d[o + 2] = v + (v < 128 ? 6 : 0); d[o + 3] = 255;
      }
    }
    const g = this.mapCanvas.getContext("2d");
    g.putImageData(this.mapImage, 0, 0, c0, H - r1, c1 - c0, r1 - r0);
    this.redraw();
  }

  fit() {
    const m = this.map;
    if (!m) return;
    const wm = m.width * m.resolution, hm = m.height * m.resolution;
    this.cx = m.origin[0] + wm / 2; this.cy = m.origin[1] + hm / 2;
    const w = this.canvas.width / this.dpr, h = this.canvas.height / this.dpr;
    this.scale = 0.94 * Math.min(w / wm, h / hm);
    this.fitted = true;
    this.redraw();
  }

  // CSS pixels <-> world metres
  toScreen(x, y) {
    const w = this.canvas.width / this.dpr, h = this.canvas.height / this.dpr;
    return [w / 2 + (x - this.cx) * this.scale, h / 2 - (y - this.cy) * this.scale];
  }
  toWorld(px, py) {
    const w = this.canvas.width / this.dpr, h = this.canvas.height / this.dpr;
    return [this.cx + (px - w / 2) / this.scale, this.cy - (py - h / 2) / this.scale];
  }
  cellAt(x, y) {
    const m = this.map;
    return [Math.floor((y - m.origin[1]) / m.resolution), Math.floor((x - m.origin[0]) / m.resolution)];
  }

  zoomAt(px, py, factor) {
    const [x, y] = this.toWorld(px, py);
    this.scale = Math.min(Math.max(this.scale * factor, 1e-3), 1e5);
    const [x2, y2] = this.toWorld(px, py);
    this.cx += x - x2; this.cy += y - y2;
    this.fitted = false;
    this.redraw();
  }
  panBy(dpx, dpy) {
    this.cx -= dpx / this.scale; this.cy += dpy / this.scale;
    this.fitted = false;
    this.redraw();
  }

  setOverlay(name, ov) {
    if (ov) this.overlays.set(name, ov); else this.overlays.delete(name);
    this.redraw();
  }

  redraw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame((t) => { this.pending = false; this.draw(t); });
  }

  draw(t) {
    const ctx = this.ctx, dpr = this.dpr;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    const m = this.map;
    if (!m) return;
    const w = this.canvas.width / dpr, h = this.canvas.height / dpr;
    // world -> CSS pixels -> device pixels
    ctx.setTransform(dpr * this.scale, 0, 0, -dpr * this.scale,
                     dpr * (w / 2 - this.cx * this.scale), dpr * (h / 2 + this.cy * this.scale));
    ctx.imageSmoothingEnabled = false;
    const wm = m.width * m.resolution, hm = m.height * m.resolution;
    // the image is drawn upside down in a y-up frame: flip it back
    ctx.save();
    ctx.translate(m.origin[0], m.origin[1] + hm);
    ctx.scale(1, -1);
    ctx.drawImage(this.mapCanvas, 0, 0, m.width, m.height, 0, 0, wm, hm);
    for (const ov of this.overlays.values()) {
      ctx.globalAlpha = ov.alpha ?? 1;
      ctx.drawImage(ov.canvas, ov.x0 - m.origin[0], m.origin[1] + hm - (ov.y0 + ov.h), ov.w, ov.h);
    }
    ctx.restore();
    ctx.globalAlpha = 1;
    ctx.lineWidth = 1 / this.scale;
    if (this.scale * m.resolution >= 12 && m.width * m.height <= 256 * 256) {
      // cell lines when the cells are big on the screen
      ctx.beginPath();
      for (let c = 1; c < m.width; c++) {
        const x = m.origin[0] + c * m.resolution;
        ctx.moveTo(x, m.origin[1]); ctx.lineTo(x, m.origin[1] + hm);
      }
      for (let r = 1; r < m.height; r++) {
        const y = m.origin[1] + r * m.resolution;
        ctx.moveTo(m.origin[0], y); ctx.lineTo(m.origin[0] + wm, y);
      }
      ctx.strokeStyle = "rgba(100,116,139,.18)";
      ctx.stroke();
    }
    ctx.strokeStyle = "#98a2b3";
    ctx.strokeRect(m.origin[0], m.origin[1], wm, hm);
    for (const f of this.drawers) { ctx.save(); f(ctx, this); ctx.restore(); }
    if (this.onFrame) this.onFrame(t);
  }

  // helpers for drawers: sizes in CSS pixels whatever the zoom
  px(n) { return n / this.scale; }

  polyline(ctx, pts, color, widthPx, dash) {
    if (!pts || pts.length < 2) return;
    ctx.beginPath();
    ctx.moveTo(pts[0][0], pts[0][1]);
    for (let i = 1; i < pts.length; i++) ctx.lineTo(pts[i][0], pts[i][1]);
    ctx.strokeStyle = color; ctx.lineWidth = this.px(widthPx);
    ctx.lineJoin = "round"; ctx.lineCap = "round";
    ctx.setLineDash(dash ? dash.map((d) => this.px(d)) : []);
    ctx.stroke();
    ctx.setLineDash([]);
  }

  disc(ctx, x, y, r, fill, stroke, widthPx = 1) {
    ctx.beginPath();
    ctx.arc(x, y, r, 0, 2 * Math.PI);
    if (fill) { ctx.fillStyle = fill; ctx.fill(); }
    if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = this.px(widthPx); ctx.stroke(); }
  }

  arrow(ctx, x, y, dx, dy, color, widthPx = 1.5) {
    const len = Math.hypot(dx, dy);
    if (!(len > 0)) return;
    const hx = x + dx, hy = y + dy, ux = dx / len, uy = dy / len;
    const head = Math.min(len * 0.35, this.px(8));
    ctx.beginPath();
    ctx.moveTo(x, y); ctx.lineTo(hx, hy);
    ctx.moveTo(hx - head * (ux - 0.5 * uy), hy - head * (uy + 0.5 * ux));
    ctx.lineTo(hx, hy);
    ctx.lineTo(hx - head * (ux + 0.5 * uy), hy - head * (uy - 0.5 * ux));
    ctx.strokeStyle = color; ctx.lineWidth = this.px(widthPx);
    ctx.stroke();
  }
}

// an offscreen canvas of w x h pixels filled by fn(i, j) -> [r, g, b, a] (row i from the top)
export function makeImage(w, h, fn) {
  const c = document.createElement("canvas");
  c.width = w; c.height = h;
  const g = c.getContext("2d");
  const img = g.createImageData(w, h);
  const d = img.data;
  for (let i = 0; i < h; i++) {
    for (let j = 0; j < w; j++) {
      const v = fn(i, j);
      if (!v) continue;
      const o = (i * w + j) * 4;
      d[o] = v[0]; d[o + 1] = v[1]; d[o + 2] = v[2]; d[o + 3] = v[3];
    }
  }
  g.putImageData(img, 0, 0);
  return c;
}

// a perceptual colour ramp (dark blue -> teal -> yellow), t in [0, 1]
const STOPS = [[48, 18, 59], [50, 100, 200], [30, 180, 160], [150, 215, 70], [250, 235, 40]];
export function ramp(t) {
  t = Math.min(Math.max(t, 0), 1) * (STOPS.length - 1);
  const i = Math.min(Math.floor(t), STOPS.length - 2), f = t - i;
  const a = STOPS[i], b = STOPS[i + 1];
  return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])];
}
