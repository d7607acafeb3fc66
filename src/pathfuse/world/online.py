"""Online planners: one velocity per tick from what the robot senses now.

Every online planner knows the static map, the start, the goal and the robot
from the start (a :class:`PlannerContext`), and sees the moving discs only
through each tick's :class:`~pathfuse.world.world.Observation` (those inside
the sensing radius, now).  It answers each observation with a velocity
``(vx, vy)``; the world clips it to the speed limit.

Registered planners (:data:`ONLINE_REGISTRY`, :func:`online_planner_names`):

``fusion``
    The paper's Algorithm 2 run online.  A* on the static map (inflated by
    the robot radius, no corner cutting) once at reset; each tick the
    resultant of :func:`pathfuse.field.stepper.fusion_force` (goal + A* path
    points ahead within ``r1``, eq. 9; static repulsion, eq. 6) plus the
    repulsion of the sensed discs within ``r2``, followed by one
    :func:`~pathfuse.field.stepper.safe_step` of ``max_speed * dt``.
``apf``
    Plain APF online: :func:`~pathfuse.field.stepper.apf_force` plus the
    sensed discs' repulsion, same step.
``astar-follow``
    The static A* path walked at full speed, blind to moving discs (the
    paper's "A* cannot handle dynamic obstacles", made measurable).
``astar-replan``
    A* replanned every ``replan_period_s`` (default 1 s, as Nav2's default
    behaviour tree replans at 1 Hz) on the static c-space plus the sensed
    discs rasterised as blocked cells; the path walked at full speed in
    between.  When no path exists the robot waits for the next replan.
``ref6``, ``ref7``
    The two reference methods online (see :mod:`pathfuse.world.refs`).

Repulsion of a moving disc
--------------------------
The distance in eq. 6 is the *gap* between the robot disc and the obstacle
disc (centre distance minus both radii), clamped below at 1 mm.

* ``repulsion: "position"`` (default): eq. 6 with gain ``k_rep_moving`` and
  range ``rho0_moving_m``, pointing from the disc to the robot.
* ``repulsion: "velocity"``: the velocity-aware repulsion of Ge and Cui
  (2002, "Dynamic motion planning for mobile robots using potential field
  method", Autonomous Robots 13), our reading of it: with ``v_ro`` the
  closing speed (relative velocity of the robot with respect to the disc
  along the line towards it) and ``rho_m = v_ro^2 / (2 a_max)`` the braking
  distance, a disc the robot is not approaching (``v_ro <= 0``) or whose
  braking-corrected gap ``gap - rho_m`` exceeds the range repels nothing;
  otherwise ``F1 = k (1 + v_ro / a_max) / (gap - rho_m)^2`` away from the
  disc plus ``F2 = k v_ro v_perp / (gap a_max (gap - rho_m)^2)`` along the
  perpendicular part of the relative velocity (which speeds up passing).
* ``swerve`` (ours, not in the paper; 0 turns it off): a tangential push of
  ``swerve`` times the radial one, scaled by how far ahead the disc is
  (cosine of the angle between the intended motion and the direction to the
  disc, when positive), towards the side away from the disc - to the
  robot's right for a disc dead ahead.  Pure radial repulsion is collinear
  with the attraction for a disc coming head on along the route, so the
  robot can only back off; the tangential part breaks that symmetry.

Examples
--------
>>> sorted(online_planner_names())
['apf', 'astar-follow', 'astar-replan', 'fusion', 'ref6', 'ref7']
>>> make_online_params(get_online_planner("fusion"), {"k_att": 0}, key="planner.params")
Traceback (most recent call last):
...
pathfuse.result.ConfigError: planner.params.k_att: must be a number > 0, got 0
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from pathfuse.field.forces import K_ATT, K_REP, RHO0_M, rep_force_xy
from pathfuse.field.stepper import (
    AHEAD_PAPER_X,
    AHEAD_PROGRESS,
    MARGIN_FRAC,
    advance_progress,
    apf_force,
    fusion_force,
    safe_step,
    segment_is_clear,
)
from pathfuse.grid import GridMap
from pathfuse.result import ConfigError
from pathfuse.search.astar import AStarSearcher, get_searcher
from pathfuse.world.geometry import segment_static_distance
from pathfuse.world.scenario import PlannerChoice, RobotSpec

__all__ = [
    "PlannerContext",
    "OnlinePlanner",
    "OnlinePlannerSpec",
    "ONLINE_REGISTRY",
    "register_online",
    "get_online_planner",
    "online_planner_names",
    "make_online_params",
    "resolve_planner_choice",
    "robot_cspace",
    "global_astar_path",
    "disc_repulsion",
    "FusionOnlineParams",
    "APFOnlineParams",
    "AStarFollowParams",
    "AStarReplanParams",
]

GAP_MIN_M = 1e-3
"""Gaps below this (metres) are clamped in the moving-disc repulsion."""
SIDE_SPEED = 0.05
"""Sideways disc speed (m/s) above which the swerve passes behind the disc."""


# ---------------------------------------------------------------------- context & base class
@dataclass(frozen=True, eq=False)
class PlannerContext:
    """What an online planner knows before the first tick (never the moving discs)."""

    grid: GridMap
    start: np.ndarray
    goal: np.ndarray
    robot: RobotSpec
    dt: float
    goal_tolerance: float


class OnlinePlanner:
    """Base class: ``reset(ctx)`` once, then ``act(observation) -> (vx, vy)`` per tick.

    Attributes
    ----------
    name : str
        Registry name.
    params : dataclass
        The planner's parameters.
    global_path : (N, 2) array or None
        The global path the planner currently follows (a new array object
        each time it changes, so the runner can record replans).
    failure : (str, str) or None
        Set to ``("no_path", message)`` or ``("stuck", message)`` when the
        planner gives up; the runner ends the episode with ``NO_PATH`` or
        ``LOCAL_MINIMUM``.
    """

    name = ""

    def __init__(self, params: Any) -> None:
        self.params = params
        self.global_path: np.ndarray | None = None
        self.failure: tuple[str, str] | None = None
        self.ctx: PlannerContext | None = None

    def warmup(self) -> None:
        """Compile the numba kernels the planner uses (kept out of the timings)."""
        warmup_online()

    def reset(self, ctx: PlannerContext) -> None:
        self.ctx = ctx
        self.global_path = None
        self.failure = None

    def act(self, obs: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


# ---------------------------------------------------------------------- registry
@dataclass(frozen=True)
class OnlinePlannerSpec:
    """A registered online planner: ``factory(params) -> OnlinePlanner``."""

    name: str
    factory: Callable[[Any], OnlinePlanner]
    params_cls: type
    description: str

    def defaults(self) -> dict[str, Any]:
        return dataclasses.asdict(self.params_cls())


ONLINE_REGISTRY: dict[str, OnlinePlannerSpec] = {}


def register_online(spec: OnlinePlannerSpec) -> OnlinePlannerSpec:
    """Add ``spec`` to :data:`ONLINE_REGISTRY` (a later registration replaces it)."""
    ONLINE_REGISTRY[spec.name] = spec
    return spec


def _load_builtin() -> None:
    import pathfuse.world.refs  # noqa: F401 - registers ref6 and ref7


def online_planner_names() -> list[str]:
    """Names of the registered online planners."""
    _load_builtin()
    return list(ONLINE_REGISTRY)


def get_online_planner(name: str) -> OnlinePlannerSpec:
    """The spec registered under ``name``; :class:`ConfigError` listing the choices otherwise."""
    _load_builtin()
    try:
        return ONLINE_REGISTRY[name]
    except (KeyError, TypeError):
        raise ConfigError(
            f"unknown online planner {name!r}; choose one of: {', '.join(ONLINE_REGISTRY)}"
        ) from None


def make_online_params(spec: OnlinePlannerSpec, params: Mapping[str, Any] | None = None,
                       key: str = "params") -> Any:
    """Build ``spec.params_cls`` from a dict; errors name ``key.<parameter>``."""
    params = dict(params or {})
    fields = [f.name for f in dataclasses.fields(spec.params_cls)]
    for k in params:
        if k not in fields:
            raise ConfigError(
                f"{key}.{k}: unknown parameter of online planner {spec.name!r} "
                f"(parameters: {', '.join(fields)})"
            )
    try:
        return spec.params_cls(**params)
    except ConfigError as exc:
        raise type(exc)(f"{key}.{exc}") from None


def resolve_planner_choice(choice: Any) -> PlannerChoice:
    """A :class:`PlannerChoice` from a name, ``{"name", "params"}`` or a PlannerChoice."""
    if isinstance(choice, PlannerChoice):
        return choice
    if isinstance(choice, str):
        return PlannerChoice(choice, {})
    if isinstance(choice, Mapping):
        for k in choice:
            if k not in ("name", "params"):
                raise ConfigError(f"planner.{k}: unknown key (allowed: name, params)")
        if not isinstance(choice.get("name"), str):
            raise ConfigError(f"planner.name: must be an online planner name, "
                              f"got {choice.get('name')!r}")
        params = choice.get("params") or {}
        if not isinstance(params, Mapping):
            raise ConfigError(f"planner.params: must be a mapping, got {params!r}")
        return PlannerChoice(choice["name"], dict(params))
    raise ConfigError(f"planner: must be a name or {{name, params}}, got {choice!r}")


# ---------------------------------------------------------------------- parameter checks
def _pos(name: str, v: Any, *, allow_zero: bool = False, optional: bool = False) -> None:
    if optional and v is None:
        return
    ok = not isinstance(v, bool) and isinstance(v, (int, float, np.integer, np.floating)) \
        and math.isfinite(float(v)) and (float(v) >= 0 if allow_zero else float(v) > 0)
    if not ok:
        raise ConfigError(f"{name}: must be a number {'>= 0' if allow_zero else '> 0'}, "
                          f"got {v!r}")


def _floats(obj: Any, *names: str) -> None:
    """Store numeric fields of a frozen dataclass as floats (one numba type per kernel)."""
    for n in names:
        v = getattr(obj, n)
        if v is not None:
            object.__setattr__(obj, n, float(v))


def _choice(name: str, v: Any, choices: tuple[str, ...]) -> None:
    if v not in choices:
        raise ConfigError(f"{name}: must be one of {', '.join(choices)}, got {v!r}")


def _flag(name: str, v: Any) -> None:
    if not isinstance(v, (bool, np.bool_)):
        raise ConfigError(f"{name}: must be true or false, got {v!r}")


_HEURISTICS = ("euclidean", "octile")


@dataclass(frozen=True)
class APFOnlineParams:
    """Online plain APF.

    Attributes
    ----------
    k_att, k_rep, rho0_m : float
        Gains and range of eq. 5/6 (paper: 40, 5, 2 m) for the goal and the
        static cells.
    k_rep_moving, rho0_moving_m : float or None
        Gain and range for the moving discs (default: ``k_rep``, ``rho0_m``).
    repulsion : {"position", "velocity"}
        Eq. 6 on the gap, or the velocity-aware form of Ge and Cui (2002).
    a_max : float
        Braking deceleration of the velocity-aware form (m/s^2).
    swerve : float
        Tangential share of the moving-disc repulsion (0 = pure eq. 6).
    dodge : bool
        When the step along the force is blocked by the static map while
        discs are sensed (a disc pressing the robot against a wall), take
        instead the clear full step, among 12 directions, that most increases
        the gap to the discs predicted one tick ahead (ours, not the paper's).
    """

    k_att: float = K_ATT
    k_rep: float = K_REP
    rho0_m: float = RHO0_M
    k_rep_moving: float | None = None
    rho0_moving_m: float | None = None
    repulsion: str = "position"
    a_max: float = 1.0
    swerve: float = 1.0
    dodge: bool = True

    def __post_init__(self) -> None:
        _pos("k_att", self.k_att)
        _pos("k_rep", self.k_rep, allow_zero=True)
        _pos("rho0_m", self.rho0_m)
        _pos("k_rep_moving", self.k_rep_moving, allow_zero=True, optional=True)
        _pos("rho0_moving_m", self.rho0_moving_m, optional=True)
        _choice("repulsion", self.repulsion, ("position", "velocity"))
        _pos("a_max", self.a_max)
        _pos("swerve", self.swerve, allow_zero=True)
        _flag("dodge", self.dodge)
        _floats(self, "k_att", "k_rep", "rho0_m", "k_rep_moving", "rho0_moving_m", "a_max",
                "swerve")


@dataclass(frozen=True)
class FusionOnlineParams(APFOnlineParams):
    """Online fusion (Algorithm 2).

    Attributes
    ----------
    r1_m : float
        Radius of the circle that collects A* path points (eq. 7), metres.
    r2_m : float
        Radius within which obstacles (static cells and moving discs) repel.
    ahead : {"progress", "paper-x"}
        Which path points count as ahead: those beyond the robot's progress
        along the path (any direction of travel), or the paper's eq. 8
        ``x_p - x > 0``.
    heuristic : {"euclidean", "octile"}
        A* heuristic (paper: Euclidean, eq. 2).
    escape_ticks : int
        Stall test of the local-minimum escape: when the robot's net move
        over this many ticks is below 2.5 steps, it *escapes*: it walks back
        along its own trajectory to the point from which the cheapest rejoin
        of the A* path is in sight (:func:`rejoin_point`), goes straight to
        that path point and follows the A* path until its progress is
        ``escape_points`` points further, pulled by a point ``r1_m`` ahead on
        that route (eq. 5) and still repelled by the moving discs; then
        Algorithm 2 resumes.  0 disables (the paper as printed).
    escape_points : int
        Path points to follow in escape mode.
    """

    r1_m: float = 1.5
    r2_m: float = 2.0
    ahead: str = "progress"
    heuristic: str = "euclidean"
    escape_ticks: int = 20
    escape_points: int = 6

    def __post_init__(self) -> None:
        super().__post_init__()
        _pos("r1_m", self.r1_m)
        _pos("r2_m", self.r2_m)
        _floats(self, "r1_m", "r2_m")
        _choice("ahead", self.ahead, ("progress", "paper-x"))
        _choice("heuristic", self.heuristic, _HEURISTICS)
        for n in ("escape_ticks", "escape_points"):
            v = getattr(self, n)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ConfigError(f"{n}: must be an integer >= 0, got {v!r}")


@dataclass(frozen=True)
class AStarFollowParams:
    """Blind A* path following.

    Attributes
    ----------
    heuristic : {"euclidean", "octile"}
        A* heuristic.
    """

    heuristic: str = "euclidean"

    def __post_init__(self) -> None:
        _choice("heuristic", self.heuristic, _HEURISTICS)


@dataclass(frozen=True)
class AStarReplanParams:
    """A* replanned at a fixed rate with the sensed discs as blocked cells.

    Attributes
    ----------
    replan_period_s : float
        Seconds between replans (1.0 = 1 Hz, Nav2's default behaviour tree).
    margin_m : float
        Extra clearance added to each sensed disc when rasterising it (on top
        of the disc's and the robot's radii).
    heuristic : {"euclidean", "octile"}
        A* heuristic.
    """

    replan_period_s: float = 1.0
    margin_m: float = 0.0
    heuristic: str = "euclidean"

    def __post_init__(self) -> None:
        _pos("replan_period_s", self.replan_period_s)
        _pos("margin_m", self.margin_m, allow_zero=True)
        _floats(self, "replan_period_s", "margin_m")
        _choice("heuristic", self.heuristic, _HEURISTICS)


# ---------------------------------------------------------------------- c-space and A*
_CSPACE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def robot_cspace(grid: GridMap, radius_m: float) -> GridMap:
    """The map with occupied cells *and the map's edge* grown by the robot radius.

    A cell is blocked when its centre is closer than ``radius_m`` to an
    occupied square or to the map's outside.  An 8-connected path through
    the free cell centres without corner cutting keeps a disc of that radius
    clear of every occupied square along its whole length (checked
    exhaustively over cell offsets and radii in the tests).  Cached per map
    and radius.

    >>> g = GridMap.from_rows([".....", ".....", "....."], resolution=0.5)
    >>> robot_cspace(g, 0.3).occupied.astype(int).tolist()    # edge cells are 0.25 m in
    [[1, 1, 1, 1, 1], [1, 0, 0, 0, 1], [1, 1, 1, 1, 1]]
    """
    r = float(radius_m)
    per = _CSPACE.setdefault(grid, {})
    if r in per:
        return per[r]
    res = grid.resolution
    k = int(math.ceil(r / res + 0.5)) + 1
    padded = np.pad(grid.occupied, k, constant_values=True)
    big = GridMap(padded, res, (grid.origin[0] - k * res, grid.origin[1] - k * res))
    occ = big.inflate(r).occupied[k:-k, k:-k] if r > 0 else grid.occupied
    cs = grid.with_occupied(occ, name=f"{grid.name}+r{r:g}")
    per[r] = cs
    return cs


def _clear(grid: GridMap, a: np.ndarray, b: np.ndarray, r: float) -> bool:
    return segment_static_distance(grid.occupied, grid.origin[0], grid.origin[1],
                                   grid.resolution, float(a[0]), float(a[1]), float(b[0]),
                                   float(b[1]), r) >= r


def _snap_cell(cs_occ: np.ndarray, grid: GridMap, p: np.ndarray,
               r: float) -> tuple[int, int] | None:
    """A free c-space cell near ``p`` whose centre the robot reaches in a clear straight line."""
    res = grid.resolution
    c = int(math.floor((p[0] - grid.origin[0]) / res))
    rr = int(math.floor((p[1] - grid.origin[1]) / res))
    h, w = cs_occ.shape
    cands = []
    for dr in range(-2, 3):
        for dc in range(-2, 3):
            r2, c2 = rr + dr, c + dc
            if 0 <= r2 < h and 0 <= c2 < w and not cs_occ[r2, c2]:
                centre = grid.cell_to_world([r2, c2])[0]
                cands.append((float(np.hypot(*(centre - p))), r2, c2, centre))
    cands.sort(key=lambda t: (t[0], t[1], t[2]))
    for _, r2, c2, centre in cands:
        if _clear(grid, p, centre, r):
            return (r2, c2)
    return None


def global_astar_path(grid: GridMap, start: np.ndarray, goal: np.ndarray, radius_m: float,
                      heuristic: str = "euclidean",
                      occupied: np.ndarray | None = None) -> np.ndarray | None:
    """A* path for a disc robot from ``start`` to ``goal`` (world points), or None.

    Runs 8-connected A* without corner cutting on :func:`robot_cspace`
    (or on ``occupied``, a c-space of the same shape, when given), then
    returns ``[start, cell centres..., goal]`` with the first and last cell
    centres dropped when the straight move past them is clear.

    >>> g = GridMap.from_rows(["....", ".##.", ".#.."])
    >>> global_astar_path(g, np.array([0.5, 0.5]), np.array([3.5, 2.5]), 0.2).tolist()
    [[0.5, 0.5], [0.5, 1.5], [0.5, 2.5], [1.5, 2.5], [2.5, 2.5], [3.5, 2.5]]
    """
    start = np.asarray(start, dtype=np.float64)
    goal = np.asarray(goal, dtype=np.float64)
    cs = robot_cspace(grid, radius_m)
    occ = cs.occupied if occupied is None else occupied
    sc = _snap_cell(occ, grid, start, radius_m)
    gc = _snap_cell(occ, grid, goal, radius_m)
    if sc is None or gc is None:
        return None
    if occupied is None:
        searcher = get_searcher(cs, corner_cutting=False)
    else:
        searcher = AStarSearcher(occ, corner_cutting=False)
    res = searcher.search(sc, gc, heuristic=heuristic)
    if res.status != "SUCCESS":
        return None
    centres = grid.cell_to_world(res.cells)
    pts = [start]
    i0 = 0
    if len(centres) > 1 and _clear(grid, start, centres[1], radius_m):
        i0 = 1
    i1 = len(centres)
    if i1 - i0 > 1 and _clear(grid, centres[i1 - 2], goal, radius_m):
        i1 -= 1
    pts.extend(centres[i0:i1])
    pts.append(goal)
    path = np.array(pts)
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.any(np.diff(path, axis=0) != 0.0, axis=1)
    return path[keep]


def _cumlen(path: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])


def _point_at(path: np.ndarray, cum: np.ndarray, s: float) -> np.ndarray:
    if s >= cum[-1]:
        return path[-1].copy()
    i = int(np.searchsorted(cum, s, side="right")) - 1
    i = min(max(i, 0), len(path) - 2)
    seg = cum[i + 1] - cum[i]
    f = 0.0 if seg <= 0 else (s - cum[i]) / seg
    return path[i] + f * (path[i + 1] - path[i])


# ---------------------------------------------------------------------- moving-disc repulsion
@njit(cache=True)
def disc_repulsion(x: float, y: float, vx: float, vy: float, radius: float, pos: np.ndarray,
                   vel: np.ndarray, radii: np.ndarray, k_rep: float, rho0_m: float,
                   reach_m: float, velocity_aware: bool, a_max: float, swerve: float,
                   ux_des: float, uy_des: float) -> tuple[float, float]:
    """Summed repulsion of sensed discs on a robot disc at ``(x, y)`` moving at ``(vx, vy)``.

    ``pos``, ``vel`` (M, 2) and ``radii`` (M,) describe the discs; only
    discs whose gap is below ``min(reach_m, range)`` count.  ``(ux_des,
    uy_des)`` is the unit direction the robot means to go (for the swerve
    term).  See the module docstring for the formulas.
    """
    fx = 0.0
    fy = 0.0
    lim = min(reach_m, rho0_m)
    for i in range(pos.shape[0]):
        cx = x - pos[i, 0]
        cy = y - pos[i, 1]
        dc = math.sqrt(cx * cx + cy * cy)
        gap = dc - radii[i] - radius
        if dc > 0.0:
            ux = cx / dc
            uy = cy / dc
        else:  # centres coincide: push to the right of the intended motion
            ux = uy_des
            uy = -ux_des
        g = max(gap, GAP_MIN_M)
        if not velocity_aware:
            if gap > lim:
                continue
            rx, ry = rep_force_xy(ux * g, uy * g, k_rep, rho0_m)
        else:
            if gap > reach_m:
                continue
            rvx = vx - vel[i, 0]
            rvy = vy - vel[i, 1]
            v_ro = -(rvx * ux + rvy * uy)  # closing speed towards the disc
            if v_ro <= 0.0:
                continue
            rho_m = v_ro * v_ro / (2.0 * a_max)
            eff = gap - rho_m
            if eff >= rho0_m:
                continue
            e = max(eff, GAP_MIN_M)
            m1 = k_rep * (1.0 + v_ro / a_max) / (e * e)
            # relative velocity minus its component along n_RO = -u
            pvx = rvx - (-v_ro) * ux
            pvy = rvy - (-v_ro) * uy
            pv = math.sqrt(pvx * pvx + pvy * pvy)
            rx = m1 * ux
            ry = m1 * uy
            if pv > 0.0:
                m2 = k_rep * v_ro * pv / (g * a_max * e * e)
                rx += m2 * pvx / pv
                ry += m2 * pvy / pv
        if swerve > 0.0:
            ahead = -(ux * ux_des + uy * uy_des)
            if ahead > 0.0:
                mag = math.sqrt(rx * rx + ry * ry)
                # obstacle left of the intended motion (cross > 0) -> push right, and
                # a disc dead ahead (cross == 0) too
                # the side to pass on: behind a disc that moves across the intended
                # motion; else away from the disc's side; a disc dead ahead: to the right
                w = vel[i, 0] * (-uy_des) + vel[i, 1] * ux_des  # disc velocity to the left
                cross = ux_des * (-cy) - uy_des * (-cx)  # > 0: disc left of the motion
                go_left = w < -SIDE_SPEED if abs(w) > SIDE_SPEED else cross < 0.0
                tx = -uy
                ty = ux
                left = tx * (-uy_des) + ty * ux_des  # component along the left normal
                if (left > 0.0) != go_left:
                    tx = -tx
                    ty = -ty
                rx += swerve * mag * ahead * tx
                ry += swerve * mag * ahead * ty
        fx += rx
        fy += ry
    return fx, fy


_WARM = False


def warmup_online() -> None:
    """Compile (or load from numba's cache) every kernel the online planners use (once)."""
    global _WARM
    if _WARM:
        return
    from pathfuse.search.astar import warmup as astar_warmup
    from pathfuse.world.geometry import warmup_geometry
    from pathfuse.world.obstacles import warmup_obstacles

    warmup_geometry()
    warmup_obstacles()
    astar_warmup()
    p = np.zeros((1, 2))
    for va in (False, True):
        disc_repulsion(0.0, 0.0, 0.5, 0.0, 0.2, p + 1.0, p, np.ones(1), 5.0, 2.0, 2.0, va, 1.0,
                       1.0, 1.0, 0.0)
    pts = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 1.5]])
    cum = _cumlen(pts)
    for ro in (False, True):
        occ = np.zeros((3, 4), dtype=np.bool_)
        occ[1, 1] = True
        occ.setflags(write=not ro)
        advance_progress(0.5, 0.5, pts, cum, 0, 1.5, occ, 0.0, 0.0, 1.0, 0.2)
        for ahead in (AHEAD_PROGRESS, AHEAD_PAPER_X):
            fusion_force(0.5, 0.5, 3.5, 2.5, pts, cum, 0, ahead, 40.0, 5.0, 2.0, 1.5, 2.0, occ,
                         0.0, 0.0, 1.0)
        apf_force(0.5, 0.5, 3.5, 2.5, 40.0, 5.0, 2.0, 2.0, occ, 0.0, 0.0, 1.0)
        safe_step(0.5, 0.5, 1.0, 1.0, 0.1, occ, 0.0, 0.0, 1.0, 0.2)
        rejoin_point(pts, 3, pts, cum, 0, 1.5, occ, 0.0, 0.0, 1.0, 0.2)
    occ = np.zeros((3, 4), dtype=np.bool_)
    _rasterise_discs(occ, 0.0, 0.0, 1.0, pts, np.ones(3), 0.2)
    _WARM = True


# ---------------------------------------------------------------------- APF-style planners
class _FieldPlanner(OnlinePlanner):
    """Shared tick logic of the APF-style planners: static force + discs + safe step."""

    def reset(self, ctx: PlannerContext) -> None:
        super().reset(ctx)
        g = ctx.grid
        self._occ = g.occupied
        self._ox = float(g.origin[0])
        self._oy = float(g.origin[1])
        self._res = float(g.resolution)
        self._r = float(ctx.robot.radius)
        self._clear_m = self._r + MARGIN_FRAC * self._res
        self._step = float(ctx.robot.max_speed) * float(ctx.dt)
        p = self.params
        self._k_mov = p.k_rep if p.k_rep_moving is None else p.k_rep_moving
        self._rho_mov = p.rho0_m if p.rho0_moving_m is None else p.rho0_moving_m
        self._gx = float(ctx.goal[0])
        self._gy = float(ctx.goal[1])

    def static_force(self, x: float, y: float) -> tuple[float, float]:
        raise NotImplementedError

    def _reach(self) -> float:
        return math.inf

    def step_velocity(self, obs: Any, fx: float, fy: float) -> np.ndarray:
        """Add the discs' repulsion to ``(fx, fy)`` and take one safe step."""
        x, y = float(obs.position[0]), float(obs.position[1])
        ctx = self.ctx
        p = self.params
        dist = math.hypot(self._gx - x, self._gy - y)
        step = min(self._step, dist)
        if step <= 0.0:
            return np.zeros(2)
        sens = obs.obstacles
        if len(sens):
            fn = math.hypot(fx, fy)
            ux, uy = (fx / fn, fy / fn) if fn > 0 else (0.0, 0.0)
            dfx, dfy = disc_repulsion(x, y, float(obs.velocity[0]), float(obs.velocity[1]),
                                      self._r, sens.positions, sens.velocities, sens.radii,
                                      self._k_mov, self._rho_mov, self._reach(),
                                      p.repulsion == "velocity", p.a_max, p.swerve, ux, uy)
            fx += dfx
            fy += dfy
        nx, ny, how = safe_step(x, y, fx, fy, step, self._occ, self._ox, self._oy, self._res,
                                self._clear_m)
        self.last_how = how
        if p.dodge and len(sens) and math.hypot(nx - x, ny - y) < 0.5 * step:
            d = self._dodge(obs, x, y, fx, fy, step)
            if d is not None:
                nx, ny = d
        return np.array([(nx - x) / ctx.dt, (ny - y) / ctx.dt])

    def _dodge(self, obs: Any, x: float, y: float, fx: float, fy: float,
               step: float) -> tuple[float, float] | None:
        """A full clear step that most increases the predicted gap to the sensed discs.

        Used when the force's own step is blocked by the static map (typically a
        disc pressing the robot against a wall).  The discs are predicted one
        tick ahead at their current velocity.  None when no clear step beats
        standing still.
        """
        sens = obs.obstacles
        q = sens.positions + sens.velocities * self.ctx.dt

        def gap(px: float, py: float) -> float:
            return float((np.hypot(q[:, 0] - px, q[:, 1] - py) - sens.radii).min())

        best = gap(x, y)
        best_xy = None
        a0 = math.atan2(fy, fx) if (fx or fy) else 0.0
        for k in range(12):  # every 30 degrees, nearest to the force first
            a = a0 + math.pi / 6 * ((k + 1) // 2) * (1 if k % 2 else -1)
            tx, ty = x + step * math.cos(a), y + step * math.sin(a)
            if segment_is_clear(x, y, tx, ty, self._occ, self._ox, self._oy, self._res,
                                self._clear_m):
                gp = gap(tx, ty)
                if gp > best + 1e-9:
                    best, best_xy = gp, (tx, ty)
        return best_xy

    def act(self, obs: Any) -> np.ndarray:
        fx, fy = self.static_force(float(obs.position[0]), float(obs.position[1]))
        return self.step_velocity(obs, fx, fy)


class APFOnline(_FieldPlanner):
    """Plain APF, online (see the module docstring)."""

    name = "apf"

    def static_force(self, x: float, y: float) -> tuple[float, float]:
        p = self.params
        return apf_force(x, y, self._gx, self._gy, p.k_att, p.k_rep, p.rho0_m, p.rho0_m,
                         self._occ, self._ox, self._oy, self._res)


@njit(cache=True)
def rejoin_point(walk: np.ndarray, n: int, pts: np.ndarray, cum: np.ndarray, k: int,
                 rvis_m: float, occ: np.ndarray, ox: float, oy: float, res: float,
                 clear: float) -> tuple[int, int]:
    """Where a stalled robot should rejoin its global path.

    Over the walked points ``walk[:n]`` (the robot is at ``walk[n - 1]``) and
    the path points ``pts[j]``, ``j >= k``, within ``rvis_m`` of them with a
    clear straight move between the two (:func:`~pathfuse.field.stepper.segment_is_clear`),
    returns the pair ``(i, j)`` minimising "walk back from ``walk[n - 1]`` to
    ``walk[i]``, go straight to ``pts[j]``, follow the path to its end";
    ``(-1, -1)`` when none is in sight.
    """
    m = pts.shape[0]
    r2 = rvis_m * rvis_m
    back = 0.0
    best = np.inf
    bi = -1
    bj = -1
    for i in range(n - 1, -1, -1):
        x = walk[i, 0]
        y = walk[i, 1]
        if i < n - 1:
            back += math.hypot(x - walk[i + 1, 0], y - walk[i + 1, 1])
        if back >= best:
            break
        for j in range(k, m):
            dx = pts[j, 0] - x
            dy = pts[j, 1] - y
            d2 = dx * dx + dy * dy
            if d2 < r2:
                cost = back + math.sqrt(d2) + cum[m - 1] - cum[j]
                if cost < best and segment_is_clear(x, y, pts[j, 0], pts[j, 1], occ, ox, oy,
                                                    res, clear):
                    best = cost
                    bi = i
                    bj = j
    return bi, bj


class FusionOnline(_FieldPlanner):
    """Algorithm 2 online, with a local-minimum escape along the A* path (see the parameters)."""

    name = "fusion"

    def reset(self, ctx: PlannerContext) -> None:
        super().reset(ctx)
        p = self.params
        path = global_astar_path(ctx.grid, ctx.start, ctx.goal, ctx.robot.radius, p.heuristic)
        if path is None:
            self.failure = ("no_path", "A* found no path for the robot on the static map")
            return
        self.global_path = path
        self._pts = np.ascontiguousarray(path)
        self._cum = _cumlen(self._pts)
        self._k = 0
        self._ahead = AHEAD_PAPER_X if p.ahead == "paper-x" else AHEAD_PROGRESS
        self._walk = np.empty((1024, 2))
        self._n = 0
        self._mark = 0  # walk index from which the stall test looks back
        self._route: np.ndarray | None = None
        self.escapes = 0

    def _reach(self) -> float:
        return self.params.r2_m

    def _record(self, x: float, y: float) -> None:
        if self._n == self._walk.shape[0]:
            self._walk = np.concatenate([self._walk, np.empty_like(self._walk)])
        self._walk[self._n, 0] = x
        self._walk[self._n, 1] = y
        self._n += 1

    def _start_escape(self) -> None:
        p = self.params
        # any path point may be the rejoin point (the start always sees the first one);
        # the cost, which includes the rest of the path, prefers those ahead
        i, j = rejoin_point(self._walk, self._n, self._pts, self._cum, 0,
                            p.r1_m + self._res, self._occ, self._ox, self._oy, self._res,
                            self._clear_m)
        if i < 0:
            return
        m = self._pts.shape[0]
        end = min(max(j, self._k) + p.escape_points, m - 1)
        route = np.concatenate([self._walk[i:self._n][::-1], self._pts[j:end + 1]])
        keep = np.ones(len(route), dtype=bool)
        keep[1:] = np.any(np.diff(route, axis=0) != 0.0, axis=1)
        self._route = route[keep]
        self._route_cum = _cumlen(self._route)
        self._route_s = 0.0
        self._route_end_k = end
        self.escapes += 1

    def _escape_force(self, x: float, y: float) -> tuple[float, float]:
        """Pull towards a point up to ``r1`` ahead of the robot's projection on the escape route.

        The look-ahead is halved (down to one step) until the point is in sight.
        """
        r, cum = self._route, self._route_cum
        a, b = r[:-1], r[1:]
        d = b - a
        l2 = np.maximum((d * d).sum(axis=1), 1e-300)
        t = np.clip(((x - a[:, 0]) * d[:, 0] + (y - a[:, 1]) * d[:, 1]) / l2, 0.0, 1.0)
        near = np.hypot(a[:, 0] + t * d[:, 0] - x, a[:, 1] + t * d[:, 1] - y)
        s_proj = cum[:-1] + t * np.sqrt(l2)
        # only look a little ahead of the current progress on the route
        window = (s_proj >= self._route_s - 1e-9) \
            & (s_proj <= self._route_s + 2.0 * self.params.r1_m)
        if window.any():
            idx = np.flatnonzero(window)
            self._route_s = float(s_proj[idx[np.argmin(near[idx])]])
        look = self.params.r1_m
        while True:  # the farthest carrot within r1 ahead that is in sight
            target = _point_at(r, cum, self._route_s + look)
            if look <= self._step or segment_is_clear(x, y, float(target[0]), float(target[1]),
                                                      self._occ, self._ox, self._oy, self._res,
                                                      self._clear_m):
                break
            look *= 0.5
        k_att = self.params.k_att
        return k_att * (float(target[0]) - x), k_att * (float(target[1]) - y)

    def act(self, obs: Any) -> np.ndarray:
        p = self.params
        x, y = float(obs.position[0]), float(obs.position[1])
        self._record(x, y)
        self._k = advance_progress(x, y, self._pts, self._cum, self._k, p.r1_m, self._occ,
                                   self._ox, self._oy, self._res, self._clear_m)
        if self._route is not None and self._k >= self._route_end_k:
            self._route = None
            self._mark = self._n - 1
        if self._route is not None:
            fx, fy = self._escape_force(x, y)
            return self.step_velocity(obs, fx, fy)
        fx, fy, _ = fusion_force(x, y, self._gx, self._gy, self._pts, self._cum, self._k,
                                 self._ahead, p.k_att, p.k_rep, p.rho0_m, p.r1_m, p.r2_m,
                                 self._occ, self._ox, self._oy, self._res)
        w = p.escape_ticks
        if w > 0 and self._n - 1 - self._mark >= w:
            old = self._walk[self._n - 1 - w]
            if math.hypot(x - old[0], y - old[1]) < 2.5 * self._step:
                self._start_escape()
                self._mark = self._n - 1
                if self._route is not None:
                    fx, fy = self._escape_force(x, y)
        return self.step_velocity(obs, fx, fy)


# ---------------------------------------------------------------------- A* followers
class AStarFollow(OnlinePlanner):
    """Walk the static A* path at full speed, ignoring moving discs."""

    name = "astar-follow"

    def reset(self, ctx: PlannerContext) -> None:
        super().reset(ctx)
        path = global_astar_path(ctx.grid, ctx.start, ctx.goal, ctx.robot.radius,
                                 self.params.heuristic)
        if path is None:
            self.failure = ("no_path", "A* found no path for the robot on the static map")
            return
        self.global_path = path
        self._cum = _cumlen(path)
        self._s = 0.0
        self._step = float(ctx.robot.max_speed) * float(ctx.dt)

    def act(self, obs: Any) -> np.ndarray:
        self._s = min(self._s + self._step, float(self._cum[-1]))
        target = _point_at(self.global_path, self._cum, self._s)
        return (target - obs.position) / self.ctx.dt


@njit(cache=True)
def _rasterise_discs(occ: np.ndarray, ox: float, oy: float, res: float, pos: np.ndarray,
                     radii: np.ndarray, grow: float) -> None:
    """Block every cell whose centre is closer than ``radii[i] + grow`` to a disc centre."""
    h, w = occ.shape
    for i in range(pos.shape[0]):
        rad = radii[i] + grow
        c0 = max(int(math.floor((pos[i, 0] - rad - ox) / res)), 0)
        c1 = min(int(math.floor((pos[i, 0] + rad - ox) / res)), w - 1)
        r0 = max(int(math.floor((pos[i, 1] - rad - oy) / res)), 0)
        r1 = min(int(math.floor((pos[i, 1] + rad - oy) / res)), h - 1)
        for r in range(r0, r1 + 1):
            cy = oy + (r + 0.5) * res - pos[i, 1]
            for c in range(c0, c1 + 1):
                cx = ox + (c + 0.5) * res - pos[i, 0]
                if cx * cx + cy * cy < rad * rad:
                    occ[r, c] = True


class AStarReplan(OnlinePlanner):
    """A* replanned at a fixed rate around the sensed discs (see :class:`AStarReplanParams`)."""

    name = "astar-replan"

    def reset(self, ctx: PlannerContext) -> None:
        super().reset(ctx)
        self._cs = robot_cspace(ctx.grid, ctx.robot.radius)
        self._step = float(ctx.robot.max_speed) * float(ctx.dt)
        self._every = max(1, int(round(self.params.replan_period_s / ctx.dt)))
        self._path: np.ndarray | None = None
        self._s = 0.0
        self.replans = 0
        self.failed_replans = 0
        path = global_astar_path(ctx.grid, ctx.start, ctx.goal, ctx.robot.radius,
                                 self.params.heuristic)
        if path is None:
            self.failure = ("no_path", "A* found no path for the robot on the static map")
            return
        self.global_path = path

    def _replan(self, obs: Any) -> None:
        ctx = self.ctx
        g = ctx.grid
        occ = self._cs.occupied.copy()
        sens = obs.obstacles
        if len(sens):
            _rasterise_discs(occ, float(g.origin[0]), float(g.origin[1]), float(g.resolution),
                             sens.positions, sens.radii,
                             float(ctx.robot.radius) + self.params.margin_m)
        self.replans += 1
        path = global_astar_path(g, obs.position, ctx.goal, ctx.robot.radius,
                                 self.params.heuristic, occupied=occ)
        if path is None:
            self.failed_replans += 1
            self._path = None
            return
        self._path = path
        self._cum = _cumlen(path)
        self._s = 0.0
        self.global_path = path

    def act(self, obs: Any) -> np.ndarray:
        if obs.tick % self._every == 0:
            self._replan(obs)
        if self._path is None:
            return np.zeros(2)
        self._s = min(self._s + self._step, float(self._cum[-1]))
        target = _point_at(self._path, self._cum, self._s)
        return (target - obs.position) / self.ctx.dt


register_online(OnlinePlannerSpec(
    "fusion", FusionOnline, FusionOnlineParams,
    "Algorithm 2 online: static A* path attraction + APF with the sensed moving discs"))
register_online(OnlinePlannerSpec(
    "apf", APFOnline, APFOnlineParams,
    "plain APF online: goal attraction, static and moving-disc repulsion"))
register_online(OnlinePlannerSpec(
    "astar-follow", AStarFollow, AStarFollowParams,
    "the static A* path walked blindly (ignores moving discs)"))
register_online(OnlinePlannerSpec(
    "astar-replan", AStarReplan, AStarReplanParams,
    "A* replanned at a fixed rate (default 1 Hz) with sensed discs as blocked cells"))
