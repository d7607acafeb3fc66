"""Collision-free moves (numba): the safe step and the final move onto a goal.

A disc robot of radius ``r`` is safe at ``X`` when every occupied square is
at least ``clear = r + margin`` away from ``X`` and ``X`` is at least
``clear`` inside the map rectangle; ``margin`` is :data:`MARGIN_FRAC` times
the resolution, so a safe robot never *touches* an occupied square (the
independent check of :mod:`pathfuse.metrics` counts a touch as a collision).

The safe step
    The robot moves ``step`` metres along the unit force.  If that straight
    move is not clear, it *slides*: it tries the move's x-only and y-only
    components (the larger first; obstacles are axis-aligned squares, so
    this is sliding along the wall it hit), keeping their projected length.
    If neither is clear it shortens the move along the force to the longest
    clear fraction (bisection, 24 halvings).  If no move of at least
    ``1e-9`` of the step is clear the robot is *blocked* (:data:`HOW_BLOCKED`).
    So a controller built on :func:`safe_step` never collides: every segment
    it adds passed :func:`~pathfuse.costmap.move_clear`.

The map comes as a :class:`~pathfuse.costmap.Costmap` (``cm``); the clearance a
move keeps is an argument (``clear``: usually ``cm.clear_m``, more to keep a
safety margin).

Examples
--------
>>> import numpy as np
>>> from pathfuse.costmap import make_costmap
>>> occ = np.zeros((5, 5), dtype=bool); occ[2, 3] = True   # the square [3, 4] x [2, 3]
>>> cm = make_costmap(occ, 0.0, lattice=False)
>>> x, y, how = safe_step(2.95, 2.5, 1.0, 1.0, 0.1, cm, 1e-6)
>>> round(x, 4), round(y, 4), how   # the diagonal move is blocked: slide along y
(2.95, 2.5707, 2)
"""

from __future__ import annotations

import math

from numba import njit

from pathfuse.costmap import move_clear, point_distance
from pathfuse.geometry import MARGIN_FRAC

__all__ = [
    "MARGIN_FRAC",
    "safe_step_margin",
    "HOW_BLOCKED",
    "HOW_FULL",
    "HOW_SLIDE",
    "HOW_SHORT",
    "safe_step",
    "straight_move",
]

# safe_step outcomes
HOW_BLOCKED = 0
HOW_FULL = 1
HOW_SLIDE = 2
HOW_SHORT = 3


# inlined: a call per step that takes the Costmap cost the apf loop ~9 % of its steps/s
# on a 256 x 256 map (benchmarks/bench_stepping.py; docs/speed-log.md), and compiles no slower
@njit(cache=True, inline="always")
def safe_step(x, y, fx, fy, step, cm, clear):
    """One collision-free move of at most ``step`` along the force ``(fx, fy)``.

    Returns ``(x_new, y_new, how)`` with ``how`` one of :data:`HOW_FULL`,
    :data:`HOW_SLIDE`, :data:`HOW_SHORT` or :data:`HOW_BLOCKED` (no move; the
    position is returned unchanged).  A zero or non-finite force blocks.
    """
    fn2 = fx * fx + fy * fy
    if fn2 > 1e-300 and fn2 < 1e300:
        fn = math.sqrt(fn2)
    else:
        fn = math.hypot(fx, fy)
    if not (fn > 0.0) or not math.isfinite(fn):
        return x, y, HOW_BLOCKED
    ux = fx / fn
    uy = fy / fn
    tx = x + step * ux
    ty = y + step * uy
    if move_clear(cm, x, y, tx, ty, clear):
        return tx, ty, HOW_FULL
    tiny = 1e-9 * step
    sx = step * ux
    sy = step * uy
    for i in range(2):
        use_x = (abs(ux) >= abs(uy)) == (i == 0)
        if use_x:
            if abs(sx) > tiny and move_clear(cm, x, y, x + sx, y, clear):
                return x + sx, y, HOW_SLIDE
        else:
            if abs(sy) > tiny and move_clear(cm, x, y, x, y + sy, clear):
                return x, y + sy, HOW_SLIDE
    lo = 0.0
    hi = 1.0
    for _ in range(24):
        mid = 0.5 * (lo + hi)
        if move_clear(cm, x, y, x + mid * sx, y + mid * sy, clear):
            lo = mid
        else:
            hi = mid
    if lo * step > tiny:
        return x + lo * sx, y + lo * sy, HOW_SHORT
    return x, y, HOW_BLOCKED


@njit(cache=True)
def straight_move(x, y, tx, ty, step):
    """At most ``step`` straight towards ``(tx, ty)``, landing exactly on it when that is
    within the step (no sliver left by rounding).  Returns ``(x_new, y_new, landed)``."""
    d = math.hypot(tx - x, ty - y)
    if d <= step * (1.0 + 1e-9):
        return tx, ty, True
    return x + step * (tx - x) / d, y + step * (ty - y) / d, False


@njit(cache=True)
def safe_step_margin(x, y, fx, fy, step, cm, clear, margin):
    """:func:`safe_step` that keeps a soft safety ``margin`` beyond ``clear`` (ours).

    With ``margin > 0`` the move keeps the clearance ``clear + min(margin,
    gap)``, ``gap`` the robot's present gap beyond ``clear`` (exact), so a
    robot outside the margin stays outside and a robot inside it never gets
    closer; a move that cannot is blocked (the fusion then escapes along its
    global path, whose moves keep only ``clear``, so a passage narrower than
    the margin stays passable for it).  ``margin = 0`` is :func:`safe_step`
    itself.
    """
    if margin <= 0.0:
        return safe_step(x, y, fx, fy, step, cm, clear)
    d = point_distance(cm, x, y, clear + margin)
    hi = clear + min(margin, max(d - clear, 0.0)) * (1.0 - 1e-9)
    return safe_step(x, y, fx, fy, step, cm, max(hi, clear))
