"""The true shortest path among the occupied squares: a visibility graph searched with A* (numba).

Definition (what ``shortest`` computes, exactly)
    For a point robot, :mod:`pathfuse.metrics` calls a path collision-free
    when it stays in the map and never *touches* an occupied square.  The
    infimum ``L*`` of the lengths of such paths is not attained: the limit
    path grazes obstacle corners and edges.  It may run along an edge and
    touch a corner, but it never passes between two squares that share only
    a corner (no collision-free path comes near that point from both sides),
    and never runs between two squares that share an edge.

    We compute the shortest path that keeps an L-infinity distance of at
    least ``rho`` from every occupied square and from the map's edge, i.e.
    among the squares grown into squares of side ``res + 2 rho``.  With
    ``rho = robot_radius + MARGIN_FRAC * res / 2`` (``5e-7`` cells for a point):

    * the path is collision-free by :mod:`pathfuse.metrics` (Euclidean
      clearance at least ``rho`` minus a ``1e-9``-cell tolerance, so > 0);
    * every path that keeps pathfuse's standard margin (Euclidean
      ``radius + MARGIN_FRAC * res``, which every pathfuse move keeps) also
      keeps L-infinity distance ``rho`` (``1/sqrt(2) > 1/2``), so no pathfuse
      planner's path is shorter, for a point robot;
    * for a point robot the length exceeds ``L*`` by at most ``2 sqrt(2) rho``
      (under ``1.5e-6`` cells) per point where the limit path touches an
      obstacle (moving such a point by ``sqrt(2) rho`` lengthens its two
      segments by at most that much each).

    For a disc robot of radius ``r`` the grown squares are the configuration
    space of an axis-aligned *square* robot of half-side ``r``, which contains
    the disc: the path keeps the disc clear, but a disc can cut the squares'
    rounded corners, so a disc planner's path can be slightly shorter than
    this reference (by up to ``2 r (sqrt(2) - 1)`` per corner turned).

Algorithm
    The shortest path among disjoint-interior polygons bends only at their
    convex corners (a taut string).  The vertices are the corners of the
    grown squares that lie in no other grown square (a corner shared by two
    squares touching diagonally, or one on another square's edge, is not
    convex) and inside the map inset by ``rho``.  A* (Euclidean heuristic,
    consistent) searches the graph lazily: from each expanded vertex every
    other vertex is a candidate; a candidate is kept only if the segment is
    tangent to both squares at its ends (the square's two edges at the corner
    lie on one side of the line: ``dx * dy <= 0`` at a bottom-left or
    top-right corner, ``>= 0`` at the other two), if it improves the
    candidate's distance and can still beat the best path to the goal, and
    if the segment enters no grown square (an exact slab test against each
    square near the segment, shrunk by ``1e-9`` cells so that running along
    an edge is allowed).  The cost is ``O(V)`` per expanded vertex.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((4, 6), dtype=bool); occ[1:3, 2] = True
>>> r = shortest_path(occ, 0.0, 0.0, 1.0, 0.0, (0.5, 0.5), (5.5, 3.5))
>>> r.status.name, np.round(r.points, 6).tolist(), round(r.length, 6)
('SUCCESS', [[0.5, 0.5], [3.0, 1.0], [5.5, 3.5]], 6.085044)
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC, _segment_hits_box
from pathfuse.result import CODE_NO_PATH, CODE_RUNNING, CODE_SUCCESS, Status
from pathfuse.search.heap import heap_pop as _pop
from pathfuse.search.heap import heap_push as _push
from pathfuse.search.thetastar import AnyAngleResult

__all__ = ["shortest_path", "convex_corners", "segment_admissible", "growth_cells", "warmup"]

_TAU = 1e-9  # cells: the grown squares are tested shrunk by this, so grazing is allowed
_CHUNK = 256  # expansions between clock checks


def growth_cells(robot_radius_m: float, res: float) -> float:
    """The growth ``rho`` of the squares, in cells: the radius plus half pathfuse's margin."""
    return robot_radius_m / res + 0.5 * MARGIN_FRAC


@njit(cache=True, inline="always")
def _corner(i, j, k, q):
    """Corner ``k`` of the square of cell ``(i, j)`` grown by ``q``: ``(x, y, type)``."""
    if k == 0:
        return j - q, i - q, 1
    if k == 1:
        return j + 1 + q, i + 1 + q, 1
    if k == 2:
        return j + 1 + q, i - q, -1
    return j - q, i + 1 + q, -1


@njit(cache=True, inline="always")
def _is_convex(occ, i, j, cx, cy, q, win):
    """Whether the corner ``(cx, cy)`` of cell ``(i, j)``'s grown square lies in the inset map
    and in no other grown square."""
    h, w = occ.shape
    if not (q <= cx <= w - q and q <= cy <= h - q):
        return False
    for i2 in range(max(i - win, 0), min(i + win, h - 1) + 1):
        for j2 in range(max(j - win, 0), min(j + win, w - 1) + 1):
            if occ[i2, j2] and (i2 != i or j2 != j) and \
                    j2 - q <= cx <= j2 + 1 + q and i2 - q <= cy <= i2 + 1 + q:
                return False
    return True


@njit(cache=True)
def convex_corners(occ, q):
    """Convex corners of the squares grown by ``q`` cells (cell units, origin 0).

    Returns ``(x, y, t)``: coordinates and the tangency type (``+1``:
    bottom-left or top-right corner, a tangent line has ``dx * dy <= 0``;
    ``-1``: bottom-right or top-left, ``dx * dy >= 0``).  Two passes (count,
    then fill), so the arrays hold exactly the corners.
    """
    h, w = occ.shape
    win = int(math.ceil(2.0 * q)) + 1
    m = 0
    for i in range(h):
        for j in range(w):
            if occ[i, j]:
                for k in range(4):
                    cx, cy, t = _corner(i, j, k, q)
                    if _is_convex(occ, i, j, cx, cy, q, win):
                        m += 1
    xs = np.empty(m)
    ys = np.empty(m)
    ts = np.empty(m, dtype=np.int64)
    m = 0
    for i in range(h):
        for j in range(w):
            if occ[i, j]:
                for k in range(4):
                    cx, cy, t = _corner(i, j, k, q)
                    if _is_convex(occ, i, j, cx, cy, q, win):
                        xs[m] = cx
                        ys[m] = cy
                        ts[m] = t
                        m += 1
    return xs, ys, ts


@njit(cache=True)
def segment_admissible(ax, ay, bx, by, occ, q):
    """Whether segment ``AB`` (cell units) enters no square grown by ``q`` (touching allowed).

    The end points must lie in the map inset by ``q`` (checked by the caller).
    Visits a strip of cells along the segment, like
    :func:`pathfuse.search.los.line_of_sight`.
    """
    h, w = occ.shape
    dx = bx - ax
    dy = by - ay
    pad = q + 1.0
    lo = -q + _TAU
    hi = 1.0 + q - _TAU
    if abs(dx) >= abs(dy):
        lo_x = min(ax, bx)
        hi_x = max(ax, bx)
        c0 = max(int(math.floor(lo_x - q)) - 1, 0)
        c1 = min(int(math.floor(hi_x + q)) + 1, w - 1)
        for c in range(c0, c1 + 1):
            xa = max(c - q - 1.0, lo_x)
            xb = min(c + 2.0 + q, hi_x)
            if dx != 0.0:
                ya = ay + dy * (xa - ax) / dx
                yb = ay + dy * (xb - ax) / dx
            else:
                ya = ay
                yb = by
            r0 = max(int(math.floor(min(ya, yb) - pad)), 0)
            r1 = min(int(math.floor(max(ya, yb) + pad)), h - 1)
            for r in range(r0, r1 + 1):
                if occ[r, c] and _segment_hits_box(ax, ay, bx, by, c + lo, r + lo, c + hi,
                                                   r + hi):
                    return False
    else:
        lo_y = min(ay, by)
        hi_y = max(ay, by)
        r0 = max(int(math.floor(lo_y - q)) - 1, 0)
        r1 = min(int(math.floor(hi_y + q)) + 1, h - 1)
        for r in range(r0, r1 + 1):
            ya = max(r - q - 1.0, lo_y)
            yb = min(r + 2.0 + q, hi_y)
            xa = ax + dx * (ya - ay) / dy
            xb = ax + dx * (yb - ay) / dy
            c0 = max(int(math.floor(min(xa, xb) - pad)), 0)
            c1 = min(int(math.floor(max(xa, xb) + pad)), w - 1)
            for c in range(c0, c1 + 1):
                if occ[r, c] and _segment_hits_box(ax, ay, bx, by, c + lo, r + lo, c + hi,
                                                   r + hi):
                    return False
    return True


@njit(cache=True)
def _vis_kernel(occ, q, xs, ys, ts, g, parent, closed, hkey, hnode, meta, max_exp):
    """A* over the visibility graph; node ``n - 2`` is the start, ``n - 1`` the goal.
    ``meta`` = [heap size, expansions].  Returns ``(code, hkey, hnode)``."""
    n = xs.shape[0]
    goal = n - 1
    gx = xs[goal]
    gy = ys[goal]
    size = meta[0]
    exp = meta[1]
    done = 0
    while size > 0:
        u, size = _pop(hkey, hnode, size)
        if closed[u]:
            continue
        if u == goal:
            meta[0] = size
            meta[1] = exp
            return CODE_SUCCESS, hkey, hnode
        closed[u] = True
        exp += 1
        done += 1
        ux = xs[u]
        uy = ys[u]
        tu = ts[u]
        gu = g[u]
        for v in range(n):
            if closed[v]:
                continue
            wx = xs[v] - ux
            wy = ys[v] - uy
            p = wx * wy
            if (tu == 1 and p > 0.0) or (tu == -1 and p < 0.0):
                continue
            tv = ts[v]
            if (tv == 1 and p > 0.0) or (tv == -1 and p < 0.0):
                continue
            nd = gu + math.sqrt(wx * wx + wy * wy)
            if nd >= g[v]:
                continue
            hv = math.hypot(gx - xs[v], gy - ys[v])
            if nd + hv >= g[goal]:
                continue
            if not segment_admissible(ux, uy, xs[v], ys[v], occ, q):
                continue
            g[v] = nd
            parent[v] = u
            hkey, hnode, size = _push(hkey, hnode, size, nd + hv, v)
        if done >= max_exp:
            meta[0] = size
            meta[1] = exp
            return CODE_RUNNING, hkey, hnode
    meta[0] = size
    meta[1] = exp
    return CODE_NO_PATH, hkey, hnode


_CORNERS: dict[tuple[tuple[int, ...], bytes, float],
               tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _corners_cached(occ: np.ndarray, q: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The convex corners of a map, cached per (map content, growth) for repeated queries."""
    key = (tuple(occ.shape), np.packbits(occ).tobytes(), q)
    hit = _CORNERS.get(key)
    if hit is None:
        if len(_CORNERS) >= 16:
            _CORNERS.clear()
        hit = _CORNERS[key] = convex_corners(np.ascontiguousarray(occ, dtype=np.bool_), q)
    return hit


def _outside_squares(x: float, y: float, occ: np.ndarray, q: float, qe: float) -> bool:
    """Whether the point (cell units) lies in the map inset by ``qe`` (the robot's radius: the
    edge rule of :func:`pathfuse.geometry.segment_is_clear`, which keeps pathfuse's margin
    from the squares only) and in no grown square's interior."""
    h, w = occ.shape
    if not (qe <= x <= w - qe and qe <= y <= h - qe):
        return False
    c0, c1 = max(int(math.floor(x - q)) - 1, 0), min(int(math.floor(x + q)) + 1, w - 1)
    r0, r1 = max(int(math.floor(y - q)) - 1, 0), min(int(math.floor(y + q)) + 1, h - 1)
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            if occ[r, c] and c - q + _TAU < x < c + 1 + q - _TAU and \
                    r - q + _TAU < y < r + 1 + q - _TAU:
                return False
    return True


def shortest_path(occ: np.ndarray, ox: float, oy: float, res: float, robot_radius_m: float,
                  start: tuple[float, float], goal: tuple[float, float],
                  max_expansions: int | None = None, time_limit_s: float | None = None,
                  upper_bound_m: float | None = None) -> AnyAngleResult:
    """The shortest path from ``start`` to ``goal`` (world metres; see the module docstring).

    ``NO_PATH`` also when the start or the goal lies within the growth
    ``rho`` (L-infinity) of a square, or within the robot's radius of the map's
    edge.  ``max_expansions`` caps the vertices expanded (``MAX_ITERATIONS``).

    ``upper_bound_m``, the length of any path (an A* path, say), speeds the
    search up without changing its answer: only corners ``v`` with ``|s v| +
    |v g|`` within the bound can lie on a shorter path (an ellipse), and the
    goal starts with that distance.  If no path within the bound is found
    (the bound was not a path's length), the search runs again without it.
    """
    t0 = time.perf_counter()
    occ = np.ascontiguousarray(occ, dtype=np.bool_)
    q = growth_cells(robot_radius_m, res)
    qe = robot_radius_m / res
    sx, sy = (start[0] - ox) / res, (start[1] - oy) / res
    gx, gy = (goal[0] - ox) / res, (goal[1] - oy) / res
    for x, y in ((sx, sy), (gx, gy)):
        if not _outside_squares(x, y, occ, q, qe):
            return AnyAngleResult(Status.NO_PATH, np.zeros((0, 2)), math.inf, 0)
    cx, cy, ct = _corners_cached(occ, q)
    used = 0
    if upper_bound_m is not None and math.isfinite(upper_bound_m):
        bound = upper_bound_m / res * (1.0 + 1e-9) + 1e-9
        keep = np.hypot(cx - sx, cy - sy) + np.hypot(cx - gx, cy - gy) <= bound
        out = _search(occ, q, cx[keep], cy[keep], ct[keep], sx, sy, gx, gy, start, goal, ox,
                      oy, res, max_expansions, time_limit_s, t0, bound)
        if out.status is not Status.NO_PATH:
            return out
        used = out.expansions
        if max_expansions is not None:
            max_expansions = max(int(max_expansions) - used, 0)
    out = _search(occ, q, cx, cy, ct, sx, sy, gx, gy, start, goal, ox, oy, res, max_expansions,
                  time_limit_s, t0, math.inf)
    out.expansions += used
    return out


def _search(occ: np.ndarray, q: float, cx: np.ndarray, cy: np.ndarray, ct: np.ndarray,
            sx: float, sy: float, gx: float, gy: float, start: tuple[float, float],
            goal: tuple[float, float], ox: float, oy: float, res: float,
            max_expansions: int | None, time_limit_s: float | None, t0: float,
            bound: float) -> AnyAngleResult:
    n = cx.shape[0] + 2
    xs = np.concatenate([cx, [sx, gx]])
    ys = np.concatenate([cy, [sy, gy]])
    ts = np.concatenate([ct, [0, 0]]).astype(np.int64)
    g = np.full(n, math.inf)
    g[n - 1] = bound
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    hkey = np.empty(max(64, n))
    hnode = np.empty(max(64, n), dtype=np.int64)
    g[n - 2] = 0.0
    parent[n - 2] = n - 2
    hkey[0] = math.hypot(gx - sx, gy - sy)
    hnode[0] = n - 2
    meta = np.array([1, 0], dtype=np.int64)
    budget = n if max_expansions is None else int(max_expansions)
    while True:
        step = min(_CHUNK, budget - int(meta[1]))
        if step <= 0:
            return AnyAngleResult(Status.MAX_ITERATIONS, np.zeros((0, 2)), math.inf,
                                  int(meta[1]))
        code, hkey, hnode = _vis_kernel(occ, q, xs, ys, ts, g, parent, closed, hkey, hnode,
                                        meta, step)
        if code == CODE_SUCCESS and parent[n - 1] >= 0:
            chain = [n - 1]
            while chain[-1] != n - 2:
                chain.append(int(parent[chain[-1]]))
            idx = np.array(chain[::-1])
            pts = np.column_stack([ox + xs[idx] * res, oy + ys[idx] * res])
            pts[0] = start
            pts[-1] = goal
            return AnyAngleResult(Status.SUCCESS, pts, float(g[n - 1]) * res, int(meta[1]))
        if code != CODE_RUNNING:
            return AnyAngleResult(Status.NO_PATH, np.zeros((0, 2)), math.inf, int(meta[1]))
        if int(meta[1]) >= budget:
            return AnyAngleResult(Status.MAX_ITERATIONS, np.zeros((0, 2)), math.inf,
                                  int(meta[1]))
        if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
            return AnyAngleResult(Status.TIMEOUT, np.zeros((0, 2)), math.inf, int(meta[1]))


_WARM = [False]


def warmup() -> None:
    """Compile (or load from numba's cache) the kernels of :func:`shortest_path`."""
    if _WARM[0]:
        return
    occ = np.zeros((3, 4), dtype=bool)
    occ[1, 1] = True
    occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
    shortest_path(occ, 0.0, 0.0, 1.0, 0.0, (0.5, 0.5), (3.5, 2.5))
    _WARM[0] = True
