"""Not stopping next to a disc that may walk in (ours, issue 17/18; the fusion's ``flee``).

Replayed on the dynamic benchmark's tuning families (``--seed 2`` scenarios 7 and 21,
``--seed 3`` scenarios 6 and 24, 2 discs, diff-drive; the reported family ``--seed 0`` was
not replayed), every failure of the fusion with 2 discs that is a collision has the same
shape: a disc comes within a metre, the fusion's sequences (MPPI among discs) slow the
robot of their own choice, to let it cross or to turn, and the robot then stands or turns
on the spot within 0.05-0.6 m of a wandering disc for 1-4 s until the disc walks into it.
At rest the shield's passive safety always passes; moving away does too while the disc's
reach (its fastest seen speed times the stop's time) leaves room, which it does until
about a second before the hit.  The discs wander (1 rad/sqrt(s) of turn noise): their
constant-velocity prediction shows the contact only 0.6-1.8 s ahead, so a trigger on it
(``evade``'s) comes too late, and ``evade``'s escapes (turn at the yaw limit, then drive at
full speed) are the first commands the shield holds back next to a disc.

:func:`flee_command`: while a sensed disc is within ``near_m`` (at any speed: a trigger
on the controller slowing below 0.3 m/s, tried first, came too late in three of these four
replays), every command of the reachable window (``nv x nw``
samples, the controller's own first) is scored by the least gap of a rollout (the command
held for ``hold_s``, then a stop at the acceleration limit, then standing to
``horizon_s``) to the discs predicted at constant velocity, each grown by ``spread_mps``
per second of elapsed time (a wandering disc's reach), static squares counted as contact;
gaps are capped at ``enough_m``.  The command with the best gap replaces the controller's
when it gains at least ``gain_m``; among equally good ones, the nearest to the
controller's.  Only commands the caller's ``passes`` accepts are scored (the fusion passes
the shield's test: the shield would let the command through unchanged), so the robot keeps
passive safety, and every command still goes through the shield.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from pathfuse.costmap import Costmap, point_distance
from pathfuse.sweep import unicycle_pose

__all__ = ["NEAR_M", "rollout_gap", "flee_command"]

NEAR_M = 1.0
"""The controller's command is checked while a sensed disc's gap is below this."""


@njit(cache=True)
def rollout_gap(cm: Costmap, x: float, y: float, th: float, v: float, w: float, dt: float,
                amax: float, hold_s: float, horizon_s: float, radius: float,
                dpos: np.ndarray, dvel: np.ndarray, drad: np.ndarray,
                spread: float) -> float:
    """The least gap, sampled each ``dt``, of ``(v, w)`` held ``hold_s`` then a stop at
    ``amax`` (turning stopped) and standing to ``horizon_s``, to the discs predicted at
    constant velocity and grown by ``spread t``; ``-inf`` where the robot's disc would
    overlap a static square."""
    n = int(round(horizon_s / dt))
    nh = int(round(hold_s / dt))
    best = np.inf
    cv = v
    cw = w
    for k in range(n):
        if k >= nh:
            cv = max(cv - amax * dt, 0.0) if cv > 0.0 else min(cv + amax * dt, 0.0)
            cw = 0.0
        if cv != 0.0 or cw != 0.0:
            x, y, th = unicycle_pose(x, y, th, cv, cw, dt)
            if cv != 0.0 and point_distance(cm, x, y, radius) < radius:
                return -np.inf
        t = (k + 1) * dt
        for i in range(drad.shape[0]):
            g = math.hypot(x - dpos[i, 0] - dvel[i, 0] * t,
                           y - dpos[i, 1] - dvel[i, 1] * t) - radius - drad[i] - spread * t
            if g < best:
                best = g
    return best


def flee_command(cm: Costmap, x: float, y: float, th: float, c0: float, c1: float,
                 v: float, w: float, dt: float, limits: tuple[float, float, float, float,
                                                               float],
                 dpos: np.ndarray, dvel: np.ndarray, drad: np.ndarray,
                 passes: Callable[[float, float], bool] | None, *, near_m: float | None = None,
                 hold_s: float = 1.0, horizon_s: float = 2.0,
                 spread_mps: float = 0.3, enough_m: float = 0.5, gain_m: float = 0.05,
                 nv: int = 7, nw: int = 9) -> tuple[float, float, bool]:
    """``(v, w, replaced)``: the controller's ``(v, w)``, or the window's command that keeps
    the largest predicted gap (see the module docstring).

    ``(c0, c1)`` is the last applied command, ``limits`` ``(vmin, vmax, amax, wmax,
    alpha)``, ``dpos``/``dvel``/``drad`` the sensed discs and ``passes(v, w)`` the test a
    replacement must pass (None: every command).
    """
    radius = float(cm.radius_m)
    near_m = NEAR_M if near_m is None else near_m
    if drad.shape[0] == 0:
        return v, w, False
    near = np.hypot(dpos[:, 0] - x, dpos[:, 1] - y) - drad - radius
    if float(near.min()) >= near_m:
        return v, w, False
    vmin, vmax, amax, wmax, alpha = limits
    g_own = min(rollout_gap(cm, x, y, th, v, w, dt, amax, hold_s, horizon_s, radius, dpos,
                            dvel, drad, spread_mps), enough_m)
    lo, hi = max(vmin, c0 - amax * dt), min(vmax, c0 + amax * dt)
    wlo, whi = max(-wmax, c1 - alpha * dt), min(wmax, c1 + alpha * dt)
    sv, sw = max(hi - lo, 1e-12), max(whi - wlo, 1e-12)
    best: tuple[float, float, float, float] | None = None  # (-gap, distance, v, w)
    for vi in np.linspace(lo, hi, nv):
        for wj in np.linspace(wlo, whi, nw):
            vi_, wj_ = float(vi), float(wj)
            g = min(rollout_gap(cm, x, y, th, vi_, wj_, dt, amax, hold_s, horizon_s, radius,
                                dpos, dvel, drad, spread_mps), enough_m)
            if not g >= g_own + gain_m:
                continue
            key = (-math.floor(max(g, -1e3) * 1000.0),
                   ((vi_ - v) / sv) ** 2 + ((wj_ - w) / sw) ** 2)
            if best is not None and key >= best[:2]:
                continue
            if passes is not None and not passes(vi_, wj_):
                continue
            best = (key[0], key[1], vi_, wj_)
    if best is None:
        return v, w, False
    return best[2], best[3], True
