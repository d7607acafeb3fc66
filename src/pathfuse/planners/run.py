"""Running a registered planner: offline (:func:`solve`) or online (:func:`start_online`).

Both build the global plan (when the planner has one) and the planner's
controller in the same way; they differ only in what drives the
controller: one :meth:`~pathfuse.planners.base.Controller.run` on the static
map, or one :meth:`~pathfuse.planners.base.Controller.act` per tick.

Numba compiles a kernel on its first call in a process (or loads it from
its on-disk cache).  :func:`warm` calls exactly the kernels a planner uses on
a tiny map before any clock starts, so ``time_s`` never includes
compilation.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from pathfuse import tier
from pathfuse.grid import GridMap
from pathfuse.metrics import PlanInfo
from pathfuse.planners.base import Controller, Observed
from pathfuse.planners.globals.astar import GlobalPlan, searched
from pathfuse.planners.globals.builtin import _astar as _builtin_astar
from pathfuse.planners.globals.builtin import run_global
from pathfuse.planners.kernel_cache import cold_kernels, is_cached
from pathfuse.planners.registry import GLOBAL_PLANNERS, PlannerSpec, make_params
from pathfuse.problem import _DEFAULT_BUDGET, Problem
from pathfuse.result import Budget, ConfigError, PlanResult, Status, _FoundPath, path_length
from pathfuse.search.astar import HEURISTICS, AStarSearcher, SearchResult, get_searcher
from pathfuse.validate import short as _shown

__all__ = ["solve", "quick_plan", "start_online", "warm", "warm_query", "Stopped", "PlanInfo"]

_WARM: set[tuple[str, str | None, bool, bool, bool, str | None]] = set()
_WARM_SEGMENT: list[bool] = []


def warm(spec: PlannerSpec, notify: Callable[[], None] | None = None, *, params: Any = None,
         diff_drive: bool = False, segments: bool = True, online: bool = False,
         margin: bool = False) -> None:
    """Compile (or load from numba's cache) the kernels ``spec`` runs, once per process.

    Only what runs is compiled: the global planner that ``params`` name (the preset's by
    default; for A*, the kernel of the ``heuristic`` they name), the controller's kernels
    for a plan on a static map (with ``margin``: with a safety margin, ``clearance_m`` > 0)
    or, with ``online``, those it runs online (among moving discs: the field loops'
    signature with disc arrays), and with ``diff_drive`` (which implies ``online``) those it
    runs online on a diff-drive robot only. ``segments`` adds the exact segment check the
    waypoints and the robot disc's end-point check use (a point robot's ``astar`` plan needs
    neither). ``notify`` is called first when the kernels are not in numba's on-disk cache
    yet (the command line prints a one-line notice with it).
    """
    gname = spec.global_planner_of(params)
    online = online or diff_drive
    # the A* heuristic picks one of two kernels: only the one the plan runs is compiled
    heuristic = getattr(params if params is not None else make_params(spec), "heuristic", None)
    key = (spec.name, gname, diff_drive, online, margin, heuristic)
    if key in _WARM:
        if segments and not _WARM_SEGMENT:
            _warm_segments()
        return
    tier.stop()  # compiling on purpose: no plan of this process runs interpreted from now
    if notify is not None and cold_kernels(spec, params=params, diff_drive=diff_drive,
                                           online=online):
        notify()
    if segments and not _WARM_SEGMENT:
        _warm_segments()
    if gname is not None:
        from pathfuse.planners.globals.builtin import warm_global

        warm_global(gname, heuristic)
    if spec.controller is not None:
        if online:
            spec.controller.warmup_online()
        else:
            spec.controller.warmup()
        if margin:
            spec.controller.warmup_margin()
        if diff_drive:
            spec.controller.warmup_diff_drive()
    _WARM.add(key)


def warm_query(spec: PlannerSpec, params: Any, robot_radius_m: float,
               notify: Callable[[], None] | None = None, *, cells: int | None = None,
               timed: bool = False) -> None:
    """:func:`warm` for one offline plan of ``spec`` (what :func:`solve` warms), unless
    the plan, on a map of ``cells`` cells (when given) and without a time limit (not
    ``timed``), will run its kernels interpreted (:mod:`pathfuse.tier`)."""
    segments = _needs_segments(spec, robot_radius_m)
    if cells is not None and _interprets(spec, params, cells, segments, timed):
        # should the plan end up compiling after all (over the budget), it says so first
        _NOTICE[:] = [notify] if notify is not None else []
        return
    warm(spec, notify, params=params, segments=segments)


#: The notice :func:`warm_query` was given for a plan it left to run interpreted: said by
#: :func:`solve` if that plan compiles after all.
_NOTICE: list[Callable[[], None]] = []


def _interprets(spec: PlannerSpec, params: Any, cells: int, segments: bool,
                timed: bool) -> bool:
    """Whether an offline plan of ``spec`` on a map of ``cells`` cells, with a time limit
    when ``timed``, runs its kernels interpreted (:func:`pathfuse.tier.admit`; a planner
    given as a function compiles)."""
    return spec.function is None and tier.admit(
        cells, lambda: bool(cold_kernels(spec, params=params)) or
        (segments and not _segments_cached()), timed=timed)


def _needs_segments(spec: PlannerSpec, robot_radius_m: float) -> bool:
    """Whether an offline plan runs the exact segment check: a disc robot's end points
    and snapping, or a controller that follows waypoints (a point robot's path follower
    returns the global path as planned)."""
    ctrl = spec.controller
    return robot_radius_m > 0 or ctrl is None or not ctrl.search_budget


def _segments_cached() -> bool:
    """Whether :func:`_warm_segments`' kernels are in numba's on-disk cache."""
    from pathfuse.costmap import move_clear
    from pathfuse.geometry import segment_is_clear

    return is_cached(move_clear) and is_cached(segment_is_clear)


def _warm_segments() -> None:
    """The robot-disc check of a query's end points (Problem.failure), of the start and goal
    snapping and of waypoints (:func:`pathfuse.costmap.move_clear`, called from Python), and
    :func:`pathfuse.geometry.segment_is_clear` as dwa's and mppi's offline goal test call it."""
    from pathfuse.costmap import make_costmap, move_clear
    from pathfuse.geometry import segment_is_clear

    occ = np.zeros((2, 2), dtype=bool)
    occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
    move_clear(make_costmap(occ, 0.1, lattice=False), 0.5, 0.5, 0.5, 0.5, 0.1)
    # dwa's and mppi's offline goal test call it from Python too: on a warm cache, loading
    # move_clear does not load it
    segment_is_clear(0.5, 0.5, 0.5, 0.5, occ, 0.0, 0.0, 1.0, 0.1)
    _WARM_SEGMENT.append(True)


def _astar_info(gp: GlobalPlan | None) -> dict[str, Any]:
    if gp is None:
        return {}
    out = {"astar_path": np.asarray(gp.points, dtype=np.float64).reshape(-1, 2),
           "astar_length": float(gp.length_m) if gp.success else 0.0,
           "astar_time_s": float(gp.time_s)}
    if gp.planner != "astar":  # the global path of another global planner, under A*'s keys
        out["global_planner"] = gp.planner
    return out


def solve(spec: PlannerSpec, problem: Problem, params: Any) -> PlanResult:
    """Plan ``problem`` with ``spec`` offline (the body of :func:`pathfuse.plan`)."""
    gname = getattr(params, "global_planner", None) or spec.global_planner  # global_planner_of
    ctrl_cls = spec.controller
    # _needs_segments, written out
    segments = problem.robot_radius_m > 0 or ctrl_cls is None or not ctrl_cls.search_budget
    margin = problem.clearance_m > 0
    if (spec.name, gname, False, False, margin, getattr(params, "heuristic", None)) \
            in _WARM and not (segments and not _WARM_SEGMENT):  # warm()'s own test
        return _solved(spec, problem, params, gname, ctrl_cls)
    notify = _NOTICE.pop() if _NOTICE else None
    if _interprets(spec, params, problem.grid.occupied.size, segments,
                   problem.budget.time_limit_s is not None):
        try:
            with tier.running(True):
                res = _solved(spec, problem, params, gname, ctrl_cls)
            res.info["kernels"] = "interpreted"
            return res
        except Exception:  # noqa: BLE001 - the budget ran out, or a kernel's Python
            # semantics differ from numba's (tests/test_tier.py holds them equal on every
            # planner): the plan again, compiled, as without pathfuse.tier
            if tier.mode() == "interpreted":
                raise
    return _solved(spec, problem, params, gname, ctrl_cls, (segments, margin), notify)


def _solved(spec: PlannerSpec, problem: Problem, params: Any, gname: str | None,
            ctrl_cls: type[Controller] | None,
            warm_first: tuple[bool, bool] | None = None,
            notify: Callable[[], None] | None = None) -> PlanResult:
    """:func:`solve` once its kernels are warm or run interpreted, or, with
    ``warm_first`` (``segments`` and ``margin`` of :func:`warm`), after warming them
    (``notify`` as :func:`warm`'s; a query that fails its checks warms nothing)."""
    bad = problem.failure()
    if bad is not None:
        return PlanResult(bad[0], planner=spec.name, message=bad[1])
    if warm_first is not None:
        warm(spec, notify, params=params, segments=warm_first[0], margin=warm_first[1])
    budget = problem.budget
    if spec.function is not None:
        res = spec.function(problem.grid, np.array(problem.start), np.array(problem.goal),
                            params, budget)
        if not isinstance(res, PlanResult):
            raise TypeError(f"planner {spec.name!r} returned {type(res).__name__}, "
                            "not a PlanResult")
        return res if res.planner == spec.name else _renamed(res, spec.name)
    assert ctrl_cls is not None
    if gname == "astar" and _LANE and problem.robot_radius_m == 0 and \
            problem.clearance_m == 0 and problem.robot is None and \
            (_AS_PLANNED.get(ctrl_cls) or _as_planned(ctrl_cls)):
        gs = GLOBAL_PLANNERS.get("astar")  # registered by now: warm() looked it up
        if gs is not None and gs.func is _builtin_astar and gs.plugin is None:  # not a plug-in
            res = _astar_as_planned(spec, problem, params)
            _remember(spec, params)
            return res
    deadline = (time.perf_counter() + budget.time_limit_s
                if budget.time_limit_s is not None else None)
    gp = None
    if gname is not None:
        gp = run_global(gname, problem, params,
                        budget.max_iterations if ctrl_cls.search_budget else None)
        if not gp.success:
            what = "A*" if gname == "astar" else gname
            msg = gp.message if ctrl_cls.search_budget else f"{what} failed: {gp.message}"
            return PlanResult(gp.status, time_s=gp.time_s, planner=spec.name,
                              expansions=gp.expansions, message=msg, info=_astar_info(gp))
    out = ctrl_cls.run_offline(problem, params, gp, deadline)
    if not ctrl_cls.search_budget:
        info = PlanInfo({**_astar_info(gp), **out.info})
    else:
        info = out.info if type(out.info) is PlanInfo else PlanInfo(out.info)
    info.bind(problem.grid, out.path, problem.robot_radius_m)
    length = out.length_m if out.length_m is not None else path_length(out.path)
    return PlanResult._made(out.status, out.path, length,
                            (gp.time_s if gp else 0.0) + out.time_s, spec.name,
                            gp.expansions if gp else 0, out.steps, out.message, info)


#: Whether :func:`solve` takes :func:`_astar_as_planned` where it applies (the tests turn it
#: off to compare it with the layers it writes out).
_LANE = True
_AS_PLANNED: dict[type, bool] = {}


def _as_planned(ctrl_cls: type[Controller]) -> bool:
    """Whether ``ctrl_cls`` answers offline with the global plan as planned: the path
    follower's own ``run_offline`` and ``run``
    (``astar``, ``astar-replan``; a subclass may override either)."""
    hit = _AS_PLANNED.get(ctrl_cls)
    if hit is None:  # once per class (the follower's module is imported only when asked)
        from pathfuse.planners.controllers.follow import FollowController

        hit = _AS_PLANNED[ctrl_cls] = (
            issubclass(ctrl_cls, FollowController) and ctrl_cls.run is FollowController.run
            and ctrl_cls.run_offline.__func__ is  # type: ignore[attr-defined]
            FollowController.run_offline.__func__)  # type: ignore[attr-defined]
    return hit


def _astar_as_planned(spec: PlannerSpec, problem: Problem, params: Any) -> PlanResult:
    """:func:`solve` for a point robot without a margin whose planner follows the built-in
    grid A*'s path as planned (:func:`_as_planned`): the result that
    :func:`~pathfuse.planners.globals.builtin.run_global`,
    :func:`~pathfuse.planners.globals.astar.plan_global` and the controller's
    :meth:`~pathfuse.planners.base.Controller.run_offline` give, built in one call from the
    map's cached searcher (issue 21: each of those layers cost 1-3 µs of a query on a
    small map, where pyastar2d's whole query is 30-60 µs).  ``solve`` runs a plug-in
    registered as ``astar`` through the layers.  ``tests/test_lane.py`` holds the two
    equal."""
    heuristic = getattr(params, "heuristic", "euclidean")
    cut = bool(getattr(params, "corner_cutting", False))
    if heuristic not in HEURISTICS:  # plan_global's check (the parameters have made it)
        raise ConfigError(f"heuristic: must be one of {', '.join(map(repr, HEURISTICS))}, "
                          f"got {_shown(heuristic)}")
    return _lane(spec.name, problem.grid, problem.start, problem.goal, problem.start_cell,
                 problem.goal_cell, problem.budget, heuristic, cut)


def _lane(name: str, grid: GridMap, start: tuple[float, float], goal: tuple[float, float],
          start_cell: tuple[int, int], goal_cell: tuple[int, int], budget: Budget,
          heuristic: str, cut: bool, searcher: AStarSearcher | None = None) -> PlanResult:
    """The body of :func:`_astar_as_planned` and of :func:`quick_plan`: the search of a
    point robot's checked query (cells in the map and free, a known heuristic) and its
    result; ``searcher``: the map's (:func:`get_searcher`), when the caller has it."""
    limit = budget.time_limit_s
    res_m = grid.resolution
    if searcher is None:
        searcher = get_searcher(grid, cut)
    t0 = time.perf_counter()
    status, cells, cost, expansions, points = searcher.search_fields(
        start_cell, goal_cell, heuristic, budget.max_iterations, limit,
        (grid.origin[0], grid.origin[1], res_m))
    elapsed = time.perf_counter() - t0
    if status is not Status.SUCCESS:
        problem = Problem._made(grid, start, goal, 0.0, budget, start_cell, goal_cell, 0.0,
                                None)
        gp = searched(problem, SearchResult(status, cells, cost, expansions, points), elapsed,
                      limit, heuristic, cut)
        return PlanResult(gp.status, time_s=gp.time_s, planner=name,
                          expansions=gp.expansions, message=gp.message, info=_astar_info(gp))
    length = cost * res_m
    info = PlanInfo(cells=cells, cost_cells=length / res_m, heuristic=heuristic,
                    corner_cutting=cut)
    info._bound = (grid, points, 0.0)  # bind()'s body (a point robot)
    # the message (found_message's text) is written when first read
    return _FoundPath._made(Status.SUCCESS, points, length, elapsed + 0.0, name, expansions,
                            0, None, info)


#: The plans that took the lane in :func:`solve`, by ``id`` of their parameters: the
#: parameters (so that a new object at a freed ``id`` is not taken for them), the spec,
#: the heuristic, the corner rule, :func:`warm`'s key and the global planner ``astar``'s
#: registry entry, the built-in's (see :func:`quick_plan`).
_QUICK: dict[int, tuple[Any, PlannerSpec, str, bool, tuple[Any, ...], Any]] = {}


def _remember(spec: PlannerSpec, params: Any) -> None:
    """Note that ``solve(spec, problem, params)`` took the lane (it warmed the kernels and
    checked the parameters' heuristic) with the global planner ``astar`` registered now,
    for :func:`quick_plan` (a later plan that takes the lane in ``solve`` notes it again:
    a plug-in may have come and gone)."""
    if len(_QUICK) >= 256 and id(params) not in _QUICK:
        _QUICK.clear()
    _QUICK[id(params)] = (params, spec, getattr(params, "heuristic", "euclidean"),
                          bool(getattr(params, "corner_cutting", False)),
                          (spec.name, "astar", False, False, False,
                           getattr(params, "heuristic", None)),
                          GLOBAL_PLANNERS.get("astar"))


def quick_plan(spec: PlannerSpec, params: Any, grid: object, start: object, goal: object,
               budget: object) -> PlanResult | None:
    """:func:`pathfuse.plan`'s result for a point robot without a margin or a robot model,
    without building the :class:`~pathfuse.problem.Problem`, or None where
    ``solve(spec, Problem.create(...), params)`` must run (issue 21: on a 32 x 32 map
    ``plan()``'s layers above the search cost as much as a third of pyastar2d's query).

    It answers only what :func:`solve` would answer through :func:`_lane` with nothing
    left to check: the same ``spec`` and ``params`` took the lane before (their kernels
    are warm, the heuristic is a known one, no plug-in replaced the global planner
    ``astar`` since), the map is a :class:`GridMap`, ``start`` and ``goal`` are tuples of
    two finite floats (``Problem.create``'s own shortcut) in free cells of the map, and
    ``budget`` is None or a :class:`Budget`.  Every other input, bad input included, gets
    None: ``plan()`` then checks it as always.  ``tests/test_lane.py`` holds the results
    equal to the layers'."""
    hit = _QUICK.get(id(params))
    if hit is None or hit[0] is not params or hit[1] is not spec or not _LANE or \
            hit[4] not in _WARM or type(grid) is not GridMap or \
            GLOBAL_PLANNERS.get("astar") is not hit[5]:  # a plug-in registered since
        return None
    if type(start) is not tuple or len(start) != 2 or type(goal) is not tuple or \
            len(goal) != 2:
        return None
    sx, sy = start
    gx, gy = goal
    if type(sx) is not float or type(sy) is not float or type(gx) is not float or \
            type(gy) is not float:
        return None
    if budget is None:
        budget = _DEFAULT_BUDGET
    elif type(budget) is not Budget:
        return None
    ox, oy = grid.origin
    res = grid.resolution
    # Problem.create's cells (floor raises on a NaN or an infinite coordinate, which
    # Problem.create rejects) and failure()'s first test (in the map, free, a point robot)
    try:
        sr, sc = math.floor((sy - oy) / res), math.floor((sx - ox) / res)
        gr, gc = math.floor((gy - oy) / res), math.floor((gx - ox) / res)
    except (ValueError, OverflowError):
        return None
    searcher = get_searcher(grid, hit[3])
    h, w = searcher.shape
    if not (0 <= sr < h and 0 <= sc < w and 0 <= gr < h and 0 <= gc < w):
        return None
    flat = searcher._flat  # a small map's labels as a list: 0 on a blocked cell
    if flat is not None:
        if not flat[sr * w + sc] or not flat[gr * w + gc]:
            return None
    else:
        occ = grid.occupied
        if occ[sr, sc] or occ[gr, gc]:
            return None
    return _lane(spec.name, grid, start, goal, (sr, sc), (gr, gc), budget, hit[2],
                 hit[3], searcher)


def _renamed(res: PlanResult, name: str) -> PlanResult:
    import dataclasses

    return dataclasses.replace(res, planner=name)


class Stopped(Controller):
    """An online controller that could not start (its global plan failed)."""

    def __init__(self, problem: Problem, params: Any, status: Status, message: str) -> None:
        super().__init__(problem, params)
        self.failure = (status, message)

    def act(self, obs: Observed) -> np.ndarray:
        return np.zeros(2)


def start_online(spec: PlannerSpec, problem: Problem, params: Any, dt: float,
                 max_speed: float) -> Controller:
    """The controller of ``spec`` ready for its first tick (global planning done).

    A planner whose global plan fails gets a :class:`Stopped` controller
    whose ``failure`` holds the status (``NO_PATH``, ...) and the reason.
    """
    if spec.controller is None:
        from pathfuse.result import ConfigError

        raise ConfigError(f"planner {spec.name!r} only plans offline (a plug-in function); "
                          "it cannot be simulated")
    rb = problem.robot
    warm(spec, params=params, diff_drive=rb is not None and rb.is_diff_drive, online=True)
    gp = None
    gname = spec.global_planner_of(params)
    if gname is not None:
        gp = run_global(gname, problem, params)
        if not gp.success:
            what = "A*" if gname == "astar" else gname
            return Stopped(problem, params, gp.status,
                           f"{what} found no path for the robot on the static map: {gp.message}")
    return spec.controller(problem, params, gp, dt=dt, max_speed=max_speed)
