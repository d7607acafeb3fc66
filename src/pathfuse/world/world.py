"""The simulated world: a disc robot, a static map and moving discs, stepped tick by tick.

:class:`World` follows the Gymnasium ``reset`` / ``step`` pattern (without
depending on Gymnasium and without a reward)::

    world = World(scenario)
    obs = world.reset(seed=0)
    while True:
        obs, terminated, truncated, info = world.step(velocity)
        if terminated or truncated:
            break

The action
----------
It depends on the robot's model (``robot.kind``, :class:`pathfuse.robot.RobotModel`):

* holonomic (the default): a **velocity** ``(vx, vy)`` in m/s, held for one
  tick of ``dt`` seconds.  Its norm is clipped to ``robot.max_speed_mps``
  (direction kept) and, with ``robot.max_accel_mps2`` set, its change to
  ``max_accel_mps2 * dt``; the robot moves in a straight line from ``p`` to
  ``p + v * dt``.
* diff-drive: ``(v, omega)``, the linear speed along the heading and the yaw
  rate, each clipped to its limit and to the window its acceleration limit
  reaches from the last command; the robot follows the exact arc
  (:func:`~pathfuse.sweep.unicycle_pose`) and its heading turns by
  ``omega * dt``.

The observation's ``heading`` is the diff-drive robot's heading, or the
direction of a holonomic robot's last non-zero velocity (at reset: the
robot's ``heading``, or facing the goal).

Collisions (checked over the whole tick, not at its end points)
---------------------------------------------------------------
* Static: the robot disc swept along its segment overlaps an occupied cell
  or leaves the map - exactly, with the checks of the map's
  :class:`~pathfuse.costmap.Costmap` (built once per map and radius):
  :func:`~pathfuse.costmap.segment_distance` (closed-form
  segment-to-square distances; no sampling, so no step size is too large).
  Along an arc: :func:`~pathfuse.costmap.arc_distance` (chords with a
  provable deviation bound, refined to 1e-9 m where it decides).
* Moving discs: both centres move linearly over the tick, so their distance
  is minimised in closed form
  (:func:`~pathfuse.sweep.disc_sweep_gaps`); along an arc,
  :func:`~pathfuse.sweep.arc_disc_gaps`.

Who is at fault (``info["at_fault"]``)
--------------------------------------
On a collision, ``True`` when the robot was moving during the colliding tick
(the applied command's linear speed, or the holonomic velocity, is non-zero)
and ``False`` when a moving disc walked into a robot standing still (a
diff-drive robot turning on the spot counts as standing: its disc footprint
does not move).  A static collision is always the robot's fault.  ``None``
without a collision.  The safety shield (:mod:`pathfuse.shield`) guarantees
only *passive* safety, so the benchmarks count the two kinds apart.

``terminated`` is ``True`` on a collision or when the robot's centre passes
within ``goal_tolerance`` of the goal during the tick (a collision in the
same tick wins: the conservative reading); ``truncated`` is ``True`` when the
tick count reaches ``ceil(time_limit / dt)``.

Sensing
-------
The observation holds the robot's state, the goal and the moving discs
whose surface lies within ``robot.sensing_radius_m`` of the robot's centre
*now*: their ids, positions, current velocities (the velocity they had over
the last tick, or their initial velocity at tick 0) and radii.  Obstacle
trajectories are precomputed at :meth:`World.reset` (they are a pure
function of the scenario and the seed), but planners only ever see
observations, so they never read the future.

Examples
--------
>>> from pathfuse.world.scenario import load_scenario
>>> sc = load_scenario({"map": {"rows": ["....."]}, "start": [0.5, 0.5],
...                     "goal": [4.5, 0.5], "robot": {"radius": 0.2}, "dt": 0.5})
>>> w = World(sc)
>>> obs = w.reset()
>>> obs.position.tolist(), obs.obstacles.positions.shape
([0.5, 0.5], (0, 2))
>>> for _ in range(8):
...     obs, term, trunc, info = w.step((5.0, 0.0))      # clipped to 1 m/s
...     if term or trunc:
...         break
>>> info["event"], obs.tick, obs.position.tolist()
('reached', 8, [4.5, 0.5])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pathfuse.costmap import arc_distance, costmap_for, segment_distance
from pathfuse.geometry import point_segment_distance
from pathfuse.result import PathfuseError, QueryError, Status
from pathfuse.shield import clip_holonomic, clip_unicycle
from pathfuse.sweep import arc_disc_gaps, disc_sweep_gaps, unicycle_pose
from pathfuse.validate import short as _shown
from pathfuse.world.obstacles import obstacle_trajectories
from pathfuse.world.scenario import Scenario, load_scenario

__all__ = ["World", "Observation", "SensedObstacles", "STATIC_CLEARANCE_CAP_M"]

STATIC_CLEARANCE_CAP_M = 2.0
"""Static clearances are computed exactly up to this many metres and reported capped at it."""


@dataclass(frozen=True)
class SensedObstacles:
    """The moving discs inside the sensing radius at one tick.

    Attributes
    ----------
    ids : (M,) int array
        Indices into the scenario's ``obstacles``.
    positions : (M, 2) float array
        Centres (metres).
    velocities : (M, 2) float array
        Current velocities (m/s): the last tick's displacement over ``dt``
        (the initial velocity at tick 0).
    radii : (M,) float array
        Radii (metres).
    """

    ids: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray

    def __len__(self) -> int:
        return int(self.ids.shape[0])


@dataclass(frozen=True)
class Observation:
    """What a planner sees at one tick.

    Attributes
    ----------
    tick : int
        Tick index (0 at reset).
    time : float
        ``tick * dt`` in seconds.
    position : (2,) float array
        Robot centre.
    velocity : (2,) float array
        The velocity the robot moved with over the last tick (zero at reset).
    goal : (2,) float array
        The goal.
    obstacles : SensedObstacles
        Moving discs within the sensing radius.
    heading : float
        The robot's heading (rad; see the module docstring).
    command : (2,) float array
        The last action as applied: ``(vx, vy)`` (holonomic) or ``(v, omega)``
        (diff-drive); zero at reset.
    """

    tick: int
    time: float
    position: np.ndarray
    velocity: np.ndarray
    goal: np.ndarray
    obstacles: SensedObstacles
    heading: float = 0.0
    command: np.ndarray = field(default_factory=lambda: np.zeros(2))


class World:
    """A scenario brought to life: the clock, the robot state and the moving discs.

    Parameters
    ----------
    scenario : Scenario, path or mapping
        Anything :func:`~pathfuse.world.scenario.load_scenario` reads.
    """

    def __init__(self, scenario: Any) -> None:
        self.scenario: Scenario = load_scenario(scenario)
        sc = self.scenario
        g = sc.grid
        self.dt = float(sc.dt)
        self.n_steps = sc.n_steps
        self.robot = sc.robot
        self.radius = float(sc.robot.radius_m)
        # the static map and the robot's disc: the collision test's costmap
        self.costmap = costmap_for(g, self.radius)
        self.max_speed = float(sc.robot.max_speed_mps)
        self.sensing_radius = float(sc.robot.sensing_radius_m)
        self.diff_drive = self.robot.is_diff_drive
        self.goal = np.array(sc.goal, dtype=np.float64)
        self.obstacle_radii = np.array([ob.radius for ob in sc.obstacles], dtype=np.float64)
        # without moving discs every observation senses none: one empty record serves them
        # all (its arrays have no element to change)
        self._none_sensed = SensedObstacles(np.zeros(0, np.int64), np.zeros((0, 2)),
                                            np.zeros((0, 2)), np.zeros(0))
        self._tick = -1
        self._done = True
        self.seed: int | None = None
        self.obstacle_positions = np.zeros((0, 0, 2))
        self.obstacle_velocities = np.zeros((0, 0, 2))
        self.position = np.array(sc.start, dtype=np.float64)
        self.velocity = np.zeros(2)
        self.heading = self._initial_heading()
        self.command = np.zeros(2)

    def _initial_heading(self) -> float:
        h = self.robot.heading_rad
        if h is not None:
            return float(h)
        sc = self.scenario
        dx, dy = sc.goal[0] - sc.start[0], sc.goal[1] - sc.start[1]
        return math.atan2(dy, dx) if (dx or dy) else 0.0

    # ------------------------------------------------------------------ state
    @property
    def tick(self) -> int:
        return self._tick

    @property
    def time(self) -> float:
        return self._tick * self.dt

    @property
    def done(self) -> bool:
        return self._done

    def static_gap(self, a: np.ndarray, b: np.ndarray | None = None) -> float:
        """Clearance of the robot disc swept from ``a`` to ``b`` to the static map.

        Negative means overlap; capped at :data:`STATIC_CLEARANCE_CAP_M`.
        """
        b = a if b is None else b
        d = segment_distance(self.costmap, float(a[0]), float(a[1]), float(b[0]), float(b[1]),
                             self.radius + STATIC_CLEARANCE_CAP_M)
        return float(d) - self.radius

    def _sense(self) -> SensedObstacles:
        k = self._tick
        if self.obstacle_radii.shape[0] == 0:
            return self._none_sensed
        q = self.obstacle_positions[k]
        d = np.hypot(q[:, 0] - self.position[0], q[:, 1] - self.position[1]) - self.obstacle_radii
        ids = np.flatnonzero(d <= self.sensing_radius)
        return SensedObstacles(ids, q[ids].copy(), self.obstacle_velocities[k, ids].copy(),
                               self.obstacle_radii[ids].copy())

    def observe(self) -> Observation:
        """The observation at the current tick."""
        if self._tick < 0:
            raise PathfuseError("the world has not been reset; call reset() first")
        return Observation(self._tick, self._tick * self.dt, self.position.copy(),
                           self.velocity.copy(), self.goal.copy(), self._sense(),
                           float(self.heading), self.command.copy())

    # ------------------------------------------------------------------ gym-style API
    def reset(self, seed: int | None = None) -> Observation:
        """Start an episode: the robot at the start, the clock at 0, the discs at tick 0.

        ``seed`` (default: the scenario's ``seed``) is mixed into the random
        walks' seeds and draws the scenario's ``perturb`` jitter of the discs
        (:meth:`~pathfuse.world.scenario.Scenario.obstacles_for`); the same
        scenario and seed give the same episode.
        """
        sc = self.scenario
        self.seed = sc.seed if seed is None else int(seed)
        self.obstacle_positions, self.obstacle_velocities = obstacle_trajectories(
            sc.obstacles_for(self.seed), sc.grid, self.dt, self.n_steps, self.seed)
        self.obstacle_positions.setflags(write=False)
        self.obstacle_velocities.setflags(write=False)
        self.position = np.array(sc.start, dtype=np.float64)
        self.velocity = np.zeros(2)
        self.heading = self._initial_heading()
        self.command = np.zeros(2)
        self._tick = 0
        self._done = False
        return self.observe()

    def clip_action(self, action: Any) -> tuple[np.ndarray, bool]:
        """The action the robot will really use, and whether it was clipped.

        Holonomic: the velocity, its norm clipped to the speed limit and its
        change to the acceleration limit.  Diff-drive: ``(v, omega)``, each
        clipped to its limits and to its acceleration window.
        """
        if type(action) is np.ndarray and action.dtype == np.float64 \
                and action.shape == (2,):
            lin, ang = float(action[0]), float(action[1])  # what the controllers return
        else:
            what = "(v, omega)" if self.diff_drive else "velocity (vx, vy)"
            try:
                v = np.asarray(action, dtype=np.float64).reshape(-1)
            except (TypeError, ValueError):
                raise QueryError(f"action must be a {what}, got {_shown(action)}") from None
            if v.shape != (2,):
                raise QueryError(f"action must be finite {what}, got {_shown(action)}")
            lin, ang = float(v[0]), float(v[1])
        if not (math.isfinite(lin) and math.isfinite(ang)):
            what = "(v, omega)" if self.diff_drive else "velocity (vx, vy)"
            raise QueryError(f"action must be finite {what}, got {_shown(action)}")
        rb = self.robot
        dt = self.dt
        if self.diff_drive:
            a, b = clip_unicycle(float(self.command[0]), float(self.command[1]), lin, ang, dt,
                                 rb.min_speed_mps, rb.max_speed_mps, rb.max_accel_mps2,
                                 rb.max_yaw_rate_radps, rb.max_yaw_accel_radps2)
        else:
            a, b = clip_holonomic(float(self.velocity[0]), float(self.velocity[1]), lin, ang,
                                  dt, self.max_speed, rb.max_accel_mps2)
        out = np.array([a, b])
        return out, bool(a != lin or b != ang)

    def step(self, action: Any) -> tuple[Observation, bool, bool, dict[str, Any]]:
        """Move the robot with velocity ``action`` for one tick and the discs with it.

        Returns
        -------
        observation : Observation
        terminated : bool
            Goal reached or collision.
        truncated : bool
            The time limit was reached without termination.
        info : dict
            ``event`` ("reached", "collision" or None: the
            :attr:`~pathfuse.result.Status.key` of the outcome), ``collision``
            ("static", the index of the disc hit, or None), ``static_gap``
            and ``obstacle_gap`` (least clearance over the tick, metres;
            ``inf`` without discs), ``clipped`` (speed limited), ``at_fault``
            (on a collision: ``True`` when the robot moved during the tick or hit
            the static map, ``False`` when a disc hit it standing still; ``None``
            without a collision; see the module docstring).
        """
        if self._done:
            raise PathfuseError("the episode is over; call reset() to start another")
        cmd, clipped = self.clip_action(action)
        k = self._tick
        p0 = self.position
        th0 = self.heading
        arc = self.diff_drive and cmd[0] != 0.0 and cmd[1] != 0.0
        if self.diff_drive:
            x1, y1, th1 = unicycle_pose(float(p0[0]), float(p0[1]), th0, float(cmd[0]),
                                        float(cmd[1]), self.dt)
            p1 = np.array([x1, y1])
        else:
            p1 = p0 + cmd * self.dt
            th1 = math.atan2(cmd[1], cmd[0]) if (cmd[0] or cmd[1]) else th0
        if arc:
            d = arc_distance(self.costmap, float(p0[0]), float(p0[1]), th0, float(cmd[0]),
                             float(cmd[1]), self.dt, self.radius,
                             self.radius + STATIC_CLEARANCE_CAP_M)
            static_gap = float(d) - self.radius
        else:
            static_gap = self.static_gap(p0, p1)
        obstacle_gap = math.inf
        hit_disc = -1
        if self.obstacle_radii.shape[0]:
            q0, q1 = self.obstacle_positions[k], self.obstacle_positions[k + 1]
            if arc:
                gaps = arc_disc_gaps(float(p0[0]), float(p0[1]), th0, float(cmd[0]),
                                     float(cmd[1]), self.dt, self.radius, q0, q1,
                                     self.obstacle_radii)
            else:
                gaps = disc_sweep_gaps(p0, p1, self.radius, q0, q1, self.obstacle_radii)
            j = int(np.argmin(gaps))
            obstacle_gap = float(gaps[j])
            if obstacle_gap < 0.0:
                hit_disc = j
        event = None
        collision: Any = None
        at_fault: bool | None = None
        if static_gap < 0.0:
            event, collision, at_fault = Status.COLLISION.key, "static", True
        elif hit_disc >= 0:
            event, collision = Status.COLLISION.key, hit_disc
            at_fault = self._moving(cmd)
        elif self._passes_goal(p0, p1, th0, cmd, arc):
            event = Status.SUCCESS.key
        self.position = p1
        self.velocity = (p1 - p0) / self.dt if self.diff_drive else cmd
        self.heading = float(th1)
        self.command = cmd
        self._tick = k + 1
        terminated = event is not None
        truncated = (not terminated) and self._tick >= self.n_steps
        self._done = terminated or truncated
        info = {"event": event, "collision": collision, "static_gap": static_gap,
                "obstacle_gap": obstacle_gap, "clipped": clipped, "at_fault": at_fault}
        return self.observe(), terminated, truncated, info

    def _moving(self, cmd: np.ndarray) -> bool:
        """Whether the applied command moves the robot's disc: a non-zero linear speed
        (diff-drive; turning on the spot leaves the disc where it is) or velocity."""
        if self.diff_drive:
            return bool(cmd[0] != 0.0)
        return bool(cmd[0] != 0.0 or cmd[1] != 0.0)

    def _passes_goal(self, p0: np.ndarray, p1: np.ndarray, th0: float, cmd: np.ndarray,
                     arc: bool) -> bool:
        """Whether the centre passes within the goal tolerance during the tick (on an arc:
        by chords, each counted only when it is within the tolerance less its bound)."""
        gx, gy = self.goal
        tol = self.scenario.goal_tolerance
        if not arc:
            return bool(point_segment_distance(gx, gy, p0[0], p0[1], p1[0], p1[1]) <= tol)
        v, w = float(cmd[0]), float(cmd[1])
        # the whole arc lies within |v w| dt^2 / 8 of its chord (its sagitta's bound): when
        # the goal is farther than that beyond the tolerance, no chord below can pass it
        if point_segment_distance(gx, gy, p0[0], p0[1], p1[0], p1[1]) \
                - abs(v * w) * self.dt ** 2 / 8.0 > tol + 1e-9:
            return False
        n = max(1, int(math.ceil(math.sqrt(abs(v * w) * self.dt ** 2 / 8.0 / 1e-6))))
        h = self.dt / n
        e = abs(v * w) * h * h / 8.0
        ax, ay = float(p0[0]), float(p0[1])
        for i in range(1, n + 1):
            bx, by, _ = unicycle_pose(float(p0[0]), float(p0[1]), th0, v, w, i * h)
            if point_segment_distance(gx, gy, ax, ay, bx, by) + e <= tol:
                return True
            ax, ay = bx, by
        return False
