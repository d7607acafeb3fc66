"""The planner registry: one dict from name to :class:`PlannerSpec`.

The CLI, the tests and the benchmarks loop over :data:`REGISTRY`, so a planner
registered here is planned, listed, tested and benchmarked everywhere.
A planner is a plain function ``func(grid, start, goal, params, budget) ->
PlanResult`` whose parameters are a frozen dataclass (``params_cls``) holding
the defaults.  :func:`pathfuse.plan` validates the query before calling it, so
planner functions receive finite in-bounds free start and goal points.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pathfuse.result import ConfigError

__all__ = ["PlannerSpec", "REGISTRY", "register", "get_planner", "make_params", "planner_names"]


@dataclass(frozen=True)
class PlannerSpec:
    """A registered planner.

    Attributes
    ----------
    name : str
        Registry key, as given to ``plan(..., planner=name)`` and ``--planner``.
    func : callable
        ``func(grid, start, goal, params, budget) -> PlanResult``.
    params_cls : type
        Frozen dataclass of the planner's parameters with their defaults.
    description : str
        One line for ``pathfuse planners``.
    uses_astar : bool
        Whether the planner runs grid A* first (its time includes it).
    warmup : callable or None
        Compiles (or loads from numba's cache) the planner's kernels, so that
        timings never include JIT compilation.
    """

    name: str
    func: Callable[..., Any]
    params_cls: type
    description: str
    uses_astar: bool = False
    warmup: Callable[[], None] | None = None

    def defaults(self) -> dict[str, Any]:
        return dataclasses.asdict(self.params_cls())


REGISTRY: dict[str, PlannerSpec] = {}


def register(spec: PlannerSpec) -> PlannerSpec:
    """Add ``spec`` to the registry (a later registration of a name replaces it)."""
    REGISTRY[spec.name] = spec
    return spec


def planner_names() -> list[str]:
    _load_builtin()
    return list(REGISTRY)


def get_planner(name: str) -> PlannerSpec:
    """The spec registered under ``name``; :class:`ConfigError` naming the choices otherwise."""
    _load_builtin()
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise ConfigError(
            f"unknown planner {name!r}; choose one of: {', '.join(REGISTRY)}"
        ) from None


def make_params(spec: PlannerSpec, params: dict[str, Any] | None = None) -> Any:
    """Build ``spec.params_cls`` from a dict, naming any unknown key or bad value."""
    params = dict(params or {})
    fields = {f.name for f in dataclasses.fields(spec.params_cls)}
    unknown = sorted(set(params) - fields)
    if unknown:
        raise ConfigError(
            f"planner {spec.name!r} has no parameter {unknown[0]!r}; "
            f"its parameters are: {', '.join(sorted(fields))}"
        )
    try:
        return spec.params_cls(**params)
    except ConfigError:
        raise
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"planner {spec.name!r}: {exc}") from None


_LOADED = False


def _load_builtin() -> None:
    """Import the built-in planner modules, which register themselves."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    import importlib

    for mod in ("astar", "apf", "fusion", "ref6", "ref7"):
        try:
            importlib.import_module(f"pathfuse.planners.{mod}")
        except ModuleNotFoundError as exc:  # a planner not written yet
            if exc.name != f"pathfuse.planners.{mod}":
                raise
