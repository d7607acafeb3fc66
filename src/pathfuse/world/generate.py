"""Seeded families of dynamic scenarios for benchmarks.

:func:`generate_scenarios` draws ``n`` scenarios with ``K`` moving discs
each: by default on the paper's map family (15 m x 15 m, 50 random cells, a
new map seed per scenario, start ``(1, 1)``, goal ``(11, 11)``), with disc
speeds drawn uniformly from ``speed_range``.  Everything comes from
``numpy.random.default_rng([seed, i])`` for scenario ``i``, so the same
arguments give the same scenarios, and scenario ``i`` does not depend on
``n_scenarios``.

Placement (``placement``):

``"route"`` (default)
    Discs are aimed at the robot's route: a point is drawn on the static A*
    path (between 20 % and 80 % of its length), the disc starts 1.5-4 m away
    from it on a random side and heads for it (linear), patrols across it
    (patrol: the start and its mirror image through the route point), or
    starts there (random walk).  So most discs cross the route, as moving
    obstacles in a benchmark should.
``"uniform"``
    Discs start at uniformly drawn free points, heading in random directions.

Every disc starts clear of occupied cells and the map's edge, at least
``min_start_gap_m`` (surface to surface) from the robot's start, and
``min_goal_gap_m`` from the goal; patrol legs are free for the disc.  A
placement that fails these checks is drawn again (up to 200 times per disc,
then a ``ConfigError``).

Examples
--------
>>> scs = generate_scenarios(3, moving=2, speed_range=(0.3, 0.6), seed=5)
>>> [len(s.obstacles) for s in scs], scs[0].start, scs[0].goal
([2, 2, 2], (1.0, 1.0), (11.0, 11.0))
>>> again = generate_scenarios(3, moving=2, speed_range=(0.3, 0.6), seed=5)
>>> [s.to_dict() for s in scs] == [s.to_dict() for s in again]
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pathfuse.costmap import costmap_for, point_clear, segment_clear
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.grid import GridMap
from pathfuse.limits import LimitError, env_name, limit
from pathfuse.planners.globals.astar import route as global_route
from pathfuse.result import ConfigError
from pathfuse.robot import RobotModel
from pathfuse.validate import short as _shown
from pathfuse.world.obstacles import (
    LinearObstacle,
    ObstacleSpec,
    PatrolObstacle,
    RandomWalkObstacle,
)
from pathfuse.world.scenario import Scenario, ScenarioError, resolve_planner_choice

__all__ = ["generate_scenarios", "KINDS", "PLACEMENTS"]

KINDS = ("linear", "patrol", "random_walk")
"""Obstacle kinds the generator draws from."""
PLACEMENTS = ("route", "uniform")
_ATTEMPTS = 200


def _pair(v: Any, name: str, lo: float) -> tuple[float, float]:
    try:
        a, b = (float(x) for x in v)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be two numbers (low, high), got {_shown(v)}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a < lo or b < a:
        raise ConfigError(f"{name} must satisfy {lo:g} <= low <= high, got {_shown(v)}")
    return a, b


def _disc_ok(grid: GridMap, p: np.ndarray, r: float) -> bool:
    """A disc of radius ``r`` at ``p`` is clear of the occupied squares and the outside."""
    return bool(point_clear(costmap_for(grid, 0.0, lattice=False), float(p[0]), float(p[1]), r))


def _leg_ok(grid: GridMap, a: np.ndarray, b: np.ndarray, r: float) -> bool:
    """A disc of radius ``r`` moving straight from ``a`` to ``b`` touches nothing static."""
    return bool(segment_clear(costmap_for(grid, 0.0, lattice=False), float(a[0]), float(a[1]),
                              float(b[0]), float(b[1]), r))


def _random_free_point(rng: np.random.Generator, grid: GridMap, r: float) -> np.ndarray:
    x0, y0, x1, y1 = grid.bounds
    for _ in range(_ATTEMPTS):
        p = np.array([rng.uniform(x0 + r, x1 - r), rng.uniform(y0 + r, y1 - r)])
        if _disc_ok(grid, p, r):
            return p
    raise ConfigError(f"found no free spot for a disc of radius {r:g} m on map {_shown(grid.name)}")


def _xy(v: np.ndarray) -> tuple[float, float]:
    """A 2-vector as a pair of Python floats."""
    return float(v[0]), float(v[1])


def _point_on(path: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray]:
    """Point at arc length ``s`` along ``path`` and the unit tangent there."""
    seg = np.hypot(*np.diff(path, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    i = int(np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1))
    t = (path[i + 1] - path[i]) / max(seg[i], 1e-12)
    f = (s - cum[i]) / max(seg[i], 1e-12)
    return path[i] + f * (path[i + 1] - path[i]), t


def _draw_obstacle(rng: np.random.Generator, grid: GridMap, kind: str, speed: float,
                   radius: float, route: np.ndarray | None, placement: str,
                   ob_seed: int) -> ObstacleSpec:
    if placement == "route" and route is not None and len(route) >= 2:
        total = float(np.hypot(*np.diff(route, axis=0).T).sum())
        q, t = _point_on(route, rng.uniform(0.2, 0.8) * total)
        normal = np.array([-t[1], t[0]]) * (1.0 if rng.random() < 0.5 else -1.0)
        # aim across the route, give or take 30 degrees
        ang = rng.uniform(-math.pi / 6, math.pi / 6)
        c, s = math.cos(ang), math.sin(ang)
        d = np.array([c * normal[0] - s * normal[1], s * normal[0] + c * normal[1]])
        p = q + rng.uniform(1.5, 4.0) * d
        if kind == "linear":
            return LinearObstacle(_xy(p), _xy(-d * speed), radius)
        if kind == "patrol":
            p2 = 2.0 * q - p
            return PatrolObstacle((_xy(p), _xy(p2)), speed, radius, loop=False)
        return RandomWalkObstacle(_xy(q), speed, radius, seed=ob_seed,
                                  heading=float(math.atan2(-d[1], -d[0])))
    p = _random_free_point(rng, grid, radius)
    h = rng.uniform(-math.pi, math.pi)
    if kind == "linear":
        return LinearObstacle(_xy(p), (speed * math.cos(h), speed * math.sin(h)), radius)
    if kind == "patrol":
        p2 = _random_free_point(rng, grid, radius)
        return PatrolObstacle((_xy(p), _xy(p2)), speed, radius, loop=False)
    return RandomWalkObstacle(_xy(p), speed, radius, seed=ob_seed, heading=h)


def _valid(grid: GridMap, ob: ObstacleSpec, start: np.ndarray, goal: np.ndarray,
           robot_r: float, min_start_gap: float, min_goal_gap: float) -> bool:
    pts = [np.asarray(w) for w in ob.waypoints] if isinstance(ob, PatrolObstacle) \
        else [np.asarray(ob.position)]
    x0, y0, x1, y1 = grid.bounds
    for p in pts:
        if not (x0 <= p[0] < x1 and y0 <= p[1] < y1) or not _disc_ok(grid, p, ob.radius):
            return False
    if isinstance(ob, PatrolObstacle) and not _leg_ok(grid, pts[0], pts[1], ob.radius):
        return False
    p0 = pts[0]
    if np.hypot(*(p0 - start)) - ob.radius - robot_r < min_start_gap:
        return False
    return bool(np.hypot(*(p0 - goal)) - ob.radius - robot_r >= min_goal_gap)


def check_body_ticks(time_limit: Any, dt: Any, moving: int, key: str = "moving") -> None:
    """Refuse episodes of more than ``MAX_TICKS`` body-ticks (``time_limit / dt x (1 +
    moving)``) before any disc is placed; values that are not numbers are left to the
    scenario's own checks."""
    try:
        steps = float(time_limit) / float(dt) * (1 + int(moving))
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        return
    cap = limit("MAX_TICKS")
    if steps > cap:
        raise LimitError(
            f"{key}: {int(moving)} moving discs over {float(time_limit):g} s in ticks of "
            f"{float(dt):g} s are {steps:.3g} body-ticks, above the limit of {cap} (MAX_TICKS; "
            f"set the environment variable {env_name('MAX_TICKS')} to raise it)")


def generate_scenarios(
    n_scenarios: int,
    moving: int = 3,
    speed_range: Sequence[float] = (0.2, 0.8),
    seed: int = 0,
    map: Mapping[str, Any] | GridMap | None = None,  # noqa: A002 - the scenario key's name
    start: Sequence[float] | None = None,
    goal: Sequence[float] | None = None,
    kinds: Sequence[str] = KINDS,
    radius_range: Sequence[float] = (0.2, 0.4),
    placement: str = "route",
    robot: RobotModel | Mapping[str, Any] | None = None,
    dt: float = 0.1,
    time_limit: float = 60.0,
    goal_tolerance: float = 0.25,
    planner: Any = "fusion",
    min_start_gap_m: float = 1.0,
    min_goal_gap_m: float = 0.5,
    name: str = "generated",
    first: int = 0,
) -> list[Scenario]:
    """A deterministic family of dynamic scenarios.

    Parameters
    ----------
    n_scenarios : int
        How many scenarios.
    moving : int
        Moving discs per scenario.
    speed_range : (float, float)
        Disc speeds are drawn uniformly from ``[low, high]`` (m/s).
    seed : int
        Master seed; scenario ``i`` uses ``default_rng([seed, i])``.
    map : map spec, GridMap or None
        None: the paper's map family, a fresh ``{paper: {seed}}`` per
        scenario.  Otherwise one fixed map for every scenario (a spec as in a
        scenario file, or a :class:`~pathfuse.grid.GridMap`).
    start, goal : (float, float), optional
        Default: the paper's ``(1, 1)`` and ``(11, 11)`` on the paper family;
        on another map, drawn per scenario (free, connected for the robot,
        at least half the map's diagonal apart when possible).
    kinds : sequence of {"linear", "patrol", "random_walk"}
        Kinds to draw from (uniformly).
    radius_range : (float, float)
        Disc radii are drawn from it.
    placement : {"route", "uniform"}
        See the module docstring.
    robot : RobotModel or mapping, optional
        Default ``RobotModel()`` (radius 0.2 m, 1 m/s, sensing 3 m, holonomic);
        a mapping is read as a scenario's ``robot:`` block.
    dt, time_limit, goal_tolerance : float
        As in a scenario file.
    planner : str or mapping
        The planner written into each scenario.
    min_start_gap_m, min_goal_gap_m : float
        Least initial gap between a disc and the robot at the start / at the goal.
    name : str
        Scenario names are ``f"{name}-{seed}-{i}"``.
    first : int
        Index of the first scenario: ``generate_scenarios(1, first=i)`` is
        scenario ``i`` of the family, without drawing the ones before it.

    Returns
    -------
    list of Scenario
    """
    if isinstance(n_scenarios, bool) or not isinstance(n_scenarios, (int, np.integer)) \
            or n_scenarios < 0:
        raise ConfigError(f"n_scenarios must be an integer >= 0, got {_shown(n_scenarios)}")
    if isinstance(moving, bool) or not isinstance(moving, (int, np.integer)) or moving < 0:
        raise ConfigError(f"moving must be an integer >= 0, got {_shown(moving)}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"seed must be an integer >= 0, got {_shown(seed)}")
    v_lo, v_hi = _pair(speed_range, "speed_range", 0.0)
    r_lo, r_hi = _pair(radius_range, "radius_range", 0.0)
    if r_lo <= 0:
        raise ConfigError(f"radius_range must be > 0, got {_shown(radius_range)}")
    kinds = tuple(kinds)
    if not kinds or any(k not in KINDS for k in kinds):
        raise ConfigError(f"kinds must be a non-empty subset of {', '.join(KINDS)}, "
                          f"got {_shown(kinds)}")
    if placement not in PLACEMENTS:
        raise ConfigError(f"placement must be one of {', '.join(PLACEMENTS)}, "
                          f"got {_shown(placement)}")
    check_body_ticks(time_limit, dt, moving)  # before placing any disc
    if isinstance(robot, Mapping):
        robot = RobotModel.from_dict(dict(robot), ConfigError)
    robot = robot or RobotModel()
    choice = resolve_planner_choice(planner)
    fixed_grid: GridMap | None = None
    fixed_spec: Any = None
    if isinstance(map, GridMap):
        fixed_grid = map
    elif map is not None:
        from pathfuse.io import map_from_spec

        fixed_grid = map_from_spec(map)
        fixed_spec = dict(map)

    out = []
    for i in range(int(first), int(first) + int(n_scenarios)):
        rng = np.random.default_rng([int(seed), i])
        if fixed_grid is None:
            map_seed = int(rng.integers(0, 2**31 - 1))
            grid = paper_map(map_seed)
            mspec: Any = {"paper": {"seed": map_seed}}
            s = np.array(PAPER_START if start is None else start, dtype=np.float64)
            g = np.array(PAPER_GOAL if goal is None else goal, dtype=np.float64)
        else:
            grid, mspec = fixed_grid, fixed_spec
            s, g = _start_goal(rng, grid, robot.radius_m, start, goal)
        route = global_route(grid, s, g, robot.radius_m)
        obstacles: list[ObstacleSpec] = []
        for j in range(int(moving)):
            for _ in range(_ATTEMPTS):
                kind = kinds[int(rng.integers(len(kinds)))]
                ob = _draw_obstacle(rng, grid, kind, float(rng.uniform(v_lo, v_hi)),
                                    float(rng.uniform(r_lo, r_hi)), route, placement,
                                    ob_seed=int(rng.integers(0, 2**31 - 1)))
                if _valid(grid, ob, s, g, robot.radius_m, min_start_gap_m, min_goal_gap_m):
                    obstacles.append(ob)
                    break
            else:
                raise ConfigError(
                    f"scenario {i}: could not place moving obstacle {j} after {_ATTEMPTS} "
                    f"draws (map {_shown(grid.name)} too cluttered?)")
        try:
            sc = Scenario(grid=grid, start=(float(s[0]), float(s[1])),
                          goal=(float(g[0]), float(g[1])), robot=robot, dt=float(dt),
                          time_limit=float(time_limit), goal_tolerance=float(goal_tolerance),
                          obstacles=tuple(obstacles), planner=choice, seed=None,
                          name=f"{name}-{seed}-{i}", map_spec=mspec,
                          description=f"generated: seed {seed}, index {i}, {moving} moving "
                                      f"discs at {v_lo:g}-{v_hi:g} m/s, {placement} placement")
        except ScenarioError as exc:
            raise ConfigError(f"scenario {i}: {exc}") from None
        out.append(sc)
    return out


def _start_goal(rng: np.random.Generator, grid: GridMap, r: float, start: Any,
                goal: Any) -> tuple[np.ndarray, np.ndarray]:
    if start is not None and goal is not None:
        return np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    x0, y0, x1, y1 = grid.bounds
    want = 0.5 * math.hypot(x1 - x0, y1 - y0)
    best = None
    for _ in range(_ATTEMPTS):
        s = np.asarray(start, dtype=np.float64) if start is not None \
            else _random_free_point(rng, grid, r)
        g = np.asarray(goal, dtype=np.float64) if goal is not None \
            else _random_free_point(rng, grid, r)
        d = float(np.hypot(*(g - s)))
        if best is not None and d <= best[0]:
            continue
        if global_route(grid, s, g, r) is None:
            continue
        best = (d, s, g)
        if d >= want:
            break
    if best is None:
        raise ConfigError(f"found no connected start and goal for the robot on map"
                          f" {_shown(grid.name)}")
    return best[1], best[2]
