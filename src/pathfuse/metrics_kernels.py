"""Numba kernels of :mod:`pathfuse.metrics`: exact polyline-to-obstacle clearance.

Also the segment lengths and heading changes (:func:`shape_kernel`), so that
:func:`pathfuse.metrics.evaluate` reads a path in one call.

Self-contained on purpose (no planner code): the metrics must stay an
independent check of what the planners produce.

Geometry: the obstacles are the closed occupied cell squares; cell
``(r, c)`` is ``[ox + c * res, ox + (c + 1) * res] x [oy + r * res, oy + (r + 1) * res]``,
its bounds computed exactly as the previous (k-d tree) implementation did,
from the cell centre plus or minus half a cell, so that the distances agree
bit for bit.

Search: for each segment, rings of cells are visited around the segment's
bounding box of cells, nearest ring first.  Every point of a cell in ring
``k >= 1`` is at least ``(k - 1 + m) * res`` from the segment (``k - 1``
whole cells lie between it and the box, and the segment lies at least ``m``
cells inside the box), so once the best distance found is below
``(k + m) * res`` no unvisited cell can be closer and the search stops.  Only
occupied cells are measured, with the exact segment-to-closed-square
distance: zero if the segment meets the square (a Liang-Barsky slab test),
otherwise the least of the distances from the segment's end points to the
square and from the square's corners to the segment.

* The best distance starts at the distance to one occupied square (any
  square's distance bounds the minimum), and only the part of the segment
  within that distance of the map rectangle is searched.
* A long segment is cut into pieces (the first 4 cells long, the next ones
  about twice the best distance so far), each searched the same way (the
  distance measured is always that of the whole segment), so the cells
  visited stay within a band around the segment rather than its whole
  bounding box.
* Along a path, each segment's search is also cut short by the least
  clearance of the segments before it when only the minimum is wanted
  (:func:`geometry_kernel`).
* A segment with an end point more than ``4 * max(H, W) + 64`` cells outside
  the map is measured against every occupied square instead (no planner
  makes one; this bounds the ring count and keeps cell indices small).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "segment_clearances_kernel",
    "geometry_kernel",
    "shape_kernel",
    "evaluate_kernel",
    "warmup",
]

# window margin, in cells: guards the floor() of the piece bounds and the stop test
# against rounding of the world -> cell conversion
_EPS_CELLS = 1e-6
# shortest piece a long segment is cut into, in cells
_MIN_PIECE_CELLS = 4.0


@njit(cache=True, inline="always")
def _point_box(px, py, x0, y0, x1, y1):
    dx = max(max(x0 - px, px - x1), 0.0)
    dy = max(max(y0 - py, py - y1), 0.0)
    return math.hypot(dx, dy)


@njit(cache=True, inline="always")
def _point_seg(px, py, ax, ay, bx, by):
    vx = bx - ax
    vy = by - ay
    l2 = vx * vx + vy * vy
    t = 0.0
    if l2 > 0:
        t = ((px - ax) * vx + (py - ay) * vy) / l2
    t = min(max(t, 0.0), 1.0)
    return math.hypot(px - (ax + t * vx), py - (ay + t * vy))


@njit(cache=True, inline="always")
def _seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
    """Closed segment meets closed box (Liang-Barsky slabs)."""
    t0 = 0.0
    t1 = 1.0
    d = bx - ax
    if d == 0:
        if ax < x0 or ax > x1:
            return False
    else:
        ta = (x0 - ax) / d
        tb = (x1 - ax) / d
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    d = by - ay
    if d == 0:
        if ay < y0 or ay > y1:
            return False
    else:
        ta = (y0 - ay) / d
        tb = (y1 - ay) / d
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    return t0 <= t1


@njit(cache=True)
def _seg_box(ax, ay, bx, by, x0, y0, x1, y1):
    """Exact distance between segment AB and the closed box [x0, x1] x [y0, y1]."""
    if _seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
        return 0.0
    d = min(_point_box(ax, ay, x0, y0, x1, y1), _point_box(bx, by, x0, y0, x1, y1))
    d = min(d, _point_seg(x0, y0, ax, ay, bx, by))
    d = min(d, _point_seg(x1, y0, ax, ay, bx, by))
    d = min(d, _point_seg(x0, y1, ax, ay, bx, by))
    d = min(d, _point_seg(x1, y1, ax, ay, bx, by))
    return d


@njit(cache=True, inline="always")
def _cell_dist(occ, r, c, ax, ay, bx, by, sx0, sy0, sx1, sy1, ox, oy, res, h, best):
    """min(best, distance of AB to cell (r, c) if it is occupied)."""
    if not occ[r, c]:
        return best
    cx = ox + (c + 0.5) * res
    cy = oy + (r + 0.5) * res
    x0 = cx - h
    x1 = cx + h
    y0 = cy - h
    y1 = cy + h
    # cheap lower bound: distance between the segment's bounding box and the square
    gx = max(max(x0 - sx1, sx0 - x1), 0.0)
    gy = max(max(y0 - sy1, sy0 - y1), 0.0)
    if gx * gx + gy * gy > best * best * (1.0 + 1e-9):
        return best
    return min(best, _seg_box(ax, ay, bx, by, x0, y0, x1, y1))


@njit(cache=True)
def _scan_rows(occ, r0, r1, c0, c1, ax, ay, bx, by, sx0, sy0, sx1, sy1, ox, oy, res, h, best):
    """Visit cells rows r0..r1, cols c0..c1, clipped to the map."""
    hgt, wid = occ.shape
    r0 = max(r0, 0)
    c0 = max(c0, 0)
    r1 = min(r1, hgt - 1)
    c1 = min(c1, wid - 1)
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            best = _cell_dist(occ, r, c, ax, ay, bx, by, sx0, sy0, sx1, sy1, ox, oy, res, h,
                              best)
            if best == 0.0:
                return 0.0
    return best


@njit(cache=True)
def _brute(occ, ox, oy, res, h, ax, ay, bx, by, best):
    """min(best, distance of AB to every occupied square): the fallback for far segments."""
    hgt, wid = occ.shape
    return _scan_rows(occ, 0, hgt - 1, 0, wid - 1, ax, ay, bx, by, min(ax, bx), min(ay, by),
                      max(ax, bx), max(ay, by), ox, oy, res, h, best)


@njit(cache=True, inline="always")
def _clip(u0, v0, u1, v1, lo_u, lo_v, hi_u, hi_v):
    """Parameter interval [t0, t1] of segment (u0, v0)-(u1, v1) inside a box (t0 > t1: none)."""
    t0 = 0.0
    t1 = 1.0
    d = u1 - u0
    if d == 0:
        if u0 < lo_u or u0 > hi_u:
            return 1.0, 0.0
    else:
        ta = (lo_u - u0) / d
        tb = (hi_u - u0) / d
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    d = v1 - v0
    if d == 0:
        if v0 < lo_v or v0 > hi_v:
            return 1.0, 0.0
    else:
        ta = (lo_v - v0) / d
        tb = (hi_v - v0) / d
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    return t0, t1


@njit(cache=True)
def _segment_clearance(occ, ox, oy, res, ax, ay, bx, by, best, seed_r, seed_c):
    """min(best, exact distance from segment AB to the nearest occupied square).

    ``(seed_r, seed_c)`` is any occupied cell; ``best = inf`` gives the
    segment's own clearance, a finite ``best`` (the least clearance found so
    far on a path) only prunes the search.
    """
    hgt, wid = occ.shape
    h = res / 2
    sx0 = min(ax, bx)
    sx1 = max(ax, bx)
    sy0 = min(ay, by)
    sy1 = max(ay, by)
    if best == math.inf:
        # the seed square bounds the answer, so the parts of AB farther than that from
        # the map rectangle can be skipped
        cx = ox + (seed_c + 0.5) * res
        cy = oy + (seed_r + 0.5) * res
        best = _seg_box(ax, ay, bx, by, cx - h, cy - h, cx + h, cy + h)
    if best == 0.0:
        return 0.0
    # cell coordinates (cell (r, c) is [c, c + 1] x [r, r + 1])
    ua = (ax - ox) / res
    va = (ay - oy) / res
    ub = (bx - ox) / res
    vb = (by - oy) / res
    far = 4.0 * max(hgt, wid) + 64.0
    if (min(ua, ub) < -far or max(ua, ub) > wid + far or min(va, vb) < -far
            or max(va, vb) > hgt + far):
        return _brute(occ, ox, oy, res, h, ax, ay, bx, by, best)
    short = abs(ub - ua) + abs(vb - va) <= _MIN_PIECE_CELLS  # one piece, whatever best is
    length = 0.0 if short else math.hypot(ub - ua, vb - va)
    first = True
    t_lo = 0.0
    while True:
        # only the part of AB within best of the map rectangle can get closer
        g = best / res + 1.0
        if (min(ua, ub) >= -g and max(ua, ub) <= wid + g and min(va, vb) >= -g
                and max(va, vb) <= hgt + g):
            t_in, t_out = 0.0, 1.0
        else:
            t_in, t_out = _clip(ua, va, ub, vb, -g, -g, wid + g, hgt + g)
        if t_in > t_out or t_lo > t_out:
            break
        t_lo = max(t_lo, t_in)
        # the next piece [t_lo, t_hi] of AB, about twice the best distance long
        piece = _MIN_PIECE_CELLS if first else max(_MIN_PIECE_CELLS, 2.0 * best / res)
        first = False
        if short or t_lo + piece / length >= t_out:
            t_hi = t_out
        else:
            t_hi = t_lo + piece / length
        pu0 = ua + t_lo * (ub - ua) if t_lo > 0.0 else ua
        pv0 = va + t_lo * (vb - va) if t_lo > 0.0 else va
        pu1 = ua + t_hi * (ub - ua) if t_hi < 1.0 else ub
        pv1 = va + t_hi * (vb - va) if t_hi < 1.0 else vb
        c0 = int(math.floor(min(pu0, pu1) - _EPS_CELLS))
        c1 = int(math.floor(max(pu0, pu1) + _EPS_CELLS))
        r0 = int(math.floor(min(pv0, pv1) - _EPS_CELLS))
        r1 = int(math.floor(max(pv0, pv1) + _EPS_CELLS))
        # margin of the piece inside its box of cells: ring k >= 1 is >= k - 1 + margin away
        margin = min(min(pu0, pu1) - c0, c1 + 1 - max(pu0, pu1), min(pv0, pv1) - r0,
                     r1 + 1 - max(pv0, pv1)) - _EPS_CELLS
        # rings 0 .. k-1 lie outside the map: start with the whole box grown by k
        k = max(0, r0 - (hgt - 1), -r1, c0 - (wid - 1), -c1)
        best = _scan_rows(occ, r0 - k, r1 + k, c0 - k, c1 + k, ax, ay, bx, by,
                          sx0, sy0, sx1, sy1, ox, oy, res, h, best)
        while best > 0.0:
            if best < (k + margin) * res:
                break  # every cell of ring k + 1 and beyond is >= (k + margin) * res away
            if r0 - k <= 0 and c0 - k <= 0 and r1 + k >= hgt - 1 and c1 + k >= wid - 1:
                break  # the whole map has been visited
            k += 1
            # ring k: bottom and top rows, then the left and right columns between them
            best = _scan_rows(occ, r0 - k, r0 - k, c0 - k, c1 + k, ax, ay, bx, by,
                              sx0, sy0, sx1, sy1, ox, oy, res, h, best)
            best = _scan_rows(occ, r1 + k, r1 + k, c0 - k, c1 + k, ax, ay, bx, by,
                              sx0, sy0, sx1, sy1, ox, oy, res, h, best)
            best = _scan_rows(occ, r0 - k + 1, r1 + k - 1, c0 - k, c0 - k, ax, ay, bx, by,
                              sx0, sy0, sx1, sy1, ox, oy, res, h, best)
            best = _scan_rows(occ, r0 - k + 1, r1 + k - 1, c1 + k, c1 + k, ax, ay, bx, by,
                              sx0, sy0, sx1, sy1, ox, oy, res, h, best)
        if best == 0.0 or t_hi >= t_out:
            break
        t_lo = t_hi
    return best


@njit(cache=True)
def _first_obstacle(occ):
    """(row, col) of one occupied cell, (-1, -1) if there is none."""
    hgt, wid = occ.shape
    for r in range(hgt):
        for c in range(wid):
            if occ[r, c]:
                return r, c
    return -1, -1


@njit(cache=True)
def segment_clearances_kernel(occ, ox, oy, res, p):
    """Per-segment clearance of the (N, 2) path ``p`` (N >= 1); one value for one point."""
    n = p.shape[0]
    m = max(n - 1, 1)
    out = np.full(m, np.inf)
    sr, sc = _first_obstacle(occ)
    if sr < 0:
        return out
    if n == 1:
        out[0] = _segment_clearance(occ, ox, oy, res, p[0, 0], p[0, 1], p[0, 0], p[0, 1],
                                    math.inf, sr, sc)
        return out
    for i in range(m):
        out[i] = _segment_clearance(occ, ox, oy, res, p[i, 0], p[i, 1], p[i + 1, 0], p[i + 1, 1],
                                    math.inf, sr, sc)
    return out


@njit(cache=True)
def geometry_kernel(occ, ox, oy, res, x0, y0, x1, y1, p):
    """(min clearance, every point in [x0, x1] x [y0, y1]) of the (N, 2) path ``p`` (N >= 1).

    One pass; each segment's search is pruned by the least clearance found so
    far, and the pass stops at the first touching segment (the minimum is then 0).
    """
    n = p.shape[0]
    inside = True
    for i in range(n):
        x = p[i, 0]
        y = p[i, 1]
        if not (x >= x0 and x <= x1 and y >= y0 and y <= y1):
            inside = False
            break
    best = math.inf
    sr, sc = _first_obstacle(occ)
    if sr < 0:
        return best, inside
    if n == 1:
        return _segment_clearance(occ, ox, oy, res, p[0, 0], p[0, 1], p[0, 0], p[0, 1],
                                  best, sr, sc), inside
    for i in range(n - 1):
        best = _segment_clearance(occ, ox, oy, res, p[i, 0], p[i, 1], p[i + 1, 0], p[i + 1, 1],
                                  best, sr, sc)
        if best == 0.0:
            break
    return best, inside


@njit(cache=True)
def shape_kernel(p):
    """(segment lengths, absolute heading changes) of the (N, 2) path ``p``.

    The heading changes are between successive non-zero segments, each
    wrapped into ``[-pi, pi]``.  Element by element the same operations as
    the numpy expressions of :func:`pathfuse.metrics.path_length` and
    :func:`pathfuse.metrics.smoothness` had (``sqrt(dx*dx + dy*dy)``,
    ``atan2``, floored ``%``); the caller sums the arrays with numpy, so the
    totals keep numpy's pairwise summation.
    """
    m = max(p.shape[0] - 1, 0)
    lengths = np.empty(m)
    headings = np.empty(m)
    k = 0
    for i in range(m):
        dx = p[i + 1, 0] - p[i, 0]
        dy = p[i + 1, 1] - p[i, 1]
        lengths[i] = math.sqrt(dx * dx + dy * dy)
        if dx != 0 or dy != 0:
            headings[k] = math.atan2(dy, dx)
            k += 1
    turns = np.empty(max(k - 1, 0))
    for j in range(k - 1):
        dh = headings[j + 1] - headings[j]
        turns[j] = abs((dh + math.pi) % (2 * math.pi) - math.pi)
    return lengths, turns


@njit(cache=True)
def evaluate_kernel(occ, ox, oy, res, x0, y0, x1, y1, p):
    """:func:`geometry_kernel` and :func:`shape_kernel` in one call (``p`` non-empty)."""
    clearance, inside = geometry_kernel(occ, ox, oy, res, x0, y0, x1, y1, p)
    lengths, turns = shape_kernel(p)
    return clearance, inside, lengths, turns


def warmup() -> None:
    """Compile (or load from numba's on-disk cache) the kernels on a tiny grid.

    Both for a writable occupancy array and a read-only one (``GridMap``'s).
    """
    p = np.array([[0.5, 0.5], [2.5, 0.5]])
    for writable in (True, False):
        occ = np.zeros((2, 3), dtype=bool)
        occ[1, 1] = True
        occ.setflags(write=writable)
        segment_clearances_kernel(occ, 0.0, 0.0, 1.0, p)
        geometry_kernel(occ, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 2.0, p)
        evaluate_kernel(occ, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 2.0, p)
    shape_kernel(p)
