"""A* with a clearance cost: the global planner when a safety margin is set (ours).

In the spirit of Nav2's inflation layer: a cell whose centre lies within the
margin ``clearance_m`` of the robot disc's surface to an occupied square
costs more to pass, so the global path keeps away from walls where the
room allows and still threads a passage that is narrower than the margin.
Moving between neighbouring cells ``a`` and ``b`` costs the step length
times ``(m[a] + m[b]) / 2`` with the per-cell multiplier::

    m = 1 + CLEARANCE_COST * ((clearance - gap) / clearance)^2    for gap < clearance
    m = 1                                                          otherwise

``gap`` is the exact distance from the cell centre to the nearest occupied
square minus the robot radius (:func:`clearance_multipliers`).  The search
is plain 8-connected A* with a binary heap and the Euclidean heuristic
(admissible: every step costs at least its length), on the robot's c-space
and with the same corner rule as the exact A* of :mod:`pathfuse.search.astar`;
it is used only when a margin is set, so the paper's A* and its numbers are
untouched.

Examples
--------
>>> import numpy as np
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["......", "......", "..##..", "......", "......"], 0.5)
>>> m = clearance_multipliers(g, 0.0, 0.5)
>>> float(m[0, 0]), round(float(m[1, 2]), 3)   # far from the block / next to it
(1.0, 2.0)
"""

from __future__ import annotations

import math
import weakref

import numpy as np
from numba import njit

from pathfuse.geometry import point_box_distance
from pathfuse.result import (
    CODE_MAX_ITERATIONS,
    CODE_NO_PATH,
    CODE_SUCCESS,
    Status,
    code_outcome,
)
from pathfuse.search.heap import heap_pop, heap_push

__all__ = ["CLEARANCE_COST", "clearance_multipliers", "costaware_search", "warmup_costaware"]

CLEARANCE_COST = 4.0
"""How much more a cell right at the robot's surface costs than a free one, minus one."""

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@njit(cache=True)
def _gaps(occ, res, k, cap):
    """Exact distance from each cell centre to the nearest occupied square (capped).

    Only the occupied cells with a free 4-neighbour are visited (the nearest
    point of the occupied squares to a free centre always lies on one of
    them), each updating the cells within ``k`` of it.
    """
    h, w = occ.shape
    out = np.full((h, w), cap)
    for r in range(h):
        for c in range(w):
            if not occ[r, c]:
                continue
            out[r, c] = 0.0
            if not ((r > 0 and not occ[r - 1, c]) or (r + 1 < h and not occ[r + 1, c])
                    or (c > 0 and not occ[r, c - 1]) or (c + 1 < w and not occ[r, c + 1])):
                continue
            x0 = c * res
            y0 = r * res
            for rr in range(max(r - k, 0), min(r + k + 1, h)):
                cy = (rr + 0.5) * res
                for cc in range(max(c - k, 0), min(c + k + 1, w)):
                    if occ[rr, cc]:
                        continue
                    d = point_box_distance((cc + 0.5) * res, cy, x0, y0, x0 + res, y0 + res)
                    if d < out[rr, cc]:
                        out[rr, cc] = d
    return out


def clearance_multipliers(grid, radius_m: float, clearance_m: float) -> np.ndarray:
    """The per-cell cost multipliers ``m`` (see the module docstring); cached per map."""
    key = (float(radius_m), float(clearance_m))
    per = _CACHE.get(grid)
    if per is None:
        per = _CACHE[grid] = {}
    hit = per.get(key)
    if hit is not None:
        return hit  # type: ignore[no-any-return]
    res = grid.resolution
    cap = radius_m + clearance_m
    k = int(math.ceil(cap / res)) + 1
    gap = _gaps(np.ascontiguousarray(grid.occupied), float(res), k, float(cap)) - radius_m
    m = np.ones(grid.shape)
    if clearance_m > 0:
        inside = gap < clearance_m
        m[inside] = 1.0 + CLEARANCE_COST * ((clearance_m - np.maximum(gap[inside], 0.0))
                                            / clearance_m) ** 2
    m.setflags(write=False)
    if len(per) >= 4:
        per.pop(next(iter(per)))
    per[key] = m
    return m


@njit(cache=True)
def _search(occ, mult, sr, sc, gr, gc, corner_cutting, max_exp):
    h, w = occ.shape
    n = h * w
    g = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    start = sr * w + sc
    goal = gr * w + gc
    g[start] = 0.0
    keys = np.empty(1 << 12)
    nodes = np.empty(1 << 12, dtype=np.int64)
    keys, nodes, size = heap_push(keys, nodes, 0, math.hypot(sr - gr, sc - gc), start)
    exp = 0
    s2 = math.sqrt(2.0)
    while size > 0:
        u, size = heap_pop(keys, nodes, size)
        if closed[u]:
            continue
        closed[u] = True
        if u == goal:
            return g, parent, CODE_SUCCESS, exp
        exp += 1
        if exp > max_exp:
            return g, parent, CODE_MAX_ITERATIONS, exp
        ur = u // w
        uc = u % w
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                if dr == 0 and dc == 0:
                    continue
                vr = ur + dr
                vc = uc + dc
                if vr < 0 or vr >= h or vc < 0 or vc >= w or occ[vr, vc]:
                    continue
                diag = dr != 0 and dc != 0
                if diag and not corner_cutting and (occ[ur, vc] or occ[vr, uc]):
                    continue
                if diag and corner_cutting and occ[ur, vc] and occ[vr, uc]:
                    continue
                v = vr * w + vc
                if closed[v]:
                    continue
                step = s2 if diag else 1.0
                ng = g[u] + step * 0.5 * (mult[ur, uc] + mult[vr, vc])
                if ng < g[v]:
                    g[v] = ng
                    parent[v] = u
                    keys, nodes, size = heap_push(keys, nodes, size,
                                                  ng + math.hypot(vr - gr, vc - gc), v)
    return g, parent, CODE_NO_PATH, exp


def costaware_search(occ: np.ndarray, mult: np.ndarray, start: tuple[int, int],
                     goal: tuple[int, int], corner_cutting: bool = False,
                     max_expansions: int | None = None
                     ) -> tuple[Status | None, np.ndarray, float, int]:
    """Cost-aware A* between two free cells of ``occ`` (see the module docstring).

    Returns ``(status, cells, cost_cells, expansions)``: status ``SUCCESS``,
    ``NO_PATH`` or ``MAX_ITERATIONS`` (the expansion cap); ``cells`` (N, 2)
    ``(row, col)`` from start to goal; ``cost_cells`` the path's cost in cell sides.
    """
    cap = int(max_expansions) if max_expansions is not None else occ.size + 1
    g, parent, code, exp = _search(occ, mult, start[0], start[1], goal[0], goal[1],
                                   bool(corner_cutting), cap)
    status = code_outcome(code)
    if status is not Status.SUCCESS:
        return status, np.zeros((0, 2), dtype=np.int64), math.inf, exp
    w = occ.shape[1]
    u = goal[0] * w + goal[1]
    out = []
    while u >= 0:
        out.append((u // w, u % w))
        u = int(parent[u])
    cells = np.array(out[::-1], dtype=np.int64)
    return status, cells, float(g[goal[0] * w + goal[1]]), exp


def warmup_costaware() -> None:
    """Compile (or load from numba's cache) the kernels of this module."""
    for ro in (False, True):
        occ = np.zeros((3, 3), dtype=np.bool_)
        occ[1, 1] = True
        m = np.ones((3, 3))
        occ.setflags(write=not ro)
        m.setflags(write=not ro)
        costaware_search(occ, m, (0, 0), (2, 2))
        _gaps(occ, 1.0, 1, 1.0)

