"""The paper's reference methods [6] and [7]: A*, then an APF through sub-goals on its path.

The paper describes both in a sentence each (Section II and IV.D); these are
faithful readings of those sentences, not the original code.

``ref6`` - "first uses the A-star algorithm for planning to obtain the
initial path, and then sequentially uses each inflection point of the
initial path as a sub-target point, and uses the improved artificial
potential field method of local path planning to obtain the final path".

1. Grid A* (:mod:`pathfuse.planners.globals.astar`) gives the initial path.
2. Its *inflection points* - the interior points where the direction of
   travel changes (:func:`inflection_points`) - then the goal are the
   sub-goals, visited in order: a sub-goal is passed within
   ``subgoal_tolerance_m`` (default half a cell).
3. The robot moves one safe step at a time along the attraction (eq. 5) of
   the current sub-goal plus the *improved* repulsion of Ge and Cui (S. S.
   Ge, Y. J. Cui, "New potential functions for mobile robot path planning",
   IEEE Trans. Robotics and Automation 16(5), 2000), which multiplies eq. 4
   by ``(rho_g / L)^n``, ``rho_g`` the distance to the target (the current
   sub-goal, or the goal with ``rep_target="goal"``)::

       F_rep* = (rho_g / L)^n F_rep + n U_rep (rho_g / L)^(n-1) / L (X_t - X) / rho_g

   Both terms vanish at the target, so a sub-goal next to an obstacle - and
   A* puts every inflection point next to an obstacle corner - is
   reachable.  ``n`` is ``rep_exponent``, ``L`` is ``rep_scale_m`` (default
   ``rho0_m``).

``ref7`` - "uses a global path planning A-star algorithm to obtain an
initial path.  On a sub-base, a local path is obtained by the artificial
potential field method of local path planning.  The two parts are combined
together".

1. Grid A* gives the initial path.
2. It is cut into sub-segments (:func:`segment_ends`): the first A* point at
   least ``segment_length_m`` of path after the previous cut (or every
   ``segment_points``-th point) ends a segment; the goal ends the last one.
3. The plain APF (eq. 5 and 6) runs from segment end to segment end: an end
   is passed within ``subgoal_tolerance_m`` (default a quarter cell, which
   also absorbs an end next to an obstacle that the plain repulsion would
   keep the robot from), the goal within ``goal_tolerance_m``.

Both are :class:`~pathfuse.planners.controllers.apf.SubgoalController` s, so offline and
online they run the same numba loop as ``apf``
(:func:`pathfuse.field.kernels.field_loop`).  ``info`` holds the A* path
(``astar_path``, ``astar_length``, ``astar_time_s``), ``subgoals`` (K, 2) (the
goal last), ``subgoals_reached`` and ``subgoal_tolerance_m``; ref7 adds
``segment_index`` (the indices of the segment ends in the A* path).

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..##..", "......", "......"])
>>> r = plan(g, (0.5, 0.5), (4.5, 3.5), planner="ref6")
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [4.5, 3.5])
>>> r.info["astar_path"].tolist()
[[0.5, 0.5], [1.5, 1.5], [2.5, 1.5], [3.5, 1.5], [4.5, 1.5], [4.5, 2.5], [4.5, 3.5]]
>>> r.info["subgoals"].tolist()   # the two turns of the A* path, then the goal
[[1.5, 1.5], [4.5, 1.5], [4.5, 3.5]]
>>> r7 = plan(g, (0.5, 0.5), (4.5, 3.5), planner="ref7", segment_points=2)
>>> r7.status.name, r7.info["subgoals"].tolist()   # every second A* point, then the goal
('SUCCESS', [[2.5, 1.5], [4.5, 1.5], [4.5, 3.5]])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pathfuse.field.forces import K_REP, RHO0_M, repulsive_force, repulsive_potential
from pathfuse.field.kernels import S_SUB
from pathfuse.planners.controllers.apf import SubgoalController
from pathfuse.planners.params import DiscParams, FieldParams, GlobalAStarParams, GlobalChoice
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.validate import integer, number, param

__all__ = [
    "Ref6Params",
    "Ref7Params",
    "Ref6Controller",
    "Ref7Controller",
    "inflection_points",
    "segment_ends",
    "improved_repulsive_potential",
    "improved_repulsive_force",
]


@dataclass(frozen=True)
class Ref6Params(GlobalAStarParams, DiscParams, FieldParams, GlobalChoice):
    """Parameters of reference method [6] (paper values for K_att, K_rep, rho_0)."""

    subgoal_tolerance_m: float | None = param(
        None, gt=0, unit="m", optional=True,
        help="a sub-goal (inflection point) is passed within this distance (default: half "
             "a cell, at least one move)")
    rep_exponent: float = param(2.0, gt=0, help="n of the improved repulsion (Ge and Cui)")
    rep_scale_m: float | None = param(None, gt=0, unit="m", optional=True,
                                      help="L of the improved repulsion (default: rho0_m)")
    rep_target: str = param("subgoal", choices=("subgoal", "goal"),
                            help="the point whose distance scales the repulsion")


@dataclass(frozen=True)
class Ref7Params(GlobalAStarParams, DiscParams, FieldParams, GlobalChoice):
    """Parameters of reference method [7] (paper values for K_att, K_rep, rho_0)."""

    segment_length_m: float = param(3.0, gt=0, unit="m",
                                    help="path length of a sub-segment of the A* path")
    segment_points: int | None = param(None, ge=1, optional=True, kind="int",
                                       help="when given, every segment_points-th A* point "
                                            "ends a segment instead")
    subgoal_tolerance_m: float | None = param(
        None, gt=0, unit="m", optional=True,
        help="a segment end is passed within this distance (default: a quarter cell, at "
             "least one move)")


# --------------------------------------------------------------------- path helpers
def inflection_points(path: object, rtol: float = 1e-9) -> np.ndarray:
    """The interior points of a polyline where its direction changes, in order.

    A point ``P[i]`` (``0 < i < N-1``) is an inflection point when the move
    into it and the move out of it are not parallel with the same sense
    (cross product above ``rtol`` times the product of their lengths, or a
    reversal).  Repeated consecutive points are dropped first.  The end
    points are never inflection points.

    >>> inflection_points([[0, 0], [1, 1], [2, 2], [3, 2], [4, 2]]).tolist()
    [[2.0, 2.0]]
    >>> inflection_points([[0, 0], [1, 0], [2, 0]]).shape
    (0, 2)
    """
    p = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    if p.shape[0] > 1:
        keep = np.concatenate([[True], np.any(np.diff(p, axis=0) != 0.0, axis=1)])
        p = p[keep]
    if p.shape[0] < 3:
        return np.zeros((0, 2))
    d = np.diff(p, axis=0)
    a, b = d[:-1], d[1:]
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    dot = np.sum(a * b, axis=1)
    scale = np.hypot(a[:, 0], a[:, 1]) * np.hypot(b[:, 0], b[:, 1])
    turn = (np.abs(cross) > rtol * scale) | (dot <= 0.0)
    return p[1:-1][turn].copy()


def segment_ends(path: object, segment_length_m: float = 3.0,
                 segment_points: int | None = None) -> np.ndarray:
    """Indices into ``path`` (N, 2) of the ends of its sub-segments, the last point last.

    With ``segment_points`` = k: ``k, 2k, ...`` and ``N - 1``.  Otherwise each
    end is the first point whose path length from the previous end (the
    first point at the start) is at least ``segment_length_m``.

    >>> p = [[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 0], [6, 0]]
    >>> segment_ends(p, segment_points=4).tolist()
    [4, 6]
    >>> segment_ends(p, segment_length_m=2.5).tolist()
    [3, 6]
    """
    p = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    m = p.shape[0]
    if m <= 1:
        return np.zeros(1, dtype=np.int64)
    if segment_points is not None:
        k = integer(segment_points, "segment_points", ge=1)
        ends = list(range(k, m - 1, k))
    else:
        length = number(segment_length_m, "segment_length_m", gt=0)
        cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        ends = []
        last = 0.0
        tol = 1e-9 * max(length, 1.0)
        for i in range(1, m - 1):
            if cum[i] - last >= length - tol:
                ends.append(i)
                last = cum[i]
    ends.append(m - 1)
    return np.asarray(ends, dtype=np.int64)


def improved_repulsive_potential(
    x: object, target: object, obstacles: object, k_rep: float = K_REP,
    rho0_m: float = RHO0_M, n: float = 2.0, scale_m: float = RHO0_M,
) -> float:
    """Ge-Cui repulsive potential at ``x`` (2,): ``sum_o U_rep(x, o) (|x - target| / L)^n``.

    A brute-force reference over every obstacle point ``obstacles`` (K, 2).

    >>> improved_repulsive_potential([1.0, 0.0], [1.0, 0.0], [[0.0, 0.0]])  # at the target
    0.0
    >>> improved_repulsive_potential([1.0, 0.0], [1.0, 2.0], [[0.0, 0.0]])  # 0.625 * (2/2)^2
    0.625
    """
    xa = np.asarray(x, dtype=np.float64).reshape(2)
    obs = np.asarray(obstacles, dtype=np.float64).reshape(-1, 2)
    u = float(repulsive_potential(xa[None, :], obs, k_rep, rho0_m).sum())
    rg = float(np.hypot(*(xa - np.asarray(target, dtype=np.float64).reshape(2))))
    return u * (rg / scale_m) ** n


def improved_repulsive_force(
    x: object, target: object, obstacles: object, k_rep: float = K_REP,
    rho0_m: float = RHO0_M, n: float = 2.0, scale_m: float = RHO0_M,
) -> np.ndarray:
    """Ge-Cui repulsive force at ``x`` (2,), the negative gradient of
    :func:`improved_repulsive_potential` (brute force over ``obstacles`` (K, 2)).

    >>> improved_repulsive_force([1.0, 0.0], [1.0, 0.0], [[0.0, 0.0]]).tolist()
    [0.0, 0.0]
    >>> improved_repulsive_force([1.0, 0.0], [1.0, 2.0], [[0.0, 0.0]]).tolist()
    [2.5, 0.625]
    """
    xa = np.asarray(x, dtype=np.float64).reshape(2)
    t = np.asarray(target, dtype=np.float64).reshape(2)
    obs = np.asarray(obstacles, dtype=np.float64).reshape(-1, 2)
    f1 = repulsive_force(xa[None, :], obs, k_rep, rho0_m).sum(axis=0)
    u = float(repulsive_potential(xa[None, :], obs, k_rep, rho0_m).sum())
    rg = float(np.hypot(*(xa - t)))
    if rg == 0.0:
        return np.zeros(2)
    q = rg / scale_m
    return q**n * f1 + u * n * q ** (n - 1.0) / scale_m * (t - xa) / rg


# --------------------------------------------------------------------- controllers
class _RefController(SubgoalController):
    """Sub-goals taken from the global path; shared ``info``."""

    #: Default sub-goal tolerance, in cells.
    default_subgoal_frac = 0.5

    def subgoal_tolerance(self) -> float:
        """The pass distance of a sub-goal: ``subgoal_tolerance_m`` when given, else a
        fraction of a cell but never less than one move.

        Moves have a fixed length (``step_m`` offline, ``max_speed * dt`` online), so a
        sub-goal passed only within less than a move can be jumped over back and forth
        forever: online on a 0.05 m BARN grid a 0.2 m move straddled a sub-goal passed
        within 2.5 cm.  With the default step (0.1 cell) offline this changes nothing.
        """
        tol = self.params.subgoal_tolerance_m
        if tol is not None:
            return float(tol)
        return max(self.default_subgoal_frac * self.problem.grid.resolution, float(self.step_m))

    def _with_goal(self, subs: np.ndarray) -> np.ndarray:
        goal = np.asarray(self.problem.goal, dtype=np.float64)
        subs = np.asarray(subs, dtype=np.float64).reshape(-1, 2)
        if subs.shape[0] == 0 or not np.array_equal(subs[-1], goal):
            subs = np.concatenate([subs, goal[None, :]])
        return subs

    def extra_info(self) -> dict[str, Any]:
        reached = int(self.state[S_SUB])
        if self.n and np.array_equal(self.buf[self.n - 1], self.subgoals[-1]):
            reached += 1
        return {"subgoals": self.subgoals.copy(), "subgoals_reached": reached,
                "subgoal_tolerance_m": self.subgoal_tolerance()}

    def failure_message(self, code: int, status: Any, path: np.ndarray, steps: int) -> str:
        base = super().failure_message(code, status, path, steps)
        return (f"{base} (heading for sub-goal {int(self.state[S_SUB]) + 1} of "
                f"{self.subgoals.shape[0]})")

    def success_message(self, steps: int) -> str:
        return (f"reached the goal through {self.subgoals.shape[0] - 1} sub-goals in "
                f"{steps} steps")


class Ref6Controller(_RefController):
    """Reference [6]: improved APF through the A* path's inflection points."""

    name = "ref6"
    label = "improved APF through the inflection points"
    improved = True

    def make_subgoals(self) -> np.ndarray:
        return self._with_goal(inflection_points(self.plan.waypoints))

    def rep_to_goal(self) -> bool:
        return bool(self.params.rep_target == "goal")

    def rep_exponent(self) -> float:
        return float(self.params.rep_exponent)

    def rep_scale(self) -> float:
        p = self.params
        return float(p.rho0_m if p.rep_scale_m is None else p.rep_scale_m)


class Ref7Controller(_RefController):
    """Reference [7]: plain APF from A* sub-segment end to sub-segment end."""

    name = "ref7"
    label = "APF from segment end to segment end"
    # a quarter cell: an end passed at half a cell can lie on the cell's boundary, right at
    # an obstacle corner, where the plain APF towards the next end stalls
    default_subgoal_frac = 0.25

    def make_subgoals(self) -> np.ndarray:
        path = self.plan.waypoints
        self.segment_index = segment_ends(path, self.params.segment_length_m,
                                          self.params.segment_points)
        subs = path[self.segment_index].copy()
        subs[-1] = self.problem.goal
        return subs

    def extra_info(self) -> dict[str, Any]:
        return {**super().extra_info(), "segment_index": self.segment_index}


register(PlannerSpec(
    name="ref6",
    params_cls=Ref6Params,
    description="reference [6]: A*, then an improved (Ge-Cui) APF through the A* inflection "
                "points as sub-goals",
    controller=Ref6Controller,
    global_planner="astar",
))
register(PlannerSpec(
    name="ref7",
    params_cls=Ref7Params,
    description="reference [7]: A* cut into sub-segments, plain APF from segment end to "
                "segment end",
    controller=Ref7Controller,
    global_planner="astar",
))
