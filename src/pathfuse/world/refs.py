"""The reference methods [6] and [7] of the paper, run online among moving discs.

Both plan A* once on the static map (as the online fusion does:
:func:`~pathfuse.world.online.global_astar_path`, the robot's c-space, no
corner cutting) and then chase a sequence of sub-goals with an APF, one safe
step of ``max_speed * dt`` per tick, the sensed moving discs repelling as in
:mod:`pathfuse.world.online` (eq. 6 on the gap, optional velocity-aware form,
swerve and dodge).  A sub-goal is passed when the robot comes within
``subgoal_tolerance_m`` of it.

``ref6``
    Sub-goals: the A* path's inflection points, then the goal
    (:func:`pathfuse.planners.ref6.inflection_points`).  Static repulsion: the
    improved (Ge-Cui 2000) repulsion of
    :func:`pathfuse.planners.ref6.grid_improved_repulsion`, eq. 6 scaled by
    ``(rho_g / L)^n`` with ``rho_g`` the distance to the current sub-goal (or
    the goal), so sub-goals next to obstacles are reachable.
``ref7``
    Sub-goals: the ends of sub-segments of the A* path
    (:func:`pathfuse.planners.ref7.segment_ends`: the first A* point at least
    ``segment_length_m`` along the path after the previous end, or every
    ``segment_points``-th point), the goal last; plain APF (eq. 5/6,
    :func:`pathfuse.field.stepper.apf_force`) from segment end to segment end.

Examples
--------
>>> from pathfuse.world import simulate
>>> ep = simulate({"map": {"rows": ["......", "..##..", "......"]}, "start": [0.5, 0.5],
...                "goal": [5.5, 2.5]}, planner="ref6")
>>> ep.status.name
'REACHED'
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pathfuse.field.stepper import apf_force, grid_repulsion
from pathfuse.planners.ref6 import Ref6Params, grid_improved_repulsion, inflection_points
from pathfuse.planners.ref7 import Ref7Params, segment_ends
from pathfuse.result import ConfigError
from pathfuse.world.online import (
    APFOnlineParams,
    OnlinePlannerSpec,
    PlannerContext,
    _choice,
    _FieldPlanner,
    _floats,
    _pos,
    global_astar_path,
    register_online,
)

__all__ = ["Ref6OnlineParams", "Ref7OnlineParams", "Ref6Online", "Ref7Online"]

_R6 = Ref6Params()
_R7 = Ref7Params()


@dataclass(frozen=True)
class Ref6OnlineParams(APFOnlineParams):
    """Online reference method [6].

    Attributes
    ----------
    k_att, k_rep, rho0_m, k_rep_moving, rho0_moving_m, repulsion, a_max, swerve, dodge
        As in :class:`~pathfuse.world.online.APFOnlineParams`.
    subgoal_tolerance_m : float or None
        Distance at which a sub-goal counts as passed (default: half a cell).
    rep_exponent : float
        ``n`` of the improved repulsion.
    rep_scale_m : float or None
        ``L`` of the improved repulsion (default ``rho0_m``).
    rep_target : {"subgoal", "goal"}
        Whose distance scales the repulsion.
    heuristic : {"euclidean", "octile"}
        A* heuristic.
    """

    subgoal_tolerance_m: float | None = _R6.subgoal_tolerance_m
    rep_exponent: float = _R6.rep_exponent
    rep_scale_m: float | None = _R6.rep_scale_m
    rep_target: str = _R6.rep_target
    heuristic: str = "euclidean"

    def __post_init__(self) -> None:
        super().__post_init__()
        _pos("subgoal_tolerance_m", self.subgoal_tolerance_m, optional=True)
        _pos("rep_exponent", self.rep_exponent)
        _pos("rep_scale_m", self.rep_scale_m, optional=True)
        _choice("rep_target", self.rep_target, ("subgoal", "goal"))
        _choice("heuristic", self.heuristic, ("euclidean", "octile"))
        _floats(self, "subgoal_tolerance_m", "rep_exponent", "rep_scale_m")


@dataclass(frozen=True)
class Ref7OnlineParams(APFOnlineParams):
    """Online reference method [7].

    Attributes
    ----------
    k_att, k_rep, rho0_m, k_rep_moving, rho0_moving_m, repulsion, a_max, swerve, dodge
        As in :class:`~pathfuse.world.online.APFOnlineParams`.
    segment_length_m : float
        Path length of a sub-segment (a segment ends at the first A* point at
        least this far along the path from the previous end).
    segment_points : int or None
        When given, every ``segment_points``-th A* point ends a segment instead.
    subgoal_tolerance_m : float or None
        Distance at which a segment end counts as passed (default: half a cell).
    heuristic : {"euclidean", "octile"}
        A* heuristic.
    """

    segment_length_m: float = _R7.segment_length_m
    segment_points: int | None = _R7.segment_points
    subgoal_tolerance_m: float | None = _R7.segment_tolerance_m
    heuristic: str = "euclidean"

    def __post_init__(self) -> None:
        super().__post_init__()
        _pos("segment_length_m", self.segment_length_m)
        v = self.segment_points
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, np.integer))
                              or v < 1):
            raise ConfigError(f"segment_points: must be an integer >= 1 or null, got {v!r}")
        _pos("subgoal_tolerance_m", self.subgoal_tolerance_m, optional=True)
        _choice("heuristic", self.heuristic, ("euclidean", "octile"))
        _floats(self, "segment_length_m", "subgoal_tolerance_m")


class _SubgoalPlanner(_FieldPlanner):
    """A* once, then an APF towards each sub-goal in turn."""

    def subgoals(self, path: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def reset(self, ctx: PlannerContext) -> None:
        super().reset(ctx)
        p = self.params
        path = global_astar_path(ctx.grid, ctx.start, ctx.goal, ctx.robot.radius, p.heuristic)
        if path is None:
            self.failure = ("no_path", "A* found no path for the robot on the static map")
            return
        self.global_path = path
        subs = np.asarray(self.subgoals(path), dtype=np.float64).reshape(-1, 2)
        goal = np.asarray(ctx.goal, dtype=np.float64)
        if subs.shape[0] == 0 or not np.array_equal(subs[-1], goal):
            subs = np.concatenate([subs, goal[None, :]])
        self.subgoal_points = np.ascontiguousarray(subs)
        self._j = 0
        self._tol = (0.5 * ctx.grid.resolution if p.subgoal_tolerance_m is None
                     else float(p.subgoal_tolerance_m))

    @property
    def subgoal_index(self) -> int:
        """Index of the current sub-goal in :attr:`subgoal_points`."""
        return self._j

    def act(self, obs: Any) -> np.ndarray:
        x, y = float(obs.position[0]), float(obs.position[1])
        subs = self.subgoal_points
        last = subs.shape[0] - 1
        while self._j < last and math.hypot(x - subs[self._j, 0],
                                            y - subs[self._j, 1]) <= self._tol:
            self._j += 1
        sx, sy = float(subs[self._j, 0]), float(subs[self._j, 1])
        fx, fy = self.subgoal_force(x, y, sx, sy)
        return self.step_velocity(obs, fx, fy)

    def subgoal_force(self, x: float, y: float, sx: float,
                      sy: float) -> tuple[float, float]:  # pragma: no cover - abstract
        raise NotImplementedError


class Ref6Online(_SubgoalPlanner):
    """Reference [6] online: improved APF through the A* inflection points."""

    name = "ref6"

    def subgoals(self, path: np.ndarray) -> np.ndarray:
        return inflection_points(path)

    def subgoal_force(self, x: float, y: float, sx: float, sy: float) -> tuple[float, float]:
        p = self.params
        tx, ty = (sx, sy) if p.rep_target == "subgoal" else (self._gx, self._gy)
        scale = p.rho0_m if p.rep_scale_m is None else p.rep_scale_m
        rx, ry = grid_improved_repulsion(x, y, tx, ty, self._occ, self._ox, self._oy, self._res,
                                         p.k_rep, p.rho0_m, p.rep_exponent, scale)
        return p.k_att * (sx - x) + rx, p.k_att * (sy - y) + ry

    def warmup(self) -> None:
        super().warmup()
        _warmup_refs()


class Ref7Online(_SubgoalPlanner):
    """Reference [7] online: plain APF from sub-segment end to sub-segment end."""

    name = "ref7"

    def subgoals(self, path: np.ndarray) -> np.ndarray:
        p = self.params
        return path[segment_ends(path, p.segment_length_m, p.segment_points)]

    def subgoal_force(self, x: float, y: float, sx: float, sy: float) -> tuple[float, float]:
        p = self.params
        return apf_force(x, y, sx, sy, p.k_att, p.k_rep, p.rho0_m, p.rho0_m, self._occ,
                         self._ox, self._oy, self._res)


_WARM = False


def _warmup_refs() -> None:
    global _WARM
    if _WARM:
        return
    for ro in (False, True):
        occ = np.zeros((3, 4), dtype=np.bool_)
        occ[1, 1] = True
        occ.setflags(write=not ro)
        grid_improved_repulsion(0.5, 0.5, 3.5, 2.5, occ, 0.0, 0.0, 1.0, 5.0, 2.0, 2.0, 2.0)
        grid_repulsion(0.5, 0.5, occ, 0.0, 0.0, 1.0, 5.0, 2.0, 2.0)
    _WARM = True


register_online(OnlinePlannerSpec(
    "ref6", Ref6Online, Ref6OnlineParams,
    "reference [6] online: improved APF through the A* inflection points, moving discs repel"))
register_online(OnlinePlannerSpec(
    "ref7", Ref7Online, Ref7OnlineParams,
    "reference [7] online: APF from A* sub-segment end to end, moving discs repel"))
