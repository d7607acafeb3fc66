"""The stepping loops of the potential-field controllers (numba), shared by plan() and simulate().

Two loops serve every field controller:

* :func:`field_loop` - a robot attracted by a sequence of sub-goals, the last
  one the goal: plain APF (one sub-goal, the goal), reference method [6]
  (the A* path's inflection points, Ge-Cui repulsion) and reference method
  [7] (the ends of A* sub-segments, plain repulsion).
* :func:`fusion_loop` - Algorithm 2 of the paper with pathfuse's
  local-minimum escape.

Each call steps from ``buf[n-1]`` until the goal, a stall, a block, or
``max_steps`` force steps, and returns ``(buf, n, code, steps)`` (the path
buffer is grown when full, so the caller keeps the returned one).
:func:`pathfuse.plan` calls a loop once, or in chunks between wall-clock
checks; :func:`pathfuse.simulate` calls the *same* loop with
``max_steps = 1`` once per tick, after writing the robot's observed position
into ``buf[n-1]`` and the sensed discs into ``dpos, dvel, drad`` (empty
arrays when none is sensed, where the disc terms vanish).  So the plan a
controller makes and the way it drives are one code path.  An offline run
passes :data:`STATIC` (``None`` for the discs): numba prunes every ``drad is
None`` branch when it compiles that signature, so a static plan compiles no
disc code (seconds on a cold cache) and computes what empty arrays give.  The
last argument, ``margin``, is the soft safety margin (the settings'
``margin_m``); a static run without one omits it (``None``), which prunes the
margin's code the same way.

The map, its frame, the robot's radius and the clearance it keeps come as one
:class:`~pathfuse.costmap.Costmap` (``cm``, built without its lattice, which
the loops do not read), the settings as named tuples read by name
(:class:`~pathfuse.field.settings.FieldSettings` or
:class:`~pathfuse.field.settings.FusionSettings`, ``s``, and the moving
discs' :class:`~pathfuse.field.settings.DiscSettings`, ``ds``); state that
persists between calls lives in an ``int64`` array (``state``).

Codes: :data:`CODE_RUNNING` (``max_steps`` reached: call again),
:data:`CODE_GOAL` (the robot stands on the goal), :data:`CODE_GOAL_SNAP`
(within the goal tolerance: a straight move onto the goal was appended, not
counted as a step), :data:`CODE_STALLED` (net move below the stall distance
over the stall window), :data:`CODE_BLOCKED` (no collision-free move along
the force), :data:`CODE_COLLISION` (``safe_step`` off: the full step along the
force touched an obstacle; the step is in the path).  :func:`code_status`
maps them to :class:`~pathfuse.result.Status`.

The paper's rules (both loops): with ``safe_step`` false the robot takes the full
step along the force, as the paper's Algorithm 2 does, instead of the safe
step (:func:`~pathfuse.field.motion.safe_step`: slide along the wall or
shorten the step); a step that would touch an obstacle (for a disc robot:
come closer than its radius, the rule of :mod:`pathfuse.metrics`) is taken and
ends the run with :data:`CODE_COLLISION`.  With ``stall_exit`` false there is no
stall test (the paper's loop ends only at the goal): the run ends at the goal,
a block, a collision or the move cap.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.costmap import move_clear
from pathfuse.field.forces import att_force_xy
from pathfuse.field.motion import (
    HOW_BLOCKED,
    HOW_FULL,
    safe_step,
    safe_step_margin,
    straight_move,
)
from pathfuse.field.pathing import advance_progress, find_rejoin
from pathfuse.field.repulsion import (
    disc_repulsion,
    fusion_force,
    grid_improved_repulsion,
    static_repulsion,
)
from pathfuse.result import (
    CODE_COLLISION,
    CODE_LOCAL_MINIMUM,
    CODE_RUNNING,
    CODE_SUCCESS,
    Status,
    code_outcome,
    refined,
)

__all__ = [
    "STATIC",
    "CODE_RUNNING",
    "CODE_GOAL",
    "CODE_STALLED",
    "CODE_BLOCKED",
    "CODE_GOAL_SNAP",
    "CODE_COLLISION",
    "code_status",
    "field_loop",
    "fusion_loop",
]

# The loops' codes, from :class:`~pathfuse.result.Status` (:data:`~pathfuse.result.CODE_SUCCESS`).
CODE_GOAL = CODE_SUCCESS
CODE_GOAL_SNAP = refined(CODE_SUCCESS)
CODE_STALLED = CODE_LOCAL_MINIMUM
CODE_BLOCKED = refined(CODE_LOCAL_MINIMUM)

# --- state
S_SUB = 0  # field_loop: current sub-goal index
# fusion_loop: progress index, mode (0 Algorithm 2, 1 escape along path points,
# 2 driving back along the walk), stall reference point, escape exit index, escapes,
# escape target index, steps dropped (planning) or driven back, walk-back target
# index, walk-back stop index, steps since the last escape target
S_K, S_MODE, S_REF, S_ESC_K, S_ESCAPES, S_T, S_BACKOFF, S_WB, S_WI, S_ESTEPS = range(10)
N_S = 10


#: The disc arguments ``dpos, dvel, drad`` of an offline run: no disc code is compiled.
STATIC = (None, None, None)


def code_status(code: int, steps: int, max_steps: int) -> Status:
    """The :class:`~pathfuse.result.Status` of a finished loop."""
    status = code_outcome(code)
    if status is not None:
        return status
    if steps >= max_steps:
        return Status.MAX_ITERATIONS
    return Status.TIMEOUT


# --------------------------------------------------------------------- shared pieces
@njit(cache=True, inline="always")
def _goal_reached(buf, n, x, y, s, cm):
    """Goal test: append the goal when within the goal tolerance and the move onto it is
    clear."""
    gx = s.goal_x_m
    gy = s.goal_y_m
    tol = s.goal_tolerance_m
    ex = x - gx
    ey = y - gy
    if ex * ex + ey * ey <= tol * tol:
        if x == gx and y == gy:
            return n, CODE_GOAL
        if move_clear(cm, x, y, gx, gy, cm.clear_m):
            buf[n, 0] = gx
            buf[n, 1] = gy
            return n + 1, CODE_GOAL_SNAP
    return n, CODE_RUNNING


@njit(cache=True, inline="always")
def _discs(x, y, fx, fy, cm, ds, dpos, dvel, drad):
    """The sensed discs' repulsion for a robot heading along ``(fx, fy)``."""
    if drad is None:  # a static run: no disc code is compiled
        return 0.0, 0.0
    if drad.shape[0] == 0:
        return 0.0, 0.0
    fn = math.hypot(fx, fy)
    ux = fx / fn if fn > 0.0 else 0.0
    uy = fy / fn if fn > 0.0 else 0.0
    return disc_repulsion(x, y, ds.robot_vx_mps, ds.robot_vy_mps, cm.radius_m, dpos, dvel,
                          drad, ds.k_rep, ds.rho0_m, ds.reach_m, ds.velocity_aware,
                          ds.a_max_mps2, ds.swerve, ux, uy)


@njit(cache=True, inline="always")
def _step(x, y, fx, fy, s, cm, margin):
    """One move of ``s.step_m``: the safe step (``s.safe_step``; keeping the soft safety
    ``margin`` too, see :func:`~pathfuse.field.motion.safe_step_margin`), or the paper's
    full step along the force.

    Returns ``(nx, ny, how)``; for the full step ``how`` is ``HOW_BLOCKED`` for a
    zero force, ``HOW_FULL`` for a step touching nothing and ``-1`` for a step
    that touches an obstacle (closer than the robot's radius; for a point any contact).
    """
    step = s.step_m
    clear = cm.clear_m
    radius = cm.radius_m
    if s.safe_step:
        if margin is None:  # no margin (pruned when compiled): the safe step itself
            return safe_step(x, y, fx, fy, step, cm, clear)
        return safe_step_margin(x, y, fx, fy, step, cm, clear, margin)
    fn = math.hypot(fx, fy)
    if not (fn > 0.0) or not math.isfinite(fn):
        return x, y, HOW_BLOCKED
    nx = x + step * fx / fn
    ny = y + step * fy / fn
    touch = radius if radius > 0.0 else 5e-324
    if move_clear(cm, x, y, nx, ny, touch):
        return nx, ny, HOW_FULL
    return nx, ny, -1


# _grow, _grow_int and _escape_move are called (not inlined by numba, inline="always"):
# they run when a buffer is full or the robot escapes, and inlining them cost the loops'
# first compilation about 0.5 s of CPU (numba re-reads and re-types an inlined body at
# each call site); LLVM may still inline them
@njit(cache=True)
def _grow(buf, n):
    if n + 2 <= buf.shape[0]:
        return buf
    nb = np.empty((2 * buf.shape[0], 2))
    for j in range(n):  # a loop, not a slice: numba compiles a slice copy's shape-error
        nb[j, 0] = buf[j, 0]  # message formatting (seconds of compile time)
        nb[j, 1] = buf[j, 1]
    return nb


@njit(cache=True)
def _grow_int(kbuf, n):
    if n + 2 <= kbuf.shape[0]:
        return kbuf
    nk = np.empty(2 * kbuf.shape[0], dtype=np.int64)
    for j in range(n):
        nk[j] = kbuf[j]
    return nk


# --------------------------------------------------------------------- field loop
@njit(cache=True)
def field_loop(buf, n, max_steps, cm, subs, state, s, ds, dpos, dvel, drad, margin=None):
    """APF steps through the sub-goals ``subs`` (K, 2), the last one the goal.

    The current sub-goal ``subs[state[S_SUB]]`` attracts (eq. 5); it is
    passed when the robot comes within the sub-goal tolerance.  Repulsion:
    eq. 6 from the cells within ``rho0`` (plain) or the Ge-Cui form towards
    the sub-goal or the goal (``s.improved``, ``s.rep_to_goal``), plus the
    sensed discs.  The goal test runs before every step.  ``cm`` is the
    :class:`~pathfuse.costmap.Costmap`, ``s`` the
    :class:`~pathfuse.field.settings.FieldSettings`, ``ds`` the
    :class:`~pathfuse.field.settings.DiscSettings`.  Returns ``(buf, n, code,
    steps)``.
    """
    gx = s.goal_x_m
    gy = s.goal_y_m
    k_att = s.k_att
    k_rep = s.k_rep
    rho0 = s.rho0_m
    stall_d = s.stall_distance_m
    sub_tol = s.subgoal_tolerance_m
    nexp = s.rep_exponent
    scale = s.rep_scale_m
    stall_n = s.stall_steps
    stall = s.stall_exit
    improved = s.improved
    to_goal = s.rep_to_goal
    boundary = s.boundary
    offset = s.boundary_offset_m
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
        if n + 2 > buf.shape[0]:
            buf = _grow(buf, n)
        if j == last:
            n, done = _goal_reached(buf, n, x, y, s, cm)
            if done != CODE_RUNNING:
                code = done
                break
        if steps >= max_steps:
            break
        sx = subs[j, 0]
        sy = subs[j, 1]
        fx, fy = att_force_xy(x, y, sx, sy, k_att)
        if improved:
            tx = gx if to_goal else sx
            ty = gy if to_goal else sy
            rx, ry = grid_improved_repulsion(x, y, tx, ty, cm, k_rep, rho0, nexp, scale,
                                             boundary, offset)
        else:
            rx, ry = static_repulsion(x, y, cm, k_rep, rho0, rho0, boundary, offset)
        fx += rx
        fy += ry
        dfx, dfy = _discs(x, y, fx, fy, cm, ds, dpos, dvel, drad)
        nx, ny, how = _step(x, y, fx + dfx, fy + dfy, s, cm, margin)
        if how == HOW_BLOCKED:
            code = CODE_BLOCKED
            break
        buf[n, 0] = nx
        buf[n, 1] = ny
        n += 1
        steps += 1
        x = nx
        y = ny
        if how < 0:
            code = CODE_COLLISION
            break
        if stall and n - 1 >= stall_n:
            p = n - 1 - stall_n
            if math.hypot(x - buf[p, 0], y - buf[p, 1]) < stall_d:
                code = CODE_STALLED
                break
    state[S_SUB] = j
    return buf, n, code, steps


# --------------------------------------------------------------------- fusion loop
@njit(cache=True)
def _escape_move(x, y, tx, ty, s, cm, ds, dpos, dvel, drad):
    """One escape move towards ``(tx, ty)``: ``(nx, ny, moved, reached)``.

    Without a disc in reach: a straight move of at most one step, landing
    exactly on the target (the move must be clear).  With discs in reach:
    a pull towards the target of the size of a path point ``r1`` away, plus
    the discs' repulsion, taken as a safe step; the target counts as reached
    within half a step.
    """
    step = s.step_m
    clear = cm.clear_m
    d = math.hypot(tx - x, ty - y)
    dfx = 0.0
    dfy = 0.0
    if drad is not None and drad.shape[0] > 0 and d > 0.0:
        dfx, dfy = _discs(x, y, tx - x, ty - y, cm, ds, dpos, dvel, drad)
    if drad is None or (dfx == 0.0 and dfy == 0.0):  # a static run compiles this move only
        nx, ny, landed = straight_move(x, y, tx, ty, step)
        if move_clear(cm, x, y, nx, ny, clear):
            return nx, ny, True, landed
        return x, y, False, False
    pull = s.k_att * s.r1_m / d
    fx = pull * (tx - x) + dfx
    fy = pull * (ty - y) + dfy
    nx, ny, how = safe_step_margin(x, y, fx, fy, step, cm, clear, s.margin_m)
    if how == HOW_BLOCKED and s.margin_m > 0.0:  # the margin gives way to the escape
        nx, ny, how = safe_step(x, y, fx, fy, step, cm, clear)
    if how == HOW_BLOCKED:
        return x, y, False, False
    return nx, ny, True, math.hypot(tx - nx, ty - ny) <= 0.5 * step


# Long on purpose (~190 lines): Algorithm 2 and pathfuse's escape are one state machine
# (the modes of ``state[S_MODE]``) whose transitions share a dozen locals (position,
# progress index, stall reference, escape targets); simulate() enters it once per tick,
# so split into calls every piece would pass that state in and out.  The force and the
# step already are helpers (fusion_force, _step, _escape_move, _goal_reached).
@njit(cache=True)
def fusion_loop(buf, kbuf, n, max_steps, cm, pts, cum, state, s, ds, dpos, dvel, drad,
                margin=None):
    """Algorithm 2 steps from ``buf[n-1]`` along the global path ``pts`` (M, 2).

    ``pts`` ends at the goal, ``cum`` (M,) is its cumulative arc length,
    ``kbuf`` (as long as ``buf``) receives the progress index at each walked
    point (``kbuf[0] = 0``).  ``cm`` is the :class:`~pathfuse.costmap.Costmap`,
    ``s`` the :class:`~pathfuse.field.settings.FusionSettings`, ``ds`` the
    :class:`~pathfuse.field.settings.DiscSettings`.  Returns ``(buf, kbuf, n,
    code, steps)``.

    Mode 0 is Algorithm 2: the progress index moves on
    (:func:`~pathfuse.field.pathing.advance_progress`), the goal and the path
    points ahead within ``r1`` attract, the cells within ``r2`` and the
    sensed discs repel, one safe step.

    Escape (``s.escape``): when the robot stalls or is blocked it picks a
    walked point and a path point to rejoin from
    (:func:`~pathfuse.field.pathing.find_rejoin`, with ``rvis = r1 + res``).
    Planning (``s.drive`` false) drops the walk after that point from the path
    and continues from there; driving (``s.drive``) walks back along its
    own trail to it (mode 2).  Then the robot goes straight to the chosen path
    point and follows the path points one by one until it is
    ``escape_points`` past its progress at the stall (mode 1); then
    Algorithm 2 resumes.  A blocked escape move ends the escape, and so does
    an escape held up by sensed discs for twice the stall window; a call that
    turns ``4 M + 64`` times without moving ends as blocked (every loop
    ends).
    """
    gx = s.goal_x_m
    gy = s.goal_y_m
    k_att = s.k_att
    k_rep = s.k_rep
    rho0 = s.rho0_m
    r1 = s.r1_m
    r2 = s.r2_m
    backoff_window = s.backoff_window_m
    stall_d = s.stall_distance_m
    res = cm.res_m
    clear = cm.clear_m
    stall_n = s.stall_steps
    ahead = s.ahead
    escape = s.escape
    esc_pts = s.escape_points
    drive = s.drive
    stall = s.stall_exit
    boundary = s.boundary
    offset = s.boundary_offset_m
    m = pts.shape[0]
    k = state[S_K]
    mode = state[S_MODE]
    ref = state[S_REF]
    esc_k = state[S_ESC_K]
    escapes = state[S_ESCAPES]
    t = state[S_T]
    backoff = state[S_BACKOFF]
    wb = state[S_WB]
    wi = state[S_WI]
    esteps = state[S_ESTEPS]
    x = buf[n - 1, 0]
    y = buf[n - 1, 1]
    code = CODE_RUNNING
    steps = 0
    idle = 0  # loop turns since the last move: escapes that cannot move end as blocked
    idle_cap = 4 * m + 64
    while True:
        idle += 1
        if idle > idle_cap:
            code = CODE_BLOCKED
            break
        if n + 2 > buf.shape[0]:
            buf = _grow(buf, n)
            kbuf = _grow_int(kbuf, n)
        n, done = _goal_reached(buf, n, x, y, s, cm)
        if done != CODE_RUNNING:
            code = done
            break
        if steps >= max_steps:
            break
        stalled = False
        blocked = False
        if mode == 0:
            k = advance_progress(x, y, pts, cum, k, r1, cm, clear)
            fx, fy, _ = fusion_force(x, y, gx, gy, pts, cum, k, ahead, k_att, k_rep, rho0,
                                     r1, r2, cm, boundary, offset)
            dfx, dfy = _discs(x, y, fx, fy, cm, ds, dpos, dvel, drad)
            nx, ny, how = _step(x, y, fx + dfx, fy + dfy, s, cm, margin)
            if how == HOW_BLOCKED:
                blocked = True
            else:
                buf[n, 0] = nx
                buf[n, 1] = ny
                kbuf[n] = k
                n += 1
                steps += 1
                idle = 0
                x = nx
                y = ny
                if how < 0:
                    code = CODE_COLLISION
                    break
                if stall and n - 1 - ref >= stall_n:
                    p = n - 1 - stall_n
                    ex = x - buf[p, 0]
                    ey = y - buf[p, 1]
                    stalled = ex * ex + ey * ey < stall_d * stall_d
        else:
            # escape: towards the next walked point (mode 2) or path point (mode 1)
            if mode == 2:
                tx = buf[wb, 0]
                ty = buf[wb, 1]
            else:
                tx = pts[t, 0]
                ty = pts[t, 1]
            if x == tx and y == ty:
                reached = True
            else:
                nx, ny, moved, reached = _escape_move(x, y, tx, ty, s, cm, ds, dpos, dvel,
                                                      drad)
                esteps += 1
                if not moved or (drad is not None and drad.shape[0] > 0 and esteps > 2 * stall_n):
                    mode = 0  # blocked (or held up by discs): back to Algorithm 2
                    ref = n - 1
                    continue
                buf[n, 0] = nx
                buf[n, 1] = ny
                kbuf[n] = k
                n += 1
                steps += 1
                idle = 0
                x = nx
                y = ny
            if reached:
                esteps = 0
                if mode == 2:
                    if wb <= wi:
                        mode = 1
                    else:
                        wb -= 1
                else:
                    if t > k:
                        k = t
                    if t >= esc_k or t >= m - 1:
                        mode = 0
                        ref = n - 1
                    else:
                        t += 1
        if stalled or blocked:
            ri = -1
            rj = -1
            if escape:
                if margin is not None and margin > 0.0:  # a way back keeping the margin first
                    ri, rj = find_rejoin(buf, n, pts, cum, r1 + res, backoff_window, cm,
                                         clear + margin, kbuf, drive)
                if ri < 0:
                    ri, rj = find_rejoin(buf, n, pts, cum, r1 + res, backoff_window, cm,
                                         clear, kbuf, drive)
            if ri < 0:
                code = CODE_BLOCKED if blocked else CODE_STALLED
                break
            escapes += 1
            backoff += n - 1 - ri
            if drive and ri < n - 1:
                mode = 2
                wb = n - 2
                wi = ri
            else:
                n = ri + 1
                x = buf[ri, 0]
                y = buf[ri, 1]
                mode = 1
            esteps = 0
            t = rj
            esc_k = min(max(k, rj) + esc_pts, m - 1)
            ref = n - 1
    state[S_K] = k
    state[S_MODE] = mode
    state[S_REF] = ref
    state[S_ESC_K] = esc_k
    state[S_ESCAPES] = escapes
    state[S_T] = t
    state[S_BACKOFF] = backoff
    state[S_WB] = wb
    state[S_WI] = wi
    state[S_ESTEPS] = esteps
    return buf, kbuf, n, code, steps
