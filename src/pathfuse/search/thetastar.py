"""Theta* and Lazy Theta* on an occupancy grid (numba): any-angle paths with exact sight lines.

Theta* (Nash, Daniel, Koenig and Felner, AAAI 2007) is A* on the 8-connected
grid of cell centres in which a node may take its parent's parent as its own
parent when the two are in sight of each other; the path is then a chain of
straight sight lines, not of grid moves.  Lazy Theta* (Nash, Koenig and
Tovey, AAAI 2010) assumes the sight line when it relaxes a node and checks it
only when the node is expanded, falling back to the best expanded neighbour.

As built here:

* the nodes are the free cells of a c-space grid ``free`` (the robot's
  :meth:`~pathfuse.grid.GridMap.cspace`), 8-connected with the same corner
  rule as pathfuse's A* (a diagonal move needs both orthogonal neighbours
  free);
* every edge, grid moves included, is checked with
  :func:`~pathfuse.search.los.line_of_sight` against the real occupied squares
  with clearance ``clear`` (the robot radius plus pathfuse's margin), so the
  path keeps exactly the clearance every other pathfuse move keeps;
* the start and goal nodes sit at the query's start and goal points, not at
  their cells' centres, so the path runs from the start point to the goal
  point;
* the heuristic is the Euclidean distance to the goal point (consistent), and
  the g value of a node is the exact length of its chain of sight lines.

With a consistent heuristic and grid moves that are always in sight (a point
robot), Theta*'s path is never longer than the A* grid path between the same
points (tested).

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((4, 6), dtype=bool); occ[1:3, 2] = True
>>> r = theta_star(~occ, occ, 0.0, 0.0, 1.0, 1e-6, (0, 0), (0.5, 0.5), (3, 5), (5.5, 3.5))
>>> r.status.name, r.points.tolist(), round(r.length, 4)
('SUCCESS', [[0.5, 0.5], [3.5, 0.5], [5.5, 3.5]], 6.6056)

The corners of a Theta* path are cell centres, so it passes the wall's corner
(3, 1) half a cell wide; the true shortest path (6.0850 m) bends at that corner.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from pathfuse.result import CODE_NO_PATH, CODE_RUNNING, CODE_SUCCESS, Status
from pathfuse.search.heap import heap_pop as _pop
from pathfuse.search.heap import heap_push as _push
from pathfuse.search.los import line_of_sight

__all__ = ["AnyAngleResult", "theta_star", "warmup"]

_CHUNK = 1 << 14  # expansions between clock checks when a time limit is set

_DR = np.array([0, 0, 1, -1, 1, 1, -1, -1], dtype=np.int64)
_DC = np.array([1, -1, 0, 0, 1, -1, 1, -1], dtype=np.int64)


@dataclass
class AnyAngleResult:
    """Outcome of :func:`theta_star` (and of the visibility-graph search).

    Attributes
    ----------
    status : Status
        ``SUCCESS``, ``NO_PATH``, ``MAX_ITERATIONS`` or ``TIMEOUT``.
    points : (N, 2) float array
        The path's corners in world metres, start point to goal point.
    length : float
        Its length in metres (``inf`` without a path).
    expansions : int
        Nodes expanded.
    """

    status: Status
    points: np.ndarray
    length: float
    expansions: int


@njit(cache=True, inline="always")
def _pos(node, w, snode, sx, sy, gnode, gx, gy, ox, oy, res):
    if node == snode:
        return sx, sy
    if node == gnode:
        return gx, gy
    r = node // w
    c = node - r * w
    return ox + (c + 0.5) * res, oy + (r + 0.5) * res


@njit(cache=True, inline="always")
def _move_ok(free, r, c, dr, dc):
    """A grid move from ``(r, c)`` by ``(dr, dc)`` under the no-corner-cutting rule."""
    h, w = free.shape
    r2 = r + dr
    c2 = c + dc
    if r2 < 0 or r2 >= h or c2 < 0 or c2 >= w or not free[r2, c2]:
        return False
    if dr != 0 and dc != 0:
        return free[r + dr, c] and free[r, c + dc]
    return True


@njit(cache=True)
def _theta_kernel(free, occ, ox, oy, res, clear, snode, sx, sy, gnode, gx, gy, lazy,
                  g, parent, closed, hkey, hnode, meta, max_exp):
    """Run (or resume) Theta*; ``meta`` = [heap size, expansions].  Returns
    ``(code, hkey, hnode)``."""
    w = free.shape[1]
    size = meta[0]
    exp = meta[1]
    done = 0
    while size > 0:
        u, size = _pop(hkey, hnode, size)
        if closed[u]:
            continue
        ux, uy = _pos(u, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
        ur = u // w
        uc = u - ur * w
        if lazy and u != snode:
            p = parent[u]
            px, py = _pos(p, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
            if not line_of_sight(px, py, ux, uy, occ, ox, oy, res, clear):
                # Lazy Theta*'s SetVertex: the best expanded neighbour in sight
                best = math.inf
                bp = -1
                for k in range(8):
                    if not _move_ok(free, ur, uc, _DR[k], _DC[k]):
                        continue
                    v = (ur + _DR[k]) * w + uc + _DC[k]
                    if not closed[v]:
                        continue
                    vx, vy = _pos(v, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
                    d = g[v] + math.hypot(ux - vx, uy - vy)
                    if d < best and line_of_sight(vx, vy, ux, uy, occ, ox, oy, res, clear):
                        best = d
                        bp = v
                if bp < 0:
                    g[u] = math.inf
                    continue
                g[u] = best
                parent[u] = bp
        if u == gnode:
            meta[0] = size
            meta[1] = exp
            return CODE_SUCCESS, hkey, hnode
        closed[u] = True
        exp += 1
        done += 1
        p = parent[u]
        px, py = _pos(p, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
        gp = g[p]
        gu = g[u]
        for k in range(8):
            if not _move_ok(free, ur, uc, _DR[k], _DC[k]):
                continue
            v = (ur + _DR[k]) * w + uc + _DC[k]
            if closed[v]:
                continue
            vx, vy = _pos(v, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
            if lazy:
                cand = gp + math.hypot(vx - px, vy - py)
                par = p
            elif p != u and line_of_sight(px, py, vx, vy, occ, ox, oy, res, clear):
                cand = gp + math.hypot(vx - px, vy - py)
                par = p
            elif line_of_sight(ux, uy, vx, vy, occ, ox, oy, res, clear):
                cand = gu + math.hypot(vx - ux, vy - uy)
                par = u
            else:
                continue
            if cand < g[v]:
                g[v] = cand
                parent[v] = par
                hkey, hnode, size = _push(hkey, hnode, size,
                                          cand + math.hypot(gx - vx, gy - vy), v)
        if done >= max_exp:
            meta[0] = size
            meta[1] = exp
            return CODE_RUNNING, hkey, hnode
    meta[0] = size
    meta[1] = exp
    return CODE_NO_PATH, hkey, hnode


@njit(cache=True)
def _trace(parent, snode, gnode, w, sx, sy, gx, gy, ox, oy, res):
    n = 1
    v = gnode
    while v != snode:
        v = parent[v]
        n += 1
    out = np.empty((n, 2))
    v = gnode
    for j in range(n - 1, -1, -1):
        x, y = _pos(v, w, snode, sx, sy, gnode, gx, gy, ox, oy, res)
        out[j, 0] = x
        out[j, 1] = y
        v = parent[v]
    return out


def theta_star(free: np.ndarray, occ: np.ndarray, ox: float, oy: float, res: float,
               clear: float, start_cell: tuple[int, int], start: tuple[float, float],
               goal_cell: tuple[int, int], goal: tuple[float, float], lazy: bool = False,
               max_expansions: int | None = None,
               time_limit_s: float | None = None) -> AnyAngleResult:
    """Theta* (or Lazy Theta*) from ``start`` to ``goal`` (see the module docstring).

    Parameters
    ----------
    free : (H, W) bool array
        The nodes: free cells of the c-space.
    occ : (H, W) bool array
        The occupied squares the sight lines are checked against.
    ox, oy, res : float
        The map's origin and resolution.
    clear : float
        Clearance every sight line keeps (metres).
    start_cell, goal_cell : (row, col)
        Free cells of ``free``; their nodes sit at ``start`` and ``goal``.
    lazy : bool
        Lazy Theta* instead of Theta*.
    max_expansions, time_limit_s : optional
        Budget: ``MAX_ITERATIONS`` / ``TIMEOUT`` when exceeded.
    """
    t0 = time.perf_counter()
    h, w = free.shape
    sx, sy = float(start[0]), float(start[1])
    gx, gy = float(goal[0]), float(goal[1])
    snode = start_cell[0] * w + start_cell[1]
    gnode = goal_cell[0] * w + goal_cell[1]
    if snode == gnode:
        if line_of_sight(sx, sy, gx, gy, occ, ox, oy, res, clear):
            pts = np.array([[sx, sy], [gx, gy]]) if (sx, sy) != (gx, gy) else np.array([[sx, sy]])
            return AnyAngleResult(Status.SUCCESS, pts, math.hypot(gx - sx, gy - sy), 0)
        return AnyAngleResult(Status.NO_PATH, np.zeros((0, 2)), math.inf, 0)
    n = h * w
    g = np.full(n, math.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    hkey = np.empty(256)
    hnode = np.empty(256, dtype=np.int64)
    g[snode] = 0.0
    parent[snode] = snode
    hkey[0] = math.hypot(gx - sx, gy - sy)
    hnode[0] = snode
    meta = np.array([1, 0], dtype=np.int64)
    budget = n if max_expansions is None else int(max_expansions)
    chunk = _CHUNK if time_limit_s is not None else budget
    free_c = np.ascontiguousarray(free, dtype=np.bool_)
    occ_c = np.ascontiguousarray(occ, dtype=np.bool_)
    while True:
        step = min(chunk, budget - int(meta[1]))
        if step <= 0:
            return AnyAngleResult(Status.MAX_ITERATIONS, np.zeros((0, 2)), math.inf,
                                  int(meta[1]))
        code, hkey, hnode = _theta_kernel(free_c, occ_c, ox, oy, res, clear, snode, sx, sy,
                                          gnode, gx, gy, lazy, g, parent, closed, hkey, hnode,
                                          meta, step)
        if code == CODE_SUCCESS:
            pts = _trace(parent, snode, gnode, w, sx, sy, gx, gy, ox, oy, res)
            return AnyAngleResult(Status.SUCCESS, pts, float(g[gnode]), int(meta[1]))
        if code == CODE_NO_PATH:
            return AnyAngleResult(Status.NO_PATH, np.zeros((0, 2)), math.inf, int(meta[1]))
        if int(meta[1]) >= budget:
            return AnyAngleResult(Status.MAX_ITERATIONS, np.zeros((0, 2)), math.inf,
                                  int(meta[1]))
        if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
            return AnyAngleResult(Status.TIMEOUT, np.zeros((0, 2)), math.inf, int(meta[1]))


_WARM: set[bool] = set()


def warmup(lazy: bool = False) -> None:
    """Compile (or load from numba's cache) the kernels of Theta* (or Lazy Theta*)."""
    if lazy in _WARM:
        return
    occ = np.zeros((3, 4), dtype=bool)
    occ[1, 1] = True
    free = ~occ
    occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
    theta_star(free, occ, 0.0, 0.0, 1.0, 1e-6, (0, 0), (0.5, 0.5), (2, 3), (3.5, 2.5),
               lazy=lazy, time_limit_s=10.0)
    _WARM.add(lazy)
