"""Exact continuous collision geometry for disc robots and disc obstacles.

Everything here works on *segments*: over one tick every body moves in a
straight line at constant speed, so a collision check over the whole tick is
a closed-form minimum distance, not a sample of end points.

* :func:`segment_static_distance` - the minimum distance from a moving point
  (a segment) to any occupied cell (an axis-aligned closed square) *or to the
  outside of the map*.  A disc of radius ``r`` swept along the segment
  overlaps a cell or leaves the map exactly when this distance is ``< r``.
  The distance from a segment to a square is exact
  (:func:`pathfuse.field.stepper.segment_box_distance`: zero when they
  intersect, else the least of the end-point-to-square and corner-to-segment
  distances).  Cells are visited ring by ring outwards from the
  segment's bounding box and the search stops once a ring is farther than the
  best distance so far (or ``cap``), so the cost does not depend on the
  number of obstacles in the map.
* :func:`disc_sweep_gaps` - for a robot moving ``p0 -> p1`` and ``K``
  obstacles moving ``q0[k] -> q1[k]`` during the same tick, the minimum over
  the tick of the distance between centres minus the sum of radii.  The
  relative position is linear in time, so the minimum is at
  ``t* = clip(-d0.dd / |dd|^2, 0, 1)``.

Overlap is strict: bodies that exactly touch (distance equal to the sum of
radii) do not collide.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((3, 3), dtype=np.bool_); occ[1, 1] = True   # square [1, 2] x [1, 2]
>>> d = segment_static_distance(occ, 0.0, 0.0, 1.0, 0.8, 1.3, 1.3, 0.8, 5.0)
>>> float(d)   # the segment cuts the square's corner: both end points are 0.2 m away
0.0
>>> round(float(segment_static_distance(occ, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 2.5, 5.0)), 6)
0.5
>>> gaps = disc_sweep_gaps(np.array([0.0, 0.0]), np.array([2.0, 0.0]), 0.2,
...                        np.array([[1.0, 1.0]]), np.array([[1.0, -1.0]]), np.array([0.3]))
>>> round(float(gaps[0]), 6)    # both cross (1, 0) at mid-tick
-0.5
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.geometry import segment_box_distance

__all__ = [
    "segment_static_distance",
    "disc_sweep_gaps",
    "point_segment_distance",
    "warmup_geometry",
]


@njit(cache=True)
def point_segment_distance(px: float, py: float, ax: float, ay: float, bx: float,
                           by: float) -> float:
    """Distance from point ``p`` to segment ``a-b`` (a point when ``a == b``).

    >>> point_segment_distance(1.0, 1.0, 0.0, 0.0, 2.0, 0.0)
    1.0
    """
    dx = bx - ax
    dy = by - ay
    l2 = dx * dx + dy * dy
    t = 0.0
    if l2 > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / l2
        t = min(1.0, max(0.0, t))
    ex = ax + t * dx - px
    ey = ay + t * dy - py
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def segment_static_distance(occ: np.ndarray, ox: float, oy: float, res: float, ax: float,
                            ay: float, bx: float, by: float, cap: float) -> float:
    """Minimum distance from segment ``a-b`` to an occupied cell or the map's outside.

    Parameters
    ----------
    occ : (H, W) bool array
        ``occupied[row, col]`` of a :class:`~pathfuse.grid.GridMap`.
    ox, oy, res : float
        The map's origin (lower-left corner) and cell side in metres.
    ax, ay, bx, by : float
        The segment's end points (metres).
    cap : float
        Search radius: the result is ``min(true distance, cap)``.  A collision
        check for a disc of radius ``r`` passes ``cap = r`` and tests ``< r``.

    Returns
    -------
    float
        0 when the segment touches an occupied square or leaves the map.
    """
    h, w = occ.shape
    xmin = ox
    ymin = oy
    xmax = ox + w * res
    ymax = oy + h * res
    best = cap
    # the map's outside: inside a rectangle, the distance to its boundary is
    # concave, so its minimum over the segment is at an end point
    for i in range(2):
        px = ax if i == 0 else bx
        py = ay if i == 0 else by
        de = min(px - xmin, xmax - px, py - ymin, ymax - py)
        if de <= 0.0:
            return 0.0
        if de < best:
            best = de
    c0 = int(math.floor((min(ax, bx) - ox) / res))
    c1 = int(math.floor((max(ax, bx) - ox) / res))
    r0 = int(math.floor((min(ay, by) - oy) / res))
    r1 = int(math.floor((max(ay, by) - oy) / res))
    c0 = min(max(c0, 0), w - 1)
    c1 = min(max(c1, 0), w - 1)
    r0 = min(max(r0, 0), h - 1)
    r1 = min(max(r1, 0), h - 1)
    k = 0
    while True:
        # every cell of ring k is at least (k - 1) cells away from the segment
        if k >= 1 and (k - 1) * res >= best:
            break
        if r0 - k < 0 and c0 - k < 0 and r1 + k >= h and c1 + k >= w:
            break
        for rr in range(r0 - k, r1 + k + 1):
            if rr < 0 or rr >= h:
                continue
            edge_row = rr == r0 - k or rr == r1 + k
            step = 1 if (edge_row or k == 0) else (c1 - c0 + 2 * k)
            cc = c0 - k
            while cc <= c1 + k:
                if 0 <= cc < w and occ[rr, cc]:
                    x0 = ox + cc * res
                    y0 = oy + rr * res
                    d = segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res)
                    if d < best:
                        best = d
                cc += step if step > 0 else 1
        k += 1
    return best


@njit(cache=True)
def disc_sweep_gaps(p0: np.ndarray, p1: np.ndarray, radius: float, q0: np.ndarray,
                    q1: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Minimum surface gap over a tick between a moving robot disc and ``K`` moving discs.

    Parameters
    ----------
    p0, p1 : (2,) float arrays
        Robot centre at the start and end of the tick.
    radius : float
        Robot radius.
    q0, q1 : (K, 2) float arrays
        Obstacle centres at the start and end of the tick.
    radii : (K,) float array
        Obstacle radii.

    Returns
    -------
    (K,) float array
        ``min_t |p(t) - q_k(t)| - radius - radii[k]``; negative means overlap.
    """
    n = q0.shape[0]
    out = np.empty(n)
    for k in range(n):
        d0x = p0[0] - q0[k, 0]
        d0y = p0[1] - q0[k, 1]
        ddx = (p1[0] - p0[0]) - (q1[k, 0] - q0[k, 0])
        ddy = (p1[1] - p0[1]) - (q1[k, 1] - q0[k, 1])
        l2 = ddx * ddx + ddy * ddy
        t = 0.0
        if l2 > 0.0:
            t = -(d0x * ddx + d0y * ddy) / l2
            t = min(1.0, max(0.0, t))
        ex = d0x + t * ddx
        ey = d0y + t * ddy
        out[k] = math.sqrt(ex * ex + ey * ey) - radius - radii[k]
    return out


def warmup_geometry() -> None:
    """Compile (or load from numba's cache) the kernels of this module.

    Both writeable and read-only arrays are used (``GridMap.occupied`` and the
    precomputed obstacle trajectories are read-only, a distinct numba type).
    """
    for ro in (False, True):
        occ = np.zeros((2, 2), dtype=np.bool_)
        occ[0, 0] = True
        q = np.zeros((1, 2))
        occ.setflags(write=not ro)
        q.setflags(write=not ro)
        segment_static_distance(occ, 0.0, 0.0, 1.0, 1.5, 1.5, 1.6, 1.2, 1.0)
        z = np.zeros(2)
        disc_sweep_gaps(z, z, 0.1, q, q, np.ones(1))
        disc_sweep_gaps(z, z, 0.1, q, np.zeros((1, 2)), np.ones(1))
