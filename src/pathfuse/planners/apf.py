"""Plain artificial potential field planner (paper Section III.B), registered as ``"apf"``.

The robot starts at ``start`` and repeatedly moves a fixed step along the
resultant of the goal's attraction (eq. 5) and the repulsion (eq. 6) of every
occupied cell centre within ``rho0_m``.  Moves are made by
:func:`pathfuse.field.stepper.safe_step`: a move that would enter an occupied
cell (grown by ``robot_radius_m``) or cross one is never taken; the robot
slides along the wall, shortens the move, or -- when no move is possible --
the plan ends with ``LOCAL_MINIMUM``.

Endings (``PlanResult.status``):

``SUCCESS``
    within ``goal_tolerance_m`` of the goal with a clear straight move onto
    it; the path ends exactly at the goal.
``LOCAL_MINIMUM``
    net displacement below ``stall_distance_m`` over the last ``stall_steps``
    steps (an equilibrium or an oscillation), or no collision-free move.
``MAX_ITERATIONS``
    ``Budget.max_iterations`` steps (default: 10 (width + height) resolution /
    step + 1000).
``TIMEOUT``
    ``Budget.time_limit_s`` passed (checked every 8192 steps).

On failure ``path`` is the partial path walked so far.  ``iterations`` is the
number of force steps; ``time_s`` covers setting up and stepping (building
the result is left out, as for A*); ``info`` holds ``step_m``, ``goal_tolerance_m``,
``step_time_s`` (time inside the stepping loop) and ``steps_per_s``.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "......", "..#...", "......"])
>>> r = plan(g, (0.5, 0.5), (5.5, 3.5), planner="apf")
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [5.5, 3.5])
>>> plan(g, (0.5, 0.5), (5.5, 3.5), planner="apf", k_att=-1).status
Traceback (most recent call last):
...
pathfuse.result.ConfigError: k_att must be > 0, got -1
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from pathfuse.field.driver import (
    check_stepping_params,
    drive,
    failure_message,
    outcome,
    resolve_stepping,
)
from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
from pathfuse.field.stepper import apf_force, apf_run, apf_solve, pack_apf
from pathfuse.grid import GridMap
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.result import Budget, PlanResult, Status, path_length

__all__ = ["APFParams", "plan_apf", "force_at", "warmup"]


@dataclass(frozen=True)
class APFParams:
    """Parameters of the plain APF planner (paper values as defaults).

    Attributes
    ----------
    k_att : float
        Attractive gain K_att of eq. 3/5 (paper: 40).
    k_rep : float
        Repulsive gain K_rep of eq. 4/6 (paper: 5).
    rho0_m : float
        Influence distance rho_0 of an obstacle point, metres (paper: 2).
    step_m : float or None
        Length of one move, metres.  Default: 0.1 x the map resolution
        (:data:`pathfuse.field.driver.STEP_FRAC`).
    goal_tolerance_m : float or None
        The goal counts as reached within this distance (then a straight move
        onto it ends the path).  Default: one step.
    robot_radius_m : float
        Radius of the disc robot; moves keep this distance from occupied
        squares (exactly, not by cell inflation).  0 = point robot.
    stall_steps : int
        Look-back of the stall test, in steps.
    stall_distance_m : float or None
        A net displacement below this over ``stall_steps`` steps is a local
        minimum.  Default: 2.5 steps.
    """

    k_att: float = K_ATT
    k_rep: float = K_REP
    rho0_m: float = RHO0_M
    step_m: float | None = None
    goal_tolerance_m: float | None = None
    robot_radius_m: float = 0.0
    stall_steps: int = 40
    stall_distance_m: float | None = None

    def __post_init__(self) -> None:
        check_stepping_params(self)


def force_at(
    grid: GridMap, xy: object, goal: object, params: APFParams | None = None
) -> np.ndarray:
    """The APF resultant force at world points ``xy`` (shape (2,) or (N, 2)).

    >>> g = GridMap.from_rows(["...", "...", "..."])
    >>> force_at(g, (0.5, 0.5), (2.5, 0.5)).tolist()
    [80.0, 0.0]
    """
    p = params or APFParams()
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    gx, gy = (float(v) for v in np.asarray(goal, dtype=np.float64).reshape(2))
    ox, oy = grid.origin
    out = np.empty_like(pts)
    for i in range(pts.shape[0]):
        out[i] = apf_force(pts[i, 0], pts[i, 1], gx, gy, p.k_att, p.k_rep, p.rho0_m, p.rho0_m,
                           grid.occupied, ox, oy, grid.resolution)
    return out[0] if np.ndim(xy) == 1 else out


def plan_apf(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    params: APFParams | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Plan with the plain APF (see the module docstring for the endings)."""
    t0 = time.perf_counter()
    p = params or APFParams()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    st = resolve_stepping(grid, p.step_m, p.goal_tolerance_m, p.stall_distance_m,
                          p.robot_radius_m, budget.max_iterations)
    ox, oy = grid.origin
    fcfg, icfg = pack_apf(goal, p.k_att, p.k_rep, p.rho0_m, p.rho0_m, st.step_m,
                          st.goal_tolerance_m, st.clear_m, p.stall_steps, st.stall_distance_m,
                          ox, oy, grid.resolution)
    occ = grid.occupied
    if budget.time_limit_s is None:
        t1 = time.perf_counter()
        path, code, steps = apf_solve(occ, float(start[0]), float(start[1]), float(goal[0]),
                                      float(goal[1]), fcfg, icfg, st.max_steps)
        out = outcome(path, code, steps, st.max_steps, time.perf_counter() - t1)
    else:
        deadline = t0 + budget.time_limit_s
        out = drive(lambda buf, n, n_stop, k: apf_run(buf, n, n_stop, k, occ, fcfg, icfg),
                    start, st.max_steps, deadline)
    time_s = time.perf_counter() - t0
    info = {
        "step_m": st.step_m,
        "goal_tolerance_m": st.goal_tolerance_m,
        "step_time_s": out.step_time_s,
        "steps_per_s": out.steps / out.step_time_s if out.step_time_s > 0 else 0.0,
    }
    msg = (f"reached the goal in {out.steps} steps" if out.status is Status.SUCCESS
           else failure_message(out, goal, st, p.stall_steps))
    return PlanResult(out.status, out.path, path_length(out.path), time_s, "apf", 0, out.steps,
                      msg, info)


def warmup() -> None:
    """Compile (or load from numba's cache) the APF kernels on a tiny map."""
    g = GridMap.from_rows(["....", ".#..", "...."])
    s, e = np.array([0.5, 0.5]), np.array([3.5, 2.5])
    plan_apf(g, s, e)  # the one-call solver
    plan_apf(g, s, e, budget=Budget(time_limit_s=60.0))  # the chunked loop
    force_at(g, s, e)


register(
    PlannerSpec(
        name="apf",
        func=plan_apf,
        params_cls=APFParams,
        description="artificial potential field (paper eq. 3-6): fixed steps along the "
        "resultant force, never entering an obstacle",
        uses_astar=False,
        warmup=warmup,
    )
)
