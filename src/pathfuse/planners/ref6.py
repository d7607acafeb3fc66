"""Reference method [6] of the paper: A*, then an improved APF through the inflection points.

Registered as ``"ref6"``.  The paper (Section II and IV.D) describes it as:
"first uses the A-star algorithm for planning to obtain the initial path, and
then sequentially uses each inflection point of the initial path as a
sub-target point, and uses the improved artificial potential field method of
local path planning to obtain the final path".  This module implements that
description:

1. Grid A* (8-connected, no corner cutting, Euclidean heuristic, on the map
   grown by ``robot_radius_m``) gives the initial path.  If A* fails its
   status is returned with an empty path.
2. The *inflection points* of the A* path -- the interior points where the
   direction of travel changes (:func:`inflection_points`) -- followed by the
   goal are the sub-goals, visited in order.
3. From the start the robot makes fixed safe steps
   (:func:`pathfuse.field.stepper.safe_step`: never into or across an
   occupied square grown by ``robot_radius_m``) along the improved APF force
   below, attracted by the *current* sub-goal.  When it is within
   ``subgoal_tolerance_m`` of a sub-goal the next one becomes current; the
   path ends at the goal as in :mod:`pathfuse.planners.apf`.

The improved repulsion
----------------------
Plain APF (eq. 4/6) cannot reach a goal that lies next to an obstacle: the
repulsion is not zero there, so the robot stops where it balances the
attraction, short of the goal (the "goal non-reachable with obstacles
nearby" problem).  The common fix, which is what "improved APF" usually
means in the A*+APF literature, is the repulsive potential of Ge and Cui
(S. S. Ge, Y. J. Cui, "New potential functions for mobile robot path
planning", IEEE Trans. Robotics and Automation 16(5), 2000), which multiplies
eq. 4 by a power of the distance to the goal.  Here, with ``rho`` the distance
to an obstacle point, ``rho_g = |X - X_t|`` the distance to the *target*
``X_t`` and ``L`` a scale length::

    U_rep*(X) = U_rep(X) (rho_g / L)^n                                  (eq. 4 x scale)
    F_rep*(X) = -grad U_rep*
              = (rho_g / L)^n F_rep(X)                                  (eq. 6, scaled)
              + n U_rep(X) (rho_g / L)^(n-1) / L  (X_t - X) / rho_g      (pull to the target)

summed over the occupied cell centres within ``rho0_m``.  ``n`` is
``rep_exponent`` and ``L`` is ``rep_scale_m`` (default ``rho0_m``: the
scaled repulsion equals eq. 6 at ``rho0_m`` from the target).  For ``n > 0``
both terms vanish at the target, so a target next to an obstacle is reached
(Ge and Cui need ``n > 0``; with ``n >= 1`` the force stays bounded near the
target).  The target ``X_t`` is the current sub-goal (``rep_target="subgoal"``,
default: every sub-problem is an improved APF towards its own goal, so
every inflection point -- which A* puts next to an obstacle corner -- is
reachable) or the final goal (``rep_target="goal"``).  The attraction is
eq. 5 towards the current sub-goal.

Endings (``PlanResult.status``): ``SUCCESS``; ``NO_PATH`` (and the other A*
failures) from step 1; ``LOCAL_MINIMUM`` when the robot stalls or is blocked
on the way to any sub-goal (the partial path is returned, the plan is not
continued past a failed sub-problem); ``MAX_ITERATIONS`` after
``Budget.max_iterations`` force steps in all; ``TIMEOUT`` after
``Budget.time_limit_s`` (A* included).  ``time_s`` is A*'s search time
plus the wall time of finding the inflection points and stepping (the convention of
:mod:`pathfuse.planners.fusion`, so that times compare).

``info``: ``astar_path`` (the A* path, cell centres), ``astar_length``,
``astar_time_s``, ``subgoals`` (K, 2) (the inflection points in order, then
the goal), ``subgoals_reached`` (how many of them the robot reached),
``step_m``, ``goal_tolerance_m``, ``subgoal_tolerance_m``, ``step_time_s``,
``steps_per_s``.

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
>>> inflection_points([[0, 0], [1, 0], [2, 0], [3, 1], [3, 2]]).tolist()
[[2.0, 0.0], [3.0, 1.0]]
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from pathfuse.field.driver import (
    check_positive,
    check_stepping_params,
    drive,
    failure_message,
    resolve_stepping,
)
from pathfuse.field.forces import (
    K_ATT,
    K_REP,
    RHO0_M,
    att_force_xy,
    rep_potential_d,
    repulsive_force,
    repulsive_potential,
)
from pathfuse.field.stepper import (
    CODE_BLOCKED,
    CODE_RUNNING,
    CODE_STALLED,
    HOW_BLOCKED,
    _goal_reached,
    grid_repulsion,
    safe_step,
)
from pathfuse.grid import GridMap
from pathfuse.planners.astar import astar_failed, global_astar
from pathfuse.planners.astar import warmup as astar_warmup
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.result import Budget, ConfigError, PlanResult, Status, path_length

__all__ = [
    "Ref6Params",
    "plan_ref6",
    "follow_subgoals",
    "inflection_points",
    "improved_repulsive_force",
    "improved_repulsive_potential",
    "grid_improved_repulsion",
    "warmup",
]

_TARGETS = {"subgoal": 0, "goal": 1}

# Slots of the float config of ref6_run.  Own layout, not stepper's: numba bakes
# global constants into the cached machine code of *this* module, and its cache
# is not invalidated when another module's constants change.
(C_GX, C_GY, C_KATT, C_KREP, C_RHO0, C_STEP, C_TOL, C_CLEAR, C_STALLD, C_OX, C_OY, C_RES,
 C_SUBTOL, C_NEXP, C_SCALE) = range(15)
N_C = 15
# state: current sub-goal index
S_SUB = 0


@dataclass(frozen=True)
class Ref6Params:
    """Parameters of reference method [6] (paper values for K_att, K_rep, rho_0).

    Attributes
    ----------
    k_att, k_rep, rho0_m, step_m, goal_tolerance_m, robot_radius_m, stall_steps, stall_distance_m
        As in :class:`pathfuse.planners.apf.APFParams` (paper: 40, 5, 2 m).
    subgoal_tolerance_m : float or None
        A sub-goal (inflection point) counts as reached within this distance,
        metres; then the next sub-goal attracts the robot.  Default: half a
        cell.
    rep_exponent : float
        ``n`` of the improved repulsion (> 0; see the module docstring).
    rep_scale_m : float or None
        ``L`` of the improved repulsion, metres.  Default: ``rho0_m``.
    rep_target : {"subgoal", "goal"}
        The point whose distance scales the repulsion: the current sub-goal
        or the final goal.
    """

    k_att: float = K_ATT
    k_rep: float = K_REP
    rho0_m: float = RHO0_M
    step_m: float | None = None
    goal_tolerance_m: float | None = None
    subgoal_tolerance_m: float | None = None
    robot_radius_m: float = 0.0
    stall_steps: int = 40
    stall_distance_m: float | None = None
    rep_exponent: float = 2.0
    rep_scale_m: float | None = None
    rep_target: str = "subgoal"

    def __post_init__(self) -> None:
        check_stepping_params(self)
        check_positive("subgoal_tolerance_m", self.subgoal_tolerance_m, optional=True)
        check_positive("rep_exponent", self.rep_exponent)
        check_positive("rep_scale_m", self.rep_scale_m, optional=True)
        if self.rep_target not in _TARGETS:
            raise ConfigError(
                f"rep_target must be one of {', '.join(repr(t) for t in _TARGETS)}, "
                f"got {self.rep_target!r}"
            )


# --------------------------------------------------------------------- inflection points
def inflection_points(path: object, rtol: float = 1e-9) -> np.ndarray:
    """The interior points of a polyline where its direction changes, in order.

    A point ``P[i]`` (``0 < i < N-1``) is an inflection point when the move
    into it and the move out of it are not parallel with the same sense
    (cross product above ``rtol`` times the product of their lengths, or a
    reversal).  Repeated consecutive points are dropped first.  The end
    points are never inflection points.

    Parameters
    ----------
    path : array_like, shape (N, 2)
    rtol : float
        Relative tolerance of the parallel test.

    Returns
    -------
    ndarray, shape (K, 2)

    Examples
    --------
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


# --------------------------------------------------------------------- improved repulsion
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


@njit(cache=True)
def grid_rep_potential(x, y, occ, ox, oy, res, k_rep, rho0_m):
    """Sum of eq. 4 over the occupied cell centres closer than ``rho0_m`` to ``(x, y)``.

    The same window as :func:`pathfuse.field.stepper.grid_repulsion`.
    """
    h, w = occ.shape
    c0 = max(int(math.ceil((x - rho0_m - ox) / res - 0.5)), 0)
    c1 = min(int(math.floor((x + rho0_m - ox) / res - 0.5)), w - 1)
    r0 = max(int(math.ceil((y - rho0_m - oy) / res - 0.5)), 0)
    r1 = min(int(math.floor((y + rho0_m - oy) / res - 0.5)), h - 1)
    u = 0.0
    rad2 = rho0_m * rho0_m
    for r in range(r0, r1 + 1):
        dy = y - (oy + (r + 0.5) * res)
        for c in range(c0, c1 + 1):
            if occ[r, c]:
                dx = x - (ox + (c + 0.5) * res)
                d2 = dx * dx + dy * dy
                if d2 < rad2:
                    u += rep_potential_d(math.sqrt(d2), k_rep, rho0_m)
    return u


@njit(cache=True)
def grid_improved_repulsion(x, y, tx, ty, occ, ox, oy, res, k_rep, rho0_m, n, scale_m):
    """The Ge-Cui repulsion at ``(x, y)`` for the target ``(tx, ty)`` on a grid.

    ``(rho_g/L)^n`` times :func:`~pathfuse.field.stepper.grid_repulsion` plus
    ``n U (rho_g/L)^(n-1) / L`` towards the target (``U`` =
    :func:`grid_rep_potential`).  Zero at the target.
    """
    dgx = tx - x
    dgy = ty - y
    rg = math.hypot(dgx, dgy)
    if rg == 0.0:
        return 0.0, 0.0
    q = rg / scale_m
    s = q**n
    fx, fy = grid_repulsion(x, y, occ, ox, oy, res, k_rep, rho0_m, rho0_m)
    fx *= s
    fy *= s
    u = grid_rep_potential(x, y, occ, ox, oy, res, k_rep, rho0_m)
    if u > 0.0:
        m = u * n * q ** (n - 1.0) / scale_m / rg
        fx += m * dgx
        fy += m * dgy
    return fx, fy


@njit(cache=True)
def ref6_run(buf, n, n_stop, max_steps, occ, subs, state, cfg, stall_n, to_goal):
    """Improved-APF steps through the sub-goals ``subs`` (K, 2) (the last is the goal).

    The calling convention of :func:`pathfuse.field.stepper.apf_run`;
    ``state[S_SUB]`` (the current sub-goal index) is carried between calls,
    ``cfg`` is built by :func:`pack_ref6`, ``stall_n`` is the stall look-back in
    steps and ``to_goal`` selects the final goal as the repulsion's target.
    """
    gx = cfg[C_GX]
    gy = cfg[C_GY]
    k_att = cfg[C_KATT]
    k_rep = cfg[C_KREP]
    rho0 = cfg[C_RHO0]
    step = cfg[C_STEP]
    tol = cfg[C_TOL]
    clear = cfg[C_CLEAR]
    stall_d = cfg[C_STALLD]
    ox = cfg[C_OX]
    oy = cfg[C_OY]
    res = cfg[C_RES]
    sub_tol = cfg[C_SUBTOL]
    nexp = cfg[C_NEXP]
    scale = cfg[C_SCALE]
    last = subs.shape[0] - 1
    j = state[S_SUB]
    x = buf[n - 1, 0]
    y = buf[n - 1, 1]
    steps = 0
    code = CODE_RUNNING
    while True:
        if j < last and math.hypot(x - subs[j, 0], y - subs[j, 1]) <= sub_tol:
            j += 1
            continue
        if j == last:
            n, done = _goal_reached(buf, n, x, y, gx, gy, tol, occ, ox, oy, res, clear)
            if done != CODE_RUNNING:
                code = done
                break
        if n >= n_stop or steps >= max_steps:
            break
        sx = subs[j, 0]
        sy = subs[j, 1]
        fx, fy = att_force_xy(x, y, sx, sy, k_att)
        if to_goal:
            rx, ry = grid_improved_repulsion(x, y, gx, gy, occ, ox, oy, res, k_rep, rho0, nexp,
                                             scale)
        else:
            rx, ry = grid_improved_repulsion(x, y, sx, sy, occ, ox, oy, res, k_rep, rho0, nexp,
                                             scale)
        nx, ny, how = safe_step(x, y, fx + rx, fy + ry, step, occ, ox, oy, res, clear)
        if how == HOW_BLOCKED:
            code = CODE_BLOCKED
            break
        buf[n, 0] = nx
        buf[n, 1] = ny
        n += 1
        steps += 1
        x = nx
        y = ny
        if n - 1 >= stall_n:
            p = n - 1 - stall_n
            if math.hypot(x - buf[p, 0], y - buf[p, 1]) < stall_d:
                code = CODE_STALLED
                break
    state[S_SUB] = j
    return n, code, steps


def pack_ref6(goal, k_att, k_rep, rho0_m, step_m, tol_m, clear_m, stall_distance_m, ox, oy,
              res, subgoal_tol_m, rep_exponent, rep_scale_m):
    """The float config array of :func:`ref6_run`."""
    c = np.zeros(N_C)
    c[C_GX], c[C_GY] = float(goal[0]), float(goal[1])
    c[C_KATT], c[C_KREP], c[C_RHO0] = k_att, k_rep, rho0_m
    c[C_STEP], c[C_TOL], c[C_CLEAR], c[C_STALLD] = step_m, tol_m, clear_m, stall_distance_m
    c[C_OX], c[C_OY], c[C_RES] = ox, oy, res
    c[C_SUBTOL], c[C_NEXP], c[C_SCALE] = subgoal_tol_m, rep_exponent, rep_scale_m
    return c


# --------------------------------------------------------------------- planner
def follow_subgoals(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    subgoals: np.ndarray,
    params: Ref6Params | None = None,
    budget: Budget | None = None,
    *,
    deadline: float | None = None,
) -> PlanResult:
    """Step 3 of ref [6] alone: improved APF from ``start`` through ``subgoals`` to ``goal``.

    ``subgoals`` (K, 2) are visited in order; ``goal`` is appended when it is
    not their last point.  ``deadline`` is the ``perf_counter`` value at
    which the plan ends with ``TIMEOUT`` (default: ``Budget.time_limit_s``
    from now).  ``time_s`` is the wall time of this call.

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> r = follow_subgoals(g, np.array([0.5, 0.5]), np.array([3.5, 0.5]), [[1.5, 2.5]])
    >>> r.status.name, r.info["subgoals_reached"], bool(r.path[:, 1].max() > 2.0)
    ('SUCCESS', 2, True)
    """
    t0 = time.perf_counter()
    p = params or Ref6Params()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    subs = np.asarray(subgoals, dtype=np.float64).reshape(-1, 2)
    if subs.shape[0] == 0 or not np.array_equal(subs[-1], goal):
        subs = np.concatenate([subs, goal[None, :]])
    subs = np.ascontiguousarray(subs)
    st = resolve_stepping(grid, p.step_m, p.goal_tolerance_m, p.stall_distance_m,
                          p.robot_radius_m, budget.max_iterations)
    sub_tol = (float(p.subgoal_tolerance_m) if p.subgoal_tolerance_m is not None
               else 0.5 * grid.resolution)
    scale = float(p.rep_scale_m) if p.rep_scale_m is not None else float(p.rho0_m)
    if deadline is None and budget.time_limit_s is not None:
        deadline = t0 + budget.time_limit_s
    ox, oy = grid.origin
    cfg = pack_ref6(goal, p.k_att, p.k_rep, p.rho0_m, st.step_m, st.goal_tolerance_m,
                    st.clear_m, st.stall_distance_m, ox, oy, grid.resolution, sub_tol,
                    float(p.rep_exponent), scale)
    stall_n = int(p.stall_steps)
    to_goal = p.rep_target == "goal"
    state = np.zeros(1, dtype=np.int64)
    occ = grid.occupied
    out = drive(lambda buf, n, n_stop, k: ref6_run(buf, n, n_stop, k, occ, subs, state, cfg,
                                                   stall_n, to_goal),
                start, st.max_steps, deadline)
    reached = int(state[S_SUB]) + (1 if out.status is Status.SUCCESS else 0)
    info = {
        "subgoals": subs,
        "subgoals_reached": reached,
        "step_m": st.step_m,
        "goal_tolerance_m": st.goal_tolerance_m,
        "subgoal_tolerance_m": sub_tol,
        "step_time_s": out.step_time_s,
        "steps_per_s": out.steps / out.step_time_s if out.step_time_s > 0 else 0.0,
    }
    if out.status is Status.SUCCESS:
        msg = f"reached the goal through {subs.shape[0] - 1} sub-goals in {out.steps} steps"
    else:
        msg = (f"{failure_message(out, goal, st, p.stall_steps)} (heading for sub-goal "
               f"{int(state[S_SUB]) + 1} of {subs.shape[0]})")
    return PlanResult(out.status, out.path, path_length(out.path), time.perf_counter() - t0,
                      "ref6", 0, out.steps, msg, info)


def plan_ref6(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    params: Ref6Params | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Plan with reference method [6]: A*, then improved APF through its inflection points.

    ``time_s`` is A*'s ``time_s`` (its search; per-map preparation such as
    growing the map by ``robot_radius_m`` is left out, as for the ``astar``
    and ``fusion`` planners) plus the wall time of finding the inflection
    points and stepping.  ``Budget.max_iterations`` caps the APF steps (A*
    runs with the time limit only); ``Budget.time_limit_s`` covers both.
    """
    t0 = time.perf_counter()
    p = params or Ref6Params()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    deadline = t0 + budget.time_limit_s if budget.time_limit_s is not None else None
    ares, base = global_astar(grid, start, goal, p.robot_radius_m, budget.time_limit_s)
    apath = base["astar_path"]
    if not ares.success:
        return astar_failed(ares, "ref6", {**base, "subgoals": np.zeros((0, 2))})
    t1 = time.perf_counter()
    res = follow_subgoals(grid, start, goal, inflection_points(apath), p, budget,
                          deadline=deadline)
    elapsed = time.perf_counter() - t1
    res.info.update(base)
    return PlanResult(res.status, res.path, res.length, ares.time_s + elapsed, "ref6",
                      ares.expansions, res.iterations, res.message, res.info)


def warmup() -> None:
    """Compile (or load from numba's cache) A* and the ref [6] kernels on a tiny map."""
    astar_warmup()
    g = GridMap.from_rows(["....", ".#..", "...."])
    s, e = np.array([0.5, 0.5]), np.array([3.5, 2.5])
    subs = np.array([[2.5, 0.5], [3.5, 1.5]])
    follow_subgoals(g, s, e, subs)
    follow_subgoals(g, s, e, subs, Ref6Params(rep_target="goal"))


register(
    PlannerSpec(
        name="ref6",
        func=plan_ref6,
        params_cls=Ref6Params,
        description="reference [6]: A*, then an improved (Ge-Cui) APF through the A* "
        "inflection points as sub-goals",
        uses_astar=True,
        warmup=warmup,
    )
)
