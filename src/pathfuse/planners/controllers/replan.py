"""The global path again from where the robot stands, around the sensed discs (ours).

Nav2's obstacle layer puts what the sensors see into the global costmap and
its default behaviour tree replans the global path once a second.
:func:`replan_around_discs` does the same for pathfuse's controllers: the
global planner runs from the robot's position on the map with the sensed
discs' cells blocked (grown by the robot's radius for A*, which searches the
c-space), and on the static map when the discs box the robot in.  ``dwa``
and ``mppi`` replan so every ``replan_period_s``; the fusion in velocity space
(:mod:`pathfuse.planners.controllers.fusion_window`) while it senses a disc.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from pathfuse.problem import Problem

__all__ = ["lane_discs", "replan_around_discs"]


def replan_around_discs(problem: Problem, x: float, y: float, dpos: np.ndarray,
                        drad: np.ndarray, params: Any,
                        clearance_m: float | None = None,
                        personal_m: float = 0.0, dvel: np.ndarray | None = None,
                        lane_s: float = 0.0, lane_detour_m: float = 0.0,
                        report: dict[str, Any] | None = None) -> np.ndarray | None:
    """Waypoints ``(M, 2)`` of a new global path from ``(x, y)`` to the goal, or None.

    Parameters
    ----------
    problem : Problem
        The query (map, goal, robot).
    x, y : float
        Where the robot stands (metres).
    dpos, drad : ndarray
        The sensed discs' centres ``(K, 2)`` and radii ``(K,)`` (``K`` may be 0:
        the static map).
    params
        The planner's parameters: ``global_planner`` names the global planner
        (``"astar"`` when it has none; A* searches with ``heuristic``).
    clearance_m : float, optional
        A* only: the soft margin it keeps from obstacles where the room allows,
        when larger than the problem's (``mppi``'s ``replan_clearance_m``).
    personal_m : float
        A* only (ours, ``dwa``'s ``social_replan``): the discs are first blocked grown by
        this much more (a person's personal space); when that leaves no path, as without.
    dvel, lane_s
        A* only (ours, the fusion's ``replan_lane_s``): with ``lane_s > 0`` and the discs'
        velocities ``dvel``, each disc is first blocked along the lane it sweeps at constant
        velocity over the next ``lane_s`` seconds too (grown as with ``personal_m``, then, when
        that leaves no path or the robot stands in it, by the robot's radius only), so the
        path leaves a walker's lane before the walker comes; when that leaves no path either,
        as without.
    lane_detour_m : float
        With the lanes (ours, the fusion's ``replan_lane_detour_m``; 0 = no limit): the path
        out of the lanes is taken only when it is at most this much longer than the path
        around the discs alone (grown as with ``personal_m``); otherwise that path.  A step
        aside out of a walker's lane is worth taking, a long detour (or a turn back) round a
        lane that a wandering or bouncing disc seldom walks is not.
    report : dict, optional
        Filled with ``"detour"``: whether the path out of the lanes was refused for its
        detour (``lane_detour_m``).

    Returns
    -------
    ndarray or None
        None when no path is found (on the crowded map nor on the static one).
    """
    name = getattr(params, "global_planner", "astar")
    if name != "astar":
        return _with_registered(problem, name, x, y, dpos, drad, params)
    from pathfuse.planners.globals.astar import plan_global

    occ = None
    here = problem.with_start((x, y))
    if clearance_m is not None and clearance_m > here.clearance_m:
        here = dataclasses.replace(here, clearance_m=clearance_m)
    gp = None
    if report is not None:
        report["detour"] = False
    if drad.shape[0]:
        from pathfuse.planners.controllers.follow import _rasterise_discs

        g = problem.grid
        static = g.cspace(problem.robot_radius_m).occupied
        lanes = lane_s > 0.0 and dvel is not None \
            and bool(np.any(np.abs(dvel) > 0.0))
        alone = None
        if lanes and lane_detour_m > 0.0:
            # ours (lane_detour_m): the path around the discs alone, to compare with
            alone = replan_around_discs(problem, x, y, dpos, drad, params, clearance_m,
                                        personal_m)
        if lanes and dvel is not None:
            lpos, lrad = lane_discs(dpos, dvel, drad, lane_s)
            # the lanes grown with the personal space, then (the robot standing in that, or
            # no path) by the robot's radius only
            for grow in dict.fromkeys((float(personal_m), 0.0)):
                occ = static.copy()
                _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]),
                                 float(g.resolution), lpos, lrad,
                                 float(problem.robot_radius_m) + grow)
                gp = plan_global(here, params.heuristic, occupied=occ)
                if gp.success:
                    break
                gp = None
            if gp is not None and lane_detour_m > 0.0 and alone is not None:
                wl = np.asarray(gp.waypoints, dtype=np.float64).reshape(-1, 2)
                if _length(wl) > _length(alone) + lane_detour_m:
                    if report is not None:
                        report["detour"] = True
                    return alone  # the lanes would cost a long detour: around the discs
        if gp is None and personal_m > 0.0:
            occ = static.copy()
            _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]), float(g.resolution),
                             dpos, drad, float(problem.robot_radius_m) + float(personal_m))
            gp = plan_global(here, params.heuristic, occupied=occ)
            if not gp.success:
                gp = None
        if gp is None:
            occ = static.copy()
            _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]),
                             float(g.resolution), dpos, drad, float(problem.robot_radius_m))
    if gp is None:
        gp = plan_global(here, params.heuristic, occupied=occ)
    if not gp.success and occ is not None:  # boxed in by the discs: the static path
        gp = plan_global(here, params.heuristic)
    return np.asarray(gp.waypoints, dtype=np.float64).reshape(-1, 2) if gp.success else None


def _length(pts: np.ndarray) -> float:
    """A polyline's length."""
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if pts.shape[0] > 1 else 0.0


def lane_discs(dpos: np.ndarray, dvel: np.ndarray, drad: np.ndarray,
               lane_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Each disc and copies of it along its constant-velocity motion over ``lane_s`` seconds,
    at most half its radius apart (ours, the fusion's ``replan_lane_s``).

    >>> p, r = lane_discs(np.array([[0.0, 0.0]]), np.array([[-1.0, 0.0]]), np.array([0.5]), 1.0)
    >>> p[:, 0].tolist(), r.tolist()
    ([0.0, -0.25, -0.5, -0.75, -1.0], [0.5, 0.5, 0.5, 0.5, 0.5])
    """
    ps = [dpos]
    rs = [drad]
    for i in range(drad.shape[0]):
        run = float(np.hypot(dvel[i, 0], dvel[i, 1])) * lane_s
        n = int(np.ceil(run / max(0.5 * float(drad[i]), 1e-3)))
        if n < 1 or run < 1e-6:
            continue
        t = np.arange(1, n + 1)[:, None] * (lane_s / n)
        ps.append(dpos[i] + dvel[i] * t)
        rs.append(np.full(n, float(drad[i])))
    return np.ascontiguousarray(np.concatenate(ps)), np.concatenate(rs)


def _with_registered(problem: Problem, name: str, x: float, y: float, dpos: np.ndarray,
                     drad: np.ndarray, params: Any) -> np.ndarray | None:
    """The registered global planner ``name`` (not A*): on the map with the sensed discs'
    cells blocked (a global planner sees a map, not discs), or, when that leaves no path
    or boxes the robot in, on the static map."""
    from pathfuse.planners.globals.builtin import run_global

    here = problem.with_start((x, y))
    gp = None
    if drad.shape[0]:
        from pathfuse.planners.controllers.follow import _rasterise_discs

        g = problem.grid
        occ = g.occupied.copy()
        _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]), float(g.resolution),
                         dpos, drad, 0.0)
        crowded = Problem.create(g.with_occupied(occ), (x, y), problem.goal,
                                 problem.robot_radius_m, problem.budget, problem.clearance_m,
                                 problem.robot)
        if crowded.failure() is None:
            gp = run_global(name, crowded, params)
    if gp is None or not gp.success:
        gp = run_global(name, here, params)
    return np.asarray(gp.waypoints, dtype=np.float64).reshape(-1, 2) if gp.success else None
