"""The Dynamic Window Approach (Fox, Burgard and Thrun, IEEE RA Magazine 1997), as ``"dwa"``.

The local planner that ships with ROS (move_base's ``dwa_local_planner``, Nav2's
DWB) and the baseline of the BARN challenge: grid A* gives the global path (or
the global planner that ``global_planner`` names, which then also makes every
replan, on the map with the sensed discs' cells blocked), then every control
period:

1. **The dynamic window.**  The commands reachable within one tick under the
   acceleration limits: for a diff-drive robot ``v`` in ``[v0 - a dt, v0 + a
   dt]`` and ``omega`` in ``[omega0 - alpha dt, omega0 + alpha dt]`` (within
   the speed and yaw-rate limits), sampled on a ``v_samples x w_samples``
   grid (plus going straight); for a holonomic robot, velocity vectors of
   ``v_samples`` speeds x ``w_samples`` directions, moved into the window
   ``|u - u0| <= a dt``.
2. **Rollouts.**  Each sample is held for ``horizon_s`` and rolled out in
   pieces of ``sim_step_s`` (exact arcs; each piece's chord is checked with
   the exact segment distance to the occupied squares, less the arc's
   deviation bound).  A sample is *admissible* when this tick's arc and chord
   are clear and, should the rollout hit the static map later, the robot
   could still stop before (Fox et al.'s ``v <= sqrt(2 a dist)``, as the
   travel before the collision exceeding one tick plus the braking
   distance).  The sensed moving discs are predicted at constant velocity;
   a sample they would hit within this tick is not admissible.
3. **Critics** (in the manner of ROS's DWB critics), summed with weights:
   *path distance* (from the rollout's end to the global path near the
   robot's progress), *goal distance* (the path left to the goal beyond
   the end's projection on the path), *heading* (the end heading against
   the direction to the carrot, ``lookahead_m`` of path beyond that
   projection), *speed* (``(v_max - v) / v_max``),
   *path align* (the rollout's mean distance to the global path, as DWB's
   PathAlign; not while a moving disc is sensed), *obstacle*
   (``exp(-gap / inflation_decay_m)`` of the least static gap within
   ``obstacle_range_m``, as Nav2's inflation layer, plus a steep penalty
   inside the robot's ``clearance_m``), *keep* (ours: the shortfall of the
   rollout's least gap over its first ``keep_horizon_s`` against the gap the
   global path keeps over that stretch ahead, up to ``keep_m``, relative to
   that gap, squared; off while a moving disc is sensed) and
   *moving* (a predicted
   collision with a sensed disc: 1.5 + 2 x its depth relative to the two radii + 0.5 x how
   early it starts within the horizon, so that a swerve that makes the overlap shallower
   beats standing in the disc's way; without one, ``exp(-gap / 0.25 m)`` of the least
   predicted gap).

The least-cost admissible sample is commanded.  With none, the robot slows
as hard as it can and turns towards the path ahead.  Among moving discs a
diff-drive robot has a *lane escape* (ours, ``lane_escape``,
:mod:`~pathfuse.planners.controllers.dwa_escape`): while standing would be
walked into and so would the chosen sample, the first step of the best
turn-then-go sequence that no disc touches is commanded instead.  The robot's progress
along the path only moves forward, to path points in sight
(:func:`~pathfuse.field.pathing.advance_progress`), and the global path is
replanned from the robot's position every ``replan_period_s`` (1 s, as
Nav2's default behaviour tree does), with the sensed discs as blocked
cells (grown by the robot's radius, as Nav2's obstacle layer puts what the
sensors see into the global costmap; the static path when they box the
robot in).  Online
(:func:`pathfuse.simulate`) this runs once per tick with the robot's model;
offline (:func:`pathfuse.plan`) the controller drives a simulated robot on
the static map, by default a diff-drive one
(:data:`pathfuse.robot.DIFF_DRIVE_DEFAULTS`, 1 m/s) with a tick of
``dt_s``, to within ``goal_tolerance_m`` of the goal (then a clear straight
move onto it ends the path), a stall (net move below ``stall_distance_m``
over ``stall_steps`` ticks: ``LOCAL_MINIMUM``) or the tick cap
(``Budget.max_iterations`` counts ticks).  ``info`` holds ``headings`` and
``commands`` per tick.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["........", "...##...", "........"])
>>> r = plan(g, (0.5, 0.5), (7.5, 2.5), planner="dwa", robot_radius_m=0.2)
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [7.5, 2.5])
>>> r.info["commands"].shape[1], bool(r.info["min_clearance_m"] > 0)
(2, True)
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pathfuse.costmap import costmap_for
from pathfuse.field.pathing import advance_progress, polyline_cumlen
from pathfuse.geometry import MARGIN_FRAC, segment_is_clear
from pathfuse.planners.base import Controller, Observed, Outcome, sensed_discs
from pathfuse.planners.controllers.dwa_checks import NO_NEAR, NearSquares, near_squares
from pathfuse.planners.controllers.dwa_escape import escape_command
from pathfuse.planners.controllers.dwa_kernel import (
    KEEP_M,
    KEEP_WEIGHT,
    DwaTick,
    dwa_choose_near,
    dwa_tick,
    pack_dwa,
    relaxed,
    route_tangent,
)
from pathfuse.planners.controllers.replan import replan_around_discs
from pathfuse.planners.controllers.social import (
    EVERY_DISC,
    PassingSides,
    SteadyDiscs,
    disc_ids,
    path_sides,
)
from pathfuse.planners.params import GlobalAStarParams, GlobalChoice, SocialParams
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, Status
from pathfuse.robot import RobotModel
from pathfuse.sweep import unicycle_pose
from pathfuse.validate import param

__all__ = ["DWAParams", "DWAController"]


FIELD_CELL_M = 0.05
"""The side (m) of the clearance lattice dwa's costmap is built with (the map's cells split up
to 8 x 8, :func:`pathfuse.costmap.clearance_lattice`): the lattice bound loses up to a lattice
cell's diagonal, so on a map of 1 m cells the map's own cells (1.4 m lost) let hardly a rollout
piece skip the exact static search; the choices are the same (the shortcut is exact)."""


@dataclass(frozen=True)
class DWAParams(SocialParams, GlobalAStarParams, GlobalChoice):
    """Parameters of ``dwa`` (the sampling, the horizon and the critics' weights)."""

    v_samples: int = param(7, ge=2, help="linear speeds sampled in the window (holonomic: "
                                         "speeds from 0 to the limit)")
    w_samples: int = param(15, ge=3, help="yaw rates sampled in the window (holonomic: "
                                          "3 x this many directions)")
    horizon_s: float = param(2.5, gt=0, unit="s", help="how long each sample is rolled out")
    sim_step_s: float = param(0.1, gt=0, unit="s", help="length of a rollout piece")
    dt_s: float = param(0.1, gt=0, unit="s",
                        help="control period offline (online: the scenario's dt)")
    path_weight: float = param(1.0, ge=0, unit="1/m",
                               help="path-distance critic (rollout end to the global path)")
    goal_weight: float = param(1.0, ge=0, unit="1/m",
                               help="goal-distance critic (path left beyond the rollout end)")
    heading_weight: float = param(0.3, ge=0, help="heading critic (per half turn)")
    speed_weight: float = param(0.2, ge=0, help="speed critic (slower = worse)")
    obstacle_weight: float = param(0.5, ge=0, help="obstacle critic (static gap)")
    keep_weight: float = param(KEEP_WEIGHT, ge=0,
                               help="keep critic (ours): the shortfall of the rollout's least "
                                    "static gap within keep_horizon_s against the gap the "
                                    "global path keeps ahead (up to keep_m), squared; 0 = off "
                                    "(5 before issue 17's clearance round)")
    keep_m: float = param(KEEP_M, gt=0, unit="m",
                          help="keep critic: the most gap it asks for (0.3 before issue 17's "
                               "clearance round)")
    keep_horizon_s: float = param(1.0, gt=0, unit="s",
                                  help="keep critic: how far along each rollout it looks")
    path_align_weight: float = param(1.0, ge=0, unit="1/m",
                                     help="path-align critic (as DWB's PathAlign): the "
                                          "rollout's mean distance to the global path")
    moving_weight: float = param(8.0, ge=0, help="moving-disc critic (predicted collision)")
    obstacle_range_m: float = param(0.5, gt=0, unit="m",
                                    help="static gaps beyond this cost nothing")
    inflation_decay_m: float = param(0.1, gt=0, unit="m",
                                     help="the obstacle cost exp(-gap / decay)")
    lookahead_m: float = param(0.5, gt=0, unit="m",
                               help="heading critic: aim at the path this far beyond the "
                                    "rollout end's projection")
    goal_tolerance_m: float = param(0.25, gt=0, unit="m",
                                    help="offline: within this a clear straight move onto "
                                         "the goal ends the path")
    replan_period_s: float = param(1.0, ge=0, unit="s",
                                   help="replan the global A* path from the robot's position, "
                                        "around the sensed discs, this often (Nav2's default "
                                        "1 Hz; 0 = never)")
    path_sides: bool = param(True, help="ours: a disc's passing side is committed as the "
                                        "replanned global path passes it (discs of a group "
                                        "then get one side; off, or social off: the side of "
                                        "the chosen rollout); with social_replan, the path "
                                        "is also replanned as soon as a new disc is sensed")
    inside_clearance: bool = param(True, help="ours: when the robot stands inside its own "
                                              "clearance and no sample keeps it, the samples "
                                              "that keep the gap it has are admissible "
                                              "(false: it stands, turning to the path)")
    dwell_s: float = param(1.5, ge=0, le=30, unit="s",
                           help="yield outside a walker's lane (ours): a rollout pays "
                                "dwell_weight where it ends within personal_m of the lane a "
                                "sensed disc, predicted at constant velocity, sweeps in the "
                                "dwell_s after the rollout (the spot where the robot may have "
                                "to stand); 0 = off (dwa's default was 0 before issue 18's "
                                "dwa work)")
    dwell_steady: bool = param(False, help="ours: the dwell critic counts only the steady "
                                           "discs (social.SteadyDiscs, as the fusion's); "
                                           "false: every sensed disc")
    passive_safety: bool = param(True, help="plan for the safety shield's passive safety "
                                            "(ours): a pass closer to a sensed disc than it "
                                            "can travel while the robot stops counts as a "
                                            "collision; false: dwa's constant-velocity "
                                            "prediction alone")
    lane_escape: bool = param(True, help="ours (dwa_escape; diff-drive): while a robot "
                                         "standing still would be touched by a sensed disc "
                                         "within lane_escape_s and so would the chosen "
                                         "sample, command the first step of the best "
                                         "turn-then-go sequence out of the discs' lanes "
                                         "that none touches; false = off")
    lane_escape_s: float = param(4.0, gt=0, le=10, unit="s",
                                 help="lane escape: how far ahead standing and the sequences "
                                      "are checked")
    lane_escape_steady: bool = param(True, help="lane escape: set off only by discs not "
                                                "seen to wander (sensed for 1 s and not "
                                                "steady, social.SteadyDiscs); false: by "
                                                "every sensed disc")
    stall_steps: int = param(50, ge=1, help="offline: look-back of the stall test, in ticks")
    stall_distance_m: float = param(0.05, gt=0, unit="m",
                                    help="offline: a net move below this over stall_steps "
                                         "ticks is a stall")

    def __post_init__(self) -> None:
        super().__post_init__()
        check_tick_work(self.v_samples, self.w_samples, self.horizon_s, self.sim_step_s)


TICK_PIECES = 1_000_000
"""The most rollout pieces one DWA tick may compute: ``v_samples x w_samples x
ceil(horizon_s / sim_step_s)`` (a holonomic robot rolls out 3 x as many, see ``w_samples``).

Each bound of :data:`~pathfuse.planners.params.BOUNDS` alone allows 64 x 128 x 10,000
pieces; a ``time_limit`` is checked between ticks, so such a tick could not honour it.
Measured with ``plan()`` on an 8 x 5 map (x86_64, 2 shared cores, load 4-8, CPU time): a
diff-drive tick at 64 x 128 x 1000 pieces took 1.19 s (so about 12 s at 10,000); at this
budget (64 x 128 x 122) a diff-drive tick took 0.19 s and a holonomic one 0.36 s, and a
``time_limit`` of 1 s ended the plan after 1.2 and 1.4 s of wall time.
The defaults use 7 x 15 x 25 = 2,625."""


def check_tick_work(v_samples: int, w_samples: int, horizon_s: float,
                    sim_step_s: float) -> None:
    """Refuse a DWA sampling whose one tick would roll out more than :data:`TICK_PIECES`.

    >>> check_tick_work(64, 128, 2.5, 0.1)
    >>> try:
    ...     check_tick_work(64, 128, 10, 0.001)
    ... except ConfigError as exc:
    ...     print(*str(exc).split(", "), sep="\\n")
    v_samples x w_samples x horizon_s / sim_step_s: must be at most 1000000 rollout pieces a tick
    got 64 x 128 x 10000 = 81920000
    """
    pieces = max(1, int(math.ceil(horizon_s / sim_step_s - 1e-9)))
    work = v_samples * w_samples * pieces
    if work > TICK_PIECES:
        raise ConfigError(f"v_samples x w_samples x horizon_s / sim_step_s: must be at most "
                          f"{TICK_PIECES} rollout pieces a tick, got {v_samples} x "
                          f"{w_samples} x {pieces} = {work}")


def _offline_robot(problem: Problem) -> RobotModel:
    rb = problem.robot
    if rb is None:
        return RobotModel.diff_drive(radius_m=problem.robot_radius_m,
                                     clearance_m=problem.clearance_m)
    return rb  # type: ignore[no-any-return]


class DWAController(Controller):
    """The Dynamic Window Approach (see the module docstring)."""

    name = "dwa"
    label = "dynamic window"
    native_unicycle: ClassVar[bool] = True

    def __init__(self, problem: Problem, params: Any, plan: Any = None, *,
                 dt: float | None = None, max_speed: float | None = None) -> None:
        super().__init__(problem, params, plan, dt=dt, max_speed=max_speed)
        p = params
        self.robot = rb = _offline_robot(problem) if problem.robot is None or not self.online \
            else problem.robot
        self.tick_s = float(dt) if dt is not None else float(p.dt_s)
        g = problem.grid
        self.clear_m = problem.robot_radius_m + MARGIN_FRAC * g.resolution
        self._set_path(np.asarray(plan.waypoints, dtype=np.float64).reshape(-1, 2))
        self.replan_every = int(round(p.replan_period_s / self.tick_s)) \
            if p.replan_period_s > 0 else 0
        self.ticks = 0
        self.replans = 0
        # the map, the radius and the clearance kept (self.clear_m) in one object; its
        # clearance lattice (the lower bound that lets a rollout piece skip the exact
        # static search) split to FIELD_CELL_M, not the map's cells
        self.costmap = costmap_for(g, float(problem.robot_radius_m), field_cell_m=FIELD_CELL_M)
        self.f = pack_dwa(
            self.tick_s, rb.min_speed_mps, rb.max_speed_mps, rb.max_accel_mps2,
            rb.max_yaw_rate_radps, rb.max_yaw_accel_radps2,
            max(problem.clearance_m, rb.clearance_m), p.horizon_s, p.sim_step_s,
            p.v_samples, p.w_samples, p.path_weight, p.goal_weight, p.heading_weight,
            p.speed_weight, p.obstacle_weight, p.moving_weight, p.obstacle_range_m,
            p.lookahead_m, p.inflation_decay_m, not rb.is_diff_drive,
            p.passive_safety,
            w_align=p.path_align_weight, near_s=p.keep_horizon_s, w_keep=p.keep_weight,
            keep_m=p.keep_m, w_social=p.social_weight if p.social else 0.0,
            personal_m=p.personal_m, w_side=p.side_weight if p.social else 0.0,
            dwell_s=p.dwell_s if p.social else 0.0, w_dwell=p.dwell_weight,
            inside_clear=p.inside_clearance)
        self.near = _near_for(g, self.costmap, self.f)
        self.sides = PassingSides(p.personal_m)
        self.steady = SteadyDiscs(self.tick_s)
        self.reach_m = 2.0 * rb.max_speed_mps * self.tick_s + g.resolution + 1.0
        self.no_choice = 0
        self.escapes = 0
        self._escape_heading = math.nan
        self._sensed = _NO_DISCS
        self._relaxed_until = -1
        self._f_relaxed = relaxed(self.f)

    def _set_path(self, pts: np.ndarray) -> None:
        gx, gy = self.problem.goal
        if pts.shape[0] == 0 or pts[-1, 0] != gx or pts[-1, 1] != gy:
            pts = np.concatenate([pts, [[gx, gy]]])
        self.pts = np.require(pts, dtype=np.float64, requirements=("C", "W"))
        self.cum = polyline_cumlen(self.pts)
        self.k = 0

    def _replan(self, x: float, y: float) -> None:
        dpos, _, drad = self._sensed
        p = self.params
        pts = replan_around_discs(self.problem, x, y, dpos, drad, p,
                                  personal_m=p.personal_m if p.social and p.social_replan
                                  else 0.0)
        self.replans += 1
        if pts is not None:
            self._set_path(pts)
            self.global_path = self.pts

    def relax(self, seconds: float) -> bool:
        """Recovery (ours): no obstacle critic and no margin for ``seconds``, and a new
        global path (the shield still keeps the robot clear)."""
        self._relaxed_until = self.ticks + int(round(seconds / self.tick_s))
        self._pending_replan = True
        return True

    _pending_replan = False
    _seen: set[int] = set()

    def _choose(self, x: float, y: float, th: float, c0: float, c1: float, dpos: np.ndarray,
                dvel: np.ndarray, drad: np.ndarray, ids: np.ndarray | None = None
                ) -> tuple[float, float]:
        p = self.params
        new_disc = False
        if ids is not None and p.social and p.social_replan and p.path_sides and len(ids):
            seen = {int(i) for i in ids}
            new_disc = bool(seen - self._seen)
            self._seen = seen
        if self._pending_replan or new_disc or (self.replan_every and self.ticks
                                                and self.ticks % self.replan_every == 0):
            self._pending_replan = False
            self._replan(x, y)
        self.ticks += 1
        self.k = int(advance_progress(x, y, self.pts, self.cum, self.k, self.reach_m,
                                      self.costmap, self.clear_m))
        f = self._f_relaxed if self.ticks <= self._relaxed_until else self.f
        n = drad.shape[0]
        ids = np.arange(n) if ids is None else ids
        chosen = np.zeros((n, 2))
        route = route_tangent(self.pts, self.k, th)
        steady = EVERY_DISC
        escape = p.lane_escape and not f.holonomic
        if (p.social and p.dwell_s > 0.0 and p.dwell_steady) or (escape and
                                                                  p.lane_escape_steady):
            # ours, as the fusion's (SteadyDiscs); every tick, so a disc that was out of
            # sight starts its history again
            mask = self.steady.update(ids, dvel)
            if n and p.social and p.dwell_s > 0.0 and p.dwell_steady:
                steady = mask
        tick = dwa_tick(self.costmap, f, self.pts, self.cum, self.k, route, steady)
        a0, a1, count, _ = dwa_choose_near(self.costmap, self.near, f, tick, x, y, th, c0, c1,
                                           self.pts, self.cum, self.k, dpos, dvel, drad,
                                           self.sides.sides(ids), chosen)
        if n and escape:
            # ours (dwa_escape): out of a walker's lane rather than standing in it; set off
            # only by discs not seen to wander (social.SteadyDiscs, as the fusion's lanes)
            trust = EVERY_DISC
            if p.lane_escape_steady:
                trust = self.steady.trusted(ids)
            v, w, hd = escape_command(self.costmap, f, p.lane_escape_s, x, y, th, c0, c1,
                                      float(a0), float(a1), self.pts, self.cum, self.k, dpos,
                                      dvel, drad, tick.steady, trust, self._escape_heading)
            self._escape_heading = hd
            if hd == hd:
                self.escapes += 1
                a0, a1 = v, w
        else:
            self._escape_heading = math.nan
        if n:
            prefer = path_sides(self.pts, self.k, dpos, drad, self.problem.robot_radius_m,
                                p.personal_m) if p.social and p.path_sides else None
            self.sides.update(ids, chosen, dpos, (x, y), route, drad,
                              self.problem.robot_radius_m, prefer)
        if count == 0:
            self.no_choice += 1
        return float(a0), float(a1)

    # ------------------------------------------------------------------ online
    def act(self, obs: Observed) -> np.ndarray:
        """``(v, omega)`` for a diff-drive robot, ``(vx, vy)`` for a holonomic one."""
        dpos, dvel, drad = sensed_discs(obs)
        self._sensed = (dpos, dvel, drad)
        cmd = obs.command
        a0, a1 = self._choose(float(obs.position[0]), float(obs.position[1]),
                              float(obs.heading), float(cmd[0]), float(cmd[1]), dpos, dvel,
                              drad, disc_ids(obs, drad.shape[0]))
        return np.array([a0, a1])

    # ------------------------------------------------------------------ offline
    def run(self, deadline: float | None) -> Outcome:
        """Drive a simulated robot to the goal on the static map (see the module docstring)."""
        pb = self.problem
        p = self.params
        g = pb.grid
        rb = self.robot
        ox, oy = g.origin
        x, y = pb.start
        gx, gy = pb.goal
        th = rb.heading_rad if rb.heading_rad is not None else (
            math.atan2(gy - y, gx - x) if (gx != x or gy != y) else 0.0)
        cap = pb.budget.max_iterations
        max_ticks = int(cap) if cap is not None else int(math.ceil(
            10.0 * (g.width + g.height) * g.resolution / (rb.max_speed_mps * self.tick_s)))
        max_ticks += 0 if cap is not None else 1000
        path = [(x, y)]
        heads = [th]
        cmds: list[tuple[float, float]] = []
        c0 = c1 = 0.0
        status = Status.MAX_ITERATIONS
        msg = ""
        t0 = time.perf_counter()
        ticks = 0
        dpos, dvel, drad = _NO_DISCS
        holo = not rb.is_diff_drive
        tol = p.goal_tolerance_m
        while True:
            if math.hypot(x - gx, y - gy) <= tol and segment_is_clear(
                    x, y, gx, gy, g.occupied, ox, oy, g.resolution, self.clear_m):
                if (x, y) != (gx, gy):
                    path.append((gx, gy))
                    heads.append(th)
                status = Status.SUCCESS
                msg = f"reached the goal in {ticks} ticks ({ticks * self.tick_s:.1f} s)"
                break
            if ticks >= max_ticks:
                msg = f"tick cap of {max_ticks} ticks reached {self._where(x, y)}"
                break
            if deadline is not None and time.perf_counter() > deadline:  # every tick
                status = Status.TIMEOUT
                msg = f"time limit reached after {ticks} ticks, {self._where(x, y)}"
                break
            a0, a1 = self._choose(x, y, th, c0, c1, dpos, dvel, drad)
            if holo:
                x, y = x + a0 * self.tick_s, y + a1 * self.tick_s
                if a0 or a1:
                    th = math.atan2(a1, a0)
            else:
                x, y, th = unicycle_pose(x, y, th, a0, a1, self.tick_s)
            c0, c1 = a0, a1
            ticks += 1
            path.append((x, y))
            heads.append(th)
            cmds.append((a0, a1))
            n = len(path)
            if n > p.stall_steps and math.hypot(
                    x - path[n - 1 - p.stall_steps][0],
                    y - path[n - 1 - p.stall_steps][1]) < p.stall_distance_m:
                status = Status.LOCAL_MINIMUM
                msg = (f"local minimum {self._where(x, y)}: moved less than "
                       f"{p.stall_distance_m:g} m over the last {p.stall_steps} ticks")
                break
        elapsed = time.perf_counter() - t0
        info = {"headings": np.array(heads), "commands": np.array(cmds).reshape(-1, 2),
                "dt_s": self.tick_s, "robot_model": rb.kind, "ticks": ticks,
                "ticks_without_admissible_command": self.no_choice, "replans": self.replans,
                "step_time_s": elapsed}
        return Outcome(status, np.array(path, dtype=np.float64).reshape(-1, 2), ticks,
                       max(elapsed, 1e-9), msg, info)

    def _where(self, x: float, y: float) -> str:
        gx, gy = self.problem.goal
        return f"at ({x:.3f}, {y:.3f}), {math.hypot(x - gx, y - gy):.3f} m from the goal"

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (dwa_choose_near, advance_progress, route_tangent, escape_command)

    @classmethod
    def warmup(cls) -> None:
        if _WARM[0]:
            return
        from pathfuse.grid import GridMap
        from pathfuse.result import Budget

        g = GridMap.from_rows(["....", ".#..", "...."])
        for robot in (RobotModel.diff_drive(radius_m=0.1), RobotModel(radius_m=0.1)):
            pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5), 0.1, Budget(max_iterations=3),
                                robot=robot)

            class _P:
                waypoints = np.array([[0.5, 0.5], [2.5, 0.5], [3.5, 2.5]])

            c = cls(pb, DWAParams(), _P())
            c.run(None)
            for ro in (False, True):
                q = np.ones((1, 2))
                q.setflags(write=not ro)
                dwa_choose_near(c.costmap, c.near, c.f, DwaTick(math.inf, 0.0, 0.0), 0.5, 0.5,
                                0.0, 0.0, 0.0, c.pts, c.cum, 0, q, q, np.ones(1), np.zeros(1),
                                np.zeros((1, 2)))
        route_tangent(c.pts, 0, 0.0)
        _WARM[0] = True


_WARM = [False]
NEAR_BUDGET = 5e6
"""The most cells :func:`_near_for` visits to build a map's near-square lists (about 30 ms)."""
_NEAR: weakref.WeakKeyDictionary[Any, dict[tuple[float, ...], NearSquares]] = \
    weakref.WeakKeyDictionary()


def _near_for(grid: Any, cm: Any, f: Any) -> NearSquares:
    """The squares near each lattice cell of ``cm`` (:func:`.dwa_checks.near_squares`), for
    the rollout pieces of the settings ``f`` (at most ``max_speed x sim_step`` long, within
    ``clear + margin + obstacle_range`` and the arcs' deviation), built once per map; none
    where building them would visit more than :data:`NEAR_BUDGET` cells (BARN's 0.05 m maps
    at 2 m/s: 150 ms a map, against 0.5-1 s of decisions in an episode)."""
    hd = cm.field_res_m * math.sqrt(0.5)
    reach = hd + 0.5 * f.max_speed_mps * f.sim_step_s * 1.01 + 1e-6
    # the chord's deviation from an arc (arc_deviation_bound; 0: holonomic rollouts are straight)
    e = 0.0 if f.holonomic else f.max_speed_mps * f.max_yaw_rate_radps * f.sim_step_s ** 2 / 8.0
    cap = cm.clear_m + f.margin_m + f.obstacle_range_m + e
    if not math.isfinite(cap + reach) or cm.field.size <= 1:
        return NO_NEAR
    dmax = cap + reach + 2.0 * hd + 1e-3
    side = 2.0 * (dmax + 2.0 * reach) / cm.res_m + 2.0
    if np.count_nonzero(cm.field <= dmax) * side * side > NEAR_BUDGET:
        return NO_NEAR
    key = (cm.radius_m, cm.clear_m, cm.field_res_m, reach, dmax)
    per = _NEAR.setdefault(grid, {})
    hit = per.get(key)
    if hit is None:
        hit = per[key] = near_squares(cm, reach, dmax)
    return hit
_NO_DISCS = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))


register(PlannerSpec(
    name="dwa",
    params_cls=DWAParams,
    description="A* + the Dynamic Window Approach (Fox et al. 1997; ROS's local planner): "
                "samples the commands reachable in one tick, rolls them out, scores path, "
                "goal, heading, speed and clearance",
    controller=DWAController,
    global_planner="astar",
))
