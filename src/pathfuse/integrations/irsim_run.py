"""One IR-SIM episode: a people world, a planner (or IR-SIM's own RVO robot), a seed.

:func:`run_irsim_episode` loads an IR-SIM world file, perturbs it with the
seed, drives its robot with :class:`~pathfuse.integrations.irsim.IrsimController`
(or lets IR-SIM's ``rvo`` behaviour drive it: the planner name
:data:`RVO_BASELINE`) until IR-SIM reports the goal reached or a collision, or
the time limit passes, and returns an :class:`IrsimEpisode` with the
trajectories, IR-SIM's verdict and the social metrics of
:mod:`pathfuse.world.social`.

pathfuse's settings of a world live in the file's ``custom: pathfuse:`` block,
which IR-SIM reads and hands back untouched (:data:`WORLD_KEYS`)::

    custom:
      pathfuse:
        kind: corridor-head-on          # the world's kind, for reports
        description: two people side by side walking head-on
        time_limit_s: 40                # default 60
        perturb: {position_m: 0.3, speed_frac: 0.15}

Seeds (``perturb``)
-------------------
Seed ``s`` moves every walker's start by an offset drawn uniformly in
``[-position_m, position_m]`` on each axis and scales its speed limits
(``vel_max``, and an RVO behaviour's ``vxmax``/``vymax``) by a factor drawn in
``[1 - speed_frac, 1 + speed_frac]``, with ``numpy.random.default_rng([s,
...])``; an offset that would put the walker into a static obstacle, the robot
or a walker already placed is drawn again (at most 50 times, then the walker
keeps its start: counted in ``IrsimEpisode.unperturbed``).  IR-SIM's own
random generator gets the seed too.  So N seeds are N different episodes, and
the same seed gives the same episode.

Examples
--------
>>> import os
>>> world = os.path.join(example_worlds_dir(), "corridor_head_on.yaml")
>>> ep = run_irsim_episode(world, "fusion", seed=0, time_limit_s=1.0)
>>> ep.status.name, ep.n_ticks, ep.positions.shape
('TIMEOUT', 10, (11, 2))
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.integrations.irsim import (
    DEFAULT_RESOLUTION_M,
    IrsimController,
    example_worlds_dir,
    make_env,
    moving_objects,
    rasterise_static,
)
from pathfuse.result import ConfigError, Status
from pathfuse.validate import short as _shown
from pathfuse.world.social import PERSONAL_SPACE_M, SocialMetrics, social_metrics

__all__ = ["irsim_row", "WorldSpec", "read_world_spec", "baseline_spec", "RvoBaselineParams",
           "perturb_env",
           "IrsimEpisode", "run_irsim_episode",
           "RVO_BASELINE", "WORLD_KEYS", "PERTURB_KEYS", "DEFAULT_TIME_LIMIT_S",
           "example_worlds_dir"]

RVO_BASELINE = "irsim-rvo"
"""The planner name of IR-SIM's own robot: its ``rvo`` behaviour drives it."""
WORLD_KEYS = ("kind", "description", "time_limit_s", "perturb")
"""The keys of a world file's ``custom: pathfuse:`` block."""
PERTURB_KEYS = ("position_m", "speed_frac")
"""The keys of its ``perturb:`` block."""
DEFAULT_TIME_LIMIT_S = 60.0
"""The time limit of a world that names none (s)."""
_MAX_DRAWS = 50


@dataclass(frozen=True)
class RvoBaselineParams:
    """IR-SIM's RVO robot takes no parameters of pathfuse's (the world file's ``behavior:``
    block, or RVO at the robot's limits, configures it)."""


def baseline_spec() -> Any:
    """A :class:`~pathfuse.planners.registry.PlannerSpec` (not registered) that names
    :data:`RVO_BASELINE` for the study engine; it has no controller: the engine's
    ``irsim`` executor lets IR-SIM drive the robot."""
    from pathfuse.planners.registry import PlannerSpec

    return PlannerSpec(RVO_BASELINE, RvoBaselineParams,
                       "IR-SIM's own robot, driven by its RVO behaviour (baseline)")


@dataclass(frozen=True)
class WorldSpec:
    """A world file and pathfuse's settings of it (its ``custom: pathfuse:`` block).

    Attributes
    ----------
    path : str
        The file.
    name : str
        The file's stem.
    kind : str
        The world's kind (default: its name).
    description : str
    time_limit_s : float
    position_m, speed_frac : float
        The seed's perturbation (0: none).
    """

    path: str
    name: str
    kind: str
    description: str
    time_limit_s: float
    position_m: float
    speed_frac: float


def _num(v: Any, where: str, lo: float, lo_ok: bool, hi: float = math.inf) -> float:
    ok = not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v) \
        and (v >= lo if lo_ok else v > lo) and v <= hi
    if not ok:
        rng = f"{'>=' if lo_ok else '>'} {lo:g}" + (f" and <= {hi:g}" if math.isfinite(hi)
                                                      else "")
        raise ConfigError(f"{where}: must be a number {rng}, got {_shown(v)}")
    return float(v)


def read_world_spec(path: str | os.PathLike[str]) -> WorldSpec:
    """Read the ``custom: pathfuse:`` block of an IR-SIM world file (defaults without one).

    Raises
    ------
    ConfigError
        No such file, not a YAML mapping, or a bad key or value in the block (the message
        names the file and the key).
    """
    from pathfuse.safeyaml import read_yaml_mapping

    p = Path(os.path.expanduser(os.fspath(path)))
    if not p.is_file():
        raise ConfigError(f"{p}: no such IR-SIM world file")
    doc = read_yaml_mapping(p, "IR-SIM world", ConfigError)
    if isinstance(doc.get("irsim"), Mapping):  # IR-SIM's optional nesting
        doc = dict(doc["irsim"])
    if "robot" not in doc or not doc["robot"]:
        raise ConfigError(f"{p}: robot: missing (an IR-SIM world with a robot to drive)")
    obstacles = doc.get("obstacle") or []
    for i, ob in enumerate(obstacles if isinstance(obstacles, list) else []):
        gb = ob.get("group_behavior") if isinstance(ob, Mapping) else None
        if (isinstance(gb, Mapping) and gb.get("name") == "orca"
                and importlib.util.find_spec("pyrvo") is None):
            raise ConfigError(f"{p}: obstacle[{i}].group_behavior: IR-SIM's ORCA walkers need "
                              "pyrvo (pip install pyrvo); without it IR-SIM leaves them "
                              "standing")
    custom = doc.get("custom") or {}
    block = custom.get("pathfuse") if isinstance(custom, Mapping) else None
    block = {} if block is None else block
    where = f"{p}: custom.pathfuse"
    if not isinstance(block, Mapping):
        raise ConfigError(f"{where}: must be a mapping, got {_shown(block)}")
    for k in block:
        if k not in WORLD_KEYS:
            raise ConfigError(f"{where}.{k}: unknown key (allowed: {', '.join(WORLD_KEYS)})")
    tl = _num(block.get("time_limit_s", DEFAULT_TIME_LIMIT_S), f"{where}.time_limit_s", 0.0,
              False)
    pert = block.get("perturb") or {}
    if not isinstance(pert, Mapping):
        raise ConfigError(f"{where}.perturb: must be {{position_m, speed_frac}}, got "
                          f"{_shown(pert)}")
    for k in pert:
        if k not in PERTURB_KEYS:
            raise ConfigError(f"{where}.perturb.{k}: unknown key (allowed: "
                              f"{', '.join(PERTURB_KEYS)})")
    pos = _num(pert.get("position_m", 0.0), f"{where}.perturb.position_m", 0.0, True)
    spd = _num(pert.get("speed_frac", 0.0), f"{where}.perturb.speed_frac", 0.0, True, 0.9)
    for key in ("kind", "description"):
        if key in block and not isinstance(block[key], str):
            raise ConfigError(f"{where}.{key}: must be a string, got {_shown(block[key])}")
    return WorldSpec(str(p), p.stem, str(block.get("kind", p.stem)),
                     str(block.get("description", "")), tl, pos, spd)


def perturb_env(env: Any, seed: int, position_m: float, speed_frac: float,
                robot_ids: tuple[int, ...] = ()) -> int:
    """Jitter the start and speed of every moving obstacle of ``env`` (see the module
    docstring); returns how many walkers kept their start (no clear offset found)."""
    import shapely

    if position_m <= 0 and speed_frac <= 0:
        return 0
    rng = np.random.default_rng([int(seed), 0x1D5E, 0x7])
    robots = [o for o in env.objects if o.role == "robot"]
    walkers = [o for o in moving_objects(env, -1) if o.role != "robot"
               and o.id not in robot_ids]
    static = [o.geometry for o in env.objects if o.static and o.shape != "map"]
    world = env._world
    placed = [o.geometry for o in robots]
    kept = 0
    for o in walkers:
        s0 = np.asarray(o.state, dtype=np.float64).copy()
        done = position_m <= 0
        for _ in range(_MAX_DRAWS if position_m > 0 else 0):
            d = rng.uniform(-position_m, position_m, size=2)
            s = s0.copy()
            s[0, 0] += d[0]
            s[1, 0] += d[1]
            o.set_state(s, init=True)
            g = o.geometry
            bad = any(shapely.intersects(g, h) for h in static + placed)
            if not bad and getattr(world, "grid_map", None) is not None:
                from irsim.world.map.obstacle_map import grid_collision_geometry

                bad = grid_collision_geometry(world.grid_map, (world.reso[0, 0],
                                                               world.reso[1, 0]), g,
                                              world.offset)
            if not bad:
                done = True
                break
        if not done:
            o.set_state(s0, init=True)
            kept += 1
        placed.append(o.geometry)
        if speed_frac > 0:
            f = float(rng.uniform(1.0 - speed_frac, 1.0 + speed_frac))
            o.vel_max = np.asarray(o.vel_max, dtype=np.float64) * f
            o.vel_min = np.asarray(o.vel_min, dtype=np.float64) * f
            beh = getattr(o, "obj_behavior", None)
            bd = getattr(beh, "behavior_dict", None)
            if isinstance(bd, dict):
                nd = dict(bd)
                for key in ("vxmax", "vymax", "vmax"):
                    if key in nd:
                        nd[key] = float(nd[key]) * f
                beh.behavior_dict = nd  # type: ignore[union-attr]
    return kept


@dataclass(frozen=True)
class _Label:
    """The few scenario fields pathfuse's animation reads (:mod:`pathfuse.viz.animate`)."""

    name: str
    dt: float
    start: tuple[float, float]
    goal: tuple[float, float]
    goal_tolerance: float
    robot: Any


@dataclass(frozen=True)
class _RobotLabel:
    radius: float
    sensing_radius: float


@dataclass(frozen=True, eq=False)
class IrsimEpisode:
    """The record of one IR-SIM episode.

    Attributes
    ----------
    world, kind : str
        The world's name and kind.
    planner : str
        The planner (or :data:`RVO_BASELINE`).
    seed : int
    status : Status
        ``SUCCESS`` (IR-SIM: arrived), ``COLLISION`` (IR-SIM reported one),
        ``TIMEOUT``, or the controller's failure (``NO_PATH``, ...).
    message : str
    times : (T,) array
    positions : (T, 2) array
        The robot's centre at each tick.
    headings : (T,) array
    people_positions : (T, K, 2) array
        Every moving object's centre at each tick (the people).
    people_radii : (K,) array
    collision_with : str or None
        ``"static"`` or ``"person"`` (what IR-SIM says the robot touched).
    collision_at_fault : bool or None
        On a collision, whether the robot was moving during its last tick (always, for a
        static one).
    social : SocialMetrics
    act_times_s : (T - 1,) array
        The adapter's wall-clock time per step (empty for the baseline).
    command_times_s : (T - 1,) array
        Of which the planner's command (sensing excluded).
    setup_time_s : float
    unperturbed : int
        Walkers that kept their start (see :func:`perturb_env`).
    """

    world: str
    kind: str
    planner: str
    seed: int
    status: Status
    message: str
    times: np.ndarray
    positions: np.ndarray
    headings: np.ndarray
    people_positions: np.ndarray
    people_radii: np.ndarray
    collision_with: str | None
    collision_at_fault: bool | None
    social: SocialMetrics
    act_times_s: np.ndarray
    command_times_s: np.ndarray
    setup_time_s: float
    unperturbed: int
    grid: GridMap = field(repr=False)
    scenario: Any = field(repr=False)
    path_updates: list[tuple[int, np.ndarray]] = field(default_factory=list, repr=False)

    @property
    def reached(self) -> bool:
        return self.status is Status.SUCCESS

    @property
    def n_ticks(self) -> int:
        return int(self.positions.shape[0] - 1)

    @property
    def path_length_m(self) -> float:
        p = self.positions
        return float(np.hypot(*np.diff(p, axis=0).T).sum()) if p.shape[0] > 1 else 0.0

    @property
    def time_to_goal_s(self) -> float | None:
        return float(self.times[-1]) if self.reached else None

    # what pathfuse's animation reads
    @property
    def obstacle_positions(self) -> np.ndarray:
        return self.people_positions

    @property
    def obstacle_radii(self) -> np.ndarray:
        return self.people_radii

    @property
    def sensed(self) -> np.ndarray:
        return np.ones(self.people_positions.shape[:2], dtype=bool)

    def metrics(self) -> dict[str, Any]:
        """The episode's scalar values (JSON-ready: non-finite numbers as None)."""
        def fin(v: float | None) -> float | None:
            return None if v is None or not math.isfinite(v) else float(v)

        soc = self.social
        at = self.act_times_s
        return {
            "world": self.world, "kind": self.kind, "planner": self.planner,
            "seed": int(self.seed), "status": self.status.name, "message": self.message,
            "collision": self.status is Status.COLLISION,
            "collision_with": self.collision_with,
            "collision_at_fault": self.collision_at_fault,
            "time_to_goal_s": fin(self.time_to_goal_s),
            "sim_time_s": float(self.times[-1]),
            "path_length_m": self.path_length_m,
            "n_ticks": self.n_ticks,
            "dt": float(self.scenario.dt),
            "people": int(self.people_radii.shape[0]),
            "min_gap_m": fin(soc.min_gap_m),
            "time_within_m_s": soc.time_within_m_s,
            "personal_m": soc.personal_m,
            "at_fault_contacts": soc.at_fault_collisions,
            "contacts": soc.contacts,
            "path_irregularity_rad_per_m": soc.path_irregularity_rad_per_m,
            "unperturbed": int(self.unperturbed),
            "mean_act_time_s": float(at.mean()) if at.size else 0.0,
            "median_act_time_s": float(np.median(at)) if at.size else 0.0,
            "median_command_time_s": float(np.median(self.command_times_s))
            if self.command_times_s.size else 0.0,
            "setup_time_s": float(self.setup_time_s),
        }


def _set_rvo(robot: Any) -> None:
    """Give IR-SIM's robot its ``rvo`` behaviour when the world gives it none (the robot's
    speed limits as RVO's)."""
    from irsim.lib.behavior.behavior import Behavior

    if getattr(robot, "beh_config", None):
        return
    vmax = np.asarray(robot.vel_max, dtype=np.float64).reshape(-1)
    acce = np.asarray(robot.info.acce, dtype=np.float64).reshape(-1)
    a = float(acce[0]) if math.isfinite(acce[0]) else 1.0
    robot.obj_behavior = Behavior(robot.info, {"name": "rvo", "vxmax": float(vmax[0]),
                                               "vymax": float(vmax[0]), "acce": a})


def run_irsim_episode(world: str | os.PathLike[str], planner: str = "fusion", seed: int = 0,
                      params: Mapping[str, Any] | None = None, *,
                      resolution_m: float = DEFAULT_RESOLUTION_M,
                      robot_overrides: Mapping[str, Any] | None = None,
                      time_limit_s: float | None = None,
                      personal_m: float = PERSONAL_SPACE_M) -> IrsimEpisode:
    """Run one episode of the IR-SIM world file ``world`` (see the module docstring).

    Parameters
    ----------
    world : path
        An IR-SIM world file with one robot (the one driven) and a goal for it.
    planner : str
        An online planner of pathfuse, or :data:`RVO_BASELINE` (IR-SIM's ``rvo``
        behaviour drives the robot).
    seed : int
        The perturbation's and IR-SIM's seed.
    params : mapping, optional
        The planner's parameters.
    resolution_m, robot_overrides
        As for :class:`~pathfuse.integrations.irsim.IrsimController`.
    time_limit_s : float, optional
        Default: the world's ``time_limit_s``.
    personal_m : float
        The personal-space gap of the social metrics.

    Raises
    ------
    ConfigError
        A bad world file, planner, parameter or seed (the message names it).
    """
    spec = read_world_spec(world)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"seed: must be an integer >= 0, got {_shown(seed)}")
    limit = spec.time_limit_s if time_limit_s is None else \
        _num(time_limit_s, "time_limit_s", 0.0, False)
    env = make_env(spec.path, seed=int(seed))
    try:
        robot = env.robot_list[0] if env.robot_list else None
        if robot is None:
            raise ConfigError(f"{spec.path}: robot: the world has no robot")
        unperturbed = perturb_env(env, int(seed), spec.position_m, spec.speed_frac,
                                  (robot.id,))
        baseline = planner == RVO_BASELINE
        t0 = time.perf_counter()
        ctrl: IrsimController | None = None
        if baseline:
            if params:
                raise ConfigError(f"params: {RVO_BASELINE} takes no parameters, got "
                                  f"{_shown(dict(params))}")
            _set_rvo(robot)
            grid = rasterise_static(env, resolution_m, exclude=(robot.id,))
            name = RVO_BASELINE
        else:
            ctrl = IrsimController(env, planner, resolution_m=resolution_m,
                                   robot_overrides=robot_overrides, **dict(params or {}))
            grid = ctrl.scene.grid
            name = ctrl.planner
        setup = time.perf_counter() - t0
        dt = float(env._world.step_time)
        n_max = max(1, int(math.ceil(limit / dt - 1e-9)))
        movers = moving_objects(env, robot.id)
        k = len(movers)
        pos = np.empty((n_max + 1, 2))
        head = np.empty(n_max + 1)
        ppl = np.empty((n_max + 1, k, 2))
        acts = np.empty(n_max)
        cmds = np.empty(n_max)

        def record(i: int) -> None:
            pos[i] = robot.state[0, 0], robot.state[1, 0]
            head[i] = robot.state[2, 0]
            for j, o in enumerate(movers):
                ppl[i, j] = o.state[0, 0], o.state[1, 0]

        record(0)
        status, message = Status.TIMEOUT, f"time limit {limit:g} s reached"
        collision_with: str | None = None
        n = 0
        if ctrl is not None and ctrl.failure is not None:
            status, message = ctrl.failure
        else:
            while n < n_max:
                if ctrl is not None:
                    a = ctrl.act(env)
                    acts[n] = ctrl.act_times_s[-1]
                    cmds[n] = ctrl.command_times_s[-1]
                    env.step(a)
                else:
                    env.step()
                n += 1
                record(n)
                if robot.collision:
                    status = Status.COLLISION
                    hit = list(getattr(robot, "collision_obj", []))
                    collision_with = "person" if any(not o.static for o in hit) else "static"
                    message = (f"IR-SIM reported a collision with "
                               f"{'a person' if collision_with == 'person' else 'an obstacle'}"
                               f" at t = {n * dt:.2f} s")
                    break
                if robot.arrive:
                    status, message = Status.SUCCESS, f"reached the goal at t = {n * dt:.2f} s"
                    break
                if ctrl is not None and ctrl.failure is not None:
                    status, message = ctrl.failure
                    break
        times = np.arange(n + 1) * dt
        radii = np.array([float(o.radius) for o in movers])
        soc = social_metrics(pos[:n + 1], ppl[:n + 1], radii, float(robot.radius), dt,
                             headings=head[:n + 1] if robot.kinematics == "diff" else None,
                             personal_m=personal_m)
        at_fault: bool | None = None
        if status is Status.COLLISION:
            moved = float(np.hypot(*(pos[n] - pos[n - 1]))) / dt if n else 0.0
            at_fault = collision_with == "static" or moved > 0.01
        g = np.asarray(robot.goal, dtype=np.float64).reshape(-1) if robot.goal is not None \
            else pos[0]
        label = _Label(spec.name, dt, (float(pos[0, 0]), float(pos[0, 1])),
                       (float(g[0]), float(g[1])), float(robot.goal_threshold),
                       _RobotLabel(float(robot.radius),
                                   ctrl.scene.robot.sensing_radius_m if ctrl else 0.0))
        updates: list[tuple[int, np.ndarray]] = []
        if ctrl is not None and ctrl.global_path is not None:
            updates.append((0, np.asarray(ctrl.global_path, dtype=np.float64)))
        m = n if ctrl is not None else 0  # the baseline has no adapter to time
        return IrsimEpisode(spec.name, spec.kind, name, int(seed), status, message, times,
                            pos[:n + 1].copy(), head[:n + 1].copy(), ppl[:n + 1].copy(), radii,
                            collision_with, at_fault, soc, acts[:m].copy(), cmds[:m].copy(),
                            setup, unperturbed, grid, label, updates)
    finally:
        del env


_TIMING = ("mean_act_time_s", "median_act_time_s", "median_command_time_s", "setup_time_s")


def _json_params(planner: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """Parameters read back from a run's JSON: lists to tuples where the default is a
    tuple."""
    from pathfuse.planners.registry import get_planner

    defaults = get_planner(planner).defaults()
    return {k: tuple(v) if isinstance(defaults.get(k), tuple) and isinstance(v, list) else v
            for k, v in params.items()}


def irsim_row(group: Mapping[str, Any], run: Mapping[str, Any],
              store_paths: bool) -> dict[str, Any]:
    """One run of the study engine's ``irsim`` kind (:mod:`pathfuse.bench.execute`): the
    episode as result columns.

    ``time`` is the adapter's compute time (setup plus every step's ``act``);
    ``solution_clearance`` the minimum gap to the people; ``collisions`` 1 when IR-SIM
    ended the episode in a collision; ``metrics`` every value of
    :meth:`~pathfuse.integrations.irsim_run.IrsimEpisode.metrics` but the timings, which
    go to ``timing``.
    """
    w = group["map_spec"]["irsim"]
    planner = run["planner"]
    params = {} if planner == RVO_BASELINE else _json_params(planner, run["params"] or {})
    limit = w.get("time_limit_s")
    ep = run_irsim_episode(w["world"], planner, int(run["seed"]), params or None,
                           resolution_m=float(w.get("resolution_m", 0.05)),
                           time_limit_s=None if limit is None else float(limit))
    m = ep.metrics()
    timing = {k: m.pop(k) for k in _TIMING}
    solved = ep.reached
    row: dict[str, Any] = {
        "status_name": ep.status.name,
        "solved": solved,
        "time": float(ep.setup_time_s + ep.act_times_s.sum()),
        "solution_length": ep.path_length_m if solved else None,
        "time_to_goal": ep.time_to_goal_s,
        "path_length": ep.path_length_m,
        "collisions": 1 if m["collision"] else 0,
        "collision_free": not m["collision"],
        "iterations": ep.n_ticks,
        "steps": ep.n_ticks,
        "solution_segments": ep.n_ticks if solved else None,
        "solution_clearance": m["min_gap_m"],
        "message": ep.message,
        "start_x": float(ep.positions[0, 0]), "start_y": float(ep.positions[0, 1]),
        "goal_x": float(ep.scenario.goal[0]), "goal_y": float(ep.scenario.goal[1]),
        "metrics": json.dumps(m, sort_keys=True),
        "timing": json.dumps(timing, sort_keys=True),
    }
    if store_paths:
        row["path"] = np.ascontiguousarray(ep.positions, dtype="<f8").tobytes()
        row["headings"] = np.ascontiguousarray(ep.headings, dtype="<f8").tobytes()
    return row
