"""The safety shield: every command checked against a stop the robot can really make.

A controller proposes a command; the shield lets it through only when the
robot, after executing it for one tick, could still come to rest without
touching the static map, by a stop it can really perform in the world's
terms: one constant command per tick, each inside the window the
acceleration limits reach from the last one.

The stop (:func:`unicycle_stop_clear`, :func:`holonomic_stop_clear`)
    Diff-drive: each tick the linear speed moves towards 0 by ``a dt`` and
    the yaw rate towards 0 by ``alpha dt`` (both at their limits), and the
    robot follows the exact arc of that tick's ``(v, omega)``
    (:func:`~pathfuse.sweep.unicycle_pose`, the world's own integration),
    until ``v = 0``; from there it only turns on the spot, which a disc
    footprint survives.  Holonomic: the velocity vector shrinks by ``a dt``
    per tick along a straight line (at once without an acceleration limit).
    Each tick's sweep is checked exactly against the occupied squares and the
    map's edge of the :class:`~pathfuse.costmap.Costmap`
    (:func:`~pathfuse.costmap.arc_distance`, which never misses a contact),
    keeping its ``clear_m`` (the radius plus a millionth of a cell).

The choice (:func:`shield_unicycle`, :func:`shield_holonomic`)
    1. the controller's command, clipped to the window as the world clips it,
       if its stop is clear;
    2. otherwise the nearest command of the window (a grid of ``nv x nw``
       samples, nearest first in units of the window's half-widths) whose
       stop is clear;
    3. otherwise the emergency stop, the first tick of the stop above.

Why this is safe (by induction): if the command accepted at tick ``t`` has a
clear stop, then at ``t + 1`` the emergency stop *is* that stop's first tick
followed by the rest of it, computed with the same floating-point operations
the world uses, so it is clear too; the shield therefore always has a clear
command, and a robot that starts clear never touches the static map.
``tests/test_shield.py`` checks it with hypothesis against a brute-force
simulation of the unicycle, with random and adversarial controllers.

Moving discs (*passive safety*: the robot is at rest whenever a disc reaches it)
    A disc may turn at any moment but not go faster than its speed bound
    ``dspeed`` (the caller's: :meth:`Controller.command
    <pathfuse.planners.base.Controller.command>` passes the fastest speed it
    has observed for that disc), so at time ``t`` it lies within ``dspeed t``
    of where it is now.  A command is preferred when, while the robot moves
    (the command's tick and its stop), it keeps a gap of at least
    ``disc_margin`` to those growing discs: then, whatever the discs do
    within their bounds, the robot is standing still before any can touch it.
    If no statically clear command achieves that, the statically clear one
    with the largest such gap is taken (evade).  A disc may still walk into a
    robot standing still: a contact while the robot moves is the robot's
    fault, and the benchmarks count those apart.

The return code says what happened: :data:`ASKED` (the command passed),
:data:`NEAREST` (replaced by a nearby safe command), :data:`EMERGENCY` (the
emergency stop), :data:`UNSAFE` (no clear command exists: the robot started
too close, or a disc pushed it there; the emergency stop is returned) and
:data:`EVADE` (statically safe, but a predicted disc contact could not be
avoided; the command with the largest predicted gap).

The static map and the robot's disc come as one :class:`~pathfuse.costmap.Costmap`
(``clear_m`` is kept from the squares, ``radius_m`` from the moving discs), the
moving discs as one :class:`~pathfuse.costmap.Discs`.

Examples
--------
>>> import numpy as np
>>> from pathfuse.costmap import NO_DISCS, make_costmap
>>> occ = np.zeros((10, 10), dtype=np.bool_); occ[:, 6] = True   # a wall at x = 6
>>> cm = make_costmap(occ, 0.3, clear_m=0.3)
>>> # 1 m/s, 1 m/s^2, dt 0.5, radius 0.3, at x = 5 heading for the wall at full speed:
>>> # a full-speed tick and the stop after it would end 0.05 m inside the wall
>>> bool(unicycle_stop_clear(cm, 5.0, 5.0, 0.0, 1.0, 0.0, 0.5, 1.0, 4.0, 0.3))
False
>>> v, w, code = shield_unicycle(cm, 5.0, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0,
...                              0.5, 0.0, 1.0, 1.0, 2.0, 4.0, NO_DISCS, 0.0, NV, NW)
>>> round(v, 6), round(w, 6), CODE_NAMES[code]   # the nearest command that can still stop
(0.916667, 0.0, 'nearest')
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.costmap import Costmap, Discs, arc_distance, point_distance, segment_distance
from pathfuse.sweep import arc_disc_gaps, disc_sweep_gaps, unicycle_pose

__all__ = [
    "ASKED", "NEAREST", "EMERGENCY", "UNSAFE", "EVADE", "CODE_NAMES",
    "clip_unicycle", "clip_holonomic", "unicycle_stop_clear", "holonomic_stop_clear",
    "unicycle_stop_disc_gap", "holonomic_stop_disc_gap", "shield_unicycle",
    "shield_holonomic", "warmup_shield", "MAX_STOP_TICKS",
]

ASKED = 0
NEAREST = 1
EMERGENCY = 2
UNSAFE = 3
EVADE = 4
CODE_NAMES = ("asked", "nearest", "emergency", "unsafe", "evade")
NV, NW = 7, 9
"""The diff-drive window's samples: ``nv`` speeds x ``nw`` yaw rates (:func:`shield_unicycle`)."""
ND = 12
"""The holonomic shield's directions (:func:`shield_holonomic`).  Callers on the tick path
pass ``NV, NW`` and ``ND`` explicitly: an omitted argument sends every call through
numba's slow dispatch (the compiled version is looked up in Python, about 0.1-1 ms)."""
"""The name of each return code."""

MAX_STOP_TICKS = 100_000
"""A stop longer than this many ticks counts as not clear (a budget: every loop ends)."""


@njit(cache=True, inline="always")
def _toward_zero(v: float, step: float) -> float:
    if v > 0.0:
        return max(v - step, 0.0)
    if v < 0.0:
        return min(v + step, 0.0)
    return 0.0


@njit(cache=True)
def clip_unicycle(v0: float, w0: float, v: float, w: float, dt: float, vmin: float,
                  vmax: float, amax: float, wmax: float, alpha: float) -> tuple[float, float]:
    """``(v, w)`` clipped to the speed limits and the window the acceleration limits reach
    from ``(v0, w0)`` in ``dt`` (what the world applies)."""
    lo = max(vmin, v0 - amax * dt)
    hi = min(vmax, v0 + amax * dt)
    wlo = max(-wmax, w0 - alpha * dt)
    whi = min(wmax, w0 + alpha * dt)
    return min(max(v, lo), hi), min(max(w, wlo), whi)


@njit(cache=True)
def clip_holonomic(ux0: float, uy0: float, ux: float, uy: float, dt: float, vmax: float,
                   amax: float) -> tuple[float, float]:
    """The velocity ``(ux, uy)`` clipped to the speed limit (direction kept) and its change
    from ``(ux0, uy0)`` to ``amax dt`` (what the world applies)."""
    s = math.sqrt(ux * ux + uy * uy)
    if s > vmax:
        ux = ux * (vmax / s)
        uy = uy * (vmax / s)
    if math.isfinite(amax):
        dx = ux - ux0
        dy = uy - uy0
        lim = amax * dt
        n = math.sqrt(dx * dx + dy * dy)
        if n > lim * (1.0 + 1e-9):  # beyond rounding
            ux = ux0 + dx * (lim / n)
            uy = uy0 + dy * (lim / n)
    return ux, uy


@njit(cache=True)
def _stop_ticks(v: float, amax: float, dt: float) -> int:
    if not math.isfinite(amax):
        return 2
    n = abs(v) / (amax * dt)
    if not n < MAX_STOP_TICKS:
        return MAX_STOP_TICKS
    return int(math.ceil(n)) + 3


@njit(cache=True)
def unicycle_stop_clear(cm: Costmap, x: float, y: float, th: float, v: float, w: float,
                        dt: float, amax: float, alpha: float, clear: float) -> bool:
    """Whether ``(v, w)`` for one tick from ``(x, y, th)``, then the stop (see the module
    docstring), keeps the disc ``clear`` from every occupied square and the map's edge."""
    n = _stop_ticks(v, amax, dt)
    for _ in range(n):
        d = arc_distance(cm, x, y, th, v, w, dt, clear, clear)
        if d < clear:
            return False
        if v == 0.0:
            return True
        x, y, th = unicycle_pose(x, y, th, v, w, dt)
        v = _toward_zero(v, amax * dt)
        w = _toward_zero(w, alpha * dt)
    return False


@njit(cache=True)
def holonomic_stop_clear(cm: Costmap, x: float, y: float, ux: float, uy: float, dt: float,
                         amax: float, clear: float) -> bool:
    """Whether the velocity ``(ux, uy)`` for one tick, then a straight stop shrinking it by
    ``amax dt`` per tick, keeps the disc ``clear`` from the static map."""
    s = math.sqrt(ux * ux + uy * uy)
    n = _stop_ticks(s, amax, dt)
    for _ in range(n):
        bx = x + ux * dt
        by = y + uy * dt
        if segment_distance(cm, x, y, bx, by, clear) < clear:
            return False
        if s == 0.0:
            return True
        x, y = bx, by
        ns = _toward_zero(s, amax * dt)
        ux = ux * (ns / s)
        uy = uy * (ns / s)
        s = ns
    return False


@njit(cache=True)
def unicycle_stop_disc_gap(x: float, y: float, th: float, v: float, w: float, dt: float,
                           amax: float, alpha: float, radius: float, discs: Discs) -> float:
    """The least gap, while the robot moves over the command's tick and its stop, to the
    places the discs can reach: disc ``i`` anywhere within ``speed_bound_mps[i] t`` of where
    it is now (``inf`` without discs or when the robot does not move)."""
    dpos = discs.pos_m
    dspeed = discs.speed_bound_mps
    drad = discs.radius_m
    best = np.inf
    if dpos.shape[0] == 0:
        return best
    n = _stop_ticks(v, amax, dt)
    reach = np.empty(drad.shape[0])
    for k in range(n):
        if v == 0.0:
            break
        for i in range(drad.shape[0]):
            reach[i] = drad[i] + dspeed[i] * ((k + 1) * dt)
        m = arc_disc_gaps(x, y, th, v, w, dt, radius, dpos, dpos, reach).min()
        if m < best:
            best = m
        x, y, th = unicycle_pose(x, y, th, v, w, dt)
        v = _toward_zero(v, amax * dt)
        w = _toward_zero(w, alpha * dt)
    return best


@njit(cache=True)
def holonomic_stop_disc_gap(x: float, y: float, ux: float, uy: float, dt: float, amax: float,
                            radius: float, discs: Discs) -> float:
    """As :func:`unicycle_stop_disc_gap` for the holonomic robot's straight stop."""
    dpos = discs.pos_m
    dspeed = discs.speed_bound_mps
    drad = discs.radius_m
    best = np.inf
    if dpos.shape[0] == 0:
        return best
    s = math.sqrt(ux * ux + uy * uy)
    n = _stop_ticks(s, amax, dt)
    p0 = np.empty(2)
    p1 = np.empty(2)
    reach = np.empty(drad.shape[0])
    for k in range(n):
        if s == 0.0:
            break
        for i in range(drad.shape[0]):
            reach[i] = drad[i] + dspeed[i] * ((k + 1) * dt)
        p0[0], p0[1] = x, y
        x = x + ux * dt
        y = y + uy * dt
        p1[0], p1[1] = x, y
        m = disc_sweep_gaps(p0, p1, radius, dpos, dpos, reach).min()
        if m < best:
            best = m
        ns = _toward_zero(s, amax * dt)
        ux = ux * (ns / s)
        uy = uy * (ns / s)
        s = ns
    return best


@njit(cache=True)
def _here_clear(cm, x, y, clear):
    """``clear``, or the present clearance when the robot is already closer (it may keep
    what it has, never come closer)."""
    d = point_distance(cm, x, y, clear)
    if d < clear:
        return d * (1.0 - 1e-12)
    return clear


@njit(cache=True)
def shield_unicycle(cm: Costmap, x: float, y: float, th: float, v0: float, w0: float,
                    v: float, w: float, dt: float, vmin: float, vmax: float, amax: float,
                    wmax: float, alpha: float, discs: Discs, disc_margin: float,
                    nv: int = NV, nw: int = NW) -> tuple[float, float, int]:
    """The shielded diff-drive command ``(v, w, code)`` (see the module docstring).

    ``cm`` is the static map with the robot's clearance ``cm.clear_m`` to keep
    (the radius plus a hair) and its disc ``cm.radius_m`` for the moving discs'
    gaps; ``(x, y, th)`` the pose, ``(v0, w0)`` the last applied command,
    ``(v, w)`` the controller's; ``discs`` the sensed discs (centres, speed
    bounds and radii are read).
    """
    radius = cm.radius_m
    dpos = discs.pos_m
    clear = _here_clear(cm, x, y, cm.clear_m)
    v, w = clip_unicycle(v0, w0, v, w, dt, vmin, vmax, amax, wmax, alpha)
    nd = dpos.shape[0]
    if unicycle_stop_clear(cm, x, y, th, v, w, dt, amax, alpha, clear):
        if nd == 0:
            return v, w, ASKED
        g = unicycle_stop_disc_gap(x, y, th, v, w, dt, amax, alpha, radius, discs)
        if g >= disc_margin:
            return v, w, ASKED
        best_g, best_v, best_w = g, v, w
    else:
        best_g, best_v, best_w = -np.inf, 0.0, 0.0
    found = best_g > -np.inf
    lo = max(vmin, v0 - amax * dt)
    hi = min(vmax, v0 + amax * dt)
    wlo = max(-wmax, w0 - alpha * dt)
    whi = min(wmax, w0 + alpha * dt)
    ve = min(max(_toward_zero(v0, amax * dt), lo), hi)
    we = min(max(_toward_zero(w0, alpha * dt), wlo), whi)
    # the window's samples, nearest to the asked command first; the emergency stop last
    m = nv * nw
    cv = np.empty(m + 1)
    cw = np.empty(m + 1)
    key = np.empty(m + 1)
    sv = max(hi - lo, 1e-12)
    sw = max(whi - wlo, 1e-12)
    for i in range(nv):
        vi = lo + (hi - lo) * (i / (nv - 1)) if nv > 1 else lo
        for j in range(nw):
            wj = wlo + (whi - wlo) * (j / (nw - 1)) if nw > 1 else wlo
            k = i * nw + j
            vi, wj = clip_unicycle(v0, w0, vi, wj, dt, vmin, vmax, amax, wmax, alpha)
            cv[k] = vi
            cw[k] = wj
            key[k] = ((vi - v) / sv) ** 2 + ((wj - w) / sw) ** 2
    cv[m] = ve
    cw[m] = we
    key[m] = np.inf
    order = np.argsort(key)
    for kk in range(m + 1):
        k = order[kk]
        vk = cv[k]
        wk = cw[k]
        if not unicycle_stop_clear(cm, x, y, th, vk, wk, dt, amax, alpha, clear):
            continue
        code = EMERGENCY if k == m else NEAREST
        if nd == 0:
            return vk, wk, code
        g = unicycle_stop_disc_gap(x, y, th, vk, wk, dt, amax, alpha, radius, discs)
        if g >= disc_margin:
            return vk, wk, code
        if not found or g > best_g:
            best_g, best_v, best_w = g, vk, wk
            found = True
    if found:
        return best_v, best_w, EVADE
    return ve, we, UNSAFE


@njit(cache=True)
def shield_holonomic(cm: Costmap, x: float, y: float, ux0: float, uy0: float, ux: float,
                     uy: float, dt: float, vmax: float, amax: float, discs: Discs,
                     disc_margin: float, nd: int = ND) -> tuple[float, float, int]:
    """The shielded holonomic velocity ``(ux, uy, code)``: the asked velocity, else the
    nearest of ``nd`` directions x 4 speeds (each clipped as the world clips), else the
    emergency stop (see the module docstring and :func:`shield_unicycle`)."""
    radius = cm.radius_m
    dpos = discs.pos_m
    clear = _here_clear(cm, x, y, cm.clear_m)
    ux, uy = clip_holonomic(ux0, uy0, ux, uy, dt, vmax, amax)
    ndisc = dpos.shape[0]
    if holonomic_stop_clear(cm, x, y, ux, uy, dt, amax, clear):
        if ndisc == 0:
            return ux, uy, ASKED
        g = holonomic_stop_disc_gap(x, y, ux, uy, dt, amax, radius, discs)
        if g >= disc_margin:
            return ux, uy, ASKED
        best_g, best_x, best_y = g, ux, uy
    else:
        best_g, best_x, best_y = -np.inf, 0.0, 0.0
    found = best_g > -np.inf
    s0 = math.sqrt(ux0 * ux0 + uy0 * uy0)
    if math.isfinite(amax) and s0 > 0.0:
        ns = _toward_zero(s0, amax * dt)
        ex, ey = ux0 * (ns / s0), uy0 * (ns / s0)
    else:
        ex, ey = 0.0, 0.0
    s = math.sqrt(ux * ux + uy * uy)
    a0 = math.atan2(uy, ux) if s > 0.0 else math.atan2(uy0, ux0)
    top = max(s, vmax * 0.25)
    m = nd * 4
    cx = np.empty(m + 1)
    cy = np.empty(m + 1)
    key = np.empty(m + 1)
    for j in range(nd):
        a = a0 + 2.0 * math.pi / nd * ((j + 1) // 2) * (1 if j % 2 else -1)
        for i in range(4):
            sp = top * (4 - i) / 4.0
            px, py = clip_holonomic(ux0, uy0, sp * math.cos(a), sp * math.sin(a), dt, vmax,
                                    amax)
            k = j * 4 + i
            cx[k] = px
            cy[k] = py
            key[k] = (px - ux) ** 2 + (py - uy) ** 2
    cx[m] = ex
    cy[m] = ey
    key[m] = np.inf
    order = np.argsort(key)
    for kk in range(m + 1):
        k = order[kk]
        px = cx[k]
        py = cy[k]
        if not holonomic_stop_clear(cm, x, y, px, py, dt, amax, clear):
            continue
        code = EMERGENCY if k == m else NEAREST
        if ndisc == 0:
            return px, py, code
        g = holonomic_stop_disc_gap(x, y, px, py, dt, amax, radius, discs)
        if g >= disc_margin:
            return px, py, code
        if not found or g > best_g:
            best_g, best_x, best_y = g, px, py
            found = True
    if found:
        return best_x, best_y, EVADE
    return ex, ey, UNSAFE


def warmup_shield() -> None:
    """Compile (or load from numba's cache) the shield for writeable and read-only disc
    arrays (a :class:`~pathfuse.costmap.Costmap`'s map is always read-only)."""
    from pathfuse.costmap import make_costmap

    occ = np.zeros((3, 3), dtype=np.bool_)
    occ[1, 1] = True
    cm = make_costmap(occ, 0.2, clear_m=0.2)
    for ro in (False, True):
        d2 = np.zeros((1, 2))
        d2[0] = (2.5, 2.5)
        v2 = np.full(1, 0.5)
        r1 = np.full(1, 0.1)
        for a in (d2, v2, r1):
            a.setflags(write=not ro)
        clip_unicycle(0.0, 0.0, 1.0, 0.5, 0.1, 0.0, 1.0, 2.0, 2.0, 4.0)
        clip_holonomic(0.0, 0.0, 1.0, 0.5, 0.1, 1.0, 2.0)
        for ds in (Discs(d2, d2, v2, r1), Discs(d2[:0], d2[:0], v2[:0], r1[:0])):
            shield_unicycle(cm, 0.5, 0.5, 0.0, 0.5, 0.0, 1.0, 0.5, 0.1, 0.0,
                            1.0, 2.0, 2.0, 4.0, ds, 0.0, NV, NW)
            shield_holonomic(cm, 0.5, 0.5, 0.0, 0.0, 1.0, 0.5, 0.1, 1.0,
                             2.0, ds, 0.0, ND)
            shield_holonomic(cm, 0.5, 0.5, 0.0, 0.0, 1.0, 0.5, 0.1, 1.0,
                             math.inf, ds, 0.0, ND)
