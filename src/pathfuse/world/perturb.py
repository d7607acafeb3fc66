"""Seeded perturbation of a scenario's moving discs (ours): N seeds, N different episodes.

A hand-written scenario is deterministic: every seed replays the same
episode, so "50 seeds" of it measure one episode 50 times.  A scenario's
optional ``perturb:`` section jitters its discs from the episode seed::

    perturb:
      position_m: 0.3     # each disc's start (a patrol: every waypoint) moves by up to
                          # this many metres, uniformly over a disc of that radius
      speed_frac: 0.2     # each disc's speed is scaled by a factor uniform in [0.8, 1.2]
      heading_deg: 10     # a constant-velocity disc's direction turns by up to 10 degrees

Each disc draws from its own stream (the episode seed and the disc's index),
so adding a disc does not change the others' draws.  A draw that puts a disc
into an occupied cell, off the map or onto the robot's start (or blocks a
patrol's leg) is drawn again, up to :data:`ATTEMPTS` times; a disc with no
valid draw keeps its written motion.  No seed (``seed: null`` and none given
to :func:`~pathfuse.simulate`) means no perturbation: the scenario as written.

Examples
--------
>>> from pathfuse.world.obstacles import LinearObstacle
>>> p = Perturbation(position_m=0.2, speed_frac=0.1)
>>> ob = LinearObstacle(position=(3.0, 1.0), velocity=(-0.5, 0.0), radius=0.3)
>>> a = perturb_obstacles((ob,), p, 7, lambda i, o: True)[0]
>>> b = perturb_obstacles((ob,), p, 7, lambda i, o: True)[0]
>>> a == b, a == ob, round(abs(a.speed / ob.speed - 1.0), 3) <= 0.1
(True, False, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pathfuse import validate
from pathfuse.result import ConfigError
from pathfuse.world.obstacles import (
    LinearObstacle,
    ObstacleSpec,
    PatrolObstacle,
    RandomWalkObstacle,
)

__all__ = ["Perturbation", "perturb_obstacles", "parse_perturb", "ATTEMPTS", "PERTURB_KEYS"]

ATTEMPTS = 32
"""Draws per disc before it keeps its written motion."""
PERTURB_KEYS = ("position_m", "speed_frac", "heading_deg")
_STREAM = 0x70657274  # "pert": keeps these draws apart from every other use of the seed


@dataclass(frozen=True)
class Perturbation:
    """How far a seed may move the discs of a scenario (see the module docstring).

    Attributes
    ----------
    position_m : float
        Largest displacement of a disc's start (a patrol: of each waypoint), metres.
    speed_frac : float
        Largest relative change of a disc's speed (``< 1``).
    heading_deg : float
        Largest turn of a constant-velocity disc's direction, degrees.
    """

    position_m: float = 0.0
    speed_frac: float = 0.0
    heading_deg: float = 0.0

    @property
    def active(self) -> bool:
        """Whether any disc can move."""
        return self.position_m > 0.0 or self.speed_frac > 0.0 or self.heading_deg > 0.0

    def to_dict(self) -> dict[str, float]:
        return {"position_m": self.position_m, "speed_frac": self.speed_frac,
                "heading_deg": self.heading_deg}


def parse_perturb(v: Any, error: type[ConfigError]) -> Perturbation | None:
    """The ``perturb:`` section of a scenario file (None when absent); a bad key or value
    raises ``error`` naming it."""
    if v is None:
        return None
    m = validate.mapping(v, "perturb", PERTURB_KEYS, "a mapping", error)
    return Perturbation(
        position_m=validate.number(m.get("position_m", 0.0), "perturb.position_m", ge=0,
                                   error=error),
        speed_frac=validate.number(m.get("speed_frac", 0.0), "perturb.speed_frac", ge=0,
                                   lt=1, error=error),
        heading_deg=validate.number(m.get("heading_deg", 0.0), "perturb.heading_deg", ge=0,
                                    le=180, error=error),
    )


def _offset(rng: np.random.Generator, r: float) -> tuple[float, float]:
    if r <= 0.0:
        return 0.0, 0.0
    rho = r * math.sqrt(float(rng.random()))
    phi = 2.0 * math.pi * float(rng.random())
    return rho * math.cos(phi), rho * math.sin(phi)


def _draw(ob: ObstacleSpec, p: Perturbation, rng: np.random.Generator) -> ObstacleSpec:
    scale = 1.0 + p.speed_frac * (2.0 * float(rng.random()) - 1.0)
    if isinstance(ob, PatrolObstacle):
        wps = []
        for w in ob.waypoints:
            dx, dy = _offset(rng, p.position_m)
            wps.append((w[0] + dx, w[1] + dy))
        return replace(ob, waypoints=tuple(wps), speed=ob.speed * scale)
    dx, dy = _offset(rng, p.position_m)
    pos = (ob.position[0] + dx, ob.position[1] + dy)
    if isinstance(ob, RandomWalkObstacle):
        return replace(ob, position=pos, speed=ob.speed * scale)
    turn = math.radians(p.heading_deg) * (2.0 * float(rng.random()) - 1.0)
    vx, vy = ob.velocity
    c, s = math.cos(turn), math.sin(turn)
    vel = ((c * vx - s * vy) * scale, (s * vx + c * vy) * scale)
    assert isinstance(ob, LinearObstacle)
    return replace(ob, position=pos, velocity=vel)


def perturb_obstacles(obstacles: tuple[ObstacleSpec, ...], perturbation: Perturbation,
                      seed: int, valid: Callable[[int, ObstacleSpec], bool]
                      ) -> tuple[ObstacleSpec, ...]:
    """The discs ``obstacles`` jittered by ``perturbation`` from ``seed``.

    Parameters
    ----------
    obstacles : tuple of obstacle specs
        The scenario's discs as written.
    perturbation : Perturbation
        The bounds of the jitter.
    seed : int
        The episode seed (``>= 0``).
    valid : callable
        ``valid(index, spec)``: whether a drawn disc fits the scene (the
        scenario's own checks).

    Returns
    -------
    tuple of obstacle specs
        Same kinds, radii and order; the same seed gives the same tuple.
    """
    if not perturbation.active:
        return tuple(obstacles)
    out = []
    for i, ob in enumerate(obstacles):
        rng = np.random.default_rng([int(seed), _STREAM, i])
        chosen = ob
        for _ in range(ATTEMPTS):
            cand = _draw(ob, perturbation, rng)
            if valid(i, cand):
                chosen = cand
                break
        out.append(chosen)
    return tuple(out)
