"""Worker side of a sweep: run a batch of runs and return their result rows.

Everything here runs in a worker process (a local process pool, a Dask
worker, or the client itself when ``workers=1``).  Workers never touch the
result store; they return plain dicts that the client writes.

A *batch* is a list of *groups*; a group is a map instance (a ``map_key``
with its loadable spec, or the map object itself) and the runs on it.  Loaded
maps, inflated maps and reference lengths are cached per process, so a
worker that gets many batches on the same map loads it once.

The run **kind** selects the executor (:data:`KINDS`): ``"static"`` plans with
:func:`pathfuse.plan` on a map; ``"dynamic"`` runs an episode with
:func:`pathfuse.world.simulate`; ``"irsim"`` runs an episode in an IR-SIM world
(:mod:`pathfuse.integrations.irsim_run`).  A run that raises becomes a row with
``status_name = "ERROR"`` and the error text; it never stops the batch.
"""

from __future__ import annotations

import functools
import json
import math
import os
import socket
import sys
import threading
import time
import traceback
from collections import OrderedDict
from collections.abc import Callable, Mapping
from datetime import datetime, timezone
from typing import Any

import numpy as np

from pathfuse.bench.plugins import ensure_imports

__all__ = ["execute_batch", "execute_run", "KINDS", "clear_caches"]

_MAP_CACHE_SIZE = 8
_MAPS: OrderedDict[Any, Any] = OrderedDict()
_REFS: OrderedDict[Any, tuple[float | None, str | None]] = OrderedDict()
_LOCK = threading.RLock()  # Dask workers may run several threads


def clear_caches() -> None:
    """Forget the maps and reference lengths cached in this process."""
    _MAPS.clear()
    _REFS.clear()


def _lru_put(cache: OrderedDict[Any, Any], key: Any, value: Any, size: int) -> None:
    cache[key] = value
    cache.move_to_end(key)
    while len(cache) > size:
        cache.popitem(last=False)


# --------------------------------------------------------------------------- batch
def execute_batch(batch: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Run every run of ``batch``; one result row (dict) per run, in order.

    ``batch = {"imports": [...], "store_paths": bool, "groups": [group, ...]}``
    with ``group = {"kind", "map_key", "map_spec", "base_dir", "grid" (optional
    map object), "runs": [run, ...]}``; a run carries ``key``, ``planner``,
    ``params``, ``seed``, ``query``, ``limits``, ``robot_radius_m``,
    ``reference``.
    """
    ensure_imports(batch.get("imports", ()))
    out: list[dict[str, Any]] = []
    for group in batch["groups"]:
        for run in group["runs"]:
            out.append(execute_run(group, run, store_paths=bool(batch.get("store_paths"))))
    return out


def execute_run(group: Mapping[str, Any], run: Mapping[str, Any],
                store_paths: bool = False) -> dict[str, Any]:
    """Run one run; never raises an ``Exception`` (it becomes an ERROR row)."""
    started = datetime.now(timezone.utc)
    t0 = time.perf_counter()
    row: dict[str, Any] = {"run_key": run["key"]}
    try:
        kind = group["kind"]
        fn = KINDS.get(kind)
        if fn is None:
            raise ValueError(f"unknown run kind {kind!r}; known kinds: {', '.join(KINDS)}")
        row.update(fn(group, run, store_paths))
    except Exception as exc:  # noqa: BLE001 - a failing run is data, not a crash
        row.update(_error_row(exc))
    row["wall_time"] = time.perf_counter() - t0
    row["started_at"] = started.isoformat(timespec="microseconds")
    row["finished_at"] = datetime.now(timezone.utc).isoformat(timespec="microseconds")
    row["memory"] = _peak_rss_mb()
    row["host"] = socket.gethostname()
    row["worker"] = _worker_name()
    from pathfuse._version import __version__

    row["pathfuse_version"] = __version__
    return row


def _peak_rss_mb() -> float | None:
    """Peak resident memory of this process in MB (None where unknown)."""
    try:
        import resource
    except ImportError:  # not POSIX
        return None
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / (1024.0 * 1024.0) if sys.platform == "darwin" else kb / 1024.0


def _worker_name() -> str:
    if "distributed" in sys.modules:  # never import dask just to ask
        try:
            return str(sys.modules["distributed"].get_worker().address)
        except Exception:  # noqa: BLE001 - not on a dask worker
            pass
    return f"pid {os.getpid()}"


def _error_row(exc: BaseException) -> dict[str, Any]:
    text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    return {"status_name": "ERROR", "solved": False, "error": text,
            "traceback": "".join(traceback.format_exception(type(exc), exc,
                                                            exc.__traceback__))}


# --------------------------------------------------------------------------- maps
def _grid(group: Mapping[str, Any]) -> Any:
    with _LOCK:
        return _grid_locked(group)


def _grid_locked(group: Mapping[str, Any]) -> Any:
    key = group["map_key"]
    if key in _MAPS:
        _MAPS.move_to_end(key)
        return _MAPS[key]
    grid = group.get("grid")
    if grid is None:
        from pathfuse.bench.spec import load_map

        grid = load_map(group["map_spec"], group.get("base_dir") or ".")
    _lru_put(_MAPS, key, grid, _MAP_CACHE_SIZE)
    return grid


def _cspace(grid: Any, radius: float) -> Any:
    """The free space of the robot's centre (cached on the map itself)."""
    return grid.cspace(radius) if radius > 0 else grid


def random_query(grid: Any, seed: int, index: int, min_distance_m: float,
                 map_key: str = "", attempts: int = 1000) -> tuple[np.ndarray, np.ndarray]:
    """A deterministic random (start, goal) pair of free cell centres in one component.

    The pair depends only on the map, ``seed`` and ``index``.  Raises
    ``ValueError`` when no pair ``min_distance_m`` apart is found in
    ``attempts`` draws.

    >>> from pathfuse.grid import GridMap
    >>> g = GridMap.from_rows(["....", ".##.", "...."])
    >>> s, t = random_query(g, seed=1, index=0, min_distance_m=2.0)
    >>> bool(g.is_free(np.array([s, t])).all()), float(np.hypot(*(s - t))) >= 2.0
    (True, True)
    """
    free = np.flatnonzero(~grid.occupied.ravel())
    if free.size < 2:
        raise ValueError(f"map {grid.name!r} has fewer than two free cells")
    labels = _component_labels(grid)
    salt = int.from_bytes(bytes.fromhex(map_key[:8]), "big") if map_key else 0
    rng = np.random.default_rng([int(seed), int(index), salt])
    w = grid.width
    for _ in range(attempts):
        a, b = rng.choice(free, size=2, replace=False)
        ra, ca = divmod(int(a), w)
        rb, cb = divmod(int(b), w)
        if labels[ra, ca] != labels[rb, cb]:
            continue
        pts = grid.cell_to_world(np.array([[ra, ca], [rb, cb]]))
        if float(np.hypot(*(pts[0] - pts[1]))) >= min_distance_m:
            return pts[0], pts[1]
    raise ValueError(f"no random start/goal pair {min_distance_m:g} m apart in one free "
                     f"region of map {grid.name!r} after {attempts} draws")


def _component_labels(grid: Any) -> np.ndarray:
    comps = getattr(grid, "components", None)
    labels = comps() if callable(comps) else comps
    if isinstance(labels, tuple):
        labels = labels[0]
    if labels is None or np.shape(labels) != grid.shape:
        from scipy import ndimage

        labels, _ = ndimage.label(~grid.occupied)
    return np.asarray(labels)


def _query_points(group: Mapping[str, Any], run: Mapping[str, Any],
                  grid: Any) -> tuple[np.ndarray, np.ndarray]:
    q = run["query"]
    if "random" in q:
        return random_query(grid, run["seed"], q["random"], q.get("min_distance_m", 0.0),
                            group["map_key"])
    return np.asarray(q["start"], dtype=float), np.asarray(q["goal"], dtype=float)


# --------------------------------------------------------------------------- static runs
def _defaults(planner: str) -> dict[str, Any]:
    from pathfuse.planners.registry import get_planner

    spec = get_planner(planner)
    hit = _DEFAULTS.get(spec.name)
    if hit is None or hit[0] is not spec:
        hit = _DEFAULTS[spec.name] = (spec, spec.defaults())
    return hit[1]


_DEFAULTS: dict[str, tuple[Any, dict[str, Any]]] = {}


def _plan_params(planner: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """Params from JSON (lists) back to the dataclass defaults' types (tuples)."""
    defaults = _defaults(planner)
    out = {}
    for k, v in params.items():
        d = defaults.get(k)
        out[k] = tuple(v) if isinstance(d, tuple) and isinstance(v, list) else v
    return out


def _budget(limits: Mapping[str, Any]) -> Any:
    from pathfuse.result import Budget

    return Budget(max_iterations=limits.get("max_iterations"),
                  time_limit_s=limits.get("time_limit_s"))


def _reference(group: Mapping[str, Any], run: Mapping[str, Any], pgrid: Any,
               start: np.ndarray, goal: np.ndarray) -> tuple[float | None, str | None]:
    q = run["query"]
    if "optimal_length" in q and run["robot_radius_m"] <= 0:
        return float(q["optimal_length"]), "scen"  # the benchmark's own optimum
    ref = run.get("reference")
    if ref is None:
        return None, None
    key = (group["map_key"], float(run["robot_radius_m"]), ref["planner"],
           json.dumps(ref.get("params") or {}, sort_keys=True),
           tuple(np.round(start, 9)), tuple(np.round(goal, 9)))
    with _LOCK:
        if key in _REFS:
            return _REFS[key]
    from pathfuse.api import plan

    res = plan(pgrid, start, goal, planner=ref["planner"],
               robot_radius_m=float(run["robot_radius_m"]), budget=_budget(run["limits"]),
               **_plan_params(ref["planner"], ref.get("params") or {}))
    val = (float(res.length), ref["planner"]) if res.success else (None, ref["planner"])
    with _LOCK:
        _lru_put(_REFS, key, val, 4096)
    return val


def _metrics(grid: Any, result: Any, radius: float) -> dict[str, Any] | None:
    try:
        from pathfuse.metrics import evaluate  # type: ignore[import-not-found]
    except ImportError:
        return None
    return dict(evaluate(grid, result, radius))


def _num(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def _pick(d: Mapping[str, Any], *names: str) -> Any:
    for n in names:
        if n in d:
            return d[n]
    return None


def _scalars(d: Mapping[str, Any]) -> dict[str, Any]:
    """The JSON-friendly scalar entries of a dict (numbers, strings, bools)."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        t = type(v)
        if t is float:  # the common cases first
            out[str(k)] = v if math.isfinite(v) else None
        elif t is str:
            out[str(k)] = v
        elif t is bool or t is int:
            out[str(k)] = v
        elif isinstance(v, (bool, np.bool_)):
            out[str(k)] = bool(v)
        elif isinstance(v, (int, np.integer)):
            out[str(k)] = int(v)
        elif isinstance(v, (float, np.floating)):
            out[str(k)] = float(v) if math.isfinite(float(v)) else None
        elif isinstance(v, str):
            out[str(k)] = str(v)
    return out


@functools.lru_cache(maxsize=1024)
def _is_timing(key: str) -> bool:
    k = key.lower()
    return "time" in k or k.endswith(("_s", "per_s", "_ms", "_us", "_ns")) or "rate" in k


def _split_info(info: Mapping[str, Any]) -> dict[str, str]:
    """Planner extras as JSON: ``info`` (reproducible) and ``timing`` (clock readings)."""
    sc = _scalars(info)
    timing = {k: v for k, v in sc.items() if _is_timing(k)}
    rest = {k: v for k, v in sc.items() if k not in timing}
    return {"info": json.dumps(rest, sort_keys=True),
            "timing": json.dumps(timing, sort_keys=True)}


def _metric_columns(m: Mapping[str, Any] | None) -> dict[str, Any]:
    if not m:
        return {}
    cf = _pick(m, "collision_free")
    coll = _pick(m, "collisions", "collision_count", "n_collisions")
    if coll is None and cf is not None:
        coll = 0 if bool(cf) else 1
    steps = _pick(m, "steps", "n_steps")
    return {
        "solution_clearance": _num(_pick(m, "min_clearance_m", "min_clearance",
                                         "clearance_m", "clearance")),
        "solution_smoothness": _num(_pick(m, "smoothness", "smoothness_rad",
                                          "total_turn_rad", "smoothness_total")),
        "collision_free": None if cf is None else bool(cf),
        "collisions": None if coll is None else int(coll),
        "steps": None if steps is None else int(steps),
        "metrics": json.dumps({k: v for k, v in _scalars(m).items() if not _is_timing(k)},
                              sort_keys=True),
    }


def _path_blob(path: np.ndarray) -> bytes:
    return np.ascontiguousarray(path, dtype="<f8").tobytes()


def run_static(group: Mapping[str, Any], run: Mapping[str, Any],
               store_paths: bool) -> dict[str, Any]:
    """Plan one static query and measure it (the ``"static"`` kind)."""
    from pathfuse.api import plan

    grid = _grid(group)
    radius = float(run["robot_radius_m"])
    start, goal = _query_points(group, run, _cspace(grid, radius))
    res = plan(grid, start, goal, planner=run["planner"], robot_radius_m=radius,
                        budget=_budget(run["limits"]),
                        **_plan_params(run["planner"], run["params"]))
    path = np.asarray(res.path, dtype=float).reshape(-1, 2)
    row: dict[str, Any] = {
        "status_name": res.status.name,
        "solved": bool(res.success),
        "time": float(res.time_s),
        "solution_length": float(res.length) if res.success else None,
        "path_length": float(res.length),
        "expansions": int(res.expansions),
        "iterations": int(res.iterations),
        "message": res.message,
        "start_x": float(start[0]), "start_y": float(start[1]),
        "goal_x": float(goal[0]), "goal_y": float(goal[1]),
        "solution_segments": max(0, int(path.shape[0]) - 1) if res.success else None,
    }
    row.update(_split_info(res.info or {}))
    if path.shape[0] >= 2:
        row.update(_metric_columns(_metrics(grid, res, radius)))
    ref_len, ref_src = _reference(group, run, grid, start, goal)
    row["reference_length"] = ref_len
    row["reference_source"] = ref_src
    if res.success and ref_len:
        row["R_length"] = (float(res.length) - ref_len) / ref_len
    if store_paths and path.shape[0]:
        row["path"] = _path_blob(path)
    return row


# --------------------------------------------------------------------------- dynamic runs
def _scenario(group: Mapping[str, Any]) -> Any:
    """The group's dynamic scenario, loaded once per process."""
    from pathfuse.bench.spec import load_dynamic

    key = (group["map_key"], "scenario")
    with _LOCK:
        if key not in _MAPS:
            sc = group.get("grid")  # shipped by a Dask client
            _lru_put(_MAPS, key, sc if sc is not None else load_dynamic(group["map_spec"]),
                     _MAP_CACHE_SIZE)
        return _MAPS[key]


def run_dynamic(group: Mapping[str, Any], run: Mapping[str, Any],
                store_paths: bool) -> dict[str, Any]:
    """One episode in a dynamic world (the ``"dynamic"`` kind).

    Calls :func:`pathfuse.world.simulate` with the online planner, its
    parameters and the run's seed, and maps the :class:`~pathfuse.world.Episode`
    to result columns (see :func:`episode_row`).
    """
    from pathfuse.world import simulate

    params = dict(run["params"])
    choice = {"name": run["planner"], "params": params} if params else run["planner"]
    spec = group.get("map_spec") or {}
    dyn = spec.get("dynamic") if isinstance(spec, Mapping) else None
    # a scenario picked from a family by its index keeps its own episode seed;
    # otherwise the run's seed is the episode seed
    seed = None if isinstance(dyn, Mapping) and "family_seed" in dyn else int(run["seed"])
    ep = simulate(_scenario(group), planner=choice, seed=seed)
    return episode_row(ep, store_paths)


def episode_row(ep: Any, store_paths: bool = False) -> dict[str, Any]:
    """Result columns of an :class:`~pathfuse.world.Episode`.

    ``time`` is the planner's total compute time (``setup_time_s`` plus every
    tick's ``plan_times_s``); ``time_to_goal`` the simulated time to reach
    the goal; ``solution_length`` the driven trajectory's length (reached
    episodes); ``solution_clearance`` the least clearance to any obstacle;
    ``collisions`` 1 when the episode ended in a collision.  ``metrics`` holds the
    episode's scalar values, with ``collision_at_fault`` and the safety shield's
    counts (``shield_asked``, ``shield_nearest``, ``shield_emergency``,
    ``shield_unsafe``, ``shield_evade``).  ``progress`` holds the episode's samples of
    time, distance to goal and clearance (:func:`episode_progress`) for OMPL's
    ``progress`` table.
    """
    status = ep.status
    name = str(getattr(status, "name", status)).upper()
    solved = bool(getattr(ep, "reached", name == "SUCCESS"))
    d = ep.to_dict(trajectories=False) if hasattr(ep, "to_dict") else {}
    plan_times = np.asarray(getattr(ep, "plan_times_s", ()), dtype=float)
    compute = float(getattr(ep, "setup_time_s", 0.0)) + float(plan_times.sum())
    coll = getattr(ep, "collision_with", None)
    positions = np.asarray(getattr(ep, "positions", np.zeros((0, 2))), dtype=float)
    sc = getattr(ep, "scenario", None)
    row: dict[str, Any] = {
        "status_name": name,
        "solved": solved,
        "time": compute,
        "solution_length": _num(getattr(ep, "path_length_m", None)) if solved else None,
        "time_to_goal": _num(getattr(ep, "time_to_goal_s", None)) if solved else None,
        "path_length": _num(getattr(ep, "path_length_m", None)),
        "collisions": 0 if coll is None else 1,
        "collision_free": coll is None,
        "iterations": int(getattr(ep, "n_ticks", 0)),
        "steps": int(getattr(ep, "n_ticks", 0)),
        "solution_segments": max(0, positions.shape[0] - 1) if solved else None,
        "solution_clearance": _num(getattr(ep, "min_distance_m", None)),
        "message": str(getattr(ep, "message", "")),
    }
    if sc is not None:
        row["start_x"], row["start_y"] = (float(c) for c in sc.start)
        row["goal_x"], row["goal_y"] = (float(c) for c in sc.goal)
    sc_d = {k: v for k, v in d.items() if k not in ("params", "scenario", "planner")}
    timing = {k: v for k, v in _scalars(sc_d).items() if _is_timing(k) and "to_goal" not in k}
    names = {} if sc is None else {"scenario": str(sc.name), "map": str(sc.grid.name)}
    row["metrics"] = json.dumps({**{k: v for k, v in _scalars(sc_d).items() if k not in timing},
                                 **_episode_extras(ep), **names}, sort_keys=True)
    row["timing"] = json.dumps(timing, sort_keys=True)
    samples = episode_progress(ep)
    if samples:
        row["progress"] = samples
    if store_paths and positions.shape[0]:
        row["path"] = _path_blob(positions)
        headings = np.asarray(getattr(ep, "headings", ()), dtype=float).reshape(-1)
        if headings.shape[0] == positions.shape[0]:
            row["headings"] = np.ascontiguousarray(headings, dtype="<f8").tobytes()
    return row


def _episode_extras(ep: Any) -> dict[str, Any]:
    """The episode's values that are not plain scalars of its dict, for ``metrics``:
    ``collision_at_fault`` (true, false, or null without a collision) and the shield
    counts as ``shield_<name>`` (:data:`pathfuse.shield.CODE_NAMES`).  An episode
    without them (older code) adds nothing, and readers show n/a."""
    out: dict[str, Any] = {}
    if hasattr(ep, "collision_at_fault"):
        v = ep.collision_at_fault
        out["collision_at_fault"] = None if v is None else bool(v)
    counts = getattr(ep, "shield_counts", None) or {}
    for name, k in counts.items():
        out[f"shield_{name}"] = int(k)
    return out


MAX_PROGRESS_SAMPLES = 100
"""Progress samples of one episode at most (ticks evenly spread, the first and last always)."""


def episode_progress(ep: Any) -> list[dict[str, float]]:
    """The ``progress`` samples of an episode: ``time`` (simulated s), ``distance_to_goal``
    (m, robot centre to goal) and ``clearance`` (m, robot disc to the nearest static cell,
    capped at 2 m as in the episode, or moving disc; negative in a collision) at
    :data:`MAX_PROGRESS_SAMPLES` ticks at most, spread evenly from the first to the last.

    Empty for an episode without its scenario (older records)."""
    sc = getattr(ep, "scenario", None)
    pos = np.asarray(getattr(ep, "positions", np.zeros((0, 2))), dtype=float).reshape(-1, 2)
    times = np.asarray(getattr(ep, "times", ()), dtype=float).reshape(-1)
    n = min(pos.shape[0], times.shape[0])
    if sc is None or n == 0:
        return []
    idx = np.unique(np.linspace(0, n - 1, min(n, MAX_PROGRESS_SAMPLES)).round().astype(int))
    goal = np.asarray(sc.goal, dtype=float)
    obst = np.asarray(getattr(ep, "obstacle_positions", np.zeros((n, 0, 2))), dtype=float)
    radii = np.asarray(getattr(ep, "obstacle_radii", ()), dtype=float).reshape(-1)
    out = []
    for i in map(int, idx):
        x, y = float(pos[i, 0]), float(pos[i, 1])
        discs = obst[i] if radii.size and obst.ndim == 3 and i < obst.shape[0] else None
        out.append({"time": float(times[i]),
                     "distance_to_goal": float(math.hypot(goal[0] - x, goal[1] - y)),
                     "clearance": _clearance_at(sc, x, y, discs, radii)})
    return out


def _clearance_at(sc: Any, x: float, y: float, discs: np.ndarray | None,
                  radii: np.ndarray) -> float:
    """Clearance of the robot disc at (x, y): to the static map (capped as the episode caps
    it) and to the moving discs at ``discs`` (None: no disc)."""
    from pathfuse.sweep import segment_static_distance
    from pathfuse.world.world import STATIC_CLEARANCE_CAP_M

    g = sc.grid
    radius = float(sc.robot.radius_m)
    gap = float(segment_static_distance(
        g.occupied, float(g.origin[0]), float(g.origin[1]), float(g.resolution), x, y, x, y,
        radius + STATIC_CLEARANCE_CAP_M)) - radius
    if discs is not None:
        gap = min(gap, float((np.hypot(discs[:, 0] - x, discs[:, 1] - y) - radii).min())
                  - radius)
    return gap


def run_irsim(group: Mapping[str, Any], run: Mapping[str, Any],
              store_paths: bool) -> dict[str, Any]:
    """One episode in an IR-SIM world (the ``"irsim"`` kind; needs ``pathfuse[irsim]``):
    :func:`pathfuse.integrations.irsim_run.irsim_row`."""
    from pathfuse.integrations.irsim_run import irsim_row

    return irsim_row(group, run, store_paths)


KINDS: dict[str, Callable[[Mapping[str, Any], Mapping[str, Any], bool], dict[str, Any]]] = {
    "static": run_static,
    "dynamic": run_dynamic,
    "irsim": run_irsim,
}
"""Run kind -> executor.  Register a new kind here (it gets its own rows)."""

EXTERNAL_PLANNERS: dict[str, tuple[str, ...]] = {"irsim": ("irsim-rvo",)}
"""Run kind -> the planner names its executor runs itself, outside pathfuse's registry
(IR-SIM's own RVO robot, :data:`pathfuse.integrations.irsim_run.RVO_BASELINE`): no
kernels to warm."""
