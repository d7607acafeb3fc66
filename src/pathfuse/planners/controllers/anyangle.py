"""The presets of the any-angle global planners, the true shortest path and jump point
search: ``thetastar``, ``lazy-thetastar``, ``astar-smooth``, ``shortest`` and ``jps``.

Each is a global planner of :mod:`pathfuse.planners.globals.builtin` plus the
``follow`` controller (as ``astar`` is):
the global planner makes a path of straight sight lines from the start point
to the goal point; offline :func:`pathfuse.plan` returns it, online
:func:`pathfuse.simulate` walks it at full speed, blind to moving discs (as
``astar`` does; on a diff-drive robot with Regulated Pure Pursuit,
:mod:`pathfuse.planners.controllers.rpp`).  ``Budget.max_iterations`` caps the global search's
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
``jps``
    Jump point search (:mod:`pathfuse.search.jps`, Harabor and Grastien,
    without corner cutting): the optimal grid paths of ``astar`` (the same
    lengths), far fewer expansions.  ``Budget.max_iterations`` counts its
    expanded jump points.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..#...", "..#...", "......"])
>>> [round(plan(g, (0.5, 0.5), (5.5, 3.5), planner=p).length, 4)
...  for p in ("astar", "jps", "astar-smooth", "thetastar", "shortest")]
[6.8284, 6.8284, 6.6056, 6.6056, 6.085]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pathfuse.planners.controllers.follow import FollowController
from pathfuse.planners.globals.astar import GlobalPlan
from pathfuse.planners.globals.builtin import PathPlan, run_global
from pathfuse.planners.params import (
    GLOBAL_PLANNER_HELP,
    GlobalAStarParams,
    GlobalChoice,
    PursuitParams,
)
from pathfuse.planners.registry import PlannerSpec, get_global_planner, register
from pathfuse.problem import Problem
from pathfuse.validate import param

__all__ = ["ThetaStarParams", "LazyThetaStarParams", "SmoothParams", "ShortestParams",
           "JPSParams", "AnyAnglePlan", "plan_any_angle", "ANY_ANGLE"]

#: The presets of this module (each one's default global planner has its name).
ANY_ANGLE = ("thetastar", "lazy-thetastar", "astar-smooth", "shortest", "jps")

#: An older name of :class:`~pathfuse.planners.globals.builtin.PathPlan`.
AnyAnglePlan = PathPlan


@dataclass(frozen=True)
class ThetaStarParams(PursuitParams, GlobalChoice):
    """Parameters of ``thetastar``: the follower's on a diff-drive robot (the search has
    none: the heuristic is the Euclidean distance, the corner rule pathfuse's)."""

    global_planner: str = param("thetastar", help=GLOBAL_PLANNER_HELP)


@dataclass(frozen=True)
class LazyThetaStarParams(PursuitParams, GlobalChoice):
    """Parameters of ``lazy-thetastar`` (as :class:`ThetaStarParams`)."""

    global_planner: str = param("lazy-thetastar", help=GLOBAL_PLANNER_HELP)


@dataclass(frozen=True)
class SmoothParams(PursuitParams, GlobalAStarParams, GlobalChoice):
    """Parameters of ``astar-smooth``: the heuristic of its A*, the follower's on a
    diff-drive robot."""

    global_planner: str = param("astar-smooth", help=GLOBAL_PLANNER_HELP)


@dataclass(frozen=True)
class ShortestParams(PursuitParams, GlobalChoice):
    """Parameters of ``shortest``: the follower's on a diff-drive robot (the search has
    none)."""

    global_planner: str = param("shortest", help=GLOBAL_PLANNER_HELP)


@dataclass(frozen=True)
class JPSParams(PursuitParams, GlobalChoice):
    """Parameters of ``jps``: the follower's on a diff-drive robot (the search has none:
    the octile heuristic, no corner cutting)."""

    global_planner: str = param("jps", help=GLOBAL_PLANNER_HELP)


def plan_any_angle(kind: str, problem: Problem, params: Any,
                   max_expansions: int | None = None) -> GlobalPlan:
    """Run the global planner ``kind`` for ``problem`` (an older name of
    :func:`~pathfuse.planners.globals.builtin.run_global`)."""
    return run_global(kind, problem, params, max_expansions)


_PARAMS = {"thetastar": ThetaStarParams, "lazy-thetastar": LazyThetaStarParams,
           "astar-smooth": SmoothParams, "shortest": ShortestParams, "jps": JPSParams}
_ONLINE = {"thetastar": "; online it walks its path blind to moving discs"}

for _kind in ANY_ANGLE:
    register(PlannerSpec(name=_kind, params_cls=_PARAMS[_kind],
                         description=get_global_planner(_kind).description
                         + _ONLINE.get(_kind, ""),
                         controller=FollowController, global_planner=_kind))
