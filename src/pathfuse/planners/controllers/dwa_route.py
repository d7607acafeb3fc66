"""Path helpers of the Dynamic Window Approach's kernel (:mod:`.dwa_kernel`): the route's
direction at a path point, the robot's progress index along the path and the local goal.

Apart from the kernel so that it stays one readable module; :mod:`.dwa_kernel` re-exports
:func:`route_tangent` and :func:`dwa_progress`.

>>> import numpy as np
>>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
>>> route_tangent(pts, 1, 0.0)
(0.0, 1.0)
>>> int(dwa_progress(0.9, 0.8, pts, np.array([0.0, 1.0, 2.0]), 0, 5.0))
2
"""

from __future__ import annotations

import math

from numba import njit

from pathfuse.field.pathing import nearest_ahead

__all__ = ["dwa_progress", "route_tangent"]


@njit(cache=True, inline="always")
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def route_tangent(pts, k, th):
    """The unit direction of the path at its point ``k`` (the heading ``th`` where the path
    has no length there): the route against which a disc's passing side is told."""
    m = pts.shape[0]
    j = min(max(k, 0), m - 1)
    while j + 1 < m:
        tx = pts[j + 1, 0] - pts[j, 0]
        ty = pts[j + 1, 1] - pts[j, 1]
        n = math.hypot(tx, ty)
        if n > 1e-9:
            return tx / n, ty / n
        j += 1
    return math.cos(th), math.sin(th)


dwa_progress = nearest_ahead
"""The nearest path point to ``(x, y)`` among those from ``k`` up to ``reach_m`` of path
beyond it (never behind ``k``): :func:`pathfuse.field.pathing.nearest_ahead`."""


@njit(cache=True)
def _local_goal(pts, cum, k, look):
    """Index of the path point ``look`` metres of path beyond ``pts[k]`` (the last one)."""
    m = pts.shape[0]
    j = k
    while j + 1 < m and cum[j + 1] - cum[k] <= look:
        j += 1
    if j + 1 < m:
        j += 1
    return j
