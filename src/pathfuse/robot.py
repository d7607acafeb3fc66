"""The robot: a disc with a kinematic model, its limits, its sensing range and a safety margin.

:class:`RobotModel` is the one Python description of a robot (units in the
names); a scenario's ``robot:`` block (:class:`pathfuse.world.RobotSpec`) is
read into it, :func:`pathfuse.simulate` accepts one (``robot=``), and the
controllers read their limits from it.

Models (``kind``)
-----------------
``"holonomic"`` (the default, and pathfuse's model before robots had kinematics)
    The action is a velocity ``(vx, vy)``.  Its norm is clipped to
    ``max_speed_mps``; with ``max_accel_mps2`` set, its change over a tick is
    clipped to ``max_accel_mps2 * dt`` too (default: none, the velocity changes
    at once).  The robot moves in a straight line over each tick.
``"diff-drive"`` (a unicycle, as a differential-drive base such as a Jackal)
    The action is ``(v, omega)``: linear speed along the heading (m/s) and
    yaw rate (rad/s).  ``v`` is clipped to ``[min_speed_mps, max_speed_mps]``
    and ``omega`` to ``+-max_yaw_rate_radps``, each also to the window its
    acceleration limit reaches within one tick from the last command.  Over a
    tick the robot follows the exact arc of constant ``(v, omega)``; the
    heading is part of the state.

The footprint is a disc of ``radius_m`` for both models (so turning on the
spot never collides).  ``clearance_m`` is a *soft* safety margin (ours): the
global planner pays a cost to come closer than it to an obstacle and the
controllers keep it where they can (see the guide's "Robots, kinematics and
the safety margin").  ``inflation_m`` is the global planner's inflation alone
(ours, after Nav2's inflation layer): the A* path pays a cost to pass closer
than it to an obstacle, so it runs down the middle of passages where the map
leaves room, while the controllers keep only the radius (and ``clearance_m``).
A diff-drive robot gets 0.3 m by default; 0 switches it off.

Examples
--------
>>> RobotModel().kind, RobotModel().max_accel_mps2
('holonomic', inf)
>>> jackal = RobotModel.diff_drive(radius_m=0.3, max_speed_mps=2.0)
>>> jackal.kind, jackal.max_yaw_rate_radps, jackal.is_diff_drive
('diff-drive', 2.0, True)
>>> RobotModel(kind="tank")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: robot.kind: must be one of 'holonomic', 'diff-drive', got 'tank'
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from pathfuse import validate
from pathfuse.result import ConfigError

__all__ = ["RobotModel", "KINDS", "DIFF_DRIVE_DEFAULTS"]

KINDS = ("holonomic", "diff-drive")
"""The kinematic models."""

DIFF_DRIVE_DEFAULTS = {"max_accel_mps2": 2.0, "max_yaw_rate_radps": 2.0,
                       "max_yaw_accel_radps2": 4.0, "inflation_m": 0.3}
"""The limits a diff-drive robot gets when none is given (a small indoor base), and its
global planner's inflation (ours, after Nav2's inflation layer)."""


@dataclass(frozen=True)
class RobotModel:
    """A disc robot with a kinematic model (see the module docstring).

    Attributes
    ----------
    kind : {"holonomic", "diff-drive"}
    radius_m : float
        Disc radius (>= 0).
    max_speed_mps : float
        Speed limit (> 0).
    sensing_radius_m : float
        Moving discs whose surface comes this close to the centre are observed.
    max_accel_mps2 : float
        Linear acceleration limit (> 0; ``inf``: none).  Holonomic: on the
        velocity vector; diff-drive: on ``v``.
    max_yaw_rate_radps, max_yaw_accel_radps2 : float
        Diff-drive only: yaw-rate limit and its acceleration limit.
    min_speed_mps : float
        Diff-drive only: the lowest ``v`` (<= 0; negative allows reversing).
    clearance_m : float
        The soft safety margin beyond the radius (>= 0; 0 = off).
    inflation_m : float
        The global planner's inflation beyond the radius (>= 0; ours; 0 = off,
        the default of a holonomic robot; a diff-drive robot gets 0.3): cells
        closer than this to an obstacle cost more to the A* path.
    heading_rad : float or None
        Initial heading (None: facing the goal).
    shield : bool
        Online, pass every command through the safety shield
        (:mod:`pathfuse.shield`, ours): a command is executed only when the
        robot could still stop clear of the static map after it.  True by
        default; False runs the controllers' commands as they are.
    recovery : bool
        Online, run a recovery behaviour when the robot stalls or oscillates
        (:mod:`pathfuse.planners.recovery`, ours: clear the obstacle critics,
        spin, back up or wait, each through the shield).  True by default.
    """

    kind: str = "holonomic"
    radius_m: float = 0.2
    max_speed_mps: float = 1.0
    sensing_radius_m: float = 3.0
    max_accel_mps2: float = math.inf
    max_yaw_rate_radps: float = math.inf
    max_yaw_accel_radps2: float = math.inf
    min_speed_mps: float = 0.0
    clearance_m: float = 0.0
    inflation_m: float = 0.0
    heading_rad: float | None = None
    shield: bool = True
    recovery: bool = True

    def __post_init__(self) -> None:
        validate.choice(self.kind, "robot.kind", KINDS)
        validate.number(self.radius_m, "robot.radius_m", ge=0)
        validate.number(self.max_speed_mps, "robot.max_speed_mps", gt=0)
        validate.number(self.sensing_radius_m, "robot.sensing_radius_m", gt=0)
        for k in ("max_accel_mps2", "max_yaw_rate_radps", "max_yaw_accel_radps2"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0
                    and not math.isnan(v)):
                raise ConfigError(f"robot.{k}: must be a number > 0 (inf: no limit), "
                                  f"got {validate.short(v)}")
        validate.number(self.min_speed_mps, "robot.min_speed_mps", le=0)
        validate.number(self.clearance_m, "robot.clearance_m", ge=0)
        validate.number(self.inflation_m, "robot.inflation_m", ge=0)
        if self.heading_rad is not None:
            validate.number(self.heading_rad, "robot.heading_rad")
        validate.flag(self.shield, "robot.shield")
        validate.flag(self.recovery, "robot.recovery")
        if self.kind == "holonomic" and self.min_speed_mps != 0:
            raise ConfigError("robot.min_speed_mps: a holonomic robot has no reverse speed "
                              f"(a velocity vector); got {self.min_speed_mps!r}")

    @classmethod
    def diff_drive(cls, **kw: Any) -> RobotModel:
        """A diff-drive robot; the limits not given take :data:`DIFF_DRIVE_DEFAULTS`."""
        return cls(kind="diff-drive", **{**DIFF_DRIVE_DEFAULTS, **kw})

    @property
    def is_diff_drive(self) -> bool:
        return self.kind == "diff-drive"

    def replace(self, **changes: Any) -> RobotModel:
        """A copy with some fields changed (checked again)."""
        return dataclasses.replace(self, **changes)
