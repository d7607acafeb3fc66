"""The ``robot:`` block of a scenario: :class:`RobotSpec` and its parser.

>>> parse_robot({"model": "diff-drive", "radius": 0.3}).to_model().max_yaw_rate_radps
2.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pathfuse import validate
from pathfuse.result import ConfigError
from pathfuse.robot import KINDS, RobotModel

__all__ = ["RobotSpec", "parse_robot", "ROBOT_KEYS"]

ROBOT_KEYS = ("radius", "max_speed", "sensing_radius", "model", "max_accel", "max_yaw_rate",
              "max_yaw_accel", "min_speed", "clearance", "inflation", "heading", "shield",
              "recovery")
"""The keys of a ``robot:`` block."""


@dataclass(frozen=True)
class RobotSpec:
    """The robot of a scenario file's ``robot:`` block: a disc with a kinematic model.

    The keys are those of the file (metres, seconds, radians);
    :meth:`to_model` gives the :class:`~pathfuse.robot.RobotModel` the world
    and the controllers use.

    Attributes
    ----------
    radius : float
        Disc radius in metres (>= 0).
    max_speed : float
        Speed limit in m/s (> 0); commanded velocities are clipped to it.
    sensing_radius : float
        Moving discs whose surface comes within this many metres of the
        robot's centre appear in the observation (> 0).
    model : {"holonomic", "diff-drive"}
        The kinematic model (:mod:`pathfuse.robot`); holonomic by default.
    max_accel : float or None
        Linear acceleration limit (m/s^2); None: none for a holonomic robot,
        2 m/s^2 for a diff-drive one.
    max_yaw_rate, max_yaw_accel : float or None
        Diff-drive: yaw-rate limit (rad/s, default 2) and its acceleration
        limit (rad/s^2, default 4).
    min_speed : float
        Diff-drive: the lowest linear speed (m/s, <= 0; negative allows
        reversing).
    clearance : float or None
        Soft safety margin beyond the radius (m; ours; 0 = off); None: the
        model's default (0).
    inflation : float or None
        The global planner's inflation beyond the radius (m; ours; 0 = off);
        None: the model's default (0.3 for a diff-drive robot, 0 for a
        holonomic one).
    heading : float or None
        Initial heading (rad; None: facing the goal).
    shield : bool
        Pass every command through the safety shield (ours; default true;
        :mod:`pathfuse.shield`).
    recovery : bool
        Run recovery behaviours when the robot stalls or oscillates (ours;
        default true; :mod:`pathfuse.planners.recovery`).
    """

    radius: float = 0.2
    max_speed: float = 1.0
    sensing_radius: float = 3.0
    model: str = "holonomic"
    max_accel: float | None = None
    max_yaw_rate: float | None = None
    max_yaw_accel: float | None = None
    min_speed: float = 0.0
    clearance: float | None = None
    inflation: float | None = None
    heading: float | None = None
    shield: bool = True
    recovery: bool = True

    def to_model(self) -> RobotModel:
        """The :class:`~pathfuse.robot.RobotModel` of this block (defaults filled in)."""
        kw: dict[str, Any] = {"radius_m": self.radius, "max_speed_mps": self.max_speed,
                              "sensing_radius_m": self.sensing_radius,
                              "min_speed_mps": self.min_speed,
                              "heading_rad": self.heading, "shield": self.shield,
                              "recovery": self.recovery}
        if self.clearance is not None:
            kw["clearance_m"] = self.clearance
        if self.inflation is not None:
            kw["inflation_m"] = self.inflation
        for key, attr in (("max_accel_mps2", "max_accel"),
                          ("max_yaw_rate_radps", "max_yaw_rate"),
                          ("max_yaw_accel_radps2", "max_yaw_accel")):
            v = getattr(self, attr)
            if v is not None:
                kw[key] = v
        if self.model == "diff-drive":
            return RobotModel.diff_drive(**kw)
        return RobotModel(kind=self.model, **kw)

    @classmethod
    def from_model(cls, m: RobotModel) -> RobotSpec:
        """The ``robot:`` block of a :class:`~pathfuse.robot.RobotModel`."""
        def lim(v: float) -> float | None:
            return None if math.isinf(v) else float(v)

        return cls(radius=m.radius_m, max_speed=m.max_speed_mps,
                   sensing_radius=m.sensing_radius_m, model=m.kind,
                   max_accel=lim(m.max_accel_mps2), max_yaw_rate=lim(m.max_yaw_rate_radps),
                   max_yaw_accel=lim(m.max_yaw_accel_radps2), min_speed=m.min_speed_mps,
                   clearance=m.clearance_m, inflation=m.inflation_m, heading=m.heading_rad,
                   shield=m.shield, recovery=m.recovery)


def parse_robot(v: Any, error: type[ConfigError] = ConfigError) -> RobotSpec:
    """The :class:`RobotSpec` of a ``robot:`` block (None: the defaults); ``error`` is raised
    naming the key."""
    if v is None:
        return RobotSpec()
    m = validate.mapping(v, "robot", ROBOT_KEYS, "a mapping", error)
    d = RobotSpec()

    def opt(key: str, **bounds: float) -> float | None:
        v = m.get(key)
        return None if v is None else validate.number(v, f"robot.{key}", **bounds, error=error)

    def num(key: str, **bounds: float) -> float:
        return validate.number(m.get(key, getattr(d, key)), f"robot.{key}", **bounds,
                               error=error)

    return RobotSpec(
        radius=num("radius", ge=0),
        max_speed=num("max_speed", gt=0),
        sensing_radius=num("sensing_radius", gt=0),
        model=validate.choice(m.get("model", d.model), "robot.model", KINDS, error),
        max_accel=opt("max_accel", gt=0),
        max_yaw_rate=opt("max_yaw_rate", gt=0),
        max_yaw_accel=opt("max_yaw_accel", gt=0),
        min_speed=num("min_speed", le=0),
        clearance=opt("clearance", ge=0),
        inflation=opt("inflation", ge=0),
        heading=opt("heading"),
        shield=validate.flag(m.get("shield", d.shield), "robot.shield", error),
        recovery=validate.flag(m.get("recovery", d.recovery), "robot.recovery", error),
    )
