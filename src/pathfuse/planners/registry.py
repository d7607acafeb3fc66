"""The planner registry: global planners, controllers, and planners made of the two.

As in Nav2, a *global planner* turns a problem into a path and a *controller*
(:class:`~pathfuse.planners.base.Controller`) drives along it:

* :func:`register_global_planner` ``(name, func)``: ``func(problem)`` returns
  the (N, 2) waypoints in metres from the start to the goal, or None when it
  finds no path (the built-in ``astar``, ``astar-smooth``, ``thetastar``,
  ``lazy-thetastar``, ``shortest`` and ``jps`` are registered this way, in
  :mod:`pathfuse.planners.globals.builtin`);
* :func:`register_controller` ``(name, cls)``: a Controller subclass;
* :func:`register` a :class:`PlannerSpec`: a *preset* of a controller, a
  default global planner and a frozen parameter dataclass holding one set of
  defaults.  A planner whose parameters have a ``global_planner`` field
  follows any registered global planner
  (``plan(..., planner="fusion", global_planner="thetastar")``).

Third-party packages register through the entry-point group
``pathfuse.planners``: each entry point names a callable that registers, and
they are loaded the first time the registry is consulted (see
``docs/plugins.md``).  :func:`pathfuse.plan`
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
>>> global_planner_names()[:3]
['astar', 'jps', 'astar-smooth']
>>> get_global_planner("jps").description.split(" (")[0]
'jump point search'
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any

from pathfuse.result import ConfigError, PathfuseError
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
    "GlobalPlannerSpec",
    "GLOBAL_PLANNERS",
    "register_global_planner",
    "get_global_planner",
    "global_planner_names",
    "CONTROLLERS",
    "register_controller",
    "get_controller",
    "controller_names",
    "PluginError",
    "ENTRY_POINT_GROUP",
    "load_plugins",
    "catalogue",
]

#: The entry-point group third-party packages register their planners under.
ENTRY_POINT_GROUP = "pathfuse.planners"


class PluginError(PathfuseError):
    """A plug-in (an entry point of :data:`ENTRY_POINT_GROUP`, or a registered global
    planner) failed; the message names it."""


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
    global_planner : str or None
        The default global planner run before the controller (a name of
        :func:`global_planner_names`), or None for a controller without one
        (``apf``).  A planner whose parameters have a ``global_planner`` field
        runs the one named there instead.
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
        """Whether grid A* runs first by default (its time is part of the planner's)."""
        return self.global_planner == "astar"

    @property
    def any_global_planner(self) -> bool:
        """Whether the preset follows any registered global planner (its parameters have a
        ``global_planner`` field)."""
        return any(f.name == "global_planner" for f in dataclasses.fields(self.params_cls))

    def global_planner_of(self, params: Any) -> str | None:
        """The global planner that runs with ``params`` (the preset's default unless the
        parameters name another)."""
        return getattr(params, "global_planner", None) or self.global_planner

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

    def key_defaults(self) -> dict[str, Any]:
        """:meth:`defaults` as a study's run keys hash them: ``global_planner`` is left out
        while it is the preset's own, so a run that does not choose another global
        planner keeps the key it had before the parameter existed (stored studies stay
        valid); one that chooses another names it in its own parameters."""
        d = self.defaults()
        if d.get("global_planner", 0) == self.global_planner:
            del d["global_planner"]
        return d

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
    if spec.controller is not None and spec.controller not in CONTROLLERS.values():
        register_controller(spec.controller.name or spec.name, spec.controller)
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


@dataclass(frozen=True)
class GlobalPlannerSpec:
    """A registered global planner.

    Attributes
    ----------
    name : str
        Registry key (``plan(..., global_planner=name)``, ``--global-planner``).
    func : callable
        ``func(problem)`` (a :class:`~pathfuse.problem.Problem`) returning the
        (N, 2) waypoints in metres, or None for no path.  A function that
        also declares a ``params`` parameter receives the planner's
        parameters, one that declares ``max_expansions`` the search cap; the
        built-in ones return a :class:`~pathfuse.planners.globals.astar.GlobalPlan`.
    description : str
        One line for ``pathfuse planners``.
    warmup : callable or None
        Compiles (or loads) its numba kernels before any clock starts.
    kernels : callable or None
        Returns its numba kernels (to tell a cold numba cache).
    taut : bool
        Whether its paths turn where they touch the robot's clearance (any-angle
        paths): a holonomic follower then stops on each corner.
    plugin : str or None
        The entry point that registered it (None: built in or registered by code).
    """

    name: str
    func: Callable[..., Any]
    description: str = ""
    warmup: Callable[[], None] | None = None
    kernels: Callable[[], Sequence[Any]] | None = None
    taut: bool = True
    plugin: str | None = None

    @cached_property
    def accepts(self) -> frozenset[str]:
        """The optional keywords ``func`` declares (``params``, ``max_expansions``); read
        once per registration (``inspect.signature`` cost a third of a tiny ``plan()``)."""
        return _accepts(self.func)


def _accepts(func: Callable[..., Any]) -> frozenset[str]:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return frozenset()
    return frozenset(n for n in ("params", "max_expansions") if n in sig.parameters)


GLOBAL_PLANNERS: dict[str, GlobalPlannerSpec] = {}
CONTROLLERS: dict[str, type[Controller]] = {}
_PLUGIN: list[str | None] = [None]  # the entry point being loaded


def _check_name(name: Any, what: str) -> str:
    if not isinstance(name, str) or not name or name != name.strip() or " " in name:
        raise ConfigError(f"{what} name: must be a non-empty word, got {_shown(name)}")
    return name


def register_global_planner(name: str, func: Callable[..., Any], description: str = "", *,
                            warmup: Callable[[], None] | None = None,
                            kernels: Callable[[], Sequence[Any]] | None = None,
                            taut: bool = True) -> GlobalPlannerSpec:
    """Register ``func(problem) -> (N, 2) waypoints in metres, or None`` as a global planner.

    Every planner whose parameters have a ``global_planner`` field (``astar``,
    ``fusion``, ``dwa``, ``ref6``, ``ref7``, ``mppi``, the any-angle ones)
    can then follow it: ``plan(grid, s, g, planner="fusion",
    global_planner=name)``, ``--global-planner name``, or
    ``params: {global_planner: name}`` in a scenario or experiment file.
    ``func`` receives a :class:`~pathfuse.problem.Problem` whose start and
    goal are free for the robot disc; its waypoints should run from the
    start to the goal (``Problem.grid``, ``.start``, ``.goal``,
    ``.robot_radius_m``, ``.budget``).  A later registration of a name
    replaces it.

    Examples
    --------
    >>> import numpy as np
    >>> spec = register_global_planner(
    ...     "doc-straight", lambda pb: np.array([pb.start, pb.goal]),
    ...     description="a straight line (an example)")
    >>> from pathfuse import GridMap, plan
    >>> r = plan(GridMap.from_rows(["...."]), (0.5, 0.5), (3.5, 0.5),
    ...          global_planner="doc-straight")
    >>> r.path.tolist(), r.length
    ([[0.5, 0.5], [3.5, 0.5]], 3.0)
    >>> _ = GLOBAL_PLANNERS.pop("doc-straight")
    """
    _check_name(name, "global planner")
    if not callable(func):
        raise ConfigError(f"global planner {name!r}: func must be callable, got "
                          f"{_shown(func)}")
    spec = GlobalPlannerSpec(name, func, str(description), warmup, kernels, bool(taut),
                             _PLUGIN[0])
    GLOBAL_PLANNERS[name] = spec
    return spec


def get_global_planner(name: str) -> GlobalPlannerSpec:
    """The global planner registered under ``name``; :class:`ConfigError` listing the
    choices otherwise."""
    spec = GLOBAL_PLANNERS.get(name) if isinstance(name, str) and \
        (_LOADED or _GLOBAL_HOME.get(name) in _HOMES_DONE) else None
    if spec is not None:
        return spec
    _load_for(name, _GLOBAL_HOME)
    try:
        return GLOBAL_PLANNERS[name]
    except (KeyError, TypeError):
        raise ConfigError(f"global_planner: must be one of {', '.join(global_planner_names())}"
                          f", got {_shown(name)}") from None


_BUILTIN_GLOBAL = ("astar", "jps", "astar-smooth", "thetastar", "lazy-thetastar", "shortest")


def global_planner_names() -> list[str]:
    """Names of the registered global planners: the built-in ones first, then plug-ins."""
    _load_builtin()
    return _ordered(list(GLOBAL_PLANNERS), _BUILTIN_GLOBAL)


def register_controller(name: str, cls: type[Controller]) -> type[Controller]:
    """Register a :class:`~pathfuse.planners.base.Controller` subclass under ``name``
    (a planner preset names its class; ``pathfuse planners`` lists them)."""
    _check_name(name, "controller")
    CONTROLLERS[name] = cls
    return cls


def get_controller(name: str) -> type[Controller]:
    """The controller class registered under ``name``."""
    _load_builtin()
    try:
        return CONTROLLERS[name]
    except (KeyError, TypeError):
        raise ConfigError(f"controller: must be one of {', '.join(controller_names())}, got "
                          f"{_shown(name)}") from None


_BUILTIN_CONTROLLERS = ("follow", "replan", "apf", "fusion", "ref6", "ref7", "dwa", "mppi")


def controller_names() -> list[str]:
    """Names of the registered controllers: the built-in ones first, then plug-ins'."""
    _load_builtin()
    return _ordered(list(CONTROLLERS), _BUILTIN_CONTROLLERS)


def _ordered(names: list[str], builtin: Sequence[str]) -> list[str]:
    order = {n: i for i, n in enumerate(builtin)}
    return sorted(names, key=lambda n: (order.get(n, len(order)), names.index(n)))


_BUILTIN = ("astar", "astar-replan", "apf", "fusion", "ref6", "ref7", "astar-smooth", "thetastar",
            "lazy-thetastar", "shortest", "jps", "dwa", "mppi")


def planner_names() -> list[str]:
    """Names of the registered planners: the built-in ones first (fixed order), then plug-ins."""
    _load_builtin()
    return _ordered(list(REGISTRY), _BUILTIN)


def get_planner(name: str) -> PlannerSpec:
    """The spec registered under ``name`` (or an alias); :class:`ConfigError` listing the
    choices otherwise."""
    # resolved before (its module imported, or every one): a look-up, without a call
    spec = REGISTRY.get(name) if isinstance(name, str) and \
        (_LOADED or _HOME.get(name) in _HOMES_DONE) else None
    if spec is not None:
        return spec
    _load_for(name, _HOME)
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

# The module (under pathfuse.planners) that registers each built-in planner, older names
# included, and each built-in global planner: while no plug-in is installed, a look-up of
# one of them imports that module only, so a plan of one planner does not import the
# others (dwa, mppi, the shield...) nor create their numba dispatchers.
_HOME = {"astar": "controllers.follow", "astar-follow": "controllers.follow",
         "astar-replan": "controllers.follow", "apf": "controllers.apf",
         "fusion": "controllers.fusion", "ref6": "controllers.refs", "ref7": "controllers.refs",
         "astar-smooth": "controllers.anyangle", "thetastar": "controllers.anyangle",
         "lazy-thetastar": "controllers.anyangle", "shortest": "controllers.anyangle",
         "jps": "controllers.anyangle", "dwa": "controllers.dwa", "mppi": "controllers.mppi"}
_GLOBAL_HOME = dict.fromkeys(_BUILTIN_GLOBAL, "globals.builtin")
_NO_PLUGINS: list[bool] = []  # [whether the entry-point group is empty], looked up once
_HOMES_DONE: set[str | None] = set()


def _load_for(name: object, homes: Mapping[str, str]) -> None:
    """Make ``name`` resolvable: import its built-in module alone when ``name`` is a built-in
    one and no plug-in is installed (a plug-in may replace a built-in name, so then every
    built-in module is imported first and the plug-ins after them,
    :func:`_load_builtin`)."""
    home = homes.get(name) if isinstance(name, str) else None
    if _LOADED or home in _HOMES_DONE:
        return
    if home is not None and not _NO_PLUGINS:
        from importlib.metadata import entry_points

        _NO_PLUGINS.append(not entry_points(group=ENTRY_POINT_GROUP))
    if home is None or not _NO_PLUGINS[0]:
        _load_builtin()
        return
    import importlib

    importlib.import_module("pathfuse.planners.globals.builtin")
    importlib.import_module(f"pathfuse.planners.{home}")
    _HOMES_DONE.add(home)


def _load_builtin() -> None:
    """Import the built-in planner modules, which register themselves, then the plug-ins
    of the entry-point group :data:`ENTRY_POINT_GROUP`."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    import importlib

    for mod in ("globals.builtin", "controllers.follow", "controllers.apf",
                "controllers.fusion", "controllers.refs", "controllers.anyangle",
                "controllers.dwa", "controllers.mppi"):
        importlib.import_module(f"pathfuse.planners.{mod}")
    try:
        load_plugins()
    except PluginError:
        _LOADED = False  # every later use of the registry reports it again
        raise


_PLUGINS_DONE: list[str] = []


def load_plugins() -> list[str]:
    """Run the registering callable of every entry point of :data:`ENTRY_POINT_GROUP`
    (once per process); returns the names of the entry points loaded.

    Raises
    ------
    PluginError
        An entry point that cannot be imported, is not callable, or raises; the
        message names it and its distribution.
    """
    if _PLUGINS_DONE:
        return _PLUGINS_DONE[1:]
    _PLUGINS_DONE.append("")  # once, even when a plug-in fails
    from importlib.metadata import entry_points

    for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        dist = getattr(getattr(ep, "dist", None), "name", None)
        who = f"plug-in {ep.name!r} ({ep.value}" + (f", from {dist})" if dist else ")")
        _PLUGIN[0] = ep.name
        try:
            hook = ep.load()
            if not callable(hook):
                raise TypeError(f"{ep.value} is a {type(hook).__name__}, not a callable that "
                                "registers")
            hook()
        except Exception as exc:  # noqa: BLE001 - any error of third-party code, named
            _PLUGINS_DONE.clear()
            raise PluginError(f"{who}: {type(exc).__name__}: {exc}") from exc
        finally:
            _PLUGIN[0] = None
        _PLUGINS_DONE.append(ep.name)
    return _PLUGINS_DONE[1:]


def _param_rows(params_cls: type) -> list[dict[str, Any]]:
    from pathfuse.validate import param_spec

    defaults = params_cls()
    rows = []
    for f in dataclasses.fields(params_cls):
        ps = param_spec(f)
        d = getattr(defaults, f.name)
        row = {
            "name": f.name,
            "default": d if d is None or isinstance(d, (bool, int, float, str)) else str(d),
            "kind": ps.kind if ps else ("float" if isinstance(d, float) else "str"),
            "unit": ps.unit if ps else "",
            "help": ps.help if ps else "",
            "gt": ps.gt if ps else None, "ge": ps.ge if ps else None,
            "le": ps.le if ps else None,
            "choices": list(ps.choices) if ps else [],
            "optional": bool(ps.optional) if ps else d is None,
            "accepts": ps.describe() if ps else "",
        }
        if f.name == "global_planner":  # the registered ones, plug-ins' included
            names = global_planner_names()
            row.update(kind="choice", choices=names,
                       accepts="one of " + ", ".join(repr(n) for n in names))
        rows.append(row)
    return rows


def catalogue() -> dict[str, Any]:
    """Every registered planner, global planner and controller as JSON-ready data: the one
    description ``pathfuse planners`` prints and the playground's forms are built from.

    ``planners`` maps each name of :func:`planner_names` to its ``description``,
    ``offline``, ``online``, default ``global_planner``, ``any_global_planner``
    (whether it follows any registered one), ``controller`` (its registered
    name), ``controller_label``, ``aliases`` and ``params`` (name, default,
    kind, unit, help, the bounds ``gt``/``ge``/``le``, ``choices``, ``optional``
    and ``accepts``, the constraint in words); ``global_planners`` maps each
    name of :func:`global_planner_names` to its ``description`` and ``plugin``;
    ``controllers`` each registered controller to its ``label`` and the
    ``planners`` (presets) that use it.

    Examples
    --------
    >>> c = catalogue()
    >>> c["planners"]["fusion"]["controller"], c["planners"]["fusion"]["global_planner"]
    ('fusion', 'astar')
    >>> "jps" in c["global_planners"] and "jps" in c["planners"]["dwa"]["params"][0]["choices"]
    True
    """
    _load_builtin()
    ctrl_names = {cls: n for n, cls in CONTROLLERS.items()}
    planners: dict[str, Any] = {}
    for n in planner_names():
        spec = REGISTRY[n]
        ctrl = spec.controller
        planners[n] = {
            "description": spec.description, "offline": spec.offline, "online": spec.online,
            "global_planner": spec.global_planner,
            "any_global_planner": spec.any_global_planner,
            "controller": ctrl_names.get(ctrl) if ctrl is not None else None,
            "controller_label": getattr(ctrl, "label", "") or None if ctrl else None,
            "aliases": list(spec.aliases), "params": _param_rows(spec.params_cls),
        }
    globals_ = {n: {"description": GLOBAL_PLANNERS[n].description,
                    "plugin": GLOBAL_PLANNERS[n].plugin} for n in global_planner_names()}
    controllers = {n: {"label": getattr(CONTROLLERS[n], "label", "") or n,
                       "planners": [p for p, d in planners.items() if d["controller"] == n]}
                   for n in controller_names()}
    return {"planners": planners, "global_planners": globals_, "controllers": controllers}
