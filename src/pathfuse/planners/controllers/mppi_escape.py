"""Lane escape for MPPI's control sequences (ours, issue 18; ``lane_escape`` of ``mppi`` and
of the fusion among discs).

A walker that does not react walks into a robot that stands in its way; the shield's passive
safety only promises that the robot is at rest when that happens.  MPPI samples its
sequences around the last optimum: a robot that has slowed in front of people coming at it
samples around standing, and when every such sample meets a walker within the horizon the
weighted mean stays near standing, though standing is a sure contact.  Replayed, ``mppi``
stood 2.5 s in front of a pair of walkers coming head-on in a 4.5 m corridor with 1.5 m free
on either side, until they walked into it (``examples/irsim-train/west_three_lanes_wide``,
seed 1).

:func:`escape_sequence`: while the robot standing where it is would be reached by a sensed
disc predicted at constant velocity within the horizon, a fan of deterministic sequences
(turn towards a heading as fast as the limits allow, then drive at full speed) is scored
with MPPI's own critics and the dwell critic, and the best replaces the optimum when it
scores better.  So a move
that gets out of a walker's lane in time always competes, and wins whenever the critics find
it better; nothing changes while standing would be safe.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.costmap import segment_distance
from pathfuse.planners.controllers.mppi_kernel import _clip_holo, _score, _turn_to, _wrap
from pathfuse.sweep import unicycle_pose

__all__ = ["ESCAPE_DWELL_S", "ESCAPE_HEADINGS", "standing_hit", "escape_sequence"]

ESCAPE_HEADINGS = 12
"""Headings of the fan, evenly spaced around the robot's (every 30 degrees)."""
ESCAPE_DWELL_S = 1.5
"""The escape and the optimum it competes with are scored with the dwell critic
(:func:`~pathfuse.planners.controllers.social.dwell_shortfall`) of at least this length (the
fusion's and ``dwa``'s default), also where the planner's own is off (``mppi``): without it
an escape that is clear over the horizon but ends in another walker's lane wins (replayed:
``mppi`` fled diagonally up a crossing stream, ``crossing_stream`` seed 1, and was caught)."""


@njit(cache=True)
def standing_hit(x, y, radius, horizon_s, dpos, dvel, drad):
    """True when a disc predicted at constant velocity comes within the radii of a robot
    standing at ``(x, y)`` within ``horizon_s``.

    >>> p = np.array([[3.0, 0.0]]); r = np.array([0.25])
    >>> bool(standing_hit(0.0, 0.0, 0.25, 2.5, p, np.array([[-1.5, 0.0]]), r))   # coming
    True
    >>> bool(standing_hit(0.0, 0.0, 0.25, 2.5, p, np.array([[1.5, 0.0]]), r))    # leaving
    False
    """
    for i in range(drad.shape[0]):
        ex = x - dpos[i, 0]
        ey = y - dpos[i, 1]
        vx = dvel[i, 0]
        vy = dvel[i, 1]
        v2 = vx * vx + vy * vy
        u = 0.0
        if v2 > 0.0:
            u = min(horizon_s, max(0.0, (ex * vx + ey * vy) / v2))
        if math.hypot(ex - u * vx, ey - u * vy) < radius + drad[i]:
            return True
    return False


@njit(cache=True)
def _towards(seq, f, x, y, th, c0, c1, heading):
    """Turn towards ``heading`` as fast as the heading can still stop, the speed the limit
    times cos^2 of the heading error (0 beyond 90 degrees); holonomic: straight at it."""
    px = x
    py = y
    pth = th
    p0 = c0
    p1 = c1
    alpha = f.max_yaw_accel_radps2
    vmax = f.max_speed_mps
    for t in range(seq.shape[0]):
        h = f.dt_s if t == 0 else f.model_dt_s
        if f.holonomic:
            a, b = _clip_holo(p0, p1, vmax * math.cos(heading), vmax * math.sin(heading), h, f)
        else:
            a, b = _turn_to(p0, p1, _wrap(heading - pth), vmax, h, alpha, f)
            px, py, pth = unicycle_pose(px, py, pth, a, b, h)
        seq[t, 0] = a
        seq[t, 1] = b
        p0 = a
        p1 = b


@njit(cache=True)
def escape_sequence(cm, f, x, y, th, c0, c1, nominal, pts, cum, pexp, k0, goal_mode,
                    dpos, dvel, drad, dsteady):
    """Replace ``nominal`` by the best of the fan of escape sequences when a robot standing
    here would be reached by a disc within the horizon and that sequence scores lower (both
    scored with the settings ``f``, which carry the dwell critic: see
    :data:`ESCAPE_DWELL_S`); True when it did."""
    n = nominal.shape[0]
    if drad.shape[0] == 0:
        return False
    horizon = f.dt_s + (n - 1) * f.model_dt_s
    if not standing_hit(x, y, cm.radius_m, horizon, dpos, dvel, drad):
        return False
    here = segment_distance(cm, x, y, x, y, cm.radius_m)
    thr = min(cm.radius_m, here * (1.0 - 1e-9))
    seq = np.empty((n, 2))
    best = np.empty((n, 2))
    found = False
    bc, _ = _score(nominal, cm, f, thr, x, y, th, c0, c1, pts, cum, pexp, k0, goal_mode,
                   dpos, dvel, drad, dsteady)
    for i in range(ESCAPE_HEADINGS):
        _towards(seq, f, x, y, th, c0, c1, th + 2.0 * math.pi * i / ESCAPE_HEADINGS)
        c, _ = _score(seq, cm, f, thr, x, y, th, c0, c1, pts, cum, pexp, k0, goal_mode,
                      dpos, dvel, drad, dsteady)
        if c < bc:
            bc = c
            best[:, :] = seq
            found = True
    if found:
        nominal[:, :] = best
    return found
