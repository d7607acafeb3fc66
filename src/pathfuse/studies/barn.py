"""The BARN challenge's protocol on its Gazebo worlds (a preset study: ``pathfuse barn``).

The Benchmark for Autonomous Robot Navigation (Perille, Truong, Xiao and Stone,
SSRR 2020; the ICRA BARN challenge) ships 300 Gazebo worlds of cylinders with a
reference path each.  The challenge's ``run.py`` defines the protocol, followed
here (constants below):

* start (-2, 3) facing +y (yaw 1.57), goal (-2, 13): 10 m ahead, beyond the
  obstacle field's open top; the goal is reached when the robot's centre comes
  within 1 m of it;
* the clock starts when the robot has moved 0.1 m from the start, and a run
  fails on a collision or after 100 s (a robot that gives up or stalls counts
  as a timeout, as it would sit there until the limit);
* the reference path ``path_files/path_N.npy`` holds grid points (i, j) of the
  world's 30 x 30 obstacle grid, mapped to the world as
  ``x = 0.15 i - 4.575, y = 0.15 j + 5.075``; the optimal length is the
  polyline start -> those points -> goal and the optimal time is that length
  at 2 m/s;
* the metric of a run is ``success * optimal_time / clip(time, 2 optimal_time,
  8 optimal_time)`` (at most 0.5).

pathfuse reads each world with :func:`pathfuse.io.gazebo.read_gazebo_world`
(the static cylinders rasterised exactly, bounds :data:`BARN_BOUNDS`) and runs
every planner online with :func:`pathfuse.simulate` through the study engine
(one dynamic map entry per world, no moving disc; the engine's workers, store,
resume and Dask scheduler).  What differs from the challenge, and is said
wherever its numbers are shown: the robot is a disc (radius
:data:`JACKAL_RADIUS_M` by default: the Jackal's 0.508 m x 0.430 m body fits in
it at any heading), the simulation is pathfuse's (exact continuous collision
checks against the occupied cells, no physics, perfect localisation, the map
known in advance) rather than Gazebo with a laser scan, and the robot is
holonomic unless a robot model says otherwise.

Examples
--------
>>> round(reference_length(np.array([[12, 0], [12, 29]])), 4)   # x = -2.775: off-centre
10.223
>>> barn_metric(True, 3.0, 5.0), barn_metric(True, 30.0, 5.0), barn_metric(False, 3.0, 5.0)
(0.5, 0.16666666666666666, 0.0)
>>> parse_world_selection("0-3,17, 20")
((0, 3), (17, 17), (20, 20))
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.result import ConfigError, Status

__all__ = [
    "BARN_START", "BARN_START_YAW", "BARN_GOAL", "BARN_GOAL_TOLERANCE_M", "BARN_TIME_LIMIT_S",
    "BARN_BOUNDS", "BARN_MOVE_START_M", "REFERENCE_SPEED_M_S", "JACKAL_RADIUS_M",
    "JACKAL_MAX_SPEED_M_S", "DWA_BASELINE", "BarnWorld", "BarnConfig", "BarnRun",
    "path_to_world", "reference_length", "barn_metric", "parse_world_selection",
    "find_worlds", "barn_experiment", "run_barn", "episode_record", "trajectory_with_yaw",
    "load_barn_file", "BARN_FILE_KEYS", "default_robot", "jackal_robot", "pick_figure_world",
]

BARN_START = (-2.0, 3.0)
"""Start of every BARN run, world frame (m)."""
BARN_START_YAW = 1.57
"""The robot starts facing +y (rad), as ``run.py`` places it."""
BARN_GOAL = (-2.0, 13.0)
"""Goal: 10 m along +y from the start."""
BARN_GOAL_TOLERANCE_M = 1.0
"""``run.py`` stops when the robot is within 1 m of the goal."""
BARN_TIME_LIMIT_S = 100.0
"""A run not at the goal after 100 s is a timeout."""
BARN_MOVE_START_M = 0.1
"""The clock starts when the robot has moved this far from the start."""
REFERENCE_SPEED_M_S = 2.0
"""optimal_time = reference path length / 2 m/s."""
BARN_BOUNDS = (-5.6, -1.0, 1.1, 14.0)
"""The grid's extent (m): the arena (cylinders at x -4.5..0, y 0..9.6) and the goal, 1 m
around."""
JACKAL_RADIUS_M = 0.333
"""A disc that holds the Clearpath Jackal's 0.508 m x 0.430 m body at any heading."""
JACKAL_MAX_SPEED_M_S = 2.0
"""The Jackal's top speed, the challenge's reference speed."""
_PATH_SCALE = 0.15
_PATH_X0 = -4.575  # -0.075 - 30 * 0.15
_PATH_Y0 = 5.075

DWA_BASELINE: dict[str, Any] = {
    "planner": "DWA (published)",
    "success": 0.880, "collision": 0.048, "timeout": 0.072, "metric": 0.1693,
    "time_s": 33.47,
    "note": "the challenge's published baseline: move_base DWA on a Jackal in Gazebo, 50 "
            "worlds x 10 runs; a reference line, not a like-for-like comparison",
}
"""The challenge's DWA baseline (ICRA BARN challenge, as in ../shared/data/SOURCES.md)."""


# --------------------------------------------------------------------------- protocol
def path_to_world(ij: Any) -> np.ndarray:
    """Reference-path grid points (M, 2) of ``path_N.npy`` -> world points (M, 2) in metres.

    >>> path_to_world([[0, 0], [29, 29]]).round(3).tolist()
    [[-4.575, 5.075], [-0.225, 9.425]]
    """
    p = np.asarray(ij, dtype=np.float64).reshape(-1, 2)
    return np.stack([_PATH_SCALE * p[:, 0] + _PATH_X0, _PATH_SCALE * p[:, 1] + _PATH_Y0], axis=1)


def reference_length(ij: Any) -> float:
    """The challenge's optimal path length: start -> the path's points -> goal (m)."""
    pts = np.vstack([np.asarray(BARN_START), path_to_world(ij), np.asarray(BARN_GOAL)])
    return float(np.hypot(*np.diff(pts, axis=0).T).sum())


def barn_metric(success: bool, time_s: float, optimal_time_s: float) -> float:
    """``success * optimal_time / clip(time, 2 optimal_time, 8 optimal_time)``."""
    if not success:
        return 0.0
    return float(optimal_time_s / min(max(time_s, 2.0 * optimal_time_s), 8.0 * optimal_time_s))


def parse_world_selection(text: str | Sequence[int] | None
                          ) -> tuple[tuple[int, int], ...] | None:
    """``"0-9,17,100-120"`` -> sorted, merged inclusive ranges ``((first, last), ...)``;
    a single index ``i`` is ``(i, i)``.  None selects every world.

    :func:`find_worlds` requires each single index to exist and takes the worlds
    that exist inside a range (the shipped set has holes).
    """
    if text is None:
        return None
    out: list[tuple[int, int]] = []
    if isinstance(text, tuple) and text and all(
            isinstance(r, tuple) and len(r) == 2 for r in text):  # already parsed
        for a, b in text:
            if not all(isinstance(v, int) and not isinstance(v, bool) for v in (a, b)) \
                    or not 0 <= a <= b:
                raise ConfigError(f"worlds: must be ranges (first, last), got {text!r}")
        return tuple(sorted(set(text)))
    if not isinstance(text, str):
        vals = list(text)
        if not vals or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                               and v >= 0 for v in vals):
            raise ConfigError(f"worlds: must be indices >= 0, got {text!r}")
        out = [(int(v), int(v)) for v in vals]
    else:
        for part in text.split(","):
            part = part.strip()
            m = re.fullmatch(r"(\d+)\s*-\s*(\d+)", part)
            if m:
                a, b = int(m.group(1)), int(m.group(2))
                if a > b:
                    raise ConfigError(f"worlds: range {part!r} runs backwards")
                out.append((a, b) if a < b else (a, a))
            elif part.isdigit():
                out.append((int(part), int(part)))
            else:
                raise ConfigError(f"worlds: must be indices and ranges such as 0-9,17, got "
                                  f"{text!r}")
    return tuple(sorted(set(out)))


@dataclass(frozen=True)
class BarnWorld:
    """One world of a BARN folder: its index, world file and reference path."""

    index: int
    world: Path
    path_file: Path

    def reference_length_m(self) -> float:
        try:
            ij = np.load(self.path_file, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise ConfigError(f"{self.path_file}: not a readable .npy path file ({exc})") \
                from None
        if ij.ndim != 2 or ij.shape[1] != 2 or ij.shape[0] < 1 or \
                not np.issubdtype(ij.dtype, np.number):
            raise ConfigError(f"{self.path_file}: must be an (M, 2) array of grid points, got "
                              f"shape {ij.shape} of {ij.dtype}")
        return reference_length(ij)


_WORLD_RE = re.compile(r"world_(\d+)\.world(\.gz)?$")


def find_worlds(directory: str | os.PathLike[str],
                selection: Any = None) -> list[BarnWorld]:
    """The worlds of a BARN folder, by index.

    ``directory`` holds ``worlds/world_N.world[.gz]`` and ``path_files/path_N.npy``
    (as shipped), or is the ``worlds`` folder itself with ``path_files`` beside
    it.  ``selection`` (:func:`parse_world_selection`'s ranges, its text, or a list
    of indices) picks worlds: every single index must exist, a range takes the
    worlds inside it.

    Raises
    ------
    ConfigError
        No such folder, no world in it, a selected index without a world, or a
        world without its path file (the messages name them).
    """
    d = Path(os.path.expanduser(os.fspath(directory)))
    if not d.is_dir():
        from pathfuse.datasets import missing_hint
        raise ConfigError(f"{d}: no such folder (expected a BARN folder with worlds/ and "
                          f"path_files/; {missing_hint('barn')})")
    wdir = d / "worlds" if (d / "worlds").is_dir() else d
    pdir = wdir.parent / "path_files" if wdir.name == "worlds" or not (d / "path_files").is_dir() \
        else d / "path_files"
    found: dict[int, Path] = {}
    for f in wdir.iterdir():
        m = _WORLD_RE.fullmatch(f.name)
        if m and f.is_file():
            found.setdefault(int(m.group(1)), f)
    if not found:
        raise ConfigError(f"{wdir}: no BARN world (world_N.world or world_N.world.gz) in it")
    ranges = parse_world_selection(selection)
    if ranges is None:
        chosen = sorted(found)
    else:
        missing = [a for a, b in ranges if a == b and a not in found]
        if missing:
            raise ConfigError(f"worlds: no world file for index {_ranges(missing)} in {wdir} "
                              f"({len(found)} worlds there: {_ranges(sorted(found))})")
        chosen = sorted({i for i in found for a, b in ranges if a <= i <= b})
        empty = [f"{a}-{b}" for a, b in ranges if a < b and not any(a <= i <= b for i in found)]
        if empty:
            raise ConfigError(f"worlds: no world file in {', '.join(empty)} in {wdir} "
                              f"({len(found)} worlds there: {_ranges(sorted(found))})")
    out = []
    for i in chosen:
        pf = pdir / f"path_{i}.npy"
        if not pf.is_file():
            raise ConfigError(f"{pf}: missing (the reference path of world {i}; path_files/ "
                              "must lie beside worlds/)")
        out.append(BarnWorld(i, found[i], pf))
    return out


def _ranges(values: Sequence[int]) -> str:
    """[0, 1, 2, 5] -> '0-2, 5'."""
    parts: list[str] = []
    vals = sorted(values)
    i = 0
    while i < len(vals):
        j = i
        while j + 1 < len(vals) and vals[j + 1] == vals[j] + 1:
            j += 1
        parts.append(str(vals[i]) if i == j else f"{vals[i]}-{vals[j]}")
        i = j + 1
    return ", ".join(parts)


# --------------------------------------------------------------------------- config
def jackal_robot(model: str = "diff-drive") -> dict[str, Any]:
    """The scenario ``robot:`` block of a Jackal-sized disc facing +y: a diff-drive base
    (``model="diff-drive"``, the limits of :data:`pathfuse.robot.DIFF_DRIVE_DEFAULTS`) or
    pathfuse's holonomic point robot (``"holonomic"``)."""
    robot: dict[str, Any] = {"model": model, "radius": JACKAL_RADIUS_M,
                             "max_speed": JACKAL_MAX_SPEED_M_S, "heading": BARN_START_YAW}
    return robot


def default_robot() -> dict[str, Any]:
    """The robot ``pathfuse barn`` runs by default: :func:`jackal_robot` (diff-drive)."""
    return jackal_robot("diff-drive")


@dataclass(frozen=True)
class BarnConfig:
    """What ``pathfuse barn`` runs.

    Attributes
    ----------
    directory : path
        The BARN folder (``worlds/`` and ``path_files/``).
    worlds : str, list of int or None
        World indices and inclusive ranges, e.g. ``"0-49,100"`` (None: every
        world in the folder; see :func:`parse_world_selection`).
    planners : tuple of str
        Online planners (empty: every registered online planner).
    resolution : float
        Grid resolution (m) the worlds are rasterised at.
    robot : mapping
        The scenario's ``robot:`` block (default :func:`default_robot`).
    dt : float
        Simulation tick (s).
    params : mapping
        Per-planner parameter overrides ``{name: {key: value}}``.
    """

    directory: str
    worlds: Any = None
    planners: tuple[str, ...] = ()
    resolution: float = 0.05
    robot: Mapping[str, Any] = field(default_factory=default_robot)
    dt: float = 0.1
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from pathfuse.planners.registry import REGISTRY, get_planner, make_params, planner_names

        object.__setattr__(self, "worlds", parse_world_selection(self.worlds))
        for key in ("resolution", "dt"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or v <= 0:
                raise ConfigError(f"{key}: must be a number > 0, got {v!r}")
        if isinstance(self.planners, str):
            raise ConfigError(f"planners: must be a list of names, got {self.planners!r}")
        names = []
        for n in tuple(self.planners) or tuple(p for p in planner_names() if REGISTRY[p].online):
            try:
                spec = get_planner(n)
            except ConfigError as exc:
                raise ConfigError(f"planners: {exc}") from None
            if not spec.online:
                raise ConfigError(f"planners: {spec.name!r} cannot run online")
            names.append(spec.name)
        object.__setattr__(self, "planners", tuple(dict.fromkeys(names)))
        if not isinstance(self.params, Mapping):
            raise ConfigError(f"params: must be {{planner: {{key: value}}}}, got "
                              f"{self.params!r}")
        for n, p in self.params.items():
            if n not in self.planners:
                raise ConfigError(f"params.{n}: not among the planners run "
                                  f"({', '.join(self.planners)})")
            make_params(get_planner(n), p, key=f"params.{n}")
        if not isinstance(self.robot, Mapping):
            raise ConfigError(f"robot: must be a mapping (radius, max_speed, ...), got "
                              f"{self.robot!r}")
        object.__setattr__(self, "robot", dict(self.robot))

    @property
    def robot_radius_m(self) -> float:
        return float(self.robot.get("radius", JACKAL_RADIUS_M))


BARN_FILE_KEYS = ("name", "description", "directory", "worlds", "planners", "resolution",
                  "robot", "dt", "params")
"""The keys of a BARN experiment file (``experiments/barn-*.yaml``)."""


def load_barn_file(path: str | os.PathLike[str]) -> tuple[BarnConfig, dict[str, Any]]:
    """Read a BARN experiment file: the :class:`BarnConfig` it describes, and its
    ``name``/``description``.

    The file holds the keys of :data:`BARN_FILE_KEYS`::

        name: barn-jackal
        directory: ../../shared/data/barn     # relative to this file
        worlds: null                          # or "0-49,100", or [0, 17]
        planners: [fusion, astar-replan]      # null: every online planner
        resolution: 0.05
        dt: 0.1
        robot: {model: diff-drive, radius: 0.333, max_speed: 2.0, heading: 1.57}
        params: {fusion: {r1_m: 1.0}}

    Raises
    ------
    ConfigError
        An unknown key, a bad value (the message names the file and the key).
    MapFormatError
        A file that is not YAML.
    """
    from pathfuse.io.ros import load_yaml_mapping

    p = Path(os.path.expanduser(os.fspath(path)))
    doc = load_yaml_mapping(p, "BARN experiment")
    for k in doc:
        if k not in BARN_FILE_KEYS:
            raise ConfigError(f"{p}: unknown key {k!r} (allowed: {', '.join(BARN_FILE_KEYS)})")
    if "directory" not in doc or not isinstance(doc["directory"], str):
        raise ConfigError(f"{p}: directory: missing (the BARN folder, relative to the file)")
    d = Path(os.path.expanduser(doc["directory"]))
    kw: dict[str, Any] = {"directory": os.path.normpath(d if d.is_absolute() else p.parent / d)}
    for key in ("worlds", "resolution", "dt", "robot", "params"):
        if doc.get(key) is not None:
            kw[key] = doc[key]
    if doc.get("planners") is not None:
        if not isinstance(doc["planners"], list):
            raise ConfigError(f"{p}: planners: must be a list of names, got "
                              f"{doc['planners']!r}")
        kw["planners"] = tuple(doc["planners"])
    try:
        cfg = BarnConfig(**kw)
    except ConfigError as exc:
        raise ConfigError(f"{p}: {exc}") from None
    return cfg, {"name": str(doc.get("name", p.stem)),
                 "description": str(doc.get("description", ""))}


def _scenario(cfg: BarnConfig, w: BarnWorld, digest: str) -> dict[str, Any]:
    """The inline scenario of one world (what the engine's dynamic entry runs)."""
    return {
        "name": f"barn-world-{w.index}",
        "description": f"BARN world {w.index} ({w.world.name}, sha256 {digest[:16]})",
        "map": {"gazebo": str(w.world.resolve()), "resolution": float(cfg.resolution),
                "bounds": list(BARN_BOUNDS), "name": f"world_{w.index}"},
        "start": list(BARN_START),
        "goal": list(BARN_GOAL),
        "robot": dict(cfg.robot),
        "dt": float(cfg.dt),
        "time_limit": BARN_TIME_LIMIT_S,
        "goal_tolerance": BARN_GOAL_TOLERANCE_M,
        "stall_time": 0.0,  # the protocol has no stall rule: a stuck robot times out
    }


def barn_experiment(cfg: BarnConfig, worlds: Sequence[BarnWorld] | None = None) -> Any:
    """The study-engine experiment: one dynamic map entry per world, every planner, seed 0."""
    from pathfuse.bench.experiment import experiment_from_dict
    from pathfuse.bench.keys import file_digest

    ws = find_worlds(cfg.directory, cfg.worlds) if worlds is None else list(worlds)
    doc = {
        "name": "barn",
        "description": "the BARN challenge protocol on Gazebo worlds",
        "seeds": 1,
        "store_paths": True,
        "maps": [{"name": f"world_{w.index}",
                  "dynamic": _scenario(cfg, w, file_digest(w.world))} for w in ws],
        "planners": [{"name": n, "params": dict(cfg.params.get(n, {})), "kinds": ["dynamic"]}
                     if cfg.params.get(n) else {"name": n, "kinds": ["dynamic"]}
                     for n in cfg.planners],
    }
    return experiment_from_dict(doc, Path(cfg.directory) / "barn.yaml", check_maps=False)


# --------------------------------------------------------------------------- records
def trajectory_with_yaw(times: np.ndarray, positions: np.ndarray,
                        yaw0: float = BARN_START_YAW,
                        headings: np.ndarray | None = None) -> list[list[float]]:
    """``[t, x, y, yaw]`` per tick.  Without ``headings`` (a holonomic robot has none)
    the yaw is the direction of travel over the tick that ends there, held while the
    robot stands still; ``yaw0`` at the start.

    >>> trajectory_with_yaw(np.array([0, 0.1, 0.2]), np.array([[0, 0], [0, 0], [1, 1]]))[2]
    [0.2, 1.0, 1.0, 0.7853981633974483]
    """
    t = np.asarray(times, dtype=np.float64)
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
    if headings is not None:
        yaw = np.asarray(headings, dtype=np.float64).reshape(-1)
    else:
        yaw = np.empty(p.shape[0])
        cur = float(yaw0)
        for k in range(p.shape[0]):
            if k:
                dx, dy = p[k] - p[k - 1]
                if dx * dx + dy * dy > 1e-18:
                    cur = math.atan2(dy, dx)
            yaw[k] = cur
    return [[float(a), float(b), float(c), float(d)] for a, b, c, d in
            zip(t, p[:, 0], p[:, 1], yaw, strict=True)]


def _positions(row: Mapping[str, Any]) -> np.ndarray:
    """The robot's (N, 2) positions per tick of a stored run (the start alone without any)."""
    blob = row.get("path")
    return np.frombuffer(blob, dtype="<f8").reshape(-1, 2) if blob else \
        np.asarray([BARN_START], dtype=np.float64)


def episode_record(world: BarnWorld, planner: str, row: Mapping[str, Any], dt: float,
                   robot_radius_m: float, optimal_time_s: float,
                   trajectory: bool = True) -> dict[str, Any]:
    """One episode as the challenge reports it, from its stored run.

    Besides the challenge's fields: ``collision_at_fault`` (on a collision, whether the
    robot moved into it; None otherwise; see :class:`pathfuse.world.Episode`) and the
    safety shield's counts ``shield_asked`` ... ``shield_evade`` (None for a row stored
    before they existed)."""
    from pathfuse.world.episode import stored_at_fault, stored_shield_counts

    m = json.loads(row.get("metrics") or "{}")
    pos = _positions(row)
    times = np.round(np.arange(pos.shape[0], dtype=np.float64) * dt, 9)
    status = str(row["status_name"])
    moved = np.hypot(pos[:, 0] - BARN_START[0], pos[:, 1] - BARN_START[1]) >= BARN_MOVE_START_M
    t_start = float(times[int(np.argmax(moved))]) if moved.any() else 0.0
    end = float(times[-1])
    success = status == Status.SUCCESS.name
    # the challenge's three outcomes (barn_report.OUTCOMES): any other end is a timeout
    ended = Status.SUCCESS if success else Status.COLLISION \
        if status == Status.COLLISION.name else Status.TIMEOUT
    outcome = ended.value
    time_s = end - t_start if success else (end - t_start if ended is Status.COLLISION
                                            else BARN_TIME_LIMIT_S)
    rec: dict[str, Any] = {
        "world": int(world.index),
        "planner": planner,
        "status": outcome,
        "pathfuse_status": status,
        "time_s": round(float(time_s), 9),
        "metric": barn_metric(success, time_s, optimal_time_s),
        "optimal_time_s": float(optimal_time_s),
        "reference_length_m": float(optimal_time_s * REFERENCE_SPEED_M_S),
        "robot_radius_m": float(robot_radius_m),
        "path_length_m": float(np.hypot(*np.diff(pos, axis=0).T).sum()) if pos.shape[0] > 1
        else 0.0,
        "min_static_clearance_m": m.get("min_static_clearance_m"),
        "ticks": int(pos.shape[0] - 1),
        "message": row.get("message") or "",
        "collision_at_fault": stored_at_fault(m, status),
        **stored_shield_counts(m),
    }
    if trajectory:
        hblob = row.get("headings")
        headings = np.frombuffer(hblob, dtype="<f8") if hblob else None
        if headings is not None and headings.shape[0] != pos.shape[0]:
            headings = None
        rec["trajectory"] = trajectory_with_yaw(times, pos, headings=headings)
    return rec


@dataclass
class BarnRun:
    """Every episode of a BARN study (records in world, then planner order); ``paths``
    holds the (N, 2) positions of every planner on the world ``figure_world``."""

    config: BarnConfig
    worlds: list[BarnWorld]
    records: list[dict[str, Any]]
    wall_s: float
    workers: int = 1
    figure_world: int | None = None
    paths: dict[str, np.ndarray] = field(default_factory=dict)


def pick_figure_world(records: Sequence[Mapping[str, Any]]) -> int | None:
    """The world whose trajectories tell most: where the planners' outcomes are most evenly
    split between success and failure, then most varied, then lowest in total metric (the
    hardest); the first such world in ``records``' order.  None without records.

    >>> pick_figure_world([{"world": 3, "status": "success", "metric": 0.5},
    ...                    {"world": 7, "status": "success", "metric": 0.2},
    ...                    {"world": 7, "status": "timeout", "metric": 0.0}])
    7
    """
    by: dict[int, list[Mapping[str, Any]]] = {}
    for r in records:
        by.setdefault(int(r["world"]), []).append(r)

    def score(rs: list[Mapping[str, Any]]) -> tuple[int, int, float]:
        ok = sum(r["status"] == "success" for r in rs)
        return (min(ok, len(rs) - ok), len({r["status"] for r in rs}),
                -sum(float(r["metric"]) for r in rs))

    return max(by, key=lambda w: score(by[w]), default=None)


def run_barn(config: BarnConfig, *, workers: int | None = 1, scheduler: Any = None,
             db_path: str | os.PathLike[str] | None = None, progress: bool | None = False,
             trajectories: bool = True, stream: Any = None,
             figure_world: int | str | None = "auto") -> BarnRun:
    """Run (or resume, with ``db_path``) the BARN protocol with the study engine.

    ``figure_world`` is the world whose paths the run keeps for its figure (``"auto"``:
    :func:`pick_figure_world`; None: none); a world not run is a :class:`ConfigError`.
    """
    from pathfuse.bench.runner import run_experiment
    from pathfuse.bench.store import ResultStore

    worlds = find_worlds(config.directory, config.worlds)
    if figure_world not in (None, "auto") and figure_world not in {w.index for w in worlds}:
        raise ConfigError(f"figure_world: world {figure_world!r} is not among the worlds run "
                          f"({_ranges([w.index for w in worlds])})")
    optimal = {w.index: w.reference_length_m() / REFERENCE_SPEED_M_S for w in worlds}
    exp = barn_experiment(config, worlds)
    specs = exp.expand()
    store = ResultStore(":memory:" if db_path is None else db_path)
    try:
        summary = run_experiment(exp, store, workers=workers, scheduler=scheduler,
                                 progress=progress, stream=stream, label="barn")
        stored = store.rows_by_key([r.key for r in specs])
    finally:
        store.close()
    by_name = {f"world_{w.index}": w for w in worlds}
    order = {n: i for i, n in enumerate(config.planners)}
    rank = {w.index: i for i, w in enumerate(worlds)}
    ordered = sorted(specs, key=lambda r: (rank[by_name[r.group].index], order[r.planner]))
    records = [episode_record(by_name[r.group], r.planner, stored[r.key], config.dt,
                              config.robot_radius_m, optimal[by_name[r.group].index],
                              trajectories) for r in ordered]
    shown = pick_figure_world(records) if figure_world == "auto" else figure_world
    paths = {r.planner: _positions(stored[r.key]) for r in ordered
             if by_name[r.group].index == shown}
    return BarnRun(config, worlds, records, summary.wall_s, summary.workers,
                   None if shown is None else int(shown), paths)
