"""The numba kernel of the Dynamic Window Approach (see :mod:`pathfuse.planners.controllers.dwa`).

:func:`dwa_choose` samples the commands reachable within one tick, rolls each
out over the horizon, scores it and returns the best; :func:`dwa_progress`
moves the robot's progress index along the global path.  The static map and
the robot's disc come as one :class:`~pathfuse.costmap.Costmap`, the
settings as one :class:`DwaSettings` (read by name, filled by
:func:`pack_dwa`), and what changes every tick (the keep critic's reference,
the route direction) as one :class:`DwaTick` (:func:`dwa_tick`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pathfuse.costmap import Discs, segment_distance
from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.controllers.dwa_bound import ADMISSIBLE, _end_cost, _probe
from pathfuse.planners.controllers.dwa_checks import (
    NearSquares,
    _path_distance,
    _segment_distance,
    _straight_pose,
    _sweep_gap,
    path_blocks,
)
from pathfuse.planners.controllers.dwa_route import _local_goal, _wrap, dwa_progress, route_tangent
from pathfuse.planners.controllers.social import EVERY_DISC, dwell_shortfall
from pathfuse.planners.params import KEEP_M, KEEP_WEIGHT
from pathfuse.shield import holonomic_stop_disc_gap, unicycle_stop_disc_gap
from pathfuse.sweep import arc_deviation_bound, unicycle_pose

__all__ = ["dwa_choose", "dwa_choose_near", "dwa_progress", "pack_dwa", "path_gap", "relaxed",
           "dwa_tick", "keep_reference", "route_tangent", "DwaSettings", "DwaTick", "KEEP_M",
           "KEEP_WEIGHT"]

SOFT = 0.3
KEEP_FLOOR = 0.02
"""The keep critic's shortfall is relative to the path's gap, but to at least this (m)."""
PASSIVE_COST = 20.0


class DwaSettings(NamedTuple):
    """The settings of :func:`dwa_choose`, read by name (one argument), from
    :func:`pack_dwa`.  The map, the robot's radius and the clearance it keeps are the
    :class:`~pathfuse.costmap.Costmap`'s."""

    dt_s: float
    min_speed_mps: float
    max_speed_mps: float
    max_accel_mps2: float
    max_yaw_rate_radps: float
    max_yaw_accel_radps2: float
    margin_m: float
    horizon_s: float
    sim_step_s: float
    v_samples: int
    w_samples: int
    path_weight: float
    goal_weight: float
    heading_weight: float
    speed_weight: float
    obstacle_weight: float
    moving_weight: float
    obstacle_range_m: float
    lookahead_m: float
    inflation_decay_m: float
    holonomic: bool
    passive: bool
    path_align_weight: float
    keep_horizon_s: float
    keep_weight: float
    keep_m: float
    social_weight: float
    personal_m: float
    side_weight: float
    dwell_s: float
    dwell_weight: float
    inside_clear: bool


class DwaTick(NamedTuple):
    """What :func:`dwa_choose` reads that changes every tick (:func:`dwa_tick`)."""

    keep_ref_m: float
    """The keep critic's reference gap (``inf`` when the critic is off)."""
    route_x: float
    route_y: float
    """The route direction against which passing sides are told (``(0, 0)``: the path's)."""
    steady: np.ndarray = EVERY_DISC
    """The dwell critic's mask of the sensed discs it counts (empty: every disc;
    :class:`~pathfuse.planners.controllers.social.SteadyDiscs`)."""


def pack_dwa(dt, vmin, vmax, amax, wmax, alpha, margin, horizon, sim_dt, n_v, n_w, w_path,
             w_goal, w_head, w_speed, w_obs, w_dyn, obstacle_range, lookahead, decay,
             holonomic, passive=True, w_align=0.0, near_s=0.0, w_keep=0.0, keep_m=0.3,
             w_social=0.0, personal_m=0.5, w_side=0.0, dwell_s=0.0, w_dwell=0.0,
             inside_clear=False):
    """The settings of :func:`dwa_choose`.

    With a safety margin (``margin > 0``) the passing-side critic is off: holding a side
    pressed the robot against a wall in ``examples/scenarios/corridor_oncoming.yaml``
    (``tests/test_clearance.py``), which a margin forbids.

    Examples
    --------
    >>> s = pack_dwa(0.1, 0.0, 1.0, 2.0, 2.0, 4.0, 0.0, 2.0, 0.1, 7, 9, 1.0, 1.0, 0.5,
    ...              0.2, 1.0, 1.0, 1.0, 1.0, 0.1, False)
    >>> s.max_speed_mps, s.v_samples, s.holonomic, relaxed(s).obstacle_weight
    (1.0, 7, False, 0.0)
    """
    if margin > 0.0:
        w_side = 0.0
    return DwaSettings(
        float(dt), float(vmin), float(vmax), float(amax), float(wmax), float(alpha),
        float(margin), float(horizon), float(sim_dt), int(float(n_v)), int(float(n_w)),
        float(w_path), float(w_goal), float(w_head), float(w_speed), float(w_obs),
        float(w_dyn), float(obstacle_range), float(lookahead), float(decay), bool(holonomic),
        bool(passive), float(w_align), float(near_s), float(w_keep), float(keep_m),
        float(w_social), float(personal_m), float(w_side), float(dwell_s), float(w_dwell),
        bool(inside_clear))


def relaxed(s):
    """The settings ``s`` without the obstacle and keep critics and the margin (the
    recovery behaviour that clears them, :mod:`pathfuse.planners.recovery`)."""
    return s._replace(obstacle_weight=0.0, margin_m=0.0, keep_weight=0.0)


def keep_reference(cm, s, pts, cum, k):
    """The keep critic's reference for this tick: the gap the path ``pts`` keeps from its
    point ``k`` over what the robot travels in ``keep_horizon_s`` at full speed (at least
    0.5 m); ``inf`` when the critic is off."""
    if s.keep_weight > 0.0:
        return float(path_gap(cm, s, pts, cum, k, max(s.max_speed_mps * s.keep_horizon_s,
                                                      0.5)))
    return math.inf


def dwa_tick(cm, s, pts, cum, k, route, steady=EVERY_DISC):
    """The :class:`DwaTick` of this tick: the keep reference along ``pts`` from ``k``
    (:func:`keep_reference`), the route direction ``route`` and the dwell critic's mask."""
    return DwaTick(keep_reference(cm, s, pts, cum, k), float(route[0]), float(route[1]),
                   steady)


@njit(cache=True)
def path_gap(cm, s, pts, cum, k, length):
    """The least gap (distance less the robot's radius) of the path from ``pts[k]`` over
    ``length`` metres, up to ``keep_m`` (the reference of the keep critic)."""
    m = pts.shape[0]
    radius = cm.radius_m
    cap = radius + s.keep_m + 1e-9
    slack = MARGIN_FRAC * cm.res_m
    best = cap
    j = k
    while j + 1 < m and cum[j] - cum[k] <= length:
        d = segment_distance(cm, pts[j, 0], pts[j, 1], pts[j + 1, 0], pts[j + 1, 1], cap,
                             slack)
        if d < best:
            best = d
        j += 1
    return best - radius


# Long on purpose (~190 lines): one sampled command's rollout and all its critics in one
# pass over the rollout's pieces, which share the piece's pose, static distance and disc
# gaps (and the admissibility that ends the rollout early); split per critic, every piece
# would be computed again for each of the v_samples x w_samples commands per tick.  The
# geometry is in helpers (dwa_checks, _path_distance, dwell_shortfall).
@njit(cache=True)
def _rollout(cm, nsq, f, clear, gref, x, y, th, v, w, pts, cum, k, jg, bb, dpos, dvel, drad,
             out, tx, ty, dside, sides, reach, steady):
    """Score one sample: ``out = [cost, admissible, first_tick_clear]``; ``sides[j] = (side,
    least predicted gap)`` of the sample against sensed disc ``j`` (the social critics,
    :mod:`pathfuse.planners.controllers.social`; ``(tx, ty)`` the route's direction);
    ``reach`` is scratch space of one float per disc (allocated once per tick); ``bb`` the
    path's segment blocks ``k .. jg`` (:func:`path_blocks`, once per tick); ``nsq`` the
    squares near each lattice cell (:func:`.dwa_checks.near_squares`, or none)."""
    res = cm.res_m
    dt = f.dt_s
    radius = cm.radius_m
    # the edge rule of segment_is_clear: pathfuse's margin is kept from squares, not the edge
    slack = MARGIN_FRAC * res
    horizon = f.horizon_s
    h = f.sim_step_s
    rng = f.obstacle_range_m
    n = max(1, int(math.ceil(horizon / h - 1e-9)))
    e = arc_deviation_bound(v, w, h)
    cap = clear + rng + e
    dmin = cap
    speed = abs(v)
    amax = f.max_accel_mps2
    brake = 0.0
    if math.isfinite(amax) and amax > 0.0:
        brake = speed * speed / (2.0 * amax)
    need = speed * dt + brake  # travel before the robot could stand still
    ax = x
    ay = y
    ok = True
    first_ok = True
    travelled = 0.0
    n_disc = drad.shape[0]
    dyn = 0.0
    stop_s = dt + (speed / amax if math.isfinite(amax) and amax > 0.0 else 0.0)
    if not f.passive:
        stop_s = 0.0
    for j in range(n_disc):
        reach[j] = math.hypot(dvel[j, 0], dvel[j, 1]) * stop_s
    gmin = np.inf
    dmaxr = 0.0
    for j in range(n_disc):
        sides[j, 0] = 0.0
        sides[j, 1] = np.inf
    near = f.keep_horizon_s
    dnear = cap
    # the path-align critic holds the robot to the global path: not while a moving disc is
    # sensed (the path may be what it crosses; the global path is replanned around it)
    walign = f.path_align_weight if n_disc == 0 else 0.0
    align = 0.0
    n_align = 0
    tc = np.inf
    ex = x
    ey = y
    eth = th
    tend = 0.0
    straight = w == 0.0  # (every holonomic sample) its pose's angle is the same at every t
    cmid = math.cos(th + 0.5 * (w * h))
    smid = math.sin(th + 0.5 * (w * h))
    for i in range(1, n + 1):
        t = min(i * h, horizon)
        if straight:
            bx, by, bth = _straight_pose(x, y, th, v, w, t, cmid, smid)
        else:
            bx, by, bth = unicycle_pose(x, y, th, v, w, t)
        # the search stops at the least distance that could still change something (the
        # clearance, the least gap so far, the keep critic's): a square farther than that
        # changes nothing, and a nearer one is found at the same distance, bit for bit
        lo = max(clear, dmin, dnear if t <= near + 1e-12 else clear) + e
        d = _segment_distance(cm, ax, ay, bx, by, min(cap, lo + 1e-12 * (1.0 + lo)),
                              slack, nsq) - e
        if t <= dt + 1e-12:
            # the tick itself: the arc (lower bound) and the chord (the path offline) clear
            if d < clear:
                first_ok = False
                ok = False
                break
            if e > 0.0 and _segment_distance(cm, ax, ay, bx, by, clear, slack, nsq) < clear:
                first_ok = False
                ok = False
                break
        if d < clear:
            if travelled < need:
                ok = False  # it could not stop before this collision
            if t <= near + 1e-12 and d < dnear:
                dnear = d
            break
        if d < dmin:
            dmin = d
        if t <= near + 1e-12 and d < dnear:
            dnear = d
        if walign > 0.0:
            pdi, _ = _path_distance(pts, cum, k, jg, bb, bx, by)
            if pdi < np.inf:
                align += pdi
                n_align += 1
        t0 = t - h if t - h > 0.0 else 0.0
        for j in range(n_disc):
            qax = dpos[j, 0] + dvel[j, 0] * t0
            qay = dpos[j, 1] + dvel[j, 1] * t0
            qbx = dpos[j, 0] + dvel[j, 0] * t
            qby = dpos[j, 1] + dvel[j, 1] * t
            # less how far the disc can come while the robot stops from here (so a pass
            # that the shield's passive-safety test would refuse counts as a collision)
            g0 = _sweep_gap(ax, ay, bx, by, radius, qax, qay, qbx, qby, drad[j]) - e
            if g0 < sides[j, 1]:
                # the side of the route the disc is on at the closest approach so far
                mx = 0.5 * (qax + qbx) - 0.5 * (ax + bx)
                my = 0.5 * (qay + qby) - 0.5 * (ay + by)
                # (the disc's signed offset from the robot across the route; a pass only
                # where the two are side by side, not one behind the other)
                cr = tx * my - ty * mx
                beside = radius + drad[j]
                sides[j, 0] = 1.0 if cr > beside else (-1.0 if cr < -beside else 0.0)
                sides[j, 1] = g0
            g = g0 - reach[j]
            if g < gmin:
                gmin = g
                dmaxr = drad[j]
            if g < 0.0 and t0 < tc:
                tc = t0
        travelled += abs(v) * (t - (i - 1) * h)
        ax = bx
        ay = by
        ex = bx
        ey = by
        eth = bth
        tend = t
    out[1] = 1.0 if ok else 0.0
    out[2] = 1.0 if first_ok else 0.0
    if not ok:
        out[0] = np.inf
        return
    if n_disc > 0:
        if tc <= dt:
            out[1] = 0.0  # a predicted collision within this tick
            out[0] = np.inf
            return
        if tc < np.inf:
            # how deep the predicted overlap gets (so a swerve that shrinks it beats
            # standing in the disc's way), and how soon it starts
            dyn = 1.5 + 2.0 * min(-gmin / (radius + dmaxr), 1.0) + 0.5 * (horizon - tc) / horizon
        elif gmin < np.inf:
            dyn = SOFT * math.exp(-max(gmin, 0.0) / 0.2)
    soc = 0.0
    side_cost = 0.0
    personal = f.personal_m
    if n_disc > 0 and (f.social_weight > 0.0 or f.side_weight > 0.0):
        # ours (pathfuse.planners.controllers.social): personal space over the predicted
        # gaps, and the committed passing sides
        for j in range(n_disc):
            gj = sides[j, 1]
            if gj < personal:
                sh = (personal - max(gj, 0.0)) / personal
                if sh * sh > soc:
                    soc = sh * sh
            if dside[j] != 0.0 and sides[j, 0] != 0.0 and sides[j, 0] != dside[j] \
                    and gj < personal + 1.0:
                side_cost = 1.0
    dwc = 0.0
    if n_disc > 0 and f.dwell_s > 0.0 and f.dwell_weight > 0.0:
        # ours (the dwell critic): the robot may have to stand where the rollout ends
        dwc = f.dwell_weight * dwell_shortfall(ex, ey, tend, dpos, dvel, drad, radius,
                                               f.dwell_s, personal, steady)
    gap = dmin - radius
    obs = math.exp(-max(gap, 0.0) / f.inflation_decay_m) if dmin < cap else 0.0
    margin = f.margin_m
    if margin > 0.0 and gap < margin:
        obs += 10.0 * (margin - gap) / margin
    # the end point's critics first (dwa_bound._end_cost: the bound the pruning uses), then
    # the others in this order: every term added after it must be non-negative, and the
    # admissibility and end pose above are dwa_bound._probe's (_choose's pruning relies on
    # both; tests/test_dwa_prune.py)
    out[0] = (_end_cost(f, pts, cum, k, jg, bb, x, y, th, v, ex, ey, eth)
              + f.obstacle_weight * obs + f.moving_weight * dyn
              + f.social_weight * soc + f.side_weight * side_cost + dwc)
    if n_align > 0:
        out[0] += walign * align / n_align
    wkeep = f.keep_weight if n_disc == 0 else 0.0
    if wkeep > 0.0:
        # ours: keep the gap the global path keeps ahead (up to keep_m): the shortfall of
        # the least gap over the first obstacle_horizon_s, squared, relative to keep_m; a
        # sample that keeps as much as the path pays nothing, so standing in front of a
        # narrowing the path goes through is not cheaper than going through
        want = min(gref, f.keep_m)
        short = want - (dnear - radius)
        if short > 0.0 and want > 0.0:
            out[0] += wkeep * min((short / max(want, KEEP_FLOOR)) ** 2, 1.0)


@njit(cache=True, inline="always")
def _passive_penalty(gap):
    """The cost of a sample whose tick and stop come closer to a sensed disc than it can
    reach at its present speed (the safety shield's passive-safety test,
    :mod:`pathfuse.shield`): chosen only when every sample does, the one with the largest
    gap first."""
    if gap >= 0.0:
        return 0.0
    return PASSIVE_COST + 10.0 * min(-gap, 10.0)


@njit(cache=True)
def dwa_choose(cm, f, tick, x, y, th, c0, c1, pts, cum, k, dpos, dvel, drad, dside, chosen):
    """:func:`dwa_choose_near` without the near squares' lists (the same choice, with a
    search of the squares wherever the lattice cannot rule them out)."""
    none = NearSquares(np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), 0.0,
                       np.zeros(0))
    return dwa_choose_near(cm, none, f, tick, x, y, th, c0, c1, pts, cum, k, dpos, dvel, drad,
                           dside, chosen)


@njit(cache=True)
def dwa_choose_near(cm, near, f, tick, x, y, th, c0, c1, pts, cum, k, dpos, dvel, drad, dside,
                    chosen):
    """The best command from the dynamic window.

    ``dside`` holds the committed passing side of each sensed disc (+1, -1, 0: none) and
    ``chosen`` receives the best sample's ``(side, predicted gap)`` against each
    (:mod:`pathfuse.planners.controllers.social`); the side is told against the route direction
    ``tick.route_x, tick.route_y`` (:func:`dwa_tick`), or the path's at ``k`` when that is
    zero.  ``cm`` is the static map with the robot's radius and clearance, ``f`` the
    :class:`DwaSettings`, ``near`` the squares near each cell of ``cm``'s lattice
    (:func:`~pathfuse.planners.controllers.dwa_checks.near_squares`: the same choice as
    without them, found faster).

    ``(c0, c1)`` is the last command: ``(v, omega)`` for a diff-drive robot,
    ``(vx, vy)`` for a holonomic one.  Returns ``(a0, a1, admissible_count,
    cost)`` with ``(a0, a1)`` in the same terms; with no admissible sample, the
    slowest command of the window turning towards the local goal.  With a
    safety margin the samples are first held to keeping ``clear + min(margin,
    max(present gap, margin / 2))`` (admissibility as above with that
    clearance; a robot already deeper inside gets none passing); only when
    none passes, to ``clear``.
    """
    margin = f.margin_m
    clear = cm.clear_m
    if margin > 0.0:
        d = segment_distance(cm, x, y, x, y, clear + margin, MARGIN_FRAC * cm.res_m)
        # keep the margin, or at least half of it where the robot still has that much
        hi = clear + min(margin, max(d - clear, 0.5 * margin)) * (1.0 - 1e-9)
        if hi > clear:
            a0, a1, count, best = _choose(cm, near, f, hi, tick, x, y, th, c0, c1, pts, cum, k,
                                          dpos, dvel, drad, dside, chosen)
            if count > 0:
                return a0, a1, count, best
    a0, a1, count, best = _choose(cm, near, f, clear, tick, x, y, th, c0, c1, pts, cum, k,
                                  dpos, dvel, drad, dside, chosen)
    if count == 0 and f.inside_clear:
        # ours: a robot already inside its own clearance (IR-SIM's Euler step or a push put
        # it there) finds no sample keeping ``clear``; the samples that keep the gap it has
        # (moving along the obstacle or away from it) are admissible instead
        d = segment_distance(cm, x, y, x, y, clear, MARGIN_FRAC * cm.res_m)
        if d < clear:
            a0, a1, count, best = _choose(cm, near, f, d * (1.0 - 1e-9), tick, x, y, th, c0,
                                          c1, pts, cum, k, dpos, dvel, drad, dside, chosen)
    return a0, a1, count, best


@njit(cache=True)
def _choose(cm, near, f, clear, tick, x, y, th, c0, c1, pts, cum, k, dpos, dvel, drad, dside,
            chosen):
    dt = f.dt_s
    vmax = f.max_speed_mps
    amax = f.max_accel_mps2
    nv = f.v_samples
    nw = f.w_samples
    jg = _local_goal(pts, cum, k, f.max_speed_mps * f.horizon_s + f.lookahead_m + 1.0)
    bb = path_blocks(pts, k, jg)
    out = np.zeros(3)
    best = np.inf
    b0 = 0.0
    b1 = 0.0
    count = 0
    n_disc = drad.shape[0] if f.passive else 0
    dspeed = np.empty(n_disc)
    for j in range(n_disc):
        dspeed[j] = math.hypot(dvel[j, 0], dvel[j, 1])
    discs = Discs(dpos, dvel, dspeed, drad)
    nd = drad.shape[0]
    sides = np.zeros((nd, 2))
    reach = np.empty(nd)  # _rollout's scratch (one allocation per tick, not per sample)
    for j in range(nd):
        chosen[j, 0] = 0.0
        chosen[j, 1] = np.inf
    tx = tick.route_x
    ty = tick.route_y
    if tx == 0.0 and ty == 0.0:
        tx, ty = route_tangent(pts, k, th)
    holo = f.holonomic
    lim = amax * dt
    # the samples, in the order of their ties: the command (s0, s1) and what the rollout
    # holds (heading sh, speed sv, yaw rate sw)
    if holo:
        # velocity vectors: speeds x directions (3 w_samples of them, every 8 degrees by
        # default), within |u - u0| <= a dt
        ndir = 3 * nw
        ns = 1 + (nv - 1) * ndir
    else:
        ns = nv * (nw + 1)
        vlo = max(f.min_speed_mps, c0 - amax * dt)
        vhi = min(vmax, c0 + amax * dt)
        wlo = max(-f.max_yaw_rate_radps, c1 - f.max_yaw_accel_radps2 * dt)
        whi = min(f.max_yaw_rate_radps, c1 + f.max_yaw_accel_radps2 * dt)
    s0 = np.empty(ns)
    s1 = np.empty(ns)
    sh = np.full(ns, th)
    sv = np.empty(ns)
    sw = np.zeros(ns)
    q = 0
    if holo:
        for i in range(nv):
            s = vmax * i / (nv - 1)
            for j in range(ndir if i > 0 else 1):
                a = 2.0 * math.pi * j / ndir
                ux = s * math.cos(a)
                uy = s * math.sin(a)
                if math.isfinite(lim):
                    dx = ux - c0
                    dy = uy - c1
                    dn = math.hypot(dx, dy)
                    if dn > lim:  # onto the window's edge (a hair inside: no clipping)
                        ux = c0 + dx * (lim / dn) * (1.0 - 1e-12)
                        uy = c1 + dy * (lim / dn) * (1.0 - 1e-12)
                        sn = math.hypot(ux, uy)
                        if sn > vmax:
                            ux *= vmax / sn * (1.0 - 1e-12)
                            uy *= vmax / sn * (1.0 - 1e-12)
                sp = math.hypot(ux, uy)
                s0[q] = ux
                s1[q] = uy
                sv[q] = sp
                sh[q] = math.atan2(uy, ux) if sp > 0.0 else th
                q += 1
    else:
        for i in range(nv):
            # exactly on the window's edges (the world clips anything beyond them)
            v = vhi if i == nv - 1 else min(max(vlo + (vhi - vlo) * (i / (nv - 1)), vlo), vhi)
            for j in range(nw + 1):
                if j < nw:
                    w = whi if j == nw - 1 else min(max(wlo + (whi - wlo) * (j / (nw - 1)),
                                                        wlo), whi)
                else:
                    w = min(max(0.0, wlo), whi)  # always try going straight
                s0[q] = v
                s1[q] = w
                sv[q] = v
                sw[q] = w
                q += 1
    # exact pruning (dwa_bound): every sample's admissibility and the least its cost can be
    # (its end point's critics) first; then the admissible ones rolled out in that bound's
    # order while it can still beat (or tie with an earlier sample) the best so far.  The
    # least cost wins, the first sample of the order above among equal costs.
    lb = np.empty(ns)
    for q in range(ns):
        state, lb[q] = _probe(cm, near, f, clear, x, y, sh[q], sv[q], sw[q], pts, cum, k, jg,
                              bb, dpos, dvel, drad, reach)
        if state == ADMISSIBLE:
            count += 1
    order = np.argsort(lb)
    bq = ns
    for r in range(ns):
        q = order[r]
        if not (lb[q] <= best and lb[q] < np.inf):
            break  # (the inadmissible samples' bound is inf: last)
        if lb[q] == best and q > bq:
            continue
        _rollout(cm, near, f, clear, tick.keep_ref_m, x, y, sh[q], sv[q], sw[q], pts, cum, k,
                 jg, bb, dpos, dvel, drad, out, tx, ty, dside, sides, reach, tick.steady)
        if out[1] == 1.0 and n_disc > 0:
            if holo:
                out[0] += _passive_penalty(holonomic_stop_disc_gap(
                    x, y, s0[q], s1[q], dt, amax, cm.radius_m, discs))
            else:
                out[0] += _passive_penalty(unicycle_stop_disc_gap(
                    x, y, th, s0[q], s1[q], dt, amax, f.max_yaw_accel_radps2, cm.radius_m,
                    discs))
        if out[1] == 1.0:
            c = out[0]
            if c < best or (c == best and c < np.inf and q < bq):
                best = c
                bq = q
                b0 = s0[q]
                b1 = s1[q]
                chosen[:, :] = sides
    if holo:
        if count == 0:  # nothing admissible: slow down as hard as the window allows
            sc = 0.0
            if math.isfinite(lim):
                sc = max(0.0, 1.0 - lim / max(math.hypot(c0, c1), 1e-300))
            return c0 * sc, c1 * sc, 0, np.inf
        return b0, b1, count, best
    if count == 0:
        # nothing admissible: as slow as possible, turning towards the local goal
        err = _wrap(math.atan2(pts[jg, 1] - y, pts[jg, 0] - x) - th)
        w = min(max(err / dt, wlo), whi)
        return vlo, w, 0, np.inf
    return b0, b1, count, best
