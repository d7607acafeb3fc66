"""Grid A* as a planner: ``astar`` (follow the A* path) and ``astar-replan`` (replan at a rate).

``astar``
    Exact 8-connected grid A* between cell centres
    (:mod:`pathfuse.planners.globals.astar`).  Offline, :func:`pathfuse.plan`
    returns the A* path through the cell centres from the start cell to the
    goal cell; its length is the A* cost (a straight move is one cell side,
    a diagonal ``sqrt(2)`` sides, times the resolution), and
    ``Budget.max_iterations`` caps the expansions.  Online,
    :func:`pathfuse.simulate` walks the path (start, centres, goal) at full
    speed, blind to moving discs: the paper's "A* cannot handle dynamic
    obstacles", made measurable.  On a diff-drive robot it follows the path
    with Regulated Pure Pursuit (:mod:`pathfuse.planners.controllers.rpp`, Nav2's
    follower), still blind to moving discs.  ``astar-follow`` is an older
    name of it.
``astar-replan``
    Online, A* replanned every ``replan_period_s`` (default 1 s, as Nav2's
    default behaviour tree replans at 1 Hz) on the robot's c-space with the
    sensed discs rasterised as blocked cells (grown by the robot radius and
    ``margin_m``), the path walked at full speed in between (on a
    diff-drive robot followed by Regulated Pure Pursuit, each replanned path
    from its start); with no path the robot waits for the next replan.
    Offline, on a static map, every replan gives the first path, so
    ``plan()`` returns the ``astar`` path.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan, Budget
>>> g = GridMap.from_rows(["....", ".##.", "...."], resolution=0.5)
>>> r = plan(g, (0.25, 0.25), (1.75, 1.25))
>>> r.status.name, r.length, r.path[[0, -1]].tolist()
('SUCCESS', 2.5, [[0.25, 0.25], [1.75, 1.25]])
>>> round(plan(g, (0.25, 0.25), (1.75, 1.25), corner_cutting=True).length, 4)
2.2071
>>> plan(g, (0.25, 0.25), (1.75, 1.25), budget=Budget(max_iterations=2)).status.name
'MAX_ITERATIONS'
>>> plan(g, (0.25, 0.25), (1.75, 1.25), heuristic="manhattan")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: astar.heuristic: must be one of 'euclidean', 'octile', got 'manhattan'
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numba import njit

from pathfuse.metrics import PlanInfo
from pathfuse.planners.base import Controller, Observed, Outcome
from pathfuse.planners.globals.astar import plan_global
from pathfuse.planners.params import GlobalAStarParams, GlobalChoice, PursuitParams
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem
from pathfuse.result import Status
from pathfuse.validate import param

__all__ = ["AStarParams", "ReplanParams", "FollowController", "ReplanController"]


@dataclass(frozen=True)
class _AStarSearch(GlobalAStarParams):
    corner_cutting: bool = param(False, help="allow a diagonal move past a blocked orthogonal "
                                             "neighbour (false: the MovingAI rule, and safe for "
                                             "a robot)")


@dataclass(frozen=True)
class _Replanning(GlobalAStarParams):
    replan_period_s: float = param(1.0, gt=0, unit="s",
                                   help="seconds between replans online (1 s = Nav2's 1 Hz)")
    margin_m: float = param(0.0, ge=0, unit="m",
                            help="extra clearance around each sensed disc when it is "
                                 "rasterised")


# the follower's parameters come last (their base class first: dataclass fields are
# collected from the last base class to the first)
@dataclass(frozen=True)
class AStarParams(PursuitParams, _AStarSearch, GlobalChoice):
    """Parameters of the ``astar`` planner: the global planner it follows (grid A* by
    default), A*'s search, and its path follower's on a diff-drive robot
    (:class:`~pathfuse.planners.params.PursuitParams`)."""


@dataclass(frozen=True)
class ReplanParams(PursuitParams, _Replanning):
    """Parameters of ``astar-replan``: its search and replanning, and its path follower's
    on a diff-drive robot (:class:`~pathfuse.planners.params.PursuitParams`)."""


def _point_at(path: np.ndarray, cum: np.ndarray, s: float) -> np.ndarray:
    if s >= cum[-1]:
        return path[-1].copy()
    i = int(np.searchsorted(cum, s, side="right")) - 1
    i = min(max(i, 0), len(path) - 2)
    seg = cum[i + 1] - cum[i]
    f = 0.0 if seg <= 0 else (s - cum[i]) / seg
    return path[i] + f * (path[i + 1] - path[i])  # type: ignore[no-any-return]


def _as_planned(gp: Any, resolution: float) -> Outcome:
    """The offline outcome of following the global plan ``gp``: its path as planned (its
    info a :class:`~pathfuse.metrics.PlanInfo` already, which ``solve`` keeps)."""
    if gp.taut or not len(gp.cells):  # an any-angle path, a plug-in's waypoints
        info = PlanInfo(global_planner=gp.planner, corners=int(len(gp.points)))
    else:
        info = PlanInfo(cells=gp.cells, cost_cells=gp.length_m / resolution,
                        heuristic=gp.heuristic, corner_cutting=gp.corner_cutting)
        if gp.planner != "astar":
            info["global_planner"] = gp.planner
    return Outcome(Status.SUCCESS, gp.points, 0, 0.0, gp.message, info, gp.length_m)


def _cumlen(path: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])


class FollowController(Controller):
    """Walk the global path at full speed (offline: return it as planned); on a diff-drive
    robot, follow it with Regulated Pure Pursuit (:mod:`pathfuse.planners.controllers.rpp`).

    It follows the path of any global planner.  A taut path (an any-angle one, or a
    plug-in's: :attr:`GlobalPlan.taut <pathfuse.planners.globals.astar.GlobalPlan.taut>`)
    turns where it touches the robot's clearance around an obstacle corner, so a move
    across a corner would come closer than the radius: a holonomic robot's walk then ends
    a tick's move on the next corner (at most one tick per corner, and these paths have
    few).
    """

    name = "follow"
    label = "follow the path"
    search_budget: ClassVar[bool] = True
    #: End a tick's move at the path's next corner instead of cutting across it, whatever
    #: the plan (a holonomic robot's walk only; a taut plan does it anyway).
    stop_at_corners: ClassVar[bool] = False

    def __init__(self, problem: Problem, params: Any, plan: Any = None, **kw: Any) -> None:
        super().__init__(problem, params, plan, **kw)
        if self.online and plan is not None:
            self._path = plan.waypoints
            self._cum = _cumlen(self._path)
            self._s = 0.0
            self._step = float(self.max_speed) * float(self.dt)  # type: ignore[arg-type]
            self._corners = self.stop_at_corners or bool(getattr(plan, "taut", False))
        self._rpp: Any = None
        rb = problem.robot
        if self.online and rb is not None and rb.is_diff_drive:
            from pathfuse.planners.controllers.rpp import RegulatedPurePursuit

            dt, top = float(self.dt), float(self.max_speed)  # type: ignore[arg-type]
            self._rpp = RegulatedPurePursuit(problem, params, dt, top)

    @property
    def acts_unicycle(self) -> bool:
        """On a diff-drive robot :meth:`act` answers ``(v, omega)`` (Regulated Pure
        Pursuit)."""
        return self._rpp is not None

    def run(self, deadline: float | None) -> Outcome:
        return _as_planned(self.plan, self.problem.grid.resolution)

    @classmethod
    def run_offline(cls, problem: Problem, params: Any, plan: Any,
                    deadline: float | None) -> Outcome:
        """The global path as planned, without an instance (a subclass with a :meth:`run` of
        its own gets one)."""
        if cls.run is not FollowController.run:
            return super().run_offline(problem, params, plan, deadline)
        return _as_planned(plan, problem.grid.resolution)

    def act(self, obs: Observed) -> np.ndarray:
        if self._rpp is not None:
            return self._rpp.command(obs, self._path)
        cum = self._cum
        s = min(self._s + self._step, float(cum[-1]))
        if self._corners:
            nxt = int(np.searchsorted(cum, self._s, side="right"))
            if nxt < len(cum) - 1 and cum[nxt] < s:
                s = float(cum[nxt])
        self._s = s
        target = _point_at(self._path, cum, s)
        return (target - obs.position) / float(self.dt)  # type: ignore[no-any-return, arg-type]

    @classmethod
    def diff_drive_kernels(cls) -> Sequence[Any]:
        from pathfuse.planners.controllers.rpp import rpp_step

        return (rpp_step,)

    @classmethod
    def warmup_diff_drive(cls) -> None:
        from pathfuse.planners.controllers.rpp import warmup_rpp

        warmup_rpp()


@njit(cache=True)
def _rasterise_discs(occ, ox, oy, res, pos, radii, grow):
    """Block every cell whose centre is closer than ``radii[i] + grow`` to a disc centre."""
    h, w = occ.shape
    for i in range(pos.shape[0]):
        rad = radii[i] + grow
        c0 = max(int(math.floor((pos[i, 0] - rad - ox) / res)), 0)
        c1 = min(int(math.floor((pos[i, 0] + rad - ox) / res)), w - 1)
        r0 = max(int(math.floor((pos[i, 1] - rad - oy) / res)), 0)
        r1 = min(int(math.floor((pos[i, 1] + rad - oy) / res)), h - 1)
        for r in range(r0, r1 + 1):
            cy = oy + (r + 0.5) * res - pos[i, 1]
            for c in range(c0, c1 + 1):
                cx = ox + (c + 0.5) * res - pos[i, 0]
                if cx * cx + cy * cy < rad * rad:
                    occ[r, c] = True


class ReplanController(FollowController):
    """A* replanned at a fixed rate around the sensed discs (see the module docstring)."""

    name = "replan"
    label = "replan at a fixed rate and follow"

    def __init__(self, problem: Problem, params: Any, plan: Any = None, **kw: Any) -> None:
        super().__init__(problem, params, plan, **kw)
        if self.online:
            dt = float(self.dt)  # type: ignore[arg-type]
            self._every = max(1, int(round(params.replan_period_s / dt)))
            self._path = None  # type: ignore[assignment]
            self.replans = 0
            self.failed_replans = 0

    def _replan(self, obs: Observed) -> None:
        pb = self.problem
        g = pb.grid
        occ = g.cspace(pb.robot_radius_m).occupied.copy()
        sens = obs.obstacles
        if len(sens):
            _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]), float(g.resolution),
                             np.require(sens.positions, np.float64, ("C", "W")),
                             np.require(sens.radii, np.float64, ("C", "W")),
                             float(pb.robot_radius_m) + self.params.margin_m)
        self.replans += 1
        here = (float(obs.position[0]), float(obs.position[1]))
        gp = plan_global(pb.with_start(here), self.params.heuristic, occupied=occ)
        if not gp.success:
            self.failed_replans += 1
            self._path = None  # type: ignore[assignment]
            return
        self._path = gp.waypoints
        self._cum = _cumlen(self._path)
        self._s = 0.0
        self.global_path = self._path

    def act(self, obs: Observed) -> np.ndarray:
        if obs.tick % self._every == 0:
            self._replan(obs)
        if self._path is None:
            return np.zeros(2)
        return super().act(obs)

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (*super().kernels(), _rasterise_discs)

    @classmethod
    def warmup(cls) -> None:
        super().warmup()
        occ = np.zeros((3, 4), dtype=np.bool_)
        _rasterise_discs(occ, 0.0, 0.0, 1.0, np.ones((1, 2)), np.ones(1), 0.2)


register(PlannerSpec(
    name="astar",
    params_cls=AStarParams,
    description="exact 8-connected grid A* (euclidean or octile heuristic, no corner cutting "
                "by default), or the path of any global_planner; online it walks the path "
                "blind to moving discs",
    controller=FollowController,
    global_planner="astar",
    aliases=("astar-follow",),
))
register(PlannerSpec(
    name="astar-replan",
    params_cls=ReplanParams,
    description="A* replanned at a fixed rate (default 1 Hz) with the sensed moving discs as "
                "blocked cells; offline the same path as astar",
    controller=ReplanController,
    global_planner="astar",
))
