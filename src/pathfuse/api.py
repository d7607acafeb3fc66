"""The one-call entry point: :func:`plan` (and :func:`plan_query`, the same body for
callers that hold the parameters as a mapping, as the playground's server does)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

from pathfuse.grid import GridMap
from pathfuse.planners.registry import PlannerSpec, get_planner, make_params
from pathfuse.planners.run import quick_plan, solve
from pathfuse.problem import Problem
from pathfuse.result import Budget, PlanResult

__all__ = ["plan", "plan_query", "Planned"]


class Planned(NamedTuple):
    """What :func:`plan_query` returns: the result and what it was planned with."""

    result: PlanResult
    spec: PlannerSpec
    params: Any
    problem: Problem


def plan_query(grid: GridMap, start: object, goal: object, planner: str = "astar",
               params: Mapping[str, Any] | None = None, *,
               robot_radius_m: float | None = None, clearance_m: float = 0.0,
               robot: Any = None, budget: Budget | None = None) -> Planned:
    """The body of :func:`plan`, with the planner's parameters as a mapping (no clash with
    the keywords): the result, the planner's spec, its parameters and the problem.

    >>> g = GridMap.from_rows(["....", ".##.", "...."])
    >>> q = plan_query(g, (0.5, 0.5), (3.5, 2.5), "fusion", {"global_planner": "jps"})
    >>> q.result.status.name, q.params.global_planner, q.spec.name
    ('SUCCESS', 'jps', 'fusion')
    """
    spec = get_planner(planner)
    cfg = make_params(spec, params)
    if robot_radius_m is None:
        robot_radius_m = getattr(robot, "radius_m", 0.0)
    problem = Problem.create(grid, start, goal, robot_radius_m, budget, clearance_m, robot)
    return Planned(solve(spec, problem, cfg), spec, cfg, problem)


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
        parameter dataclass).  Among them ``global_planner``: the global
        planner whose path the planner's controller follows, a name of
        :func:`pathfuse.global_planner_names` (plug-ins' included); default:
        the planner's own.  Every planner with a global planner takes it (not
        ``apf``, ``astar-replan``, ``mppi``).

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
    >>> g2 = GridMap.from_rows(["......", "..#...", "..#...", "......"])
    >>> [round(plan(g2, (0.5, 0.5), (5.5, 3.5), planner="fusion", global_planner=gp)
    ...        .info["astar_length"], 4) for gp in ("astar", "thetastar")]
    [6.8284, 6.6056]
    """
    # plan_query's body without its Planned tuple (the same checks in the same order)
    spec = get_planner(planner)
    cfg = make_params(spec, params)
    if robot_radius_m is None and robot is None and type(clearance_m) is float and \
            clearance_m == 0.0:  # a point robot: A*'s path as planned needs no Problem
        res = quick_plan(spec, cfg, grid, start, goal, budget)
        if res is not None:
            return res
    if robot_radius_m is None:  # None has no radius_m: no attribute look-up that fails
        robot_radius_m = 0.0 if robot is None else getattr(robot, "radius_m", 0.0)
    return solve(spec, Problem.create(grid, start, goal, robot_radius_m, budget, clearance_m,
                                      robot), cfg)
