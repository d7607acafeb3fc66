"""Dynamic scenarios: YAML files (or dicts) describing a map, a robot, moving discs and a planner.

A complete, documented file (``examples/scenarios/crossing.yaml`` holds it)::

    name: crossing                 # optional (default: the file's stem)
    description: three discs cross the paper map   # optional
    map: {random: {size: [15, 15], resolution: 1.0, obstacles: 50, seed: 7}}
        # or {paper: {seed: 3}}, {movingai: FILE.map}, {ros: FILE.yaml},
        # {image: FILE.png, resolution: 0.05}, {rows: ["....", ".##."], resolution: 1.0}
        # (file paths are relative to the scenario file)
    start: [1, 1]                  # metres
    goal: [11, 11]
    robot:                         # optional, the defaults shown
      radius: 0.2                  # m; the robot is a disc
      max_speed: 1.0               # m/s; every commanded velocity is clipped to it
      sensing_radius: 3.0          # m; discs reaching inside it are observed
    dt: 0.1                        # s per tick
    time_limit: 60                 # s; the episode is truncated (TIMEOUT) after it
    goal_tolerance: 0.25           # m; reached when the robot centre comes this close
    stall_time: 10                 # s; LOCAL_MINIMUM when the robot stays within
    stall_radius: 0.25             #    stall_radius m for stall_time s (0 disables)
    seed: null                     # optional episode seed (random walks); an int or null
    perturb:                       # optional (ours): with a seed, jitter every disc
      position_m: 0.3              #   start (patrol: waypoints) moved by up to 0.3 m
      speed_frac: 0.2              #   speed scaled by a factor in [0.8, 1.2]
      heading_deg: 10              #   a linear disc's direction turned by up to 10 deg
    obstacles:                     # moving discs (default: none)
      - {position: [6, 2], velocity: [0, 0.5], radius: 0.3}               # constant velocity,
                                                                          # bounces
      - {waypoints: [[3, 8], [9, 8]], speed: 0.6, radius: 0.4, loop: true}  # patrol
      - {random_walk: {position: [5, 5], speed: 0.4, seed: 1, turn_std: 1.0}, radius: 0.3}
    planner: {name: fusion, params: {}}   # or just: planner: fusion

Every key is checked: a malformed value or an unknown key raises
:class:`ScenarioError` with one line naming the file and the key, e.g.
``obstacles[1].speed: must be a number > 0, got 'fast'``; a file that is not
valid YAML (or repeats a key) raises :class:`~pathfuse.result.MapFormatError`
naming the line.  The scene is checked too: start, goal and every disc must
lie in the map and clear of occupied cells (the robot and each disc taken as
discs), no disc may overlap the robot at ``t = 0``, and a patrol's legs
must be free for its disc.

Examples
--------
>>> sc = load_scenario({"map": {"rows": ["......", "......", "......"]},
...                     "start": [0.5, 1.5], "goal": [5.5, 1.5],
...                     "obstacles": [{"position": [3, 0.5], "velocity": [0, 0.4]}]})
>>> sc.robot.max_speed_mps, sc.n_steps, sc.obstacles[0].kind
(1.0, 600, 'linear')
>>> load_scenario({"map": {"rows": ["..."]}, "start": [0.5, 0.5], "goal": [2.5, 0.5],
...                "dt": "fast"})
Traceback (most recent call last):
...
pathfuse.world.scenario.ScenarioError: dt: must be a number > 0, got 'fast'
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from pathfuse import validate
from pathfuse.costmap import costmap_for, point_distance, segment_distance
from pathfuse.grid import GridMap
from pathfuse.limits import MAX_SEED, LimitError, env_name, limit
from pathfuse.result import ConfigError, MapFormatError, PathfuseError
from pathfuse.robot import RobotModel
from pathfuse.validate import short as _shown
from pathfuse.world.obstacles import (
    LinearObstacle,
    ObstacleSpec,
    PatrolObstacle,
    RandomWalkObstacle,
)
from pathfuse.world.perturb import Perturbation, parse_perturb, perturb_obstacles

__all__ = [
    "Scenario",
    "PlannerChoice",
    "ScenarioError",
    "load_scenario",
    "save_scenario",
    "scenario_from_dict",
    "resolve_planner_choice",
    "SCENARIO_KEYS",
]


class ScenarioError(ConfigError):
    """A scenario key is missing, unknown or malformed; the message names it."""


SCENARIO_KEYS = ("name", "description", "map", "start", "goal", "robot", "dt", "time_limit",
                 "goal_tolerance", "stall_time", "stall_radius", "seed", "perturb", "obstacles",
                 "planner")
"""The keys a scenario file may have."""
_REQUIRED = ("map", "start", "goal")
_LINEAR_KEYS = ("position", "velocity", "radius")
_PATROL_KEYS = ("waypoints", "speed", "radius", "loop")
_RW_OUTER_KEYS = ("random_walk", "radius")
_RW_KEYS = ("position", "speed", "seed", "turn_std", "heading")
_PLANNER_KEYS = ("name", "params")


# ---------------------------------------------------------------------- specs
@dataclass(frozen=True)
class PlannerChoice:
    """An online planner's registry name and its parameter overrides."""

    name: str = "fusion"
    params: Mapping[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "params": dict(self.params)}


@dataclass(frozen=True, eq=False)
class Scenario:
    """A validated dynamic scenario (build it with :func:`load_scenario`).

    Attributes
    ----------
    grid : GridMap
        The static map.
    start, goal : (float, float)
        Robot start and goal in metres.
    robot : RobotModel
        The robot (:class:`pathfuse.robot.RobotModel`); its
        :attr:`~pathfuse.robot.RobotModel.explicit` fields are the ``robot:`` keys the
        scenario sets, and the only ones :meth:`to_dict` writes.
    dt : float
        Tick length in seconds.
    time_limit : float
        Episode length limit in seconds.
    goal_tolerance : float
        Goal reached when the robot centre passes within this many metres.
    obstacles : tuple
        :class:`~pathfuse.world.obstacles.LinearObstacle`,
        :class:`~pathfuse.world.obstacles.PatrolObstacle` and
        :class:`~pathfuse.world.obstacles.RandomWalkObstacle` specs.
    planner : PlannerChoice
        The online planner to run (overridable in :func:`~pathfuse.simulate`).
    seed : int or None
        Default episode seed (mixed into the random walks' seeds).
    perturb : Perturbation or None
        Seeded jitter of the discs (:mod:`pathfuse.world.perturb`; ours).
    stall_time, stall_radius : float
        Stall detection of the episode runner (``stall_time = 0`` disables).
    name, description : str
        Labels.
    map_spec : dict or None
        The ``map`` section as written (kept for :meth:`to_dict`).
    source : str or None
        The file the scenario was read from.
    """

    grid: GridMap
    start: tuple[float, float]
    goal: tuple[float, float]
    robot: RobotModel = field(default_factory=RobotModel)
    dt: float = 0.1
    time_limit: float = 60.0
    goal_tolerance: float = 0.25
    obstacles: tuple[ObstacleSpec, ...] = ()
    planner: PlannerChoice = field(default_factory=PlannerChoice)
    seed: int | None = None
    perturb: Perturbation | None = None
    stall_time: float = 10.0
    stall_radius: float = 0.25
    name: str = "scenario"
    description: str = ""
    map_spec: Any = None
    source: str | None = None

    def __post_init__(self) -> None:
        _check_scene(self)

    @property
    def n_steps(self) -> int:
        """Number of ticks that fit in ``time_limit``: ``ceil(time_limit / dt)``."""
        return max(1, int(math.ceil(self.time_limit / self.dt - 1e-9)))

    def obstacles_for(self, seed: int | None) -> tuple[ObstacleSpec, ...]:
        """The discs of the episode with ``seed``: as written without a seed or a
        ``perturb`` section, else jittered (:func:`~pathfuse.world.perturb.perturb_obstacles`;
        examples in ``tests/test_perturb.py``)."""
        if seed is None or self.perturb is None or not self.perturb.active:
            return self.obstacles

        def valid(i: int, ob: ObstacleSpec) -> bool:
            try:
                _check_disc(self, i, ob)
            except ScenarioError:
                return False
            return True

        return perturb_obstacles(self.obstacles, self.perturb, int(seed), valid)

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (re-validated)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """A YAML/JSON-ready dict that :func:`load_scenario` reads back to an equal scenario.

        >>> sc = load_scenario({"map": {"rows": ["...."]}, "start": [0.5, 0.5],
        ...                     "goal": [3.5, 0.5]})
        >>> load_scenario(sc.to_dict()).to_dict() == sc.to_dict()
        True
        """
        if isinstance(self.map_spec, Mapping):
            mspec: Any = _plain(self.map_spec)
            if self.source is not None:
                mspec = _absolute_paths(mspec, Path(self.source).parent)
        elif isinstance(self.map_spec, str):
            mspec = self.map_spec
        else:
            g = self.grid
            rows = ["".join("#" if v else "." for v in row) for row in g.occupied[::-1]]
            mspec = {"rows": rows, "resolution": g.resolution, "origin": list(g.origin)}
        d: dict[str, Any] = {
            "name": self.name,
            "description": self.description,
            "map": mspec,
            "start": list(self.start),
            "goal": list(self.goal),
            "robot": self.robot.to_dict(),
            "dt": self.dt,
            "time_limit": self.time_limit,
            "goal_tolerance": self.goal_tolerance,
            "stall_time": self.stall_time,
            "stall_radius": self.stall_radius,
            "seed": self.seed,
            "obstacles": [ob.to_dict() for ob in self.obstacles],
            "planner": self.planner.to_dict(),
        }
        if self.perturb is not None:
            d["perturb"] = self.perturb.to_dict()
        return d


def _plain(x: Any) -> Any:
    if isinstance(x, Mapping):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


_FILE_KEYS = ("movingai", "ros", "image", "npy")


def _absolute_paths(spec: dict, base: Path) -> dict:
    out = dict(spec)
    for k in _FILE_KEYS:
        if k in out and isinstance(out[k], str) and not Path(out[k]).is_absolute():
            out[k] = str((base / out[k]).resolve())
    return out


# ---------------------------------------------------------------------- scene checks
def _disc_clear(grid: GridMap, p: tuple[float, float], r: float) -> bool:
    """A disc of radius ``r`` at ``p`` keeps clear of the occupied squares and the map's
    outside (asked of the map's :class:`~pathfuse.costmap.Costmap`)."""
    return point_distance(costmap_for(grid, 0.0, lattice=False), p[0], p[1],
                          max(r, 1e-12)) >= r


def _check_point(grid: GridMap, p: tuple[float, float], r: float, key: str, what: str) -> None:
    x0, y0, x1, y1 = grid.bounds
    if not (x0 <= p[0] < x1 and y0 <= p[1] < y1):
        raise ScenarioError(
            f"{key}: ({p[0]:g}, {p[1]:g}) lies outside the map [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}]"
        )
    if not _disc_clear(grid, p, r):
        raise ScenarioError(
            f"{key}: {what} (radius {r:g} m) at ({p[0]:g}, {p[1]:g}) overlaps an occupied "
            f"cell or the map's edge"
        )


def _check_scene(sc: Scenario) -> None:
    if not isinstance(sc.grid, GridMap):
        raise ScenarioError(f"map: must be a GridMap, got {type(sc.grid).__name__}")
    # numbers (the parser checks them too; this guards Scenario(...) and replace())
    _num(sc.dt, "dt", gt=0)
    _num(sc.time_limit, "time_limit", gt=0)
    _num(sc.goal_tolerance, "goal_tolerance", gt=0)
    _num(sc.stall_time, "stall_time", ge=0)
    _num(sc.stall_radius, "stall_radius", gt=0)
    # the world keeps every disc's trajectory for the whole episode: bound ticks x bodies
    ticks = sc.time_limit / sc.dt
    steps = ticks * (1 + len(sc.obstacles))
    cap = limit("MAX_TICKS")
    if not steps <= cap:
        raise LimitError(
            f"time_limit / dt: {sc.time_limit:g} s / {sc.dt:g} s = {ticks:.3g} ticks for "
            f"the robot and {len(sc.obstacles)} moving discs ({steps:.3g} body-ticks) is above "
            f"the limit of {cap} (MAX_TICKS; set the environment variable "
            f"{env_name('MAX_TICKS')} to raise it)")
    if not isinstance(sc.robot, RobotModel):  # checked when it was built
        raise ScenarioError(f"robot: must be a pathfuse.RobotModel, got "
                            f"{type(sc.robot).__name__}")
    r = sc.robot.radius_m
    _check_point(sc.grid, sc.start, r, "start", "the robot")
    _check_point(sc.grid, sc.goal, r, "goal", "the robot")
    for i, ob in enumerate(sc.obstacles):
        _check_disc(sc, i, ob)
    if sc.perturb is not None:
        p = sc.perturb
        if not isinstance(p, Perturbation):
            raise ScenarioError(f"perturb: must be a Perturbation, got {type(p).__name__}")
        parse_perturb(p.to_dict(), ScenarioError)


def _check_disc(sc: Scenario, i: int, ob: ObstacleSpec) -> None:
    """Disc ``i`` lies in the map, clear of occupied cells and of the robot's start (a
    patrol: every waypoint and leg)."""
    key = f"obstacles[{i}]"
    if isinstance(ob, PatrolObstacle):
        for j, w in enumerate(ob.waypoints):
            _check_point(sc.grid, w, ob.radius, f"{key}.waypoints[{j}]", "the disc")
        poly = ob.polyline()
        cm = costmap_for(sc.grid, 0.0, lattice=False)
        for j in range(len(poly) - 1):
            a, b = poly[j], poly[j + 1]
            if segment_distance(cm, a[0], a[1], b[0], b[1], ob.radius) < ob.radius:
                jn = (j + 1) % len(ob.waypoints)
                raise ScenarioError(
                    f"{key}.waypoints: the leg from waypoint {j} to waypoint {jn} is "
                    f"blocked for a disc of radius {ob.radius:g} m"
                )
    else:
        pkey = f"{key}.random_walk.position" if isinstance(ob, RandomWalkObstacle) \
            else f"{key}.position"
        _check_point(sc.grid, ob.position, ob.radius, pkey, "the disc")
    gap = math.hypot(ob.position[0] - sc.start[0], ob.position[1] - sc.start[1]) \
        - ob.radius - sc.robot.radius_m
    if gap < 0:
        raise ScenarioError(f"{key}: overlaps the robot at the start (by {-gap:.3g} m)")


# ---------------------------------------------------------------------- value parsers
# the checks of pathfuse.validate, raising ScenarioError


def _num(v: Any, key: str, *, gt: float | None = None, ge: float | None = None,
         lt: float | None = None, le: float | None = None) -> float:
    return validate.number(v, key, gt=gt, ge=ge, lt=lt, le=le, error=ScenarioError)


def _int(v: Any, key: str, *, ge: int = 0) -> int:
    out = validate.integer(v, key, ge=ge, error=ScenarioError)
    if out > MAX_SEED:  # seeds are stored as SQLite (64-bit) integers
        raise ScenarioError(f"{key}: must be an integer in [0, 2**63), got {_shown(out)}")
    return out


def _bool(v: Any, key: str) -> bool:
    return validate.flag(v, key, ScenarioError)


def _str(v: Any, key: str) -> str:
    return validate.text(v, key, ScenarioError)


def _point(v: Any, key: str) -> tuple[float, float]:
    return validate.point(v, key, ScenarioError)


def _mapping(v: Any, key: str, allowed: tuple[str, ...], what: str = "a mapping") -> Mapping:
    return validate.mapping(v, key, allowed, what, ScenarioError)


# ---------------------------------------------------------------------- section parsers
def _parse_obstacle(v: Any, index: int) -> ObstacleSpec:
    key = f"obstacles[{index}]"
    if not isinstance(v, Mapping):
        raise ScenarioError(
            f"{key}: must be a mapping with position+velocity, waypoints+speed or random_walk, "
            f"got {_shown(v)}"
        )
    if "random_walk" in v:
        m = _mapping(v, key, _RW_OUTER_KEYS)
        rw = _mapping(m["random_walk"], f"{key}.random_walk", _RW_KEYS)
        if "position" not in rw:
            raise ScenarioError(f"{key}.random_walk.position: missing (the start [x, y])")
        if "speed" not in rw:
            raise ScenarioError(f"{key}.random_walk.speed: missing (m/s)")
        heading = rw.get("heading")
        return RandomWalkObstacle(
            position=_point(rw["position"], f"{key}.random_walk.position"),
            speed=_num(rw["speed"], f"{key}.random_walk.speed", gt=0),
            radius=_num(m.get("radius", 0.3), f"{key}.radius", gt=0),
            seed=_int(rw.get("seed", index), f"{key}.random_walk.seed"),
            turn_std=_num(rw.get("turn_std", 1.0), f"{key}.random_walk.turn_std", ge=0),
            heading=None if heading is None else _num(heading, f"{key}.random_walk.heading"),
        )
    if "waypoints" in v:
        m = _mapping(v, key, _PATROL_KEYS)
        wps = m["waypoints"]
        if not isinstance(wps, (list, tuple)) or len(wps) < 2:
            raise ScenarioError(f"{key}.waypoints: must be a list of at least two [x, y] points, "
                                f"got {_shown(wps)}")
        if "speed" not in m:
            raise ScenarioError(f"{key}.speed: missing (m/s along the waypoints)")
        pts = tuple(_point(p, f"{key}.waypoints[{j}]") for j, p in enumerate(wps))
        return PatrolObstacle(
            waypoints=pts,
            speed=_num(m["speed"], f"{key}.speed", gt=0),
            radius=_num(m.get("radius", 0.3), f"{key}.radius", gt=0),
            loop=_bool(m.get("loop", True), f"{key}.loop"),
        )
    if "position" in v:
        m = _mapping(v, key, _LINEAR_KEYS)
        return LinearObstacle(
            position=_point(m["position"], f"{key}.position"),
            velocity=_point(m.get("velocity", (0.0, 0.0)), f"{key}.velocity"),
            radius=_num(m.get("radius", 0.3), f"{key}.radius", gt=0),
        )
    keys = ", ".join(map(str, v)) or "none"
    raise ScenarioError(
        f"{key}: an obstacle needs 'position' (constant velocity), 'waypoints' (patrol) or "
        f"'random_walk'; it has keys: {keys}"
    )


def _parse_planner(v: Any) -> PlannerChoice:
    from pathfuse.planners.registry import get_planner, make_params

    if v is None:
        v = "fusion"
    if isinstance(v, str):
        v = {"name": v}
    m = _mapping(v, "planner", _PLANNER_KEYS, "a planner name or {name, params}")
    if "name" not in m:
        raise ScenarioError("planner.name: missing (a planner name)")
    name = _str(m["name"], "planner.name")
    params = m.get("params") or {}
    if not isinstance(params, Mapping):
        raise ScenarioError(f"planner.params: must be a mapping, got {validate.short(params)}")
    try:
        spec = get_planner(name)
    except ConfigError as exc:
        raise ScenarioError(f"planner.name: {exc}") from None
    if not spec.online:
        raise ScenarioError(f"planner.name:"
                            f" {_shown(name)} only plans offline (it cannot be simulated)")
    make_params(spec, params, key="planner.params", error=ScenarioError)
    return PlannerChoice(name=spec.name, params=dict(params))


def resolve_planner_choice(choice: Any) -> PlannerChoice:
    """A checked :class:`PlannerChoice` from a name, ``{"name", "params"}`` or a PlannerChoice.

    >>> resolve_planner_choice("astar-follow")
    PlannerChoice(name='astar', params={})
    """
    if isinstance(choice, PlannerChoice):
        return _parse_planner(choice.to_dict())
    return _parse_planner(choice)


def scenario_from_dict(doc: Mapping[str, Any], base_dir: str | os.PathLike[str] = ".",
                       default_name: str = "scenario", source: str | None = None) -> Scenario:
    """Build a :class:`Scenario` from the parsed content of a scenario file.

    ``doc["map"]`` may also be a :class:`~pathfuse.grid.GridMap` instance.
    """
    if not isinstance(doc, Mapping):
        raise ScenarioError(f"a scenario must be a mapping of keys to values, got {_shown(doc)}")
    _mapping(doc, "", SCENARIO_KEYS)
    for k in _REQUIRED:
        if k not in doc:
            raise ScenarioError(f"{k}: missing (required keys: {', '.join(_REQUIRED)})")
    mspec = doc["map"]
    if isinstance(mspec, GridMap):
        grid = mspec
        mspec = None
    else:
        from pathfuse.io import map_from_spec

        if not isinstance(mspec, (Mapping, str)):
            raise ScenarioError(f"map: must be a map spec mapping or a file name, got"
                                f" {_shown(mspec)}")
        try:
            grid = map_from_spec(mspec, base_dir)
        except PathfuseError as exc:
            try:
                err = type(exc)(f"map: {exc}")
            except Exception:  # noqa: BLE001 - an error class with another signature
                err = ScenarioError(f"map: {exc}")
            raise err from None
    obstacles = doc.get("obstacles") or []
    if not isinstance(obstacles, (list, tuple)):
        raise ScenarioError(f"obstacles: must be a list of obstacles, got {_shown(obstacles)}")
    seed = doc.get("seed")
    name = doc.get("name", default_name)
    return Scenario(
        grid=grid,
        start=_point(doc["start"], "start"),
        goal=_point(doc["goal"], "goal"),
        robot=RobotModel.from_dict(doc.get("robot"), ScenarioError),
        dt=_num(doc.get("dt", 0.1), "dt", gt=0),
        time_limit=_num(doc.get("time_limit", 60.0), "time_limit", gt=0),
        goal_tolerance=_num(doc.get("goal_tolerance", 0.25), "goal_tolerance", gt=0),
        stall_time=_num(doc.get("stall_time", 10.0), "stall_time", ge=0),
        stall_radius=_num(doc.get("stall_radius", 0.25), "stall_radius", gt=0),
        seed=None if seed is None else _int(seed, "seed"),
        perturb=parse_perturb(doc.get("perturb"), ScenarioError),
        obstacles=tuple(_parse_obstacle(o, i) for i, o in enumerate(obstacles)),
        planner=_parse_planner(doc.get("planner")),
        name=_str(name, "name"),
        description=_str(doc.get("description", "") or "", "description"),
        map_spec=_plain(mspec) if mspec is not None else None,
        source=source,
    )


# ---------------------------------------------------------------------- files
def _read_yaml(path: Path) -> Any:
    from pathfuse.safeyaml import read_yaml

    return read_yaml(path, "scenario", MapFormatError)


def load_scenario(scenario: str | os.PathLike[str] | Mapping[str, Any] | Scenario,
                  base_dir: str | os.PathLike[str] | None = None) -> Scenario:
    """Read a scenario from a YAML file, a dict with the same content, or pass one through.

    Parameters
    ----------
    scenario : path, mapping or Scenario
        A YAML file, its content as a dict, or an already built
        :class:`Scenario` (returned unchanged).
    base_dir : path, optional
        Folder for relative map paths of a dict (default: the current
        folder); a file's own folder is used for a file.

    Raises
    ------
    ScenarioError
        A missing, unknown or malformed key (a :class:`~pathfuse.ConfigError`);
        the message is one line naming the file and the key.
    MapFormatError
        The file is missing or is not valid YAML (the message names the line).
    """
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, Mapping):
        return scenario_from_dict(scenario, "." if base_dir is None else base_dir,
                                  default_name=str(scenario.get("name", "scenario")))
    if not isinstance(scenario, (str, os.PathLike)):
        raise ScenarioError(
            f"a scenario is a YAML file path or a mapping, got {type(scenario).__name__}")
    path = Path(os.path.expanduser(os.fspath(scenario)))
    doc = _read_yaml(path)
    if not isinstance(doc, Mapping):
        kind = "empty" if doc is None else f"a {type(doc).__name__}"
        raise ScenarioError(f"{path}: a scenario must be a mapping of keys to values, got {kind}")
    try:
        return scenario_from_dict(doc, path.parent if base_dir is None else base_dir,
                                  default_name=path.stem, source=str(path))
    except PathfuseError as exc:
        try:
            err = type(exc)(f"{path}: {exc}")
        except Exception:  # noqa: BLE001
            err = ScenarioError(f"{path}: {exc}")
        raise err from None


def save_scenario(scenario: Scenario, path: str | os.PathLike[str]) -> Path:
    """Write ``scenario`` as YAML (readable by :func:`load_scenario`); returns the path."""
    p = Path(path)
    p.write_text(yaml.safe_dump(scenario.to_dict(), sort_keys=False, default_flow_style=None),
                 encoding="utf-8")
    return p
