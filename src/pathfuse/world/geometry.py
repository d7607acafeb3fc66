"""Exact continuous collision geometry for disc robots and disc obstacles.

The two segment kernels live in :mod:`pathfuse.sweep` (a lower layer, so that
the controllers use them too, beside the arc checks of a diff-drive robot)
and are re-exported here under their old names.

Everything here works on *segments*: over one tick every body moves in a
straight line at constant speed, so a collision check over the whole tick is
a closed-form minimum distance, not a sample of end points.

* :func:`segment_static_distance` - the minimum distance from a moving point
  (a segment) to any occupied cell (an axis-aligned closed square) *or to the
  outside of the map*.  A disc of radius ``r`` swept along the segment
  overlaps a cell or leaves the map exactly when this distance is ``< r``.
  The distance from a segment to a square is exact
  (:func:`pathfuse.geometry.segment_box_distance`: zero when they
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

from numba import njit

from pathfuse.sweep import disc_sweep_gaps, segment_static_distance, warmup_segments

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


def warmup_geometry() -> None:
    """Compile (or load from numba's cache) the kernels of this module (writeable and
    read-only arrays: :func:`pathfuse.sweep.warmup_segments`)."""
    warmup_segments()
    point_segment_distance(1.0, 1.0, 0.0, 0.0, 2.0, 0.0)
