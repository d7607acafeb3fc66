"""Moving disc obstacles: their specs and their (deterministic) motion.

Three kinds, each a frozen dataclass parsed from a scenario file:

* :class:`LinearObstacle` - constant velocity, bouncing off occupied cells
  and the map's edge (``velocity: [0, 0]`` gives a standing disc).
* :class:`PatrolObstacle` - constant speed along waypoints, cycling
  (``loop: true``) or back and forth (``loop: false``).
* :class:`RandomWalkObstacle` - constant speed, heading perturbed each tick
  by seeded Gaussian noise, bouncing like the linear kind.

Motion model
------------
A trajectory is the list of centre positions at the tick times
``t_k = k * dt``; between two ticks a disc moves in a straight line at
constant speed (this is the motion the collision checks of
:mod:`pathfuse.world.world` integrate exactly).  Consequences, all
deliberate:

* Bounces happen *at tick times*: when the straight move of the coming tick
  would make the disc overlap an occupied cell or leave the map, its velocity
  is reflected first (the component of the blocking axis; both on a corner;
  reversed if that fails too), so a disc turns up to one tick's travel before
  the wall and never overlaps it, and every tick it travels exactly
  ``speed * dt``.  The only exception: a disc boxed in so tightly that no
  reflection fits stands still for that tick.
* A patrol disc's tick positions lie exactly on its polyline at arc length
  ``speed * t``; over a tick that turns a corner it moves along the chord,
  i.e. slightly less than ``speed * dt``.
* Obstacles do not interact with each other or with the robot.

Trajectories are a pure function of the spec, the map, ``dt``, the number of
ticks and the episode seed, so an episode replays bit for bit.

Examples
--------
>>> import numpy as np
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["....", "....", "...."])            # 4 m x 3 m, empty
>>> ob = LinearObstacle(position=(1.0, 1.5), velocity=(1.0, 0.0), radius=0.5)
>>> pos, vel = ob.trajectory(g, dt=0.5, n_steps=6)
>>> pos[:, 0].tolist()      # bounces off the right edge (x <= 4 - 0.5)
[1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 3.0]
>>> vel[-1].tolist()        # the velocity it had arriving at the last tick
[-1.0, 0.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from pathfuse.costmap import (
    Costmap,
    costmap_for,
    make_costmap,
    point_distance,
    segment_clear,
    segment_distance,
)
from pathfuse.grid import GridMap

__all__ = [
    "LinearObstacle",
    "PatrolObstacle",
    "RandomWalkObstacle",
    "ObstacleSpec",
    "obstacle_trajectories",
    "warmup_obstacles",
]


@njit(cache=True)
def _bounce_trajectory(cm: Costmap, x0: float, y0: float, vx: float, vy: float, radius: float,
                       dt: float, n_steps: int, turns: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n+1, 2) and arrival velocities (n+1, 2) of a bouncing disc on the map
    ``cm`` (each move checked with :func:`~pathfuse.costmap.segment_clear` for the disc's
    ``radius``).

    ``turns`` holds one heading change (radians) per tick, applied before the
    tick's move (empty for constant velocity).
    """
    pos = np.empty((n_steps + 1, 2))
    vel = np.empty((n_steps + 1, 2))
    x = x0
    y = y0
    pos[0, 0] = x
    pos[0, 1] = y
    vel[0, 0] = vx
    vel[0, 1] = vy
    # the last step actually taken (its reverse is always free)
    lvx = 0.0
    lvy = 0.0
    moved = False
    cand = np.empty((5, 2))
    for k in range(n_steps):
        if turns.shape[0] > 0:
            c = math.cos(turns[k])
            s = math.sin(turns[k])
            vx, vy = c * vx - s * vy, s * vx + c * vy
        nvx = vx
        nvy = vy
        ok = (vx == 0.0 and vy == 0.0) or segment_clear(cm, x, y, x + vx * dt, y + vy * dt,
                                                         radius)
        if not ok:
            bx = vx != 0.0 and not segment_clear(cm, x, y, x + vx * dt, y, radius)
            by = vy != 0.0 and not segment_clear(cm, x, y, x, y + vy * dt, radius)
            if bx and not by:
                order = (0, 1, 2)
            elif by and not bx:
                order = (1, 0, 2)
            else:
                order = (2, 0, 1)
            n = 0
            for o in order:
                if o == 0:
                    cand[n, 0] = -vx
                    cand[n, 1] = vy
                elif o == 1:
                    cand[n, 0] = vx
                    cand[n, 1] = -vy
                else:
                    cand[n, 0] = -vx
                    cand[n, 1] = -vy
                n += 1
            if moved:
                cand[n, 0] = -lvx
                cand[n, 1] = -lvy
                n += 1
            for i in range(n):
                if segment_clear(cm, x, y, x + cand[i, 0] * dt, y + cand[i, 1] * dt, radius):
                    nvx = cand[i, 0]
                    nvy = cand[i, 1]
                    ok = True
                    break
        if ok:
            vx = nvx
            vy = nvy
            x = x + vx * dt
            y = y + vy * dt
            if vx != 0.0 or vy != 0.0:
                lvx = vx
                lvy = vy
                moved = True
            vel[k + 1, 0] = vx
            vel[k + 1, 1] = vy
        else:
            vel[k + 1, 0] = 0.0
            vel[k + 1, 1] = 0.0
        pos[k + 1, 0] = x
        pos[k + 1, 1] = y
    return pos, vel


def _map_of(grid: GridMap) -> Costmap:
    """The map's :class:`~pathfuse.costmap.Costmap` without a robot (radius 0, no lattice):
    each check is given the disc's radius."""
    return costmap_for(grid, 0.0, lattice=False)


@dataclass(frozen=True)
class LinearObstacle:
    """A disc moving at constant velocity, bouncing off occupied cells and the map's edge.

    Attributes
    ----------
    position : (float, float)
        Centre at ``t = 0`` (metres).
    velocity : (float, float)
        Velocity (m/s); ``(0, 0)`` is a standing disc.
    radius : float
        Disc radius (metres).
    """

    position: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.3

    kind = "linear"

    @property
    def speed(self) -> float:
        return float(math.hypot(*self.velocity))

    def trajectory(self, grid: GridMap, dt: float, n_steps: int,
                   seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Centre positions ``(n_steps + 1, 2)`` at the ticks and arrival velocities.

        ``velocities[k]`` is the velocity the disc had over tick ``k - 1 -> k``
        (``velocities[0]`` is the initial velocity): what a sensor sees at
        tick ``k`` without looking ahead.  ``seed`` is unused (no randomness).
        """
        return _bounce_trajectory(_map_of(grid), float(self.position[0]),
                                  float(self.position[1]), float(self.velocity[0]),
                                  float(self.velocity[1]), float(self.radius), float(dt),
                                  int(n_steps), np.zeros(0))

    def to_dict(self) -> dict:
        return {"position": list(self.position), "velocity": list(self.velocity),
                "radius": self.radius}


@dataclass(frozen=True)
class PatrolObstacle:
    """A disc travelling at constant speed along waypoints.

    Attributes
    ----------
    waypoints : tuple of (float, float)
        At least two points; the disc starts at the first.
    speed : float
        Speed along the polyline (m/s, > 0).
    radius : float
        Disc radius (metres).
    loop : bool
        ``True``: after the last waypoint go straight back to the first and
        repeat.  ``False``: go back and forth along the polyline.

    Examples
    --------
    >>> from pathfuse.grid import GridMap
    >>> p = PatrolObstacle(((1.0, 1.0), (3.0, 1.0)), speed=1.0, radius=0.2, loop=False)
    >>> pos, _ = p.trajectory(GridMap.from_rows(["....", "...."]), dt=1.0, n_steps=5)
    >>> pos[:, 0].tolist()
    [1.0, 2.0, 3.0, 2.0, 1.0, 2.0]
    """

    waypoints: tuple[tuple[float, float], ...]
    speed: float
    radius: float = 0.3
    loop: bool = True

    kind = "patrol"

    @property
    def position(self) -> tuple[float, float]:
        return self.waypoints[0]

    def polyline(self) -> np.ndarray:
        """The closed (loop) or open polyline the disc travels, (M, 2)."""
        w = np.asarray(self.waypoints, dtype=np.float64)
        if self.loop:
            w = np.vstack([w, w[:1]])
        return w

    def positions_at(self, t: np.ndarray) -> np.ndarray:
        """Centre positions (N, 2) at times ``t`` (seconds), in closed form."""
        w = self.polyline()
        seg = np.hypot(*np.diff(w, axis=0).T)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        total = float(cum[-1])
        t = np.asarray(t, dtype=np.float64)
        if total == 0.0:
            return np.repeat(w[:1], t.shape[0], axis=0)
        s = self.speed * t
        if self.loop:
            s = np.mod(s, total)
        else:
            s = np.mod(s, 2.0 * total)
            s = np.where(s > total, 2.0 * total - s, s)
        i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
        seg_len = np.where(seg[i] > 0, seg[i], 1.0)
        f = np.clip((s - cum[i]) / seg_len, 0.0, 1.0)[:, None]
        return w[i] + f * (w[i + 1] - w[i])

    def trajectory(self, grid: GridMap, dt: float, n_steps: int,
                   seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Positions and arrival velocities, as :meth:`LinearObstacle.trajectory`."""
        pos = self.positions_at(np.arange(n_steps + 1) * float(dt))
        vel = np.empty_like(pos)
        vel[1:] = np.diff(pos, axis=0) / dt
        w = self.polyline()
        d = w[1] - w[0]
        n = float(np.hypot(*d))
        vel[0] = d / n * self.speed if n > 0 else 0.0
        return pos, vel

    def to_dict(self) -> dict:
        return {"waypoints": [list(p) for p in self.waypoints], "speed": self.speed,
                "radius": self.radius, "loop": self.loop}


@dataclass(frozen=True)
class RandomWalkObstacle:
    """A disc moving at constant speed with a seeded random heading.

    Each tick the heading turns by a Gaussian angle of standard deviation
    ``turn_std * sqrt(dt)`` radians (a heading random walk with diffusion
    ``turn_std`` rad/sqrt(s)); the disc bounces like :class:`LinearObstacle`.

    Attributes
    ----------
    position : (float, float)
        Centre at ``t = 0``.
    speed : float
        Speed (m/s, > 0).
    radius : float
        Disc radius (metres).
    seed : int
        Seed of the heading noise (and of the initial heading when
        ``heading`` is None).
    turn_std : float
        Heading diffusion in rad/sqrt(s).
    heading : float or None
        Initial heading in radians (0 = +x); None draws it from ``seed``.
    """

    position: tuple[float, float]
    speed: float
    radius: float = 0.3
    seed: int = 0
    turn_std: float = 1.0
    heading: float | None = None

    kind = "random_walk"

    def trajectory(self, grid: GridMap, dt: float, n_steps: int,
                   seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Positions and arrival velocities, as :meth:`LinearObstacle.trajectory`.

        The noise comes from ``numpy.random.default_rng(self.seed)``, or from
        ``default_rng([seed, self.seed])`` when an episode ``seed`` is given,
        so one scenario can be replayed with other random walks.
        """
        rng = np.random.default_rng(self.seed if seed is None else [int(seed), self.seed])
        h0 = rng.uniform(-math.pi, math.pi)
        if self.heading is not None:
            h0 = float(self.heading)
        turns = rng.standard_normal(int(n_steps)) * (self.turn_std * math.sqrt(dt))
        return _bounce_trajectory(_map_of(grid), float(self.position[0]),
                                  float(self.position[1]), self.speed * math.cos(h0),
                                  self.speed * math.sin(h0), float(self.radius), float(dt),
                                  int(n_steps), turns)

    def to_dict(self) -> dict:
        rw: dict = {"position": list(self.position), "speed": self.speed, "seed": self.seed,
                    "turn_std": self.turn_std}
        if self.heading is not None:
            rw["heading"] = self.heading
        return {"random_walk": rw, "radius": self.radius}


ObstacleSpec = LinearObstacle | PatrolObstacle | RandomWalkObstacle


def obstacle_trajectories(obstacles: tuple[ObstacleSpec, ...] | list[ObstacleSpec],
                          grid: GridMap, dt: float, n_steps: int,
                          seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Positions and arrival velocities of all obstacles, each ``(n_steps + 1, K, 2)``.

    >>> from pathfuse.grid import GridMap
    >>> pos, vel = obstacle_trajectories([], GridMap.from_rows([".."]), 0.1, 3)
    >>> pos.shape, vel.shape
    ((4, 0, 2), (4, 0, 2))
    """
    k = len(obstacles)
    pos = np.empty((n_steps + 1, k, 2))
    vel = np.empty((n_steps + 1, k, 2))
    for i, ob in enumerate(obstacles):
        pos[:, i], vel[:, i] = ob.trajectory(grid, dt, n_steps, seed)
    return pos, vel


def warmup_obstacles() -> None:
    """Compile (or load from numba's cache) the motion kernel and the checks the scenario
    and the world call from Python (a disc at a point, a straight move)."""
    cm = make_costmap(np.zeros((3, 3), dtype=np.bool_), 0.0, lattice=False)
    _bounce_trajectory(cm, 1.5, 1.5, 1.0, 0.0, 0.2, 0.5, 4, np.zeros(4))
    point_distance(cm, 1.5, 1.5, 0.2)
    segment_distance(cm, 1.5, 1.5, 1.6, 1.2, 0.2)
