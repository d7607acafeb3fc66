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

from pathfuse.planners.base import Controller, Observed
from pathfuse.planners.global_astar import GlobalPlan, plan_global
from pathfuse.planners.registry import PlannerSpec
from pathfuse.problem import Problem
from pathfuse.result import PlanResult, Status, path_length

__all__ = ["solve", "start_online", "warm", "Stopped", "PlanInfo"]

_WARM: set[str] = set()


def warm(spec: PlannerSpec, notify: Callable[[], None] | None = None) -> None:
    """Compile (or load from numba's cache) the kernels ``spec`` runs, once per process.

    ``notify`` is called first when the kernels are not in numba's on-disk
    cache yet (the command line prints a one-line notice with it).
    """
    if spec.name in _WARM:
        return
    from pathfuse.planners.kernel_cache import cold_kernels

    if notify is not None and cold_kernels(spec):
        notify()
    if not _WARM:  # the robot-disc check of a query's end points (Problem.failure)
        from pathfuse.geometry import segment_is_clear

        occ = np.zeros((2, 2), dtype=bool)
        occ.setflags(write=False)  # as GridMap.occupied: numba types read-only arrays apart
        segment_is_clear(0.5, 0.5, 0.5, 0.5, occ, 0.0, 0.0, 1.0, 0.1)
    if spec.uses_astar:
        from pathfuse.search.astar import warmup as astar_warmup

        astar_warmup()
    if spec.controller is not None:
        spec.controller.warmup()
    _WARM.add(spec.name)


def _astar_info(gp: GlobalPlan | None) -> dict[str, Any]:
    if gp is None:
        return {}
    return {"astar_path": np.asarray(gp.points, dtype=np.float64).reshape(-1, 2),
            "astar_length": float(gp.length_m) if gp.success else 0.0,
            "astar_time_s": float(gp.time_s)}


def solve(spec: PlannerSpec, problem: Problem, params: Any) -> PlanResult:
    """Plan ``problem`` with ``spec`` offline (the body of :func:`pathfuse.plan`)."""
    bad = problem.failure()
    if bad is not None:
        return PlanResult(bad[0], planner=spec.name, message=bad[1])
    warm(spec)
    budget = problem.budget
    if spec.function is not None:
        res = spec.function(problem.grid, np.array(problem.start), np.array(problem.goal),
                            params, budget)
        if not isinstance(res, PlanResult):
            raise TypeError(f"planner {spec.name!r} returned {type(res).__name__}, "
                            "not a PlanResult")
        return res if res.planner == spec.name else _renamed(res, spec.name)
    ctrl_cls = spec.controller
    assert ctrl_cls is not None
    deadline = (time.perf_counter() + budget.time_limit_s
                if budget.time_limit_s is not None else None)
    gp = None
    if spec.global_planner is not None:
        gp = _global(spec, problem, params,
                     budget.max_iterations if ctrl_cls.search_budget else None)
        if not gp.success:
            msg = gp.message if ctrl_cls.search_budget else f"A* failed: {gp.message}"
            return PlanResult(gp.status, time_s=gp.time_s, planner=spec.name,
                              expansions=gp.expansions, message=msg, info=_astar_info(gp))
    out = ctrl_cls(problem, params, gp).run(deadline)
    info = PlanInfo({**_astar_info(gp), **out.info} if not ctrl_cls.search_budget
                    else out.info)
    info.bind(problem.grid, out.path, problem.robot_radius_m)
    length = out.length_m if out.length_m is not None else path_length(out.path)
    return PlanResult(out.status, out.path, length, (gp.time_s if gp else 0.0) + out.time_s,
                      spec.name, gp.expansions if gp else 0, out.steps, out.message, info)


def _global(spec: PlannerSpec, problem: Problem, params: Any,
            max_expansions: int | None = None) -> GlobalPlan:
    """The global plan of ``spec``: grid A*, or an any-angle planner."""
    if spec.uses_astar:
        return plan_global(problem, params.heuristic,
                           bool(getattr(params, "corner_cutting", False)),
                           max_expansions=max_expansions)
    from pathfuse.planners.anyangle import plan_any_angle

    return plan_any_angle(str(spec.global_planner), problem, params, max_expansions)


class PlanInfo(dict):
    """``PlanResult.info`` of the registered planners: a dict that also answers
    ``info["min_clearance_m"]``, the least gap between the robot disc along the path and
    any occupied square (metres; ``inf`` on an empty map), computed on first access by
    :func:`pathfuse.metrics.min_clearance` (independently of the planner), so that a
    caller who never asks pays nothing.  It pickles as a plain dict."""

    _bound: tuple[Any, np.ndarray, float] | None = None

    def bind(self, grid: Any, path: np.ndarray, radius_m: float) -> None:
        self._bound = (grid, path, float(radius_m))

    def __missing__(self, key: Any) -> Any:
        if key != "min_clearance_m" or self._bound is None:
            raise KeyError(key)
        from pathfuse.metrics import min_clearance

        grid, path, r = self._bound
        v = min_clearance(grid, path) - r if path.shape[0] else math.nan
        self[key] = v
        return v

    def __reduce__(self) -> Any:
        return (dict, (dict(self),))


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
    warm(spec)
    gp = None
    if spec.global_planner is not None:
        gp = _global(spec, problem, params)
        if not gp.success:
            what = "A*" if spec.uses_astar else spec.global_planner
            return Stopped(problem, params, gp.status,
                           f"{what} found no path for the robot on the static map: {gp.message}")
    return spec.controller(problem, params, gp, dt=dt, max_speed=max_speed)
