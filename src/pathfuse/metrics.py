"""Path metrics, the same for every planner and computed without any planner code.

Geometry: obstacles are the *closed* occupied cell squares of the map.  A
path is the polyline through its points.

* :func:`min_clearance` -- exact distance from the polyline to the nearest
  occupied square (0 when it touches or enters one; ``inf`` on a map without
  obstacles).  Computed per segment by a numba kernel
  (:mod:`pathfuse.metrics_kernels`) with an exact segment-to-square distance
  (a slab intersection test, then the vertex-to-edge distances of the two
  convex shapes), visiting only the cells in rings around the segment up to
  the ring that provably cannot hold a closer square, and beyond a few rings
  the blocks of an occupancy pyramid (built once per map) that can.
* :func:`collision_free` -- every point inside the map rectangle and, for a
  point robot (``robot_radius_m == 0``), no contact with any occupied square:
  touching counts, so a diagonal that squeezes through the shared corner of
  two occupied cells is a collision; for a disc robot, clearance ``>=`` the
  radius (a disc that exactly touches a wall is allowed, as in
  :meth:`pathfuse.grid.GridMap.inflate`).
* :func:`path_length` (m), :func:`smoothness` (sum of absolute heading
  changes between successive non-zero segments, radians), :func:`n_steps`
  (segments), :func:`r_ratio` (paper eq. 10-11), and :func:`evaluate`, all of
  them for a :class:`~pathfuse.result.PlanResult`.  :func:`evaluate` walks
  the path once (one kernel call) for the clearance, the bounds, the lengths
  and the turns, and reuses that clearance for ``min_clearance_m`` and
  ``collision_free``.

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

from pathfuse.grid import GridMap
from pathfuse.metrics_kernels import (
    build_pyramid,
    evaluate_kernel,
    geometry_kernel,
    segment_clearances_kernel,
    shape_kernel,
)
from pathfuse.result import ConfigError, PlanResult, QueryError
from pathfuse.validate import short as _shown

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
    "PlanInfo",
]


# occupancy pyramid of each map (pathfuse.metrics_kernels.build_pyramid), built on first use
_PYRAMIDS: weakref.WeakKeyDictionary[GridMap, tuple[np.ndarray, np.ndarray]] = (
    weakref.WeakKeyDictionary()
)


def _pyramid(grid: GridMap) -> tuple[np.ndarray, np.ndarray]:
    entry = _PYRAMIDS.get(grid)
    if entry is None:
        entry = _PYRAMIDS[grid] = build_pyramid(grid.occupied)
    return entry


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
    return float(shape_kernel(np.ascontiguousarray(p))[0].sum())


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
    return float(shape_kernel(np.ascontiguousarray(p))[1].sum())


def _geometry(grid: GridMap, p: np.ndarray) -> tuple[float, bool]:
    """(min clearance, in bounds) of a validated non-empty path, in one pass."""
    x0, y0, x1, y1 = grid.bounds
    c, inside = geometry_kernel(grid.occupied, *_pyramid(grid), grid.origin[0], grid.origin[1],
                                grid.resolution, x0, y0, x1, y1, np.ascontiguousarray(p))
    return float(c), bool(inside)


def _radius(robot_radius_m: float) -> float:
    r = float(robot_radius_m)
    if not math.isfinite(r) or r < 0:
        raise ConfigError(f"robot_radius_m: must be a finite number >= 0, got"
                          f" {_shown(robot_radius_m)}")
    return r


def _is_free(clearance: float, inside: bool, r: float) -> bool:
    if not inside:
        return False
    return clearance > 0.0 if r == 0.0 else clearance >= r


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
    return segment_clearances_kernel(grid.occupied, *_pyramid(grid), grid.origin[0],
                                     grid.origin[1], grid.resolution, np.ascontiguousarray(p))


def min_clearance(grid: GridMap, path: object) -> float:
    """Exact distance (m) from the polyline to the nearest occupied square (``inf`` if none).

    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> round(min_clearance(g, [[0.2, 0.2]]), 6)          # to the corner (1, 1)
    1.131371
    """
    p = _path(path)
    return _geometry(grid, p)[0] if p.shape[0] else math.inf


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
    r = _radius(robot_radius_m)
    p = _path(path)
    if p.shape[0] == 0:
        return True
    return _is_free(*_geometry(grid, p), r)


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
        raise ConfigError(f"r_ratio: the reference value must be non-zero and finite, got"
                          f" {_shown(b)}")
    if not math.isfinite(a):
        raise ConfigError(f"r_ratio: the value must be finite, got {_shown(a)}")
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
    r = _radius(robot_radius_m)
    if p.shape[0]:
        # one pass of the path for clearance (-> min_clearance_m, collision_free), bounds,
        # segment lengths and turns
        x0, y0, x1, y1 = grid.bounds
        clearance, inside, lengths, turns = evaluate_kernel(
            grid.occupied, *_pyramid(grid), grid.origin[0], grid.origin[1], grid.resolution,
            x0, y0, x1, y1, np.ascontiguousarray(p))
        clearance, inside = float(clearance), bool(inside)
        length, turn = float(lengths.sum()), float(turns.sum())
    else:
        clearance, inside, length, turn = math.inf, True, 0.0, 0.0
    return {
        "planner": result.planner,
        "status": result.status.name,
        "success": bool(result.success),
        "time_s": float(result.time_s),
        "iterations": int(result.iterations),
        "expansions": int(result.expansions),
        "length_m": length,
        "steps": max(p.shape[0] - 1, 0),
        "smoothness_rad": turn,
        "min_clearance_m": clearance,
        "in_bounds": inside,
        "collision_free": _is_free(clearance, inside, r),
    }


class PlanInfo(dict):
    """``PlanResult.info`` of the registered planners: a dict that also answers
    ``info["min_clearance_m"]``, the least gap between the robot disc along the path and
    any occupied square (metres; ``inf`` on an empty map), computed on first access by
    :func:`min_clearance` (independently of the planner), so that a
    caller who never asks pays nothing.  It pickles as a plain dict."""

    _bound: tuple[Any, np.ndarray, float] | None = None

    def bind(self, grid: Any, path: np.ndarray, radius_m: float) -> None:
        self._bound = (grid, path, float(radius_m))

    def __missing__(self, key: Any) -> Any:
        if key != "min_clearance_m" or self._bound is None:
            raise KeyError(key)
        grid, path, r = self._bound
        v = min_clearance(grid, path) - r if path.shape[0] else math.nan
        self[key] = v
        return v

    def __reduce__(self) -> Any:
        return (dict, (dict(self),))
