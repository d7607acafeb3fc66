"""Lane escape for ``dwa`` (ours, issue 18; ``lane_escape`` of ``dwa``, diff-drive robots).

A walker that does not react walks into a robot that stands in its way; the shield's passive
safety only promises that the robot is at rest when that happens.  ``dwa`` holds each sampled
``(v, omega)`` constant over its horizon, from a window of at most ``a dt`` around the last
command: from standing, its samples move at most 0.2 m/s for 2.5 s and cannot leave a lane
that a walker sweeps, and the samples that move are charged the walker's reach while they stop
(passive safety), so standing scores best.  Replayed on the training worlds
(``examples/irsim-train``): ``dwa`` commanded v = 0 from the first tick while a walker at
1.4 m/s came from behind in its lane (``fast_from_behind``), and stood in a pair's lane in the
three-lane worlds, until walked into.

:func:`escape_command`: while a robot standing where it is would be touched by a sensed disc
(one the caller trusts: ``dwa`` leaves out those seen to wander) predicted at constant
velocity within ``lane_escape_s`` (:func:`standing_contact_s`), ``dwa``'s chosen sample is
rolled out again over that time (held, as ``dwa`` assumes, then standing where the static map
would stop it); if a disc touches it, a fan of *turn-then-go* sequences towards
:data:`ESCAPE_HEADINGS` headings (turning as fast as the limits allow while speeding up as
``cos^2`` of the heading error, or at full speed on an arc; every step inside the acceleration
window of the last) is rolled out the same way and the best one that no disc touches is
commanded (its first step, which is inside ``dwa``'s window).  The sequences are scored by
where they end against the global path (``dwa``'s path and goal critics), the least predicted
gap to every disc against ``personal_m``, the dwell critic at the end
(:func:`~pathfuse.planners.controllers.social.dwell_shortfall`) and where they come closer to
a disc than it can travel while the robot stops (the shield's passive safety would slow them
there: :data:`PASSIVE_COST`), so the side is chosen from every sensed disc's sweep at once.
While escaping (hysteresis) ``dwa``'s own choice, even untouched, must score better than the
escape, and the heading escaped towards last tick is preferred (:data:`HOLD_BONUS`).  Nothing
changes while standing would be safe or ``dwa``'s own choice is not touched; the command still
passes the safety shield.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.costmap import segment_distance
from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.controllers.dwa_checks import _path_distance, _sweep_gap, path_blocks
from pathfuse.planners.controllers.dwa_route import _local_goal, _wrap
from pathfuse.planners.controllers.social import dwell_shortfall
from pathfuse.sweep import arc_deviation_bound, unicycle_pose

__all__ = ["ESCAPE_HEADINGS", "ESCAPE_DWELL_S", "HOLD_BONUS", "standing_contact_s",
           "escape_rollout", "escape_command"]

ESCAPE_HEADINGS = 16
"""Headings of the fan, evenly spaced around the robot's (every 22.5 degrees)."""
ESCAPE_DWELL_S = 1.5
"""The dwell critic of the sequences' ends is at least this long (``dwa``'s default)."""
HOLD_BONUS = 0.5
"""Taken off the cost of the sequence towards the heading escaped towards last tick."""
CONTACT_COST = 1000.0
PASSIVE_COST = 20.0
"""Added to a sequence that, while it moves, comes closer to a disc than the disc can travel
while the robot stops (the shield would slow it there), plus 10 per metre of the shortfall."""


@njit(cache=True)
def standing_contact_s(x, y, radius, horizon_s, dpos, dvel, drad, trust):
    """The earliest time in ``[0, horizon_s]`` at which a disc predicted at constant velocity
    touches a robot of ``radius`` standing at ``(x, y)``; ``inf`` when none does.  Only the
    discs ``i`` with ``trust[i]`` count (every disc when ``trust`` is empty).

    >>> p = np.array([[3.0, 0.0]]); r = np.array([0.25]); every = np.zeros(0, np.bool_)
    >>> v = np.array([[-1.25, 0.0]])
    >>> round(standing_contact_s(0.0, 0.0, 0.25, 2.5, p, v, r, every), 6)
    2.0
    >>> standing_contact_s(0.0, 0.0, 0.25, 2.5, p, -v, r, every)   # leaving
    inf
    >>> standing_contact_s(0.0, 0.0, 0.25, 1.0, p, v, r, every)    # too late
    inf
    >>> standing_contact_s(0.0, 0.0, 0.25, 2.5, p, v, r, np.array([False]))   # not trusted
    inf
    """
    best = np.inf
    every = trust.shape[0] == 0
    for i in range(drad.shape[0]):
        if not (every or trust[i]):
            continue
        ex = dpos[i, 0] - x
        ey = dpos[i, 1] - y
        vx = dvel[i, 0]
        vy = dvel[i, 1]
        rr = radius + drad[i]
        c = ex * ex + ey * ey - rr * rr
        if c <= 0.0:
            return 0.0
        a = vx * vx + vy * vy
        b = 2.0 * (ex * vx + ey * vy)
        disc = b * b - 4.0 * a * c
        if a <= 0.0 or b >= 0.0 or disc < 0.0:
            continue
        t = (-b - math.sqrt(disc)) / (2.0 * a)
        if t <= horizon_s and t < best:
            best = t
    return best


@njit(cache=True)
def _turn_step(p0, p1, err, h, vmin, vmax, amax, wmax, alpha, arc):
    """One step of a turn-then-go sequence from the command ``(p0, p1)``: the yaw rate that
    can still stop at the heading error ``err``, the speed ``vmax cos^2(err)`` (0 beyond 90
    degrees; ``arc``: ``vmax``, turning on an arc), each moved at most one step of its
    acceleration limit."""
    want_w = math.copysign(min(wmax, math.sqrt(2.0 * alpha * abs(err))), err)
    want_w = min(want_w, abs(err) / h) if err >= 0.0 else max(want_w, -abs(err) / h)
    w = min(max(want_w, p1 - alpha * h), p1 + alpha * h)
    w = min(max(w, -wmax), wmax)
    c = math.cos(err)
    want_v = vmax * c * c if abs(err) < 0.5 * math.pi else 0.0
    if arc:
        want_v = vmax
    v = min(max(want_v, p0 - amax * h), p0 + amax * h)
    v = min(max(v, vmin), vmax)
    return v, w


@njit(cache=True)
def escape_rollout(cm, f, clear, x, y, th, c0, c1, turn, heading, hold_v, hold_w, n, pts, cum,
                   k, jg, bb, dpos, dvel, drad, dwell_s, steady, out):
    """Roll one sequence out over ``n`` steps of ``f.dt_s``: ``dwa``'s sample ``(hold_v,
    hold_w)`` held (``turn`` 0) or turn-then-go towards ``heading`` (``turn`` 1: speeding up
    as the heading comes round; 2: at full speed on an arc), the robot
    standing once the static map (``clear``) would be touched.  ``out = [cost, first contact
    time (inf: none), v, w of the first step, static stop (1: yes)]``."""
    h = f.dt_s
    radius = cm.radius_m
    slack = MARGIN_FRAC * cm.res_m
    px = x
    py = y
    pth = th
    p0 = c0
    p1 = c1
    nd = drad.shape[0]
    gmin = np.inf
    pmin = np.inf
    tc = np.inf
    stopped = False
    amax = f.max_accel_mps2
    brake = 1.0 / amax if math.isfinite(amax) and amax > 0.0 else 0.0
    out[2] = hold_v
    out[3] = hold_w
    out[4] = 0.0
    for i in range(n):
        t0 = i * h
        t1 = t0 + h
        if stopped:
            v = 0.0
            w = 0.0
        elif turn > 0:
            v, w = _turn_step(p0, p1, _wrap(heading - pth), h, f.min_speed_mps,
                              f.max_speed_mps, f.max_accel_mps2, f.max_yaw_rate_radps,
                              f.max_yaw_accel_radps2, turn == 2)
        else:
            v = hold_v
            w = hold_w
        if i == 0:
            out[2] = v
            out[3] = w
        bx, by, bth = unicycle_pose(px, py, pth, v, w, h)
        if v != 0.0:
            e = arc_deviation_bound(v, w, h)
            d = segment_distance(cm, px, py, bx, by, clear + e + 1e-9, slack) - e
            if d < clear:
                # the static map would stop it here (the shield keeps it clear): it stands
                stopped = True
                out[4] = 1.0
                if i == 0:
                    out[0] = np.inf
                    out[1] = 0.0
                    return
                bx = px
                by = py
                bth = pth
        for j in range(nd):
            g = _sweep_gap(px, py, bx, by, radius, dpos[j, 0] + dvel[j, 0] * t0,
                           dpos[j, 1] + dvel[j, 1] * t0, dpos[j, 0] + dvel[j, 0] * t1,
                           dpos[j, 1] + dvel[j, 1] * t1, drad[j])
            if g < gmin:
                gmin = g
            if v != 0.0:
                # the shield's passive safety: the gap less how far the disc can come while
                # the robot stops from this step
                gp = g - math.hypot(dvel[j, 0], dvel[j, 1]) * (h + abs(v) * brake)
                if gp < pmin:
                    pmin = gp
            if g < 0.0 and t0 < tc:
                tc = t0
        px = bx
        py = by
        pth = bth
        p0 = v
        p1 = w
    tend = n * h
    m = pts.shape[0]
    pd, s_end = _path_distance(pts, cum, k, jg, bb, px, py)
    if pd == np.inf:
        pd = math.hypot(px - pts[m - 1, 0], py - pts[m - 1, 1])
        s_end = cum[m - 1]
    cost = f.path_weight * pd + f.goal_weight * (cum[m - 1] - s_end)
    personal = f.personal_m
    if gmin < personal:
        sh = (personal - max(gmin, 0.0)) / personal
        cost += f.social_weight * sh * sh
    if dwell_s > 0.0:
        cost += f.dwell_weight * dwell_shortfall(px, py, tend, dpos, dvel, drad, radius,
                                                 dwell_s, personal, steady)
    if pmin < 0.0:
        cost += PASSIVE_COST + 10.0 * min(-pmin, 10.0)
    if tc < np.inf:
        cost += CONTACT_COST + 100.0 * (tend - tc)
    out[0] = cost
    out[1] = tc


@njit(cache=True)
def escape_command(cm, f, horizon_s, x, y, th, c0, c1, a0, a1, pts, cum, k, dpos, dvel, drad,
                   steady, trust, last_heading, hold_bonus=HOLD_BONUS):
    """The lane escape (see the module docstring) for ``dwa``'s chosen command ``(a0, a1)``:
    ``(v, w, heading)``, the first step of the best turn-then-go sequence and the heading it
    turns to, when it replaces ``(a0, a1)``; ``(a0, a1, nan)`` otherwise.  ``last_heading`` is
    the heading escaped towards last tick (nan: none); ``trust`` the discs whose contact with
    the robot standing sets the escape off (empty: every disc).  ``f`` is ``dwa``'s
    :class:`~pathfuse.planners.controllers.dwa_kernel.DwaSettings` (its dwell critic at least
    :data:`ESCAPE_DWELL_S` long); ``hold_bonus`` is taken off the cost of the sequence
    towards ``last_heading`` (``dwa``: :data:`HOLD_BONUS`)."""
    nan = math.nan
    if drad.shape[0] == 0:
        return a0, a1, nan
    radius = cm.radius_m
    if standing_contact_s(x, y, radius, horizon_s, dpos, dvel, drad, trust) == np.inf:
        return a0, a1, nan
    n = max(1, int(math.ceil(horizon_s / f.dt_s - 1e-9)))
    here = segment_distance(cm, x, y, x, y, cm.clear_m, MARGIN_FRAC * cm.res_m)
    clear = min(cm.clear_m, here * (1.0 - 1e-9))
    jg = _local_goal(pts, cum, k, f.max_speed_mps * horizon_s + f.lookahead_m + 1.0)
    bb = path_blocks(pts, k, jg)
    dwell_s = max(f.dwell_s, ESCAPE_DWELL_S)
    out = np.zeros(5)
    escape_rollout(cm, f, clear, x, y, th, c0, c1, 0, 0.0, a0, a1, n, pts, cum, k, jg, bb,
                   dpos, dvel, drad, dwell_s, steady, out)
    escaping = last_heading == last_heading
    if out[1] == np.inf and not escaping:
        return a0, a1, nan  # dwa's own choice is not touched within the horizon
    # while escaping (hysteresis), dwa's own choice must score better than the escape
    best = out[0] if out[1] == np.inf else np.inf
    bv = a0
    bw = a1
    bh = nan
    for i in range(2 * ESCAPE_HEADINGS + 2):
        ii = i // 2
        if ii < ESCAPE_HEADINGS:
            hd = _wrap(th + 2.0 * math.pi * ii / ESCAPE_HEADINGS)
        elif last_heading == last_heading:
            hd = last_heading
        else:
            break
        escape_rollout(cm, f, clear, x, y, th, c0, c1, 1 + i % 2, hd, 0.0, 0.0, n, pts, cum,
                       k, jg, bb, dpos, dvel, drad, dwell_s, steady, out)
        if out[1] < np.inf:
            continue  # touched too: not an escape
        c = out[0]
        if last_heading == last_heading and abs(_wrap(hd - last_heading)) < 1e-9:
            c -= hold_bonus
        if c < best:
            best = c
            bv = out[2]
            bw = out[3]
            bh = hd
    return bv, bw, bh
