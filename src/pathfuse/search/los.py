"""Line of sight for the any-angle planners (numba): exact, and cheap on long segments.

:func:`line_of_sight` answers exactly what
:func:`pathfuse.geometry.segment_is_clear` answers (a straight move keeps at
least ``clear`` from every occupied square and from the outside of the map;
touching at exactly ``clear`` is allowed), with the same exact
segment-to-square test per cell (:func:`pathfuse.geometry.segment_box_distance`).
It differs only in which cells it visits: ``segment_is_clear`` scans the
segment's whole bounding box, which is fine for a robot's short moves but
costs ``O(length^2)`` cells on the long sight lines of Theta*;
:func:`line_of_sight` scans a strip along the segment, column by column (or
row by row for a steep segment), ``O(length)`` cells.  The strip reaches
``1e-7`` cell beyond ``clear``, so the rounding of its bounds never leaves out
a square within ``clear`` of the segment; the per-cell test decides.

:func:`smooth_path` is the post-smoothing of A* PS (Nash et al. 2007): from
each kept point, skip ahead while the next point after is in sight.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((5, 5), dtype=bool); occ[2, 3] = True   # the square [3, 4] x [2, 3]
>>> bool(line_of_sight(0.5, 2.5, 2.9, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
True
>>> bool(line_of_sight(0.5, 0.5, 4.5, 4.5, occ, 0.0, 0.0, 1.0, 1e-6))   # touches (3, 3)
False
>>> bool(line_of_sight(0.5, 2.5, 4.5, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
False
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC, _segment_hits_box, segment_box_distance

__all__ = ["line_of_sight", "smooth_path"]


@njit(cache=True, inline="always")
def _cell_blocks(ax, ay, bx, by, x0, y0, res, clear):
    """Whether the square ``[x0, x0+res] x [y0, y0+res]`` is closer than ``clear``."""
    if not _segment_hits_box(ax, ay, bx, by, x0 - clear, y0 - clear, x0 + res + clear,
                             y0 + res + clear):
        return False
    return segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res) < clear


@njit(cache=True)
def line_of_sight(ax, ay, bx, by, occ, ox, oy, res, clear):
    """True when segment ``AB`` stays ``>= clear`` from every occupied square and inside the map,
    at least ``clear - MARGIN_FRAC * res`` (the robot's radius) from its edge.

    The same answer as :func:`pathfuse.geometry.segment_is_clear`, visiting a
    strip of cells along the segment instead of its bounding box.
    """
    h, w = occ.shape
    edge = max(clear - MARGIN_FRAC * res, 0.0)  # the edge rule of segment_is_clear:
    xmin = ox + edge  # the robot's radius from the map's edge, the margin only from squares
    ymin = oy + edge
    xmax = ox + w * res - edge
    ymax = oy + h * res - edge
    if not (xmin <= ax <= xmax and xmin <= bx <= xmax and ymin <= ay <= ymax
            and ymin <= by <= ymax):
        return False
    dx = bx - ax
    dy = by - ay
    pad = clear + 1e-7 * res  # a sliver more than needed: rounding never leaves a square out
    if abs(dx) >= abs(dy):
        # column by column: the segment's y over the column's x-range (grown by clear)
        lo_x = min(ax, bx)
        hi_x = max(ax, bx)
        c0 = max(int(math.floor((lo_x - clear - ox) / res)), 0)
        c1 = min(int(math.floor((hi_x + clear - ox) / res)), w - 1)
        for c in range(c0, c1 + 1):
            xa = max(ox + c * res - clear, lo_x)
            xb = min(ox + (c + 1) * res + clear, hi_x)
            if dx != 0.0:
                ya = ay + dy * (xa - ax) / dx
                yb = ay + dy * (xb - ax) / dx
            else:
                ya = ay
                yb = by
            r0 = max(int(math.floor((min(ya, yb) - pad - oy) / res)), 0)
            r1 = min(int(math.floor((max(ya, yb) + pad - oy) / res)), h - 1)
            x0 = ox + c * res
            for r in range(r0, r1 + 1):
                if occ[r, c] and _cell_blocks(ax, ay, bx, by, x0, oy + r * res, res, clear):
                    return False
    else:
        lo_y = min(ay, by)
        hi_y = max(ay, by)
        r0 = max(int(math.floor((lo_y - clear - oy) / res)), 0)
        r1 = min(int(math.floor((hi_y + clear - oy) / res)), h - 1)
        for r in range(r0, r1 + 1):
            ya = max(oy + r * res - clear, lo_y)
            yb = min(oy + (r + 1) * res + clear, hi_y)
            xa = ax + dx * (ya - ay) / dy
            xb = ax + dx * (yb - ay) / dy
            c0 = max(int(math.floor((min(xa, xb) - pad - ox) / res)), 0)
            c1 = min(int(math.floor((max(xa, xb) + pad - ox) / res)), w - 1)
            y0 = oy + r * res
            for c in range(c0, c1 + 1):
                if occ[r, c] and _cell_blocks(ax, ay, bx, by, ox + c * res, y0, res, clear):
                    return False
    return True


@njit(cache=True)
def smooth_path(pts, occ, ox, oy, res, clear):
    """Greedy line-of-sight shortcutting of the polyline ``pts`` (N, 2).

    Keeps the first point; from the last kept point ``a``, a point ``k`` is
    dropped while ``pts[k + 1]`` is in sight of ``pts[a]``.  Every kept
    segment was found in sight (or is a segment of ``pts``), so the result is
    no longer than ``pts`` (triangle inequality).  Returns ``(M, 2)``.
    """
    n = pts.shape[0]
    out = np.empty((max(n, 1), 2))
    if n == 0:
        return out[:0]
    out[0, 0] = pts[0, 0]
    out[0, 1] = pts[0, 1]
    m = 1
    a = 0
    for k in range(1, n - 1):
        if not line_of_sight(pts[a, 0], pts[a, 1], pts[k + 1, 0], pts[k + 1, 1], occ, ox, oy,
                             res, clear):
            out[m, 0] = pts[k, 0]
            out[m, 1] = pts[k, 1]
            m += 1
            a = k
    if n > 1:
        out[m, 0] = pts[n - 1, 0]
        out[m, 1] = pts[n - 1, 1]
        m += 1
    return out[:m]
