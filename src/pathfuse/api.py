"""The one-call entry point: :func:`plan`."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.result import Budget, PlanResult, QueryError, Status

__all__ = ["plan", "as_point", "check_query"]

_WARM: set[str] = set()


def as_point(value: object, what: str) -> np.ndarray:
    """A finite ``(x, y)`` float array, or :class:`QueryError` naming ``what``.

    >>> as_point((1, 2.5), "start").tolist()
    [1.0, 2.5]
    """
    try:
        p = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise QueryError(f"{what} must be two numbers (x, y), got {value!r}") from None
    if p.shape != (2,):
        raise QueryError(f"{what} must be two numbers (x, y), got {value!r}")
    if not np.all(np.isfinite(p)):
        raise QueryError(f"{what} must be finite, got {value!r}")
    return p


def check_query(grid: GridMap, start: np.ndarray, goal: np.ndarray) -> PlanResult | None:
    """A failed :class:`PlanResult` when start or goal is off the map or blocked, else None."""
    checks = (
        (start, "start", Status.START_OUT_OF_BOUNDS, Status.START_OCCUPIED),
        (goal, "goal", Status.GOAL_OUT_OF_BOUNDS, Status.GOAL_OCCUPIED),
    )
    for p, what, oob, occ in checks:
        if not grid.in_bounds(p)[0]:
            x0, y0, x1, y1 = grid.bounds
            return PlanResult(
                oob,
                message=f"{what} ({p[0]:g}, {p[1]:g}) is outside the map "
                f"[{x0:g}, {x1:g}) x [{y0:g}, {y1:g})",
            )
        if not grid.is_free(p)[0]:
            return PlanResult(occ, message=f"{what} ({p[0]:g}, {p[1]:g}) lies in an occupied cell")
    return None


def plan(
    grid: GridMap,
    start: object,
    goal: object,
    planner: str = "astar",
    *,
    budget: Budget | None = None,
    **params: Any,
) -> PlanResult:
    """Plan a path on ``grid`` from ``start`` to ``goal`` (world coordinates, metres).

    Parameters
    ----------
    grid : GridMap
        The map.  Plan on ``grid.inflate(robot_radius)`` for a disc robot.
    start, goal : (float, float)
        World coordinates in metres.
    planner : str
        A name from :func:`pathfuse.planner_names` (``pathfuse planners``).
    budget : Budget, optional
        Iteration and time caps; every planner also has finite defaults.
    **params
        Planner parameters (see each planner's parameter dataclass).

    Returns
    -------
    PlanResult
        Truthy on success.  Failures are statuses, not exceptions.

    Raises
    ------
    ConfigError
        Unknown planner or parameter.
    QueryError
        ``start`` or ``goal`` is not a pair of finite numbers.

    Notes
    -----
    The first call of a planner in a process compiles (or loads from numba's
    on-disk cache) its kernels *before* the clock starts, so ``time_s`` never
    includes JIT compilation.

    Examples
    --------
    >>> g = GridMap.from_rows(["....", ".##.", "...."])
    >>> r = plan(g, (0.5, 0.5), (3.5, 2.5))
    >>> r.status.name, round(r.length, 4)
    ('SUCCESS', 5.0)
    >>> plan(g, (1.5, 1.5), (3.5, 2.5)).status.name
    'START_OCCUPIED'
    """
    spec = get_planner(planner)
    cfg = make_params(spec, params)
    budget = budget or Budget()
    s = as_point(start, "start")
    g = as_point(goal, "goal")
    if not isinstance(grid, GridMap):
        raise QueryError(f"grid must be a pathfuse.GridMap, got {type(grid).__name__}")
    bad = check_query(grid, s, g)
    if bad is not None:
        return dataclasses.replace(bad, planner=spec.name)
    if spec.name not in _WARM:
        if spec.warmup is not None:
            spec.warmup()
        _WARM.add(spec.name)
    result = spec.func(grid, s, g, cfg, budget)
    return dataclasses.replace(result, planner=spec.name)
