"""Drive a robot of an IR-SIM environment with any online planner of pathfuse.

IR-SIM (PyPI ``ir-sim``, MIT; install the extra ``pip install "pathfuse[irsim]"``)
simulates robots, walls and walkers (``dash``, RVO, ORCA and social-force
behaviours) with its own kinematics and collision checks.
:class:`IrsimController` puts one of pathfuse's online planners in charge of
one of its robots::

    env = irsim.make("examples/irsim/corridor_head_on.yaml", display=False)
    ctrl = IrsimController(env, planner="fusion")
    for _ in range(400):
        env.step(ctrl.act(env))
        if env.robot.arrive or env.robot.collision:
            break

What is read once, at construction
----------------------------------
* **The static obstacles**, rasterised into a :class:`~pathfuse.grid.GridMap`
  over the world's extent (``world.offset``, ``width`` x ``height``) at
  ``resolution_m`` (default :data:`DEFAULT_RESOLUTION_M`, 0.05 m).  A cell is
  occupied when an obstacle's IR-SIM geometry overlaps its square by more
  than :data:`pathfuse.io.shapes.OVERLAP_EPS_M` (the rule of
  :mod:`pathfuse.io.shapes`): convex shapes (rectangles, convex polygons and
  circles, which IR-SIM itself stores as 64-sided polygons) by the separating
  axis test, other polygons and line strings by shapely's exact predicates
  (their interiors meet), and the cells of a binary grid map (``obstacle_map``,
  values above 50) by exact interval overlap.  So the grid is exact for the
  geometry IR-SIM checks collisions against: every cell any obstacle reaches
  into is occupied, and no other.  The world's edge is a wall to pathfuse (to
  IR-SIM it is not).
* **The robot**: its kinematics (``diff`` -> pathfuse's diff-drive model, the
  action ``(v, omega)``; ``omni`` -> the holonomic model, a world-frame
  velocity), radius (a non-circular robot is planned as the disc of its
  circumscribed radius; a diff robot's radius grown by :func:`euler_margin_m`, the
  most IR-SIM's forward-Euler step can leave pathfuse's exact arcs over one stop, ours),
  velocity and acceleration limits (``vel_max``,
  ``vel_min``, ``acce``; an omni robot's per-axis limits become the smaller of
  the two as a bound on the vector), start, heading and goal (its
  ``goal_threshold`` is the goal tolerance).

What is sensed at every :meth:`IrsimController.act`
----------------------------------------------------
Every object that can move (not ``static``, not the grid map, not the robot
itself: walkers, other robots, pushable bodies) whose surface lies within the
robot's sensing radius, as a disc of its (circumscribed) radius, with the
velocity of its last displacement (the difference of its last two sensed
positions over the time between them; before a second state, the velocity
IR-SIM reports).  The robot's own velocity is sensed the same way, its last
applied command is read from IR-SIM.  The planner then sees the same
:class:`~pathfuse.world.Observation` as in pathfuse's own world, and its
command goes through the same safety shield and recovery behaviours.

The action returned is what ``env.step(action)`` expects: a ``(2, 1)`` array,
``[[v], [omega]]`` for a diff robot, ``[[forward], [lateral]]`` (IR-SIM's body
frame) for an omni robot.

Examples
--------
>>> import pathlib
>>> env = make_env(pathlib.Path(example_worlds_dir()) / "corridor_head_on.yaml")
>>> ctrl = IrsimController(env, planner="fusion")
>>> ctrl.scene.kinematics, ctrl.scene.grid.resolution
('diff', 0.05)
>>> # planned as a disc grown by the gap between IR-SIM's Euler step and the arcs
>>> r, m = ctrl.scene.robot.radius_m, ctrl.scene.euler_margin_m
>>> round(r - m, 6), round(m, 3)
(0.25, 0.022)
>>> a = ctrl.act(env)
>>> a.shape
(2, 1)
>>> env.step(a)
>>> bool(env.robot.collision)
False
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.integrations.irsim_robot import (
    DEFAULT_SENSING_RADIUS_M,
    KINEMATICS,
    _col,
    euler_margin_m,
    robot_model,
)
from pathfuse.planners.base import Controller
from pathfuse.result import ConfigError, Status
from pathfuse.robot import RobotModel

__all__ = ["IrsimController", "IrsimScene", "read_scene", "rasterise_static", "robot_model",
           "moving_objects", "import_irsim", "make_env", "example_worlds_dir",
           "DEFAULT_RESOLUTION_M", "DEFAULT_SENSING_RADIUS_M", "KINEMATICS"]

DEFAULT_RESOLUTION_M = 0.05
"""Side of the cells the static obstacles are rasterised into (m)."""


def import_irsim() -> Any:
    """The ``irsim`` module, imported quietly.

    IR-SIM picks a matplotlib backend on import and prints each one it cannot
    use; the prints are swallowed and the backend in use before is restored, so
    pathfuse's figures are drawn as before.

    Raises
    ------
    ConfigError
        IR-SIM is not installed (the message says how to install it).
    """
    import sys

    mod = sys.modules.get("irsim")
    if mod is not None:
        return mod
    import matplotlib

    before = matplotlib.get_backend()
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            import irsim
    except ImportError:
        raise ConfigError("IR-SIM is not installed: pip install 'pathfuse[irsim]' "
                          "(the PyPI package ir-sim)") from None
    finally:
        with contextlib.suppress(Exception):
            if matplotlib.get_backend() != before:
                matplotlib.use(before)
    return irsim


def make_env(world: str | os.PathLike[str], seed: int | None = None) -> Any:
    """An IR-SIM environment of the world file ``world``, headless and quiet (IR-SIM logs
    errors only).

    Raises
    ------
    ConfigError
        No such file, or IR-SIM cannot read it (the message names the file).
    """
    irsim = import_irsim()
    p = Path(os.path.expanduser(os.fspath(world)))
    if not p.is_file():
        raise ConfigError(f"{p}: no such IR-SIM world file")
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            env = irsim.make(str(p), display=False, headless=True, log_level="ERROR",
                             seed=seed)
    except Exception as exc:  # noqa: BLE001 - IR-SIM raises many kinds; one line names it
        raise ConfigError(f"{p}: IR-SIM cannot read this world: "
                          f"{type(exc).__name__}: {exc}") from None
    _check_group_behaviours(env, p)
    return env


def _check_group_behaviours(env: Any, path: Path) -> None:
    """Raise when a group of the world names a ``group_behavior`` that IR-SIM could not
    start: IR-SIM logs the error and leaves the group's members standing, which would make
    another world than the file describes (ORCA walkers without ``pyrvo``)."""
    try:
        from irsim.lib.behavior.behavior_registry import group_behaviors_class_map
    except ImportError:  # another IR-SIM layout: nothing to check against
        return
    for group in getattr(env, "_object_groups", None) or ():
        gb = getattr(group, "group_behavior", None)
        name = getattr(gb, "name", None)
        if name is None or getattr(gb, "_invoke_func", None) is not None:
            continue
        if (getattr(gb, "kinematics", None), name) not in group_behaviors_class_map:
            continue
        hint = " (IR-SIM's ORCA needs pyrvo: pip install pyrvo)" if name == "orca" else ""
        raise ConfigError(f"{path}: group_behavior {name!r} of a group of "
                          f"{getattr(group, 'number', '?')} objects could not start in IR-SIM"
                          f"{hint}; without it IR-SIM would leave them standing")


def example_worlds_dir() -> str:
    """The folder of the IR-SIM people worlds shipped with pathfuse (``examples/irsim`` of a
    clone; the copy installed with the package when there is one).

    >>> os.path.isfile(os.path.join(example_worlds_dir(), "corridor_head_on.yaml"))
    True
    """
    here = Path(__file__).resolve()
    for cand in (here.parent.parent / "examples" / "irsim",             # package data
                 here.parents[3] / "examples" / "irsim"):               # a clone: src/../
        if cand.is_dir():
            return str(cand)
    raise ConfigError("the IR-SIM example worlds are not installed with this copy of pathfuse "
                      "(they live in examples/irsim of the repository)")


# --------------------------------------------------------------------------- the static map
def _world(env: Any) -> Any:
    w = getattr(env, "_world", None)
    if w is None:
        raise ConfigError("env: not an IR-SIM environment (no world); build it with "
                          "irsim.make(...)")
    return w


def _convex_vertices(geom: Any) -> np.ndarray | None:
    """Counter-clockwise vertices of a convex polygon without holes (None otherwise)."""
    from shapely.geometry import Polygon
    from shapely.geometry.polygon import orient

    if not isinstance(geom, Polygon) or geom.is_empty or len(geom.interiors):
        return None
    hull = geom.convex_hull.area
    if hull - geom.area > 1e-12 * max(1.0, hull):
        return None
    return np.asarray(orient(geom, 1.0).exterior.coords, dtype=np.float64)[:-1]


def _add_exact(occ: np.ndarray, geom: Any, origin: tuple[float, float], res: float) -> None:
    """Mark the cells whose open square meets the interior of ``geom`` (shapely's exact
    predicates: they intersect and do not merely touch)."""
    import shapely

    from pathfuse.io.shapes import _cell_window

    win = _cell_window(occ, tuple(geom.bounds), origin, res)  # type: ignore[arg-type]
    if win is None:
        return
    r0, r1, c0, c1 = win
    xs = origin[0] + np.arange(c0, c1) * res
    ys = origin[1] + np.arange(r0, r1) * res
    gx, gy = np.meshgrid(xs, ys)
    boxes = shapely.box(gx, gy, gx + res, gy + res)
    hit = shapely.intersects(boxes, geom) & ~shapely.touches(boxes, geom)
    occ[r0:r1, c0:c1] |= hit


def _add_grid_map(occ: np.ndarray, world: Any, origin: tuple[float, float], res: float) -> None:
    """Mark the cells that overlap an occupied cell of the world's grid map by more than
    the overlap tolerance (exact interval arithmetic on both grids)."""
    from pathfuse.io.shapes import OVERLAP_EPS_M as eps

    g = getattr(world, "grid_map", None)
    if g is None:
        return
    mask = np.asarray(g) > 50.0  # IR-SIM's occupancy threshold; indexed [i (x), j (y)]
    if not mask.any():
        return
    rx, ry = float(world.reso[0, 0]), float(world.reso[1, 0])
    wx0, wy0 = float(world.offset[0]), float(world.offset[1])
    nx, ny = mask.shape
    h, w = occ.shape
    x0 = origin[0] + np.arange(w) * res
    y0 = origin[1] + np.arange(h) * res
    i_lo = np.clip(np.floor((x0 - wx0 + eps) / rx), 0, nx).astype(np.int64)
    i_hi = np.clip(np.ceil((x0 + res - wx0 - eps) / rx), 0, nx).astype(np.int64)  # exclusive
    j_lo = np.clip(np.floor((y0 - wy0 + eps) / ry), 0, ny).astype(np.int64)
    j_hi = np.clip(np.ceil((y0 + res - wy0 - eps) / ry), 0, ny).astype(np.int64)
    s = np.zeros((nx + 1, ny + 1), dtype=np.int64)
    s[1:, 1:] = mask.astype(np.int64).cumsum(0).cumsum(1)
    # rows of occ run along y (j), columns along x (i)
    cnt = (s[i_hi[None, :], j_hi[:, None]] - s[i_lo[None, :], j_hi[:, None]]
           - s[i_hi[None, :], j_lo[:, None]] + s[i_lo[None, :], j_lo[:, None]])
    ok = (i_hi > i_lo)[None, :] & (j_hi > j_lo)[:, None]
    occ |= (cnt > 0) & ok


def rasterise_static(env: Any, resolution_m: float = DEFAULT_RESOLUTION_M,
                     exclude: tuple[int, ...] = ()) -> GridMap:
    """The static obstacles of ``env`` as a :class:`~pathfuse.grid.GridMap` over the world's
    extent (see the module docstring for the rule; ``exclude``: object ids left out).

    Raises
    ------
    ConfigError
        A resolution that is not a number > 0, or one that leaves fewer than two cells
        across the world.
    """
    from pathfuse.io.shapes import add_polygon

    if isinstance(resolution_m, bool) or not isinstance(resolution_m, (int, float)) \
            or not math.isfinite(resolution_m) or resolution_m <= 0:
        raise ConfigError(f"resolution_m: must be a number > 0 (metres), got {resolution_m!r}")
    world = _world(env)
    res = float(resolution_m)
    ox, oy = float(world.offset[0]), float(world.offset[1])
    w = int(math.ceil(float(world.width) / res - 1e-9))
    h = int(math.ceil(float(world.height) / res - 1e-9))
    if w < 2 or h < 2:
        raise ConfigError(f"resolution_m: {res:g} m leaves {w} x {h} cells across the "
                          f"{float(world.width):g} m x {float(world.height):g} m world")
    occ = np.zeros((h, w), dtype=bool)
    origin = (ox, oy)
    for obj in env.objects:
        if obj.id in exclude or not obj.static or obj.shape == "map":
            continue
        geom = obj.geometry
        parts = list(getattr(geom, "geoms", [geom]))
        for part in parts:
            v = _convex_vertices(part)
            if v is not None and v.shape[0] >= 3:
                add_polygon(occ, v, origin, res)
            elif not part.is_empty:
                _add_exact(occ, part, origin, res)
    _add_grid_map(occ, world, origin, res)
    return GridMap(occ, res, origin, name=str(getattr(world, "name", "irsim")))


# --------------------------------------------------------------------------- the robot
def _robot_object(env: Any, robot: int) -> Any:
    robots = list(getattr(env, "robot_list", []))
    if isinstance(robot, bool) or not isinstance(robot, (int, np.integer)) \
            or not 0 <= int(robot) < len(robots):
        raise ConfigError(f"robot: no robot {robot!r} in this IR-SIM env ({len(robots)} "
                          f"robot{'s' if len(robots) != 1 else ''}: indices 0.."
                          f"{len(robots) - 1})" if robots else
                          "robot: this IR-SIM env has no robot (add a robot: block)")
    return robots[int(robot)]


@dataclass(frozen=True)
class IrsimScene:
    """What the adapter read once from an IR-SIM environment.

    Attributes
    ----------
    grid : GridMap
        The static obstacles, rasterised (see the module docstring).
    start, goal : (float, float)
        The robot's position at construction and its (first) goal, metres.
    goal_tolerance_m : float
        The robot's ``goal_threshold``.
    robot : RobotModel
        The robot as pathfuse models it.
    kinematics : {"diff", "omni"}
        IR-SIM's kinematics of the robot.
    dt_s : float
        IR-SIM's ``step_time``.
    robot_id : int
        The IR-SIM object id of the robot.
    euler_margin_m : float
        How much ``robot.radius_m`` was grown over IR-SIM's radius for the gap between
        IR-SIM's Euler step and pathfuse's arcs (:func:`euler_margin_m`; 0 for omni).
    """

    grid: GridMap
    start: tuple[float, float]
    goal: tuple[float, float]
    goal_tolerance_m: float
    robot: RobotModel
    kinematics: str
    dt_s: float
    robot_id: int
    euler_margin_m: float = 0.0


def read_scene(env: Any, robot: int = 0, resolution_m: float = DEFAULT_RESOLUTION_M,
               sensing_radius_m: float = DEFAULT_SENSING_RADIUS_M,
               robot_overrides: Mapping[str, Any] | None = None) -> IrsimScene:
    """Read the static map, the robot and its goal of ``env`` once (:class:`IrsimScene`)."""
    obj = _robot_object(env, robot)
    goal = getattr(obj, "goal", None)
    if goal is None:
        raise ConfigError(f"robot {obj.name!r}: has no goal (give it goal: [x, y, theta] in "
                          "the world file)")
    model = robot_model(obj, sensing_radius_m, **dict(robot_overrides or {}))
    step = float(_world(env).step_time)
    margin = euler_margin_m(model, step) if obj.kinematics == "diff" else 0.0
    if margin > 0.0:
        model = model.replace(radius_m=model.radius_m + margin)
    grid = rasterise_static(env, resolution_m, exclude=(obj.id,))
    g = _col(goal)
    return IrsimScene(grid, (float(obj.state[0, 0]), float(obj.state[1, 0])),
                      (float(g[0]), float(g[1])), float(obj.goal_threshold), model,
                      str(obj.kinematics), step, int(obj.id), margin)


def moving_objects(env: Any, robot_id: int) -> list[Any]:
    """The objects of ``env`` that can move, the robot ``robot_id`` and the map left out."""
    return [o for o in env.objects
            if o.id != robot_id and not o.static and o.shape != "map"]


# --------------------------------------------------------------------------- the controller
@dataclass
class _Track:
    """The last sensed state of the moving objects, by id."""

    count: int = -1
    positions: dict[int, tuple[float, float]] = field(default_factory=dict)
    velocities: dict[int, tuple[float, float]] = field(default_factory=dict)


class IrsimController:
    """An online planner of pathfuse driving robot ``robot`` of an IR-SIM env.

    Parameters
    ----------
    env : irsim EnvBase
        The environment (``irsim.make(...)``), at the state the robot starts from.
    planner : str
        An online planner of :func:`pathfuse.planner_names` (``pathfuse planners``).
    robot : int
        Index of the robot in ``env.robot_list``.
    resolution_m : float
        Cell side of the static map (m).
    sensing_radius_m : float
        Moving objects whose surface comes this close to the robot's centre are sensed.
    robot_overrides : mapping, optional
        Fields of :class:`pathfuse.robot.RobotModel` to set beyond what IR-SIM says
        (``clearance_m``, ``inflation_m``, ``shield``, ``recovery``, ...).
    **params
        The planner's parameters (as for :func:`pathfuse.plan`).

    Attributes
    ----------
    scene : IrsimScene
        What was read once.
    controller : pathfuse.planners.base.Controller
        The planner's controller (its ``global_path``, ``shield_counts``, ...).
    act_times_s : list of float
        Wall-clock time of every :meth:`act` (sensing, planning and conversion).
    command_times_s : list of float
        Of which the planner's command (:meth:`Controller.command`, with its shield); the
        rest is what the adapter adds.

    Raises
    ------
    ConfigError
        An unknown planner or parameter, a robot index or kinematics the adapter cannot
        drive, a robot without a goal (the message names it).
    """

    def __init__(self, env: Any, planner: str = "fusion", robot: int = 0, *,
                 resolution_m: float = DEFAULT_RESOLUTION_M,
                 sensing_radius_m: float = DEFAULT_SENSING_RADIUS_M,
                 robot_overrides: Mapping[str, Any] | None = None, **params: Any) -> None:
        from pathfuse.planners.registry import get_planner, make_params
        from pathfuse.planners.run import Stopped, start_online
        from pathfuse.problem import Problem
        from pathfuse.world.episode import warm_online

        spec = get_planner(planner)
        if not spec.online:
            raise ConfigError(f"planner {spec.name!r} only plans offline; the adapter needs an "
                              "online planner")
        cfg = make_params(spec, params)
        self.planner = spec.name
        self.params = cfg
        self.scene = read_scene(env, robot, resolution_m, sensing_radius_m, robot_overrides)
        sc = self.scene
        model = sc.robot
        self.problem = Problem.create(sc.grid, sc.start, sc.goal, model.radius_m,
                                      clearance_m=model.clearance_m, robot=model)
        # what a pathfuse episode warms (the robot model's kernels, the shield, a warm-up
        # episode among discs), so that no IR-SIM step's decision holds a compile
        warm_online(spec, model, cfg)
        bad = self.problem.failure()
        t0 = time.perf_counter()
        self.controller: Controller
        if bad is not None:
            self.controller = Stopped(self.problem, cfg, bad[0], bad[1])
        else:
            self.controller = start_online(spec, self.problem, cfg, sc.dt_s,
                                           model.max_speed_mps)
        self.setup_time_s = time.perf_counter() - t0
        self.act_times_s: list[float] = []
        self.command_times_s: list[float] = []
        self._track = _Track()
        self._robot_prev: tuple[float, float] | None = None
        self._robot_vel = np.zeros(2)
        self._tick = 0
        gx, gy = sc.goal[0] - sc.start[0], sc.goal[1] - sc.start[1]
        self._heading = math.atan2(gy, gx) if (gx or gy) else 0.0

    # ------------------------------------------------------------------ state
    @property
    def failure(self) -> tuple[Status, str] | None:
        """``(status, reason)`` once the controller gave up (no global path, ...), else None."""
        return self.controller.failure

    @property
    def global_path(self) -> np.ndarray | None:
        """The path the controller follows (None for a planner without one)."""
        return self.controller.global_path

    def _robot(self, env: Any) -> Any:
        for o in env.robot_list:
            if o.id == self.scene.robot_id:
                return o
        raise ConfigError(f"env: the robot (IR-SIM id {self.scene.robot_id}) is no longer in "
                          "the environment")

    def observe(self, env: Any) -> Any:
        """The :class:`~pathfuse.world.Observation` of the current state of ``env``."""
        from pathfuse.world.world import Observation, SensedObstacles

        rb = self._robot(env)
        sc = self.scene
        count = int(_world(env).count)
        tr = self._track
        elapsed = (count - tr.count) * sc.dt_s if tr.count >= 0 else 0.0
        x, y = float(rb.state[0, 0]), float(rb.state[1, 0])
        heading = float(rb.state[2, 0])
        if elapsed > 0 and self._robot_prev is not None:
            self._robot_vel = np.array([(x - self._robot_prev[0]) / elapsed,
                                        (y - self._robot_prev[1]) / elapsed])
        self._robot_prev = (x, y)
        vel = _col(rb.velocity)
        if sc.kinematics == "diff":
            command = np.array([float(vel[0]), float(vel[1])])
        else:  # IR-SIM's body frame -> the world's; the heading is that of the last motion
            c, s = math.cos(heading), math.sin(heading)
            command = np.array([c * vel[0] - s * vel[1], s * vel[0] + c * vel[1]])
            if command.any():
                self._heading = math.atan2(command[1], command[0])
            heading = self._heading
        movers = moving_objects(env, sc.robot_id)
        n = len(movers)
        ids = np.empty(n, dtype=np.int64)
        pos = np.empty((n, 2))
        velo = np.empty((n, 2))
        rad = np.empty(n)
        new_pos: dict[int, tuple[float, float]] = {}
        new_vel: dict[int, tuple[float, float]] = {}
        for j, o in enumerate(movers):
            k = int(o.id)
            px, py = float(o.state[0, 0]), float(o.state[1, 0])
            prev = tr.positions.get(k)
            if prev is not None and elapsed > 0:
                v = ((px - prev[0]) / elapsed, (py - prev[1]) / elapsed)
            elif prev is not None:
                v = tr.velocities[k]
            else:
                vxy = _col(o.velocity_xy)
                v = (float(vxy[0]), float(vxy[1]))
            ids[j], pos[j], velo[j], rad[j] = k, (px, py), v, float(o.radius)
            new_pos[k], new_vel[k] = (px, py), v
        tr.positions, tr.velocities, tr.count = new_pos, new_vel, count
        if n:
            d = np.hypot(pos[:, 0] - x, pos[:, 1] - y) - rad
            keep = d <= sc.robot.sensing_radius_m
            sensed = SensedObstacles(ids[keep], pos[keep], velo[keep], rad[keep])
        else:
            sensed = SensedObstacles(ids, pos, velo, rad)
        return Observation(self._tick, count * sc.dt_s, np.array([x, y]),
                           self._robot_vel.copy(), np.array(sc.goal), sensed, heading,
                           command)

    def act(self, env: Any) -> np.ndarray:
        """The action for this step of ``env``: a ``(2, 1)`` array for ``env.step`` (zero once
        the controller gave up, see :attr:`failure`)."""
        t0 = time.perf_counter()
        obs = self.observe(env)
        t1 = time.perf_counter()
        if self.controller.failure is not None:
            a = np.zeros(2)
        else:
            a = np.asarray(self.controller.command(obs), dtype=np.float64).reshape(-1)
        self.command_times_s.append(time.perf_counter() - t1)
        if self.scene.kinematics == "omni":  # world velocity -> IR-SIM's body frame
            th = float(self._robot(env).state[2, 0])
            c, s = math.cos(th), math.sin(th)
            a = np.array([c * a[0] + s * a[1], -s * a[0] + c * a[1]])
        self._tick += 1
        self.act_times_s.append(time.perf_counter() - t0)
        return a.reshape(2, 1)
