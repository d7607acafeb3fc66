"""Model Predictive Path Integral control (Williams et al. 2016/2017; Nav2's default controller
since Iron), as ``"mppi"``.

Grid A* on the robot's c-space gives the global path (replanned from the
robot's position every ``replan_period_s``, around the sensed discs, as
``dwa`` does, and, ours, keeping ``replan_clearance_m`` from obstacles where
the room allows: the cost-aware A* of the safety margin); then every control
period:

1. **Sampling.**  ``batch_size`` control sequences of ``time_steps`` steps of
   ``model_dt_s``: the previous optimal sequence shifted by one tick, plus
   Gaussian noise of per-channel standard deviation (``vx_std_mps`` and
   ``wz_std_radps`` for a diff-drive robot's ``(v, omega)``; ``vx_std_mps``
   and ``vy_std_mps`` for a holonomic robot's ``(vx, vy)``), each clipped
   step by step to the robot's limits and to the window its acceleration
   limits reach from the previous step (from the last command for the first
   step).  Four samples are not noise (ours): the nominal sequence itself, a
   pure-pursuit guide along the path at full speed, a regulated one whose
   speed falls with the clearance (the limit x gap / ``inflation_radius_m``,
   at least ``slow_guide_speed_mps``, as Nav2's regulated pure pursuit) and
   that aims at half the lookahead, so it keeps close to the path through
   narrow passages, and braking at the limits.
2. **Rollouts** with the exact unicycle (:func:`pathfuse.sweep.unicycle_pose`)
   or straight moves.
3. **Critics**, weighted and summed (Nav2's critics, in our terms):
   *collision* with the static map (``collision_cost`` x 1..2, the earlier
   the more, ending the rollout; decided by a lower bound of the clearance
   read from a fine distance field, :func:`clearance_field`, and the map's
   edge, and by the exact distance of the step's chord where that bound is
   too close), *obstacle* (Nav2's inflation layer: ``exp(-cost_scaling_factor
   x gap)`` within ``inflation_radius_m`` of the occupied squares, averaged
   over the steps with ``obstacle_weight`` and at the rollout's closest point
   with ``obstacle_peak_weight``; with ``relative_inflation`` (ours) only
   what exceeds the global path's own cost at that point counts, so a
   passage the path has to take is no barrier; plus a linear penalty inside
   the robot's safety margin), *path align* (mean distance of the rollout to the global
   path), *path follow* (path left beyond the rollout end's projection:
   progress), *path angle* (the end heading against a carrot ``lookahead_m``
   further along the path; diff-drive), *goal* (mean distance to the goal,
   instead of path align and angle once less than ``goal_distance_m`` of
   path is left), *moving discs* (predicted at constant velocity: a predicted
   collision costs ``disc_collision_cost`` x (1 + its depth + how early it
   starts); near passes ``exp(-gap / disc_decay_m)``), *smoothness* (squared
   control changes in units of the noise) and *prefer forward* (distance
   driven in reverse).
4. **Update**: softmax weights ``exp(-(cost - min) / temperature)``; the new
   optimal sequence is the weighted mean of the (clipped) samples, i.e. the
   nominal plus the weighted mean of the noise as applied; with
   ``keep_better_guide`` (ours) the fast guide replaces it when it scores
   better (on an open path the noise's mean is never exactly straight).  Its
   first control is commanded; it is inside the window the world allows (a
   mean of sequences that keep the limits keeps them).

The noise comes from a numpy ``Generator`` seeded with ``seed``, so an
episode is reproduced bit for bit.  Online the command goes through the
safety shield (:mod:`pathfuse.shield`) like every controller's; offline
(:func:`pathfuse.plan`) the controller drives a simulated robot on the
static map through the same shield (unless the robot's ``shield`` is off:
then a tick that would touch the map ends the run with ``COLLISION``), by
default a diff-drive one (:data:`pathfuse.robot.DIFF_DRIVE_DEFAULTS`, 1 m/s)
with a tick of ``dt_s``, to within ``goal_tolerance_m`` of the goal (then a
clear straight move onto it ends the path), a stall (``LOCAL_MINIMUM``), the
tick cap (``Budget.max_iterations`` counts ticks, ``MAX_ITERATIONS``) or the
time limit (``TIMEOUT``).  ``info`` holds ``headings`` and ``commands`` per
tick and ``shield_counts`` (indexed by :data:`pathfuse.shield.CODE_NAMES`).

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["........", "...##...", "........"])
>>> r = plan(g, (0.5, 0.5), (7.5, 2.5), planner="mppi", robot_radius_m=0.2)
>>> r.status.name, r.path[0].tolist(), r.path[-1].tolist()
('SUCCESS', [0.5, 0.5], [7.5, 2.5])
>>> r.info["commands"].shape[1], bool(r.info["min_clearance_m"] > 0)
(2, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pathfuse.costmap import NO_DISCS, clearance_lattice, costmap_for
from pathfuse.field.pathing import advance_progress, polyline_cumlen
from pathfuse.geometry import MARGIN_FRAC, segment_is_clear
from pathfuse.grid import GridMap
from pathfuse.planners.base import Controller, Observed, Outcome, sensed_discs
from pathfuse.planners.controllers.mppi_escape import ESCAPE_DWELL_S, escape_sequence
from pathfuse.planners.controllers.mppi_kernel import mppi_optimise, pack_mppi, path_inflation
from pathfuse.planners.controllers.replan import replan_around_discs
from pathfuse.planners.controllers.social import EVERY_DISC, SteadyDiscs, disc_ids
from pathfuse.planners.params import GlobalAStarParams, PersonalSpaceParams
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem
from pathfuse.result import Status
from pathfuse.robot import RobotModel
from pathfuse.sweep import arc_static_distance, segment_static_distance, unicycle_pose
from pathfuse.validate import param

__all__ = ["MPPIParams", "MPPIController", "clearance_field"]


@dataclass(frozen=True)
class MPPIParams(PersonalSpaceParams, GlobalAStarParams):
    """Parameters of ``mppi`` (the sampling, the update and the critics' weights)."""

    batch_size: int = param(600, ge=4, help="control sequences sampled per tick (Nav2: 1000)")
    time_steps: int = param(25, ge=2, help="steps of each sequence (Nav2: 56 of 0.05 s)")
    model_dt_s: float = param(0.1, gt=0, unit="s",
                              help="length of a step of the sequences (best equal to the "
                                   "control period, as Nav2 recommends)")
    vx_std_mps: float = param(0.2, gt=0, unit="m/s",
                              help="noise of the linear speed v (holonomic: of vx) (Nav2: 0.2)")
    vy_std_mps: float = param(0.2, gt=0, unit="m/s",
                              help="noise of vy (holonomic robot) (Nav2: 0.2)")
    wz_std_radps: float = param(0.4, gt=0, unit="rad/s",
                                help="noise of the yaw rate omega (diff-drive) (Nav2: 0.4)")
    temperature: float = param(0.3, gt=0,
                               help="softmax temperature of the update: lower follows the best "
                                    "samples more closely (Nav2: 0.3)")
    collision_cost: float = param(1000.0, ge=0,
                                  help="a rollout that hits the static map (x 1..2, the earlier "
                                       "the more; the rollout ends there)")
    obstacle_weight: float = param(5.0, ge=0,
                                   help="obstacle critic: the inflation cost averaged over the "
                                        "rollout")
    obstacle_peak_weight: float = param(5.0, ge=0,
                                        help="obstacle critic: the inflation cost at the "
                                             "rollout's closest point (ours)")
    inflation_radius_m: float = param(0.55, gt=0, unit="m",
                                      help="gaps beyond this cost nothing (Nav2's inflation "
                                           "layer default 0.55)")
    cost_scaling_factor: float = param(10.0, gt=0, unit="1/m",
                                       help="the obstacle cost exp(-factor x gap) (Nav2's "
                                            "inflation layer default 10)")
    path_align_weight: float = param(2.0, ge=0, unit="1/m",
                                     help="path-align critic (mean distance to the path)")
    path_follow_weight: float = param(5.0, ge=0, unit="1/m",
                                      help="path-follow critic (path left beyond the rollout "
                                           "end: progress) (Nav2: 5)")
    path_angle_weight: float = param(1.0, ge=0,
                                     help="path-angle critic, per half turn (diff-drive)")
    goal_weight: float = param(5.0, ge=0, unit="1/m",
                               help="goal critic (mean distance to the goal) (Nav2: 5)")
    goal_distance_m: float = param(1.4, gt=0, unit="m",
                                   help="the goal critic replaces path align and angle once "
                                        "this little path is left (Nav2: 1.4)")
    lookahead_m: float = param(0.6, gt=0, unit="m",
                               help="path-angle critic and guide sample: aim this far along "
                                    "the path")
    disc_collision_cost: float = param(100.0, ge=0,
                                       help="a predicted collision with a sensed moving disc "
                                            "(x 1 + depth + earliness)")
    disc_proximity_weight: float = param(5.0, ge=0,
                                         help="near passes to sensed moving discs "
                                              "(mean exp(-gap / disc_decay_m))")
    disc_decay_m: float = param(0.2, gt=0, unit="m", help="decay of the disc proximity cost")
    smoothness_weight: float = param(0.05, ge=0,
                                     help="squared control changes, in units of the noise")
    prefer_forward_weight: float = param(5.0, ge=0, unit="1/m",
                                         help="distance driven in reverse (Nav2: 5)")
    slow_guide_speed_mps: float = param(0.3, gt=0, unit="m/s",
                                        help="least speed of the regulated guide sample, "
                                             "which drives at the limit x gap / "
                                             "inflation_radius_m and keeps close to the path "
                                             "(ours)")
    relative_inflation: bool = param(True, help="the obstacle critic counts only the inflation "
                                                "cost beyond the global path's own at that "
                                                "point (ours; false = Nav2's absolute cost)")
    keep_better_guide: bool = param(True, help="take the fast guide instead of the weighted "
                                               "mean when it scores better (ours; false = the "
                                               "plain MPPI update)")
    lane_escape: bool = param(True, help="ours: while a robot standing still would be "
                                         "reached by a sensed disc within the horizon, score "
                                         "a fan of sequences turning out and driving off and "
                                         "take the best when it beats the optimum "
                                         "(mppi_escape); false = off")
    clearance_cell_m: float = param(0.0125, gt=0, unit="m",
                                    help="cell of the clearance lookup (the map's cells are "
                                         "split down to about this, up to 8 x 8)")
    seed: int = param(0, ge=0, help="seed of the sampling noise (the same seed reproduces an "
                                    "episode bit for bit)")
    dt_s: float = param(0.1, gt=0, unit="s",
                        help="control period offline (online: the scenario's dt)")
    goal_tolerance_m: float = param(0.25, gt=0, unit="m",
                                    help="offline: within this a clear straight move onto "
                                         "the goal ends the path")
    replan_period_s: float = param(1.0, ge=0, unit="s",
                                   help="replan the global A* path from the robot's position, "
                                        "around the sensed discs, this often (Nav2's default "
                                        "1 Hz; 0 = never)")
    replan_clearance_m: float = param(0.3, ge=0, unit="m",
                                      help="the replanned A* path pays to come closer than "
                                           "this to an obstacle (the cost-aware A* of a safety "
                                           "margin; 0 = the plain A*)")
    stall_steps: int = param(50, ge=1, help="offline: look-back of the stall test, in ticks")
    stall_distance_m: float = param(0.05, gt=0, unit="m",
                                    help="offline: a net move below this over stall_steps "
                                         "ticks is a stall")


def clearance_field(grid: GridMap, cell_m: float) -> tuple[np.ndarray, float]:
    """A clearance lower bound on a lattice of the map's cells split ``s x s`` (``s`` up to 8,
    so that a lattice cell is about ``cell_m``): :func:`pathfuse.costmap.clearance_lattice`,
    the distance layer of the :class:`~pathfuse.costmap.Costmap`.  Returns
    ``(field, lattice cell side)``; cached per map."""
    return clearance_lattice(grid, cell_m)


def _offline_robot(problem: Problem) -> RobotModel:
    rb = problem.robot
    if rb is None:
        return RobotModel.diff_drive(radius_m=problem.robot_radius_m,
                                     clearance_m=problem.clearance_m)
    return rb  # type: ignore[no-any-return]


_NO_DISCS = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))


class MPPIController(Controller):
    """Model Predictive Path Integral control (see the module docstring)."""

    name = "mppi"
    label = "model predictive path integral"
    native_unicycle: ClassVar[bool] = True

    def __init__(self, problem: Problem, params: Any, plan: Any = None, *,
                 dt: float | None = None, max_speed: float | None = None) -> None:
        super().__init__(problem, params, plan, dt=dt, max_speed=max_speed)
        p = params
        if not self.online:
            rb = _offline_robot(problem)
        elif problem.robot is not None:
            rb = problem.robot
        else:  # online without a model: the world's default, a holonomic robot
            rb = RobotModel(radius_m=problem.robot_radius_m,
                            max_speed_mps=float(max_speed) if max_speed else 1.0)
        self.robot = rb
        self.tick_s = float(dt) if dt is not None else float(p.dt_s)
        g = problem.grid
        self.clear_m = problem.robot_radius_m + MARGIN_FRAC * g.resolution
        # the map, the radius and the clearance lattice (about clearance_cell_m) in one object
        self.costmap = costmap_for(g, float(problem.robot_radius_m),
                                   field_cell_m=p.clearance_cell_m)
        self.field = self.costmap.field
        self._set_path(np.asarray(plan.waypoints, dtype=np.float64).reshape(-1, 2))
        self.replan_every = int(round(p.replan_period_s / self.tick_s)) \
            if p.replan_period_s > 0 else 0
        self.ticks = 0
        self.replans = 0
        self.holonomic = not rb.is_diff_drive
        vmax = rb.max_speed_mps
        if self.online and max_speed is not None and self.holonomic:
            vmax = min(vmax, float(max_speed))
        self.f = pack_mppi(
            self.tick_s, p.model_dt_s, rb.min_speed_mps, vmax, rb.max_accel_mps2,
            rb.max_yaw_rate_radps, rb.max_yaw_accel_radps2, self.holonomic,
            max(problem.clearance_m, rb.clearance_m), p.temperature,
            p.collision_cost, p.obstacle_weight, p.inflation_radius_m, p.cost_scaling_factor,
            p.path_align_weight, p.path_follow_weight, p.goal_weight, p.goal_distance_m,
            p.path_angle_weight, p.lookahead_m, p.disc_collision_cost,
            p.disc_proximity_weight, p.disc_decay_m, p.smoothness_weight,
            p.prefer_forward_weight, p.vx_std_mps,
            p.vy_std_mps if self.holonomic else p.wz_std_radps, self.seg_max,
            float(problem.goal[0]), float(problem.goal[1]), p.obstacle_peak_weight,
            min(vmax, p.slow_guide_speed_mps), p.keep_better_guide,
            w_social=p.social_weight if p.social else 0.0, personal_m=p.personal_m,
            dwell_s=p.dwell_s if p.social else 0.0, w_dwell=p.dwell_weight)
        self._baseline()
        n, k = int(p.time_steps), int(p.batch_size)
        self.nominal = np.zeros((n, 2))
        self.noise = np.zeros((k, n, 2))
        self.ctrl = np.zeros((k, n, 2))
        self.weights = np.zeros(k)
        self.rng = np.random.default_rng(int(p.seed))
        self.shift = max(1, int(round(self.tick_s / p.model_dt_s)))
        self.reach_m = 2.0 * vmax * self.tick_s + g.resolution + 1.0
        self.colliding_ticks = 0
        self.escapes = 0
        self.offline_shield = np.zeros(5, dtype=np.int64)
        self._sensed = _NO_DISCS
        self.steady = SteadyDiscs(self.tick_s)

    # ------------------------------------------------------------------ the path
    def _set_path(self, pts: np.ndarray) -> None:
        gx, gy = self.problem.goal
        if pts.shape[0] == 0 or pts[-1, 0] != gx or pts[-1, 1] != gy:
            pts = np.concatenate([pts, [[gx, gy]]])
        self.pts = np.require(pts, dtype=np.float64, requirements=("C", "W"))
        self.cum = polyline_cumlen(self.pts)
        self.seg_max = float(np.diff(self.cum).max()) if self.pts.shape[0] > 1 else 0.0
        self.k = 0
        if hasattr(self, "f"):
            self.f = self.f._replace(seg_max_m=self.seg_max)
            self._baseline()

    def _baseline(self) -> None:
        # the lane escape's scoring carries the dwell critic even where mppi's own is off;
        # made again with every path (its seg_max_m is the path's)
        self.f_escape = self.f if self.f.dwell_s >= ESCAPE_DWELL_S else self.f._replace(
            dwell_s=ESCAPE_DWELL_S, dwell_weight=self.params.dwell_weight)
        self.pexp = path_inflation(self.costmap, self.f, self.pts,
                                   bool(self.params.relative_inflation))

    def _replan(self, x: float, y: float) -> None:
        dpos, _, drad = self._sensed
        # keep away from obstacles where the room allows (ours; Nav2's global costmap is
        # inflated likewise)
        p = self.params
        pts = replan_around_discs(self.problem, x, y, dpos, drad, p,
                                  clearance_m=p.replan_clearance_m,
                                  personal_m=p.personal_m if p.social and p.social_replan
                                  else 0.0)
        self.replans += 1
        if pts is not None:
            self._set_path(pts)
            self.global_path = self.pts

    # ------------------------------------------------------------------ one decision
    def _choose(self, x: float, y: float, th: float, c0: float, c1: float, dpos: np.ndarray,
                dvel: np.ndarray, drad: np.ndarray,
                dsteady: np.ndarray = EVERY_DISC) -> tuple[float, float]:
        if self.replan_every and self.ticks and self.ticks % self.replan_every == 0:
            self._replan(x, y)
        self.k = int(advance_progress(x, y, self.pts, self.cum, self.k, self.reach_m,
                                      self.costmap, self.clear_m))
        if self.ticks:  # the previous optimal sequence, one tick on
            s = min(self.shift, self.nominal.shape[0])
            self.nominal[:-s] = self.nominal[s:].copy()
            self.nominal[-s:] = self.nominal[-s - 1] if s < self.nominal.shape[0] else 0.0
        self.ticks += 1
        self.rng.standard_normal(out=self.noise)
        goal_mode = float(self.cum[-1] - self.cum[self.k]) <= self.params.goal_distance_m
        a0, a1, _, free = mppi_optimise(self.costmap, self.f, x, y, th, c0, c1,
                                        self.nominal, self.noise, self.ctrl, self.weights,
                                        self.pts, self.cum, self.pexp, self.k, goal_mode, dpos,
                                        dvel, drad, dsteady)
        if self.params.lane_escape and drad.shape[0] and escape_sequence(
                self.costmap, self.f_escape, x, y, th, c0, c1, self.nominal, self.pts,
                self.cum, self.pexp, self.k, goal_mode, dpos, dvel, drad, dsteady):
            # ours (mppi_escape): out of a walker's lane rather than standing in it
            self.escapes += 1
            a0, a1 = self.nominal[0, 0], self.nominal[0, 1]
        if free == 0:
            self.colliding_ticks += 1
        return float(a0), float(a1)

    # ------------------------------------------------------------------ online
    def act(self, obs: Observed) -> np.ndarray:
        """``(v, omega)`` for a diff-drive robot, ``(vx, vy)`` for a holonomic one."""
        dpos, dvel, drad = sensed_discs(obs)
        self._sensed = (dpos, dvel, drad)
        # the dwell critic counts the discs that keep their velocity (social.SteadyDiscs)
        steady = self.steady.update(disc_ids(obs, drad.shape[0]), dvel)
        cmd = obs.command
        a0, a1 = self._choose(float(obs.position[0]), float(obs.position[1]),
                              float(obs.heading), float(cmd[0]), float(cmd[1]), dpos, dvel,
                              drad, steady)
        return np.array([a0, a1])

    # ------------------------------------------------------------------ offline
    def _shield_offline(self, x: float, y: float, th: float, c0: float, c1: float, a0: float,
                        a1: float) -> tuple[float, float]:
        from pathfuse.shield import ND, NV, NW, shield_holonomic, shield_unicycle

        rb = self.robot
        cm = self.costmap
        if self.holonomic:
            u, w, code = shield_holonomic(cm, x, y, c0, c1, a0, a1, self.tick_s,
                                          rb.max_speed_mps, rb.max_accel_mps2, NO_DISCS, 0.0,
                                          ND)
        else:
            u, w, code = shield_unicycle(cm, x, y, th, c0, c1, a0, a1, self.tick_s,
                                         rb.min_speed_mps, rb.max_speed_mps,
                                         rb.max_accel_mps2, rb.max_yaw_rate_radps,
                                         rb.max_yaw_accel_radps2, NO_DISCS, 0.0, NV, NW)
        self.offline_shield[code] += 1
        return float(u), float(w)

    def run(self, deadline: float | None) -> Outcome:
        """Drive a simulated robot to the goal on the static map (see the module docstring)."""
        pb = self.problem
        p = self.params
        g = pb.grid
        rb = self.robot
        ox, oy = float(g.origin[0]), float(g.origin[1])
        res = float(g.resolution)
        x, y = pb.start
        gx, gy = pb.goal
        th = rb.heading_rad if rb.heading_rad is not None else (
            math.atan2(gy - y, gx - x) if (gx != x or gy != y) else 0.0)
        cap = pb.budget.max_iterations
        max_ticks = int(cap) if cap is not None else int(math.ceil(
            10.0 * (g.width + g.height) * res / (rb.max_speed_mps * self.tick_s))) + 1000
        path = [(x, y)]
        heads = [th]
        cmds: list[tuple[float, float]] = []
        c0 = c1 = 0.0
        status = Status.MAX_ITERATIONS
        t0 = time.perf_counter()
        ticks = 0
        dpos, dvel, drad = _NO_DISCS
        tol = p.goal_tolerance_m
        while True:
            if math.hypot(x - gx, y - gy) <= tol and segment_is_clear(
                    x, y, gx, gy, g.occupied, ox, oy, res, self.clear_m):
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
            if rb.shield:
                a0, a1 = self._shield_offline(x, y, th, c0, c1, a0, a1)
            if self.holonomic:
                nx, ny, nth = x + a0 * self.tick_s, y + a1 * self.tick_s, th
                if a0 or a1:
                    nth = math.atan2(a1, a0)
                d = segment_static_distance(g.occupied, ox, oy, res, x, y, nx, ny, self.clear_m)
            else:
                nx, ny, nth = unicycle_pose(x, y, th, a0, a1, self.tick_s)
                d = arc_static_distance(g.occupied, ox, oy, res, x, y, th, a0, a1, self.tick_s,
                                        self.clear_m, self.clear_m)
            if d < float(pb.robot_radius_m):  # only without the shield
                status = Status.COLLISION
                msg = (f"collision {self._where(x, y)}: the command ({a0:.3g}, {a1:.3g}) "
                       "hits the static map (the robot's shield is off)")
                break
            x, y, th = nx, ny, nth
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
                "ticks_without_collision_free_sample": self.colliding_ticks,
                "shield_counts": self.offline_shield.copy(), "replans": self.replans,
                "step_time_s": elapsed}
        return Outcome(status, np.array(path, dtype=np.float64).reshape(-1, 2), ticks,
                       max(elapsed, 1e-9), msg, info)

    def _where(self, x: float, y: float) -> str:
        gx, gy = self.problem.goal
        return f"at ({x:.3f}, {y:.3f}), {math.hypot(x - gx, y - gy):.3f} m from the goal"

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (mppi_optimise, advance_progress)

    @classmethod
    def warmup(cls) -> None:
        if _WARM[0]:
            return
        from pathfuse.result import Budget
        from pathfuse.shield import warmup_shield
        from pathfuse.sweep import warmup_sweep

        warmup_shield()
        warmup_sweep()
        g = GridMap.from_rows(["....", ".#..", "...."])

        class _P:
            waypoints = np.array([[0.5, 0.5], [2.5, 0.5], [3.5, 2.5]])

        small = MPPIParams(batch_size=4, time_steps=2)
        for robot in (RobotModel.diff_drive(radius_m=0.1), RobotModel(radius_m=0.1)):
            pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5), 0.1, Budget(max_iterations=2),
                                robot=robot)
            c = cls(pb, small, _P())
            c.run(None)
            # the replans: the cost-aware A*, on the map and around a sensed disc
            c._replan(0.5, 0.5)
            c._sensed = (np.array([[2.5, 2.5]]), np.zeros((1, 2)), np.array([0.2]))
            c._replan(0.5, 0.5)
            for ro in (False, True):
                q = np.ones((1, 2))
                q.setflags(write=not ro)
                mppi_optimise(c.costmap, c.f, 0.5, 0.5, 0.0, 0.0, 0.0, c.nominal,
                              c.noise, c.ctrl, c.weights, c.pts, c.cum, c.pexp, 0, False,
                              q, q, np.ones(1), np.ones(1, dtype=np.bool_))
        _WARM[0] = True


_WARM = [False]


register(PlannerSpec(
    name="mppi",
    params_cls=MPPIParams,
    description="A* + Model Predictive Path Integral control (Williams et al.; Nav2's default "
                "controller): samples noisy control sequences around the last optimum, rolls "
                "them out, scores collision, inflation, path, goal, discs and smoothness, and "
                "takes their softmax-weighted mean",
    controller=MPPIController,
    global_planner="astar",
))
