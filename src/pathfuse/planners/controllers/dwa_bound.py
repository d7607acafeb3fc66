"""The dwa kernel's exact pruning of samples (:mod:`pathfuse.planners.controllers.dwa_kernel`).

A sample whose every rollout piece the costmap's clearance lattice puts beyond the
clearance (with room to spare) runs to the horizon and is admissible but for a sensed
disc within the tick; its cost is then at least the end point's critics
(:func:`_end_cost`: path distance, goal distance, heading and speed), because every other
critic adds a non-negative term after them, and floating-point addition is monotone.
:func:`_clear_bound` finds that state and bound with the pose and the lattice alone (no
search of the squares, no path-align distance per piece), so the kernel's ``_choose``
rolls out such samples fully in increasing bound order only while the bound can still
beat, or tie with an earlier sample, the best so far: the same choice, cost, admissible
count and passing sides, bit for bit (``tests/test_dwa_exact.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.controllers.dwa_checks import (
    _field_bound,
    _path_distance,
    _straight_pose,
    _sweep_gap,
)
from pathfuse.planners.controllers.dwa_route import _wrap
from pathfuse.sweep import arc_deviation_bound, edge_distance, unicycle_pose

__all__ = ["CLEAR", "INADMISSIBLE", "UNKNOWN", "_clear_bound", "_end_cost"]

UNKNOWN = -1
""":func:`_clear_bound`: the lattice cannot tell (the sample is rolled out)."""
INADMISSIBLE = 0
""":func:`_clear_bound`: clear of the map, but a sensed disc is hit within the tick."""
CLEAR = 1
""":func:`_clear_bound`: admissible, rolled out to the horizon; the bound holds."""


@njit(cache=True, inline="always")
def _end_cost(f, pts, cum, k, jg, bb, x, y, th, v, ex, ey, eth):
    """The first four critics of a rollout from ``(x, y, th)`` at speed ``v`` ending at
    ``(ex, ey, eth)``: path distance, goal distance, heading and speed, summed in the
    kernel's order (the kernel adds the others to this sum)."""
    m = pts.shape[0]
    speed = abs(v)
    # the end point against the path near the progress index: its distance to the path and
    # how much path is left beyond its projection
    pd, s_end = _path_distance(pts, cum, k, jg, bb, ex, ey)
    if pd == np.inf:
        pd = math.hypot(ex - pts[m - 1, 0], ey - pts[m - 1, 1])
        s_end = cum[m - 1]
    left = cum[m - 1] - s_end
    # the carrot: lookahead_m of path beyond the projection
    sc = min(s_end + f.lookahead_m, cum[m - 1])
    j = k
    while j + 1 < m - 1 and cum[j + 1] < sc:
        j += 1
    seg = cum[j + 1] - cum[j] if j + 1 < m else 0.0
    u = (sc - cum[j]) / seg if seg > 0.0 else 0.0
    u = min(max(u, 0.0), 1.0)
    gx = pts[j, 0] + u * (pts[min(j + 1, m - 1), 0] - pts[j, 0])
    gy = pts[j, 1] + u * (pts[min(j + 1, m - 1), 1] - pts[j, 1])
    gd = math.hypot(gx - ex, gy - ey)
    if f.holonomic:
        hd = math.atan2(gy - y, gx - x)
        he = abs(_wrap(hd - th)) / math.pi if speed > 0.0 else 0.5
    else:
        he = abs(_wrap(math.atan2(gy - ey, gx - ex) - eth)) / math.pi if gd > 1e-9 else 0.0
    return (f.path_weight * pd + f.goal_weight * left + f.heading_weight * he
            + f.speed_weight * (f.max_speed_mps - v) / f.max_speed_mps)


@njit(cache=True)
def _clear_bound(cm, f, clear, x, y, th, v, w, pts, cum, k, jg, bb, dpos, dvel, drad, reach):
    """The state of one sample (:data:`CLEAR`, :data:`INADMISSIBLE` or :data:`UNKNOWN`) and,
    when :data:`CLEAR`, a lower bound of its cost (:func:`_end_cost` at the horizon's pose).

    :data:`CLEAR` needs every piece's chord (the same poses as ``_rollout``'s) beyond
    ``clear`` plus the arc's deviation plus 1e-6 m by the clearance lattice and the map's
    edge: then no piece of the rollout can come below ``clear`` (its static distance,
    searched under any cap at least that, is at least that), so it runs to the horizon and
    only a sensed disc closer than it can come while the robot stops, on a piece starting
    within the tick, makes it inadmissible (as in ``_rollout``).  ``reach`` is scratch
    space of one float per disc."""
    res = cm.res_m
    dt = f.dt_s
    radius = cm.radius_m
    slack = MARGIN_FRAC * res
    horizon = f.horizon_s
    h = f.sim_step_s
    n = max(1, int(math.ceil(horizon / h - 1e-9)))
    e = arc_deviation_bound(v, w, h)
    cc = clear + e
    capc = cc + 1e-6 * (1.0 + cc)
    tol = capc + 1e-9 * (1.0 + capc)
    hh, ww = cm.occ.shape
    xmax = cm.ox_m + ww * res
    ymax = cm.oy_m + hh * res
    speed = abs(v)
    amax = f.max_accel_mps2
    n_disc = drad.shape[0]
    stop_s = dt + (speed / amax if math.isfinite(amax) and amax > 0.0 else 0.0)
    if not f.passive:
        stop_s = 0.0
    for j in range(n_disc):
        reach[j] = math.hypot(dvel[j, 0], dvel[j, 1]) * stop_s
    hit = False
    straight = w == 0.0
    cmid = math.cos(th + 0.5 * (w * h))
    smid = math.sin(th + 0.5 * (w * h))
    ax = x
    ay = y
    bx = x
    by = y
    bth = th
    for i in range(1, n + 1):
        t = min(i * h, horizon)
        if straight:
            bx, by, bth = _straight_pose(x, y, th, v, w, t, cmid, smid)
        else:
            bx, by, bth = unicycle_pose(x, y, th, v, w, t)
        half = 0.5 * math.sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
        if not (_field_bound(cm, 0.5 * (ax + bx), 0.5 * (ay + by)) - half > tol):
            return UNKNOWN, 0.0
        if edge_distance(cm.ox_m, cm.oy_m, xmax, ymax, ax, ay, bx, by, capc, slack) < capc:
            return UNKNOWN, 0.0
        t0 = t - h if t - h > 0.0 else 0.0
        if t0 <= dt:
            for j in range(n_disc):
                qax = dpos[j, 0] + dvel[j, 0] * t0
                qay = dpos[j, 1] + dvel[j, 1] * t0
                qbx = dpos[j, 0] + dvel[j, 0] * t
                qby = dpos[j, 1] + dvel[j, 1] * t
                g0 = _sweep_gap(ax, ay, bx, by, radius, qax, qay, qbx, qby, drad[j]) - e
                if g0 - reach[j] < 0.0:
                    hit = True
        ax = bx
        ay = by
    if hit:
        return INADMISSIBLE, np.inf
    return CLEAR, _end_cost(f, pts, cum, k, jg, bb, x, y, th, v, bx, by, bth)
