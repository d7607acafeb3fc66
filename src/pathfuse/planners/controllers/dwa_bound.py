"""The dwa kernel's exact pruning of samples (:mod:`pathfuse.planners.controllers.dwa_kernel`).

Where a sample's rollout ends, and whether it is admissible, depends on its static
distances only down to the clearance: :func:`_probe` finds both with the poses, the
clearance lattice and a search of the squares capped at the clearance (no obstacle
critic's wider search, no path-align distance per piece, no disc sweep beyond the tick).
An admissible sample costs at least its end point's critics (:func:`_end_cost`: path
distance, goal distance, heading and speed), because every other critic adds a
non-negative term after them and floating-point addition is monotone; so the kernel's
``_choose`` rolls out the admissible samples fully in increasing bound order only while
the bound can still beat, or tie with an earlier sample, the best so far: the same
choice, cost, admissible count and passing sides, bit for bit
(``tests/test_dwa_exact.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC
from pathfuse.planners.controllers.dwa_checks import (
    _field_bound,
    _path_distance,
    _segment_distance,
    _straight_pose,
    _sweep_gap,
)
from pathfuse.planners.controllers.dwa_route import _wrap
from pathfuse.sweep import arc_deviation_bound, edge_distance, unicycle_pose

__all__ = ["ADMISSIBLE", "INADMISSIBLE", "_end_cost", "_probe"]

INADMISSIBLE = 0
""":func:`_probe`: the sample is not admissible."""
ADMISSIBLE = 1
""":func:`_probe`: the sample is admissible; the bound holds."""


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
def _probe(cm, nsq, f, clear, x, y, th, v, w, pts, cum, k, jg, bb, dpos, dvel, drad, reach):
    """Whether one sample is admissible (:data:`ADMISSIBLE` or :data:`INADMISSIBLE`) and, when
    it is, a lower bound of its cost: :func:`_end_cost` at the pose where its rollout ends.

    The rollout's poses and its end are ``_rollout``'s (:mod:`.dwa_kernel`), found with less
    work: a piece whose chord the clearance lattice and the map's edge put beyond ``clear``
    plus the arc's deviation plus 1e-6 m cannot end the rollout; any other piece's static
    distance is searched only up to ``clear`` plus the deviation (plus 1e-9 m), which tells
    whether it is below ``clear`` as the rollout's wider search does (under a smaller cap
    the distance is the same value, or the cap).  A sensed disc closer than it can come
    while the robot stops, on a piece starting within the tick, makes the sample
    inadmissible, as in ``_rollout``.  ``reach`` is scratch space of one float per disc."""
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
    capb = cc + 1e-9 * (1.0 + cc)
    hh, ww = cm.occ.shape
    xmax = cm.ox_m + ww * res
    ymax = cm.oy_m + hh * res
    speed = abs(v)
    amax = f.max_accel_mps2
    brake = 0.0
    if math.isfinite(amax) and amax > 0.0:
        brake = speed * speed / (2.0 * amax)
    need = speed * dt + brake  # travel before the robot could stand still
    n_disc = drad.shape[0]
    stop_s = dt + (speed / amax if math.isfinite(amax) and amax > 0.0 else 0.0)
    if not f.passive:
        stop_s = 0.0
    for j in range(n_disc):
        reach[j] = math.hypot(dvel[j, 0], dvel[j, 1]) * stop_s
    straight = w == 0.0
    cmid = math.cos(th + 0.5 * (w * h))
    smid = math.sin(th + 0.5 * (w * h))
    ax = x
    ay = y
    ex = x
    ey = y
    eth = th
    travelled = 0.0
    for i in range(1, n + 1):
        t = min(i * h, horizon)
        if straight:
            bx, by, bth = _straight_pose(x, y, th, v, w, t, cmid, smid)
        else:
            bx, by, bth = unicycle_pose(x, y, th, v, w, t)
        half = 0.5 * math.sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
        if not (_field_bound(cm, 0.5 * (ax + bx), 0.5 * (ay + by)) - half > tol
                and edge_distance(cm.ox_m, cm.oy_m, xmax, ymax, ax, ay, bx, by, capc,
                                  slack) >= capc):
            d = _segment_distance(cm, ax, ay, bx, by, capb, slack, nsq) - e
            if t <= dt + 1e-12:
                # the tick itself: the arc (lower bound) and the chord clear
                if d < clear:
                    return INADMISSIBLE, np.inf
                if e > 0.0 and _segment_distance(cm, ax, ay, bx, by, clear, slack,
                                                 nsq) < clear:
                    return INADMISSIBLE, np.inf
            if d < clear:
                if travelled < need:
                    return INADMISSIBLE, np.inf  # it could not stop before this collision
                break
        t0 = t - h if t - h > 0.0 else 0.0
        if t0 <= dt:
            for j in range(n_disc):
                qax = dpos[j, 0] + dvel[j, 0] * t0
                qay = dpos[j, 1] + dvel[j, 1] * t0
                qbx = dpos[j, 0] + dvel[j, 0] * t
                qby = dpos[j, 1] + dvel[j, 1] * t
                g0 = _sweep_gap(ax, ay, bx, by, radius, qax, qay, qbx, qby, drad[j]) - e
                if g0 - reach[j] < 0.0:
                    return INADMISSIBLE, np.inf  # a predicted collision within the tick
        travelled += abs(v) * (t - (i - 1) * h)
        ax = bx
        ay = by
        ex = bx
        ey = by
        eth = bth
    return ADMISSIBLE, _end_cost(f, pts, cum, k, jg, bb, x, y, th, v, ex, ey, eth)
