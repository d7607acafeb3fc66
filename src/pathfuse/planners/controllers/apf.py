"""Plain artificial potential field (paper Section III.B), registered as ``"apf"``.

No global planner: the robot starts at ``start`` and repeatedly moves one
step along the resultant of the goal's attraction (eq. 5) and the repulsion
(eq. 6) of every occupied cell centre within ``rho0_m`` (plus, online, the
sensed moving discs).  Moves are made by
:func:`pathfuse.field.motion.safe_step`: a move that would enter or cross an
occupied square (kept ``robot_radius_m`` away) is never taken; the robot
slides along the wall, shortens the move, or is blocked.

Endings (``PlanResult.status``): ``SUCCESS`` (within ``goal_tolerance_m`` of
the goal with a clear straight move onto it; the path ends exactly at the
goal), ``LOCAL_MINIMUM`` (net move below ``stall_distance_m`` over the last
``stall_steps`` moves, or no collision-free move), ``MAX_ITERATIONS``
(``Budget.max_iterations`` moves; default 10 (width + height) resolution /
step + 1000), ``TIMEOUT`` (``Budget.time_limit_s``, checked every 8192
moves).  On failure ``path`` is the partial path walked so far.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "......", "..#...", "......"])
>>> r = plan(g, (0.5, 0.5), (5.5, 3.5), planner="apf")
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [5.5, 3.5])
>>> plan(g, (0.5, 0.5), (5.5, 3.5), planner="apf", k_att=-1)
Traceback (most recent call last):
...
pathfuse.result.ConfigError: apf.k_att: must be a number > 0, got -1
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from pathfuse.costmap import costmap_for
from pathfuse.field.kernels import field_loop
from pathfuse.field.repulsion import apf_force
from pathfuse.field.settings import pack_field
from pathfuse.grid import GridMap
from pathfuse.planners.base import FieldController
from pathfuse.planners.params import DiscParams, FieldParams
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["APFParams", "APFController", "SubgoalController", "force_at"]


@dataclass(frozen=True)
class APFParams(DiscParams, FieldParams):
    """Parameters of the plain APF (paper values as defaults)."""


class SubgoalController(FieldController):
    """A robot attracted by a sequence of sub-goals, the last one the goal
    (:func:`pathfuse.field.kernels.field_loop`); the base of ``apf``, ``ref6`` and ``ref7``."""

    improved = False

    def __init__(self, problem: Problem, params: Any, plan: Any = None, **kw: Any) -> None:
        super().__init__(problem, params, plan, **kw)
        p = params
        self.subgoals = np.require(self.make_subgoals(), dtype=np.float64,
                                   requirements=("C", "W"))
        self.settings = pack_field(
            problem.goal, p.k_att, p.k_rep, p.rho0_m, self.step_m, self.goal_tolerance_m,
            p.stall_steps, self.stall_distance_m, self.subgoal_tolerance(), self.improved,
            self.rep_to_goal(), self.rep_exponent(), self.rep_scale(), p.safe_step,
            p.stall_exit, problem.clearance_m, p.static_repulsion == "boundary",
            p.boundary_offset_m)
        self.state = np.zeros(1, dtype=np.int64)

    def make_subgoals(self) -> np.ndarray:
        """The sub-goals in order, the goal last (``apf``: the goal alone)."""
        return np.array([self.problem.goal], dtype=np.float64)

    def subgoal_tolerance(self) -> float:
        return 0.0

    def rep_to_goal(self) -> bool:
        return False

    def rep_exponent(self) -> float:
        return 0.0

    def rep_scale(self) -> float:
        return 1.0

    def _call(self, max_steps: int, dpos: np.ndarray | None, dvel: np.ndarray | None,
              drad: np.ndarray | None) -> tuple[int, int]:
        self.buf, self.n, code, steps = field_loop(self.buf, self.n, max_steps, self.costmap,
                                                   self.subgoals, self.state, self.settings,
                                                   self.disc_cfg, dpos, dvel, drad,
                                                   *self._margin(dpos))
        return code, steps

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (field_loop,)

    @classmethod
    def warmup(cls) -> None:
        _warm_field(online=False)

    @classmethod
    def warmup_margin(cls) -> None:
        _warm_field(online=False, margin=True)

    @classmethod
    def warmup_online(cls) -> None:
        _warm_field(online=True)


class APFController(SubgoalController):
    """Plain APF: the goal is the only sub-goal."""

    name = "apf"
    label = "APF"


_WARM: set[tuple[bool, bool]] = set()


def _warm_field(online: bool, margin: bool = False) -> None:
    """Compile (or load from numba's cache) :func:`field_loop` on a tiny map: the signature
    of a static plan (no disc code; with ``margin``, that of one with a safety margin) or,
    ``online``, the one with disc arrays (one signature with and without sensed discs)."""
    if (online, margin) in _WARM:
        return
    from pathfuse.planners.base import ONE_DISC
    from pathfuse.result import Budget

    g = GridMap.from_rows(["....", ".#..", "...."])
    pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5), budget=Budget(max_iterations=5),
                        clearance_m=0.05 if margin else 0.0)
    if online:
        APFController(pb, APFParams(), dt=0.1, max_speed=1.0)._call(1, *ONE_DISC)
    else:
        APFController(pb, APFParams()).run(None)
    _WARM.add((online, margin))


def force_at(grid: GridMap, xy: object, goal: object, params: APFParams | None = None
             ) -> np.ndarray:
    """The APF resultant force at world points ``xy`` (shape (2,) or (N, 2)).

    >>> g = GridMap.from_rows(["...", "...", "..."])
    >>> force_at(g, (0.5, 0.5), (2.5, 0.5)).tolist()
    [80.0, 0.0]
    """
    p = params or APFParams()
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    gx, gy = (float(v) for v in np.asarray(goal, dtype=np.float64).reshape(2))
    cm = costmap_for(grid, 0.0, lattice=False)
    out = np.empty_like(pts)
    for k in range(pts.shape[0]):
        out[k] = apf_force(pts[k, 0], pts[k, 1], gx, gy, p.k_att, p.k_rep, p.rho0_m, p.rho0_m,
                           cm, p.static_repulsion == "boundary", p.boundary_offset_m)
    return out[0] if np.ndim(cast("ArrayLike", xy)) == 1 else out


register(PlannerSpec(
    name="apf",
    params_cls=APFParams,
    description="artificial potential field (paper eq. 3-6): one step at a time along the "
                "resultant force, never into an obstacle (safe_step=false: the paper's full step)",
    controller=APFController,
))
