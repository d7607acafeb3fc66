"""The A*-APF fusion planner (paper Section III.C, Algorithm 2), registered as ``"fusion"``.

Step 1 plans a global path with grid A*
(:mod:`pathfuse.planners.globals.astar`), or with the global planner that the
parameter ``global_planner`` names (ours: any registered one, a plug-in's
too); if it fails its status is returned.
Step 2 starts the robot at ``start`` and repeats, until the goal is reached:

* every A* path point strictly inside the circle of radius ``r1_m`` around
  the robot that lies *ahead* attracts it (eq. 5), summed with the goal's
  attraction (eq. 9);
* every occupied cell centre closer than ``r2_m`` repels it (eq. 6, zero
  beyond ``rho0_m``), and online every sensed moving disc too;
* the robot makes one safe step along the resultant
  (:func:`pathfuse.field.motion.safe_step`: never into or across an
  occupied square, kept ``robot_radius_m`` away).

:func:`pathfuse.plan` and :func:`pathfuse.simulate` run the same numba loop
(:func:`pathfuse.field.kernels.fusion_loop`) with the same parameters.

"Ahead" (``ahead``):

``"progress"`` (default, ours)
    path points after the robot's progress index: the nearest path point in
    sight within reach along the path, which only moves forward
    (:func:`pathfuse.field.pathing.advance_progress`).  It does not depend on
    the direction of travel, so the planner gives the same walk on a rotated
    or mirrored map.
``"paper-x"``
    the paper's eq. 8, ``x_p - x_current > 0``, over the whole path.  It
    assumes the goal lies towards +x.

Local-minimum escape (``escape=True``, ours; ``escape=False`` is the paper
as printed).  The goal's attraction is usually much larger than that of the
few path points inside ``r1`` (K_att |X - X_g| against K_att |X - P|), so the
robot heads for the goal, slides along obstacles on the way, and can stall
where the A* path turns around a cluster.  When it stalls (net move below
``stall_distance_m`` over ``stall_steps`` moves) or is blocked, it picks the
walked point and the A* point within ``r1_m + resolution`` of it, with a
clear straight move between them, that make the rest of the route shortest
(:func:`pathfuse.field.pathing.find_rejoin`).  Planning offline, the walk
after that point is dropped from the returned path (a planner need not drive
into the dead end it backed out of; ``info["backoff_steps"]`` counts the
dropped moves); driving online, the robot walks back along its trail to it.
It then goes straight to the A* point and follows the A* path point by point
until it is ``escape_points`` points past its progress at the stall; then
Algorithm 2 resumes.  Every move is checked for collision.

Result: ``time_s`` is A*'s search time plus the time of step 2's loop;
``info`` holds ``astar_path``, ``astar_time_s``, ``astar_length``,
``escapes``, ``backoff_steps``, ``step_time_s``, ``steps_per_s``, ``step_m``
and ``goal_tolerance_m``.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> from pathfuse import plan
>>> g = GridMap.from_rows(["......", "..##..", "......", "......"])
>>> r = plan(g, (0.5, 0.5), (4.5, 3.5), planner="fusion")
>>> r.status.name, r.path[-1].tolist(), r.length < r.info["astar_length"] + 1.0
('SUCCESS', [4.5, 3.5], True)
>>> plan(g, (0.5, 0.5), (4.5, 3.5), planner="fusion", ahead="behind")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: fusion.ahead: must be one of 'progress', 'paper-x', got 'behind'
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pathfuse.costmap import costmap_for
from pathfuse.field.forces import RHO0_M
from pathfuse.field.kernels import (
    N_S,
    S_BACKOFF,
    S_ESCAPES,
    S_ESTEPS,
    S_K,
    S_MODE,
    S_REF,
    fusion_loop,
)
from pathfuse.field.pathing import polyline_cumlen
from pathfuse.field.repulsion import AHEAD_PAPER_X, AHEAD_PROGRESS, fusion_force
from pathfuse.field.settings import pack_fusion
from pathfuse.grid import GridMap
from pathfuse.planners.base import FieldController, _plain, sensed_discs
from pathfuse.planners.controllers.replan import replan_around_discs
from pathfuse.planners.controllers.social import disc_ids
from pathfuse.planners.params import (
    KEEP_M,
    KEEP_WEIGHT,
    DiscParams,
    FieldParams,
    GlobalAStarParams,
    GlobalChoice,
    SocialParams,
)
from pathfuse.planners.registry import PlannerSpec, register
from pathfuse.problem import Problem
from pathfuse.validate import param

__all__ = ["FUSION_STEP_FRAC", "FusionParams", "FusionController", "force_at", "follow_path"]

_AHEAD = {"progress": AHEAD_PROGRESS, "paper-x": AHEAD_PAPER_X}

#: Default step of the fusion planner offline, as a fraction of the map resolution.
FUSION_STEP_FRAC = 0.5


@dataclass(frozen=True)
class FusionParams(SocialParams, GlobalAStarParams, DiscParams, FieldParams, GlobalChoice):
    """Parameters of the fusion planner (paper values for K_att, K_rep, rho_0).

    The default ``step_m`` offline is :data:`FUSION_STEP_FRAC` (0.5) x the map
    resolution, coarser than the 0.1 of the plain APF: success and length
    hardly change with the step (every move is checked exactly), while the
    planning time falls with the number of moves.
    """

    r1_m: float = param(RHO0_M, gt=0, unit="m",
                        help="radius of the circle (eq. 7) inside which A* path points "
                             "attract the robot (the paper gives no value; default rho0_m)")
    r2_m: float = param(RHO0_M, gt=0, unit="m",
                        help="radius inside which obstacles repel (zero beyond rho0_m anyway)")
    ahead: str = param("progress", choices=tuple(_AHEAD),
                       help="which path points count as ahead: past the robot's progress "
                            "along the path (ours), or the paper's eq. 8 x_p > x")
    escape: bool = param(True, help="escape local minima along the A* path (ours; false = "
                                    "the paper as printed)")
    escape_points: int = param(3, ge=1, help="A* points to follow in an escape before "
                                             "Algorithm 2 resumes")
    replan_period_s: float = param(
        1.0, ge=0, le=3600, unit="s",
        help="diff-drive robot online, velocity space, while a moving disc is sensed: plan "
             "the global path again from the robot, around the sensed discs, this often "
             "(ours, as dwa; 0 = never)")
    among_discs: str = param(
        "mppi", choices=("mppi", "window"),
        help="diff-drive robot online, velocity space, while a moving disc is sensed: track "
             "Algorithm 2's local path with MPPI's sampled control sequences (ours; they can "
             "swerve and get away) or with the dynamic window as without discs")
    seed: int = param(0, ge=0, le=2**63 - 1,
                      help="seed of MPPI's sampling noise among discs (among_discs='mppi')")
    dwell_s: float = param(1.5, ge=0, le=30, unit="s",
                           help="yield outside a walker's lane (ours, among discs): a rollout "
                                "pays dwell_weight where it ends within personal_m of the lane "
                                "a steady sensed disc (one that kept its velocity for 1 s), "
                                "predicted at constant velocity, sweeps in the "
                                "dwell_s after the rollout; 0 = off (the default of mppi)")
    replan_lane_s: float = param(
        3.0, ge=0, le=30, unit="s",
        help="ours, with social (diff-drive robot online, velocity space): the replanned A* "
             "path first keeps out of the lane each sensed disc (not seen to wander: "
             "sensed for 1 s and not steady) sweeps at constant velocity "
             "over the next replan_lane_s (grown by personal_m where social_replan), so the "
             "robot leaves a walker's lane before the walker comes rather than fleeing "
             "ahead of it; where no such path exists, as before; 0 = off")
    replan_lane_detour_m: float = param(
        2.0, ge=0, le=1000, unit="m",
        help="ours, with replan_lane_s: the path out of the lanes is taken only when it is at "
             "most this much longer than the path around the discs alone (grown by personal_m "
             "where social_replan); otherwise that path, and Algorithm 2's local path leads "
             "(a step aside out of a walker's lane, not a long detour or a turn back round "
             "the lane of a disc that seldom walks it); 0 = no limit (as before)")
    lane_escape: bool = param(
        True, help="ours (diff-drive robot online, among_discs='mppi'): MPPI's lane escape "
                   "(mppi's lane_escape: out of a walker's lane rather than standing in it); "
                   "false = off")
    evade: bool = param(
        False, help="ours (diff-drive robot online, among_discs='mppi'): when MPPI's plan, "
                    "rolled out and then held standing for 3 s, comes within 0.3 m of a "
                    "sensed disc predicted at constant velocity, a fan of escape sequences "
                    "is judged against every sensed disc's sweep (grown by 0.2 m/s) and "
                    "the safest whose first command the shield passes unchanged (kept with "
                    "hysteresis) replaces it (planners/controllers/evade.py); off by "
                    "default: no gain measured (docs/results/dynamic.md)")
    evade_steady: bool = param(
        False, help="ours, with evade: only sensed discs seen steady (sensed for 1 s and "
                    "keeping their velocity) set the escape off; the escapes are still judged "
                    "against every disc (a wandering disc's constant-velocity prediction "
                    "shows its contact too late to escape); false = every disc")
    walker_escape: bool = param(
        True, help="ours (diff-drive robot online, among_discs='mppi'): dwa's lane escape "
                   "(planners/controllers/dwa_escape.py) on the sequences' command: while "
                   "the robot standing would be touched within walker_escape_s by a sensed "
                   "disc not seen to wander, and so would the command, the first step of the "
                   "best turn-then-go sequence out of the discs' lanes that none touches "
                   "(kept with hysteresis); the shield still checks it; false = off (the "
                   "default until 27 Nov, docs/guide/people.md)")
    walker_escape_hold: float = param(
        5.0, ge=0, le=1000,
        help="ours, with walker_escape: taken off the cost of the sequence towards the "
             "heading escaped towards last tick (hysteresis; dwa's HOLD_BONUS is 0.5, with "
             "which the escape's heading swung and east_three_lanes seed 0 collided)")
    walker_escape_s: float = param(
        3.5, gt=0, le=30, unit="s",
        help="ours, with walker_escape: the escape's horizon: it is set off while "
             "the robot standing would be touched within this time, and its "
             "sequences are rolled out over it (dwa's lane_escape_s is 4 s, which the "
             "walker escape used until 27 Nov)")
    escape_limit: bool = param(
        True, help="ours (diff-drive robot online, velocity space): Algorithm 2's escape is "
                   "given up after 2 x stall_steps moves that have not reached its target, "
                   "with or without discs (the loop gives up so only among discs): the robot, "
                   "turned by the window and taken elsewhere by the recovery, may never pass "
                   "the escape's target, and the escape drew it back there, its progress "
                   "along the path frozen; false = off")
    flee: bool = param(
        False, help="ours (diff-drive robot online, velocity space, among discs): while a "
                    "sensed disc is within 1 m, the reachable window's command whose rollout "
                    "(held 1 s, then a stop) keeps the largest gap to the discs predicted at "
                    "constant velocity and grown by 0.3 m/s replaces it, if it gains 0.05 m "
                    "and the shield would pass it unchanged (planners/controllers/flee.py); "
                    "false = off")
    replan_new: bool = param(
        True, help="ours (diff-drive robot online, velocity space): replan around a disc as "
                   "soon as it is first sensed, not up to replan_period_s later; false = off")
    keep_weight: float = param(
        KEEP_WEIGHT, ge=0, le=1e6,
        help="diff-drive robot online, velocity space: the window's keep critic (dwa's "
             "keep_weight, ours: the rollout's shortfall from the gap the A* path keeps "
             "ahead); 0 = off (5 before issue 17's clearance round)")
    keep_m: float = param(KEEP_M, gt=0, le=100, unit="m",
                          help="diff-drive robot online, velocity space: the most gap the "
                               "window's keep critic asks for (dwa's keep_m; 0.3 before)")
    velocity_space: bool = param(True, help="diff-drive robot online: choose (v, omega) from "
                                            "the dynamic window by agreement with Algorithm "
                                            "2's move, clearance and the predicted discs "
                                            "(ours); false: the shared conversion of "
                                            "planners/drive.py")


def _meeting_points(p: np.ndarray, v: np.ndarray, dpos: np.ndarray, dvel: np.ndarray,
                    horizon_s: float) -> np.ndarray:
    """Each disc's position at its time of closest approach to a robot at ``p`` moving at
    ``v`` (both at constant velocity), that time clipped to ``[0, horizon_s]``."""
    rel = dpos - p
    dv = dvel - v
    dd = np.einsum("ij,ij->i", dv, dv)
    t = np.where(dd > 1e-12, -np.einsum("ij,ij->i", rel, dv) / np.maximum(dd, 1e-12), 0.0)
    t = np.clip(t, 0.0, horizon_s)
    return np.ascontiguousarray(dpos + dvel * t[:, None])


class FusionController(FieldController):
    """Algorithm 2 with the escape (see the module docstring)."""

    name = "fusion"
    label = "Algorithm 2"
    default_step_frac = FUSION_STEP_FRAC

    def __init__(self, problem: Problem, params: Any, plan: Any = None, **kw: Any) -> None:
        self.disc_reach_m = float(params.r2_m)
        super().__init__(problem, params, plan, **kw)
        p = params
        g = problem.grid
        self._set_path(np.asarray(plan.waypoints, dtype=np.float64))
        window = p.stall_steps * self.step_m + 2.0 * (p.r1_m + g.resolution)
        self.settings = pack_fusion(
            problem.goal, p.k_att, p.k_rep, p.rho0_m, p.r1_m, p.r2_m, self.step_m,
            self.goal_tolerance_m, p.stall_steps, self.stall_distance_m, _AHEAD[p.ahead],
            p.escape, p.escape_points, window, self.online, p.safe_step, p.stall_exit,
            problem.clearance_m, p.static_repulsion == "boundary", p.boundary_offset_m)
        self.state = np.zeros(N_S, dtype=np.int64)
        self.kbuf = np.zeros(self.buf.shape[0], dtype=np.int64)
        rb = problem.robot
        self._window: Any = None
        if self.online and rb is not None and rb.is_diff_drive and p.velocity_space:
            from pathfuse.planners.controllers.fusion_window import ForceWindow

            self._window = ForceWindow(problem, float(self.dt),  # type: ignore[arg-type]
                                       social=p, among_discs=p.among_discs, seed=p.seed,
                                       keep=(p.keep_weight, p.keep_m))
        self._ticks = 0
        self._seen: set[int] = set()
        self.escapes_given_up = 0
        """Escapes of Algorithm 2 given up online (``escape_limit``)."""
        self.replans = 0
        self.flees = 0
        """Ticks whose command came from ``flee``."""
        self._replan_every = 0
        if self._window is not None and p.replan_period_s > 0:
            self._replan_every = max(1, int(round(p.replan_period_s / self._window.f.dt_s)))

    def command(self, obs: Any) -> np.ndarray:
        """On a diff-drive robot with ``velocity_space`` (ours): Algorithm 2's move for this
        tick scored in velocity space (:mod:`pathfuse.planners.controllers.fusion_window`), then the
        shield; otherwise as every controller (:meth:`Controller.command`)."""
        if self._window is None:
            return super().command(obs)
        self._replan_among_discs(obs)
        self.act(obs)  # Algorithm 2 keeps up with the robot, in a recovery too
        if self.params.escape_limit and int(self.state[S_MODE]) != 0 \
                and int(self.state[S_ESTEPS]) > 2 * int(self.params.stall_steps):
            # ours (escape_limit): an escape whose target the robot does not reach is given
            # up, as the loop gives it up among discs; Algorithm 2 resumes from the robot
            self.state[S_MODE] = 0
            self.state[S_REF] = self.n - 1
            self.state[S_ESTEPS] = 0
            self.escapes_given_up += 1
        a = self._recovering(obs, self.problem.robot, force=True)
        if a is None:
            if self._window.evader is not None:
                self._window.passes = self._shield_passes(obs)
            a = self._window.choose(obs, self._streamline(obs), self.pts, self.cum,
                                    int(self.state[S_K]))
            if self.params.flee and len(obs.obstacles):
                a = self._flee(obs, a)
        if not self.problem.robot.shield:  # type: ignore[union-attr]
            return a
        return self._shielded(obs, a)

    def _shield_passes(self, obs: Any) -> Any:
        """Ours (``evade``): a test of a command against this tick's shield, True when the
        shield would let it through unchanged (an escape the shield would hold back is not
        taken: the robot keeps passive safety)."""
        from pathfuse.costmap import Discs
        from pathfuse.shield import ASKED, NV, NW, shield_unicycle

        pb = self.problem
        rb = pb.robot
        if rb is None or not rb.shield or not len(obs.obstacles):
            return None
        sens = obs.obstacles
        dp, dr = _plain(sens.positions), _plain(sens.radii)
        discs = Discs(dp, dp, self._disc_speed_bounds(sens), dr)
        cm = self._window.costmap
        x, y, th = float(obs.position[0]), float(obs.position[1]), float(obs.heading)
        c0, c1 = float(obs.command[0]), float(obs.command[1])
        dt = float(self.dt)  # type: ignore[arg-type]
        lim = (float(rb.min_speed_mps), float(rb.max_speed_mps), float(rb.max_accel_mps2),
               float(rb.max_yaw_rate_radps), float(rb.max_yaw_accel_radps2))

        def passes(v: float, w: float) -> bool:
            code = shield_unicycle(cm, x, y, th, c0, c1, v, w, dt, *lim, discs, 0.0, NV,
                                   NW)[2]
            return bool(code == ASKED)

        return passes

    def _flee(self, obs: Any, a: np.ndarray) -> np.ndarray:
        """Ours (``flee``): the controller's slow command next to a disc replaced by the
        window's command that keeps the largest predicted gap, if the shield passes it
        unchanged (:mod:`pathfuse.planners.controllers.flee`)."""
        from pathfuse.planners.controllers.flee import flee_command

        rb = self.problem.robot
        assert rb is not None
        sens = obs.obstacles
        passes = self._shield_passes(obs)
        lim = (float(rb.min_speed_mps), float(rb.max_speed_mps), float(rb.max_accel_mps2),
               float(rb.max_yaw_rate_radps), float(rb.max_yaw_accel_radps2))
        v, w, done = flee_command(
            self._window.costmap, float(obs.position[0]), float(obs.position[1]),
            float(obs.heading), float(obs.command[0]), float(obs.command[1]), float(a[0]),
            float(a[1]), float(self.dt), lim,  # type: ignore[arg-type]
            _plain(sens.positions), _plain(sens.velocities), _plain(sens.radii), passes)
        if not done:
            return a
        self.flees += 1
        return np.array([v, w])

    def _set_path(self, pts: np.ndarray) -> None:
        """The global path the A* points come from, ending at the goal."""
        gx, gy = self.problem.goal
        if pts.shape[0] == 0 or pts[-1, 0] != gx or pts[-1, 1] != gy:
            pts = np.concatenate([pts.reshape(-1, 2), [[gx, gy]]])
        self.pts = np.require(pts, dtype=np.float64, requirements=("C", "W"))
        self.cum = polyline_cumlen(self.pts)

    def _replan_among_discs(self, obs: Any) -> None:
        """Ours (velocity space): while a disc is sensed, the global path again from the
        robot, around the discs, every ``replan_period_s`` (as ``dwa`` does; the A* points
        that attract the robot then lead around them).  Not during an escape, whose target
        indices refer to the path it started on."""
        self._ticks += 1
        dpos, dvel, drad = sensed_discs(obs)
        p = self.params
        new_disc = False
        if p.replan_new and drad.shape[0]:
            # ours (replan_new): a disc sensed for the first time is replanned around now,
            # not up to replan_period_s later
            seen = {int(i) for i in disc_ids(obs, drad.shape[0])}
            new_disc = bool(seen - self._seen)
            self._seen = seen
        if not (drad.shape[0] and self._replan_every
                and (new_disc or self._ticks % self._replan_every == 0)
                and int(self.state[S_MODE]) == 0):
            return
        rep: dict[str, Any] = {}
        pts = replan_around_discs(self.problem, float(obs.position[0]),
                                  float(obs.position[1]), dpos, drad, p,
                                  personal_m=p.personal_m if p.social and p.social_replan
                                  else 0.0, dvel=self._window.lane_velocities(obs, dvel),
                                  lane_s=p.replan_lane_s if p.social else 0.0,
                                  lane_detour_m=p.replan_lane_detour_m, report=rep)
        if p.replan_lane_detour_m > 0.0:
            # ours (replan_lane_detour_m): the A* path does not lead out of a lane when the
            # path out of the lanes was refused for its detour
            self._window.lanes_on = not rep["detour"]
        self.replans += 1
        if pts is None:
            return
        self._set_path(pts)
        self.state[S_K] = 0  # the new path starts where the robot stands
        # the walked points' progress indices referred to the old path (the escape's rejoin
        # search reads them as indices into the path): the new path's start for each
        self.kbuf[:self.n] = 0
        self.global_path = self.pts

    def relax(self, seconds: float) -> bool:
        """Recovery (ours): the velocity-space window drops its obstacle critic for
        ``seconds`` and follows a new A* path (:meth:`ForceWindow.relax
        <pathfuse.planners.controllers.fusion_window.ForceWindow.relax>`)."""
        if self._window is None:
            return False
        self._window.relax(seconds)
        return True

    def _streamline(self, obs: Any) -> np.ndarray:
        """The robot's position and Algorithm 2's next moves from its present state (the
        move just made and up to the window's horizon of further ones, among the sensed
        discs as they are now or, with ``social``, where each meets the robot), without
        committing them: the fusion's local path."""
        n0 = self.n
        here = np.array([[float(obs.position[0]), float(obs.position[1])]])
        if n0 < 2 or self._window is None:
            return here
        keep = (self.buf, self.kbuf, self.state.copy(), self.buf[:n0].copy(),
                self.kbuf[:n0].copy())
        dpos, dvel, drad = sensed_discs(obs)
        if drad.shape[0] and self.params.social:
            # ours (social): each disc where it will be at its closest approach to the
            # robot (both at their present velocities, within the horizon), so that the
            # local path bends around the meeting point rather than where the disc is now
            dpos = _meeting_points(here[0], np.asarray(obs.velocity, dtype=np.float64),
                                   dpos, dvel, self._window.horizon_s)
        self._call(self._window.steps, dpos, dvel, drad)
        line = np.concatenate([here, self.buf[n0 - 1:self.n]])
        self.buf, self.kbuf, self.state = keep[0], keep[1], keep[2]
        self.buf[:n0] = keep[3]
        self.kbuf[:n0] = keep[4]
        self.n = n0
        return line

    def _call(self, max_steps: int, dpos: np.ndarray | None, dvel: np.ndarray | None,
              drad: np.ndarray | None) -> tuple[int, int]:
        self.buf, self.kbuf, self.n, code, steps = fusion_loop(
            self.buf, self.kbuf, self.n, max_steps, self.costmap, self.pts, self.cum, self.state,
            self.settings, self.disc_cfg, dpos, dvel, drad, *self._margin(dpos))
        return code, steps

    def on_stuck(self) -> None:
        # the escape found no way back to the path: wait a stall window before the next try
        self.state[S_REF] = self.n - 1

    def length_of(self, path: np.ndarray) -> float | None:
        return float(polyline_cumlen(path)[-1])

    @property
    def escapes(self) -> int:
        return int(self.state[S_ESCAPES])

    def extra_info(self) -> dict[str, Any]:
        return {"escapes": self.escapes, "backoff_steps": int(self.state[S_BACKOFF])}

    def success_message(self, steps: int) -> str:
        return f"reached the goal in {steps} steps ({self.escapes} escapes)"

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        return (fusion_loop,)

    @classmethod
    def diff_drive_kernels(cls) -> Sequence[Any]:
        from pathfuse.planners.controllers.dwa_kernel import dwa_choose, route_tangent
        from pathfuse.planners.controllers.mppi import MPPIController

        return (dwa_choose, route_tangent, *MPPIController.kernels())

    @classmethod
    def warmup(cls) -> None:
        """:func:`fusion_loop` for a plan on a static map (no disc code compiled)."""
        if _WARM[0]:
            return
        g = GridMap.from_rows(["....", ".#..", "...."])
        follow_path(g, (0.5, 0.5), (3.5, 2.5), _WARM_PATH)
        _WARM[0] = True

    @classmethod
    def warmup_margin(cls) -> None:
        """:func:`fusion_loop` for a plan on a static map with a safety margin."""
        if _WARM[2]:
            return
        g = GridMap.from_rows(["....", ".#..", "...."])
        pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5), clearance_m=0.05)
        wp = np.asarray(_WARM_PATH, dtype=np.float64)
        FusionController(pb, FusionParams(), _Path(wp)).run(None)
        _WARM[2] = True

    @classmethod
    def warmup_online(cls) -> None:
        """:func:`fusion_loop` with disc arrays, as it runs online."""
        if _WARM[1]:
            return
        from pathfuse.planners.base import ONE_DISC

        g = GridMap.from_rows(["....", ".#..", "...."])
        pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5))
        wp = np.asarray(_WARM_PATH, dtype=np.float64)
        FusionController(pb, FusionParams(), _Path(wp), dt=0.1, max_speed=1.0)._call(1, *ONE_DISC)
        _WARM[1] = True

    @classmethod
    def warmup_diff_drive(cls) -> None:
        from pathfuse.planners.controllers.dwa import DWAController
        from pathfuse.planners.controllers.mppi import MPPIController

        DWAController.warmup()  # the velocity-space fusion scores with dwa's window
        MPPIController.warmup()  # and among discs with MPPI's sequences


_WARM = [False, False, False]  # offline, online, offline with a safety margin
_WARM_PATH = [[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 1.5], [3.5, 2.5]]


class _Path:
    """A stand-in global plan: just the waypoints."""

    def __init__(self, waypoints: np.ndarray) -> None:
        self.waypoints = waypoints


def follow_path(grid: GridMap, start: object, goal: object, global_path: object,
                params: FusionParams | None = None, robot_radius_m: float = 0.0) -> Any:
    """Step 2 alone: follow ``global_path`` (M, 2) with Algorithm 2 from ``start`` to ``goal``.

    Returns the :class:`~pathfuse.planners.base.Outcome` (status, path, steps,
    time, message, info).

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> r = follow_path(g, (0.5, 0.5), (3.5, 2.5), [[0.5, 0.5], [1.5, 1.5], [2.5, 2.5]])
    >>> r.status.name, r.path[-1].tolist()
    ('SUCCESS', [3.5, 2.5])
    """
    pb = Problem.create(grid, start, goal, robot_radius_m)
    wp = np.asarray(global_path, dtype=np.float64).reshape(-1, 2)
    return FusionController(pb, params or FusionParams(), _Path(wp)).run(None)


def force_at(grid: GridMap, xy: object, goal: object, global_path: object,
             params: FusionParams | None = None, progress: int = 0) -> np.ndarray:
    """The resultant force of Algorithm 2 at ``xy`` (2,) given the global path.

    ``progress`` is the robot's progress index along ``global_path`` (used by
    ``ahead="progress"``).  Returns ``[fx, fy]``.

    >>> g = GridMap.from_rows(["....", "....", "...."])
    >>> path = [[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5]]
    >>> force_at(g, (0.5, 0.5), (3.5, 0.5), path, FusionParams(r1_m=1.5)).tolist()
    [160.0, 0.0]
    """
    p = params or FusionParams()
    pts = np.ascontiguousarray(global_path, dtype=np.float64).reshape(-1, 2)
    x, y = (float(v) for v in np.asarray(xy, dtype=np.float64).reshape(2))
    gx, gy = (float(v) for v in np.asarray(goal, dtype=np.float64).reshape(2))
    fx, fy, _ = fusion_force(x, y, gx, gy, pts, polyline_cumlen(pts), int(progress),
                             _AHEAD[p.ahead], p.k_att, p.k_rep, p.rho0_m, p.r1_m, p.r2_m,
                             costmap_for(grid, 0.0, lattice=False),
                             p.static_repulsion == "boundary", p.boundary_offset_m)
    return np.array([fx, fy])


register(PlannerSpec(
    name="fusion",
    params_cls=FusionParams,
    description="A*-APF fusion (paper Algorithm 2): APF attracted by the goal and the A* path "
                "points ahead within r1",
    controller=FusionController,
    global_planner="astar",
))
