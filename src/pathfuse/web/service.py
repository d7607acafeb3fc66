"""The work behind each API endpoint, as plain functions of a JSON body (no web framework).

Each function checks its body with :mod:`pathfuse.validate`, so a bad value
raises the same one-line :class:`~pathfuse.PathfuseError` as the library and
the command line; :mod:`pathfuse.web.app` turns it into a 4xx answer.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pathfuse import validate
from pathfuse.result import Budget, ConfigError
from pathfuse.web.maps import ApiError, Limits, MapStore, grid_to_json, pack_mask

__all__ = ["planners_json", "plan_request", "field_request", "map_request", "parse_body",
           "LAYERS"]

LAYERS = ("closed", "cspace", "attractors")
"""Layers ``POST /api/plan`` can add under ``extras``."""

_PLAN_KEYS = ("map", "seed", "start", "goal", "planner", "params", "robot_radius",
              "time_limit", "extras", "layers")


def parse_body(raw: bytes, max_depth: int = 32) -> Any:
    """A JSON request body: UTF-8, standard JSON (no ``NaN``), nested at most ``max_depth``
    levels of objects and lists.

    Raises
    ------
    ApiError
        400 naming what is wrong.

    >>> parse_body(b'{"map": "paper"}')
    {'map': 'paper'}
    >>> parse_body(b"[" * 40 + b"]" * 40)
    Traceback (most recent call last):
    ...
    pathfuse.web.limits.ApiError: request body: JSON nested deeper than 32 levels
    """
    import json

    def no_constant(name: str) -> Any:
        raise ValueError(f"{name} is not JSON")

    too_deep = ApiError(400, f"request body: JSON nested deeper than {max_depth} levels")
    try:
        doc = json.loads(raw.decode("utf-8"), parse_constant=no_constant)
    except RecursionError:
        raise too_deep from None
    except UnicodeDecodeError as exc:
        raise ApiError(400, f"request body: not valid JSON (not UTF-8 at byte {exc.start})"
                       ) from None
    except ValueError as exc:
        raise ApiError(400, f"request body: not valid JSON ({exc})") from None
    stack: list[tuple[Any, int]] = [(doc, 1)]
    while stack:
        node, depth = stack.pop()
        children = node.values() if isinstance(node, dict) else node \
            if isinstance(node, list) else ()
        for child in children:
            if isinstance(child, (dict, list)):
                if depth + 1 > max_depth:
                    raise too_deep
                stack.append((child, depth + 1))
    return doc


def planners_json() -> list[dict[str, Any]]:
    """Every registered planner with its parameters' metadata, for generated forms.

    One entry per planner of :func:`pathfuse.planner_names`, in its order: the
    registry's :func:`~pathfuse.planners.registry.catalogue` entry (``description``,
    ``offline``, ``online``, ``global_planner``, ``controller``, ``aliases``,
    ``params``: name, default, kind (``float``, ``int``, ``bool``, ``choice``,
    ``str``), unit, help, the bounds ``gt``/``ge``/``le``, ``choices``,
    ``optional`` and ``accepts``) with its ``name`` and ``layers`` (which of
    :data:`LAYERS` apply).
    """
    from pathfuse.planners.registry import REGISTRY, catalogue

    out = []
    for name, d in catalogue()["planners"].items():
        spec = REGISTRY[name]
        names = {q["name"] for q in d["params"]}
        layers = []
        if spec.uses_astar:
            layers.append("closed")
        if spec.uses_astar and "r1_m" in names:
            layers.append("attractors")
        out.append({"name": name, **d, "layers": layers})
    return out


def _keys(body: Any, allowed: tuple[str, ...], what: str = "request") -> Mapping[str, Any]:
    if not isinstance(body, Mapping):
        raise ConfigError(f"{what}: must be a JSON object, got {validate.short(body)}")
    for k in body:
        if k not in allowed:
            raise ConfigError(f"{k}: unknown key (allowed: {', '.join(allowed)})")
    return body


def _grid(store: MapStore, body: Mapping[str, Any]) -> tuple[Any, Any]:
    if "map" not in body:
        raise ConfigError("map: missing ('paper', a map id, or a map spec)")
    return store.resolve(body["map"], body.get("seed"))


def _points(body: Mapping[str, Any], grid: Any, paper: bool) -> tuple[tuple[float, float],
                                                                       tuple[float, float]]:
    from pathfuse.generate import PAPER_GOAL, PAPER_START

    if ("start" not in body or "goal" not in body) and not paper:
        raise ConfigError("start and goal are required unless map is 'paper'")
    start = validate.point(body["start"], "start") if "start" in body else PAPER_START
    goal = validate.point(body["goal"], "goal") if "goal" in body else PAPER_GOAL
    return (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))


def _is_paper(body: Mapping[str, Any]) -> bool:
    m = body.get("map")
    return (isinstance(m, str) and m.strip().lower() == "paper") or \
        (isinstance(m, Mapping) and "paper" in m)


def _time_limit(body: Mapping[str, Any], limits: Limits) -> float:
    t = body.get("time_limit")
    if t is None:
        return limits.time_budget_s
    return min(validate.number(t, "time_limit", gt=0), limits.time_budget_s)


def map_request(store: MapStore, body: Any) -> dict[str, Any]:
    """``POST /api/map``: the grid of a map spec (``paper`` + seed, random, rows, blank) as
    JSON, kept under a new id so that later requests can name it."""
    body = _keys(body, ("map", "seed"))
    grid, spec = _grid(store, body)
    e = store.add_upload(grid, grid.name, spec)
    d = grid_to_json(grid, e.id)
    d["spec"] = spec
    return d


def plan_request(store: MapStore, body: Any, limits: Limits) -> dict[str, Any]:
    """``POST /api/plan``: the JSON object of ``pathfuse plan --json``.

    With ``"extras": true`` it adds ``extras``: the independent metrics of
    :func:`pathfuse.metrics.evaluate` (minimum clearance, collision-free),
    the A* path of the hybrids, and the layers asked for in ``layers``
    (``closed``: the A* closed set as packed bits, and its cells in expansion order as
    base64 int32 row-major indices; ``cspace``: the inflated
    map; ``attractors``: per path point, the A* waypoints attracting there).
    """
    from pathfuse.api import plan_query

    body = _keys(body, _PLAN_KEYS)
    grid, _ = _grid(store, body)
    start, goal = _points(body, grid, _is_paper(body))
    planner = validate.text(body.get("planner", "astar"), "planner")
    params = body.get("params") or {}
    validate.mapping(params, "params")
    radius = validate.number(body.get("robot_radius", 0.0), "robot_radius", ge=0)
    layers = body.get("layers") or []
    if not isinstance(layers, list) or any(x not in LAYERS for x in layers):
        raise ConfigError(f"layers: must be a list of {', '.join(map(repr, LAYERS))}, got "
                          f"{validate.short(layers)}")
    extras = validate.flag(body.get("extras", False), "extras") or bool(layers)
    limit = _time_limit(body, limits)
    # pathfuse.plan()'s body, with the parameters as a dict (no clash with its keywords)
    result, spec, cfg, problem = plan_query(grid, start, goal, planner, params,
                                            robot_radius_m=radius,
                                            budget=Budget(time_limit_s=limit))
    on_astar = spec.global_planner_of(cfg) == "astar"
    d = result.to_dict()
    d["map"] = grid.name
    d["start"], d["goal"] = list(start), list(goal)
    d["global_planner"] = spec.global_planner_of(cfg)
    if not extras:
        return d
    from pathfuse.metrics import evaluate

    m = evaluate(grid, result, radius)
    ex: dict[str, Any] = {
        "min_clearance_m": None if not math.isfinite(m["min_clearance_m"])
        else float(m["min_clearance_m"]),
        "collision_free": bool(m["collision_free"]),
        "smoothness_rad": float(m["smoothness_rad"]),
    }
    ap = result.info.get("astar_path")
    if ap is not None:
        ex["astar_path"] = np.asarray(ap, dtype=float).tolist()
    heuristic = getattr(cfg, "heuristic", "euclidean")
    cutting = bool(getattr(cfg, "corner_cutting", False))
    if "closed" in layers and on_astar:
        from pathfuse.web.layers import closed_order, i32

        got = closed_order(problem, heuristic, cutting, limit)
        ex["closed"] = None if got is None else {"bits": pack_mask(got[0]),
                                                 "count": int(got[0].sum()),
                                                 "order": i32(got[1])}
    if "cspace" in layers:
        ex["cspace"] = {"bits": pack_mask(grid.cspace(radius).occupied),
                        "robot_radius": radius}
    r1 = getattr(cfg, "r1_m", None)
    if "attractors" in layers and on_astar and r1 is not None and len(result.path):
        from pathfuse.planners.globals.astar import plan_global
        from pathfuse.web.layers import attractors

        gp = plan_global(problem, heuristic)
        if gp.success:
            wp = np.asarray(gp.waypoints, dtype=float)
            gx, gy = goal
            if wp.shape[0] == 0 or wp[-1, 0] != gx or wp[-1, 1] != gy:
                wp = np.concatenate([wp.reshape(-1, 2), [[gx, gy]]])
            ex["attractors"] = {
                "r1_m": float(r1), "ahead": getattr(cfg, "ahead", "progress"),
                "waypoints": wp.tolist(),
                "per_point": attractors(problem, result.path, wp, float(r1),
                                        getattr(cfg, "ahead", "progress")),
            }
    d["extras"] = ex
    return d


_FIELD_KEYS = ("map", "seed", "goal", "planner", "params", "max_side", "arrows")


def field_request(store: MapStore, body: Any, limits: Limits) -> dict[str, Any]:
    """``POST /api/field``: the APF potential and force of a map and goal (see
    :func:`pathfuse.web.layers.potential_field`), with the gains of ``planner``
    (default ``apf``) and ``params``."""
    from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
    from pathfuse.planners.registry import get_planner, make_params
    from pathfuse.web.layers import potential_field

    body = _keys(body, _FIELD_KEYS)
    grid, _ = _grid(store, body)
    from pathfuse.generate import PAPER_GOAL

    if "goal" not in body and not _is_paper(body):
        raise ConfigError("goal: missing (required unless map is 'paper')")
    goal = validate.point(body.get("goal", PAPER_GOAL), "goal")
    spec = get_planner(validate.text(body.get("planner", "apf"), "planner"))
    params = body.get("params") or {}
    validate.mapping(params, "params")
    cfg = make_params(spec, params)
    max_side = validate.integer(body.get("max_side", 256), "max_side", ge=2, le=512)
    arrows = validate.integer(body.get("arrows", 24), "arrows", ge=2, le=64)
    out = potential_field(grid, goal, float(getattr(cfg, "k_att", K_ATT)),
                          float(getattr(cfg, "k_rep", K_REP)),
                          float(getattr(cfg, "rho0_m", RHO0_M)), max_side, arrows)
    out["map"] = grid.name
    out["planner"] = spec.name
    return out


def check_budget_inputs(limits: Limits, n_ticks: int, n_discs: int) -> None:
    """Refuse an episode longer or more crowded than the server allows, before running it."""
    if n_ticks > limits.max_ticks:
        raise ApiError(413, f"time_limit / dt = {n_ticks} ticks is more than this server's "
                            f"limit of {limits.max_ticks} ticks per episode")
    if n_discs > limits.max_discs:
        raise ApiError(413, f"obstacles: {n_discs} discs is more than this server's limit of "
                            f"{limits.max_discs}")
