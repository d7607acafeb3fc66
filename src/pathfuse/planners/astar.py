"""The ``astar`` planner: exact 8-connected grid A* between cell centres.

The path runs from the centre of the start cell to the centre of the goal
cell through the centres of the cells in between; its length is the A* cost
times the map resolution (a straight step is one cell side, a diagonal step
``sqrt(2)`` sides).  Other planners (fusion, ref6, ref7) call
:func:`plan_astar` directly for their global path.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse.result import Budget
>>> g = GridMap.from_rows(["....", ".##.", "...."], resolution=0.5)
>>> r = plan_astar(g, (0.25, 0.25), (1.75, 1.25), AStarParams(), Budget())
>>> r.status.name, r.length, r.path[[0, -1]].tolist()
('SUCCESS', 2.5, [[0.25, 0.25], [1.75, 1.25]])
>>> cut = plan_astar(g, (0.25, 0.25), (1.75, 1.25), AStarParams(corner_cutting=True), Budget())
>>> round(cut.length, 4)
2.2071
>>> plan_astar(g, (0.25, 0.25), (1.75, 1.25), AStarParams(), Budget(max_iterations=2)).status.name
'MAX_ITERATIONS'
>>> AStarParams(heuristic="manhattan")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: astar: heuristic must be one of 'euclidean', 'octile'; got 'manhattan'
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.result import Budget, ConfigError, PlanResult, QueryError, Status
from pathfuse.search.astar import HEURISTICS, SearchResult, get_searcher, warmup

__all__ = ["AStarParams", "plan_astar", "astar_cells"]


@dataclass(frozen=True)
class AStarParams:
    """Parameters of the ``astar`` planner.

    Attributes
    ----------
    heuristic : {"euclidean", "octile"}
        ``"euclidean"`` is the straight-line distance of the paper (eq. 2);
        ``"octile"`` is tighter on an 8-connected grid (fewer expansions).
        Both give optimal paths.
    corner_cutting : bool
        ``False`` (default, MovingAI convention): a diagonal step needs both
        orthogonally adjacent cells free.  ``True``: only the diagonal cell.
    """

    heuristic: str = "euclidean"
    corner_cutting: bool = False

    def __post_init__(self) -> None:
        if self.heuristic not in HEURISTICS:
            choices = ", ".join(repr(h) for h in HEURISTICS)
            raise ConfigError(
                f"astar: heuristic must be one of {choices}; got {self.heuristic!r}"
            )
        if not isinstance(self.corner_cutting, (bool, np.bool_)):
            raise ConfigError(
                f"astar: corner_cutting must be true or false; got {self.corner_cutting!r}"
            )
        object.__setattr__(self, "corner_cutting", bool(self.corner_cutting))


def _check_cell(grid: GridMap, cell: object, what: str) -> tuple[int, int]:
    try:
        r, c = (int(v) for v in np.asarray(cell).reshape(-1))
    except (TypeError, ValueError):
        raise QueryError(f"{what} cell must be two integers (row, col), got {cell!r}") from None
    if not (0 <= r < grid.height and 0 <= c < grid.width):
        raise QueryError(f"{what} cell ({r}, {c}) is outside the {grid.height}x{grid.width} map")
    if grid.occupied[r, c]:
        raise QueryError(f"{what} cell ({r}, {c}) is occupied")
    return r, c


def astar_cells(
    grid: GridMap,
    start_cell: tuple[int, int],
    goal_cell: tuple[int, int],
    *,
    heuristic: str = "euclidean",
    corner_cutting: bool = False,
    max_expansions: int | None = None,
    time_limit_s: float | None = None,
) -> SearchResult:
    """Grid A* between two free ``(row, col)`` cells of ``grid``.

    Returns a :class:`~pathfuse.search.astar.SearchResult` whose ``cells``
    run from start to goal and whose ``cost`` is in cells (multiply by
    ``grid.resolution`` for metres).  Raises :class:`QueryError` if a cell is
    out of the map or occupied.

    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> r = astar_cells(g, (0, 0), (2, 2))
    >>> r.status, r.cost, len(r.cells)
    ('SUCCESS', 4.0, 5)
    >>> round(astar_cells(g, (0, 0), (2, 2), corner_cutting=True).cost, 4)
    3.4142
    """
    s = _check_cell(grid, start_cell, "start")
    g = _check_cell(grid, goal_cell, "goal")
    if heuristic not in HEURISTICS:
        raise ConfigError(f"heuristic must be one of {HEURISTICS}, got {heuristic!r}")
    searcher = get_searcher(grid, corner_cutting=bool(corner_cutting))
    return searcher.search(
        s, g, heuristic=heuristic, max_expansions=max_expansions, time_limit_s=time_limit_s
    )


def plan_astar(
    grid: GridMap,
    start: object,
    goal: object,
    params: AStarParams | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Shortest 8-connected grid path from ``start`` to ``goal`` (world points, metres).

    Parameters
    ----------
    grid : GridMap
        The map (inflate it first for a robot with a radius).
    start, goal : (float, float)
        World coordinates; each is snapped to the cell it lies in.
    params : AStarParams, optional
    budget : Budget, optional
        ``max_iterations`` caps expansions (default: the number of free
        cells, which never cuts a search short); ``time_limit_s`` caps wall
        time, checked every 65,536 expansions.

    Returns
    -------
    PlanResult
        ``SUCCESS`` with the cell-centre path, ``NO_PATH``,
        ``MAX_ITERATIONS``, ``TIMEOUT``, or ``START_/GOAL_OUT_OF_BOUNDS`` /
        ``START_/GOAL_OCCUPIED``.  ``time_s`` covers the search only: the
        kernels are compiled, and the map's buffers built (first query on a
        map), before the clock starts.  ``info`` holds
        ``cells`` (the ``(row, col)`` path), ``cost_cells``, ``heuristic``
        and ``corner_cutting``.
    """
    from pathfuse.api import as_point, check_query

    params = params if params is not None else AStarParams()
    budget = budget if budget is not None else Budget()
    s = as_point(start, "start")
    g = as_point(goal, "goal")
    bad = check_query(grid, s, g)
    if bad is not None:
        return PlanResult(bad.status, planner="astar", message=bad.message)
    warmup()
    s_cell = tuple(int(v) for v in grid.world_to_cell(s)[0])
    g_cell = tuple(int(v) for v in grid.world_to_cell(g)[0])
    # per-map preparation (padded copy, buffers, labels) happens once per map and
    # is not part of a query's time, like numba compilation
    searcher = get_searcher(grid, corner_cutting=params.corner_cutting)
    t0 = time.perf_counter()
    res = searcher.search(
        s_cell,
        g_cell,
        heuristic=params.heuristic,
        max_expansions=budget.max_iterations,
        time_limit_s=budget.time_limit_s,
    )
    elapsed = time.perf_counter() - t0
    info = {
        "cells": res.cells,
        "cost_cells": res.cost,
        "heuristic": params.heuristic,
        "corner_cutting": params.corner_cutting,
    }
    status = Status[res.status]
    if status is Status.SUCCESS:
        length = res.cost * grid.resolution
        path = grid.cell_to_world(res.cells)
        msg = (
            f"path through {len(res.cells)} cells, {length:.6g} m, "
            f"{res.expansions} expansions"
        )
        return PlanResult(status, path, length, elapsed, "astar", res.expansions, 0, msg, info)
    if status is Status.NO_PATH:
        msg = (
            "goal is not reachable from start (different connected free regions)"
            if res.expansions == 0
            else f"goal is not reachable from start ({res.expansions} expansions)"
        )
    elif status is Status.MAX_ITERATIONS:
        msg = f"stopped after {res.expansions} expansions (max_iterations)"
    else:
        msg = (
            f"stopped after {elapsed:.3g} s > time_limit_s={budget.time_limit_s:g} "
            f"({res.expansions} expansions)"
        )
    return PlanResult(
        status, planner="astar", time_s=elapsed, expansions=res.expansions, message=msg, info=info
    )


register(
    PlannerSpec(
        name="astar",
        func=plan_astar,
        params_cls=AStarParams,
        description="Exact 8-connected grid A* (euclidean or octile heuristic, "
        "no corner cutting by default)",
        uses_astar=True,
        warmup=warmup,
    )
)


def global_astar(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    robot_radius_m: float = 0.0,
    time_limit_s: float | None = None,
) -> tuple[PlanResult, dict]:
    """Step 1 of the A*-based hybrids (fusion, ref6, ref7): the global A* path.

    A* runs with the paper's settings (Euclidean heuristic, no corner
    cutting) on the map grown by ``robot_radius_m``.  Returns the A* result
    and the ``info`` entries every hybrid reports: ``astar_path`` ((N, 2)
    cell centres), ``astar_length`` and ``astar_time_s``.
    """
    agrid = grid.inflate(robot_radius_m) if robot_radius_m > 0 else grid
    ares = plan_astar(agrid, start, goal, _HYBRID_PARAMS, Budget(time_limit_s=time_limit_s))
    info = {
        "astar_path": np.asarray(ares.path, dtype=np.float64).reshape(-1, 2),
        "astar_length": float(ares.length),
        "astar_time_s": float(ares.time_s),
    }
    return ares, info


def astar_failed(ares: PlanResult, planner: str, info: dict) -> PlanResult:
    """The result of a hybrid whose A* step failed: A*'s status, an empty path."""
    return PlanResult(ares.status, np.zeros((0, 2)), 0.0, ares.time_s, planner,
                      ares.expansions, 0, f"A* failed: {ares.message}", info)


_HYBRID_PARAMS = AStarParams(heuristic="euclidean", corner_cutting=False)
