"""Exact segment geometry against occupied grid squares (numba kernels).

Obstacle *regions* are the closed occupied cell squares of a map given as
``occ, ox, oy, res``: the boolean occupancy ``GridMap.occupied`` (row 0 at the
bottom, column along x), the world coordinates of the map's lower-left
corner and the cell side in metres.

* :func:`segment_box_distance` - exact distance between a segment and a
  closed axis-aligned box (0 when they intersect).
* :func:`segment_is_clear` - whether a straight move keeps at least
  ``clear`` from every occupied square *and* from the outside of the map; a
  disc of radius ``clear`` swept along the segment then touches nothing
  (touching at exactly ``clear`` is allowed).  With equal end points it
  tests a disc at rest.

Every planner and controller uses these two for its moves, the global
planner for its c-space snapping, and :class:`pathfuse.problem.Problem` for
the robot disc at the start and the goal.  The metrics and the simulated
world judge paths with independent code.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((5, 5), dtype=bool); occ[2, 3] = True   # the square [3, 4] x [2, 3]
>>> bool(segment_is_clear(0.5, 2.5, 2.9, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
True
>>> bool(segment_is_clear(0.5, 2.5, 3.1, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
False
>>> round(float(segment_box_distance(0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 3.0, 2.0)), 6)
1.414214
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["MARGIN_FRAC", "segment_box_distance", "segment_is_clear", "strip_is_clear",
           "point_box_distance", "point_segment_distance"]

#: Clearance every move keeps from occupied squares beyond the robot radius, in cells: a
#: safe robot never *touches* a square (the metrics count a touch as a collision).
MARGIN_FRAC = 1e-6


@njit(cache=True, inline="always")
def point_box_distance(px, py, x0, y0, x1, y1):
    """Distance from a point to the closed box ``[x0, x1] x [y0, y1]``."""
    dx = max(x0 - px, 0.0, px - x1)
    dy = max(y0 - py, 0.0, py - y1)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def point_segment_distance(px, py, ax, ay, bx, by):
    """Distance from a point to the closed segment ``AB``."""
    vx = bx - ax
    vy = by - ay
    l2 = vx * vx + vy * vy
    t = 0.0
    if l2 > 0.0:
        t = ((px - ax) * vx + (py - ay) * vy) / l2
        t = min(max(t, 0.0), 1.0)
    ex = px - (ax + t * vx)
    ey = py - (ay + t * vy)
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True, inline="always")
def _segment_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
    t0 = 0.0
    t1 = 1.0
    dx = bx - ax
    if dx == 0.0:
        if ax < x0 or ax > x1:
            return False
    else:
        ta = (x0 - ax) / dx
        tb = (x1 - ax) / dx
        if ta > tb:
            ta, tb = tb, ta
        t0 = max(t0, ta)
        t1 = min(t1, tb)
        if t0 > t1:
            return False
    dy = by - ay
    if dy == 0.0:
        if ay < y0 or ay > y1:
            return False
    else:
        ta = (y0 - ay) / dy
        tb = (y1 - ay) / dy
        if ta > tb:
            ta, tb = tb, ta
        t0 = max(t0, ta)
        t1 = min(t1, tb)
        if t0 > t1:
            return False
    return True


@njit(cache=True)
def segment_box_distance(ax, ay, bx, by, x0, y0, x1, y1):
    """Exact distance between segment ``AB`` and the closed box ``[x0,x1] x [y0,y1]``."""
    if _segment_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
        return 0.0
    d = min(point_box_distance(ax, ay, x0, y0, x1, y1), point_box_distance(bx, by, x0, y0, x1, y1))
    d = min(d, point_segment_distance(x0, y0, ax, ay, bx, by))
    d = min(d, point_segment_distance(x1, y0, ax, ay, bx, by))
    d = min(d, point_segment_distance(x0, y1, ax, ay, bx, by))
    d = min(d, point_segment_distance(x1, y1, ax, ay, bx, by))
    return d


@njit(cache=True)
def _cell_blocks(ax, ay, bx, by, x0, y0, res, clear):
    """Whether the square ``[x0, x0+res] x [y0, y0+res]`` is closer than ``clear`` to ``AB``."""
    # cheap exact rejection: missing the box grown by ``clear`` as a square means the
    # distance (to the box grown by a disc) is above ``clear``
    if not _segment_hits_box(ax, ay, bx, by, x0 - clear, y0 - clear, x0 + res + clear,
                             y0 + res + clear):
        return False
    return segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res) < clear


@njit(cache=True)
def strip_is_clear(ax, ay, bx, by, occ, ox, oy, res, clear):
    """Whether no occupied square is closer than ``clear`` to segment ``AB`` (the map's edge
    is not checked), visiting only a strip of cells along the segment.

    Column by column (row by row for a steep segment): the cells whose square
    can come within ``clear`` of the part of ``AB`` over that column, so
    ``O(length)`` cells where the bounding box holds ``O(length^2)``.  The
    strip reaches ``1e-7`` cell beyond ``clear``, so the rounding of its bounds
    never leaves out a square within ``clear``; the exact per-cell test decides.
    """
    h, w = occ.shape
    dx = bx - ax
    dy = by - ay
    pad = clear + 1e-7 * res  # a sliver more than needed: rounding never leaves a square out
    if abs(dx) >= abs(dy):
        # column by column: the segment's y over the column's x-range (grown by clear)
        lo_x = min(ax, bx)
        hi_x = max(ax, bx)
        c0 = max(int(math.floor((lo_x - pad - ox) / res)), 0)
        c1 = min(int(math.floor((hi_x + pad - ox) / res)), w - 1)
        for c in range(c0, c1 + 1):
            xa = max(ox + c * res - pad, lo_x)
            xb = min(ox + (c + 1) * res + pad, hi_x)
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
        r0 = max(int(math.floor((lo_y - pad - oy) / res)), 0)
        r1 = min(int(math.floor((hi_y + pad - oy) / res)), h - 1)
        for r in range(r0, r1 + 1):
            ya = max(oy + r * res - pad, lo_y)
            yb = min(oy + (r + 1) * res + pad, hi_y)
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
def segment_is_clear(ax, ay, bx, by, occ, ox, oy, res, clear):
    """True when segment ``AB`` stays ``>= clear`` from every occupied square and inside the
    map, at least ``clear - MARGIN_FRAC * res`` (the robot's radius) from its edge.

    The map's edge is not an obstacle: a robot may touch it (and a point robot may stand
    and move on it, the lower and left edges being part of the map), so the margin that
    keeps a robot from *touching* an occupied square is not kept from the edge.

    A short move scans the cells of its bounding box; a long, oblique segment (a box of
    more than 16 cells) only the strip of cells along it (:func:`strip_is_clear`), with
    the same exact test per cell, so the answer is the same.
    """
    h, w = occ.shape
    edge = max(clear - MARGIN_FRAC * res, 0.0)
    xmin = ox + edge
    ymin = oy + edge
    xmax = ox + w * res - edge
    ymax = oy + h * res - edge
    if not (xmin <= ax <= xmax and xmin <= bx <= xmax and ymin <= ay <= ymax
            and ymin <= by <= ymax):
        return False
    pad = clear + 1e-7 * res  # as strip_is_clear: rounding never leaves a square out
    c0 = max(int(math.floor((min(ax, bx) - pad - ox) / res)), 0)
    c1 = min(int(math.floor((max(ax, bx) + pad - ox) / res)), w - 1)
    r0 = max(int(math.floor((min(ay, by) - pad - oy) / res)), 0)
    r1 = min(int(math.floor((max(ay, by) + pad - oy) / res)), h - 1)
    if (c1 - c0 + 1) * (r1 - r0 + 1) > 16:
        return strip_is_clear(ax, ay, bx, by, occ, ox, oy, res, clear)
    for r in range(r0, r1 + 1):
        y0 = oy + r * res
        for c in range(c0, c1 + 1):
            if occ[r, c] and _cell_blocks(ax, ay, bx, by, ox + c * res, y0, res, clear):
                return False
    return True
