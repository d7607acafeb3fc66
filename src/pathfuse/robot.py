"""The robot: a disc with a kinematic model, its limits, its sensing range and a safety margin.

:class:`RobotModel` is pathfuse's one description of a robot (units in the
names).  A scenario's ``robot:`` block is read into one
(:meth:`RobotModel.from_dict`) and written back from it
(:meth:`RobotModel.to_dict`); :func:`pathfuse.simulate` accepts one
(``robot=``), and the world and the controllers read their limits from it.

Set and unset fields
--------------------
Every field left out (or given as None) is *unset*: it takes its default,
which for the acceleration and yaw limits and the inflation depends on the
``kind`` (:data:`DIFF_DRIVE_DEFAULTS` for a diff-drive robot).  The robot
records which fields were set (:attr:`RobotModel.explicit`), so that a
scenario file written back holds the keys it was read with and no others,
and :meth:`RobotModel.replace` with another ``kind`` gives the unset limits
that kind's defaults.

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
>>> jackal.to_dict()
{'radius': 0.3, 'max_speed': 2.0, 'model': 'diff-drive'}
>>> RobotModel.from_dict({"model": "diff-drive", "radius": 0.3, "max_speed": 2.0}) == jackal
True
>>> RobotModel(kind="tank")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: robot.kind: must be one of 'holonomic', 'diff-drive', got 'tank'
>>> RobotModel.from_dict({"radius": -1})
Traceback (most recent call last):
...
pathfuse.result.ConfigError: robot.radius: must be a number >= 0, got -1
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from pathfuse import validate
from pathfuse.result import ConfigError

__all__ = ["RobotModel", "KINDS", "DIFF_DRIVE_DEFAULTS", "ROBOT_KEYS", "FIELDS"]

KINDS = ("holonomic", "diff-drive")
"""The kinematic models."""

DIFF_DRIVE_DEFAULTS = {"max_accel_mps2": 2.0, "max_yaw_rate_radps": 2.0,
                       "max_yaw_accel_radps2": 4.0, "inflation_m": 0.3}
"""The limits a diff-drive robot gets when none is given (a small indoor base), and its
global planner's inflation (ours, after Nav2's inflation layer)."""

_DEFAULTS: dict[str, Any] = {
    "kind": "holonomic", "radius_m": 0.2, "max_speed_mps": 1.0, "sensing_radius_m": 3.0,
    "max_accel_mps2": math.inf, "max_yaw_rate_radps": math.inf,
    "max_yaw_accel_radps2": math.inf, "min_speed_mps": 0.0, "clearance_m": 0.0,
    "inflation_m": 0.0, "heading_rad": None, "shield": True, "recovery": True}

_FIELD_OF_KEY = {"radius": "radius_m", "max_speed": "max_speed_mps",
                 "sensing_radius": "sensing_radius_m", "model": "kind",
                 "max_accel": "max_accel_mps2", "max_yaw_rate": "max_yaw_rate_radps",
                 "max_yaw_accel": "max_yaw_accel_radps2", "min_speed": "min_speed_mps",
                 "clearance": "clearance_m", "inflation": "inflation_m",
                 "heading": "heading_rad", "shield": "shield", "recovery": "recovery"}
_KEY_OF_FIELD = {f: k for k, f in _FIELD_OF_KEY.items()}

ROBOT_KEYS = tuple(_FIELD_OF_KEY)
"""The keys of a scenario's ``robot:`` block (metres, seconds, radians), in the order
:meth:`RobotModel.to_dict` writes them."""

FIELDS = tuple(_DEFAULTS)
"""The fields of :class:`RobotModel` that describe the robot (all but ``explicit``)."""

_LIMITS = ("max_accel_mps2", "max_yaw_rate_radps", "max_yaw_accel_radps2")
_BOUNDS: dict[str, dict[str, float]] = {
    "radius_m": {"ge": 0}, "max_speed_mps": {"gt": 0}, "sensing_radius_m": {"gt": 0},
    "min_speed_mps": {"le": 0}, "clearance_m": {"ge": 0}, "inflation_m": {"ge": 0},
    "heading_rad": {}}


def _limit(v: Any, key: str, error: type[ConfigError]) -> float:
    if isinstance(v, (int, float)) and not isinstance(v, bool) and v == math.inf:
        return math.inf
    try:
        return validate.number(v, key, gt=0, error=error)
    except ConfigError:
        raise error(f"{key}: must be a number > 0 (inf: no limit), "
                    f"got {validate.short(v)}") from None


def _checked(name: str, v: Any, key: str, error: type[ConfigError]) -> Any:
    """The value of field ``name`` (given as ``v``, named ``key`` in messages), checked."""
    if name == "kind":
        return validate.choice(v, key, KINDS, error)
    if name in _LIMITS:
        return _limit(v, key, error)
    if name in ("shield", "recovery"):
        return validate.flag(v, key, error)
    return validate.number(v, key, **_BOUNDS[name], error=error)


@dataclass(frozen=True, init=False)
class RobotModel:
    """A disc robot with a kinematic model (see the module docstring).

    Every parameter is keyword-only; one left out (or None) is *unset*: it takes its
    default (for ``max_accel_mps2``, ``max_yaw_rate_radps``, ``max_yaw_accel_radps2`` and
    ``inflation_m``, the default of the ``kind``), and :meth:`to_dict` leaves it out.

    Parameters
    ----------
    kind : {"holonomic", "diff-drive"}
        The kinematic model (default holonomic).
    radius_m : float
        Disc radius (>= 0; default 0.2).
    max_speed_mps : float
        Speed limit (> 0; default 1).
    sensing_radius_m : float
        Moving discs whose surface comes this close to the centre are observed
        (> 0; default 3).
    max_accel_mps2 : float
        Linear acceleration limit (> 0; ``inf``: none).  Holonomic: on the
        velocity vector (default none); diff-drive: on ``v`` (default 2).
    max_yaw_rate_radps, max_yaw_accel_radps2 : float
        Diff-drive only: yaw-rate limit and its acceleration limit (> 0; default
        2 and 4; a holonomic robot: none).
    min_speed_mps : float
        Diff-drive only: the lowest ``v`` (<= 0, default 0; negative allows reversing).
    clearance_m : float
        The soft safety margin beyond the radius (>= 0; 0 = off, the default).
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

    Attributes
    ----------
    explicit : tuple of str
        The fields that were set (in :data:`FIELDS` order); the others hold their
        defaults.  Part of equality: two robots are equal when they drive alike
        *and* were set alike.

    Raises
    ------
    ConfigError
        A bad value, named ``robot.FIELD`` (``robot.KEY`` for :meth:`from_dict`):
        ``robot.radius_m: must be a number >= 0, got -1``.

    Examples
    --------
    >>> rb = RobotModel(kind="diff-drive", radius_m=0.3)
    >>> rb.max_accel_mps2, rb.inflation_m, rb.explicit
    (2.0, 0.3, ('kind', 'radius_m'))
    >>> rb.replace(kind="holonomic").max_accel_mps2     # unset: the new kind's default
    inf
    >>> RobotModel(max_speed_mps=0)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: robot.max_speed_mps: must be a number > 0, got 0
    """

    kind: str
    radius_m: float
    max_speed_mps: float
    sensing_radius_m: float
    max_accel_mps2: float
    max_yaw_rate_radps: float
    max_yaw_accel_radps2: float
    min_speed_mps: float
    clearance_m: float
    inflation_m: float
    heading_rad: float | None
    shield: bool
    recovery: bool
    explicit: tuple[str, ...] = field(init=False)

    def __init__(self, *, kind: str | None = None, radius_m: float | None = None,
                 max_speed_mps: float | None = None, sensing_radius_m: float | None = None,
                 max_accel_mps2: float | None = None, max_yaw_rate_radps: float | None = None,
                 max_yaw_accel_radps2: float | None = None,
                 min_speed_mps: float | None = None, clearance_m: float | None = None,
                 inflation_m: float | None = None, heading_rad: float | None = None,
                 shield: bool | None = None, recovery: bool | None = None) -> None:
        given = {"kind": kind, "radius_m": radius_m, "max_speed_mps": max_speed_mps,
                 "sensing_radius_m": sensing_radius_m, "max_accel_mps2": max_accel_mps2,
                 "max_yaw_rate_radps": max_yaw_rate_radps,
                 "max_yaw_accel_radps2": max_yaw_accel_radps2,
                 "min_speed_mps": min_speed_mps, "clearance_m": clearance_m,
                 "inflation_m": inflation_m, "heading_rad": heading_rad, "shield": shield,
                 "recovery": recovery}
        self._fill(given, lambda name: f"robot.{name}", ConfigError)

    def _fill(self, given: Mapping[str, Any], key_of: Callable[[str], str],
              error: type[ConfigError]) -> None:
        """Check the set fields of ``given`` (None: unset) in :data:`ROBOT_KEYS` order,
        naming each ``key_of(field)``, and fill in the defaults of the others."""
        values = {}
        for k in ROBOT_KEYS:
            name = _FIELD_OF_KEY[k]
            v = given.get(name)
            if v is not None:
                values[name] = _checked(name, v, key_of(name), error)
        kind = values.get("kind", _DEFAULTS["kind"])
        if kind == "holonomic" and values.get("min_speed_mps", 0.0) != 0:
            shown = validate.short(given["min_speed_mps"])
            raise error(f"{key_of('min_speed_mps')}: must be 0 for a holonomic robot (only "
                        f"a diff-drive robot reverses), got {shown}")
        defaults = {**_DEFAULTS, **DIFF_DRIVE_DEFAULTS} if kind == "diff-drive" else _DEFAULTS
        for name in FIELDS:
            object.__setattr__(self, name, values.get(name, defaults[name]))
        object.__setattr__(self, "explicit", tuple(n for n in FIELDS if n in values))

    @classmethod
    def diff_drive(cls, **kw: Any) -> RobotModel:
        """A diff-drive robot (``kind="diff-drive"``): the limits not given take
        :data:`DIFF_DRIVE_DEFAULTS`."""
        return cls(kind="diff-drive", **kw)

    @classmethod
    def from_dict(cls, block: Mapping[str, Any] | None, error: type[ConfigError] = ConfigError,
                  key: str = "robot") -> RobotModel:
        """The robot of a scenario's ``robot:`` block (keys :data:`ROBOT_KEYS`; None: the
        defaults); a key left out or null is unset.  ``error`` is raised naming
        ``KEY.KEY_OF_THE_BLOCK`` and the value.

        >>> RobotModel.from_dict({"model": "diff-drive", "max_accel": None}).explicit
        ('kind',)
        """
        m = {} if block is None else validate.mapping(block, key, ROBOT_KEYS, "a mapping", error)
        rb = cls.__new__(cls)
        rb._fill({_FIELD_OF_KEY[k]: v for k, v in m.items()},
                 lambda name: f"{key}.{_KEY_OF_FIELD[name]}", error)
        return rb

    def to_dict(self) -> dict[str, Any]:
        """The ``robot:`` block of this robot: the keys that were set, and no others
        (:meth:`from_dict` reads it back to an equal robot)."""
        return {k: getattr(self, f) for k, f in _FIELD_OF_KEY.items() if f in self.explicit}

    @property
    def is_diff_drive(self) -> bool:
        return self.kind == "diff-drive"

    def replace(self, **changes: Any) -> RobotModel:
        """A copy with some fields changed (checked again); a field changed to None is
        unset, and the unset ones take the defaults of the (new) kind."""
        for k in changes:
            if k not in FIELDS:
                raise ConfigError(f"robot.{k}: not a field of pathfuse.RobotModel "
                                  f"({', '.join(FIELDS)})")
        return type(self)(**{**{n: getattr(self, n) for n in self.explicit}, **changes})
