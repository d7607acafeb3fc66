"""The dwa kernel's checks on scalars (:mod:`pathfuse.planners.controllers.dwa_kernel`).

Each returns exactly what the function it stands for returns (bit for bit,
``tests/test_dwa_exact.py``), with less work per rollout piece: no array per
call, and no search of the squares when the clearance lattice rules them out.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pathfuse.costmap import segment_distance
from pathfuse.geometry import point_box_distance, segment_box_distance
from pathfuse.sweep import edge_distance

__all__ = ["BLOCK", "NearSquares", "NO_NEAR", "near_squares", "_path_distance",
           "_segment_distance", "_straight_pose", "_sweep_gap", "path_blocks"]


class NearSquares(NamedTuple):
    """Per clearance-lattice cell of a costmap, the occupied squares that can be the nearest
    to a segment near the cell (:func:`near_squares`): ``sq[start[2 i]:start[2 i + 1]]``
    (squares ``row * W + col``) for lattice cell ``i = q * Ws + c`` when ``start[2 i] >= 0``
    (``-1``: no list, the cell's lattice bound is beyond ``dmax_m``); a segment whose points
    are all within ``reach_m`` of the cell's centre is nearest to one of them (or to none
    nearer than the cell's nearest square plus ``2 reach_m``... see :func:`near_squares`)."""

    start: np.ndarray
    sq: np.ndarray
    reach_m: float
    dc: np.ndarray = np.zeros(0)
    """Per entry of ``sq``, the distance from its lattice cell's centre to the square; each
    cell's list sorted by it, so that :func:`_segment_distance` stops at the first square
    that cannot be nearer than its best so far (empty: no such stop, the whole list)."""


NO_NEAR = NearSquares(np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), 0.0,
                      np.zeros(0))
"""No lists: :func:`_segment_distance` searches the squares every time."""


@njit(cache=True)
def _near_lists(occ, ox, oy, res, field, fres, reach, dmax):
    h, w = occ.shape
    hs, ws = field.shape
    half_diag = fres * math.sqrt(0.5)
    start = np.full(2 * hs * ws, -1, dtype=np.int64)
    cap = 1024
    sq = np.empty(cap, dtype=np.int64)
    dc = np.empty(cap)
    n = 0
    # the occupied columns of each row (row rr: cols[rows[rr]:rows[rr + 1]], ascending), so
    # that a cell's window visits its occupied squares only, in the same order as a scan
    rows = np.zeros(h + 1, dtype=np.int64)
    for rr in range(h):
        rows[rr + 1] = rows[rr] + np.count_nonzero(occ[rr])
    cols = np.empty(rows[h], dtype=np.int64)
    for rr in range(h):
        m = rows[rr]
        for cc in range(w):
            if occ[rr, cc]:
                cols[m] = cc
                m += 1
    for q in range(hs):
        cy = oy + (q + 0.5) * fres
        for c in range(ws):
            i = q * ws + c
            # the distance from the centre to its nearest square is at most the lattice's
            # lower bound plus a lattice cell's diagonal (field = EDT - half a diagonal)
            up = field[q, c] + 2.0 * half_diag
            if not (up <= dmax):
                continue
            cx = ox + (c + 0.5) * fres
            # a segment within reach of the centre is at most up + reach from a square, so its
            # nearest square is at most up + 2 reach from the centre (with room for rounding)
            lim = up + 2.0 * reach + 1e-6 * (1.0 + up + abs(cx) + abs(cy))
            c0 = max(int(math.floor((cx - lim - ox) / res)), 0)
            c1 = min(int(math.floor((cx + lim - ox) / res)), w - 1)
            r0 = max(int(math.floor((cy - lim - oy) / res)), 0)
            r1 = min(int(math.floor((cy + lim - oy) / res)), h - 1)
            start[2 * i] = n
            for rr in range(r0, r1 + 1):
                e = rows[rr + 1]
                m = rows[rr] + np.searchsorted(cols[rows[rr]:e], c0)
                while m < e and cols[m] <= c1:
                    cc = cols[m]
                    m += 1
                    x0 = ox + cc * res
                    y0 = oy + rr * res
                    dd = point_box_distance(cx, cy, x0, y0, x0 + res, y0 + res)
                    if dd <= lim:
                        if n == cap:
                            cap *= 2
                            grown = np.empty(cap, dtype=np.int64)
                            grown[:n] = sq[:n]
                            sq = grown
                            grown_d = np.empty(cap)
                            grown_d[:n] = dc[:n]
                            dc = grown_d
                        sq[n] = rr * w + cc
                        dc[n] = dd
                        n += 1
            s0 = start[2 * i]
            if n - s0 > 1:  # the cell's list nearest first (_segment_distance stops early)
                order = np.argsort(dc[s0:n], kind="mergesort")
                sq[s0:n] = sq[s0:n][order]
                dc[s0:n] = dc[s0:n][order]
            start[2 * i + 1] = n
    return start, sq[:n].copy(), dc[:n].copy()


def near_squares(cm, reach_m: float, dmax_m: float,
                 max_entries: int = 20_000_000) -> NearSquares:
    """The squares near each lattice cell of the costmap ``cm`` (:class:`NearSquares`), for
    segments within ``reach_m`` of a cell's centre, on the cells whose lattice bound is at
    most ``dmax_m`` (farther ones are left to the lattice shortcut or the search); ``NO_NEAR``
    when the lists would exceed ``max_entries`` squares or the costmap has no lattice."""
    hs, ws = cm.field.shape
    if hs * ws <= 1 or hs * ws > max_entries:
        return NO_NEAR
    start, sq, dc = _near_lists(cm.occ, cm.ox_m, cm.oy_m, cm.res_m, cm.field, cm.field_res_m,
                                float(reach_m), float(dmax_m))
    if sq.shape[0] > max_entries:
        return NO_NEAR
    return NearSquares(start, sq, float(reach_m), dc)


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
def _field_bound(cm, x, y):
    """:func:`pathfuse.costmap.field_distance`'s first value with ``sqrt`` for ``hypot`` (a
    few units in the last place apart, far within the 1e-9 m that
    :func:`_segment_distance`'s test keeps to spare; glibc's ``hypot`` was a fifth of the
    kernel's time)."""
    ox = cm.ox_m
    oy = cm.oy_m
    r = cm.field_res_m
    h, w = cm.field.shape
    c = min(max(int(math.floor((x - ox) / r)), 0), w - 1)
    q = min(max(int(math.floor((y - oy) / r)), 0), h - 1)
    ex = x - (ox + (c + 0.5) * r)
    ey = y - (oy + (q + 0.5) * r)
    return cm.field[q, c] - math.sqrt(ex * ex + ey * ey)


@njit(cache=True, inline="always")
def _segment_distance(cm, ax, ay, bx, by, cap, slack, near):
    """:func:`pathfuse.costmap.segment_distance`, the same value, with an exact shortcut:
    when the costmap's clearance lattice (a lower bound of the distance to the occupied
    squares, :func:`pathfuse.costmap.field_distance`, at the segment's midpoint less half
    its length) puts every square beyond ``cap`` (with 1e-9 to spare for rounding), no
    square can lower the result, which is then ``cap`` or the distance to the map's edge
    (:func:`pathfuse.sweep.edge_distance`, as :func:`pathfuse.sweep.segment_static_distance`
    takes it).

    Otherwise, with the lists ``near`` (:func:`near_squares`), when the segment lies within
    their reach of its midpoint's lattice cell, the least distance over the cell's list
    (the same squares' exact distances as the search's, so the same value); else the
    search."""
    half = 0.5 * math.sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
    mx = 0.5 * (ax + bx)
    my = 0.5 * (ay + by)
    lb = _field_bound(cm, mx, my)
    h, w = cm.occ.shape
    if lb - half > cap + 1e-9 * (1.0 + cap):
        return edge_distance(cm.ox_m, cm.oy_m, cm.ox_m + w * cm.res_m,
                             cm.oy_m + h * cm.res_m, ax, ay, bx, by, cap, slack)
    if near.start.shape[0] > 0:
        r = cm.field_res_m
        hs, ws = cm.field.shape
        c = int(math.floor((mx - cm.ox_m) / r))
        q = int(math.floor((my - cm.oy_m) / r))
        if 0 <= c < ws and 0 <= q < hs:
            i = q * ws + c
            s0 = near.start[2 * i]
            ex = mx - (cm.ox_m + (c + 0.5) * r)
            ey = my - (cm.oy_m + (q + 0.5) * r)
            rad = math.sqrt(ex * ex + ey * ey) + half
            if s0 >= 0 and rad <= near.reach_m * (1.0 - 1e-9):
                best = edge_distance(cm.ox_m, cm.oy_m, cm.ox_m + w * cm.res_m,
                                     cm.oy_m + h * cm.res_m, ax, ay, bx, by, cap, slack)
                if best == 0.0:
                    return 0.0
                res = cm.res_m
                # every point of the segment is within rad of the cell's centre, so a square
                # dc from the centre is at least dc - rad from it: once that is beyond the
                # best so far (with 1e-9 m to spare for rounding), no later square of the
                # sorted list can be nearer (the same least distance)
                sorted_ = near.dc.shape[0] > 0
                tol = 1e-9 * (1.0 + abs(mx) + abs(my) + rad)
                for j in range(s0, near.start[2 * i + 1]):
                    if sorted_ and near.dc[j] - rad > best + tol:
                        break
                    sq = near.sq[j]
                    rr = sq // w
                    cc = sq - rr * w
                    x0 = cm.ox_m + cc * res
                    y0 = cm.oy_m + rr * res
                    d = segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res)
                    if d < best:
                        best = d
                return best
    return segment_distance(cm, ax, ay, bx, by, cap, slack)


@njit(cache=True, inline="always")
def _straight_pose(x, y, th, v, w, t, cmid, smid):
    """:func:`pathfuse.sweep.unicycle_pose` for ``w == 0`` and ``t > 0`` (a straight rollout:
    every holonomic sample), bit for bit, with ``cmid, smid`` the cosine and sine of
    ``th + 0.5 * (w * h)`` for any ``h > 0``: the angle ``th + w t / 2`` is that same value
    at every ``t > 0`` (``w t`` is a zero of ``w``'s sign), so the rollout computes them
    once instead of per piece."""
    a = w * t
    chord = v * t * (1.0 - a * a / 24.0)
    return x + chord * cmid, y + chord * smid, th + a


BLOCK = 4
"""Path segments per block of :func:`path_blocks`."""


@njit(cache=True)
def path_blocks(pts, k, jg):
    """The bounding boxes ``(xmin, ymin, xmax, ymax)`` of the path's segments ``k .. jg - 1``
    in blocks of :data:`BLOCK` (block ``b`` holds segments ``k + BLOCK b`` on), which
    :func:`_path_distance` skips when a box is farther than its best so far."""
    end = min(jg, pts.shape[0] - 1)
    nb = max(0, (end - k + BLOCK - 1) // BLOCK)
    bb = np.empty((nb, 4))
    for b in range(nb):
        j0 = k + b * BLOCK
        j1 = min(j0 + BLOCK, end)
        x0 = pts[j0, 0]
        x1 = x0
        y0 = pts[j0, 1]
        y1 = y0
        for j in range(j0 + 1, j1 + 1):
            x0 = min(x0, pts[j, 0])
            x1 = max(x1, pts[j, 0])
            y0 = min(y0, pts[j, 1])
            y1 = max(y1, pts[j, 1])
        bb[b, 0] = x0
        bb[b, 1] = y0
        bb[b, 2] = x1
        bb[b, 3] = y1
    return bb


@njit(cache=True, inline="always")
def _segment_offset(pts, j, x, y):
    """The offset from the projection of ``(x, y)`` on the path's segment ``j`` to it and the
    segment parameter of the projection."""
    ax0 = pts[j, 0]
    ay0 = pts[j, 1]
    vx = pts[j + 1, 0] - ax0
    vy = pts[j + 1, 1] - ay0
    l2 = vx * vx + vy * vy
    tt = 0.0
    if l2 > 0.0:
        tt = min(max(((x - ax0) * vx + (y - ay0) * vy) / l2, 0.0), 1.0)
    return x - (ax0 + tt * vx), y - (ay0 + tt * vy), tt


@njit(cache=True, inline="always")
def _box_distance2(bb, b, x, y):
    """The squared distance from ``(x, y)`` to block ``b``'s box."""
    ox = max(bb[b, 0] - x, 0.0, x - bb[b, 2])
    oy = max(bb[b, 1] - y, 0.0, y - bb[b, 3])
    return ox * ox + oy * oy


@njit(cache=True, inline="always")
def _path_distance(pts, cum, k, jg, bb, x, y):
    """Distance from ``(x, y)`` to the path's segments ``k .. jg`` and the arc length of its
    projection (``inf`` and the path's end when there is no segment): the first segment of
    least distance, bit for bit as a scan of every segment in order.

    With the blocks ``bb`` (:func:`path_blocks`) it first takes the least distance
    ``bound`` over the segments of the block whose box is nearest, then scans in order,
    skipping every block whose box is farther than ``bound`` (or the best so far) by more
    than 1e-9 m: none of its segments can be the first of least distance.  (Any block's
    least distance bounds the result from above, so ``bound`` needs no more than a block
    near the nearest: the boxes are compared squared, without their square roots.)"""
    m = pts.shape[0]
    end = min(jg, m - 1)
    bound = np.inf
    nb = bb.shape[0]
    if nb > 1:
        bn = 0
        dn = np.inf
        for b in range(nb):
            db = _box_distance2(bb, b, x, y)
            if db < dn:
                dn = db
                bn = b
        b2 = np.inf
        for j in range(k + bn * BLOCK, min(k + (bn + 1) * BLOCK, end)):
            ex, ey, _ = _segment_offset(pts, j, x, y)
            b2 = min(b2, ex * ex + ey * ey)
        bound = math.sqrt(b2)  # within 1e-9 of the hypot
    pd = np.inf
    s_at = cum[m - 1]
    j = k
    while j < end:
        b = (j - k) // BLOCK
        if (j - k) % BLOCK == 0 and b < nb:
            lim = min(pd, bound) + 1e-9
            if _box_distance2(bb, b, x, y) > lim * lim:
                j += BLOCK
                continue
        ex, ey, tt = _segment_offset(pts, j, x, y)
        # a segment whose squared distance is beyond pd's (by far more than rounding) is
        # not nearer: its hypot, the costly part, is left out
        if ex * ex + ey * ey <= pd * pd * (1.0 + 1e-9):
            dd = math.hypot(ex, ey)
            if dd < pd:
                pd = dd
                s_at = cum[j] + tt * (cum[j + 1] - cum[j])
        j += 1
    return pd, s_at
