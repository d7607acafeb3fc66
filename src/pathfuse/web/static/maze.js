// A seeded maze drawn into a map of any size: corridors `corridor` cells wide between walls
// one cell thick, carved by a depth-first search (a "perfect" maze: one way between any two
// rooms).  The page builds it here and sends it as an edited grid.

// a small seeded generator (mulberry32): the same seed gives the same maze
export function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

// occupancy (Uint8Array, row 0 = bottom) of a W x H maze, and the first and last rooms'
// centre cells [row, col]; null when the map is too small for 2 x 2 rooms
export function maze(W, H, corridor, seed) {
  const w = Math.max(1, Math.floor(corridor)), p = w + 1;
  const nx = Math.floor((W - 1) / p), ny = Math.floor((H - 1) / p);
  if (nx < 2 || ny < 2) return null;
  const occ = new Uint8Array(W * H).fill(1);
  const carve = (r0, c0, h, wd) => {
    for (let r = r0; r < r0 + h; r++) for (let c = c0; c < c0 + wd; c++) occ[r * W + c] = 0;
  };
  const room = (i, j) => [1 + j * p, 1 + i * p];  // [row, col] of room (i = x, j = y)
  const seen = new Uint8Array(nx * ny);
  const next = rng(seed);
  const stack = [[0, 0]];
  seen[0] = 1;
  carve(...room(0, 0), w, w);
  const moves = [[1, 0], [-1, 0], [0, 1], [0, -1]];
  while (stack.length) {
    const [i, j] = stack[stack.length - 1];
    const open = moves.map(([di, dj]) => [i + di, j + dj])
      .filter(([a, b]) => a >= 0 && b >= 0 && a < nx && b < ny && !seen[b * nx + a]);
    if (!open.length) { stack.pop(); continue; }
    const [a, b] = open[Math.floor(next() * open.length)];
    seen[b * nx + a] = 1;
    const [r0, c0] = room(i, j), [r1, c1] = room(a, b);
    carve(...room(a, b), w, w);
    // the wall between the two rooms
    carve(Math.min(r0, r1), Math.min(c0, c1), Math.abs(r1 - r0) + w, Math.abs(c1 - c0) + w);
    stack.push([a, b]);
  }
  const half = Math.floor(w / 2);
  const [sr, sc] = room(0, 0), [gr, gc] = room(nx - 1, ny - 1);
  return { occ, start: [sr + half, sc + half], goal: [gr + half, gc + half] };
}
