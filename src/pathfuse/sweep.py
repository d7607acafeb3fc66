"""Exact continuous collision geometry of a disc robot over one tick: straight moves and arcs.

Over a tick a holonomic robot moves in a straight line, a diff-drive robot
along the arc of constant ``(v, omega)``; moving discs move in straight lines.

* :func:`segment_static_distance` - the minimum distance from a segment to
  any occupied cell (a closed square) *or to the outside of the map*, exact
  (ring search outwards, capped).
* :func:`disc_sweep_gaps` - the least surface gap over a tick between a
  linearly moving robot disc and ``K`` linearly moving discs, in closed form.
* :func:`unicycle_pose` - the exact pose after ``t`` seconds of constant
  ``(v, omega)`` (numerically stable for ``omega -> 0``).
* :func:`arc_static_distance` and :func:`arc_disc_gaps` - the same two
  checks for an arc, by chords with a provable bound: over a time piece of
  length ``h`` the arc leaves the chord (the linear interpolation in time of
  its end points) by at most ``|v omega| h^2 / 8`` (the interpolation error
  of a curve whose acceleration is ``|v omega|``).  A chord's exact distance
  minus that bound is a lower bound for the arc; pieces where the bound
  cannot decide against the threshold are halved until the bound is below
  ``1e-9`` m.  So the result is a lower bound of the true distance, exact
  at the threshold to 1e-9 m: a collision is never missed, and a clear arc
  is reported clear unless it passes within 1e-9 m of touching.

Overlap is strict: bodies that exactly touch do not collide.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((3, 3), dtype=np.bool_); occ[1, 1] = True   # square [1, 2] x [1, 2]
>>> float(segment_static_distance(occ, 0.0, 0.0, 1.0, 0.8, 1.3, 1.3, 0.8, 5.0))
0.0
>>> x, y, th = unicycle_pose(0.0, 0.0, 0.0, 1.0, np.pi / 2, 1.0)  # a quarter circle, R = 2/pi
>>> round(x, 9), round(y, 9), round(th, 9)
(0.636619772, 0.636619772, 1.570796327)
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
    "edge_distance",
    "segment_static_distance",
    "disc_sweep_gaps",
    "unicycle_pose",
    "arc_deviation_bound",
    "arc_static_distance",
    "arc_disc_gaps",
    "FINE_TOL_M",
    "warmup_segments",
    "warmup_sweep",
]

FINE_TOL_M = 1e-9
"""Arc pieces are halved until their chord bound is below this (where it matters)."""
_COARSE_TOL_M = 1e-4
_MAX_PIECES = 1 << 14


@njit(cache=True, inline="always")
def edge_distance(xmin: float, ymin: float, xmax: float, ymax: float, ax: float, ay: float,
                  bx: float, by: float, cap: float, edge_slack: float) -> float:
    """``min(cap, distance)`` from segment ``a-b`` to the outside of the rectangle
    ``[xmin, xmax] x [ymin, ymax]`` plus ``edge_slack`` (0 when an end lies outside, or on
    the edge without slack): inside a rectangle the distance to its boundary is concave, so
    its least over the segment is at an end point."""
    best = cap
    for i in range(2):
        px = ax if i == 0 else bx
        py = ay if i == 0 else by
        de = min(px - xmin, xmax - px, py - ymin, ymax - py)
        if de < 0.0 or (de == 0.0 and edge_slack == 0.0):
            return 0.0
        de += edge_slack
        if de < best:
            best = de
    return best


@njit(cache=True)
def segment_static_distance(occ: np.ndarray, ox: float, oy: float, res: float, ax: float,
                            ay: float, bx: float, by: float, cap: float,
                            edge_slack: float = 0.0) -> float:
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
    edge_slack : float
        Added to the distance to the map's outside (not to the squares), for a
        caller that keeps a margin from the squares but, like
        :func:`pathfuse.geometry.segment_is_clear`, only the radius from the
        edge (0 by default: the edge counts like a square).

    Returns
    -------
    float
        0 when the segment touches an occupied square or leaves the map.
    """
    h, w = occ.shape
    best = edge_distance(ox, oy, ox + w * res, oy + h * res, ax, ay, bx, by, cap, edge_slack)
    if best == 0.0:
        return 0.0
    c0 = int(math.floor((min(ax, bx) - ox) / res))
    c1 = int(math.floor((max(ax, bx) - ox) / res))
    r0 = int(math.floor((min(ay, by) - oy) / res))
    r1 = int(math.floor((max(ay, by) - oy) / res))
    c0 = min(max(c0, 0), w - 1)
    c1 = min(max(c1, 0), w - 1)
    r0 = min(max(r0, 0), h - 1)
    r1 = min(max(r1, 0), h - 1)
    sx0 = min(ax, bx)
    sx1 = max(ax, bx)
    sy0 = min(ay, by)
    sy1 = max(ay, by)
    tol = 1e-9 * (1.0 + abs(ax) + abs(ay) + abs(bx) + abs(by))  # far above rounding
    lim = best + tol + 1e-9 * best
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
                    # the square's gap to the segment's bounding box, a lower bound of its
                    # distance: beyond best by more than tol, the square cannot lower
                    # best, and its exact distance is left out (the same result)
                    gx = max(x0 - sx1, sx0 - (x0 + res), 0.0)
                    gy = max(y0 - sy1, sy0 - (y0 + res), 0.0)
                    if gx * gx + gy * gy <= lim * lim:
                        d = segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res)
                        if d < best:
                            best = d
                            lim = best + tol + 1e-9 * best
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


@njit(cache=True)
def unicycle_pose(x: float, y: float, th: float, v: float, w: float,
                  t: float) -> tuple[float, float, float]:
    """The pose after ``t`` s of constant ``(v, w)`` from ``(x, y, th)`` (exact arc).

    The chord has length ``2 v sin(w t / 2) / w`` and points along
    ``th + w t / 2``; the small-angle series keeps it exact to rounding as
    ``w -> 0``.
    """
    a = w * t
    if abs(a) < 1e-4:
        chord = v * t * (1.0 - a * a / 24.0)
    else:
        chord = 2.0 * v * math.sin(0.5 * a) / w
    mid = th + 0.5 * a
    return x + chord * math.cos(mid), y + chord * math.sin(mid), th + a


@njit(cache=True, inline="always")
def arc_deviation_bound(v: float, w: float, h: float) -> float:
    """How far an arc of ``(v, w)`` leaves its chord over ``h`` seconds: ``|v w| h^2 / 8``."""
    return abs(v * w) * h * h / 8.0


@njit(cache=True)
def _n_pieces(v: float, w: float, dt: float) -> int:
    e = arc_deviation_bound(v, w, dt)
    if e <= _COARSE_TOL_M:
        return 1
    n = int(math.ceil(math.sqrt(e / _COARSE_TOL_M)))
    return min(n, _MAX_PIECES)


@njit(cache=True)
def arc_static_distance(occ: np.ndarray, ox: float, oy: float, res: float, x: float, y: float,
                        th: float, v: float, w: float, dt: float, thr: float,
                        cap: float) -> float:
    """A lower bound of the distance from the arc of ``(v, w)`` over ``dt`` s to an occupied
    square or the map's outside, exact to 1e-9 m at ``thr`` (see the module docstring).

    ``min(result, cap)`` is returned; a straight move or a turn on the spot
    is exact (:func:`segment_static_distance`).
    """
    if v == 0.0 or w == 0.0:
        bx, by, _ = unicycle_pose(x, y, th, v, w, dt)
        return segment_static_distance(occ, ox, oy, res, x, y, bx, by, cap)
    n = _n_pieces(v, w, dt)
    h0 = dt / n
    stack_t = np.empty(64 + n)
    stack_h = np.empty(64 + n)
    top = 0
    for k in range(n - 1, -1, -1):
        stack_t[top] = k * h0
        stack_h[top] = h0
        top += 1
    best = cap
    while top > 0:
        top -= 1
        t0 = stack_t[top]
        h = stack_h[top]
        ax, ay, _ = unicycle_pose(x, y, th, v, w, t0)
        bx, by, _ = unicycle_pose(x, y, th, v, w, t0 + h)
        e = arc_deviation_bound(v, w, h)
        d = segment_static_distance(occ, ox, oy, res, ax, ay, bx, by, best + e)
        lb = d - e
        if lb >= best:
            continue
        if lb < thr <= d + e and e > FINE_TOL_M and top + 2 < stack_t.shape[0]:
            stack_t[top] = t0 + 0.5 * h
            stack_h[top] = 0.5 * h
            stack_t[top + 1] = t0
            stack_h[top + 1] = 0.5 * h
            top += 2
            continue
        best = max(lb, 0.0) if lb < best else best
    return best


@njit(cache=True)
def arc_disc_gaps(x: float, y: float, th: float, v: float, w: float, dt: float, radius: float,
                  q0: np.ndarray, q1: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Lower bounds of the least surface gaps over a tick between a robot disc on the arc of
    ``(v, w)`` and ``K`` discs moving linearly ``q0 -> q1``, exact to 1e-9 m at 0."""
    k = q0.shape[0]
    out = np.empty(k)
    bx, by, _ = unicycle_pose(x, y, th, v, w, dt)
    if v == 0.0 or w == 0.0 or k == 0:
        p0 = np.array([x, y])
        p1 = np.array([bx, by])
        return disc_sweep_gaps(p0, p1, radius, q0, q1, radii)
    n = _n_pieces(v, w, dt)
    h0 = dt / n
    pa = np.empty(2)
    pb = np.empty(2)
    qa = np.empty((1, 2))
    qb = np.empty((1, 2))
    rr = np.empty(1)
    stack_t = np.empty(64 + n)
    stack_h = np.empty(64 + n)
    for j in range(k):
        rr[0] = radii[j]
        top = 0
        for i in range(n - 1, -1, -1):
            stack_t[top] = i * h0
            stack_h[top] = h0
            top += 1
        best = np.inf
        while top > 0:
            top -= 1
            t0 = stack_t[top]
            h = stack_h[top]
            ax, ay, _ = unicycle_pose(x, y, th, v, w, t0)
            cx, cy, _ = unicycle_pose(x, y, th, v, w, t0 + h)
            pa[0], pa[1] = ax, ay
            pb[0], pb[1] = cx, cy
            fa = t0 / dt
            fb = (t0 + h) / dt
            qa[0, 0] = q0[j, 0] + fa * (q1[j, 0] - q0[j, 0])
            qa[0, 1] = q0[j, 1] + fa * (q1[j, 1] - q0[j, 1])
            qb[0, 0] = q0[j, 0] + fb * (q1[j, 0] - q0[j, 0])
            qb[0, 1] = q0[j, 1] + fb * (q1[j, 1] - q0[j, 1])
            g = disc_sweep_gaps(pa, pb, radius, qa, qb, rr)[0]
            e = arc_deviation_bound(v, w, h)
            lb = g - e
            if lb >= best:
                continue
            if lb < 0.0 <= g + e and e > FINE_TOL_M and top + 2 < stack_t.shape[0]:
                stack_t[top] = t0 + 0.5 * h
                stack_h[top] = 0.5 * h
                stack_t[top + 1] = t0
                stack_h[top + 1] = 0.5 * h
                top += 2
                continue
            best = lb
        out[j] = best
    return out


def _warm_inputs() -> list[tuple[np.ndarray, np.ndarray]]:
    """A tiny occupancy grid and disc positions, writeable and read-only
    (``GridMap.occupied`` and precomputed obstacle trajectories are read-only, a
    distinct numba type)."""
    out = []
    for ro in (False, True):
        occ = np.zeros((2, 2), dtype=np.bool_)
        occ[0, 0] = True
        q = np.zeros((1, 2))
        occ.setflags(write=not ro)
        q.setflags(write=not ro)
        out.append((occ, q))
    return out


def warmup_segments() -> None:
    """Compile (or load from numba's cache) the straight-segment kernels (a holonomic
    robot's ticks)."""
    for occ, q in _warm_inputs():
        segment_static_distance(occ, 0.0, 0.0, 1.0, 1.5, 1.5, 1.6, 1.2, 1.0)
        z = np.zeros(2)
        disc_sweep_gaps(z, z, 0.1, q, q, np.ones(1))
        disc_sweep_gaps(z, z, 0.1, q, np.zeros((1, 2)), np.ones(1))


def warmup_sweep() -> None:
    """Compile (or load from numba's cache) the segment and the arc kernels."""
    warmup_segments()
    for occ, q in _warm_inputs():
        arc_static_distance(occ, 0.0, 0.0, 1.0, 1.5, 1.5, 0.0, 0.1, 0.5, 0.1, 0.1, 1.0)
        arc_disc_gaps(0.0, 0.0, 0.0, 0.1, 0.5, 0.1, 0.1, q, q, np.ones(1))
