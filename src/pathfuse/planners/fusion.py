"""The A*-APF fusion planner (paper Section III.C, Algorithm 2), registered as ``"fusion"``.

Step 1 plans a global path with grid A* (Euclidean heuristic, no corner
cutting, on the map grown by ``robot_radius_m``); if A* fails its status is
returned.  Step 2 starts the robot at ``start`` and repeats, until the goal is
reached:

* every A* path point strictly inside the circle of radius ``r1_m`` around
  the robot that lies *ahead* attracts it (eq. 5), summed with the goal's
  attraction (eq. 9);
* every occupied cell centre closer than ``r2_m`` repels it (eq. 6, zero
  beyond ``rho0_m``);
* the robot makes one safe step along the resultant
  (:func:`pathfuse.field.stepper.safe_step`: never into or across an
  occupied cell grown by ``robot_radius_m``).

"Ahead" (``ahead``):

``"progress"`` (default)
    path points after the robot's progress index: the nearest path point in
    sight within reach along the path, which only moves forward
    (:func:`pathfuse.field.stepper.advance_progress`).  It does not depend on
    the direction of travel, so the planner gives the same walk on a rotated
    or mirrored map.
``"paper-x"``
    the paper's eq. 8, ``x_p - x_current > 0``, over the whole path.  It
    assumes the goal lies towards +x; travelling towards -x it attracts the
    points already passed and ignores those ahead (on the paper maps rotated
    by 180 degrees, 2 of 1000 plans succeed without escapes).

Local-minimum escape (``escape=True``, default).  The goal's attraction is
usually much larger than that of the few path points inside ``r1``
(K_att |X - X_g| against K_att |X - P|), so the robot heads for the goal,
slides along obstacles on the way, and can stall where the A* path turns
around a cluster.  When it stalls (net move below ``stall_distance_m`` over
``stall_steps`` steps) or is blocked, it backs off along its own walk: among
the walked points and the A* points within ``r1_m + resolution`` of them with
a clear straight move between the two, it picks the pair that makes "walk to
there, go straight to the A* point, follow the A* path to the goal" shortest
(first over the recent walk, ``stall_steps`` steps plus ``2 (r1_m +
resolution)`` metres back, then over the whole walk); the walk after that
point is dropped from the returned path
(``info["backoff_steps"]`` counts the dropped steps).  It goes straight to the
A* point, then follows the A* path point by point until it is
``escape_points`` points past its progress at the stall; then Algorithm 2
resumes.  Every move is checked for collision, each escape moves the progress
index forward, and the start (the first walked point) sees the first A*
point, so escapes end.  With ``escape=False`` the planner is the paper's as
printed and a stall ends the plan with ``LOCAL_MINIMUM`` (527 of the 1000
paper maps succeed that way; 1000 with escapes).

Result: ``time_s`` includes A*'s (see :func:`plan_fusion`); ``info`` holds
``astar_path``, ``astar_time_s``, ``astar_length``, ``escapes`` (count),
``backoff_steps``, ``step_time_s``, ``steps_per_s``, ``step_m`` and
``goal_tolerance_m``.  Other statuses as in :mod:`pathfuse.planners.apf`.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..##..", "......", "......"])
>>> r = plan(g, (0.5, 0.5), (4.5, 3.5), planner="fusion")
>>> r.status.name, r.path[-1].tolist(), r.length < r.info["astar_length"] + 1.0
('SUCCESS', [4.5, 3.5], True)
>>> plan(g, (0.5, 0.5), (4.5, 3.5), planner="fusion", ahead="behind")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: ahead must be one of 'progress', 'paper-x', got 'behind'
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from pathfuse.field.driver import (
    check_int,
    check_positive,
    check_stepping_params,
    drive,
    failure_message,
    outcome,
    resolve_stepping,
)
from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
from pathfuse.field.stepper import (
    AHEAD_PAPER_X,
    AHEAD_PROGRESS,
    F_GX,
    F_GY,
    N_S,
    S_BACKOFF,
    S_ESCAPES,
    fusion_force,
    fusion_run,
    fusion_solve,
    pack_fusion,
    polyline_cumlen,
)
from pathfuse.grid import GridMap
from pathfuse.planners.astar import astar_failed, global_astar
from pathfuse.planners.astar import warmup as astar_warmup
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.result import Budget, ConfigError, PlanResult, Status

#: A* settings of step 1: the paper's Euclidean heuristic, no corner cutting.

__all__ = [
    "FUSION_STEP_FRAC",
    "FusionParams",
    "plan_fusion",
    "follow_global_path",
    "force_at",
    "warmup",
]

_AHEAD = {"progress": AHEAD_PROGRESS, "paper-x": AHEAD_PAPER_X}

#: Default step of the fusion planner, as a fraction of the map resolution.
FUSION_STEP_FRAC = 0.5


@dataclass(frozen=True)
class FusionParams:
    """Parameters of the fusion planner (paper values for K_att, K_rep, rho_0).

    Attributes
    ----------
    step_m : float or None
        Length of one move, metres.  Default: :data:`FUSION_STEP_FRAC` (0.5)
        x the map resolution, coarser than the 0.1 of the plain APF: on the
        1000 paper maps success (100 %) and path length (median R_length vs
        A* -8.4 % at 0.5, -8.7 % at 0.1) hardly change with the step --
        every move is checked exactly, so a longer step is as safe -- while
        the planning time falls with the number of steps (fusion / A* time
        1.7-1.9 at 0.5, about 4 at 0.1).  Pass ``step_m`` to compare
        planners at equal steps.
    k_att, k_rep, rho0_m, goal_tolerance_m, robot_radius_m, stall_steps, stall_distance_m
        As in :class:`pathfuse.planners.apf.APFParams` (the goal tolerance and
        stall distance default to one and 2.5 steps).
    r1_m : float
        Radius of the circle (eq. 7) inside which A* path points attract the
        robot, metres.  The paper gives no value; the default is ``rho0_m``
        (2 m), the reach of the obstacles' repulsion, which takes in the next
        one or two A* points.  On the 1000 paper maps r1 = 1.5 / 2 / 3 m all
        succeed; 2 m gives shorter paths and fewer escapes than 1.5 m.
    r2_m : float
        Radius inside which obstacle points repel, metres.  Repulsion (eq. 6)
        is zero beyond ``rho0_m`` anyway, so the default equals ``rho0_m``
        (2 m) and larger values change nothing.
    ahead : {"progress", "paper-x"}
        Which path points count as ahead (see the module docstring).
    escape : bool
        Enable the local-minimum escape along the A* path.
    escape_points : int
        Path points to advance in escape mode before Algorithm 2 resumes.
    """

    k_att: float = K_ATT
    k_rep: float = K_REP
    rho0_m: float = RHO0_M
    r1_m: float = RHO0_M
    r2_m: float = RHO0_M
    ahead: str = "progress"
    step_m: float | None = None
    goal_tolerance_m: float | None = None
    robot_radius_m: float = 0.0
    stall_steps: int = 40
    stall_distance_m: float | None = None
    escape: bool = True
    escape_points: int = 3

    def __post_init__(self) -> None:
        check_stepping_params(self)
        check_positive("r1_m", self.r1_m)
        check_positive("r2_m", self.r2_m)
        if self.ahead not in _AHEAD:
            raise ConfigError(
                f"ahead must be one of {', '.join(repr(a) for a in _AHEAD)}, got {self.ahead!r}"
            )
        if not isinstance(self.escape, (bool, np.bool_)):
            raise ConfigError(f"escape must be true or false, got {self.escape!r}")
        check_int("escape_points", self.escape_points, 1)


def force_at(
    grid: GridMap,
    xy: object,
    goal: object,
    global_path: object,
    params: FusionParams | None = None,
    progress: int = 0,
) -> np.ndarray:
    """The resultant force of Algorithm 2 at ``xy`` (2,) given the global path.

    ``progress`` is the robot's progress index along ``global_path`` (used by
    ``ahead="progress"``).  Returns ``[fx, fy]``.

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> path = [[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5]]
    >>> force_at(g, (0.5, 0.5), (3.5, 0.5), path, FusionParams(r1_m=1.5)).tolist()
    [160.0, 0.0]
    """
    p = params or FusionParams()
    pts = np.ascontiguousarray(global_path, dtype=np.float64).reshape(-1, 2)
    x, y = (float(v) for v in np.asarray(xy, dtype=np.float64).reshape(2))
    gx, gy = (float(v) for v in np.asarray(goal, dtype=np.float64).reshape(2))
    ox, oy = grid.origin
    fx, fy, _ = fusion_force(x, y, gx, gy, pts, polyline_cumlen(pts), int(progress),
                             _AHEAD[p.ahead],
                             p.k_att, p.k_rep, p.rho0_m, p.r1_m, p.r2_m, grid.occupied, ox, oy,
                             grid.resolution)
    return np.array([fx, fy])


_CFG_CACHE: dict = {}


def _config(grid: GridMap, p: FusionParams, max_iterations: int | None):
    """(Stepping, float config template, int config) for a map frame; cached."""
    key = (p, grid.resolution, grid.origin, grid.shape, max_iterations)
    hit = _CFG_CACHE.get(key)
    if hit is None:
        step = p.step_m if p.step_m is not None else FUSION_STEP_FRAC * grid.resolution
        st = resolve_stepping(grid, step, p.goal_tolerance_m, p.stall_distance_m,
                              p.robot_radius_m, max_iterations)
        ox, oy = grid.origin
        window = p.stall_steps * st.step_m + 2.0 * (p.r1_m + grid.resolution)
        fcfg, icfg = pack_fusion((0.0, 0.0), p.k_att, p.k_rep, p.rho0_m, p.r1_m, p.r2_m,
                                 st.step_m, st.goal_tolerance_m, st.clear_m, p.stall_steps,
                                 st.stall_distance_m, ox, oy, grid.resolution, _AHEAD[p.ahead],
                                 p.escape, p.escape_points, window)
        if len(_CFG_CACHE) > 256:
            _CFG_CACHE.clear()
        hit = _CFG_CACHE[key] = (st, fcfg, icfg)
    return hit


def _step2(grid, start, goal, global_path, p, budget, deadline):
    """Run step 2; returns (DriveOutcome, state, Stepping, elapsed seconds)."""
    st, fcfg, icfg = _config(grid, p, budget.max_iterations)
    gpath = np.asarray(global_path, dtype=np.float64).reshape(-1, 2)
    gx, gy = float(goal[0]), float(goal[1])
    sx, sy = float(start[0]), float(start[1])
    occ = grid.occupied
    if deadline is None:
        # one numba call: the fast path.  Like A*'s time_s, the clock covers the
        # planning call itself (argument conversion and result building excluded).
        t0 = time.perf_counter()
        path, code, steps, state = fusion_solve(occ, sx, sy, gx, gy, gpath, fcfg, icfg,
                                                st.max_steps)
        t1 = time.perf_counter()
        return outcome(path, code, steps, st.max_steps, t1 - t0), state, st, t1 - t0
    t0 = time.perf_counter()
    if gpath.shape[0] == 0 or gpath[-1, 0] != gx or gpath[-1, 1] != gy:
        gpath = np.concatenate([gpath, np.array([[gx, gy]])])
    pts = np.ascontiguousarray(gpath)
    cum = polyline_cumlen(pts)
    fcfg = fcfg.copy()
    fcfg[F_GX] = gx
    fcfg[F_GY] = gy
    state = np.zeros(N_S, dtype=np.int64)
    occ = grid.occupied

    kbufs = [np.zeros(0, dtype=np.int64)]

    def run(buf, n, n_stop, k):
        kbuf = kbufs[0]
        if kbuf.shape[0] < buf.shape[0]:  # follow drive()'s buffer growth
            grown = np.zeros(buf.shape[0], dtype=np.int64)
            grown[: kbuf.shape[0]] = kbuf
            kbuf = kbufs[0] = grown
        return fusion_run(buf, n, n_stop, k, occ, pts, cum, state, fcfg, icfg, kbuf)

    out = drive(run, start, st.max_steps, deadline)
    return out, state, st, time.perf_counter() - t0


def _result(out, state, st, goal, p, time_s, expansions, info):
    """The PlanResult of step 2."""
    info.update(
        escapes=int(state[S_ESCAPES]),
        backoff_steps=int(state[S_BACKOFF]),
        step_m=st.step_m,
        goal_tolerance_m=st.goal_tolerance_m,
        step_time_s=out.step_time_s,
        steps_per_s=out.steps / out.step_time_s if out.step_time_s > 0 else 0.0,
    )
    if out.status is Status.SUCCESS:
        msg = f"reached the goal in {out.steps} steps ({int(state[S_ESCAPES])} escapes)"
    else:
        msg = failure_message(out, goal, st, p.stall_steps)
    length = float(polyline_cumlen(out.path)[-1])
    return PlanResult(out.status, out.path, length, time_s, "fusion", expansions, out.steps, msg,
                      info)


def follow_global_path(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    global_path: np.ndarray,
    params: FusionParams | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Step 2 of the fusion planner alone: follow ``global_path`` (M, 2) with Algorithm 2.

    The path points are the attractors of eq. 9 (the goal is appended if the
    path does not end there).  ``time_s`` is the time of step 2, measured as
    for :func:`plan_fusion`.

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> r = follow_global_path(g, (0.5, 0.5), (3.5, 2.5), [[0.5, 0.5], [1.5, 1.5], [2.5, 2.5]])
    >>> r.status.name, r.path[-1].tolist()
    ('SUCCESS', [3.5, 2.5])
    """
    p = params or FusionParams()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    deadline = (time.perf_counter() + budget.time_limit_s if budget.time_limit_s is not None
                else None)
    out, state, st, elapsed = _step2(grid, start, goal, global_path, p, budget, deadline)
    return _result(out, state, st, goal, p, elapsed, 0, {})


def plan_fusion(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    params: FusionParams | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Plan with Algorithm 2: A* (step 1), then the fused potential field (step 2).

    ``time_s`` is A*'s ``time_s`` plus the time of step 2, both measured the
    same way: around the planning call itself (for step 2 the numba call that
    builds the attractor list and steps), leaving out the query checks,
    argument conversion and result building, as the ``astar`` planner does.
    ``Budget.max_iterations`` caps the steps of step 2 (A* runs with the time
    limit only); ``Budget.time_limit_s`` covers both steps.
    """
    t0 = time.perf_counter()
    p = params or FusionParams()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    ares, info = global_astar(grid, start, goal, p.robot_radius_m, budget.time_limit_s)
    if not ares.success:
        return astar_failed(ares, "fusion", info)
    deadline = t0 + budget.time_limit_s if budget.time_limit_s is not None else None
    out, state, st, elapsed = _step2(grid, start, goal, ares.path, p, budget, deadline)
    return _result(out, state, st, goal, p, ares.time_s + elapsed, ares.expansions, info)


def warmup() -> None:
    """Compile (or load from numba's cache) A* and the fusion kernels on a tiny map."""
    astar_warmup()
    g = GridMap.from_rows(["....", ".#..", "...."])
    s, e = np.array([0.5, 0.5]), np.array([3.5, 2.5])
    path = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 1.5], [3.5, 2.5]])
    follow_global_path(g, s, e, path)  # the one-call solver
    follow_global_path(g, s, e, path, budget=Budget(time_limit_s=60.0))  # the chunked loop
    force_at(g, s, e, path)
    plan_fusion(g, s, e)


register(
    PlannerSpec(
        name="fusion",
        func=plan_fusion,
        params_cls=FusionParams,
        description="A*-APF fusion (paper Algorithm 2): APF attracted by the goal and the "
        "A* path points ahead within r1",
        uses_astar=True,
        warmup=warmup,
    )
)
