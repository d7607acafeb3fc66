"""Local controllers: what a planner does after (or without) its global plan.

A :class:`Controller` is built for one problem and runs it one of two ways:

* :meth:`Controller.run` - offline, as :func:`pathfuse.plan` does: to the goal
  on the static map, in one numba call (or in chunks between wall-clock
  checks under a time limit); returns an :class:`Outcome`.
* :meth:`Controller.act` - online, as :func:`pathfuse.simulate` does: one
  velocity per tick from an observation (the robot's position and velocity,
  the sensed moving discs).

:class:`FieldController` is the base of the potential-field controllers
(``apf``, ``fusion``, ``ref6``, ``ref7``): both ways call the same numba loop
of :mod:`pathfuse.field.kernels`, offline with a budget of many moves and
no discs, online with a budget of one move and the sensed discs.  The move
length is the parameter ``step_m`` offline and ``max_speed * dt`` online.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import numpy as np

from pathfuse.costmap import costmap_for, move_clear, point_distance
from pathfuse.field.kernels import (
    CODE_BLOCKED,
    CODE_COLLISION,
    CODE_GOAL,
    CODE_GOAL_SNAP,
    CODE_RUNNING,
    CODE_STALLED,
    STATIC,
    code_status,
)
from pathfuse.field.motion import MARGIN_FRAC
from pathfuse.field.settings import DiscSettings, FieldSettings, FusionSettings, disc_settings
from pathfuse.limits import LimitError, env_name, limit
from pathfuse.problem import Problem
from pathfuse.result import Status
from pathfuse.tier import interpreting

__all__ = ["Outcome", "Controller", "FieldController", "Observed", "CHUNK", "CAP_FACTOR",
           "STALL_FRAC", "sensed_discs"]

#: Moves per numba call between wall-clock checks when a time limit is set.
CHUNK = 8192
_INTERPRETED_CHUNK = 512  # steps of one interpreted call: some 0.1 s
#: Default move cap: this many times (width + height) / step, plus 1000.
CAP_FACTOR = 10.0
#: Default stall distance, in moves.
STALL_FRAC = 2.5

_NO_DISCS = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
#: One sensed disc, as the kernels take it: compiles a loop's online signature (warm-ups).
ONE_DISC = (np.array([[3.5, 0.5]]), np.array([[0.0, 0.1]]), np.array([0.2]))


_NO_SHIELD_DISCS: Any = None


def _no_shield_discs() -> Any:
    """The shield's empty :class:`~pathfuse.costmap.Discs`, built once (its arrays are
    empty: nothing in them can change)."""
    global _NO_SHIELD_DISCS
    if _NO_SHIELD_DISCS is None:
        from pathfuse.costmap import Discs

        _NO_SHIELD_DISCS = Discs(_NO_DISCS[0], _NO_DISCS[0], _NO_DISCS[2], _NO_DISCS[2])
    return _NO_SHIELD_DISCS


def _plain(a: Any) -> np.ndarray:
    """A C-contiguous writable float64 array (one numba signature for every caller)."""
    return np.require(a, dtype=np.float64, requirements=("C", "W"))


def sensed_discs(obs: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sensed discs' positions, velocities and radii as the kernels take them (empty
    arrays without discs)."""
    sens = obs.obstacles
    if not len(sens):
        return _NO_DISCS
    return _plain(sens.positions), _plain(sens.velocities), _plain(sens.radii)


class Observed(Protocol):
    """What an online controller reads from an observation (see :class:`pathfuse.world.World`)."""

    @property
    def tick(self) -> int: ...
    @property
    def position(self) -> np.ndarray: ...
    @property
    def velocity(self) -> np.ndarray: ...
    @property
    def obstacles(self) -> Any: ...  # positions (M, 2), velocities (M, 2), radii (M,), len()
    @property
    def heading(self) -> float: ...
    @property
    def command(self) -> np.ndarray: ...


@dataclass
class Outcome:
    """What an offline run of a controller returns (``plan()`` turns it into a PlanResult)."""

    status: Status
    path: np.ndarray
    steps: int
    time_s: float
    message: str
    info: dict[str, Any] = field(default_factory=dict)
    length_m: float | None = None
    """The path's length when the controller knows it exactly (A*'s cost); else summed."""


class Controller:
    """A local controller for one problem: :meth:`run` offline, :meth:`act` online.

    Parameters
    ----------
    problem : Problem
    params : dataclass
        The planner's parameters.
    plan : GlobalPlan or None
        The global plan (None for a planner without one, such as ``apf``).
    dt, max_speed : float, optional
        Given online: the tick length (s) and the robot's speed limit (m/s).

    Attributes
    ----------
    global_path : (N, 2) array or None
        The path the controller currently follows (a new array object each
        time it changes, so an episode can record replans).
    failure : (Status, str) or None
        Set online when the controller gives up (the episode ends with that
        status).
    """

    name: ClassVar[str] = ""
    label: ClassVar[str] = ""
    """What the controller does, in a few words (``pathfuse planners``)."""
    search_budget: ClassVar[bool] = False
    """Whether ``Budget.max_iterations`` caps the global search (``astar``) rather than the
    controller's moves."""
    native_unicycle: ClassVar[bool] = False
    """Whether :meth:`act` answers ``(v, omega)`` itself on a diff-drive robot (``dwa``);
    otherwise :meth:`command` converts its velocity (:mod:`pathfuse.planners.drive`).
    :meth:`command` reads it through :attr:`acts_unicycle`."""

    def __init__(self, problem: Problem, params: Any, plan: Any = None, *,
                 dt: float | None = None, max_speed: float | None = None) -> None:
        self.problem = problem
        self.params = params
        self.plan = plan
        self.dt = dt
        self.max_speed = max_speed
        self.online = dt is not None
        self._global_path: np.ndarray | None = None
        self.failure: tuple[Status, str] | None = None
        #: Online: how many commands the shield passed, replaced by a nearby one, replaced
        #: by the emergency stop, found no clear command for, or evaded a disc with
        #: (indexed by :data:`pathfuse.shield.CODE_NAMES`).
        self.shield_counts = np.zeros(5, dtype=np.int64)
        self._disc_speeds: dict[int, float] = {}
        #: Online: the recovery behaviours (:mod:`pathfuse.planners.recovery`; None until the
        #: first command, or when the robot's ``recovery`` is off).
        self.recovery: Any = None

    @property
    def acts_unicycle(self) -> bool:
        """Whether this controller's :meth:`act` answers ``(v, omega)`` on a diff-drive
        robot (the class's :attr:`native_unicycle`; a controller that decides per robot,
        as the path followers do, overrides this)."""
        return self.native_unicycle

    @property
    def global_path(self) -> np.ndarray | None:
        """The path the controller currently follows (the global plan's waypoints until a
        replanning controller sets another)."""
        if self._global_path is None and self.plan is not None:
            self._global_path = self.plan.waypoints
        return self._global_path

    @global_path.setter
    def global_path(self, path: np.ndarray | None) -> None:
        self._global_path = path

    def run(self, deadline: float | None) -> Outcome:  # pragma: no cover - abstract
        """Drive to the goal on the static map (``deadline``: a ``perf_counter`` value)."""
        raise NotImplementedError

    @classmethod
    def run_offline(cls, problem: Problem, params: Any, plan: Any,
                    deadline: float | None) -> Outcome:
        """What :func:`pathfuse.plan` asks: :meth:`run` of a new controller (one whose
        offline answer needs no instance, such as the path follower's, overrides this)."""
        return cls(problem, params, plan).run(deadline)

    def act(self, obs: Observed) -> np.ndarray:  # pragma: no cover - abstract
        """The velocity ``(vx, vy)`` for this tick."""
        raise NotImplementedError

    def command(self, obs: Observed) -> np.ndarray:
        """The action for this tick in the robot's terms, through the safety shield.

        :meth:`act`'s velocity for a holonomic robot, ``(v, omega)`` for a
        diff-drive one (converted by :func:`pathfuse.planners.drive.to_unicycle`
        unless the controller plans in ``(v, omega)`` itself); then, unless the
        robot's ``shield`` is off, :mod:`pathfuse.shield` replaces it with the
        nearest command from which the robot can still stop clear of the static
        map (:attr:`shield_counts` counts what it did).  When the robot stalls or
        oscillates, a recovery behaviour (:mod:`pathfuse.planners.recovery`, ours;
        the robot's ``recovery`` switches it) commands instead of :meth:`act`, through
        the shield too.
        """
        rb = self.problem.robot
        a = self._recovering(obs, rb)
        if a is not None:  # a recovery behaviour: already in the robot's terms
            return self._shielded(obs, a) if rb.shield else a
        a = self.act(obs)
        if rb is None:
            return a
        if rb.is_diff_drive and not self.acts_unicycle:
            from pathfuse.planners.drive import to_unicycle

            a = to_unicycle(self.problem, rb, float(self.dt),  # type: ignore[arg-type]
                            obs, a)
        if not rb.shield:
            return a
        return self._shielded(obs, a)

    def relax(self, seconds: float) -> bool:
        """Recovery (ours, as Nav2's clear-costmap): drop the obstacle critics for
        ``seconds`` and replan; True when this controller has critics to drop (the base
        class has none)."""
        return False

    recovers: ClassVar[bool] = True
    """Whether :meth:`command` runs the recovery behaviours (the potential-field controllers
    have their own escape, which the paper's and pathfuse's holonomic results rest on; the
    velocity-space fusion calls them itself)."""

    def _recovering(self, obs: Observed, rb: Any, force: bool = False) -> np.ndarray | None:
        if rb is None or not rb.recovery or not self.online or not (self.recovers or force):
            return None
        from pathfuse.planners.recovery import RecoveryMonitor

        if self.recovery is None:
            self.recovery = RecoveryMonitor(
                float(self.dt), rb.is_diff_drive,  # type: ignore[arg-type]
                rb.min_speed_mps < 0.0, rb.max_yaw_rate_radps, rb.max_yaw_accel_radps2)
        return self.recovery.step(obs.position, float(obs.heading),
                                  lambda: self._path_bearing(obs), self.relax)

    def _path_bearing(self, obs: Observed) -> float | None:
        """The direction from the robot to the global path 1 m beyond its nearest point."""
        path = self.global_path
        if path is None or len(path) == 0:
            return None
        pts = np.asarray(path, dtype=np.float64).reshape(-1, 2)
        x, y = float(obs.position[0]), float(obs.position[1])
        i = int(np.argmin(np.hypot(pts[:, 0] - x, pts[:, 1] - y)))
        seg = np.hypot(*np.diff(pts[i:], axis=0).T) if pts.shape[0] - i > 1 else np.zeros(0)
        j = i + int(np.searchsorted(np.cumsum(seg), 1.0)) + 1 if seg.size else i
        j = min(j, pts.shape[0] - 1)
        dx, dy = float(pts[j, 0]) - x, float(pts[j, 1]) - y
        return math.atan2(dy, dx) if dx or dy else None

    def _shielded(self, obs: Observed, a: np.ndarray) -> np.ndarray:
        from pathfuse.costmap import Discs, costmap_for
        from pathfuse.shield import ND, NV, NW, shield_holonomic, shield_unicycle

        pb = self.problem
        rb = pb.robot
        assert rb is not None
        cm = costmap_for(pb.grid, float(pb.robot_radius_m))
        sens = obs.obstacles
        if len(sens):
            dp, dr = _plain(sens.positions), _plain(sens.radii)
            discs = Discs(dp, dp, self._disc_speed_bounds(sens), dr)
        else:
            discs = _no_shield_discs()
        cmd = obs.command
        dt = float(self.dt)  # type: ignore[arg-type]
        if rb.is_diff_drive:
            u, w, code = shield_unicycle(
                cm, float(obs.position[0]), float(obs.position[1]),
                float(obs.heading), float(cmd[0]), float(cmd[1]), float(a[0]), float(a[1]),
                dt, float(rb.min_speed_mps), float(rb.max_speed_mps),
                float(rb.max_accel_mps2), float(rb.max_yaw_rate_radps),
                float(rb.max_yaw_accel_radps2), discs, 0.0, NV, NW)
        else:
            u, w, code = shield_holonomic(
                cm, float(obs.position[0]), float(obs.position[1]),
                float(cmd[0]), float(cmd[1]), float(a[0]), float(a[1]), dt,
                float(self.max_speed if self.max_speed is not None else rb.max_speed_mps),
                float(rb.max_accel_mps2), discs, 0.0, ND)
        self.shield_counts[code] += 1
        return np.array([u, w])

    def _disc_speed_bounds(self, sens: Any) -> np.ndarray:
        """The fastest speed observed so far of each sensed disc (by id): the shield's bound
        on how fast it can come."""
        seen = self._disc_speeds
        ids = np.asarray(sens.ids)
        speed = np.hypot(sens.velocities[:, 0], sens.velocities[:, 1])
        out = np.empty(speed.shape[0])
        for j in range(speed.shape[0]):
            k = int(ids[j])
            out[j] = max(float(speed[j]), seen.get(k, 0.0))
            seen[k] = out[j]
        return out

    @classmethod
    def kernels(cls) -> Sequence[Any]:
        """The numba kernels this controller runs (to tell a cold cache)."""
        return ()

    @classmethod
    def warmup(cls) -> None:
        """Compile (or load from numba's cache) the kernels this controller runs."""

    @classmethod
    def warmup_margin(cls) -> None:
        """Compile (or load) what a plan on a static map with a safety margin
        (``clearance_m`` > 0) runs beyond :meth:`warmup`."""

    @classmethod
    def warmup_online(cls) -> None:
        """Compile (or load) the kernels it runs online (:meth:`warmup` by default; the
        field controllers' loops have a signature of their own among moving discs)."""
        cls.warmup()

    @classmethod
    def diff_drive_kernels(cls) -> Sequence[Any]:
        """The further kernels it runs online on a diff-drive robot only (compiled only
        for such an episode: a command compiles what it runs)."""
        return ()

    @classmethod
    def warmup_diff_drive(cls) -> None:
        """Compile (or load) :meth:`diff_drive_kernels`."""


class FieldController(Controller):
    """Shared logic of the potential-field controllers (see the module docstring).

    Subclasses set :attr:`default_step_frac`, the named settings ``self.settings``
    of their loop (:class:`~pathfuse.field.settings.FieldSettings` or
    :class:`~pathfuse.field.settings.FusionSettings`), and implement
    :meth:`_call`, which runs the loop on ``self.costmap`` (the
    :class:`~pathfuse.costmap.Costmap`, without its lattice) with
    ``self.disc_cfg`` (:class:`~pathfuse.field.settings.DiscSettings`) for at
    most ``max_steps`` moves from ``self.buf[self.n - 1]`` and returns ``(code,
    steps)``.
    """

    default_step_frac: ClassVar[float] = 0.1
    recovers: ClassVar[bool] = False  # Algorithm 2's escape, and apf/ref6/ref7 as printed
    disc_reach_m: float = math.inf
    settings: FieldSettings | FusionSettings

    def __init__(self, problem: Problem, params: Any, plan: Any = None, *,
                 dt: float | None = None, max_speed: float | None = None) -> None:
        super().__init__(problem, params, plan, dt=dt, max_speed=max_speed)
        p = params
        g = problem.grid
        res = g.resolution
        if self.online:
            step = float(max_speed) * float(dt)  # type: ignore[arg-type]
        else:
            step = float(p.step_m) if p.step_m is not None else self.default_step_frac * res
        self.step_m = step
        self.goal_tolerance_m = float(p.goal_tolerance_m) if p.goal_tolerance_m is not None \
            else step
        self.stall_distance_m = float(p.stall_distance_m) if p.stall_distance_m is not None \
            else STALL_FRAC * step
        self.clear_m = problem.robot_radius_m + MARGIN_FRAC * res
        #: The one collision-checking object of the loop (its clearance is ``clear_m``).
        self.costmap = costmap_for(g, problem.robot_radius_m, lattice=False)
        #: The moving discs' settings (the robot's velocity replaced every tick online).
        self.disc_cfg = self.disc_settings()
        cap = problem.budget.max_iterations
        most = limit("MAX_STEPS")
        if cap is not None:
            # the path keeps every move: more than MAX_STEPS moves are never taken (the
            # result's message then names the limit)
            self.max_steps = min(int(cap), most)
        else:
            moves = CAP_FACTOR * (g.width + g.height) * res / step + 1000
            if not moves <= most:
                raise LimitError(
                    f"step_m: a step of {step:g} m needs up to {moves:.3g} moves to cross this "
                    f"map ({g.width} x {g.height} cells of {res:g} m), above the limit of "
                    f"{most} moves (MAX_STEPS; set the environment variable "
                    f"{env_name('MAX_STEPS')} to raise it, or use a larger step)")
            self.max_steps = int(math.ceil(moves))
        size = 1024 if self.online else min(self.max_steps, 1022) + 2
        self.buf = np.empty((size, 2))
        self.buf[0] = problem.start
        self.n = 1

    def disc_settings(self) -> DiscSettings:
        """Moving-disc settings for the kernels (no effect without discs)."""
        p = self.params
        return disc_settings(
            p.k_rep if p.k_rep_moving is None else p.k_rep_moving,
            p.rho0_m if p.rho0_moving_m is None else p.rho0_moving_m,
            self.disc_reach_m, p.repulsion == "velocity", p.a_max, p.swerve)

    def _margin(self, dpos: np.ndarray | None) -> tuple[float, ...]:
        """The loops' last argument, the soft safety margin: left out of a static run
        without one (numba then compiles no margin code), the settings' ``margin_m``
        otherwise."""
        m = self.settings.margin_m
        return () if dpos is None and m <= 0.0 else (m,)

    def _call(self, max_steps: int, dpos: np.ndarray | None, dvel: np.ndarray | None,
              drad: np.ndarray | None) -> tuple[int, int]:  # pragma: no cover - abstract
        raise NotImplementedError

    # ------------------------------------------------------------------ offline
    def run(self, deadline: float | None) -> Outcome:
        """Step to the goal, a local minimum, the move cap or the deadline."""
        t0 = time.perf_counter()
        total = 0
        code = CODE_RUNNING
        while True:
            left = self.max_steps - total
            chunk = left if deadline is None else min(CHUNK, left)
            if interpreting():  # kernels run interpreted (pathfuse.tier): its budget is
                chunk = min(_INTERPRETED_CHUNK, left)  # checked between calls
            code, steps = self._call(chunk, *STATIC)  # no disc code compiled
            total += steps
            if code != CODE_RUNNING or total >= self.max_steps:
                break
            if deadline is not None and time.perf_counter() > deadline:
                break
        elapsed = time.perf_counter() - t0
        status = code_status(code, total, self.max_steps)
        path = self.buf[: self.n].copy()
        info = {"step_m": self.step_m, "goal_tolerance_m": self.goal_tolerance_m,
                "step_time_s": elapsed, "steps_per_s": total / elapsed if elapsed > 0 else 0.0}
        info.update(self.extra_info())
        if status is Status.SUCCESS:
            msg = self.success_message(total)
        else:
            msg = self.failure_message(code, status, path, total)
        return Outcome(status, path, total, elapsed, msg, info, self.length_of(path))

    def length_of(self, path: np.ndarray) -> float | None:
        """The path's length when the controller sums it its own way (None: summed by
        :func:`pathfuse.result.path_length`)."""
        return None

    def extra_info(self) -> dict[str, Any]:
        """Controller-specific entries of ``PlanResult.info``."""
        return {}

    def success_message(self, steps: int) -> str:
        return f"reached the goal in {steps} steps"

    def failure_message(self, code: int, status: Status, path: np.ndarray, steps: int) -> str:
        """A sentence for a run that did not reach the goal."""
        x, y = path[-1]
        gx, gy = self.problem.goal
        where = f"at ({x:.3f}, {y:.3f}), {math.hypot(x - gx, y - gy):.3f} m from the goal"
        if code == CODE_BLOCKED:
            return f"blocked {where}: no collision-free move along the force"
        if code == CODE_COLLISION:
            return (f"collision {where}: the full step along the force touches an obstacle "
                    "(safe_step=false, the paper's rule)")
        if code == CODE_STALLED:
            return (f"local minimum {where}: moved less than {self.stall_distance_m:g} m "
                    f"over the last {self.params.stall_steps} steps")
        if status is Status.MAX_ITERATIONS:
            cap = f"step cap of {self.max_steps} steps"
            if self.max_steps == limit("MAX_STEPS"):
                cap += " (MAX_STEPS)"
            return f"{cap} reached {where}"
        return f"time limit reached after {steps} steps, {where}"

    # ------------------------------------------------------------------ online
    def act(self, obs: Observed) -> np.ndarray:
        """One move of the same loop as :meth:`run`, among the sensed discs."""
        x = float(obs.position[0])
        y = float(obs.position[1])
        n0 = self.n
        last = self.buf[n0 - 1]
        if abs(last[0] - x) > 1e-9 or abs(last[1] - y) > 1e-9:
            self.buf[n0 - 1] = (x, y)  # the world moved the robot elsewhere (clipped, pushed)
        else:
            x, y = float(last[0]), float(last[1])
        sens = obs.obstacles
        if len(sens):
            discs = (_plain(sens.positions), _plain(sens.velocities), _plain(sens.radii))
        else:
            discs = _NO_DISCS
        self.disc_cfg = self.disc_cfg._replace(robot_vx_mps=float(obs.velocity[0]),
                                               robot_vy_mps=float(obs.velocity[1]))
        costmap = self.costmap
        self._tight(x, y)
        code, _ = self._call(1, *discs)
        self.costmap = costmap
        if code in (CODE_STALLED, CODE_BLOCKED):
            self.on_stuck()
        if self.n > n0:
            nx, ny = float(self.buf[self.n - 1, 0]), float(self.buf[self.n - 1, 1])
        else:
            nx, ny = x, y
        if self.params.dodge and len(sens) and code not in (CODE_GOAL, CODE_GOAL_SNAP) and \
                math.hypot(nx - x, ny - y) < 0.5 * self.step_m:
            d = self._dodge(sens, x, y, nx - x, ny - y)
            if d is not None:
                nx, ny = d
        dt = float(self.dt)  # type: ignore[arg-type]
        return np.array([(nx - x) / dt, (ny - y) / dt])

    def _tight(self, x: float, y: float) -> bool:
        """Online, a robot that the world left closer to a wall than the controller's
        clearance (a diff-drive robot braking late) may keep what it has for this move;
        True when the clearance of ``self.costmap`` was lowered for it (:meth:`act` puts
        the Costmap back after the move)."""
        rb = self.problem.robot
        if rb is None or not rb.is_diff_drive:
            return False
        d = point_distance(self.costmap, x, y, self.clear_m)
        if d >= self.clear_m:
            return False
        self.costmap = self.costmap._replace(clear_m=d * (1.0 - 1e-12))
        return True

    def on_stuck(self) -> None:
        """Online: the loop stalled or was blocked and could not escape; keep going."""

    def _dodge(self, sens: Any, x: float, y: float, fx: float,
               fy: float) -> tuple[float, float] | None:
        """A full clear move that most increases the predicted gap to the sensed discs.

        Used when the controller's own move is (nearly) blocked while discs
        are sensed (typically a disc pressing the robot against a wall).  The
        discs are predicted one tick ahead at their current velocity; none of
        the 12 directions (every 30 degrees, nearest to the intended move
        first) is taken unless it beats standing still.
        """
        q = sens.positions + sens.velocities * float(self.dt)  # type: ignore[arg-type]
        radii = sens.radii
        cm = self.costmap
        step = self.step_m

        def gap(px: float, py: float) -> float:
            return float((np.hypot(q[:, 0] - px, q[:, 1] - py) - radii).min())

        best = gap(x, y)
        best_xy = None
        clear = self.clear_m
        margin = self.problem.clearance_m
        if margin > 0:  # keep the safety margin, or what is left of it (ours)
            d = point_distance(cm, x, y, clear + margin)
            clear = max(clear, clear + min(margin, max(d - clear, 0.0)) * (1.0 - 1e-9))
        if fx == 0.0 and fy == 0.0:
            gx, gy = self.problem.goal
            fx, fy = gx - x, gy - y
        a0 = math.atan2(fy, fx) if (fx or fy) else 0.0
        for k in range(12):
            a = a0 + math.pi / 6 * ((k + 1) // 2) * (1 if k % 2 else -1)
            tx, ty = x + step * math.cos(a), y + step * math.sin(a)
            if move_clear(cm, x, y, tx, ty, clear):
                gp = gap(tx, ty)
                if gp > best + 1e-9:
                    best, best_xy = gp, (tx, ty)
        return best_xy
