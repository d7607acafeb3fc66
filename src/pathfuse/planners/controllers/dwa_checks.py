"""The dwa kernel's checks on scalars (:mod:`pathfuse.planners.controllers.dwa_kernel`).

Each returns exactly what the function it stands for returns (bit for bit,
``tests/test_dwa_exact.py``), with less work per rollout piece: no array per
call, and no search of the squares when the clearance lattice rules them out.
"""

from __future__ import annotations

import math

from numba import njit

from pathfuse.costmap import field_distance, segment_distance

__all__ = ["_segment_distance", "_sweep_gap"]


@njit(cache=True, inline="always")
def _sweep_gap(ax, ay, bx, by, radius, qax, qay, qbx, qby, rq):
    """:func:`pathfuse.sweep.disc_sweep_gaps` for one disc, on scalars (the same arithmetic
    in the same order, without its arrays): the least surface gap over a tick between the
    robot moving ``a -> b`` and a disc of radius ``rq`` moving ``qa -> qb``."""
    d0x = ax - qax
    d0y = ay - qay
    ddx = (bx - ax) - (qbx - qax)
    ddy = (by - ay) - (qby - qay)
    l2 = ddx * ddx + ddy * ddy
    u = 0.0
    if l2 > 0.0:
        u = -(d0x * ddx + d0y * ddy) / l2
        u = min(1.0, max(0.0, u))
    ex = d0x + u * ddx
    ey = d0y + u * ddy
    return math.sqrt(ex * ex + ey * ey) - radius - rq


@njit(cache=True, inline="always")
def _segment_distance(cm, ax, ay, bx, by, cap, slack):
    """:func:`pathfuse.costmap.segment_distance`, the same value, with an exact shortcut:
    when the costmap's clearance lattice (a lower bound of the distance to the occupied
    squares, :func:`pathfuse.costmap.field_distance`, at the segment's midpoint less half
    its length) puts every square beyond ``cap`` (with 1e-9 to spare for rounding), no
    square can lower the result, which is then ``cap`` or the distance to the map's edge
    (computed as :func:`pathfuse.sweep.segment_static_distance` does)."""
    half = 0.5 * math.hypot(bx - ax, by - ay)
    lb, _ = field_distance(cm, 0.5 * (ax + bx), 0.5 * (ay + by))
    if not (lb - half > cap + 1e-9 * (1.0 + cap)):
        return segment_distance(cm, ax, ay, bx, by, cap, slack)
    h, w = cm.occ.shape
    xmin = cm.ox_m
    ymin = cm.oy_m
    xmax = cm.ox_m + w * cm.res_m
    ymax = cm.oy_m + h * cm.res_m
    best = cap
    for i in range(2):
        px = ax if i == 0 else bx
        py = ay if i == 0 else by
        de = min(px - xmin, xmax - px, py - ymin, ymax - py)
        if de < 0.0 or (de == 0.0 and slack == 0.0):
            return 0.0
        de += slack
        if de < best:
            best = de
    return best
