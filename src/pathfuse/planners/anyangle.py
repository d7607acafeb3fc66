"""Any-angle global planners and the true shortest path: ``thetastar``, ``lazy-thetastar``,
``astar-smooth`` and ``shortest``.

Each is a *global planner* plus the ``follow`` controller (as ``astar`` is):
the global planner makes a path of straight sight lines from the start point
to the goal point; offline :func:`pathfuse.plan` returns it, online
:func:`pathfuse.simulate` walks it at full speed, blind to moving discs (as
``astar`` does; on a diff-drive robot with Regulated Pure Pursuit,
:mod:`pathfuse.planners.rpp`).  ``Budget.max_iterations`` caps the global search's
expansions.

``thetastar``
    Theta* (Nash, Daniel, Koenig, Felner, AAAI 2007) on the robot's c-space
    grid (:mod:`pathfuse.search.thetastar`).  Every sight line is checked
    exactly against the occupied squares, keeping the robot radius plus
    pathfuse's margin, so the path is collision-free by
    :mod:`pathfuse.metrics`.  For a point robot it is never longer than the A*
    path (tested).
``lazy-thetastar``
    Lazy Theta* (Nash, Koenig, Tovey, AAAI 2010): the same paths up to ties,
    fewer sight-line checks.
``astar-smooth``
    Grid A* (no corner cutting), then line-of-sight shortcutting of its
    waypoints (A* PS, :func:`pathfuse.search.los.smooth_path`).
``shortest``
    The shortest path among the occupied squares
    (:mod:`pathfuse.search.visibility`, where its exact definition is): for a
    point robot the physical limit of path length, within ``1.5e-6`` cells per
    obstacle point it touches, and a lower bound of the length of every pathfuse
    planner that keeps pathfuse's margin (all, by default); for a disc
    robot the shortest path of the square robot that holds the disc.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..#...", "..#...", "......"])
>>> [round(plan(g, (0.5, 0.5), (5.5, 3.5), planner=p).length, 4)
...  for p in ("astar", "astar-smooth", "thetastar", "shortest")]
[6.8284, 6.6056, 6.6056, 6.085]
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.astar import FollowController
from pathfuse.planners.base import Outcome
from pathfuse.planners.global_astar import GlobalPlan, plan_global, snap_cell
from pathfuse.planners.params import GlobalAStarParams, PursuitParams
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem
from pathfuse.result import Status

__all__ = ["ThetaStarParams", "SmoothParams", "ShortestParams", "AnyAnglePlan",
           "plan_any_angle", "ANY_ANGLE"]

#: The global planners of this module (``PlannerSpec.global_planner`` values).
ANY_ANGLE = ("thetastar", "lazy-thetastar", "astar-smooth", "shortest")


@dataclass(frozen=True)
class ThetaStarParams(PursuitParams):
    """Parameters of ``thetastar`` and ``lazy-thetastar``: the follower's on a diff-drive
    robot (the search has none: the heuristic is the Euclidean distance, the corner rule
    pathfuse's)."""


@dataclass(frozen=True)
class SmoothParams(PursuitParams, GlobalAStarParams):
    """Parameters of ``astar-smooth``: the heuristic of its A*, the follower's on a
    diff-drive robot."""


@dataclass(frozen=True)
class ShortestParams(PursuitParams):
    """Parameters of ``shortest``: the follower's on a diff-drive robot (the search has
    none)."""


@dataclass(eq=False)
class AnyAnglePlan(GlobalPlan):
    """A global plan whose points are already what a controller follows."""

    @cached_property
    def waypoints(self) -> np.ndarray:  # type: ignore[override]
        return self.points


def _fail(status: Status, message: str, expansions: int = 0, time_s: float = 0.0) -> GlobalPlan:
    return AnyAnglePlan(status, expansions=expansions, time_s=time_s, message=message)


def plan_any_angle(kind: str, problem: Problem, params: Any,
                   max_expansions: int | None = None) -> GlobalPlan:
    """Run the global planner ``kind`` (one of :data:`ANY_ANGLE`) for ``problem``."""
    import time

    grid = problem.grid
    r = problem.robot_radius_m
    ox, oy = grid.origin
    res = grid.resolution
    clear = r + MARGIN_FRAC * res
    limit = problem.budget.time_limit_s
    if kind == "astar-smooth":
        gp = plan_global(problem, params.heuristic, False, max_expansions=max_expansions)
        if not gp.success:
            return gp
        from pathfuse.search.los import smooth_path

        t0 = time.perf_counter()
        pts = smooth_path(np.ascontiguousarray(gp.waypoints, dtype=np.float64), grid.occupied,
                          ox, oy, res, clear)
        elapsed = time.perf_counter() - t0
        length = _length(pts)
        return AnyAnglePlan(Status.SUCCESS, points=pts, problem=problem, length_m=length,
                            expansions=gp.expansions, time_s=gp.time_s + elapsed,
                            message=f"A* path of {len(gp.waypoints)} points smoothed to "
                                    f"{len(pts)}, {length:.6g} m, {gp.expansions} expansions",
                            heuristic=gp.heuristic)
    if kind == "shortest":
        from pathfuse.search.visibility import shortest_path

        t0 = time.perf_counter()
        # the A* path's length bounds the search (an ellipse of useful corners); the
        # visibility graph's answer does not depend on it (see shortest_path)
        gp = plan_global(problem, "octile", False)
        bound = _length(gp.waypoints) if gp.success else None
        res_ = shortest_path(grid.occupied, ox, oy, res, r, problem.start, problem.goal,
                             max_expansions, limit, upper_bound_m=bound)
        elapsed = time.perf_counter() - t0
        return _from_result(res_, problem, elapsed, "visibility graph")
    if kind not in ("thetastar", "lazy-thetastar"):
        raise ValueError(f"unknown any-angle planner {kind!r}")
    from pathfuse.search.thetastar import theta_star

    cs = grid.cspace(r)
    if r > 0:
        sc = snap_cell(cs.occupied, grid, problem.start, r)
        gc = snap_cell(cs.occupied, grid, problem.goal, r)
        if sc is None or gc is None:
            what = "start" if sc is None else "goal"
            status = Status.START_OCCUPIED if sc is None else Status.GOAL_OCCUPIED
            return _fail(status, f"no free cell near the {what} that the robot (radius {r:g} m) "
                                 "can reach in a straight line")
    else:
        sc, gc = problem.start_cell, problem.goal_cell
    t0 = time.perf_counter()
    out = theta_star(~cs.occupied, grid.occupied, ox, oy, res, clear, sc, problem.start, gc,
                     problem.goal, lazy=kind == "lazy-thetastar", max_expansions=max_expansions,
                     time_limit_s=limit)
    elapsed = time.perf_counter() - t0
    return _from_result(out, problem, elapsed, "Theta*" if kind == "thetastar" else "Lazy Theta*")


def _length(pts: np.ndarray) -> float:
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0


def _from_result(out: Any, problem: Problem, elapsed: float, what: str) -> GlobalPlan:
    if out.status is Status.SUCCESS:
        length = _length(out.points)
        return AnyAnglePlan(Status.SUCCESS, points=out.points, problem=problem, length_m=length,
                            expansions=out.expansions, time_s=elapsed,
                            message=f"{what}: {len(out.points)} points, {length:.6g} m, "
                                    f"{out.expansions} expansions")
    if out.status is Status.NO_PATH:
        msg = f"goal is not reachable from start ({what}, {out.expansions} expansions)"
    elif out.status is Status.MAX_ITERATIONS:
        msg = f"stopped after {out.expansions} expansions (max_iterations)"
    else:
        msg = f"stopped after {elapsed:.3g} s ({out.expansions} expansions)"
    return _fail(out.status, msg, out.expansions, elapsed)


class PathController(FollowController):
    """Follow the global planner's any-angle path (offline: return it as planned)."""

    label = "follow the path"
    search_budget: ClassVar[bool] = True
    kind: ClassVar[str] = ""
    # An any-angle path is taut: it turns where it touches the robot's clearance around an
    # obstacle corner, so a move across a corner (from a point before it to one after it)
    # would come closer than the radius.  Stopping on each corner costs at most one tick
    # per corner, and these paths have few.  (A holonomic robot's walk; a diff-drive robot
    # follows the path with Regulated Pure Pursuit, planners/rpp.py.)
    stop_at_corners: ClassVar[bool] = True

    def run(self, deadline: float | None) -> Outcome:
        gp = self.plan
        info = {"global_planner": self.kind, "corners": int(len(gp.points))}
        return Outcome(Status.SUCCESS, gp.points, 0, 0.0, gp.message, info, gp.length_m)

    @classmethod
    def warmup(cls) -> None:
        super().warmup()
        _warm(cls.kind)

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (*super().kernels(), *_kernels(cls.kind))


class ThetaStarController(PathController):
    name = kind = "thetastar"


class LazyThetaStarController(PathController):
    name = kind = "lazy-thetastar"


class SmoothController(PathController):
    name = kind = "astar-smooth"


class ShortestController(PathController):
    name = kind = "shortest"


def _warm(kind: str) -> None:
    if kind in ("thetastar", "lazy-thetastar"):
        from pathfuse.search import thetastar

        thetastar.warmup(lazy=kind == "lazy-thetastar")
    elif kind == "astar-smooth":
        from pathfuse.search.astar import warmup as astar_warmup
        from pathfuse.search.los import smooth_path

        astar_warmup()
        occ = np.zeros((3, 3), bool)
        occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
        smooth_path(np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 1.5]]), occ, 0.0, 0.0, 1.0, 1e-6)
    elif kind == "shortest":
        from pathfuse.search import visibility
        from pathfuse.search.astar import warmup as astar_warmup

        astar_warmup()
        visibility.warmup()


def _kernels(kind: str) -> Sequence[Any]:
    if kind in ("thetastar", "lazy-thetastar"):
        from pathfuse.search.thetastar import _theta_kernel

        return (_theta_kernel,)
    if kind == "astar-smooth":
        from pathfuse.search.kernel import _astar_kernel
        from pathfuse.search.los import smooth_path

        return (_astar_kernel, smooth_path)
    from pathfuse.search.kernel import _astar_kernel
    from pathfuse.search.visibility import _vis_kernel, convex_corners

    return (_astar_kernel, _vis_kernel, convex_corners)


_DESCRIPTIONS = {
    "thetastar": "Theta* (Nash et al. 2007): any-angle A* on the c-space grid with exact sight "
                 "lines; online it walks its path blind to moving discs",
    "lazy-thetastar": "Lazy Theta* (Nash et al. 2010): Theta* checking each sight line only "
                      "when a node is expanded",
    "astar-smooth": "grid A* followed by line-of-sight shortcutting of its path (A* PS)",
    "shortest": "the true shortest path among the occupied squares (visibility graph over "
                "their convex corners, A*): the physical limit of path length",
}
_PARAMS = {"thetastar": ThetaStarParams, "lazy-thetastar": ThetaStarParams,
           "astar-smooth": SmoothParams, "shortest": ShortestParams}

_CONTROLLERS: dict[str, type[PathController]] = {
    "thetastar": ThetaStarController, "lazy-thetastar": LazyThetaStarController,
    "astar-smooth": SmoothController, "shortest": ShortestController}

for _kind in ANY_ANGLE:
    register(PlannerSpec(name=_kind, params_cls=_PARAMS[_kind],
                         description=_DESCRIPTIONS[_kind], controller=_CONTROLLERS[_kind],
                         global_planner=_kind))
