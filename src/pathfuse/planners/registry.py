"""The planner registry: one dict from name to :class:`PlannerSpec`.

A planner is a *global planner* (grid A*, or none) plus a *local
controller* (:class:`~pathfuse.planners.base.Controller`), with one frozen
parameter dataclass holding one set of defaults.  :func:`pathfuse.plan`
runs the controller to the goal on the static map; :func:`pathfuse.simulate`
runs the same controller once per tick among moving discs.  The CLI, the
study engine, the tests and the benchmarks loop over :data:`REGISTRY`, so a
planner registered here is planned, simulated, listed, tested and
benchmarked everywhere.

A plug-in that only plans offline can register a plain function with
:func:`register_function`: ``func(grid, start, goal, params, budget) ->
PlanResult``.

Examples
--------
>>> planner_names()[:6]          # the built-in planners come first, in this order
['astar', 'astar-replan', 'apf', 'fusion', 'ref6', 'ref7']
>>> get_planner("astar-follow").name     # an older name of the same planner
'astar'
>>> get_planner("fusion").online, get_planner("fusion").uses_astar
(True, True)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pathfuse.result import ConfigError
from pathfuse.validate import short as _shown

if TYPE_CHECKING:
    from pathfuse.planners.base import Controller

__all__ = [
    "PlannerSpec",
    "REGISTRY",
    "register",
    "register_function",
    "get_planner",
    "make_params",
    "planner_names",
]


@dataclass(frozen=True)
class PlannerSpec:
    """A registered planner.

    Attributes
    ----------
    name : str
        Registry key, as given to ``plan(..., planner=name)`` and ``--planner``.
    params_cls : type
        Frozen dataclass of the planner's parameters with their defaults
        (fields declared with :func:`pathfuse.validate.param`).
    description : str
        One line for ``pathfuse planners``.
    controller : type or None
        The :class:`~pathfuse.planners.base.Controller` subclass; it runs
        offline (:func:`pathfuse.plan`) and online (:func:`pathfuse.simulate`).
    global_planner : {"astar", "astar-smooth", "thetastar", "lazy-thetastar", "shortest", None}
        The global planner run before the controller (grid A*, an any-angle
        planner of :mod:`pathfuse.planners.anyangle`, or none).
    function : callable or None
        An offline-only planner ``func(grid, start, goal, params, budget)``
        (plug-ins registered with :func:`register_function`).
    aliases : tuple of str
        Older names that resolve to this planner.
    """

    name: str
    params_cls: type
    description: str
    controller: type[Controller] | None = None
    global_planner: str | None = None
    function: Callable[..., Any] | None = None
    aliases: tuple[str, ...] = ()

    @property
    def uses_astar(self) -> bool:
        """Whether grid A* runs first (its time is part of the planner's)."""
        return self.global_planner == "astar"

    @property
    def has_global_plan(self) -> bool:
        """Whether a global planner (A* or an any-angle one) runs before the controller."""
        return self.global_planner is not None

    @property
    def offline(self) -> bool:
        """Whether :func:`pathfuse.plan` can run it (every planner can)."""
        return self.controller is not None or self.function is not None

    @property
    def online(self) -> bool:
        """Whether :func:`pathfuse.simulate` can run it (tick by tick)."""
        return self.controller is not None

    def defaults(self) -> dict[str, Any]:
        """The default parameters as a dict."""
        return dataclasses.asdict(self.params_cls())

    def capabilities(self) -> tuple[str, ...]:
        """``("offline", "online")`` or a part of it."""
        return tuple(c for c, ok in (("offline", self.offline), ("online", self.online)) if ok)


REGISTRY: dict[str, PlannerSpec] = {}
_ALIASES: dict[str, str] = {}
_DEFAULTS: dict[str, Any] = {}
_BUILT: dict[Any, Any] = {}


def register(spec: PlannerSpec) -> PlannerSpec:
    """Add ``spec`` to the registry (a later registration of a name replaces it).

    :func:`planner_names` lists the built-in planners first, in a fixed order,
    then plug-ins in the order they were registered.
    """
    if spec.controller is None and spec.function is None:
        raise ConfigError(f"planner {spec.name!r}: needs a controller or a function")
    REGISTRY[spec.name] = spec
    _DEFAULTS.pop(spec.name, None)
    for a in spec.aliases:
        _ALIASES[a] = spec.name
    return spec


def register_function(name: str, func: Callable[..., Any], params_cls: type,
                      description: str) -> PlannerSpec:
    """Register an offline-only planner ``func(grid, start, goal, params, budget) -> PlanResult``.

    ``plan()`` validates the query before calling it, so ``func`` receives a
    :class:`~pathfuse.grid.GridMap`, finite in-bounds free ``start`` and
    ``goal`` arrays, an instance of ``params_cls`` and a
    :class:`~pathfuse.result.Budget`.
    """
    return register(PlannerSpec(name, params_cls, description, function=func))


_BUILTIN = ("astar", "astar-replan", "apf", "fusion", "ref6", "ref7", "astar-smooth", "thetastar",
            "lazy-thetastar", "shortest", "dwa", "mppi")


def planner_names() -> list[str]:
    """Names of the registered planners: the built-in ones first (fixed order), then plug-ins."""
    _load_builtin()
    order = {n: i for i, n in enumerate(_BUILTIN)}
    names = list(REGISTRY)
    return sorted(names, key=lambda n: (order.get(n, len(order)), names.index(n)))


def get_planner(name: str) -> PlannerSpec:
    """The spec registered under ``name`` (or an alias); :class:`ConfigError` listing the
    choices otherwise."""
    spec = REGISTRY.get(name) if isinstance(name, str) and _LOADED else None
    if spec is not None:
        return spec
    _load_builtin()
    try:
        return REGISTRY[_ALIASES.get(name, name)]
    except (KeyError, TypeError):
        raise ConfigError(
            f"unknown planner {_shown(name)}; choose one of: {', '.join(planner_names())}"
        ) from None


def make_params(spec: PlannerSpec, params: Mapping[str, Any] | None = None,
                key: str = "", error: type[ConfigError] = ConfigError) -> Any:
    """Build ``spec.params_cls`` from a dict, naming any unknown key or bad value.

    ``key`` prefixes the message (``planners[1].params``); without it the
    message starts with the planner's name (``fusion.r1_m: ...``).  The
    defaults are built once.
    """
    if not params:
        hit = _DEFAULTS.get(spec.name)
        if hit is None or type(hit) is not spec.params_cls:
            hit = _DEFAULTS[spec.name] = spec.params_cls()
        return hit
    try:  # the same parameters again (a sweep, a loop of plan() calls): built once
        ck = (spec.name, spec.params_cls, key, error,
              tuple(sorted((k, type(v), v) for k, v in params.items())))
        hit = _BUILT.get(ck)
    except TypeError:  # an unhashable value: build it (its check names the problem)
        ck, hit = None, None
    if hit is not None:
        return hit
    from pathfuse.validate import build

    built: Any = build(spec.params_cls, params, key or spec.name, error)
    if ck is not None:
        if len(_BUILT) >= 512:
            _BUILT.clear()
        _BUILT[ck] = built
    return built


_LOADED = False


def _load_builtin() -> None:
    """Import the built-in planner modules, which register themselves."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    import importlib

    for mod in ("astar", "apf", "fusion", "refs", "anyangle", "dwa", "mppi"):
        importlib.import_module(f"pathfuse.planners.{mod}")
