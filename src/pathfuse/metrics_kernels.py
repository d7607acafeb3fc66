"""Numba kernels of :mod:`pathfuse.metrics`: exact polyline-to-obstacle clearance.

Also the segment lengths and heading changes (:func:`shape_kernel`), so that
:func:`pathfuse.metrics.evaluate` reads a path in one call.

Self-contained on purpose (no planner code): the metrics must stay an
independent check of what the planners produce.

Geometry: the obstacles are the closed occupied cell squares; cell
``(r, c)`` is ``[ox + c * res, ox + (c + 1) * res] x [oy + r * res, oy + (r + 1) * res]``,
its bounds computed exactly as the previous (k-d tree) implementation did,
from the cell centre plus or minus half a cell, so that the distances agree
bit for bit.  A square is measured with the exact segment-to-closed-square
distance: zero if the segment meets it (a Liang-Barsky slab test), otherwise
the least of the distances from the segment's end points to the square and
from the square's corners to the segment.

Search, per segment (the answer is the same whichever way it is found):

1. *Rings* (short segments in or near the map, the common case): rings of
   cells around the segment's box of cells, nearest first.  Every point of a
   cell in ring ``k >= 1`` is at least ``(k - 1 + m) * res`` from the segment
   (``k - 1`` whole cells lie between it and the box, and the segment lies at
   least ``m`` cells inside the box), so once the best distance found is
   below ``(k + m) * res`` no unvisited cell can be closer and the search
   stops.  At most :data:`_MAX_RINGS` rings are visited.
2. *Pyramid* (what rings did not settle: large clearance, long segments,
   segments far outside the map): branch and bound over an occupancy pyramid
   (level ``l`` block = ``2**l x 2**l`` cells, marked if any cell in it is
   occupied; built once per map by :func:`build_pyramid`).  Blocks are
   visited depth first, nearest first; an empty block, or one whose
   rectangle is no nearer than the best distance so far, is skipped with
   everything in it.  The cost grows with the number of blocks near the
   answer, not with the area around the segment.

Along a path, when only the minimum is wanted (:func:`geometry_kernel`), each
segment's search also starts from the least clearance of the segments before
it, which prunes both searches.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "build_pyramid",
    "segment_clearances_kernel",
    "geometry_kernel",
    "shape_kernel",
    "evaluate_kernel",
    "warmup",
]

# window margin, in cells: guards the floor() of the segment's box and the stop test
# against rounding of the world -> cell conversion
_EPS_CELLS = 1e-6
# segments longer than this (in cells, |du| + |dv|) go straight to the pyramid
_SHORT_CELLS = 4.0
# rings visited before the pyramid takes over
_MAX_RINGS = 4


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
def build_pyramid(occ):
    """Occupancy pyramid of ``occ``: (flat uint8 levels 1..L, (L, 3) int64 [offset, h, w]).

    Level ``l`` holds ``ceil(H / 2**l) x ceil(W / 2**l)`` blocks, block
    ``(i, j)`` = 1 when any cell of rows ``i * 2**l ..`` and columns ``j * 2**l ..``
    is occupied.  The last level has one block (none for a 1 x 1 map).
    """
    hgt, wid = occ.shape
    nlev = 0
    total = 0
    h, w = hgt, wid
    while h > 1 or w > 1:
        h = (h + 1) // 2
        w = (w + 1) // 2
        nlev += 1
        total += h * w
    meta = np.zeros((nlev, 3), dtype=np.int64)
    pyr = np.zeros(total, dtype=np.uint8)
    h, w = hgt, wid
    off = 0
    for lev in range(nlev):
        ph, pw = h, w
        h = (h + 1) // 2
        w = (w + 1) // 2
        meta[lev, 0] = off
        meta[lev, 1] = h
        meta[lev, 2] = w
        poff = meta[lev - 1, 0] if lev > 0 else 0
        for i in range(ph):
            for j in range(pw):
                if lev == 0:
                    full = occ[i, j]
                else:
                    full = pyr[poff + i * pw + j] != 0
                if full:
                    pyr[off + (i // 2) * w + j // 2] = 1
        off += h * w
    return pyr, meta


@njit(cache=True, inline="always")
def _block_full(occ, pyr, meta, lev, i, j):
    if lev == 0:
        return occ[i, j]
    m = meta[lev - 1]
    return pyr[m[0] + i * m[2] + j] != 0


@njit(cache=True)
def _pyramid_search(occ, pyr, meta, ox, oy, res, ax, ay, bx, by, best, ws):
    """min(best, exact distance from AB to every occupied square), by branch and bound."""
    stack, stack_lb, cl, cij = ws
    hgt, wid = occ.shape
    h = res / 2
    nlev = meta.shape[0]
    sx0 = min(ax, bx)
    sx1 = max(ax, bx)
    sy0 = min(ay, by)
    sy1 = max(ay, by)
    if nlev == 0:  # a 1 x 1 map
        return _cell_dist(occ, 0, 0, ax, ay, bx, by, sx0, sy0, sx1, sy1, ox, oy, res, h, best)
    # block rectangles are grown by eps so that their distance never exceeds, by
    # rounding, that of a square inside them
    eps = 1e-6 * res + 1e-12 * (abs(ox) + abs(oy) + (hgt + wid) * res)
    if not _block_full(occ, pyr, meta, nlev, 0, 0):
        return best
    n = 1
    stack[0, 0] = nlev
    stack[0, 1] = 0
    stack[0, 2] = 0
    stack_lb[0] = 0.0
    while n > 0:
        n -= 1
        if stack_lb[n] >= best:
            continue  # best improved since this block was pushed
        lev = stack[n, 0]
        i = stack[n, 1]
        j = stack[n, 2]
        # children: level lev - 1, blocks (2i .. 2i + 1, 2j .. 2j + 1) within that level
        clev = lev - 1
        if clev == 0:
            ch, cw = hgt, wid
        else:
            ch = meta[clev - 1, 1]
            cw = meta[clev - 1, 2]
        size = 1 << clev  # cells per child block side
        k = 0
        for ii in range(2 * i, min(2 * i + 2, ch)):
            for jj in range(2 * j, min(2 * j + 2, cw)):
                if not _block_full(occ, pyr, meta, clev, ii, jj):
                    continue
                if clev == 0:
                    best = _cell_dist(occ, ii, jj, ax, ay, bx, by, sx0, sy0, sx1, sy1,
                                      ox, oy, res, h, best)
                    if best == 0.0:
                        return 0.0
                    continue
                x0 = ox + (jj * size) * res - eps
                x1 = ox + (min((jj + 1) * size, wid)) * res + eps
                y0 = oy + (ii * size) * res - eps
                y1 = oy + (min((ii + 1) * size, hgt)) * res + eps
                gx = max(max(x0 - sx1, sx0 - x1), 0.0)
                gy = max(max(y0 - sy1, sy0 - y1), 0.0)
                if math.hypot(gx, gy) >= best:  # not squares: best * best can underflow
                    continue  # even the boxes are too far apart
                lb = _seg_box(ax, ay, bx, by, x0, y0, x1, y1)
                if lb >= best:
                    continue
                # insert, keeping cl descending: the nearest child is pushed last
                p = k
                while p > 0 and cl[p - 1] < lb:
                    cl[p] = cl[p - 1]
                    cij[p, 0] = cij[p - 1, 0]
                    cij[p, 1] = cij[p - 1, 1]
                    p -= 1
                cl[p] = lb
                cij[p, 0] = ii
                cij[p, 1] = jj
                k += 1
        for q in range(k):
            stack[n, 0] = clev
            stack[n, 1] = cij[q, 0]
            stack[n, 2] = cij[q, 1]
            stack_lb[n] = cl[q]
            n += 1
    return best


@njit(cache=True)
def _ring_search(occ, ox, oy, res, ax, ay, bx, by, best):
    """(min(best, distance from AB to the occupied squares nearby), whether that is final).

    Final: no square beyond the rings visited can be nearer.  Not final for
    long segments, segments far outside the map, and when :data:`_MAX_RINGS`
    rings did not settle it; the pyramid search must then finish the job
    (the ``best`` returned is still a valid start for it).
    """
    hgt, wid = occ.shape
    ua = (ax - ox) / res
    va = (ay - oy) / res
    ub = (bx - ox) / res
    vb = (by - oy) / res
    lim = _MAX_RINGS + 1.0
    if (abs(ub - ua) + abs(vb - va) <= _SHORT_CELLS and min(ua, ub) > -lim
            and max(ua, ub) < wid + lim and min(va, vb) > -lim and max(va, vb) < hgt + lim):
        h = res / 2
        sx0 = min(ax, bx)
        sx1 = max(ax, bx)
        sy0 = min(ay, by)
        sy1 = max(ay, by)
        c0 = int(math.floor(min(ua, ub) - _EPS_CELLS))
        c1 = int(math.floor(max(ua, ub) + _EPS_CELLS))
        r0 = int(math.floor(min(va, vb) - _EPS_CELLS))
        r1 = int(math.floor(max(va, vb) + _EPS_CELLS))
        # margin of the segment inside its box of cells: ring k >= 1 is >= k - 1 + margin away
        margin = min(min(ua, ub) - c0, c1 + 1 - max(ua, ub), min(va, vb) - r0,
                     r1 + 1 - max(va, vb)) - _EPS_CELLS
        # rings 0 .. k-1 lie outside the map: start with the whole box grown by k
        k = max(0, r0 - (hgt - 1), -r1, c0 - (wid - 1), -c1)
        best = _scan_rows(occ, r0 - k, r1 + k, c0 - k, c1 + k, ax, ay, bx, by,
                          sx0, sy0, sx1, sy1, ox, oy, res, h, best)
        while True:
            if best < (k + margin) * res:
                # every cell of ring k + 1 and beyond is >= (k + margin) * res away
                return best, True
            if r0 - k <= 0 and c0 - k <= 0 and r1 + k >= hgt - 1 and c1 + k >= wid - 1:
                return best, True  # the whole map has been visited
            if k >= _MAX_RINGS:
                break  # not settled nearby: the pyramid takes over
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
    return best, False


@njit(cache=True)
def _workspace(meta):
    """Buffers of the pyramid search: its stack (at most 3 blocks per level pending at
    once, plus one) with the blocks' distances, and room to sort 4 children."""
    cap = 4 * (meta.shape[0] + 2)
    return (np.empty((cap, 3), dtype=np.int64), np.empty(cap), np.empty(4),
            np.empty((4, 2), dtype=np.int64))


@njit(cache=True)
def segment_clearances_kernel(occ, pyr, meta, ox, oy, res, p):
    """Per-segment clearance of the (N, 2) path ``p`` (N >= 1); one value for one point."""
    n = p.shape[0]
    m = max(n - 1, 1)
    out = np.full(m, np.inf)
    if not _block_full(occ, pyr, meta, meta.shape[0], 0, 0):
        return out
    ws = _workspace(meta)
    for i in range(m):
        j = min(i + 1, n - 1)  # a one-point path is the segment from that point to itself
        # (the two searches are called here, not through a helper taking every array: a
        # call per segment with that many arrays costs as much as the ring search itself)
        d, final = _ring_search(occ, ox, oy, res, p[i, 0], p[i, 1], p[j, 0], p[j, 1], math.inf)
        if not final:
            d = _pyramid_search(occ, pyr, meta, ox, oy, res, p[i, 0], p[i, 1], p[j, 0], p[j, 1],
                                d, ws)
        out[i] = d
    return out


@njit(cache=True)
def geometry_kernel(occ, pyr, meta, ox, oy, res, x0, y0, x1, y1, p):
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
    if not _block_full(occ, pyr, meta, meta.shape[0], 0, 0):
        return best, inside
    ws = _workspace(meta)
    for i in range(max(n - 1, 1)):
        j = min(i + 1, n - 1)
        best, final = _ring_search(occ, ox, oy, res, p[i, 0], p[i, 1], p[j, 0], p[j, 1], best)
        if not final:
            best = _pyramid_search(occ, pyr, meta, ox, oy, res, p[i, 0], p[i, 1], p[j, 0],
                                   p[j, 1], best, ws)
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
def evaluate_kernel(occ, pyr, meta, ox, oy, res, x0, y0, x1, y1, p):
    """:func:`geometry_kernel` and :func:`shape_kernel` in one call (``p`` non-empty)."""
    clearance, inside = geometry_kernel(occ, pyr, meta, ox, oy, res, x0, y0, x1, y1, p)
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
        pyr, meta = build_pyramid(occ)
        segment_clearances_kernel(occ, pyr, meta, 0.0, 0.0, 1.0, p)
        geometry_kernel(occ, pyr, meta, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 2.0, p)
        evaluate_kernel(occ, pyr, meta, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 2.0, p)
    shape_kernel(p)
