"""What the page draws to look inside the planners: the potential field, the A* closed
set, the c-space and the fusion's attracting points.

Nothing here is on a planner's path: each function runs after (or beside) a
plan, on request.

* :func:`potential_field` samples the APF potentials of the paper (eq. 3 and
  4, the same kernels the planners step with) at cell centres on a lattice
  of at most ``max_side`` x ``max_side`` points, and the force (eq. 5 + 6)
  on a coarser lattice for arrows.
* :func:`closed_set` runs the planner's global A* again on a fresh searcher
  (the same c-space, heuristic and corner rule; A* is deterministic, so the
  same search) and reads the cells it closed; :func:`closed_order` also gives
  them in expansion order, for the page's animated search.
* :func:`attractors` walks the returned path and, at each of its points,
  lists the A* waypoints that attract the robot there: inside the circle of
  radius ``r1_m`` and ahead (past the progress index, replayed with
  :func:`pathfuse.field.pathing.advance_progress`, or the paper's ``x_p > x``).
"""

from __future__ import annotations

import base64
import math
from typing import Any

import numpy as np
from numba import njit

from pathfuse.costmap import costmap_for
from pathfuse.field.forces import rep_potential_d
from pathfuse.field.repulsion import apf_force
from pathfuse.grid import GridMap
from pathfuse.problem import Problem

__all__ = ["potential_field", "closed_set", "closed_order", "attractors", "f32", "i32"]


def f32(a: np.ndarray) -> str:
    """base64 of a float32 array (row-major; NaN stays NaN)."""
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def i32(a: np.ndarray) -> str:
    """base64 of a little-endian int32 array (row-major)."""
    return base64.b64encode(np.ascontiguousarray(a, dtype="<i4").tobytes()).decode("ascii")


@njit(cache=True, nogil=True)
def _rep_samples(rows, cols, occ, ox, oy, res, k_rep, rho0_m):  # pragma: no cover - numba
    """Eq. 4 summed over the occupied cell centres within rho0 of each sampled cell centre
    (NaN on an occupied sample); the window of ``grid_rep_potential``."""
    h, w = occ.shape
    out = np.empty((rows.shape[0], cols.shape[0]), dtype=np.float64)
    rad2 = rho0_m * rho0_m
    span = int(math.floor(rho0_m / res))
    for i in range(rows.shape[0]):
        r = rows[i]
        for j in range(cols.shape[0]):
            c = cols[j]
            if occ[r, c]:
                out[i, j] = np.nan
                continue
            u = 0.0
            for rr in range(max(r - span, 0), min(r + span, h - 1) + 1):
                dy = (rr - r) * res
                for cc in range(max(c - span, 0), min(c + span, w - 1) + 1):
                    if occ[rr, cc]:
                        dx = (cc - c) * res
                        d2 = dx * dx + dy * dy
                        if d2 < rad2:
                            u += rep_potential_d(math.sqrt(d2), k_rep, rho0_m)
            out[i, j] = u
    return out


@njit(cache=True, nogil=True)
def _force_samples(xs, ys, gx, gy, k_att, k_rep, rho0_m, cm):  # pragma: no cover - numba
    """The APF force (eq. 5 + 6) at every lattice point (NaN inside an occupied cell) of the
    :class:`~pathfuse.costmap.Costmap` ``cm``."""
    occ = cm.occ
    ox = cm.ox_m
    oy = cm.oy_m
    res = cm.res_m
    h, w = occ.shape
    fx = np.empty((ys.shape[0], xs.shape[0]), dtype=np.float64)
    fy = np.empty_like(fx)
    for i in range(ys.shape[0]):
        for j in range(xs.shape[0]):
            x = xs[j]
            y = ys[i]
            c = int(math.floor((x - ox) / res))
            r = int(math.floor((y - oy) / res))
            if r < 0 or r >= h or c < 0 or c >= w or occ[r, c]:
                fx[i, j] = np.nan
                fy[i, j] = np.nan
                continue
            a, b = apf_force(x, y, gx, gy, k_att, k_rep, rho0_m, rho0_m, cm)
            fx[i, j] = a
            fy[i, j] = b
    return fx, fy


def _lattice(n: int, side: int) -> np.ndarray:
    """Indices of about ``side`` evenly spread cells among ``n`` (all of them if n <= side)."""
    if n <= side:
        return np.arange(n, dtype=np.int64)
    step = n / side
    return np.minimum((np.arange(side) * step + step / 2).astype(np.int64), n - 1)


def potential_field(grid: GridMap, goal: tuple[float, float], k_att: float, k_rep: float,
                    rho0_m: float, max_side: int = 256, arrows: int = 24) -> dict[str, Any]:
    """The APF potentials on a lattice of cell centres and the force on a coarser one.

    Returns a JSON-ready dict: ``heat`` with the sampled cells' centres
    (``xs``, ``ys`` in metres), the attractive and repulsive potentials as
    base64 float32 arrays of shape (len(ys), len(xs)) (NaN on obstacles),
    and ``arrows`` with the lattice points and the force there.

    >>> from pathfuse.grid import GridMap
    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> d = potential_field(g, (2.5, 2.5), 40.0, 5.0, 2.0)
    >>> d["heat"]["shape"], round(d["heat"]["max_attractive"], 3)
    ([3, 3], 160.0)
    """
    occ = grid.occupied
    h, w = occ.shape
    ox, oy = grid.origin
    res = grid.resolution
    rows = _lattice(h, max_side)
    cols = _lattice(w, max_side)
    xs = ox + (cols + 0.5) * res
    ys = oy + (rows + 0.5) * res
    gx, gy = float(goal[0]), float(goal[1])
    att = 0.5 * k_att * ((xs[None, :] - gx) ** 2 + (ys[:, None] - gy) ** 2)
    rep = _rep_samples(rows, cols, occ, ox, oy, res, k_rep, rho0_m)
    att = np.where(np.isnan(rep), np.nan, att)
    ax = np.linspace(ox, ox + w * res, arrows + 1)
    ay = np.linspace(oy, oy + h * res, arrows + 1)
    axc = (ax[:-1] + ax[1:]) / 2 if w > arrows else xs
    ayc = (ay[:-1] + ay[1:]) / 2 if h > arrows else ys
    fx, fy = _force_samples(np.ascontiguousarray(axc), np.ascontiguousarray(ayc), gx, gy,
                            k_att, k_rep, rho0_m, costmap_for(grid, 0.0, lattice=False))

    def finite_max(a: np.ndarray) -> float:
        ok = a[np.isfinite(a)]
        return float(ok.max()) if ok.size else 0.0

    return {
        "heat": {"shape": [int(ys.size), int(xs.size)], "xs": xs.tolist(), "ys": ys.tolist(),
                 "attractive": f32(att), "repulsive": f32(rep),
                 "max_attractive": finite_max(att), "max_repulsive": finite_max(rep)},
        "arrows": {"shape": [int(ayc.size), int(axc.size)], "xs": axc.tolist(),
                   "ys": ayc.tolist(), "fx": _nan_list(fx), "fy": _nan_list(fy)},
        "params": {"k_att": k_att, "k_rep": k_rep, "rho0_m": rho0_m},
        "goal": [gx, gy],
    }


def _nan_list(a: np.ndarray) -> list[list[float | None]]:
    return [[None if not math.isfinite(v) else float(v) for v in row] for row in a.tolist()]


def closed_set(problem: Problem, heuristic: str = "euclidean",
               corner_cutting: bool = False, time_limit_s: float | None = None
               ) -> np.ndarray | None:
    """The cells the planner's global A* closes for ``problem`` ((H, W) bool), or None when
    the problem fails before any search (a blocked or outside start or goal)."""
    got = closed_order(problem, heuristic, corner_cutting, time_limit_s)
    return None if got is None else got[0]


def closed_order(problem: Problem, heuristic: str = "euclidean",
                 corner_cutting: bool = False, time_limit_s: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`closed_set` and the same cells in the order the search expanded them
    (row-major indices, :meth:`~pathfuse.search.astar.AStarSearcher.expansion_order`), or
    None when the problem fails before any search."""
    from pathfuse.planners.globals.astar import snap_cell
    from pathfuse.search.astar import AStarSearcher

    if problem.failure() is not None:
        return None
    grid = problem.grid
    r = problem.robot_radius_m
    cs = grid.cspace(r)
    if r > 0:
        sc = snap_cell(cs.occupied, grid, problem.start, r)
        gc = snap_cell(cs.occupied, grid, problem.goal, r)
        if sc is None or gc is None:
            return None
    else:
        sc, gc = problem.start_cell, problem.goal_cell
    labels = None if corner_cutting else cs.components
    searcher = AStarSearcher(cs.occupied, corner_cutting=corner_cutting, labels=labels)
    searcher.search_checked(sc, gc, heuristic, None, time_limit_s)
    return searcher.closed_mask(), searcher.expansion_order(gc, heuristic)


def attractors(problem: Problem, path: np.ndarray, waypoints: np.ndarray, r1_m: float,
               ahead: str = "progress", max_points: int = 5000) -> list[list[int]]:
    """For each point of ``path`` (at most ``max_points``), the indices of the waypoints
    (the goal appended, as the fusion controller does) that attract the robot there.

    >>> from pathfuse.grid import GridMap
    >>> g = GridMap.from_rows(["......"])
    >>> pb = Problem.create(g, (0.5, 0.5), (5.5, 0.5))
    >>> wp = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5], [4.5, 0.5], [5.5, 0.5]])
    >>> attractors(pb, wp[:2], wp, 1.6)
    [[1], [2]]
    """
    from pathfuse.field.pathing import advance_progress, polyline_cumlen

    grid = problem.grid
    pts = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    gx, gy = problem.goal
    if pts.shape[0] == 0 or pts[-1, 0] != gx or pts[-1, 1] != gy:
        pts = np.concatenate([pts, [[gx, gy]]])
    pts = np.ascontiguousarray(pts)
    cum = polyline_cumlen(pts)
    cm = costmap_for(grid, problem.robot_radius_m, lattice=False)
    clear = cm.clear_m
    r1sq = r1_m * r1_m
    out: list[list[int]] = []
    k = 0
    for x, y in np.asarray(path, dtype=np.float64)[:max_points]:
        d2 = (pts[:, 0] - x) ** 2 + (pts[:, 1] - y) ** 2
        if ahead == "paper-x":
            sel = np.nonzero((pts[:, 0] > x) & (d2 < r1sq))[0]
        else:
            k = int(advance_progress(float(x), float(y), pts, cum, k, r1_m, cm, clear))
            reach = math.sqrt(float(d2[k])) + r1_m
            j = np.arange(k + 1, pts.shape[0])
            j = j[(cum[j] - cum[k] <= reach) & (d2[j] < r1sq)]
            sel = j
        out.append([int(v) for v in sel])
    return out
