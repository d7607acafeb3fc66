"""The robot of an IR-SIM environment as pathfuse models it (:mod:`pathfuse.integrations.irsim`):
its :class:`~pathfuse.robot.RobotModel` from IR-SIM's limits, and the margin that covers
IR-SIM's forward-Euler step against pathfuse's exact arcs."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pathfuse.result import ConfigError
from pathfuse.robot import FIELDS, RobotModel

__all__ = ["robot_model", "euler_margin_m", "KINEMATICS", "DEFAULT_SENSING_RADIUS_M"]

DEFAULT_SENSING_RADIUS_M = 5.0
"""Moving objects whose surface comes this close to the robot's centre are sensed (m)."""

KINEMATICS = ("diff", "omni")
"""The IR-SIM robot kinematics the adapter drives."""


def _col(v: Any) -> np.ndarray:
    return np.asarray(v, dtype=np.float64).reshape(-1)


def robot_model(obj: Any, sensing_radius_m: float = DEFAULT_SENSING_RADIUS_M,
                **overrides: Any) -> RobotModel:
    """The :class:`~pathfuse.robot.RobotModel` of an IR-SIM robot object (see the module
    docstring); ``overrides`` replace fields of the model (``clearance_m``, ``shield``, ...).

    Raises
    ------
    ConfigError
        Kinematics other than diff or omni, or an override that is not a field of the
        model or has a bad value (the message names it).
    """
    kin = obj.kinematics
    if kin not in KINEMATICS:
        raise ConfigError(f"robot {obj.name!r}: kinematics {kin!r} is not supported "
                          f"(the adapter drives {', '.join(KINEMATICS)})")
    vmax, vmin, acce = _col(obj.vel_max), _col(obj.vel_min), _col(obj.info.acce)
    heading = float(obj.state[2, 0]) if obj.state.shape[0] > 2 else 0.0
    kw: dict[str, Any] = {"radius_m": float(obj.radius), "sensing_radius_m": sensing_radius_m,
                          "heading_rad": heading}
    if kin == "diff":
        kw.update(max_speed_mps=float(vmax[0]), min_speed_mps=min(0.0, float(vmin[0])),
                  max_accel_mps2=float(acce[0]),
                  max_yaw_rate_radps=min(float(vmax[1]), -float(vmin[1])),
                  max_yaw_accel_radps2=float(acce[1]))
        base: Any = RobotModel.diff_drive
    else:
        kw.update(max_speed_mps=float(min(vmax[0], vmax[1], -vmin[0], -vmin[1])),
                  max_accel_mps2=float(min(acce[0], acce[1])))
        base = RobotModel
    for k in overrides:
        if k not in FIELDS:
            raise ConfigError(f"robot_overrides.{k}: not a field of pathfuse.RobotModel "
                              f"({', '.join(sorted(set(FIELDS) - {'kind'}))})")
    return base(**{**kw, **overrides})


def euler_margin_m(robot: RobotModel, dt: float) -> float:
    """How far IR-SIM's diff-drive step can leave pathfuse's prediction over one stop, m.

    IR-SIM moves a diff robot by a forward-Euler step (``v dt`` along its heading, then
    the heading turns by ``omega dt``); pathfuse's shield and controllers predict the exact
    arc.  The headings agree after every tick; the positions differ by the gap between the
    chord of the arc and the Euler step.  This sums that gap over the worst case the
    shield relies on: the command's tick at full speed and full turn rate, then the stop
    (speed and turn rate falling at their acceleration limits to zero).  The adapter plans
    with the robot's radius grown by it, so a stop the shield found clear stays clear in
    IR-SIM (ours).

    Examples
    --------
    >>> rb = RobotModel.diff_drive(radius_m=0.25, max_speed_mps=1.0, max_accel_mps2=2.0,
    ...                            max_yaw_rate_radps=2.0, max_yaw_accel_radps2=4.0)
    >>> round(euler_margin_m(rb, 0.1), 4)
    0.022
    """
    if not robot.is_diff_drive or dt <= 0.0:
        return 0.0
    v = max(abs(robot.max_speed_mps), abs(robot.min_speed_mps))
    w = robot.max_yaw_rate_radps
    a, alpha = robot.max_accel_mps2, robot.max_yaw_accel_radps2
    if not (math.isfinite(v) and math.isfinite(w)):
        return 0.0
    total = 0.0
    for _ in range(100_000):
        h = w * dt
        if abs(h) > 1e-12:
            dx, dy = v / w * math.sin(h), v / w * (1.0 - math.cos(h))
            total += math.hypot(v * dt - dx, dy)
        if v <= 0.0 or not (math.isfinite(a) and a > 0.0):
            break
        v = max(0.0, v - a * dt)
        w = max(0.0, w - alpha * dt) if math.isfinite(alpha) else 0.0
    return total
