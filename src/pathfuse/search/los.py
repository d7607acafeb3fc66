"""Line of sight for the any-angle planners (numba): exact, and cheap on long segments.

Since these sight lines are long, :func:`line_of_sight` always scans the strip of
cells along the segment (:func:`pathfuse.geometry.strip_is_clear`, ``O(length)``
cells), with the same exact test per cell and the same edge rule as
:func:`pathfuse.geometry.segment_is_clear`, which does the same for any segment
whose bounding box holds more than 16 cells.

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

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC, strip_is_clear

__all__ = ["line_of_sight", "smooth_path"]


@njit(cache=True)
def line_of_sight(ax, ay, bx, by, occ, ox, oy, res, clear):
    """True when segment ``AB`` stays ``>= clear`` from every occupied square and inside the map,
    at least ``clear - MARGIN_FRAC * res`` (the robot's radius) from its edge.

    The same answer as :func:`pathfuse.geometry.segment_is_clear`, always visiting
    the strip of cells along the segment (:func:`pathfuse.geometry.strip_is_clear`).
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
    return strip_is_clear(ax, ay, bx, by, occ, ox, oy, res, clear)


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
