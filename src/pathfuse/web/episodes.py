"""Moving obstacles in the web app: scenarios in and out, and one episode run server-side.

A scenario in a request is the content of a scenario file (see
``examples/scenarios/crossing.yaml``) whose ``map`` is what
:meth:`pathfuse.web.maps.MapStore.resolve` accepts (``paper``, a spec, a map
id, an edited grid): never a file name.  The export writes a YAML file that
``pathfuse simulate`` runs unchanged: the map as its spec when it has one
(the paper map, a random or rows spec), else inline ``rows``.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pathfuse import validate
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.web.maps import ApiError, Limits, MapStore, grid_to_json
from pathfuse.web.service import check_budget_inputs

__all__ = ["build_scenario", "simulate_request", "export_request", "scenario_json",
           "upload_scenario"]

_SIM_KEYS = ("scenario", "planner", "seed")


def build_scenario(store: MapStore, doc: Any, limits: Limits) -> Any:
    """A checked :class:`~pathfuse.world.scenario.Scenario` from a request's scenario dict
    (its map resolved by the store; a map spec is kept for the export)."""
    from pathfuse.world.scenario import scenario_from_dict

    if not isinstance(doc, Mapping):
        raise ConfigError(f"scenario: must be a mapping, got {validate.short(doc)}")
    if "map" not in doc:
        raise ConfigError("scenario.map: missing")
    obstacles = doc.get("obstacles") or []
    if isinstance(obstacles, list):
        n = len(obstacles)
        check_budget_inputs(limits, 0, n)
    dt = doc.get("dt", 0.1)
    tl = doc.get("time_limit", 60.0)
    try:
        n_ticks = math.ceil(float(tl) / float(dt))
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        n_ticks = 0  # scenario_from_dict names the bad value
    check_budget_inputs(limits, n_ticks, 0)
    grid, spec = store.resolve(doc["map"], None, "scenario.map")
    d = dict(doc)
    d["map"] = grid
    try:
        sc = scenario_from_dict(d, default_name=str(doc.get("name") or "scenario"))
    except PathfuseError as exc:
        raise type(exc)(f"scenario.{exc}" if not str(exc).startswith("scenario") else str(exc)
                        ) from None
    if spec is not None:
        sc = sc.replace(map_spec=spec)
    return sc


def simulate_request(store: MapStore, body: Any, limits: Limits) -> dict[str, Any]:
    """``POST /api/simulate``: run one episode and return it with its trajectories.

    ``{"scenario": {...}, "planner": NAME or {"name", "params"}, "seed": N}``
    (``planner`` and ``seed`` default to the scenario's).  The answer is
    :meth:`pathfuse.world.Episode.to_dict` plus ``sensed`` (which discs the
    planner saw, per tick), ``path_updates``, the robot, start and goal.
    """
    from pathfuse.world.episode import simulate

    if not isinstance(body, Mapping):
        raise ConfigError(f"request: must be a JSON object, got {validate.short(body)}")
    validate.mapping(body, "", _SIM_KEYS)
    if "scenario" not in body:
        raise ConfigError("scenario: missing")
    sc = build_scenario(store, body["scenario"], limits)
    seed = body.get("seed")
    if seed is not None:
        seed = validate.integer(seed, "seed", ge=0)
    ep = simulate(sc, planner=body.get("planner"), seed=seed)
    d = ep.to_dict(trajectories=True)
    d["sensed"] = ep.sensed.astype(int).tolist()
    d["path_updates"] = [{"tick": int(t), "path": p.tolist()} for t, p in ep.path_updates]
    d["robot"] = _robot_form(sc.robot)
    d["start"], d["goal"] = list(sc.start), list(sc.goal)
    d["goal_tolerance"] = sc.goal_tolerance
    return d


def _robot_form(robot: Any) -> dict[str, float]:
    """The robot's values the page shows (set or not): radius, speed, sensing radius."""
    return {"radius": robot.radius_m, "max_speed": robot.max_speed_mps,
            "sensing_radius": robot.sensing_radius_m}


def export_yaml(sc: Any) -> str:
    """The YAML text of a scenario, runnable by ``pathfuse simulate``."""
    import yaml

    d = sc.to_dict()
    if not d.get("description"):
        d.pop("description", None)
    return yaml.safe_dump(d, sort_keys=False, default_flow_style=None, width=1 << 20)


def export_request(store: MapStore, body: Any, limits: Limits) -> dict[str, Any]:
    """``POST /api/scenario/export``: ``{"scenario": {...}}`` -> ``{"yaml", "filename"}``."""
    if not isinstance(body, Mapping):
        raise ConfigError(f"request: must be a JSON object, got {validate.short(body)}")
    validate.mapping(body, "", ("scenario",))
    if "scenario" not in body:
        raise ConfigError("scenario: missing")
    sc = build_scenario(store, body["scenario"], limits)
    name = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in sc.name) or "scenario"
    return {"yaml": export_yaml(sc), "filename": f"{name}.yaml"}


def scenario_json(store: MapStore, sc: Any) -> dict[str, Any]:
    """A scenario for the page: its dict with the map replaced by a map id, and the map."""
    spec = sc.map_spec if isinstance(sc.map_spec, Mapping) and \
        any(k in sc.map_spec for k in ("paper", "random", "rows")) else None
    e = store.add_upload(sc.grid, sc.grid.name, spec)
    d = sc.to_dict()
    d["map"] = {"id": e.id}
    d["robot"] = {**d["robot"], **_robot_form(sc.robot)}  # the page's form shows these
    return {"scenario": d, "map": grid_to_json(sc.grid, e.id)}


def load_catalog_scenario(store: MapStore, scenario_id: str) -> dict[str, Any]:
    """``GET /api/scenarios/{id}``: a scenario of the catalog (a file the server found)."""
    from pathfuse.web.files import check_scenario_cells
    from pathfuse.world.scenario import load_scenario

    path = store.scenarios.get(scenario_id)
    if path is None:
        raise ApiError(404, f"scenario: no scenario with id {validate.short(scenario_id)} on "
                            "this server (GET /api/scenarios lists them)")
    check_scenario_cells(path, store.limits, scenario_id)
    return scenario_json(store, load_scenario(path))


def upload_scenario(store: MapStore, name: str, data: bytes, limits: Limits) -> dict[str, Any]:
    """``POST /api/scenarios``: read an uploaded scenario YAML (its map must not name a file)."""
    from pathfuse.safeyaml import load_yaml
    from pathfuse.world.scenario import load_scenario

    base = os.path.basename(str(name).replace("\\", "/")) or "scenario.yaml"
    safe = "".join(ch if ch.isalnum() or ch in "._-" else "_" for ch in base).lstrip(".")
    if not safe.lower().endswith((".yaml", ".yml")):
        safe = (safe or "scenario") + ".yaml"
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{safe}: not a UTF-8 text file") from None
    try:
        doc = load_yaml(data, safe)
    except PathfuseError:
        doc = None  # load_scenario below names the line
    if isinstance(doc, Mapping):
        _check_scenario_map(store, doc.get("map"), safe)
        obstacles = doc.get("obstacles")
        if isinstance(obstacles, list):
            check_budget_inputs(limits, 0, len(obstacles))
    with tempfile.TemporaryDirectory(prefix="pathfuse-scenario-") as tmp:
        path = Path(tmp) / safe
        path.write_bytes(data)
        try:
            sc = load_scenario(path)
        except PathfuseError as exc:
            raise type(exc)(str(exc).replace(str(path), safe)) from None
    check_budget_inputs(limits, sc.n_steps, len(sc.obstacles))
    sc = sc.replace(source=None)
    return scenario_json(store, sc)


_SCENARIO_SOURCES = ("paper", "random", "rows")


def _check_scenario_map(store: MapStore, m: Any, where: str) -> None:
    """A scenario file's map must be generated (paper, random, rows) and within the cell
    limit; anything else, a file name above all, is refused before the file is loaded."""
    refuse = ApiError(400, f"{where}: map: the server reads no file a scenario names; use a "
                           "paper, random or rows map, or export the scene from the page")
    if isinstance(m, str):
        if m.strip().lower() != "paper":
            raise refuse
        return
    if not isinstance(m, Mapping):
        return  # load_scenario names the problem
    sources = [k for k in m if k in _SCENARIO_SOURCES]
    if len(sources) != 1 or any(k not in _SCENARIO_SOURCES and k not in
                                ("resolution", "origin", "name") for k in m):
        raise refuse
    store.check_spec_size(m, f"{where}: map")
