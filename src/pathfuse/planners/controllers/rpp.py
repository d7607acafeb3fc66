"""Regulated Pure Pursuit: the path followers' controller on a diff-drive robot.

The path followers (``astar``, ``astar-replan``, ``thetastar``,
``lazy-thetastar``, ``astar-smooth``, ``shortest``) walk their path point by
point on a holonomic robot.  On a diff-drive robot they answer ``(v, omega)``
with this follower instead, after the Regulated Pure Pursuit controller of
Nav2 (S. Macenski, S. Singh, F. Martin, J. Gines, "Regulated Pure Pursuit for
Robot Path Tracking", Autonomous Robots, 2023).  Written for pathfuse from
that description; each tick (:func:`rpp_step`, one numba call):

1. **Progress.**  The closest point of the path (the goal appended as its
   end) to the robot, searched from the last one forward over
   ``pose_search_distance_m`` of path (:func:`closest_progress`): progress
   is monotone and never jumps back or across a loop of the path.
2. **Lookahead.**  ``L = clip(|v| lookahead_time_s, min_lookahead_m,
   max_lookahead_m)`` (``v`` the last command); the carrot is the first
   point of the path beyond the closest point at distance ``L`` from the
   robot, interpolated where the path leaves that circle, as Nav2 finds it
   (:func:`carrot_point`; the path's end when no point is that far).
   **Clear carrot** (ours, ``clear_carrot``): pathfuse's paths are shortest
   paths that touch the robot's clearance where they turn round an
   obstacle, so a pursuit arc that cuts such a corner would touch it (Nav2's
   paths keep away by the costmap's inflation, and its collision check
   stops the robot).  The candidates ``L, 0.7 L, 0.49 L, ...`` (at most
   :data:`SHRINKS` shortenings, never below a quarter of
   ``min_lookahead_m``), each moved :data:`CARROT_MARGIN_M` off the map
   where the path has no slack, are tried in turn: the farthest whose way
   keeps the robot's radius (the pursuit arc to it, or the straight line
   after a turn on the spot when it is to be turned to; swept disc, exact,
   :func:`carrot_is_clear`) is taken; if none, the farthest whose straight
   line does, after turning on the spot to face it; if none, the nearest
   heading (within 0.8 rad) from which an arc to one does, turning to it
   first; else the nearest candidate (the shield decides).
3. **Rotate to heading.**  When the carrot's bearing in the robot frame
   exceeds ``rotate_to_heading_min_angle_rad``, the robot brakes (``v = 0``)
   and turns on the spot towards it, at the yaw rate from which the turn
   can still stop at that heading, ``min(|e| / dt, sqrt(2 alpha |e|),
   max_yaw_rate)`` (as :mod:`pathfuse.planners.drive` turns).
4. **Pure pursuit.**  Otherwise the arc through the carrot: curvature
   ``kappa = 2 y / L'^2`` (carrot at ``(x, y)`` in the robot frame,
   ``L'`` its distance).  The speed (:func:`regulated_speed`) starts at the
   robot's top speed and is regulated by the **curvature** (on an arc of
   radius below ``regulated_min_radius_m`` it scales by radius / that) and
   the **proximity** of obstacles (closer than ``proximity_distance_m``, the
   exact gap of the disc to the map, it scales by gap / that), each limited
   below by ``regulated_min_speed_mps``; then the **approach** (within
   ``approach_distance_m`` of the goal by distance / that, at least
   ``min_approach_speed_mps``) and never faster than the robot can brake to
   the goal, ``sqrt(2 a d)``, nor past it in one tick.  ``omega = v kappa``;
   when that yaw rate is outside the window the yaw limits reach this tick,
   ``v`` is lowered to keep the curvature.  Last (ours), on the same arc, the
   fastest of that speed and 8 even steps down to the lowest the braking limit
   allows whose tick and stop keep the robot clear of the map, by the safety
   shield's own test (:func:`pathfuse.shield.unicycle_stop_clear`), so that
   the shield seldom has to replace the command (Nav2's collision check
   instead stops the robot when the arc to the carrot would collide).

The command then passes the safety shield (:mod:`pathfuse.shield`) as every
controller's does; the follower is built so that the shield rarely has to
change it.  Every loop is bounded: the path scans by the path's length, the
candidates by :data:`SHRINKS` and the headings tried by 12.

Examples
--------
>>> round(pursuit_curvature(1.0, 1.0), 6)     # carrot at 45 deg: the circle of radius 1
1.0
>>> lookahead_distance(1.0, 1.5, 0.3, 0.9), lookahead_distance(0.1, 1.5, 0.3, 0.9)
(0.9, 0.3)
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from pathfuse.costmap import Costmap, arc_distance, costmap_for, make_costmap, segment_distance
from pathfuse.shield import unicycle_stop_clear

__all__ = ["RegulatedPurePursuit", "rpp_step", "closest_progress", "point_at", "carrot_point",
           "pursuit_curvature", "lookahead_distance", "regulated_speed", "carrot_is_clear",
           "pack_settings", "RppSettings", "warmup_rpp", "MODE_PURSUIT", "MODE_ROTATE",
           "MODE_ARRIVED", "SHRINKS"]

#: What :func:`rpp_step` did: followed the arc, turned on the spot, or stood at the goal.
MODE_PURSUIT, MODE_ROTATE, MODE_ARRIVED = 0, 1, 2
#: How many times the lookahead is shortened at most to find a clear carrot.
SHRINKS = 10
_SHRINK = 0.7
#: The carrot is never brought closer than this fraction of ``min_lookahead_m``.
_MIN_CARROT = 0.25
#: A carrot is kept this much further from the map than the robot's clearance (m).
CARROT_MARGIN_M = 0.002
#: Headings tried (both ways, rad) when no way to any carrot is clear from the present one.
_TURNS = (0.05, 0.1, 0.2, 0.35, 0.5, 0.8)

class RppSettings(NamedTuple):
    """The follower's settings as :func:`rpp_step` reads them (one argument, by name), from
    :func:`pack_settings`.  The map, the radius and the clearance kept are the
    :class:`~pathfuse.costmap.Costmap`'s."""

    lookahead_time_s: float
    min_lookahead_m: float
    max_lookahead_m: float
    rotate_min_angle_rad: float
    regulated_min_radius_m: float
    regulated_min_speed_mps: float
    proximity_distance_m: float
    approach_distance_m: float
    min_approach_speed_mps: float
    pose_search_distance_m: float
    clear_carrot: bool
    max_speed_mps: float
    max_accel_mps2: float
    max_yaw_rate_radps: float
    max_yaw_accel_radps2: float
    dt_s: float


def pack_settings(params: Any, robot: Any, dt: float, max_speed: float) -> RppSettings:
    """The settings of :func:`rpp_step` from the parameters (a
    :class:`~pathfuse.planners.params.PursuitParams`) and the robot's limits.

    Examples
    --------
    >>> from pathfuse.planners.params import PursuitParams
    >>> from pathfuse.robot import RobotModel
    >>> s = pack_settings(PursuitParams(), RobotModel.diff_drive(radius_m=0.2), 0.1, 0.5)
    >>> s.max_speed_mps, s.dt_s
    (0.5, 0.1)
    """
    return RppSettings(
        float(params.lookahead_time_s), float(params.min_lookahead_m),
        float(params.max_lookahead_m), float(params.rotate_to_heading_min_angle_rad),
        float(params.regulated_min_radius_m), float(params.regulated_min_speed_mps),
        float(params.proximity_distance_m), float(params.approach_distance_m),
        float(params.min_approach_speed_mps), float(params.pose_search_distance_m),
        bool(params.clear_carrot), min(float(max_speed), float(robot.max_speed_mps)),
        float(robot.max_accel_mps2), float(robot.max_yaw_rate_radps),
        float(robot.max_yaw_accel_radps2), float(dt))


@njit(cache=True)
def closest_progress(path: np.ndarray, cum: np.ndarray, x: float, y: float, i0: int,
                     s0: float, window: float) -> tuple[int, float]:
    """The segment and arc length of the path point closest to ``(x, y)``, searched from
    arc length ``s0`` (on segment ``i0``) forward over segments that start within
    ``window`` of it; never behind ``s0`` (ties: the earliest)."""
    n = path.shape[0]
    if n < 2:
        return 0, 0.0
    best_d = math.inf
    best_i = i0
    best_s = s0
    i = i0
    while i < n - 1 and cum[i] <= s0 + window:
        ax, ay = path[i, 0], path[i, 1]
        ex, ey = path[i + 1, 0] - ax, path[i + 1, 1] - ay
        seg = cum[i + 1] - cum[i]
        t = 0.0
        if seg > 0.0:
            t = ((x - ax) * ex + (y - ay) * ey) / (seg * seg)
            lo = 0.0
            if i == i0:
                lo = min(max((s0 - cum[i]) / seg, 0.0), 1.0)
            t = min(max(t, lo), 1.0)
        d = math.hypot(ax + t * ex - x, ay + t * ey - y)
        if d < best_d:
            best_d = d
            best_i = i
            best_s = cum[i] + t * seg
        i += 1
    return best_i, max(best_s, s0)


@njit(cache=True)
def point_at(path: np.ndarray, cum: np.ndarray, i0: int, s: float) -> tuple[float, float]:
    """The path point at arc length ``s`` (the end beyond it), scanning from segment
    ``i0``."""
    n = path.shape[0]
    if n < 2 or s >= cum[n - 1]:
        return path[n - 1, 0], path[n - 1, 1]
    i = max(i0, 0)
    while i < n - 2 and cum[i + 1] < s:
        i += 1
    seg = cum[i + 1] - cum[i]
    f = 0.0 if seg <= 0.0 else min(max((s - cum[i]) / seg, 0.0), 1.0)
    return (path[i, 0] + f * (path[i + 1, 0] - path[i, 0]),
            path[i, 1] + f * (path[i + 1, 1] - path[i, 1]))


@njit(cache=True)
def carrot_point(path: np.ndarray, cum: np.ndarray, i0: int, s0: float, x: float, y: float,
                 la: float) -> tuple[float, float]:
    """The carrot: the first point of the path beyond arc length ``s0`` (on segment
    ``i0``: the closest point) at distance ``la`` from ``(x, y)``, interpolated where the
    path leaves that circle; the closest point when it is already that far, the path's end
    when no point is."""
    n = path.shape[0]
    ax, ay = point_at(path, cum, i0, s0)
    if n < 2 or (ax - x) ** 2 + (ay - y) ** 2 >= la * la:
        return ax, ay
    i = max(i0, 0)
    while i < n - 1:
        bx, by = path[i + 1, 0], path[i + 1, 1]
        if (bx - x) ** 2 + (by - y) ** 2 >= la * la:
            # a inside the circle, b on or outside it: where a -> b leaves it
            dx, dy = bx - ax, by - ay
            fx, fy = ax - x, ay - y
            a2 = dx * dx + dy * dy
            b2 = fx * dx + fy * dy
            c2 = fx * fx + fy * fy - la * la
            t = (-b2 + math.sqrt(max(b2 * b2 - a2 * c2, 0.0))) / a2
            t = min(max(t, 0.0), 1.0)
            return ax + t * dx, ay + t * dy
        ax, ay = bx, by
        i += 1
    return path[n - 1, 0], path[n - 1, 1]


@njit(cache=True)
def pursuit_curvature(xr: float, yr: float) -> float:
    """The curvature ``2 y / L^2`` of the arc from the robot (at the origin, heading +x)
    through the carrot ``(xr, yr)`` in the robot frame (positive: to the left)."""
    d2 = xr * xr + yr * yr
    if d2 <= 0.0:
        return 0.0
    return 2.0 * yr / d2


@njit(cache=True)
def lookahead_distance(v: float, t: float, lo: float, hi: float) -> float:
    """``clip(|v| t, lo, hi)``."""
    return min(max(abs(v) * t, lo), hi)


@njit(cache=True)
def regulated_speed(vmax: float, kappa: float, gap: float, d_goal: float, amax: float,
                    dt: float, rmin: float, vreg: float, prox: float, approach: float,
                    vapproach: float) -> float:
    """The regulated linear speed (see the module docstring, step 4)."""
    vc = vmax
    if rmin > 0.0 and kappa != 0.0:
        r = 1.0 / abs(kappa)
        if r < rmin:
            vc = vmax * r / rmin
    vp = vmax
    if prox > 0.0 and gap < prox:
        vp = vmax * max(gap, 0.0) / prox
    v = max(min(vc, vp), min(vreg, vmax))
    if approach > 0.0 and d_goal < approach:
        v = min(v, max(v * d_goal / approach, vapproach))
    if math.isfinite(amax):
        v = min(v, math.sqrt(2.0 * amax * d_goal))
    return max(min(v, d_goal / dt), 0.0)


@njit(cache=True)
def carrot_is_clear(cm: Costmap, x: float, y: float, th: float, xr: float, yr: float,
                    rot: float, clear: float) -> bool:
    """Whether the robot disc keeps ``clear`` along its way to the carrot ``(xr, yr)``
    (robot frame): the pursuit arc, or, beyond the bearing ``rot``, the straight line
    after turning on the spot."""
    dist = math.hypot(xr, yr)
    if dist <= 0.0:
        return True
    bearing = math.atan2(yr, xr)
    if abs(bearing) > rot or abs(yr) <= 1e-9 * dist:
        c, s = math.cos(th), math.sin(th)
        bx = x + c * xr - s * yr
        by = y + s * xr + c * yr
        return segment_distance(cm, x, y, bx, by, clear) >= clear
    kappa = 2.0 * yr / (dist * dist)
    length = 2.0 * bearing / kappa
    return arc_distance(cm, x, y, th, 1.0, kappa, length, clear,
                               clear) >= clear


@njit(cache=True, inline="always")
def _in_frame(px: float, py: float, x: float, y: float, c: float,
              sn: float) -> tuple[float, float]:
    return c * (px - x) + sn * (py - y), -sn * (px - x) + c * (py - y)


@njit(cache=True)
def _off_the_wall(cm: Costmap, px: float, py: float, clear: float) -> tuple[float, float]:
    """The carrot moved away from the nearest obstacle until it keeps ``clear`` plus
    :data:`CARROT_MARGIN_M` (a path that touches the robot's clearance, as pathfuse's
    shortest paths do, cannot be driven on exactly: the shield keeps a hair more)."""
    want = clear + CARROT_MARGIN_M
    res = cm.res_m
    cap = want + res
    d = segment_distance(cm, px, py, px, py, cap)
    if d >= want:
        return px, py
    h = 0.25 * res
    gx = (segment_distance(cm, px + h, py, px + h, py, cap)
          - segment_distance(cm, px - h, py, px - h, py, cap))
    gy = (segment_distance(cm, px, py + h, px, py + h, cap)
          - segment_distance(cm, px, py - h, px, py - h, cap))
    n = math.hypot(gx, gy)
    if n <= 0.0:
        return px, py
    qx = px + gx / n * (want - d)
    qy = py + gy / n * (want - d)
    if segment_distance(cm, qx, qy, qx, qy, cap) > d:
        return qx, qy
    return px, py


@njit(cache=True)
def _clear_candidate(cm: Costmap, x: float, y: float, th: float, cand: np.ndarray, nc: int,
                     rot: float, clear: float) -> int:
    """The first (farthest) carrot candidate whose way from heading ``th`` is clear
    (:func:`carrot_is_clear`), or -1."""
    c, sn = math.cos(th), math.sin(th)
    for k in range(nc):
        xr, yr = _in_frame(cand[k, 0], cand[k, 1], x, y, c, sn)
        if carrot_is_clear(cm, x, y, th, xr, yr, rot, clear):
            return k
    return -1


@njit(cache=True)
def _turn_rate(e: float, dt: float, wmax: float, alpha: float) -> float:
    """The yaw rate towards the heading error ``e`` from which the turn can still stop
    there: ``sign(e) min(|e| / dt, sqrt(2 alpha |e|), wmax)``."""
    rate = min(abs(e) / dt, wmax)
    if math.isfinite(alpha):
        rate = min(rate, math.sqrt(2.0 * alpha * abs(e)))
    return rate if e >= 0.0 else -rate


@njit(cache=True)
def rpp_step(path: np.ndarray, cum: np.ndarray, cm: Costmap, cfg: RppSettings, x: float,
             y: float, th: float, v0: float, w0: float, i0: int,
             s0: float) -> tuple[float, float, int, float, int, float, float]:
    """One tick: ``(v, omega, segment, progress, mode, carrot_x, carrot_y)`` (see the module
    docstring; ``cfg`` from :func:`pack_settings`, ``(v0, w0)`` the last command)."""
    n = path.shape[0]
    dt = cfg.dt_s
    i, s = closest_progress(path, cum, x, y, i0, s0, cfg.pose_search_distance_m)
    gx, gy = path[n - 1, 0], path[n - 1, 1]
    d_goal = max(cum[n - 1] - s, math.hypot(gx - x, gy - y))
    c, sn = math.cos(th), math.sin(th)
    clear = cm.clear_m
    gap_c = segment_distance(cm, x, y, x, y,
                                    cm.radius_m + max(cfg.proximity_distance_m, 0.0) + clear)
    if gap_c < clear:  # already closer (a robot that braked late): keep what it has
        clear = gap_c * (1.0 - 1e-12)
    la0 = lookahead_distance(v0, cfg.lookahead_time_s, cfg.min_lookahead_m,
                             cfg.max_lookahead_m)
    rot = cfg.rotate_min_angle_rad
    wmax = cfg.max_yaw_rate_radps
    alpha = cfg.max_yaw_accel_radps2
    # the carrot candidates: la0, 0.7 la0, 0.49 la0, ... down to the floor
    floor = min(la0, _MIN_CARROT * cfg.min_lookahead_m)
    cand = np.empty((SHRINKS + 1, 2))
    nc = 0
    la = la0
    for _ in range(SHRINKS + 1):
        qx, qy = carrot_point(path, cum, i, s, x, y, la)
        cand[nc, 0], cand[nc, 1] = _off_the_wall(cm, qx, qy, cm.clear_m)
        nc += 1
        if la <= floor:
            break
        la = max(la * _SHRINK, floor)
    # which one, and whether to turn on the spot first (by ``turn`` rad)
    pick, turn = 0, math.nan
    if cfg.clear_carrot:
        pick = _clear_candidate(cm, x, y, th, cand, nc, rot, clear)
        if pick < 0:  # no arc is clear: the straight line after a turn on the spot
            pick = _clear_candidate(cm, x, y, th, cand, nc, 0.0, clear)
            if pick >= 0:
                xr, yr = _in_frame(cand[pick, 0], cand[pick, 1], x, y, c, sn)
                turn = math.atan2(yr, xr)
        if pick < 0:  # nor a line: a heading nearby from which an arc is
            for j in range(2 * len(_TURNS)):
                d = _TURNS[j // 2] * (1.0 if j % 2 == 0 else -1.0)
                pick = _clear_candidate(cm, x, y, th + d, cand, nc, rot, clear)
                if pick >= 0:
                    turn = d
                    break
        if pick < 0:  # none: the nearest carrot (the shield decides)
            pick = nc - 1
    px, py = cand[pick, 0], cand[pick, 1]
    xr, yr = _in_frame(px, py, x, y, c, sn)
    if not math.isnan(turn):
        return 0.0, _turn_rate(turn, dt, wmax, alpha), i, s, MODE_ROTATE, px, py
    dist = math.hypot(xr, yr)
    if dist <= 1e-9:
        return 0.0, 0.0, i, s, MODE_ARRIVED, px, py
    bearing = math.atan2(yr, xr)
    if abs(bearing) > rot:
        return 0.0, _turn_rate(bearing, dt, wmax, alpha), i, s, MODE_ROTATE, px, py
    kappa = pursuit_curvature(xr, yr)
    amax = cfg.max_accel_mps2
    v = regulated_speed(cfg.max_speed_mps, kappa, gap_c - cm.radius_m, d_goal, amax, dt,
                        cfg.regulated_min_radius_m, cfg.regulated_min_speed_mps,
                        cfg.proximity_distance_m, cfg.approach_distance_m,
                        cfg.min_approach_speed_mps)
    # the windows the acceleration limits reach this tick (as the world clips)
    vlo, vhi = v0 - amax * dt, v0 + amax * dt
    v = min(max(v, max(vlo, 0.0)), vhi)
    wlo = max(-wmax, w0 - alpha * dt)
    whi = min(wmax, w0 + alpha * dt)
    w = v * kappa
    if w > whi and kappa > 0.0:  # too sharp a turn for this tick: slow down to keep kappa
        v = max(whi / kappa, 0.0)
    elif w < wlo and kappa < 0.0:
        v = max(wlo / kappa, 0.0)
    # on the same arc, the fastest of v and 8 even steps down to the window's lowest speed
    # from which the robot can still stop clear (the shield's own test), so that the shield
    # need not step in
    low = min(max(vlo, 0.0), v)
    for k in range(9):
        vk = v - (v - low) * (k / 8.0)
        if vk <= 0.0:
            break
        wk = min(max(vk * kappa, wlo), whi)
        if unicycle_stop_clear(cm, x, y, th, vk, wk, dt, amax, alpha, clear):
            return vk, vk * kappa, i, s, MODE_PURSUIT, px, py
    # none: the arc as it is (the shield then takes the nearest command it can stop from,
    # turning too; standing still here could last for ever on a path with no slack)
    return v, v * kappa, i, s, MODE_PURSUIT, px, py


def _cumlen(path: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])


class RegulatedPurePursuit:
    """The follower's state for one episode: the path (the goal appended), the progress,
    and what it did (``modes``: ticks of pursuit, rotation, arrival)."""

    def __init__(self, problem: Any, params: Any, dt: float, max_speed: float) -> None:
        g = problem.grid
        self.costmap = costmap_for(g, float(problem.robot_radius_m))
        self.goal = np.asarray(problem.goal, dtype=np.float64)
        self.cfg = pack_settings(params, problem.robot, float(dt), float(max_speed))
        self._source: np.ndarray | None = None
        self.path = np.zeros((0, 2))
        self.cum = np.zeros(0)
        self.segment = 0
        self.progress_m = 0.0
        self.carrot: tuple[float, float] | None = None
        self.modes = np.zeros(3, dtype=np.int64)

    def set_path(self, path: np.ndarray) -> None:
        """Follow ``path`` from its start (the goal appended when it does not end there)."""
        p = np.asarray(path, dtype=np.float64).reshape(-1, 2)
        if p.shape[0] == 0 or math.hypot(*(p[-1] - self.goal)) > 1e-12:
            p = np.vstack([p, self.goal[None, :]])
        self.path = np.ascontiguousarray(p)
        self.cum = _cumlen(self.path)
        self._source = path
        self.segment = 0
        self.progress_m = 0.0

    def command(self, obs: Any, path: np.ndarray) -> np.ndarray:
        """``(v, omega)`` for this tick; ``path`` is the path to follow (a new array object
        restarts the progress: a replanned path)."""
        if path is not self._source:
            self.set_path(path)
        cmd = obs.command
        v, w, i, s, mode, cx, cy = rpp_step(
            self.path, self.cum, self.costmap, self.cfg,
            float(obs.position[0]), float(obs.position[1]), float(obs.heading),
            float(cmd[0]), float(cmd[1]), self.segment, self.progress_m)
        self.segment, self.progress_m = int(i), float(s)
        self.carrot = (float(cx), float(cy))
        self.modes[mode] += 1
        return np.array([v, w])


def warmup_rpp() -> None:
    """Compile (or load from numba's cache) the follower's kernel (a
    :class:`~pathfuse.costmap.Costmap`'s map is always read-only)."""
    from pathfuse.planners.params import PursuitParams
    from pathfuse.robot import RobotModel

    cfg = pack_settings(PursuitParams(), RobotModel.diff_drive(radius_m=0.2), 0.1, 1.0)
    path = np.array([[0.75, 0.75], [2.25, 0.75], [2.25, 2.25]])
    cum = _cumlen(path)
    occ = np.zeros((6, 6), dtype=np.bool_)
    occ[3, 1] = True
    cm = make_costmap(occ, 0.2, resolution_m=0.5)
    for th in (0.0, 3.0):  # the pursuit arc and a turn on the spot
        rpp_step(path, cum, cm, cfg, 0.75, 0.75, th, 0.5, 0.0, 0, 0.0)
