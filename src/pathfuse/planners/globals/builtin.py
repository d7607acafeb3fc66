"""The built-in global planners, registered by name as a plug-in's would be, and
:func:`run_global`, which runs any registered one.

A global planner is ``func(problem) -> (N, 2) waypoints in metres, or None``
(:func:`~pathfuse.planners.registry.register_global_planner`).  The built-in
ones return a :class:`~pathfuse.planners.globals.astar.GlobalPlan` instead,
which carries what their searches know besides the path (expansions, the
status of a search that ran out of budget, the grid cells):

``astar``
    Exact 8-connected grid A* on the robot's c-space
    (:func:`~pathfuse.planners.globals.astar.plan_global`; the planner's
    ``heuristic`` and ``corner_cutting``).
``jps``
    Jump point search (:mod:`pathfuse.search.jps`): the same optimal costs
    as ``astar`` without corner cutting, far fewer expansions; the path is
    filled in cell by cell, so it is a grid path like A*'s.  It searches the
    c-space alone (no clearance cost: a ``clearance_m`` or a robot's
    ``inflation_m`` is not paid for).
``astar-smooth``
    ``astar``, then line-of-sight shortcutting of its waypoints (A* PS).
``thetastar``, ``lazy-thetastar``
    Theta* and Lazy Theta* on the c-space grid with exact sight lines
    (:mod:`pathfuse.search.thetastar`).
``shortest``
    The shortest path among the occupied squares (visibility graph,
    :mod:`pathfuse.search.visibility`).

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse.problem import Problem
>>> g = GridMap.from_rows(["......", "..#...", "..#...", "......"])
>>> pb = Problem.create(g, (0.5, 0.5), (5.5, 3.5))
>>> [round(run_global(n, pb).length_m, 4) for n in ("astar", "jps", "thetastar", "shortest")]
[6.8284, 6.8284, 6.6056, 6.085]
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.globals.astar import GlobalPlan, plan_global, snap_cell
from pathfuse.planners.registry import (
    _BUILTIN_GLOBAL,
    PluginError,
    get_global_planner,
    register_global_planner,
)
from pathfuse.problem import Problem
from pathfuse.result import PathfuseError, Status
from pathfuse.validate import short as _shown

__all__ = ["PathPlan", "run_global", "warm_global", "global_kernels"]


@dataclass(eq=False)
class PathPlan(GlobalPlan):
    """A global plan whose points are already what a controller follows (an any-angle
    path, or a plug-in's waypoints)."""

    @cached_property
    def waypoints(self) -> np.ndarray:  # type: ignore[override]
        return self.points


def _length(pts: np.ndarray) -> float:
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0


def run_global(name: str, problem: Problem, params: Any = None,
               max_expansions: int | None = None) -> GlobalPlan:
    """Run the registered global planner ``name`` for ``problem`` (start and goal free).

    A plug-in's waypoints become a :class:`PathPlan`; None becomes a ``NO_PATH``
    plan.  Anything else it returns, and any exception but a pathfuse one, is
    a :class:`~pathfuse.planners.registry.PluginError` naming it.
    """
    gs = get_global_planner(name)
    if gs.func is _astar and gs.plugin is None:  # every planner's default: _astar's body
        out = plan_global(problem, getattr(params, "heuristic", "euclidean"),
                          bool(getattr(params, "corner_cutting", False)),
                          max_expansions=max_expansions)
        out.planner = name
        return out
    kw: dict[str, Any] = {}
    accepts = gs.accepts
    if "params" in accepts:
        kw["params"] = params
    if "max_expansions" in accepts:
        kw["max_expansions"] = max_expansions
    builtin = name in _BUILTIN_GLOBAL and gs.plugin is None
    t0 = time.perf_counter()
    try:
        out = gs.func(problem, **kw)
    except PathfuseError:
        raise
    except Exception as exc:
        if builtin:
            raise
        raise PluginError(f"global planner {name!r}{_from(gs.plugin)}: "
                          f"{type(exc).__name__}: {exc}") from exc
    elapsed = time.perf_counter() - t0
    if isinstance(out, GlobalPlan):
        out.planner = name
        return out
    if out is None:
        return PathPlan(Status.NO_PATH, time_s=elapsed, planner=name,
                        message=f"goal is not reachable from start (global planner {name!r})")
    try:
        pts = np.array(out, dtype=np.float64)
    except (TypeError, ValueError):
        pts = np.zeros((0, 3))
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1 or not np.isfinite(pts).all():
        raise PluginError(f"global planner {name!r}{_from(gs.plugin)}: must return (N, 2) "
                          f"finite waypoints in metres or None, got {_shown(out)}")
    pts.setflags(write=False)
    length = _length(pts)
    return PathPlan(Status.SUCCESS, points=pts, problem=problem, length_m=length,
                    time_s=elapsed, planner=name, taut=gs.taut,
                    message=f"{name}: {len(pts)} waypoints, {length:.6g} m")


def _from(plugin: str | None) -> str:
    return f" (plug-in {plugin!r})" if plugin else ""


def warm_global(name: str, heuristic: str | None = None) -> None:
    """Compile (or load from numba's cache) the kernels of the global planner ``name``;
    for ``astar`` and ``astar-smooth``, A*'s kernel of ``heuristic`` only (each heuristic
    has its own; None: both)."""
    gs = get_global_planner(name)
    if gs.warmup is not None and gs.warmup in _BY_HEURISTIC and heuristic is not None:
        gs.warmup(heuristic)
    elif gs.warmup is not None:
        gs.warmup()


def global_kernels(name: str, heuristic: str | None = None) -> Sequence[Any]:
    """The numba kernels of the global planner ``name`` (to tell a cold cache); for
    ``astar`` and ``astar-smooth``, A*'s kernel of ``heuristic`` (None: the default's), as
    :func:`warm_global` compiles it."""
    gs = get_global_planner(name)
    if gs.kernels is None:
        return ()
    if gs.kernels in _KERNELS_BY_HEURISTIC and heuristic is not None:
        return tuple(gs.kernels(heuristic))
    return tuple(gs.kernels())


# --------------------------------------------------------------------------- the built-ins
def _astar(problem: Problem, params: Any = None, max_expansions: int | None = None
           ) -> GlobalPlan:
    return plan_global(problem, getattr(params, "heuristic", "euclidean"),
                       bool(getattr(params, "corner_cutting", False)),
                       max_expansions=max_expansions)


def _jps(problem: Problem, max_expansions: int | None = None) -> GlobalPlan:
    return plan_global(problem, "octile", max_expansions=max_expansions, jps=True)


def _smooth(problem: Problem, params: Any = None, max_expansions: int | None = None
            ) -> GlobalPlan:
    gp = plan_global(problem, getattr(params, "heuristic", "euclidean"), False,
                     max_expansions=max_expansions)
    if not gp.success:
        return gp
    from pathfuse.search.los import smooth_path

    grid = problem.grid
    ox, oy = grid.origin
    clear = problem.robot_radius_m + MARGIN_FRAC * grid.resolution
    t0 = time.perf_counter()
    pts = smooth_path(np.ascontiguousarray(gp.waypoints, dtype=np.float64), grid.occupied,
                      ox, oy, grid.resolution, clear)
    elapsed = time.perf_counter() - t0
    length = _length(pts)
    return PathPlan(Status.SUCCESS, points=pts, problem=problem, length_m=length,
                    expansions=gp.expansions, time_s=gp.time_s + elapsed,
                    message=f"A* path of {len(gp.waypoints)} points smoothed to "
                            f"{len(pts)}, {length:.6g} m, {gp.expansions} expansions",
                    heuristic=gp.heuristic, taut=True)


def _shortest(problem: Problem, max_expansions: int | None = None) -> GlobalPlan:
    from pathfuse.search.visibility import shortest_path

    grid = problem.grid
    ox, oy = grid.origin
    t0 = time.perf_counter()
    # the A* path's length bounds the search (an ellipse of useful corners); the
    # visibility graph's answer does not depend on it (see shortest_path)
    gp = plan_global(problem, "octile", False)
    bound = _length(gp.waypoints) if gp.success else None
    out = shortest_path(grid.occupied, ox, oy, grid.resolution, problem.robot_radius_m,
                        problem.start, problem.goal, max_expansions,
                        problem.budget.time_limit_s, upper_bound_m=bound)
    return _from_result(out, problem, time.perf_counter() - t0, "visibility graph")


def _theta(problem: Problem, max_expansions: int | None, lazy: bool) -> GlobalPlan:
    from pathfuse.search.thetastar import theta_star

    grid = problem.grid
    r = problem.robot_radius_m
    ox, oy = grid.origin
    cs = grid.cspace(r)
    if r > 0:
        sc = snap_cell(cs.occupied, grid, problem.start, r)
        gc = snap_cell(cs.occupied, grid, problem.goal, r)
        if sc is None or gc is None:
            what = "start" if sc is None else "goal"
            status = Status.START_OCCUPIED if sc is None else Status.GOAL_OCCUPIED
            return PathPlan(status, message=f"no free cell near the {what} that the robot "
                                            f"(radius {r:g} m) can reach in a straight line")
    else:
        sc, gc = problem.start_cell, problem.goal_cell
    t0 = time.perf_counter()
    out = theta_star(~cs.occupied, grid.occupied, ox, oy, grid.resolution,
                     r + MARGIN_FRAC * grid.resolution, sc, problem.start, gc, problem.goal,
                     lazy=lazy, max_expansions=max_expansions,
                     time_limit_s=problem.budget.time_limit_s)
    return _from_result(out, problem, time.perf_counter() - t0,
                        "Lazy Theta*" if lazy else "Theta*")


def _thetastar(problem: Problem, max_expansions: int | None = None) -> GlobalPlan:
    return _theta(problem, max_expansions, False)


def _lazy_thetastar(problem: Problem, max_expansions: int | None = None) -> GlobalPlan:
    return _theta(problem, max_expansions, True)


def _from_result(out: Any, problem: Problem, elapsed: float, what: str) -> GlobalPlan:
    if out.status is Status.SUCCESS:
        length = _length(out.points)
        return PathPlan(Status.SUCCESS, points=out.points, problem=problem, length_m=length,
                        expansions=out.expansions, time_s=elapsed, taut=True,
                        message=f"{what}: {len(out.points)} points, {length:.6g} m, "
                                f"{out.expansions} expansions")
    if out.status is Status.NO_PATH:
        msg = f"goal is not reachable from start ({what}, {out.expansions} expansions)"
    elif out.status is Status.MAX_ITERATIONS:
        msg = f"stopped after {out.expansions} expansions (max_iterations)"
    else:
        msg = f"stopped after {elapsed:.3g} s ({out.expansions} expansions)"
    return PathPlan(out.status, expansions=out.expansions, time_s=elapsed, message=msg)


# --------------------------------------------------------------------------- warm-ups
def _warm_astar(heuristic: str | None = None) -> None:
    from pathfuse.search.astar import HEURISTICS, warmup

    warmup(HEURISTICS if heuristic is None else (heuristic,))


def _warm_jps() -> None:
    from pathfuse.search.jps import warmup

    warmup()


def _warm_smooth(heuristic: str | None = None) -> None:
    from pathfuse.search.los import smooth_path

    _warm_astar(heuristic)
    occ = np.zeros((3, 3), bool)
    occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
    smooth_path(np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 1.5]]), occ, 0.0, 0.0, 1.0, 1e-6)


def _warm_theta(lazy: bool) -> None:
    from pathfuse.search import thetastar

    thetastar.warmup(lazy=lazy)


def _warm_shortest() -> None:
    from pathfuse.search import visibility

    _warm_astar("octile")  # the A* run that bounds the search
    visibility.warmup()


def _k_astar(heuristic: str | None = None) -> Sequence[Any]:
    from pathfuse.search.kernel import _astar_radix, _astar_ring

    # each heuristic has its own kernel; None: the default's (euclidean)
    return (_astar_radix if heuristic == "octile" else _astar_ring,)


def _k_jps() -> Sequence[Any]:
    from pathfuse.search.jps import _jps_kernel

    return (_jps_kernel,)


def _k_smooth(heuristic: str | None = None) -> Sequence[Any]:
    from pathfuse.search.los import smooth_path

    return (*_k_astar(heuristic), smooth_path)


def _k_theta() -> Sequence[Any]:
    from pathfuse.search.thetastar import _theta_kernel

    return (_theta_kernel,)


def _k_shortest() -> Sequence[Any]:
    from pathfuse.search.kernel import _astar_radix
    from pathfuse.search.visibility import _vis_kernel, convex_corners

    return (_astar_radix, _vis_kernel, convex_corners)


_BY_HEURISTIC = (_warm_astar, _warm_smooth)  # warm-ups that take the A* heuristic
_KERNELS_BY_HEURISTIC = (_k_astar, _k_smooth)  # and their kernel lists

register_global_planner(
    "astar", _astar, "exact 8-connected grid A* on the robot's c-space (the planner's "
    "heuristic and corner_cutting)", warmup=_warm_astar, kernels=_k_astar, taut=False)
register_global_planner(
    "jps", _jps, "jump point search (Harabor and Grastien, without corner cutting): A*'s "
    "optimal grid paths, far fewer expansions", warmup=_warm_jps, kernels=_k_jps, taut=False)
register_global_planner(
    "astar-smooth", _smooth, "grid A* followed by line-of-sight shortcutting of its path "
    "(A* PS)", warmup=_warm_smooth, kernels=_k_smooth)
register_global_planner(
    "thetastar", _thetastar, "Theta* (Nash et al. 2007): any-angle A* on the c-space grid "
    "with exact sight lines", warmup=lambda: _warm_theta(False), kernels=_k_theta)
register_global_planner(
    "lazy-thetastar", _lazy_thetastar, "Lazy Theta* (Nash et al. 2010): Theta* checking each "
    "sight line only when a node is expanded", warmup=lambda: _warm_theta(True),
    kernels=_k_theta)
register_global_planner(
    "shortest", _shortest, "the true shortest path among the occupied squares (visibility "
    "graph over their convex corners)", warmup=_warm_shortest, kernels=_k_shortest)
