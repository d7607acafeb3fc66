"""The fusion in velocity space, for a diff-drive robot (ours).

The paper's Algorithm 2 decides a *move*: the resultant of the goal's and the
A* points' attraction (within ``r1``) and the obstacles' repulsion (within
``r2``), one safe step along it, with our escape from local minima.  A
holonomic robot takes that move as its velocity (the paper's model, and
pathfuse's Tables I/II).  A diff-drive robot cannot: it must turn and brake,
and following the move's direction tick by tick made it swing and graze
(the BARN and dynamic results in docs/results before this module).

:class:`ForceWindow` keeps Algorithm 2 as the judge of *where* to go and lets
the dynamic window decide *how*.  Each tick:

1. Algorithm 2 makes its move (:meth:`FieldController.act
   <pathfuse.planners.base.FieldController.act>`: the force of eqs. 3-6 with
   the A* points within ``r1``, the safe step, the escape, the sensed discs'
   repulsion) and looks ahead ``horizon`` (2.5 s) of further moves without
   committing them: the field's streamline from the robot, the fusion's
   *local path*;
2. the reachable ``(v, omega)`` window is sampled and rolled out as ``dwa``
   does (:func:`pathfuse.planners.controllers.dwa_kernel.dwa_choose`, ``dwa``'s default
   critics), scored against that local path: distance from it and progress
   along it (agreement with the field), heading, speed, static clearance
   (``exp(-gap / 0.1 m)`` within 0.5 m) and the sensed discs predicted at
   constant velocity;
3. the best command goes through the safety shield (:mod:`pathfuse.shield`).

Where the local path's bearing is more than 60 degrees off the heading, or
the window's best is to stand and turn, the robot turns on the spot towards
it at the rate from which the turn can stop there (rotate to heading, as
Regulated Pure Pursuit does: the window's 2.5 s constant-``omega`` rollouts
wrap around and would spin past it) -- but not while a moving disc is sensed
(ours: the local path swings as discs come near, and a robot standing to turn
was walked into).

When Algorithm 2 goes nowhere (its local path ends within a quarter of its
nominal length of the robot) the A* path from the robot's progress takes its
place.

Among moving discs (ours, ``among_discs="mppi"``, the default): while a disc
is sensed, MPPI's sampled control sequences (:mod:`pathfuse.planners.controllers.mppi`)
track the local path, then the A* path beyond it, instead of the window.  A
sequence can accelerate and then swerve or get away; one command held over
the horizon cannot, and on the dynamic benchmark the window stood in the
discs' way.  The fusion's controller also plans the A* path again around the
sensed discs every ``replan_period_s`` (:mod:`pathfuse.planners.controllers.replan`,
as ``dwa`` does), so the A* points that attract the robot lead around them.
Without discs nothing of this runs: the static results (BARN) do not change.

Out of walkers' lanes (ours, ``replan_lane_s``, 3 s by default; issue 18): that A* path is
first planned with each sensed disc's lane blocked too, the ground it sweeps at constant
velocity over the next ``replan_lane_s`` (:func:`pathfuse.planners.controllers.replan.lane_discs`),
and while Algorithm 2's local path walks into such a lane (:func:`crosses_lane`) the
sequences track the A* path instead: Algorithm 2's goal attraction led the robot on down a
walker's lane, MPPI's 2.5 s rollouts saw the walker too late to cross and the robot fled
ahead of walkers faster than itself.  A disc first sensed is replanned around at once
(``replan_new``), not up to ``replan_period_s`` later.  The path out of the lanes is taken
only when at most ``replan_lane_detour_m`` (2 m) longer than the path around the discs
alone; otherwise that path, and the A* path does not lead (a disc bouncing between walls
made the path jump by 10 m and back and the robot turn back and forth).

Recovery (ours): when the robot has moved less than 0.3 m in 3 s, A* is
planned again from where it stands and followed for 4 s, then Algorithm 2
resumes (the escape of Algorithm 2 backs out along the walked trail, which a
robot that cannot follow the field's every turn does not have).

``fusion.velocity_space: false`` turns all this off: the move is then
converted by :func:`pathfuse.planners.drive.unicycle_command`, as before.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pathfuse.costmap import costmap_for
from pathfuse.field.pathing import polyline_cumlen
from pathfuse.planners.base import sensed_discs
from pathfuse.planners.controllers.dwa_kernel import (
    dwa_choose,
    dwa_progress,
    dwa_tick,
    pack_dwa,
    relaxed,
    route_tangent,
)
from pathfuse.planners.controllers.social import PassingSides, SteadyDiscs, disc_ids

__all__ = ["ForceWindow", "PASSIVE_WINDOW", "crosses_lane"]

PASSIVE_WINDOW = False
"""Whether the window plans for the shield's passive safety as ``dwa`` does by default
(``dwa.passive_safety``).  Off for the fusion: on the dynamic benchmark (diff-drive, 50
scenarios) the fusion reached 84/70/54/18 % with 0/2/4/8 discs without it and 84/70/38/14 %
with it, never at fault either way (the shield still enforces passive safety)."""



def crosses_lane(line: np.ndarray, dpos: np.ndarray, dvel: np.ndarray, drad: np.ndarray,
                 lane_s: float, radius: float) -> bool:
    """Whether a point of ``line`` after its first lies within ``radius + drad[i]`` of the
    lane disc ``i`` sweeps at constant velocity over ``lane_s`` seconds (ours, the fusion's
    ``replan_lane_s``), the robot's own point aside.

    >>> line = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> crosses_lane(line, np.array([[5.0, 0.3]]), np.array([[-1.0, 0.0]]), np.array([0.25]),
    ...              3.0, 0.25)
    True
    >>> crosses_lane(line, np.array([[5.0, 1.0]]), np.array([[-1.0, 0.0]]), np.array([0.25]),
    ...              3.0, 0.25)
    False
    """
    for i in range(drad.shape[0]):
        ax, ay = float(dpos[i, 0]), float(dpos[i, 1])
        bx, by = float(dvel[i, 0]) * lane_s, float(dvel[i, 1]) * lane_s
        l2 = bx * bx + by * by
        reach = radius + float(drad[i])
        for j in range(1, line.shape[0]):
            qx, qy = float(line[j, 0]) - ax, float(line[j, 1]) - ay
            u = min(1.0, max(0.0, (qx * bx + qy * by) / l2)) if l2 > 0.0 else 0.0
            if math.hypot(qx - u * bx, qy - u * by) < reach:
                return True
    return False


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class ForceWindow:
    """The dynamic window scored against Algorithm 2's move (see the module docstring).

    Parameters
    ----------
    problem : Problem
        With a diff-drive :class:`~pathfuse.robot.RobotModel`.
    dt : float
        The tick (s).
    social : SocialParams, optional
        The social critics among sensed moving discs (ours,
        :mod:`pathfuse.planners.controllers.social`; default: ``dwa``'s).
    among_discs : {"mppi", "window"}
        Who tracks the local path while a moving disc is sensed (ours): MPPI's
        sampled sequences, or the dynamic window as without discs.
    seed : int
        Seed of MPPI's sampling noise.
    keep : (float, float), optional
        The keep critic's weight and the most gap it asks for (the fusion's ``keep_weight``
        and ``keep_m``; default: ``dwa``'s).
    """

    def __init__(self, problem: Any, dt: float, social: Any = None,
                 among_discs: str = "mppi", seed: int = 0,
                 keep: tuple[float, float] | None = None) -> None:
        from pathfuse.planners.controllers.dwa import DWAParams

        rb = problem.robot
        p = DWAParams()
        w_keep, keep_m = (p.keep_weight, p.keep_m) if keep is None else keep
        sp = p if social is None else social
        self.social = sp
        self.among_discs = among_discs
        self.seed = int(seed)
        self._mppi: Any = None
        self.sequenced = 0
        self._last_seq = -10
        """Ticks decided by MPPI's sequences among discs."""
        g = problem.grid
        self.problem = problem
        self.horizon_s = float(p.horizon_s)
        self.vmax = float(rb.max_speed_mps)
        # the map, the radius and the clearance kept (radius + MARGIN_FRAC of a cell)
        self.costmap = costmap_for(g, float(problem.robot_radius_m))
        self.f = pack_dwa(
            dt, rb.min_speed_mps, rb.max_speed_mps, rb.max_accel_mps2, rb.max_yaw_rate_radps,
            rb.max_yaw_accel_radps2,
            max(problem.clearance_m, rb.clearance_m), p.horizon_s, p.sim_step_s, p.v_samples,
            p.w_samples, p.path_weight, p.goal_weight, p.heading_weight, p.speed_weight,
            p.obstacle_weight, p.moving_weight, p.obstacle_range_m, p.lookahead_m,
            p.inflation_decay_m, False, PASSIVE_WINDOW,
            w_align=p.path_align_weight, near_s=p.keep_horizon_s, w_keep=w_keep,
            keep_m=keep_m, w_social=sp.social_weight if sp.social else 0.0,
            personal_m=sp.personal_m, w_side=sp.side_weight if sp.social else 0.0,
            dwell_s=sp.dwell_s if sp.social else 0.0, w_dwell=sp.dwell_weight)
        self.sides = PassingSides(sp.personal_m)
        self.steady = SteadyDiscs(float(dt))
        self._steady = np.zeros(0, dtype=np.bool_)
        self.steps = max(1, int(math.ceil(p.horizon_s / dt)))
        """Algorithm 2's moves looked ahead each tick (the rollouts' horizon)."""
        self.min_reach_m = 0.25 * self.steps * self.vmax * dt
        """A local path whose end is closer than this to the robot (Algorithm 2 circling or
        stalled in a local minimum) gives way to the A* path."""
        self.on_line = 0
        """Ticks scored against Algorithm 2's local path (the rest: against the A* path)."""
        self.on_path = 0
        self.lane_ticks = 0
        """Ticks the A* path led because the local path walked into a disc's lane."""
        self.lanes_on = True
        """False while the last replanned A* path was refused its way out of the lanes for
        the detour (the fusion's ``replan_lane_detour_m``): the A* path does not lead then."""
        self.look_m = float(p.lookahead_m)
        self.rotate_rad = math.pi / 3.0
        """Beyond this bearing of the local path (``look_m`` along it) the robot first turns
        on the spot."""
        self.rotations = 0
        self.res = float(g.resolution)
        self.stall_ticks = max(2, int(round(3.0 / dt)))
        self.stall_m = 0.3
        """Moving less than ``stall_m`` over ``stall_ticks`` ticks (3 s) starts a recovery."""
        self.recover_ticks = max(1, int(round(4.0 / dt)))
        self.recover_left = 0
        self.recover_k = 0
        self.recoveries = 0
        self.rec_pts: np.ndarray | None = None
        self.rec_cum = np.zeros(1)
        self.trail = np.full((self.stall_ticks, 2), np.nan)
        self.ticks = 0
        self.relaxed_until = -1
        self.relax_replan = False
        self.f_relaxed = relaxed(self.f)
        if among_discs == "mppi":
            # built now, not at the first disc: its distance field would cost that tick
            from pathfuse.planners.controllers.mppi import MPPIController, MPPIParams

            class _Plan:
                waypoints = np.array([problem.start, problem.goal], dtype=np.float64)

            mp = MPPIParams(seed=self.seed, social=sp.social, social_weight=sp.social_weight,
                            personal_m=sp.personal_m, dwell_s=sp.dwell_s,
                            dwell_weight=sp.dwell_weight,
                            lane_escape=bool(getattr(sp, "lane_escape", True)))
            self._mppi = MPPIController(problem, mp, _Plan(), dt=float(dt),
                                        max_speed=self.vmax)
            self._mppi.replan_every = 0  # the fusion replans (FusionController)
        self.evader: Any = None
        self.passes: Any = None
        """The shield's test of a command this tick (set by the fusion's controller)."""
        if among_discs == "mppi" and bool(getattr(sp, "evade", False)):
            # ours (evade): out of a walker's swept lane instead of stopping in it
            from pathfuse.planners.controllers.evade import Evader

            self.evader = Evader(problem.goal, dt=float(dt))
        self.evade_steady = bool(getattr(sp, "evade_steady", False))
        """Ours (the fusion's ``evade_steady``): only discs seen steady set ``evade`` off."""
        self.walker_escape = among_discs == "mppi" and bool(getattr(sp, "walker_escape",
                                                                    False))
        """Ours (the fusion's ``walker_escape``): ``dwa``'s lane escape on the sequences'
        command (:func:`~pathfuse.planners.controllers.dwa_escape.escape_command`)."""
        self.walker_escape_s = float(getattr(sp, "walker_escape_s", p.lane_escape_s))
        self.walker_escape_hold = float(getattr(sp, "walker_escape_hold", 5.0))
        self.walker_escapes = 0
        """Ticks whose command the walker escape replaced."""
        self._escape_heading = math.nan

    def relax(self, seconds: float) -> None:
        """Recovery (ours, as Nav2's clear-costmap): no obstacle critic and no margin for
        ``seconds``, following a new A* path (the shield keeps the robot clear)."""
        self.relaxed_until = self.ticks + int(round(seconds / self.f.dt_s))
        self.relax_replan = True

    def _replan(self, x: float, y: float) -> None:
        from pathfuse.planners.globals.astar import plan_global

        pb = self.problem
        gp = plan_global(pb.with_start((x, y)), "euclidean")
        self.recoveries += 1
        if not gp.success:
            self.rec_pts = None
            return
        pts = np.asarray(gp.waypoints, dtype=np.float64).reshape(-1, 2)
        gx, gy = pb.goal
        if pts[-1, 0] != gx or pts[-1, 1] != gy:
            pts = np.concatenate([pts, [[gx, gy]]])
        self.rec_pts = np.require(pts, np.float64, ("C", "W"))
        self.rec_cum = polyline_cumlen(self.rec_pts)
        self.recover_k = 0
        self.recover_left = self.recover_ticks

    def _stalled(self, x: float, y: float) -> bool:
        i = self.ticks % self.stall_ticks
        old = self.trail[i].copy()
        self.trail[i] = (x, y)
        self.ticks += 1
        if self.recover_left > 0 or not np.isfinite(old[0]):
            return False
        if math.hypot(x - old[0], y - old[1]) >= self.stall_m:
            return False
        self.trail[:] = np.nan
        return True

    def choose(self, obs: Any, local: np.ndarray, pts: np.ndarray, cum: np.ndarray,
               k: int) -> np.ndarray:
        """``(v, omega)`` from the observation, Algorithm 2's local path ``local`` (the
        robot's position, then the fusion's next moves) and, when that is empty (Algorithm 2
        stands still), the A* path ``pts`` with its cumulative length ``cum`` from the
        robot's progress index ``k``."""
        x = float(obs.position[0])
        y = float(obs.position[1])
        dpos, dvel, drad = sensed_discs(obs)
        # the dwell critic counts the discs that keep their velocity (social.SteadyDiscs)
        self._steady = self.steady.update(disc_ids(obs, drad.shape[0]), dvel)
        lc = polyline_cumlen(local)
        net = math.hypot(float(local[-1, 0]) - x, float(local[-1, 1]) - y)
        if self.relax_replan:
            self.relax_replan = False
            self._replan(x, y)
        if self._stalled(x, y):
            # recovery (ours): Algorithm 2 led the robot nowhere for 3 s; plan A* from here
            # and follow that path for 4 s
            self._replan(x, y)
        if self.recover_left > 0 and self.rec_pts is not None:
            self.recover_left -= 1
            self.recover_k = int(dwa_progress(x, y, self.rec_pts, self.rec_cum,
                                              self.recover_k, 2.0))
            pts, cum, k = self.rec_pts, self.rec_cum, self.recover_k
            net = -1.0
        lane_s = float(getattr(self.social, "replan_lane_s", 0.0)) if self.social.social \
            else 0.0
        if lane_s > 0.0 and self.lanes_on and drad.shape[0] and net >= 0.0 \
                and crosses_lane(local, dpos, self.lane_velocities(obs, dvel), drad, lane_s,
                                 float(self.problem.robot_radius_m)):
            # ours (replan_lane_s): Algorithm 2's local path walks into a sensed disc's lane;
            # the A* path, replanned out of the lanes, leads instead
            net = -1.0
            self.lane_ticks += 1
        if local.shape[0] >= 2 and net >= self.min_reach_m:
            path, pcum, kk = np.require(local, np.float64, ("C", "W")), lc, 0
            self.on_line += 1
        else:
            path, pcum, kk = pts, cum, min(max(int(k), 0), pts.shape[0] - 1)
            self.on_path += 1
        cmd = obs.command
        th = float(obs.heading)
        # rotate to heading first (as Regulated Pure Pursuit does): constant-omega rollouts
        # over the horizon wrap around and make turning on the spot a slow spiral
        j = int(np.searchsorted(pcum, pcum[kk] + self.look_m))
        j = min(max(j, kk + 1), path.shape[0] - 1)
        err = _wrap(math.atan2(float(path[j, 1]) - y, float(path[j, 0]) - x) - th)
        # ours: not while a disc is sensed; standing to turn is how the fusion was walked
        # into (the local path swung as discs came near and the robot spun on the spot)
        among = drad.shape[0] > 0
        if abs(err) > self.rotate_rad and not among:
            return self._rotate(err)
        if self.among_discs == "mppi" and drad.shape[0] > 0:
            return self._sequences(obs, path, kk, pts, cum, k, dpos, dvel, drad)
        self._escape_heading = math.nan  # the walker escape's hysteresis ends with the discs
        f = self.f_relaxed if self.ticks <= self.relaxed_until else self.f
        # the keep critic's reference: the gap the A* path keeps ahead (the local path is
        # the field's streamline, which may graze)
        n = drad.shape[0]
        ids = disc_ids(obs, n)
        chosen = np.zeros((n, 2))
        # passing sides are told against the A* route (the local path bends around discs)
        route = route_tangent(pts, min(max(int(k), 0), pts.shape[0] - 1), th)
        tick = dwa_tick(self.costmap, f, pts, cum, min(max(int(k), 0), pts.shape[0] - 1), route)
        a0, a1, _, _ = dwa_choose(self.costmap, f, tick, x, y,
                                  float(obs.heading), float(cmd[0]), float(cmd[1]), path, pcum,
                                  kk, dpos, dvel, drad, self.sides.sides(ids), chosen)
        if n:
            self.sides.update(ids, chosen, dpos, (x, y), route, drad,
                              self.problem.robot_radius_m)
        if a0 <= 0.0 and float(cmd[0]) <= 0.0 and abs(err) > 0.05 and not among:
            # the window's best is to stand and turn: turn towards the local path at the rate
            # from which the turn stops there (the window's long constant-omega rollouts
            # would spin past it)
            return self._rotate(err)
        return np.array([float(a0), float(a1)])

    def lane_velocities(self, obs: Any, dvel: np.ndarray) -> np.ndarray:
        """The sensed discs' velocities, 0 for those seen to wander (sensed for a second and
        not steady, :class:`~pathfuse.planners.controllers.social.SteadyDiscs`): the lanes
        of ``replan_lane_s`` are those of the discs that may keep their velocity (ours)."""
        ids = disc_ids(obs, dvel.shape[0])
        keep = self.steady.trusted(ids).astype(np.float64)
        return np.ascontiguousarray(dvel * keep[:, None]) if keep.size else dvel

    def _sequences(self, obs: Any, path: np.ndarray, kk: int, pts: np.ndarray, cum: np.ndarray,
                   k: int, dpos: np.ndarray, dvel: np.ndarray, drad: np.ndarray) -> np.ndarray:
        """Among sensed discs (``among_discs="mppi"``, ours): the command of MPPI's sampled
        control sequences (:mod:`pathfuse.planners.controllers.mppi`, its defaults and
        critics) tracking Algorithm 2's local path from the robot, then the A* path beyond
        the point nearest that path's end.  A sequence can swerve or get away after it has
        accelerated, which the window's one command held over the horizon cannot."""
        m = self._mppi
        if self._last_seq != self.ticks - 1:
            # entering among discs: the sequences start from the present command, not from
            # the optimum of the last stretch with discs, seconds old (on the dynamic
            # benchmark's first 50 scenarios: 80/72/54 % -> 84/78/62 % with 2/4/8 discs)
            m.nominal[:, 0] = float(obs.command[0])
            m.nominal[:, 1] = float(obs.command[1])
        self._last_seq = self.ticks
        e = path[-1]
        k0 = min(max(int(k), 0), pts.shape[0] - 1)
        j = k0 + int(np.argmin(np.hypot(pts[k0:, 0] - e[0], pts[k0:, 1] - e[1])))
        m._set_path(np.concatenate([path[kk:], pts[j + 1:]]))
        m._sensed = (dpos, dvel, drad)
        cmd = obs.command
        self.sequenced += 1
        x, y, th = float(obs.position[0]), float(obs.position[1]), float(obs.heading)
        a0, a1 = m._choose(x, y, th, float(cmd[0]), float(cmd[1]), dpos, dvel, drad,
                           self._steady)
        if self.evader is not None and self.evader.choose(
                m.costmap, m.f, x, y, th, float(cmd[0]), float(cmd[1]), m.nominal, dpos, dvel,
                drad, self.passes, self._steady if self.evade_steady else None):
            # ours (evade, :mod:`pathfuse.planners.controllers.evade`): the plan stops in a
            # disc's predicted sweep; an escape out of every sensed disc's sweep instead
            a0, a1 = float(m.nominal[0, 0]), float(m.nominal[0, 1])
        if self.walker_escape:
            a0, a1 = self._walker_escape(obs, x, y, th, float(a0), float(a1), pts, cum, k,
                                         dpos, dvel, drad)
        return np.array([a0, a1])

    def _walker_escape(self, obs: Any, x: float, y: float, th: float, a0: float, a1: float,
                       pts: np.ndarray, cum: np.ndarray, k: int, dpos: np.ndarray,
                       dvel: np.ndarray, drad: np.ndarray) -> tuple[float, float]:
        """Ours (the fusion's ``walker_escape``): ``dwa``'s lane escape
        (:func:`~pathfuse.planners.controllers.dwa_escape.escape_command`) applied to the
        sequences' command ``(a0, a1)`` as ``dwa`` applies it to its own: set off only by
        the discs not seen to wander (:class:`~pathfuse.planners.controllers.social.SteadyDiscs`),
        the heading escaped towards last tick kept (hysteresis), the sequences scored against
        the A* path from the robot's progress with the window's settings (``dwa``'s defaults
        and the fusion's social critics).  The command still passes the shield."""
        from pathfuse.planners.controllers.dwa_escape import escape_command

        ids = disc_ids(obs, drad.shape[0])
        trust = self.steady.trusted(ids)
        cmd = obs.command
        kk = min(max(int(k), 0), pts.shape[0] - 1)
        v, w, hd = escape_command(self.costmap, self.f, self.walker_escape_s, x, y, th,
                                  float(cmd[0]), float(cmd[1]), a0, a1, pts, cum, kk, dpos,
                                  dvel, drad, self._steady, trust, self._escape_heading,
                                  self.walker_escape_hold)
        self._escape_heading = hd
        if hd == hd:
            self.walker_escapes += 1
            return float(v), float(w)
        return a0, a1

    def _rotate(self, err: float) -> np.ndarray:
        rb = self.problem.robot
        dt = self.f.dt_s
        rate = min(abs(err) / dt, rb.max_yaw_rate_radps)
        if math.isfinite(rb.max_yaw_accel_radps2):
            rate = min(rate, math.sqrt(2.0 * rb.max_yaw_accel_radps2 * abs(err)))
        self.rotations += 1
        return np.array([0.0, rate if err > 0 else -rate])
