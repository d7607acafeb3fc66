"""Path metrics, the same for every planner and computed without any planner code.

Geometry: obstacles are the *closed* occupied cell squares of the map.  A
path is the polyline through its points.

* :func:`min_clearance` -- exact distance from the polyline to the nearest
  occupied square (0 when it touches or enters one; ``inf`` on a map without
  obstacles).  Computed per segment with an exact segment-to-square distance
  (a slab intersection test, then the vertex-to-edge distances of the two
  convex shapes); candidate squares come from a k-d tree over the occupied
  cell centres, searched with a radius that provably contains the nearest
  square.
* :func:`collision_free` -- every point inside the map rectangle and, for a
  point robot (``robot_radius_m == 0``), no contact with any occupied square:
  touching counts, so a diagonal that squeezes through the shared corner of
  two occupied cells is a collision; for a disc robot, clearance ``>=`` the
  radius (a disc that exactly touches a wall is allowed, as in
  :meth:`pathfuse.grid.GridMap.inflate`).
* :func:`path_length` (m), :func:`smoothness` (sum of absolute heading
  changes between successive non-zero segments, radians), :func:`n_steps`
  (segments), :func:`r_ratio` (paper eq. 10-11), and :func:`evaluate`, all of
  them for a :class:`~pathfuse.result.PlanResult`.

Examples
--------
>>> import numpy as np
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["...", ".#.", "..."])          # obstacle square [1, 2] x [1, 2]
>>> p = np.array([[0.5, 0.5], [2.5, 0.5], [2.5, 2.5]])
>>> path_length(p), round(min_clearance(g, p), 6), collision_free(g, p)
(4.0, 0.5, True)
>>> collision_free(g, np.array([[0.5, 0.5], [2.5, 2.5]]))    # straight through it
False
>>> round(smoothness(p), 6)                                  # one 90 degree turn
1.570796
>>> round(r_ratio(14.2182, 14.7279), 4)                      # paper Table I, fusion vs A*
-0.0346
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, PlanResult, QueryError

__all__ = [
    "path_length",
    "n_steps",
    "smoothness",
    "segment_clearances",
    "min_clearance",
    "collision_free",
    "in_bounds",
    "r_ratio",
    "evaluate",
]

_TREES: weakref.WeakKeyDictionary[GridMap, tuple[cKDTree, np.ndarray] | None] = (
    weakref.WeakKeyDictionary()
)


def _path(path: object) -> np.ndarray:
    p = np.asarray(path, dtype=np.float64)
    if p.size == 0:
        return np.zeros((0, 2))
    if p.ndim != 2 or p.shape[1] != 2:
        raise QueryError(f"a path must have shape (N, 2), got {p.shape}")
    if not np.all(np.isfinite(p)):
        bad = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
        raise QueryError(f"path point {bad} is not finite: {p[bad].tolist()}")
    return p


def path_length(path: object) -> float:
    """Sum of the segment lengths, metres (0 for fewer than two points).

    >>> path_length([[0, 0], [3, 4], [3, 5]])
    6.0
    """
    p = _path(path)
    if p.shape[0] < 2:
        return 0.0
    d = np.diff(p, axis=0)
    return float(np.sqrt((d * d).sum(axis=1)).sum())


def n_steps(path: object) -> int:
    """Number of segments, ``max(N - 1, 0)``.

    >>> n_steps([[0, 0], [1, 0], [2, 0]])
    2
    """
    return max(_path(path).shape[0] - 1, 0)


def smoothness(path: object) -> float:
    """Sum of absolute heading changes between successive segments, radians.

    Zero-length segments are skipped; each change is wrapped into
    ``[-pi, pi]``, so a U-turn counts ``pi``.

    >>> round(smoothness([[0, 0], [1, 0], [1, 1], [0, 1]]), 6)
    3.141593
    >>> smoothness([[0, 0], [1, 1], [1, 1], [2, 2]])
    0.0
    """
    p = _path(path)
    if p.shape[0] < 3:
        return 0.0
    d = np.diff(p, axis=0)
    d = d[(d != 0).any(axis=1)]
    if d.shape[0] < 2:
        return 0.0
    h = np.arctan2(d[:, 1], d[:, 0])
    dh = np.diff(h)
    dh = (dh + np.pi) % (2 * np.pi) - np.pi
    return float(np.abs(dh).sum())


def _tree(grid: GridMap) -> tuple[cKDTree, np.ndarray] | None:
    if grid in _TREES:
        return _TREES[grid]
    cells = np.argwhere(grid.occupied)
    if cells.shape[0] == 0:
        entry = None
    else:
        centres = grid.cell_to_world(cells)
        entry = (cKDTree(centres), centres)
    _TREES[grid] = entry
    return entry


def _point_box_dist(px, py, x0, y0, x1, y1):
    dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - py, py - y1), 0.0)
    return np.hypot(dx, dy)


def _point_seg_dist(px, py, ax, ay, bx, by):
    vx, vy = bx - ax, by - ay
    l2 = vx * vx + vy * vy
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(l2 > 0, ((px - ax) * vx + (py - ay) * vy) / np.where(l2 > 0, l2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(px - (ax + t * vx), py - (ay + t * vy))


def _seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
    """Closed segment vs closed box intersection (Liang-Barsky slabs), vectorised."""
    t0 = np.zeros(np.broadcast(ax, x0).shape)
    t1 = np.ones_like(t0)
    ok = np.ones(t0.shape, dtype=bool)
    for a, b, lo, hi in ((ax, bx, x0, x1), (ay, by, y0, y1)):
        d = b - a
        flat = d == 0
        ok &= ~(flat & ((a < lo) | (a > hi)))
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            dd = np.where(flat, 1.0, d)
            ta = (lo - a) / dd
            tb = (hi - a) / dd
        tmin = np.where(flat, -np.inf, np.minimum(ta, tb))
        tmax = np.where(flat, np.inf, np.maximum(ta, tb))
        t0 = np.maximum(t0, tmin)
        t1 = np.minimum(t1, tmax)
    return ok & (t0 <= t1)


def _seg_box_dist(ax, ay, bx, by, x0, y0, x1, y1):
    d = np.minimum(_point_box_dist(ax, ay, x0, y0, x1, y1), _point_box_dist(bx, by, x0, y0, x1, y1))
    for cx, cy in ((x0, y0), (x1, y0), (x0, y1), (x1, y1)):
        d = np.minimum(d, _point_seg_dist(cx, cy, ax, ay, bx, by))
    return np.where(_seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1), 0.0, d)


def _group_min(values: np.ndarray, groups: np.ndarray, n: int) -> np.ndarray:
    out = np.full(n, np.inf)
    np.minimum.at(out, groups, values)
    return out


def _candidates(tree: cKDTree, centres_q: np.ndarray, radii: np.ndarray):
    lists = tree.query_ball_point(centres_q, r=radii)
    lens = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
    if lens.sum() == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    idx = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists if len(x)])
    owner = np.repeat(np.arange(len(lists)), lens)
    return owner, idx


def _point_clearances(grid: GridMap, p: np.ndarray, tree, centres) -> np.ndarray:
    h = grid.resolution / 2
    near, _ = tree.query(p)
    # the nearest square's centre lies within (distance to nearest centre) + half a diagonal
    owner, idx = _candidates(tree, p, near + h * math.sqrt(2) + 1e-9 * grid.resolution)
    c = centres[idx]
    d = _point_box_dist(p[owner, 0], p[owner, 1], c[:, 0] - h, c[:, 1] - h, c[:, 0] + h,
                        c[:, 1] + h)
    return _group_min(d, owner, p.shape[0])


def segment_clearances(grid: GridMap, path: object) -> np.ndarray:
    """Exact distance (m) from each segment of ``path`` to the nearest occupied square.

    Shape ``(N - 1,)``; for a one-point path, shape ``(1,)`` with that point's
    distance; ``inf`` everywhere on a map without obstacles.

    >>> g = GridMap.from_rows(["#..", "...", "..#"])     # squares [0,1]x[2,3], [2,3]x[0,1]
    >>> # the diagonal y = x passes the corners (2, 1) and (1, 2) at 1/sqrt(2)
    >>> segment_clearances(g, [[0.5, 0.5], [1.5, 1.5], [2.5, 2.5]]).round(6).tolist()
    [0.707107, 0.707107]
    """
    p = _path(path)
    if p.shape[0] == 0:
        return np.zeros(0)
    entry = _tree(grid)
    n = max(p.shape[0] - 1, 1)
    if entry is None:
        return np.full(n, np.inf)
    tree, centres = entry
    dp = _point_clearances(grid, p, tree, centres)
    if p.shape[0] == 1:
        return dp
    a, b = p[:-1], p[1:]
    upper = np.minimum(dp[:-1], dp[1:])
    mid = 0.5 * (a + b)
    half = 0.5 * np.hypot(*(b - a).T)
    h = grid.resolution / 2
    radii = upper + half + h * math.sqrt(2) + 1e-9 * grid.resolution
    owner, idx = _candidates(tree, mid, radii)
    c = centres[idx]
    d = _seg_box_dist(a[owner, 0], a[owner, 1], b[owner, 0], b[owner, 1], c[:, 0] - h,
                      c[:, 1] - h, c[:, 0] + h, c[:, 1] + h)
    return np.minimum(_group_min(d, owner, n), upper)


def min_clearance(grid: GridMap, path: object) -> float:
    """Exact distance (m) from the polyline to the nearest occupied square (``inf`` if none).

    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> round(min_clearance(g, [[0.2, 0.2]]), 6)          # to the corner (1, 1)
    1.131371
    """
    d = segment_clearances(grid, path)
    return float(d.min()) if d.size else math.inf


def in_bounds(grid: GridMap, path: object) -> bool:
    """Whether every point of ``path`` lies in the closed map rectangle.

    >>> in_bounds(GridMap.from_rows(["..", ".."]), [[0.0, 0.0], [2.0, 1.0]])
    True
    """
    p = _path(path)
    x0, y0, x1, y1 = grid.bounds
    return bool(np.all((p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)))


def collision_free(grid: GridMap, path: object, robot_radius_m: float = 0.0) -> bool:
    """Whether the polyline stays in the map and clear of every occupied square.

    Point robot (radius 0): no contact at all (touching a square, e.g. through
    the shared corner of two diagonal obstacles, is a collision).  Disc robot:
    clearance at least the radius.  An empty path is collision-free.

    >>> g = GridMap.from_rows([".#", "#."])   # cells (0,1) and (1,0) occupied
    >>> collision_free(g, [[0.5, 1.5], [1.5, 0.5]])   # corner-cutting diagonal
    False
    """
    r = float(robot_radius_m)
    if not math.isfinite(r) or r < 0:
        raise ConfigError(f"robot_radius_m must be a finite number >= 0, got {robot_radius_m!r}")
    p = _path(path)
    if p.shape[0] == 0:
        return True
    if not in_bounds(grid, p):
        return False
    c = min_clearance(grid, p)
    return c > 0.0 if r == 0.0 else c >= r


def r_ratio(a: float, b: float) -> float:
    """Paper eq. 10-11: ``(a - b) / b``, e.g. ``R_length`` with a = fusion, b = reference.

    >>> r_ratio(3.0, 2.0)
    0.5
    >>> r_ratio(1.0, 0.0)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: r_ratio: the reference value must be non-zero and finite, got 0.0
    """
    a = float(a)
    b = float(b)
    if b == 0.0 or not math.isfinite(b):
        raise ConfigError(f"r_ratio: the reference value must be non-zero and finite, got {b!r}")
    if not math.isfinite(a):
        raise ConfigError(f"r_ratio: the value must be finite, got {a!r}")
    return (a - b) / b


def evaluate(grid: GridMap, result: PlanResult, robot_radius_m: float = 0.0) -> dict[str, Any]:
    """All metrics of a :class:`~pathfuse.result.PlanResult` as a dict.

    Keys: ``planner``, ``status`` (name), ``success``, ``time_s``,
    ``iterations``, ``expansions``, ``length_m``, ``steps``,
    ``smoothness_rad``, ``min_clearance_m``, ``in_bounds``,
    ``collision_free``.  The geometric ones are computed from ``result.path``
    (the partial path on failure), never taken from the planner.

    >>> import numpy as np
    >>> from pathfuse.result import PlanResult, Status
    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> m = evaluate(g, PlanResult(Status.SUCCESS, np.array([[0.5, 0.5], [2.5, 0.5]])))
    >>> m["length_m"], m["collision_free"], m["min_clearance_m"], m["steps"]
    (2.0, True, 0.5, 1)
    """
    p = _path(result.path)
    return {
        "planner": result.planner,
        "status": result.status.name,
        "success": bool(result.success),
        "time_s": float(result.time_s),
        "iterations": int(result.iterations),
        "expansions": int(result.expansions),
        "length_m": path_length(p),
        "steps": n_steps(p),
        "smoothness_rad": smoothness(p),
        "min_clearance_m": min_clearance(grid, p),
        "in_bounds": in_bounds(grid, p) if p.shape[0] else True,
        "collision_free": collision_free(grid, p, robot_radius_m),
    }
