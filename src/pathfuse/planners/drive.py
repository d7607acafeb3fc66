"""From a desired velocity to a diff-drive command: the one conversion every controller shares.

The potential-field controllers (``apf``, ``fusion``, ``ref6``, ``ref7``) and
the A* followers (``astar``, ``astar-replan``) decide a velocity vector
``u = (ux, uy)`` (where to be after the tick).  A holonomic robot takes it
as it is.  A diff-drive robot gets ``(v, omega)`` from
:func:`unicycle_command`, which does this, in this order:

1. **Heading.**  ``err`` is the angle from the robot's heading to ``u``
   (wrapped to ``[-pi, pi]``).  The desired yaw rate is the fastest from
   which the turn can still stop at the target heading,
   ``sign(err) min(|err| / dt, sqrt(2 alpha |err|))`` (``alpha`` the yaw
   acceleration limit), clipped to ``+-max_yaw_rate`` and to the window
   ``omega_0 +- alpha dt`` of the last command.
2. **Speed.**  ``v = |u| cos(err)^2`` while ``|err| < 90 deg``, else 0 (the
   robot turns towards ``u`` first, slowing as the error grows; it never
   reverses), clipped to ``[min_speed, max_speed]`` and to the window
   ``v_0 +- a dt``.
3. **Admissibility** (Fox et al.'s rule, against the static map).  A speed
   is taken only when the disc swept along this tick's arc *and then along a
   straight stop of* ``v^2 / (2 a)`` *metres on the final heading* stays
   the :class:`~pathfuse.costmap.Costmap`'s ``clear_m`` (the radius plus
   :data:`~pathfuse.geometry.MARGIN_FRAC` of a cell) clear of every occupied
   square and the map's edge (:func:`~pathfuse.costmap.arc_distance`, exact).  Otherwise the
   speed is lowered in 8 even steps towards the lowest speed of the window;
   if none passes, the same with the yaw rates of the window nearest the
   desired one (the last one, 0, either extreme).  If nothing passes, the
   lowest speed with the desired yaw rate is taken (the world judges it).
   With a safety margin (``clearance_m``, ours) all this is first tried
   keeping ``radius + min(margin, present gap)`` clear, then with the
   radius alone.  A robot already closer than that (it braked too late) may
   keep its present clearance: moves that do not reduce it pass.

So a robot that can brake in time never drives into a wall because of the
conversion, turning on the spot is always allowed (the footprint is a
disc), and the moving discs are left to the controller that chose ``u``.

Examples
--------
>>> import numpy as np
>>> from pathfuse.costmap import make_costmap
>>> cm = make_costmap(np.zeros((4, 4), dtype=np.bool_), 0.2, clear_m=0.2)
>>> v, w = unicycle_command(cm, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.1,
...                         0.0, 1.0, 2.0, 2.0, 4.0, 0.0)
>>> round(v, 6), round(w, 6)     # straight ahead, from rest: the acceleration window
(0.2, 0.0)
>>> v, w = unicycle_command(cm, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.1,
...                         0.0, 1.0, 2.0, 2.0, 4.0, 0.0)
>>> round(v, 6), round(w, 6)     # 90 degrees to the left: turn on the spot
(0.0, 0.4)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from pathfuse.costmap import (
    Costmap,
    arc_distance,
    costmap_for,
    make_costmap,
    point_distance,
    segment_distance,
)
from pathfuse.sweep import unicycle_pose

__all__ = ["unicycle_command", "admissible", "wrap_angle", "to_unicycle", "warmup_drive"]


@njit(cache=True, inline="always")
def wrap_angle(a: float) -> float:
    """``a`` wrapped to ``[-pi, pi)``."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def admissible(cm: Costmap, x: float, y: float, th: float, v: float, w: float, dt: float,
               brake_m: float, clear: float) -> bool:
    """Whether the arc of ``(v, w)`` over ``dt`` and a straight stop of ``brake_m`` on the
    final heading keep the disc ``clear`` from every occupied square and the map's edge."""
    d = arc_distance(cm, x, y, th, v, w, dt, clear, clear)
    if d < clear:
        return False
    if brake_m > 0.0:
        bx, by, bth = unicycle_pose(x, y, th, v, w, dt)
        ex = bx + brake_m * math.cos(bth)
        ey = by + brake_m * math.sin(bth)
        if segment_distance(cm, bx, by, ex, ey, clear) < clear:
            return False
    return True


@njit(cache=True)
def unicycle_command(cm: Costmap, x: float, y: float, th: float, v0: float, w0: float,
                     ux: float, uy: float, dt: float, vmin: float, vmax: float, amax: float,
                     wmax: float, alpha: float, margin: float = 0.0) -> tuple[float, float]:
    """``(v, omega)`` for the desired velocity ``(ux, uy)`` (see the module docstring;
    ``cm.clear_m`` is the clearance kept, ``margin`` the safety margin beyond it)."""
    clear = cm.clear_m
    s = math.sqrt(ux * ux + uy * uy)
    v_des = 0.0
    w_des = 0.0
    if s > 1e-12:
        err = wrap_angle(math.atan2(uy, ux) - th)
        rate = abs(err) / dt
        if math.isfinite(alpha):
            rate = min(rate, math.sqrt(2.0 * alpha * abs(err)))
        w_des = rate if err >= 0.0 else -rate
        c = math.cos(err)
        if c > 0.0:
            v_des = s * c * c
    wlo = max(-wmax, w0 - alpha * dt)
    whi = min(wmax, w0 + alpha * dt)
    w = min(max(w_des, wlo), whi)
    vlo = max(vmin, v0 - amax * dt)
    vhi = min(vmax, v0 + amax * dt)
    v = min(max(v_des, vlo), vhi)
    # a robot that came closer than ``clear`` (braking too late) may keep what it has
    d = point_distance(cm, x, y, clear + margin + 1.0)
    if d < clear:
        clear = d * (1.0 - 1e-12)
    # with a safety margin: first keep it (or what is left of it), then only the radius
    hi = clear
    if margin > 0.0:
        hi = max(clear, clear + min(margin, max(d - clear, 0.0)) * (1.0 - 1e-9))
    for pas in range(2 if hi > clear else 1):
        cl = hi if pas == 0 else clear
        vk, wj, ok = _first_admissible(cm, x, y, th, v, vlo, w, w0, wlo, whi, dt, amax, cl)
        if ok:
            return vk, wj
    return vlo, w


@njit(cache=True)
def _first_admissible(cm, x, y, th, v, vlo, w, w0, wlo, whi, dt, amax, clear):
    # the desired yaw rate first; if no speed is admissible with it, the yaw rates of the
    # window nearest to it (keep turning, go straight, turn hard either way)
    for j in range(5):
        if j == 0:
            wj = w
        elif j == 1:
            wj = min(max(w0, wlo), whi)
        elif j == 2:
            wj = min(max(0.0, wlo), whi)
        elif j == 3:
            wj = wlo if abs(wlo - w) > abs(whi - w) else whi
        else:
            wj = whi if abs(wlo - w) > abs(whi - w) else wlo
        for k in range(9):
            vk = v - (v - vlo) * (k / 8.0)
            brake = 0.0
            if vk > 0.0 and math.isfinite(amax):
                brake = vk * vk / (2.0 * amax)
            if admissible(cm, x, y, th, vk, wj, dt, brake, clear):
                return vk, wj, True
    return vlo, w, False


def to_unicycle(problem: Any, robot: Any, dt: float, obs: Any, u: Any) -> np.ndarray:
    """The diff-drive command for the desired velocity ``u`` of a controller, from the
    observation's pose and last command (:func:`unicycle_command`)."""
    cm = costmap_for(problem.grid, float(problem.robot_radius_m))
    cmd = obs.command
    v, w = unicycle_command(
        cm, float(obs.position[0]),
        float(obs.position[1]), float(obs.heading), float(cmd[0]), float(cmd[1]),
        float(u[0]), float(u[1]), float(dt), float(robot.min_speed_mps),
        float(robot.max_speed_mps), float(robot.max_accel_mps2),
        float(robot.max_yaw_rate_radps), float(robot.max_yaw_accel_radps2),
        float(problem.clearance_m))
    return np.array([v, w])


def warmup_drive() -> None:
    """Compile (or load from numba's cache) the conversion (a
    :class:`~pathfuse.costmap.Costmap`'s map is always read-only)."""
    cm = make_costmap(np.zeros((3, 3), dtype=np.bool_), 0.2)
    unicycle_command(cm, 1.5, 1.5, 0.0, 0.0, 0.0, 1.0, 0.5, 0.1, 0.0, 1.0,
                     2.0, 2.0, 4.0, 0.0)
