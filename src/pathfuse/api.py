"""The one-call entry point: :func:`plan`."""

from __future__ import annotations

from typing import Any

from pathfuse.grid import GridMap
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.planners.run import solve
from pathfuse.problem import Problem
from pathfuse.result import Budget, PlanResult

__all__ = ["plan"]


def plan(
    grid: GridMap,
    start: object,
    goal: object,
    planner: str = "astar",
    *,
    robot_radius_m: float | None = None,
    clearance_m: float = 0.0,
    robot: Any = None,
    budget: Budget | None = None,
    **params: Any,
) -> PlanResult:
    """Plan a path on ``grid`` from ``start`` to ``goal`` (world coordinates, metres).

    The planner's global planner (if any) runs first, then its controller
    drives to the goal on the static map (:func:`pathfuse.simulate` runs the
    same controller among moving obstacles).

    Parameters
    ----------
    grid : GridMap
        The map.
    start, goal : (float, float)
        World coordinates in metres.
    planner : str
        A name from :func:`pathfuse.planner_names` (``pathfuse planners``).
    robot_radius_m : float
        Radius of a disc robot (default 0: a point; with ``robot``, its
        radius).  The global planner searches the map with obstacles and the
        map's edge grown by it, and every move keeps that clearance.
    clearance_m : float
        A soft safety margin beyond the radius (ours; default 0 = off): A*
        pays an extra cost near obstacles and the controllers keep the
        margin where they can.  ``info["min_clearance_m"]`` reports the
        least clearance of the path's disc (checked independently).
    robot : RobotModel, optional
        The robot's kinematics (:class:`pathfuse.robot.RobotModel`); used by
        the controllers that drive a model offline (``dwa``; default: a
        diff-drive robot with :data:`pathfuse.robot.DIFF_DRIVE_DEFAULTS`).
    budget : Budget, optional
        Iteration and time caps; every planner also has finite defaults.
    **params
        Planner parameters (see ``pathfuse planners`` or each planner's
        parameter dataclass).

    Returns
    -------
    PlanResult
        Truthy on success.  Failures are statuses, not exceptions.

    Raises
    ------
    ConfigError
        Unknown planner or parameter, a bad value, or a bad robot radius.
    QueryError
        ``start`` or ``goal`` is not a pair of finite numbers, or ``grid`` is
        not a GridMap.

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
    >>> plan(g, (0.5, 0.5), (3.5, 2.5), robot_radius_m=0.6).status.name
    'START_OCCUPIED'
    """
    spec = get_planner(planner)
    cfg = make_params(spec, params)
    if robot_radius_m is None:
        robot_radius_m = getattr(robot, "radius_m", 0.0)
    return solve(spec, Problem.create(grid, start, goal, robot_radius_m, budget, clearance_m,
                                      robot), cfg)
