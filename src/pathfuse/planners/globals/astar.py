"""The global planner: grid A* on the robot's c-space, one wrapper for every planner.

:func:`plan_global` runs exact 8-connected A* (:mod:`pathfuse.search.astar`)
on :meth:`GridMap.cspace` of the problem's robot radius (obstacles and the
map's edge grown by the radius; the map itself for a point robot).

* A point robot starts from the cell its start lies in.  A disc robot
  starts from the nearest free c-space cell (within two cells) whose centre
  it reaches in a clear straight move; the goal likewise.
* :attr:`GlobalPlan.points` are the cell centres from the start cell to the
  goal cell: the grid path, whose length is the A* cost
  (:attr:`GlobalPlan.length_m`).  This is what the ``astar`` planner returns.
* With a safety margin or an inflation (:attr:`Problem.inflation_m` > 0:
  ``clearance_m``, or the robot's ``inflation_m``, 0.3 m by default for a
  diff-drive robot; ours) the search pays a clearance cost near obstacles
  (:mod:`pathfuse.search.costaware`); ``length_m`` is then the path's
  length, not its cost.
* :attr:`GlobalPlan.waypoints` are what a controller follows:
  ``[start, centres..., goal]``, the first and last centres left out when
  the straight move past them is clear (on a query between cell centres the
  waypoints equal the centres).

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse.problem import Problem
>>> g = GridMap.from_rows(["....", ".##.", ".#.."])
>>> gp = plan_global(Problem.create(g, (0.5, 0.5), (3.5, 2.5), robot_radius_m=0.2))
>>> gp.status.name, gp.waypoints.tolist()
('SUCCESS', [[0.5, 0.5], [0.5, 1.5], [0.5, 2.5], [1.5, 2.5], [2.5, 2.5], [3.5, 2.5]])
>>> round(gp.length_m, 4), gp.expansions > 0
(5.0, True)
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from pathfuse.costmap import costmap_for, move_clear
from pathfuse.grid import GridMap
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, Status
from pathfuse.search.astar import HEURISTICS, AStarSearcher, get_searcher
from pathfuse.validate import short as _shown

__all__ = ["GlobalPlan", "plan_global", "route", "snap_cell", "searched", "found_message"]

_NO_POINTS = np.zeros((0, 2))
_NO_POINTS.setflags(write=False)
_NO_CELLS = np.zeros((0, 2), dtype=np.int64)
_NO_CELLS.setflags(write=False)


@dataclass(eq=False)
class GlobalPlan:
    """The outcome of :func:`plan_global`.

    Attributes
    ----------
    status : Status
        ``SUCCESS``, ``NO_PATH``, ``MAX_ITERATIONS``, ``TIMEOUT``, or
        ``START_/GOAL_OCCUPIED`` when a disc robot finds no c-space cell to
        start or end in.
    cells : (N, 2) int array
        ``(row, col)`` from the start cell to the goal cell.
    points : (N, 2) float array
        Their centres (metres).
    problem : Problem
        The problem planned (for :attr:`waypoints`).
    waypoints : (M, 2) float array
        What a controller follows: the start, the centres, the goal.
    length_m : float
        The A* cost in metres (the length of ``points``).
    expansions : int
    time_s : float
        Time of the search itself (per-map buffers and numba compilation
        are prepared before the clock starts).
    message : str
    heuristic : str
    corner_cutting : bool
    planner : str
        The registered global planner that made it (``astar``, ``jps``, a plug-in).
    taut : bool
        Whether the path turns where it touches the robot's clearance (an
        any-angle path): a holonomic follower stops on each corner.
    """

    status: Status
    cells: np.ndarray = field(default_factory=lambda: _NO_CELLS)
    points: np.ndarray = field(default_factory=lambda: _NO_POINTS)
    problem: Problem | None = field(default=None, repr=False)
    length_m: float = math.inf
    expansions: int = 0
    time_s: float = 0.0
    message: str = ""
    heuristic: str = "euclidean"
    corner_cutting: bool = False
    planner: str = "astar"
    taut: bool = False

    @property
    def success(self) -> bool:
        return self.status is Status.SUCCESS

    @cached_property
    def waypoints(self) -> np.ndarray:
        """What a controller follows (computed on first use: ``astar`` never needs it)."""
        if self.problem is None or not self.success:
            return _NO_POINTS
        return _waypoints(self.problem, self.points)


def snap_cell(occ: np.ndarray, grid: GridMap, p: tuple[float, float],
              r: float) -> tuple[int, int] | None:
    """A free cell of ``occ`` near ``p`` whose centre a disc of radius ``r`` reaches in a
    clear straight move (nearest first, within two cells; asked of the map's
    :class:`~pathfuse.costmap.Costmap`, :func:`~pathfuse.costmap.move_clear`); None if there
    is none."""
    res = grid.resolution
    ox, oy = grid.origin
    c = math.floor((p[0] - ox) / res)
    rr = math.floor((p[1] - oy) / res)
    h, w = occ.shape
    cands = []
    for dr in range(-2, 3):
        for dc in range(-2, 3):
            r2, c2 = rr + dr, c + dc
            if 0 <= r2 < h and 0 <= c2 < w and not occ[r2, c2]:
                cx = ox + (c2 + 0.5) * res
                cy = oy + (r2 + 0.5) * res
                cands.append((math.hypot(cx - p[0], cy - p[1]), r2, c2, cx, cy))
    cands.sort(key=lambda t: (t[0], t[1], t[2]))
    cm = costmap_for(grid, r, lattice=False)
    for _, r2, c2, cx, cy in cands:
        if move_clear(cm, p[0], p[1], cx, cy, r):
            return (r2, c2)
    return None


def plan_global(problem: Problem, heuristic: str = "euclidean", corner_cutting: bool = False,
                occupied: np.ndarray | None = None, max_expansions: int | None = None,
                time_limit_s: float | None = None, jps: bool = False) -> GlobalPlan:
    """Grid A* for ``problem`` (its start and goal must be free: :meth:`Problem.failure`).

    Parameters
    ----------
    problem : Problem
    heuristic : {"euclidean", "octile"}
    corner_cutting : bool
        Allow a diagonal move past a blocked orthogonal neighbour (the path
        then grazes obstacle corners).
    occupied : (H, W) bool array, optional
        A c-space of the map's shape to search instead (a replanner's, with
        moving discs rasterised into it).
    max_expansions : int, optional
        Stop with ``MAX_ITERATIONS`` after this many expansions (default: no
        cap beyond the number of free cells).
    time_limit_s : float, optional
        Default: the problem's budget.
    jps : bool
        Search with jump point search (:mod:`pathfuse.search.jps`: the same
        optimal costs without corner cutting, fewer expansions; no clearance
        cost) instead of A*.
    """
    if heuristic not in HEURISTICS:
        raise ConfigError(f"heuristic: must be one of {', '.join(map(repr, HEURISTICS))}, "
                          f"got {_shown(heuristic)}")
    grid = problem.grid
    r = problem.robot_radius_m
    if r == 0 and occupied is None:  # a point robot on the map itself: the problem's cells
        cs = grid
        occ = grid.occupied
        sc, gc = problem.start_cell, problem.goal_cell
    else:
        cs = grid.cspace(r)
        occ = cs.occupied if occupied is None else occupied
        snapped = (snap_cell(occ, grid, problem.start, r), snap_cell(occ, grid, problem.goal, r))
        if snapped[0] is None or snapped[1] is None:
            what = "start" if snapped[0] is None else "goal"
            status = Status.START_OCCUPIED if snapped[0] is None else Status.GOAL_OCCUPIED
            return GlobalPlan(status, message=f"no free cell near the {what} that the robot "
                              f"(radius {r:g} m) can reach in a straight line",
                              heuristic=heuristic, corner_cutting=corner_cutting)
        sc, gc = snapped[0], snapped[1]
    # a margin needs clearance_m > 0 or a robot (Problem.inflation_m is 0 without either)
    if not jps and (problem.clearance_m > 0 or problem.robot is not None) \
            and problem.inflation_m > 0:
        return _plan_with_margin(problem, occ, sc, gc, heuristic, corner_cutting,
                                 max_expansions)
    if jps:
        from pathfuse.search.jps import JPSSearcher, get_jps_searcher

        searcher: Any = get_jps_searcher(cs) if occupied is None else JPSSearcher(occ)
    elif occupied is None:
        searcher = get_searcher(cs, corner_cutting=corner_cutting)
    else:
        searcher = AStarSearcher(occ, corner_cutting=corner_cutting)
    limit = problem.budget.time_limit_s if time_limit_s is None else time_limit_s
    ox, oy = grid.origin
    origin = (ox, oy, grid.resolution)
    t0 = time.perf_counter()
    # the cells are in bounds and free (the problem and the snapping checked them)
    res = searcher.search_checked(sc, gc, heuristic, max_expansions, limit, origin)
    elapsed = time.perf_counter() - t0
    return searched(problem, res, elapsed, limit, heuristic, corner_cutting)


def searched(problem: Problem, res: Any, elapsed: float, limit: float | None, heuristic: str,
             corner_cutting: bool) -> GlobalPlan:
    """The :class:`GlobalPlan` of a grid search's result ``res`` (a
    :class:`~pathfuse.search.astar.SearchResult` with world points) that took ``elapsed``
    seconds under the time limit ``limit``: :func:`plan_global`'s outcome, its message
    included."""
    if res.status is not Status.SUCCESS:
        if res.status is Status.NO_PATH:
            msg = ("goal is not reachable from start (different connected free regions)"
                   if res.expansions == 0
                   else f"goal is not reachable from start ({res.expansions} expansions)")
        elif res.status is Status.MAX_ITERATIONS:
            msg = f"stopped after {res.expansions} expansions (max_iterations)"
        else:
            msg = (f"stopped after {elapsed:.3g} s > time_limit_s={limit:g} "
                   f"({res.expansions} expansions)")
        return GlobalPlan(res.status, expansions=res.expansions, time_s=elapsed, message=msg,
                          heuristic=heuristic, corner_cutting=corner_cutting)
    length = res.cost * problem.grid.resolution
    return GlobalPlan(Status.SUCCESS, res.cells, res.points, problem, length, res.expansions,
                      elapsed, found_message(len(res.cells), length, res.expansions),
                      heuristic, corner_cutting)


def found_message(cells: int, length_m: float, expansions: int) -> str:
    """The message of a grid path found (:func:`plan_global`'s)."""
    return f"path through {cells} cells, {length_m:.6g} m, {expansions} expansions"


_WARM_COST: list[bool] = []


def _plan_with_margin(problem: Problem, occ: np.ndarray, sc: tuple[int, int],
                      gc: tuple[int, int], heuristic: str, corner_cutting: bool,
                      max_expansions: int | None) -> GlobalPlan:
    """A* with the clearance cost of :mod:`pathfuse.search.costaware` (a margin is set)."""
    from pathfuse.search.costaware import (
        clearance_multipliers,
        costaware_search,
        warmup_costaware,
    )

    if not _WARM_COST:
        warmup_costaware()  # compilation stays out of time_s
        _WARM_COST.append(True)
    grid = problem.grid
    margin = problem.inflation_m
    mult = clearance_multipliers(grid, problem.robot_radius_m, margin)
    t0 = time.perf_counter()
    status, cells, cost, exp = costaware_search(occ, mult, sc, gc, corner_cutting,
                                                max_expansions)
    elapsed = time.perf_counter() - t0
    if status is Status.NO_PATH:
        return GlobalPlan(Status.NO_PATH, expansions=exp, time_s=elapsed,
                          message=f"goal is not reachable from start ({exp} expansions)",
                          heuristic=heuristic, corner_cutting=corner_cutting)
    if status is Status.MAX_ITERATIONS:
        return GlobalPlan(Status.MAX_ITERATIONS, expansions=exp, time_s=elapsed,
                          message=f"stopped after {exp} expansions (max_iterations)",
                          heuristic=heuristic, corner_cutting=corner_cutting)
    res = grid.resolution
    pts = np.column_stack([grid.origin[0] + (cells[:, 1] + 0.5) * res,
                           grid.origin[1] + (cells[:, 0] + 0.5) * res])
    length = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
    return GlobalPlan(Status.SUCCESS, cells, pts, problem, length, exp, elapsed,
                      f"path through {len(cells)} cells, {length:.6g} m, keeping a "
                      f"{margin:g} m margin where it can (cost {cost * res:.6g}), "
                      f"{exp} expansions", heuristic, corner_cutting)


def _waypoints(problem: Problem, centres: np.ndarray) -> np.ndarray:
    """``[start, centres..., goal]``, leaving out the first and last centres when the straight
    move past them is clear (the robot's :class:`~pathfuse.costmap.Costmap`), and repeated
    points."""
    cm = costmap_for(problem.grid, problem.robot_radius_m, lattice=False)
    clear = cm.clear_m
    (sx, sy), (gx, gy) = problem.start, problem.goal
    i0 = 0
    n = centres.shape[0]
    if n > 1 and move_clear(cm, sx, sy, centres[1, 0], centres[1, 1], clear):
        i0 = 1
    i1 = n
    if i1 - i0 > 1 and move_clear(cm, centres[i1 - 2, 0], centres[i1 - 2, 1], gx, gy, clear):
        i1 -= 1
    mid = centres[i0:i1]  # distinct cells: a point can repeat only at the two joints
    head = not (mid[0, 0] == sx and mid[0, 1] == sy)
    tail = not (mid[-1, 0] == gx and mid[-1, 1] == gy)
    path = np.empty((mid.shape[0] + head + tail, 2))
    if head:
        path[0, 0], path[0, 1] = sx, sy
    path[int(head):int(head) + mid.shape[0]] = mid
    if tail:
        path[-1, 0], path[-1, 1] = gx, gy
    return path


def route(grid: GridMap, start: object, goal: object, robot_radius_m: float = 0.0,
          heuristic: str = "euclidean") -> np.ndarray | None:
    """The waypoints a controller would follow from ``start`` to ``goal``, or None when
    the start or goal is blocked or A* finds no path.

    >>> g = GridMap.from_rows(["....", ".##.", "...."])
    >>> route(g, (0.5, 0.5), (3.5, 2.5)).tolist()
    [[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5], [3.5, 1.5], [3.5, 2.5]]
    >>> route(g, (0.5, 0.5), (1.5, 1.5)) is None   # the goal lies in an obstacle
    True
    """
    problem = Problem.create(grid, start, goal, robot_radius_m)
    if problem.failure() is not None:
        return None
    gp = plan_global(problem, heuristic)
    return gp.waypoints if gp.success else None
