"""Progress along a global path and where to rejoin it after a stall (numba).

Whether a path point is in sight is asked of the :class:`~pathfuse.costmap.Costmap`
(``cm``): :func:`~pathfuse.costmap.move_clear` with the clearance ``clear``.

Examples
--------
>>> import numpy as np
>>> from pathfuse.costmap import make_costmap
>>> pts = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5]])
>>> polyline_cumlen(pts).tolist()
[0.0, 1.0, 2.0, 3.0]
>>> cm = make_costmap(np.zeros((2, 4), dtype=bool), 0.0, lattice=False)
>>> int(advance_progress(2.3, 0.6, pts, polyline_cumlen(pts), 0, 1.0, cm, 1e-6))
2
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.costmap import move_clear

__all__ = ["polyline_cumlen", "nearest_ahead", "advance_progress", "find_rejoin"]


@njit(cache=True)
def polyline_cumlen(pts):
    """Cumulative arc length of a polyline ``pts`` (M, 2): ``cum[0] = 0``, ``cum[-1]`` = length."""
    m = pts.shape[0]
    cum = np.zeros(m)
    for j in range(1, m):
        cum[j] = cum[j - 1] + math.hypot(pts[j, 0] - pts[j - 1, 0], pts[j, 1] - pts[j - 1, 1])
    return cum


@njit(cache=True)
def nearest_ahead(x, y, pts, cum, k, reach_m):
    """The path point nearest to ``(x, y)`` among ``pts[k]`` and those after it up to
    ``reach_m`` of path beyond it (the first of equals; never behind ``k``).

    >>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> int(nearest_ahead(1.9, 0.5, pts, polyline_cumlen(pts), 0, 5.0))
    2
    """
    m = pts.shape[0]
    best = k
    ex = x - pts[k, 0]
    ey = y - pts[k, 1]
    bd = ex * ex + ey * ey
    j = k + 1
    while j < m and cum[j] - cum[k] <= reach_m:
        ex = x - pts[j, 0]
        ey = y - pts[j, 1]
        d = ex * ex + ey * ey
        if d < bd:
            bd = d
            best = j
        j += 1
    return best


@njit(cache=True)
def advance_progress(x, y, pts, cum, k, r1_m, cm, clear):
    """Monotone progress index along a path: the nearest *visible* path point within reach.

    Searches the path points after ``k`` whose arc length beyond ``pts[k]`` is
    at most ``|X - pts[k]| + r1_m`` and returns the index of the nearest one
    that is closer than ``pts[k]`` and in sight (:func:`~pathfuse.costmap.move_clear`
    from ``X``); ``k`` if there is none.  Never decreases, and never jumps
    through a wall to a later part of the path that passes close by.
    """
    m = pts.shape[0]
    ex = x - pts[k, 0]
    ey = y - pts[k, 1]
    dk2 = ex * ex + ey * ey
    reach = math.sqrt(dk2) + r1_m
    # the nearest candidate first: usually the only one that needs a sight check
    best = nearest_ahead(x, y, pts, cum, k, reach)
    if best == k or move_clear(cm, x, y, pts[best, 0], pts[best, 1], clear):
        return best
    # the nearest one is out of sight: the nearest visible one
    best = k
    bd2 = dk2
    j = k + 1
    while j < m and cum[j] - cum[k] <= reach:
        ex = x - pts[j, 0]
        ey = y - pts[j, 1]
        d2 = ex * ex + ey * ey
        if d2 < bd2 and move_clear(cm, x, y, pts[j, 0], pts[j, 1], clear):
            bd2 = d2
            best = j
        j += 1
    return best


@njit(cache=True)
def find_rejoin(buf, n, pts, cum, rvis_m, window_m, cm, clear, kbuf, drive):
    """Where to rejoin the global path after a stall: a walked point and a path point.

    Over the walked points ``buf[i]`` and the path points ``pts[j]`` closer
    than ``rvis_m`` to them with a clear straight move between the two, picks
    the pair ``(i, j)`` that makes the rest of the route shortest:

    * ``drive`` false (planning, :func:`pathfuse.plan`): the walk after
      ``buf[i]`` is dropped from the plan, so the route is "the walk up to
      ``buf[i]``, straight to ``pts[j]``, the path to its end";
    * ``drive`` true (a robot that has to drive back, :func:`pathfuse.simulate`):
      "back along the walk from ``buf[n-1]`` to ``buf[i]``, straight to
      ``pts[j]``, the path to its end".

    First only the walked points at most ``window_m`` of walk back from
    ``buf[n-1]`` are searched, against the path points that can be within
    ``rvis_m`` of them.  If none of them sees a path point, the whole walk is
    searched, each walked point ``i`` against the path points from its
    progress index ``kbuf[i]`` on, within ``|buf[i] - pts[kbuf[i]]| + rvis_m``
    of arc length, so the cost stays proportional to the walk.  The start
    (``kbuf[0] = 0``) always sees the first path point when it lies in the
    same free cell.  Returns ``(i, j)``, or ``(-1, -1)`` when no walked point
    sees a path point.
    """
    m = pts.shape[0]
    x = buf[n - 1, 0]
    y = buf[n - 1, 1]
    lim = window_m + rvis_m
    near = np.empty(m, dtype=np.int64)
    nk = 0
    for j in range(m):
        dx = pts[j, 0] - x
        dy = pts[j, 1] - y
        if dx * dx + dy * dy <= lim * lim:
            near[nk] = j
            nk += 1
    r2 = rvis_m * rvis_m
    total = cum[m - 1]
    sign = 1.0 if drive else -1.0
    best = np.inf
    bi = -1
    bj = -1
    back = 0.0
    for i in range(n - 1, -1, -1):
        x = buf[i, 0]
        y = buf[i, 1]
        if i < n - 1:
            ex = x - buf[i + 1, 0]
            ey = y - buf[i + 1, 1]
            back += math.sqrt(ex * ex + ey * ey)
            if back > window_m:
                break
        for q in range(nk):
            j = near[q]
            dx = pts[j, 0] - x
            dy = pts[j, 1] - y
            d2 = dx * dx + dy * dy
            if d2 < r2:
                score = math.sqrt(d2) + (total - cum[j]) + sign * back
                if score < best and move_clear(cm, x, y, pts[j, 0], pts[j, 1], clear):
                    best = score
                    bi = i
                    bj = j
    if bi >= 0:
        return bi, bj
    walked_total = 0.0
    if drive:
        for i in range(1, n):
            ex = buf[i, 0] - buf[i - 1, 0]
            ey = buf[i, 1] - buf[i - 1, 1]
            walked_total += math.sqrt(ex * ex + ey * ey)
    walked = 0.0
    for i in range(n):
        x = buf[i, 0]
        y = buf[i, 1]
        if i > 0:
            ex = x - buf[i - 1, 0]
            ey = y - buf[i - 1, 1]
            walked += math.sqrt(ex * ex + ey * ey)
        cost_i = walked_total - walked if drive else walked
        k = kbuf[i]
        ex = x - pts[k, 0]
        ey = y - pts[k, 1]
        reach = math.sqrt(ex * ex + ey * ey) + rvis_m
        j = k
        while j < m and cum[j] - cum[k] <= reach:
            dx = pts[j, 0] - x
            dy = pts[j, 1] - y
            d2 = dx * dx + dy * dy
            if d2 < r2:
                score = cost_i + math.sqrt(d2) + (total - cum[j])
                if score < best and move_clear(cm, x, y, pts[j, 0], pts[j, 1], clear):
                    best = score
                    bi = i
                    bj = j
            j += 1
    return bi, bj
