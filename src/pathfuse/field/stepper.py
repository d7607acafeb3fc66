"""The numba stepping kernel shared by every potential-field planner.

Everything here is ``@njit(cache=True)`` and works on plain arrays, so other
planners (sub-goal APF, online planners with moving obstacles) can build on
the same pieces.  The map is passed as ``occ, ox, oy, res``: the boolean
occupancy ``GridMap.occupied`` (row 0 at the bottom, column along x), the
world coordinates of the lower-left map corner and the cell side in metres.

Geometry
    Obstacle *points* (for the forces of eq. 6) are the centres of the
    occupied cells.  Obstacle *regions* (for collisions) are the closed
    occupied cell squares.  A disc robot of radius ``r`` is safe at ``X`` when
    every occupied square is at least ``clear = r + margin`` away from ``X``
    and ``X`` is at least ``clear`` inside the map rectangle; ``margin`` is
    :data:`MARGIN_FRAC` times the resolution, so a safe robot never *touches*
    an occupied square (the independent check of :mod:`pathfuse.metrics` counts
    a touch as a collision).

Building blocks (pure functions)
    :func:`grid_repulsion` ``(x, y, occ, ox, oy, res, k_rep, rho0_m, radius_m)``
        sum of eq. 6 over the occupied cell centres within ``radius_m``
        (usually ``rho0_m``; the fusion planner's ``r2``) of ``(x, y)``.  It
        reads only the ``(2 radius / res + 1)^2`` cells around the robot, so its
        cost does not depend on the size of the map.
    :func:`apf_force` ``(x, y, gx, gy, k_att, k_rep, rho0_m, radius_m, occ, ox, oy, res)``
        the resultant of the goal's attraction (eq. 5) and :func:`grid_repulsion`.
    :func:`fusion_force`
        the resultant of Algorithm 2: goal, A* path points ahead within ``r1``
        (eq. 9), and repulsion within ``r2``.
    :func:`segment_is_clear` ``(ax, ay, bx, by, occ, ox, oy, res, clear)``
        exact test that a straight move keeps ``clear`` from every occupied square.
    :func:`safe_step` ``(x, y, fx, fy, step, occ, ox, oy, res, clear)``
        one collision-free move along a force (see below).

Batch loops
    :func:`apf_run` and :func:`fusion_run` step until the goal, a stall, a
    step cap, or ``n_stop`` points in the path buffer; they return so that
    the caller can check a wall-clock limit between chunks and call them again
    to resume (:func:`pathfuse.field.driver.drive` does this).  Their scalar
    settings travel in two small arrays built by :func:`pack_apf` /
    :func:`pack_fusion` (few arguments = little dispatch overhead).
    :func:`apf_solve` and :func:`fusion_solve` run a whole plan in one call
    when there is no time limit.

The safe step
    The robot moves ``step`` metres along the unit force.  If that straight
    move is not clear, it *slides*: it tries the move's x-only and y-only
    components (the larger first; obstacles are axis-aligned squares, so this
    is sliding along the wall it hit), keeping their projected length.  If
    neither is clear it shortens the move along the force to the longest clear
    fraction (bisection, 24 halvings).  If no move of at least ``1e-9`` of the
    step is clear the robot is *blocked* (:data:`HOW_BLOCKED`); the planners
    report that as ``LOCAL_MINIMUM``.  So a planner built on :func:`safe_step`
    never collides: every segment it adds passed :func:`segment_is_clear`.

Stall detection
    The batch loops stop with :data:`CODE_STALLED` when the robot's net
    displacement over the last ``stall_steps`` steps is below
    ``stall_distance_m`` (oscillation in a local minimum, or crawling).

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((5, 5), dtype=bool); occ[2, 3] = True   # one obstacle, centre (3.5, 2.5)
>>> fx, fy = grid_repulsion(2.5, 2.5, occ, 0.0, 0.0, 1.0, 5.0, 2.0, 2.0)
>>> round(fx, 6), round(fy, 6)   # 5 * (1/1 - 1/2) / 1 = 2.5 pointing to -x
(-2.5, 0.0)
>>> bool(segment_is_clear(0.5, 2.5, 2.9, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
True
>>> bool(segment_is_clear(0.5, 2.5, 3.1, 2.5, occ, 0.0, 0.0, 1.0, 1e-6))
False
>>> x, y, how = safe_step(2.95, 2.5, 1.0, 1.0, 0.1, occ, 0.0, 0.0, 1.0, 1e-6)
>>> round(x, 4), round(y, 4), how   # the diagonal move is blocked: slide along y
(2.95, 2.5707, 2)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.field.forces import D_MIN_M, att_force_xy

__all__ = [
    "MARGIN_FRAC",
    "HOW_BLOCKED",
    "HOW_FULL",
    "HOW_SLIDE",
    "HOW_SHORT",
    "CODE_RUNNING",
    "CODE_GOAL",
    "CODE_STALLED",
    "CODE_BLOCKED",
    "CODE_GOAL_SNAP",
    "AHEAD_PROGRESS",
    "AHEAD_PAPER_X",
    "grid_repulsion",
    "apf_force",
    "fusion_force",
    "segment_box_distance",
    "segment_is_clear",
    "safe_step",
    "advance_progress",
    "find_backoff",
    "apf_run",
    "fusion_run",
    "apf_solve",
    "fusion_solve",
    "pack_apf",
    "pack_fusion",
    "polyline_cumlen",
]

#: Clearance kept from occupied squares beyond the robot radius, in cells.
MARGIN_FRAC = 1e-6

# safe_step outcomes
HOW_BLOCKED = 0
HOW_FULL = 1
HOW_SLIDE = 2
HOW_SHORT = 3

# batch-loop outcomes
CODE_RUNNING = 0  # n_stop reached; call again to continue
CODE_GOAL = 1
CODE_STALLED = 2
CODE_BLOCKED = 3
CODE_GOAL_SNAP = 4  # goal reached by a final straight move onto it (not a force step)

# "ahead" rules of the fusion planner
AHEAD_PROGRESS = 0
AHEAD_PAPER_X = 1

# float config slots (pack_apf / pack_fusion)
F_GX, F_GY, F_KATT, F_KREP, F_RHO0, F_RADIUS, F_STEP, F_TOL = 0, 1, 2, 3, 4, 5, 6, 7
F_CLEAR, F_STALLD, F_OX, F_OY, F_RES, F_R1, F_BACKOFF = 8, 9, 10, 11, 12, 13, 14
N_F = 15
# int config slots
I_STALLN, I_AHEAD, I_ESCAPE, I_ESC_PTS = 0, 1, 2, 3
N_I = 4
# fusion state slots: progress index, mode (0 fusion, 1 escape), stall reference
# point index, escape exit index, escapes so far, escape target index, back-offs
S_K, S_MODE, S_REF, S_ESC_K, S_ESCAPES, S_T, S_BACKOFF = 0, 1, 2, 3, 4, 5, 6
N_S = 7


# --------------------------------------------------------------------- forces on a grid
@njit(cache=True)
def grid_repulsion(x, y, occ, ox, oy, res, k_rep, rho0_m, radius_m):
    """Sum of eq. 6 over occupied cell centres closer than ``radius_m`` to ``(x, y)``.

    Reads only the window of cells whose centres can be within ``radius_m``.
    """
    h, w = occ.shape
    rad = radius_m if radius_m < rho0_m else rho0_m
    if rad <= 0.0:
        return 0.0, 0.0
    c0 = int(math.ceil((x - rad - ox) / res - 0.5))
    c1 = int(math.floor((x + rad - ox) / res - 0.5))
    r0 = int(math.ceil((y - rad - oy) / res - 0.5))
    r1 = int(math.floor((y + rad - oy) / res - 0.5))
    c0 = max(c0, 0)
    r0 = max(r0, 0)
    c1 = min(c1, w - 1)
    r1 = min(r1, h - 1)
    fx = 0.0
    fy = 0.0
    rad2 = rad * rad
    inv_rho0 = 1.0 / rho0_m
    x0 = x - (ox + 0.5 * res)
    for r in range(r0, r1 + 1):
        dy = y - (oy + (r + 0.5) * res)
        dy2 = dy * dy
        for c in range(c0, c1 + 1):
            if occ[r, c]:
                dx = x0 - c * res
                d2 = dx * dx + dy2
                if d2 < rad2 and d2 > 0.0:
                    # eq. 6, as rep_force_xy, without the cost of hypot
                    d = math.sqrt(d2)
                    if d > D_MIN_M:
                        inv = 1.0 / d
                        m = k_rep * (inv - inv_rho0) * inv * inv * inv
                        fx += m * dx
                        fy += m * dy
                    else:
                        mag = k_rep * (1.0 / D_MIN_M - inv_rho0) / (D_MIN_M * D_MIN_M)
                        fx += mag * (dx / d)
                        fy += mag * (dy / d)
    return fx, fy


@njit(cache=True)
def apf_force(x, y, gx, gy, k_att, k_rep, rho0_m, radius_m, occ, ox, oy, res):
    """Resultant force of the plain APF at ``(x, y)``: eq. 5 to the goal plus eq. 6."""
    fx, fy = att_force_xy(x, y, gx, gy, k_att)
    rx, ry = grid_repulsion(x, y, occ, ox, oy, res, k_rep, rho0_m, radius_m)
    return fx + rx, fy + ry


@njit(cache=True)
def fusion_force(x, y, gx, gy, pts, cum, k, ahead, k_att, k_rep, rho0_m, r1_m, r2_m,
                 occ, ox, oy, res):
    """Resultant force of Algorithm 2 at ``(x, y)``.

    Attraction (eq. 5) of the goal plus of every path point ``pts[j]``
    strictly inside the circle of radius ``r1_m`` that is *ahead* (eq. 9):

    * ``ahead == AHEAD_PROGRESS``: ``j > k`` (``k`` from
      :func:`advance_progress`) and ``pts[j]`` within the reach window of
      :func:`advance_progress`; the same for any direction of travel.
    * ``ahead == AHEAD_PAPER_X``: the paper's eq. 8, ``x_p - x > 0``, over all
      path points.

    Repulsion: eq. 6 from every obstacle point closer than ``r2_m`` (and
    ``rho0_m``).  Returns ``(fx, fy, n_attractors)``.
    """
    fx, fy = att_force_xy(x, y, gx, gy, k_att)
    m = pts.shape[0]
    r1sq = r1_m * r1_m
    na = 0
    if ahead == AHEAD_PAPER_X:
        for j in range(m):
            px = pts[j, 0]
            py = pts[j, 1]
            if px - x > 0.0:
                dx = x - px
                dy = y - py
                if dx * dx + dy * dy < r1sq:
                    fx -= k_att * dx
                    fy -= k_att * dy
                    na += 1
    else:
        ex = x - pts[k, 0]
        ey = y - pts[k, 1]
        reach = math.sqrt(ex * ex + ey * ey) + r1_m
        j = k + 1
        while j < m and cum[j] - cum[k] <= reach:
            dx = x - pts[j, 0]
            dy = y - pts[j, 1]
            if dx * dx + dy * dy < r1sq:
                fx -= k_att * dx
                fy -= k_att * dy
                na += 1
            j += 1
    rx, ry = grid_repulsion(x, y, occ, ox, oy, res, k_rep, rho0_m, r2_m)
    return fx + rx, fy + ry, na


# --------------------------------------------------------------------- exact collision
@njit(cache=True, inline="always")
def _point_box(px, py, x0, y0, x1, y1):
    dx = max(x0 - px, 0.0, px - x1)
    dy = max(y0 - py, 0.0, py - y1)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def _point_segment(px, py, ax, ay, bx, by):
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
    d = min(_point_box(ax, ay, x0, y0, x1, y1), _point_box(bx, by, x0, y0, x1, y1))
    d = min(d, _point_segment(x0, y0, ax, ay, bx, by))
    d = min(d, _point_segment(x1, y0, ax, ay, bx, by))
    d = min(d, _point_segment(x0, y1, ax, ay, bx, by))
    d = min(d, _point_segment(x1, y1, ax, ay, bx, by))
    return d


@njit(cache=True)
def segment_is_clear(ax, ay, bx, by, occ, ox, oy, res, clear):
    """True when segment ``AB`` stays ``>= clear`` from every occupied square and the map edge."""
    h, w = occ.shape
    xmin = ox + clear
    ymin = oy + clear
    xmax = ox + w * res - clear
    ymax = oy + h * res - clear
    if not (xmin <= ax <= xmax and xmin <= bx <= xmax and ymin <= ay <= ymax
            and ymin <= by <= ymax):
        return False
    c0 = max(int(math.floor((min(ax, bx) - clear - ox) / res)), 0)
    c1 = min(int(math.floor((max(ax, bx) + clear - ox) / res)), w - 1)
    r0 = max(int(math.floor((min(ay, by) - clear - oy) / res)), 0)
    r1 = min(int(math.floor((max(ay, by) + clear - oy) / res)), h - 1)
    for r in range(r0, r1 + 1):
        y0 = oy + r * res
        for c in range(c0, c1 + 1):
            if occ[r, c]:
                x0 = ox + c * res
                # cheap exact rejection: missing the box grown by ``clear`` as a square
                # means the distance (to the box grown by a disc) is above ``clear``
                if not _segment_hits_box(ax, ay, bx, by, x0 - clear, y0 - clear,
                                         x0 + res + clear, y0 + res + clear):
                    continue
                if segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res) < clear:
                    return False
    return True


@njit(cache=True)
def safe_step(x, y, fx, fy, step, occ, ox, oy, res, clear):
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
    if segment_is_clear(x, y, tx, ty, occ, ox, oy, res, clear):
        return tx, ty, HOW_FULL
    tiny = 1e-9 * step
    sx = step * ux
    sy = step * uy
    for i in range(2):
        use_x = (abs(ux) >= abs(uy)) == (i == 0)
        if use_x:
            if abs(sx) > tiny and segment_is_clear(x, y, x + sx, y, occ, ox, oy, res, clear):
                return x + sx, y, HOW_SLIDE
        else:
            if abs(sy) > tiny and segment_is_clear(x, y, x, y + sy, occ, ox, oy, res, clear):
                return x, y + sy, HOW_SLIDE
    lo = 0.0
    hi = 1.0
    for _ in range(24):
        mid = 0.5 * (lo + hi)
        if segment_is_clear(x, y, x + mid * sx, y + mid * sy, occ, ox, oy, res, clear):
            lo = mid
        else:
            hi = mid
    if lo * step > tiny:
        return x + lo * sx, y + lo * sy, HOW_SHORT
    return x, y, HOW_BLOCKED


# --------------------------------------------------------------------- progress along a path
@njit(cache=True)
def polyline_cumlen(pts):
    """Cumulative arc length of a polyline ``pts`` (M, 2): ``cum[0] = 0``, ``cum[-1]`` = length."""
    m = pts.shape[0]
    cum = np.zeros(m)
    for j in range(1, m):
        cum[j] = cum[j - 1] + math.hypot(pts[j, 0] - pts[j - 1, 0], pts[j, 1] - pts[j - 1, 1])
    return cum


@njit(cache=True)
def advance_progress(x, y, pts, cum, k, r1_m, occ, ox, oy, res, clear):
    """Monotone progress index along a path: the nearest *visible* path point within reach.

    Searches the path points after ``k`` whose arc length beyond ``pts[k]`` is
    at most ``|X - pts[k]| + r1_m`` and returns the index of the nearest one
    that is closer than ``pts[k]`` and in sight (:func:`segment_is_clear`
    from ``X``); ``k`` if there is none.  Never decreases, and never jumps
    through a wall to a later part of the path that passes close by.
    """
    m = pts.shape[0]
    ex = x - pts[k, 0]
    ey = y - pts[k, 1]
    dk2 = ex * ex + ey * ey
    reach = math.sqrt(dk2) + r1_m
    # the nearest candidate first: usually the only one that needs a sight check
    best = k
    bd2 = dk2
    j = k + 1
    while j < m and cum[j] - cum[k] <= reach:
        ex = x - pts[j, 0]
        ey = y - pts[j, 1]
        d2 = ex * ex + ey * ey
        if d2 < bd2:
            bd2 = d2
            best = j
        j += 1
    if best == k or segment_is_clear(x, y, pts[best, 0], pts[best, 1], occ, ox, oy, res, clear):
        return best
    # the nearest one is out of sight: the nearest visible one
    best = k
    bd2 = dk2
    j = k + 1
    while j < m and cum[j] - cum[k] <= reach:
        ex = x - pts[j, 0]
        ey = y - pts[j, 1]
        d2 = ex * ex + ey * ey
        if d2 < bd2 and segment_is_clear(x, y, pts[j, 0], pts[j, 1], occ, ox, oy, res, clear):
            bd2 = d2
            best = j
        j += 1
    return best


@njit(cache=True)
def find_backoff(buf, n, pts, cum, rvis_m, window_m, occ, ox, oy, res, clear, kbuf):
    """Where to rejoin the global path after a stall: a walked point and a path point.

    Over the walked points ``buf[i]`` and the path points ``pts[j]`` closer
    than ``rvis_m`` to them with a clear straight move between the two, picks
    the pair that minimises the length of "walk to ``buf[i]``, go straight to
    ``pts[j]``, follow the path to its end".

    First only the walked points at most ``window_m`` of walk back from
    ``buf[n-1]`` are searched, against the path points that can be within
    ``rvis_m`` of them.  If none of them sees a path point, the whole walk is
    searched, each walked point ``i`` against the path points from its
    progress index ``kbuf[i]`` (:func:`advance_progress` at the time) on,
    within ``|buf[i] - pts[kbuf[i]]| + rvis_m`` of arc length, so the cost
    stays proportional to the walk.  The start (``kbuf[0] = 0``) always sees
    the first path point when it lies in the same free cell.  Returns
    ``(i, j)``, or ``(-1, -1)`` when no walked point sees a path point.
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
                score = math.sqrt(d2) + (total - cum[j]) - back
                if score < best and segment_is_clear(x, y, pts[j, 0], pts[j, 1], occ, ox, oy,
                                                     res, clear):
                    best = score
                    bi = i
                    bj = j
    if bi >= 0:
        return bi, bj
    walked = 0.0
    for i in range(n):
        x = buf[i, 0]
        y = buf[i, 1]
        if i > 0:
            ex = x - buf[i - 1, 0]
            ey = y - buf[i - 1, 1]
            walked += math.sqrt(ex * ex + ey * ey)
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
                score = walked + math.sqrt(d2) + (total - cum[j])
                if score < best and segment_is_clear(x, y, pts[j, 0], pts[j, 1], occ, ox, oy,
                                                     res, clear):
                    best = score
                    bi = i
                    bj = j
            j += 1
    return bi, bj


# --------------------------------------------------------------------- batch loops
def pack_apf(goal, k_att, k_rep, rho0_m, radius_m, step_m, tol_m, clear_m, stall_steps,
             stall_distance_m, ox, oy, res):
    """Float and int config arrays for :func:`apf_run`."""
    f = np.zeros(N_F)
    f[F_GX], f[F_GY] = float(goal[0]), float(goal[1])
    f[F_KATT], f[F_KREP], f[F_RHO0], f[F_RADIUS] = k_att, k_rep, rho0_m, radius_m
    f[F_STEP], f[F_TOL], f[F_CLEAR], f[F_STALLD] = step_m, tol_m, clear_m, stall_distance_m
    f[F_OX], f[F_OY], f[F_RES] = ox, oy, res
    i = np.zeros(N_I, dtype=np.int64)
    i[I_STALLN] = stall_steps
    return f, i


def pack_fusion(goal, k_att, k_rep, rho0_m, r1_m, r2_m, step_m, tol_m, clear_m, stall_steps,
                stall_distance_m, ox, oy, res, ahead, escape, escape_points, backoff_window_m):
    """Float and int config arrays for :func:`fusion_run` (``r2_m`` is the repulsion radius)."""
    f, i = pack_apf(goal, k_att, k_rep, rho0_m, r2_m, step_m, tol_m, clear_m, stall_steps,
                    stall_distance_m, ox, oy, res)
    f[F_R1] = r1_m
    f[F_BACKOFF] = backoff_window_m
    i[I_AHEAD] = ahead
    i[I_ESCAPE] = 1 if escape else 0
    i[I_ESC_PTS] = escape_points
    return f, i


@njit(cache=True)
def _goal_reached(buf, n, x, y, gx, gy, tol, occ, ox, oy, res, clear):
    """Goal test: append the goal when within ``tol`` and the move onto it is clear.

    Returns ``(n, code)``: :data:`CODE_RUNNING` (not reached), :data:`CODE_GOAL`
    (already exactly at the goal) or :data:`CODE_GOAL_SNAP` (goal appended).
    """
    ex = x - gx
    ey = y - gy
    if ex * ex + ey * ey <= tol * tol:
        if x == gx and y == gy:
            return n, CODE_GOAL
        if segment_is_clear(x, y, gx, gy, occ, ox, oy, res, clear):
            buf[n, 0] = gx
            buf[n, 1] = gy
            return n + 1, CODE_GOAL_SNAP
    return n, CODE_RUNNING


@njit(cache=True)
def apf_run(buf, n, n_stop, max_steps, occ, fcfg, icfg):
    """Plain APF steps from ``buf[n-1]``.

    ``buf`` (cap, 2) holds the path so far (``n`` points).  Runs until the
    goal, a stall, ``max_steps`` steps, or ``n == n_stop`` (``n_stop <= cap - 1``:
    one slot is kept for the goal).  Returns ``(n, code, steps)`` with ``code``
    one of :data:`CODE_RUNNING` (a limit was hit; call again to continue),
    :data:`CODE_GOAL` (the last step landed on the goal), :data:`CODE_GOAL_SNAP`
    (within tolerance: the goal was appended), :data:`CODE_STALLED`,
    :data:`CODE_BLOCKED`.  The goal test runs before every step and before
    returning :data:`CODE_RUNNING`.
    """
    gx = fcfg[F_GX]
    gy = fcfg[F_GY]
    k_att = fcfg[F_KATT]
    k_rep = fcfg[F_KREP]
    rho0 = fcfg[F_RHO0]
    radius = fcfg[F_RADIUS]
    step = fcfg[F_STEP]
    tol = fcfg[F_TOL]
    clear = fcfg[F_CLEAR]
    stall_d = fcfg[F_STALLD]
    ox = fcfg[F_OX]
    oy = fcfg[F_OY]
    res = fcfg[F_RES]
    stall_n = icfg[I_STALLN]
    x = buf[n - 1, 0]
    y = buf[n - 1, 1]
    steps = 0
    while True:
        n, done = _goal_reached(buf, n, x, y, gx, gy, tol, occ, ox, oy, res, clear)
        if done != CODE_RUNNING:
            return n, done, steps
        if n >= n_stop or steps >= max_steps:
            return n, CODE_RUNNING, steps
        fx, fy = apf_force(x, y, gx, gy, k_att, k_rep, rho0, radius, occ, ox, oy, res)
        nx, ny, how = safe_step(x, y, fx, fy, step, occ, ox, oy, res, clear)
        if how == HOW_BLOCKED:
            return n, CODE_BLOCKED, steps
        buf[n, 0] = nx
        buf[n, 1] = ny
        n += 1
        steps += 1
        x = nx
        y = ny
        if n - 1 >= stall_n:
            p = n - 1 - stall_n
            ex = x - buf[p, 0]
            ey = y - buf[p, 1]
            if ex * ex + ey * ey < stall_d * stall_d:
                return n, CODE_STALLED, steps


@njit(cache=True)
def fusion_run(buf, n, n_stop, max_steps, occ, pts, cum, state, fcfg, icfg, kbuf):
    """Algorithm 2 steps from ``buf[n-1]``; the protocol of :func:`apf_run` plus the A* path.

    ``pts`` (M, 2) are the global path points (ending at the goal), ``cum``
    (M,) their cumulative arc length, ``state`` an int64 array of :data:`N_S`
    slots carried between calls (all zero at the start), ``kbuf`` an int64
    array as long as ``buf`` that receives the progress index at each path
    point (``kbuf[0] = 0``; used by :func:`find_backoff`).

    Escape (``escape`` set in ``icfg``): when the robot stalls or is blocked it
    backs off along its own walk to the point from which it rejoins the path
    best (:func:`find_backoff` with ``rvis = r1 + res`` and the backoff window
    of ``fcfg``; the rest of the walk is dropped from the path), goes straight
    to the chosen path point, then
    follows the path points one by one until it has reached the point
    ``escape_points`` past its progress index at the stall; then Algorithm 2
    resumes.  Every move is still checked by :func:`segment_is_clear`.
    """
    gx = fcfg[F_GX]
    gy = fcfg[F_GY]
    k_att = fcfg[F_KATT]
    k_rep = fcfg[F_KREP]
    rho0 = fcfg[F_RHO0]
    r2 = fcfg[F_RADIUS]
    r1 = fcfg[F_R1]
    backoff_window = fcfg[F_BACKOFF]
    step = fcfg[F_STEP]
    tol = fcfg[F_TOL]
    clear = fcfg[F_CLEAR]
    stall_d = fcfg[F_STALLD]
    ox = fcfg[F_OX]
    oy = fcfg[F_OY]
    res = fcfg[F_RES]
    stall_n = icfg[I_STALLN]
    ahead = icfg[I_AHEAD]
    escape = icfg[I_ESCAPE]
    esc_pts = icfg[I_ESC_PTS]
    m = pts.shape[0]
    k = state[S_K]
    mode = state[S_MODE]
    ref = state[S_REF]
    esc_k = state[S_ESC_K]
    escapes = state[S_ESCAPES]
    t = state[S_T]
    backoff = state[S_BACKOFF]
    x = buf[n - 1, 0]
    y = buf[n - 1, 1]
    code = CODE_RUNNING
    steps = 0
    while True:
        n, done = _goal_reached(buf, n, x, y, gx, gy, tol, occ, ox, oy, res, clear)
        if done != CODE_RUNNING:
            code = done
            break
        if n >= n_stop or steps >= max_steps:
            break
        stalled = False
        blocked = False
        if mode == 0:
            k = advance_progress(x, y, pts, cum, k, r1, occ, ox, oy, res, clear)
            fx, fy, _ = fusion_force(x, y, gx, gy, pts, cum, k, ahead, k_att, k_rep, rho0,
                                     r1, r2, occ, ox, oy, res)
            nx, ny, how = safe_step(x, y, fx, fy, step, occ, ox, oy, res, clear)
            if how == HOW_BLOCKED:
                blocked = True
            else:
                buf[n, 0] = nx
                buf[n, 1] = ny
                kbuf[n] = k
                n += 1
                steps += 1
                x = nx
                y = ny
                if n - 1 - ref >= stall_n:
                    p = n - 1 - stall_n
                    ex = x - buf[p, 0]
                    ey = y - buf[p, 1]
                    stalled = ex * ex + ey * ey < stall_d * stall_d
        else:
            # escape: straight moves of at most one step towards pts[t]
            tx = pts[t, 0]
            ty = pts[t, 1]
            d = math.hypot(tx - x, ty - y)
            if d == 0.0:
                # already there (no move): take the next target
                if t > k:
                    k = t
                if t >= esc_k or t >= m - 1:
                    mode = 0
                    ref = n - 1
                else:
                    t += 1
                continue
            if d <= step * (1.0 + 1e-9):  # land exactly (no sliver step left by rounding)
                nx = tx
                ny = ty
            else:
                nx = x + step * (tx - x) / d
                ny = y + step * (ty - y) / d
            if segment_is_clear(x, y, nx, ny, occ, ox, oy, res, clear):
                buf[n, 0] = nx
                buf[n, 1] = ny
                kbuf[n] = k
                n += 1
                steps += 1
                x = nx
                y = ny
                if x == tx and y == ty:
                    if t > k:
                        k = t
                    if t >= esc_k or t >= m - 1:
                        mode = 0
                        ref = n - 1
                    else:
                        t += 1
            else:
                mode = 0
                ref = n - 1
        if stalled or blocked:
            i = -1
            j = -1
            if escape == 1:
                i, j = find_backoff(buf, n, pts, cum, r1 + res, backoff_window, occ, ox, oy, res,
                                    clear, kbuf)
            if i < 0:
                code = CODE_BLOCKED if blocked else CODE_STALLED
                break
            escapes += 1
            backoff += n - 1 - i
            n = i + 1
            x = buf[i, 0]
            y = buf[i, 1]
            mode = 1
            t = j
            esc_k = min(max(k, j) + esc_pts, m - 1)
            ref = n - 1
    state[S_K] = k
    state[S_MODE] = mode
    state[S_REF] = ref
    state[S_ESC_K] = esc_k
    state[S_ESCAPES] = escapes
    state[S_T] = t
    state[S_BACKOFF] = backoff
    return n, code, steps


# --------------------------------------------------------------------- one-call solvers
@njit(cache=True)
def apf_solve(occ, sx, sy, gx, gy, fcfg_template, icfg, max_steps):
    """:func:`apf_run` from ``(sx, sy)`` to the goal ``(gx, gy)`` in one call, no time limit.

    Allocates and grows the path buffer itself.  Returns ``(path, code,
    steps)`` with ``code`` as :func:`apf_run` (:data:`CODE_RUNNING` means the
    ``max_steps`` cap was reached).
    """
    fcfg = fcfg_template.copy()
    fcfg[F_GX] = gx
    fcfg[F_GY] = gy
    cap = min(max_steps, 1022) + 2
    buf = np.empty((cap, 2))
    buf[0, 0] = sx
    buf[0, 1] = sy
    n = 1
    total = 0
    while True:
        n, code, steps = apf_run(buf, n, cap - 1, max_steps - total, occ, fcfg, icfg)
        total += steps
        if code != CODE_RUNNING or total >= max_steps:
            break
        nb = np.empty((2 * cap, 2))
        nb[:n] = buf[:n]
        buf = nb
        cap *= 2
    return buf[:n].copy(), code, total


@njit(cache=True)
def fusion_solve(occ, sx, sy, gx, gy, global_path, fcfg_template, icfg, max_steps):
    """:func:`fusion_run` in one call, no time limit (the fast path of the fusion planner).

    ``global_path`` (M, 2) is the A* path; the goal is appended when it does
    not end there.  Returns ``(path, code, steps, state)``.
    """
    m = global_path.shape[0]
    if m > 0 and global_path[m - 1, 0] == gx and global_path[m - 1, 1] == gy:
        pts = np.ascontiguousarray(global_path)
    else:
        pts = np.empty((m + 1, 2))
        pts[:m] = global_path
        pts[m, 0] = gx
        pts[m, 1] = gy
    cum = polyline_cumlen(pts)
    state = np.zeros(N_S, dtype=np.int64)
    fcfg = fcfg_template.copy()
    fcfg[F_GX] = gx
    fcfg[F_GY] = gy
    # room for about twice the global path's length in steps; grown when needed
    est = int(2.0 * cum[cum.shape[0] - 1] / fcfg[F_STEP]) + 64
    cap = min(max_steps, est, 1 << 20) + 2
    buf = np.empty((cap, 2))
    kbuf = np.empty(cap, dtype=np.int64)
    buf[0, 0] = sx
    buf[0, 1] = sy
    kbuf[0] = 0
    n = 1
    total = 0
    while True:
        n, code, steps = fusion_run(buf, n, cap - 1, max_steps - total, occ, pts, cum, state,
                                    fcfg, icfg, kbuf)
        total += steps
        if code != CODE_RUNNING or total >= max_steps:
            break
        nb = np.empty((2 * cap, 2))
        nb[:n] = buf[:n]
        buf = nb
        nk = np.empty(2 * cap, dtype=np.int64)
        nk[:n] = kbuf[:n]
        kbuf = nk
        cap *= 2
    return buf[:n].copy(), code, total, state
