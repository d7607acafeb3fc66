"""The episode runner: one scenario, one planner run online, one :class:`Episode` record.

:func:`simulate` (exported as ``pathfuse.simulate``) reads a scenario, builds
the :class:`~pathfuse.world.world.World` and the planner's controller (the
same one :func:`pathfuse.plan` runs offline, :mod:`pathfuse.planners.run`),
and steps them until the goal, a collision, a stall or the time limit::

    ep = pathfuse.simulate("examples/scenarios/crossing.yaml", planner="astar")
    ep.status, ep.time_to_goal_s, ep.min_distance_m

The :class:`Episode` holds everything needed to analyse or animate the run:
the robot's trajectory with its times, every obstacle's position at every
tick, the planner's global path(s), the sensing mask, per-tick planning times
and the scene (map, radii, start, goal).

Statuses (:class:`~pathfuse.result.Status`, the one vocabulary of pathfuse):

``SUCCESS``        the robot's centre came within ``goal_tolerance`` of the goal
``COLLISION``      the robot disc overlapped an occupied cell, the map's outside
                   or a moving disc during a tick (checked continuously)
``TIMEOUT``        the time limit passed
``LOCAL_MINIMUM``  the robot stayed within ``stall_radius`` for ``stall_time``
                   seconds
``NO_PATH``        a planner that needs a global path found none on the static
                   map (the robot did not move); ``START_/GOAL_OCCUPIED`` when a
                   disc robot found no c-space cell near the start or goal
"""

from __future__ import annotations

import contextvars
import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.planners.base import Controller
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.planners.run import start_online, warm
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, Status, path_length
from pathfuse.robot import RobotModel
from pathfuse.world.scenario import Scenario, load_scenario, resolve_planner_choice
from pathfuse.world.world import World

__all__ = ["Episode", "simulate", "run_episode", "warm_online", "stored_at_fault",
           "stored_shield_counts"]


@dataclass(frozen=True, eq=False)
class Episode:
    """The record of one simulated run.

    Attributes
    ----------
    status : Status
        How it ended (``SUCCESS``: the goal was reached).
    planner : str
        Planner name.
    params : dict
        The planner parameters used (defaults filled in).
    times : (T,) float array
        Tick times in seconds, ``times[0] = 0``.
    positions : (T, 2) float array
        Robot centre at each tick (``positions[0]`` is the start).
    velocities : (T - 1, 2) float array
        Velocity used over each tick (after clipping to the speed limit): the
        displacement over the tick divided by ``dt`` (for a diff-drive robot,
        along the chord of its arc).
    obstacle_positions : (T, K, 2) float array
        Every moving disc's centre at each tick.
    obstacle_radii : (K,) float array
        Disc radii.
    sensed : (T, K) bool array
        Which discs the planner observed at each tick.
    global_path : (N, 2) float array or None
        The planner's first global path (A* through cell centres), if any.
    path_updates : list of (tick, (N, 2) array)
        Every global path the planner adopted and the tick of the observation
        it planned from (more than one for replanning planners).
    path_length_m : float
        Length of the robot's trajectory.
    time_to_goal_s : float or None
        Time of the tick at which the goal was reached (None otherwise).
    min_distance_m : float
        Least clearance between the robot disc and any obstacle - static or
        moving - over the whole run (exact over each tick; static clearances
        are capped at 2 m).  Negative after a collision.
    min_obstacle_distance_m : float
        The same for the moving discs only (``inf`` without discs).
    min_static_clearance_m : float
        The same for the static map and its edge only.
    n_ticks : int
        Number of ticks simulated (``T - 1``).
    plan_times_s : (T - 1,) float array
        Wall-clock time of the planner's ``act`` at each tick.
    setup_time_s : float
        Wall-clock time of the planner's ``reset`` (global planning).
    collision_with : str, int or None
        ``"static"`` or the index of the disc hit.
    message : str
        A sentence about the outcome.
    scenario : Scenario
        The scenario run (map, robot, goal, obstacle specs).
    seed : int or None
        The episode seed.
    headings : (T,) float array
        The robot's heading at each tick (rad; see :class:`~pathfuse.world.World`).
    commands : (T - 1, 2) float array
        The action applied at each tick: ``(vx, vy)`` for a holonomic robot,
        ``(v, omega)`` for a diff-drive one (after clipping).
    collision_at_fault : bool or None
        On a collision, whether it was the robot's fault: ``True`` when the
        robot was moving during the colliding tick (a non-zero linear speed or
        holonomic velocity) or hit the static map, ``False`` when a moving disc
        walked into the robot standing still (which the safety shield's
        *passive* safety allows).  ``None`` without a collision.
    shield_counts : dict of str to int
        How often the safety shield (:mod:`pathfuse.shield`) passed the
        controller's command (``asked``), replaced it by a nearby safe one
        (``nearest``), by the emergency stop (``emergency``), found no clear
        command (``unsafe``) or evaded a predicted disc contact (``evade``);
        keys :data:`pathfuse.shield.CODE_NAMES`.  Empty when the controller
        has no shield counts.
    """

    status: Status
    planner: str
    params: dict[str, Any]
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    obstacle_positions: np.ndarray
    obstacle_radii: np.ndarray
    sensed: np.ndarray
    global_path: np.ndarray | None
    path_updates: list[tuple[int, np.ndarray]]
    path_length_m: float
    time_to_goal_s: float | None
    min_distance_m: float
    min_obstacle_distance_m: float
    min_static_clearance_m: float
    n_ticks: int
    plan_times_s: np.ndarray
    setup_time_s: float
    collision_with: Any
    message: str
    scenario: Scenario = field(repr=False)
    seed: int | None = None
    headings: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    commands: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    collision_at_fault: bool | None = None
    shield_counts: dict[str, int] = field(default_factory=dict)

    @property
    def reached(self) -> bool:
        return self.status is Status.SUCCESS

    @property
    def social(self) -> Any:
        """The social metrics of the run with the moving discs as the people
        (:func:`pathfuse.world.social.social_metrics`: minimum gap, time within 0.45 m,
        contacts the robot drove into, path irregularity); None without discs."""
        if not self.obstacle_radii.size:
            return None
        from pathfuse.world.social import social_metrics

        heads = self.headings if self.robot.is_diff_drive and \
            self.headings.shape[0] == self.positions.shape[0] else None
        return social_metrics(self.positions, self.obstacle_positions, self.obstacle_radii,
                              self.robot_radius, float(self.scenario.dt), headings=heads)

    @property
    def mean_plan_time_s(self) -> float:
        """Mean wall-clock planning time per tick (0 without ticks)."""
        return float(self.plan_times_s.mean()) if self.plan_times_s.size else 0.0

    @property
    def grid(self) -> GridMap:
        return self.scenario.grid

    @property
    def robot_radius(self) -> float:
        return self.scenario.robot.radius_m

    @property
    def robot(self) -> RobotModel:
        """The robot's model (:class:`pathfuse.robot.RobotModel`)."""
        return self.scenario.robot

    def trajectory(self) -> np.ndarray:
        """``(T, 4)``: ``[t, x, y, yaw]`` per tick."""
        return np.column_stack([self.times, self.positions, self.headings])

    def to_dict(self, trajectories: bool = True) -> dict[str, Any]:
        """A JSON-ready dict (``trajectories=False`` leaves out the per-tick arrays)."""

        def fin(x: float | None) -> float | None:
            return None if x is None or not math.isfinite(x) else float(x)

        d: dict[str, Any] = {
            "scenario": self.scenario.name,
            "planner": self.planner,
            "params": dict(self.params),
            "seed": self.seed,
            "status": self.status.name,
            "message": self.message,
            "collision_with": self.collision_with,
            "collision_at_fault": self.collision_at_fault,
            "shield_counts": dict(self.shield_counts),
            "path_length_m": float(self.path_length_m),
            "time_to_goal_s": fin(self.time_to_goal_s),
            "min_distance_m": fin(self.min_distance_m),
            "min_obstacle_distance_m": fin(self.min_obstacle_distance_m),
            "min_static_clearance_m": fin(self.min_static_clearance_m),
            "n_ticks": int(self.n_ticks),
            "dt": float(self.scenario.dt),
            "mean_plan_time_s": self.mean_plan_time_s,
            "max_plan_time_s": float(self.plan_times_s.max()) if self.plan_times_s.size else 0.0,
            "setup_time_s": float(self.setup_time_s),
            "robot_model": self.scenario.robot.kind,
        }
        soc = self.social
        if soc is not None:  # among moving discs: the social metrics (pathfuse.world.social)
            d.update({k: fin(v) if isinstance(v, float) else v
                      for k, v in soc.as_dict().items()})
        if trajectories:
            d["times"] = self.times.tolist()
            d["positions"] = self.positions.tolist()
            d["headings"] = self.headings.tolist()
            d["commands"] = self.commands.tolist()
            d["obstacle_positions"] = self.obstacle_positions.tolist()
            d["obstacle_radii"] = self.obstacle_radii.tolist()
            d["global_path"] = None if self.global_path is None else self.global_path.tolist()
        return d


def _stalled(positions: np.ndarray, n: int, window: int, radius: float) -> bool:
    """Whether the last ``window + 1`` positions all lie within ``radius`` of the newest."""
    if window <= 0 or n <= window:
        return False
    seg = positions[n - window - 1:n]
    d = np.hypot(seg[:, 0] - positions[n - 1, 0], seg[:, 1] - positions[n - 1, 1])
    return bool(d.max() < radius)


def _params_of(spec: Any, params: Any) -> Any:
    """The planner's parameter dataclass: ``params`` itself when it is one (of the
    planner's class), else built from a mapping (None: the defaults)."""
    if dataclasses.is_dataclass(params) and not isinstance(params, type):
        if type(params) is not spec.params_cls:
            raise ConfigError(f"params: must be a {spec.params_cls.__name__} for planner "
                              f"{spec.name!r}, got {type(params).__name__}")
        return params
    return make_params(spec, params)


def warm_online(spec: Any, model: RobotModel, cfg: Any) -> None:
    """Compile (or load) the kernels an episode of ``spec`` with the parameters ``cfg`` on a
    robot of ``model``'s kind runs, so that none compiles on a tick (of a pathfuse episode
    or of another simulator's, through :mod:`pathfuse.integrations.irsim`)."""
    warm(spec, params=cfg, diff_drive=model.is_diff_drive, online=True)
    from pathfuse.shield import warmup_shield

    warmup_shield()  # the world's clip and the shield
    if model.is_diff_drive:
        from pathfuse.planners.drive import warmup_drive
        from pathfuse.sweep import warmup_sweep

        warmup_drive()
        warmup_sweep()
    _warm_episode(spec, model, cfg)


# A disc coming head on in a small hall (examples/scenarios/head_on.yaml, shorter): a
# controller's decisions among discs call kernels its warm-up may leave out (escapes, replans
# around discs, a further signature), which would then compile (or load) inside the first
# episode's timed decisions; this episode's 40 ticks make them compile before the clock.
_WARM_SCENARIO: dict[str, Any] = {
    "name": "warm-up", "map": {"rows": ["." * 10] * 5, "resolution": 1.0},
    "start": [1.5, 2.5], "goal": [8.5, 2.5], "dt": 0.1, "time_limit": 4.0,
    "obstacles": [{"position": [5.5, 2.5], "velocity": [-1.0, 0.0], "radius": 0.3}],
}
_WARM_EPISODES: set[Any] = set()
_WARMING: contextvars.ContextVar[bool] = contextvars.ContextVar("pathfuse_warm_episode",
                                                               default=False)


def _warm_episode(spec: Any, model: RobotModel, cfg: Any) -> None:
    """Run :data:`_WARM_SCENARIO` once per process for ``spec`` with the parameters ``cfg``
    on a robot of ``model``'s kind and options (its size fitted to the hall), untimed and
    thrown away.  pathfuse's own controllers only: a plug-in's controller is not made
    once more behind its author's back (its warm-up methods are its own)."""
    ctrl = spec.controller
    if _WARMING.get() or ctrl is None or not ctrl.__module__.startswith("pathfuse."):
        return
    key: Any = (spec.name, repr(model.to_dict()), cfg)
    try:
        hash(key)
    except TypeError:  # parameters that do not hash
        key = (spec.name, repr(model.to_dict()), repr(cfg))
    if key in _WARM_EPISODES:
        return
    robot = model.replace(radius_m=min(model.radius_m, 0.2), sensing_radius_m=3.0,
                          clearance_m=min(model.clearance_m, 0.05),
                          inflation_m=min(model.inflation_m, 0.2), heading_rad=None)
    token = _WARMING.set(True)
    try:
        run_episode(load_scenario(_WARM_SCENARIO), spec.name, cfg, seed=0, robot=robot)
    finally:
        _WARMING.reset(token)
    _WARM_EPISODES.add(key)


def _first_gaps(world: World, position: np.ndarray) -> tuple[float, float]:
    """The robot's static clearance and least surface gap to a disc (inf: no discs) at
    the start."""
    min_obst = math.inf
    if world.obstacle_radii.shape[0]:
        q = world.obstacle_positions[0]
        g0 = np.hypot(q[:, 0] - position[0], q[:, 1] - position[1]) \
            - world.obstacle_radii - world.radius
        min_obst = float(g0.min())
    return world.static_gap(position), min_obst


def _ending(info: Mapping[str, Any], t: float,
            n: int) -> tuple[Status, str, Any, bool | None]:
    """``(status, message, collision_with, at_fault)`` of a tick that ended the episode
    (``info`` from :meth:`World.step`, ``t`` the time after it, ``n`` the positions so far)."""
    status = Status.from_key(info["event"])
    if status is Status.SUCCESS:
        return status, f"reached the goal at t = {t:.2f} s", None, None
    collision_with = info["collision"]
    at_fault = info.get("at_fault")
    what = "the static map" if collision_with == "static" \
        else f"moving obstacle {collision_with}"
    message = f"collided with {what} during tick {n - 2} -> {n - 1} (t = {t:.2f} s)"
    if at_fault is False:
        message += ": it hit the robot standing still"
    return status, message, collision_with, at_fault


def run_episode(scenario: Scenario, planner: str = "fusion", params: Any = None,
                seed: int | None = None, robot: Any = None) -> Episode:
    """Run the registered ``planner`` (with ``params``: a dict, or its parameter dataclass)
    through ``scenario`` (with ``robot``, a :class:`~pathfuse.robot.RobotModel` or a
    ``robot:`` mapping, instead of the scenario's robot)."""
    spec = get_planner(planner)
    cfg = _params_of(spec, params)
    scenario = load_scenario(scenario)
    if robot is not None:
        scenario = scenario.replace(robot=_robot(robot))
    world = World(scenario)
    sc = world.scenario
    model = world.robot
    obs = world.reset(seed)
    n_max = world.n_steps
    k_obs = len(sc.obstacles)
    positions = np.empty((n_max + 1, 2))
    velocities = np.empty((n_max, 2))
    commands = np.empty((n_max, 2))
    headings = np.empty(n_max + 1)
    headings[0] = obs.heading
    sensed = np.zeros((n_max + 1, k_obs), dtype=bool)
    plan_times = np.empty(n_max)
    positions[0] = obs.position
    sensed[0, obs.obstacles.ids] = True

    problem = Problem.create(sc.grid, sc.start, sc.goal, sc.robot.radius_m,
                             clearance_m=model.clearance_m, robot=model)
    warm_online(spec, model, cfg)
    t0 = time.perf_counter()
    ctrl: Controller = start_online(spec, problem, cfg, float(sc.dt), float(sc.robot.max_speed_mps))
    setup = time.perf_counter() - t0
    path_updates: list[tuple[int, np.ndarray]] = []
    last_path = ctrl.global_path
    if last_path is not None:
        path_updates.append((0, np.array(last_path)))

    min_static, min_obst = _first_gaps(world, obs.position)
    window = int(round(min(sc.stall_time / sc.dt, sc.n_steps + 1))) if sc.stall_time > 0 else 0
    status = Status.TIMEOUT
    message = ""
    collision_with = None
    at_fault: bool | None = None
    n = 1
    if ctrl.failure is not None:
        status, message = ctrl.failure
    else:
        while True:
            acted = obs.tick
            t0 = time.perf_counter()
            action = ctrl.command(obs)
            plan_times[n - 1] = time.perf_counter() - t0
            obs, terminated, truncated, info = world.step(action)
            positions[n] = obs.position
            velocities[n - 1] = obs.velocity
            commands[n - 1] = obs.command
            headings[n] = obs.heading
            if k_obs:
                sensed[n, obs.obstacles.ids] = True
            min_static = min(min_static, info["static_gap"])
            min_obst = min(min_obst, info["obstacle_gap"])
            n += 1
            gp = ctrl.global_path
            if gp is not None and gp is not last_path:
                path_updates.append((acted, np.array(gp)))
                last_path = gp
            if terminated:
                status, message, collision_with, at_fault = _ending(info, obs.time, n)
                break
            if truncated:
                message = f"time limit {sc.time_limit:g} s reached"
                break
            if ctrl.failure is not None:
                status, message = ctrl.failure
                break
            if _stalled(positions, n, window, sc.stall_radius):
                status = Status.LOCAL_MINIMUM
                message = (f"stalled: stayed within {sc.stall_radius:g} m for "
                           f"{sc.stall_time:g} s (t = {obs.time:.2f} s)")
                break
    t = n - 1
    times = np.arange(n, dtype=np.float64) * sc.dt
    pos = positions[:n].copy()
    return Episode(
        status=status,
        planner=spec.name,
        params=dataclasses.asdict(cfg),
        times=times,
        positions=pos,
        velocities=velocities[:t].copy(),
        obstacle_positions=np.array(world.obstacle_positions[:n]),
        obstacle_radii=world.obstacle_radii.copy(),
        sensed=sensed[:n].copy(),
        global_path=None if not path_updates else path_updates[0][1],
        path_updates=path_updates,
        path_length_m=path_length(pos),
        time_to_goal_s=float(times[-1]) if status is Status.SUCCESS else None,
        min_distance_m=min(min_static, min_obst),
        min_obstacle_distance_m=min_obst,
        min_static_clearance_m=min_static,
        n_ticks=t,
        plan_times_s=plan_times[:t].copy(),
        setup_time_s=setup,
        collision_with=collision_with,
        message=message,
        scenario=sc,
        seed=world.seed,
        headings=headings[:n].copy(),
        commands=commands[:t].copy(),
        collision_at_fault=at_fault,
        shield_counts=_shield_counts(ctrl),
    )


def _shield_counts(ctrl: Any) -> dict[str, int]:
    """The controller's shield counts by :data:`pathfuse.shield.CODE_NAMES` (empty
    without them)."""
    from pathfuse.shield import CODE_NAMES

    counts = getattr(ctrl, "shield_counts", None)
    if counts is None:
        return {}
    vals = np.asarray(counts).reshape(-1)
    return {name: int(vals[i]) if i < vals.shape[0] else 0
            for i, name in enumerate(CODE_NAMES)}


def stored_at_fault(metrics: Mapping[str, Any], status: str) -> bool | None:
    """``collision_at_fault`` of a stored episode, from the ``metrics`` JSON of its row.

    None unless the episode ended in a collision.  A row written before the value
    existed has none: a collision with the static map is then still the robot's
    (always, by definition), one with a disc is unknown (None).

    >>> stored_at_fault({"collision_with": 2}, "COLLISION") is None
    True
    >>> stored_at_fault({"collision_with": "static"}, "COLLISION")
    True
    >>> stored_at_fault({"collision_with": 2, "collision_at_fault": False}, "COLLISION")
    False
    """
    if str(status).upper() != "COLLISION":
        return None
    v = metrics.get("collision_at_fault")
    if v is not None:
        return bool(v)
    return True if metrics.get("collision_with") == "static" else None


def stored_shield_counts(metrics: Mapping[str, Any]) -> dict[str, int | None]:
    """``shield_<name>`` -> count (:data:`pathfuse.shield.CODE_NAMES`) of a stored
    episode's ``metrics``; None for each where the row has none (older rows).

    >>> stored_shield_counts({"shield_asked": 7})["shield_asked"]
    7
    """
    from pathfuse.shield import CODE_NAMES

    out: dict[str, int | None] = {}
    for name in CODE_NAMES:
        v = metrics.get(f"shield_{name}")
        out[f"shield_{name}"] = None if v is None else int(v)
    return out


def _robot(robot: Any) -> RobotModel:
    if isinstance(robot, RobotModel):
        return robot
    return RobotModel.from_dict(robot, ConfigError)


def simulate(scenario: Any, planner: Any = None, seed: int | None = None,
             robot: Any = None, global_planner: str | None = None) -> Episode:
    """Simulate one episode of a dynamic scenario.

    Parameters
    ----------
    scenario : path, mapping or Scenario
        A scenario YAML file, the same content as a dict, or a
        :class:`~pathfuse.world.scenario.Scenario`.
    planner : str or mapping, optional
        A planner name (``pathfuse planners``; every built-in planner runs
        online) or ``{"name": ..., "params": {...}}``; overrides the
        scenario's ``planner``.
    seed : int, optional
        Episode seed (default: the scenario's); the same scenario and seed
        give the same episode, bit for bit.
    robot : RobotModel or mapping, optional
        The robot to drive instead of the scenario's (a
        :class:`pathfuse.robot.RobotModel`, or a ``robot:`` block as a dict).
    global_planner : str, optional
        The global planner whose path the planner's controller follows (a name
        of :func:`pathfuse.global_planner_names`; the parameter
        ``global_planner``), instead of the planner's own.

    Returns
    -------
    Episode

    Raises
    ------
    ScenarioError, ConfigError
        A malformed scenario or planner choice (the message names the key).

    Examples
    --------
    >>> sc = {"map": {"rows": ["........", "........", "........"]},
    ...       "start": [0.5, 1.5], "goal": [7.5, 1.5], "robot": {"radius": 0.2}}
    >>> ep = simulate(sc, planner="astar")
    >>> ep.status.name, ep.n_ticks, round(ep.path_length_m, 6)
    ('SUCCESS', 68, 6.8)
    >>> simulate(sc, planner="fusion", global_planner="thetastar").status.name
    'SUCCESS'
    """
    sc = load_scenario(scenario)
    choice = resolve_planner_choice(sc.planner if planner is None else planner)
    params = dict(choice.params)
    if global_planner is not None:
        params["global_planner"] = global_planner
    return run_episode(sc, choice.name, params, seed=seed, robot=robot)
