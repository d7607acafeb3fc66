"""Reference method [7] of the paper: A*, cut into sub-segments, plain APF along each.

Registered as ``"ref7"``.  The paper (Section II and IV.D) describes it as:
"uses a global path planning A-star algorithm to obtain an initial path.  On
a sub-base, a local path is obtained by the artificial potential field method
of local path planning.  The two parts are combined together".  This module
implements that description:

1. Grid A* (8-connected, no corner cutting, Euclidean heuristic, on the map
   grown by ``robot_radius_m``) gives the initial path.  If A* fails its
   status is returned with an empty path.
2. The A* path is cut into sub-segments (:func:`segment_ends`): every
   ``segment_points``-th A* point, or -- by default -- the first A* point at
   least ``segment_length_m`` of path length after the previous cut, ends a
   segment; the goal ends the last one.
3. The plain APF of :mod:`pathfuse.planners.apf` (eq. 5 attraction to the
   segment end, eq. 6 repulsion, fixed safe steps that never enter or cross
   an occupied square) plans from the start to the first segment end, from
   there to the next, and so on.  A segment end counts as reached within
   ``segment_tolerance_m``; the local path then ends with a straight,
   collision-checked move *onto* it, so the next local path starts exactly
   there.  The local paths are joined into one path with each joint point
   once.

Each local problem is the paper's plain APF, so a segment end or goal that
lies next to obstacles can still be out of reach (the repulsion balances the
attraction short of it); the tolerance of intermediate segment ends (half a
cell by default) absorbs that for them, and the final goal uses
``goal_tolerance_m`` (one step by default) as the plain APF does.

Endings (``PlanResult.status``): ``SUCCESS``; ``NO_PATH`` (and the other A*
failures) from step 1; ``LOCAL_MINIMUM`` when a local APF stalls or is blocked
(the partial path is returned and the remaining segments are not planned);
``MAX_ITERATIONS`` after ``Budget.max_iterations`` force steps over all
segments; ``TIMEOUT`` after ``Budget.time_limit_s`` (A* included).
``time_s`` is A*'s search time plus the wall time of cutting the path and stepping
(the convention of :mod:`pathfuse.planners.fusion`, so that times compare).

``info``: ``astar_path``, ``astar_length``, ``astar_time_s``, ``segments``
(K, 2) (the segment end points in order, the goal last),
``segment_index`` (K,) (their indices in the A* path),
``segments_done`` (how many local plans reached their end), ``joints``
(the indices in ``path`` of the reached segment ends), ``step_m``,
``goal_tolerance_m``, ``segment_tolerance_m``, ``step_time_s``,
``steps_per_s``.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..##..", "......", "......"])
>>> r = plan(g, (0.5, 0.5), (4.5, 3.5), planner="ref7", segment_points=2)
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [4.5, 3.5])
>>> r.info["segments"].tolist()   # every second A* point, then the goal
[[2.5, 1.5], [4.5, 1.5], [4.5, 3.5]]
>>> r.path[r.info["joints"]].tolist() == r.info["segments"].tolist()
True
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
    resolve_stepping,
)
from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
from pathfuse.field.stepper import apf_run, pack_apf
from pathfuse.grid import GridMap
from pathfuse.planners.astar import astar_failed, global_astar
from pathfuse.planners.astar import warmup as astar_warmup
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.result import Budget, PlanResult, Status, path_length

__all__ = ["Ref7Params", "plan_ref7", "follow_segments", "segment_ends", "warmup"]


@dataclass(frozen=True)
class Ref7Params:
    """Parameters of reference method [7] (paper values for K_att, K_rep, rho_0).

    Attributes
    ----------
    k_att, k_rep, rho0_m, step_m, goal_tolerance_m, robot_radius_m, stall_steps, stall_distance_m
        As in :class:`pathfuse.planners.apf.APFParams` (paper: 40, 5, 2 m).
    segment_length_m : float
        Path length of a sub-segment, metres: a segment ends at the first A*
        point at least this far along the A* path from the previous end.
    segment_points : int or None
        When given, a segment ends at every ``segment_points``-th A* point
        instead (``segment_length_m`` is then ignored).
    segment_tolerance_m : float or None
        An intermediate segment end counts as reached within this distance,
        metres.  Default: half a cell.
    """

    k_att: float = K_ATT
    k_rep: float = K_REP
    rho0_m: float = RHO0_M
    segment_length_m: float = 3.0
    segment_points: int | None = None
    step_m: float | None = None
    goal_tolerance_m: float | None = None
    segment_tolerance_m: float | None = None
    robot_radius_m: float = 0.0
    stall_steps: int = 40
    stall_distance_m: float | None = None

    def __post_init__(self) -> None:
        check_stepping_params(self)
        check_positive("segment_length_m", self.segment_length_m)
        if self.segment_points is not None:
            check_int("segment_points", self.segment_points, 1)
        check_positive("segment_tolerance_m", self.segment_tolerance_m, optional=True)


def segment_ends(
    path: object, segment_length_m: float = 3.0, segment_points: int | None = None
) -> np.ndarray:
    """Indices into ``path`` (N, 2) of the ends of its sub-segments, the last point last.

    With ``segment_points`` = k: ``k, 2k, ...`` and ``N - 1``.  Otherwise each
    end is the first point whose path length from the previous end (the
    first point at the start) is at least ``segment_length_m``; the last
    point always ends the last segment.  A path of one point gives ``[0]``.

    Examples
    --------
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
        check_int("segment_points", segment_points, 1)
        ends = list(range(segment_points, m - 1, segment_points))
    else:
        check_positive("segment_length_m", segment_length_m)
        cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        ends = []
        last = 0.0
        tol = 1e-9 * max(segment_length_m, 1.0)
        for i in range(1, m - 1):
            if cum[i] - last >= segment_length_m - tol:
                ends.append(i)
                last = cum[i]
    ends.append(m - 1)
    return np.asarray(ends, dtype=np.int64)


def follow_segments(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    ends: np.ndarray,
    params: Ref7Params | None = None,
    budget: Budget | None = None,
    *,
    deadline: float | None = None,
) -> PlanResult:
    """Step 3 of ref [7] alone: plain APF from ``start`` to each of ``ends`` (K, 2) in turn.

    ``goal`` is appended to ``ends`` when it is not their last point.
    ``deadline`` is the ``perf_counter`` value at which the plan ends with
    ``TIMEOUT`` (default: ``Budget.time_limit_s`` from now).  ``time_s`` is
    the wall time of this call.

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> r = follow_segments(g, np.array([0.5, 0.5]), np.array([3.5, 0.5]), [[1.5, 2.5]])
    >>> r.status.name, r.info["segments_done"], r.path[r.info["joints"]].tolist()
    ('SUCCESS', 2, [[1.5, 2.5], [3.5, 0.5]])
    """
    t0 = time.perf_counter()
    p = params or Ref7Params()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    targets = np.asarray(ends, dtype=np.float64).reshape(-1, 2)
    if targets.shape[0] == 0 or not np.array_equal(targets[-1], goal):
        targets = np.concatenate([targets, goal[None, :]])
    st = resolve_stepping(grid, p.step_m, p.goal_tolerance_m, p.stall_distance_m,
                          p.robot_radius_m, budget.max_iterations)
    seg_tol = (float(p.segment_tolerance_m) if p.segment_tolerance_m is not None
               else 0.5 * grid.resolution)
    if deadline is None and budget.time_limit_s is not None:
        deadline = t0 + budget.time_limit_s
    ox, oy = grid.origin
    occ = grid.occupied
    pieces = [start[None, :]]
    joints: list[int] = []
    npts = 1
    total = 0
    step_time = 0.0
    status = Status.SUCCESS
    out = None
    pos = start
    k_last = targets.shape[0] - 1
    for k in range(targets.shape[0]):
        tgt = targets[k]
        tol = st.goal_tolerance_m if k == k_last else seg_tol
        if total >= st.max_steps:
            status = Status.MAX_ITERATIONS
            break
        if deadline is not None and time.perf_counter() > deadline:
            status = Status.TIMEOUT
            break
        fcfg, icfg = pack_apf(tgt, p.k_att, p.k_rep, p.rho0_m, p.rho0_m, st.step_m, tol,
                              st.clear_m, p.stall_steps, st.stall_distance_m, ox, oy,
                              grid.resolution)
        out = drive(lambda buf, n, n_stop, cap, f=fcfg, i=icfg: apf_run(buf, n, n_stop, cap, occ,
                                                                         f, i),
                    pos, st.max_steps - total, deadline)
        total += out.steps
        step_time += out.step_time_s
        pieces.append(out.path[1:])
        npts += out.path.shape[0] - 1
        pos = out.path[-1]
        if out.status is not Status.SUCCESS:
            status = out.status
            break
        joints.append(npts - 1)
    path = np.concatenate(pieces)
    info = {
        "segments": targets,
        "segments_done": len(joints),
        "joints": np.asarray(joints, dtype=np.int64),
        "step_m": st.step_m,
        "goal_tolerance_m": st.goal_tolerance_m,
        "segment_tolerance_m": seg_tol,
        "step_time_s": step_time,
        "steps_per_s": total / step_time if step_time > 0 else 0.0,
    }
    if status is Status.SUCCESS:
        msg = f"reached the goal over {targets.shape[0]} segments in {total} steps"
    else:
        x, y = path[-1]
        where = (f"at ({x:.3f}, {y:.3f}), {float(np.hypot(x - goal[0], y - goal[1])):.3f} m "
                 f"from the goal")
        if out is not None and out.status is status:
            # the local plan of this segment ended the plan: explain it against its end
            what = failure_message(out, targets[len(joints)], st, p.stall_steps)
            msg = f"segment {len(joints) + 1} of {targets.shape[0]}: {what}"
        elif status is Status.MAX_ITERATIONS:
            msg = f"step cap of {st.max_steps} steps reached {where}"
        else:
            msg = f"time limit reached after {total} steps, {where}"
    return PlanResult(status, path, path_length(path), time.perf_counter() - t0, "ref7", 0,
                      total, msg, info)


def plan_ref7(
    grid: GridMap,
    start: np.ndarray,
    goal: np.ndarray,
    params: Ref7Params | None = None,
    budget: Budget | None = None,
) -> PlanResult:
    """Plan with reference method [7]: A*, cut into segments, plain APF segment by segment.

    ``time_s`` is A*'s ``time_s`` (its search; per-map preparation such as
    growing the map by ``robot_radius_m`` is left out, as for the ``astar``
    and ``fusion`` planners) plus the wall time of cutting the path and
    stepping.  ``Budget.max_iterations`` caps the APF steps over all segments
    (A* runs with the time limit only); ``Budget.time_limit_s`` covers both.
    """
    t0 = time.perf_counter()
    p = params or Ref7Params()
    budget = budget or Budget()
    start = np.asarray(start, dtype=np.float64).reshape(2)
    goal = np.asarray(goal, dtype=np.float64).reshape(2)
    deadline = t0 + budget.time_limit_s if budget.time_limit_s is not None else None
    ares, base = global_astar(grid, start, goal, p.robot_radius_m, budget.time_limit_s)
    apath = base["astar_path"]
    if not ares.success:
        return astar_failed(ares, "ref7", {**base, "segments": np.zeros((0, 2)),
                                            "segment_index": np.zeros(0, dtype=np.int64)})
    t1 = time.perf_counter()
    idx = segment_ends(apath, p.segment_length_m, p.segment_points)
    ends = apath[idx]
    ends[-1] = goal  # the last A* point is the goal's cell centre: end at the goal itself
    res = follow_segments(grid, start, goal, ends, p, budget, deadline=deadline)
    elapsed = time.perf_counter() - t1
    res.info.update(base, segment_index=idx)
    return PlanResult(res.status, res.path, res.length, ares.time_s + elapsed, "ref7",
                      ares.expansions, res.iterations, res.message, res.info)


def warmup() -> None:
    """Compile (or load from numba's cache) A* and the APF kernel on a tiny map."""
    from pathfuse.planners.apf import warmup as apf_warmup

    astar_warmup()
    apf_warmup()
    g = GridMap.from_rows(["....", ".#..", "...."])
    follow_segments(g, np.array([0.5, 0.5]), np.array([3.5, 2.5]), np.array([[2.5, 0.5]]))


register(
    PlannerSpec(
        name="ref7",
        func=plan_ref7,
        params_cls=Ref7Params,
        description="reference [7]: A* cut into sub-segments, plain APF from segment end "
        "to segment end, the local paths joined",
        uses_astar=True,
        warmup=warmup,
    )
)
