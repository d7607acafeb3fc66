"""Experiment files: what a benchmark sweep runs, and its deterministic run list.

An experiment is a YAML file naming maps, planners (with parameter grids),
seeds and limits.  :func:`load_experiment` validates it (every error is one
line naming the file and the key, e.g. ``planners[1].params.r1: ...``) and
:meth:`Experiment.expand` turns it into the list of runs, always in the same
order and each with a stable **run key**: the SHA-256 of the canonical JSON
of the run's full parameters.  The result store uses the key to skip runs
that are already stored, which is what makes an interrupted sweep resumable.

File layout
-----------
.. code-block:: yaml

    name: fusion-sweep               # default: the file name without suffix
    description: free text
    seeds: 100                       # 100 -> 0..99; also [1, 5, 7], "0:100", {start: 0, count: 100}
    limits: {time_limit_s: 5, max_iterations: 200000}   # per run (pathfuse.Budget)
    robot_radius_m: 0.0              # plan on the map inflated by this radius
    reference: astar                 # planner whose length defines R_length; null: none
                                     # (scen queries use the file's optimum instead)
    store_paths: false               # keep every path (float64 (N, 2)) in runs.path
    imports: [my_planners.py]        # modules / .py files that register extra planners
    maps:
      - name: paper                  # generated map: a fresh map for every seed
        map: paper                   # = {paper: {}}; start/goal default to the paper's
      - name: random-40
        map: {random: {size: [40, 40], density: 0.2}}
        queries: {random: 5, min_distance_m: 10}   # 5 random free pairs per seed
      - name: den312d
        map: {movingai: ../shared/data/movingai/den312d.map}
        scen: ../shared/data/movingai/den312d.map.scen
        lines: {sample: 50, seed: 0}  # or 50 (first 50), [2, 9], {every: 10}, {limit: 50}
        seeds: [0]                   # per-map seeds override the top-level ones
      - name: sandbox
        map: {ros: ../shared/data/rosmaps/nav2_tb3_sandbox/tb3_sandbox.yaml}
        queries: [{start: [-1.0, -0.5], goal: [1.5, 0.5]}]
      - name: crossing
        dynamic: scenarios/crossing.yaml      # dynamic world (pathfuse.world.simulate)
      - name: paper-dynamic                   # a generated family: one scenario per seed
        dynamic: {generate: {moving: 3, speed_range: [0.2, 0.8]}}
    planners:
      - astar
      - name: fusion
        label: fusion                # optional name in reports (default: name + swept values)
        params: {r1: [0.5, 1, 1.5, 2], r2: [1, 2], step: 0.5}   # lists are swept
        limits: {time_limit_s: 2}    # per-planner override
        kinds: [static]              # optional: only static maps (or dynamic)

A planner runs on the static maps when its name is a :func:`pathfuse.plan`
planner and on the dynamic entries when it is an online planner of
:mod:`pathfuse.world` (``kinds`` restricts this).  A list value in
``params`` is a grid axis; the runs take the cartesian product of all axes,
in the order the keys are written.  To give a parameter a list *value*, wrap
it: ``[[1, 2]]``.  Relative paths are relative to the experiment file.  For
generated maps (``paper``, ``random``) without an explicit ``seed`` the
run's seed is the map's seed.

Run order: maps (file order) > seeds > queries > planners (file order) >
parameter combinations (cartesian product, first key outermost).

Examples
--------
>>> import tempfile, pathlib
>>> text = '''
... name: demo
... seeds: 2
... maps:
...   - name: tiny
...     map: {rows: ["....", ".##.", "...."]}
...     start: [0.5, 0.5]
...     goal: [3.5, 2.5]
... planners:
...   - name: apf
... '''
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "demo.yaml"
...     _ = p.write_text(text)
...     exp = load_experiment(p)
...     runs = exp.expand()
>>> len(runs), [r.seed for r in runs]
(2, [0, 1])
>>> len(runs[0].key), runs[0].key == runs[1].key
(64, False)
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import itertools
import json
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from pathfuse.result import Budget, ConfigError, PathfuseError

__all__ = [
    "Experiment",
    "MapEntry",
    "PlannerEntry",
    "RunSpec",
    "load_experiment",
    "parse_experiment",
    "experiment_from_dict",
    "parse_seeds",
    "canonical_json",
    "run_key",
    "load_map",
    "GENERATED_FAMILIES",
    "FILE_FAMILIES",
]

KEY_VERSION = 1
"""Bumped only if the meaning of a run key changes (it never silently does)."""

GENERATED_FAMILIES = ("paper", "random")
"""Map families drawn from a seed; without an explicit seed they take the run's."""
FILE_FAMILIES = ("movingai", "ros", "image", "npy")
"""Map families read from a file (path relative to the experiment file)."""
INLINE_FAMILIES = ("rows",)
"""Maps written inline in the experiment."""
ALL_FAMILIES = GENERATED_FAMILIES + FILE_FAMILIES + INLINE_FAMILIES

_TOP_KEYS = ("name", "description", "seeds", "limits", "robot_radius_m", "reference",
             "store_paths", "imports", "maps", "planners")
_MAP_KEYS = ("name", "map", "start", "goal", "queries", "scen", "lines", "seeds",
             "robot_radius_m", "dynamic")
_PLANNER_KEYS = ("name", "label", "params", "limits", "kinds")
_LIMIT_KEYS = ("time_limit_s", "max_iterations")


# --------------------------------------------------------------------------- helpers
def canonical_json(obj: Any) -> str:
    """Canonical JSON: sorted keys, no spaces, shortest float repr, no NaN.

    >>> canonical_json({"b": 1.0, "a": [1, (2, 3)], "c": np.float64(0.1)})
    '{"a":[1,[2,3]],"b":1.0,"c":0.1}'
    """
    return json.dumps(_plain(obj), sort_keys=True, separators=(",", ":"), allow_nan=False,
                      ensure_ascii=True)


def _plain(obj: Any) -> Any:
    """Convert numpy scalars/arrays, tuples and paths into plain JSON types."""
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj)
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return _plain(dataclasses.asdict(obj))
    if isinstance(obj, enum.Enum):
        return str(obj.name)
    return obj


def run_key(payload: Mapping[str, Any]) -> str:
    """SHA-256 hex digest of the canonical JSON of ``payload``.

    >>> run_key({"b": 2, "a": 1}) == run_key({"a": 1, "b": 2})
    True
    >>> len(run_key({"a": 1}))
    64
    """
    return hashlib.sha256(canonical_json(payload).encode("ascii")).hexdigest()


def _is_int(v: Any) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def _is_num(v: Any) -> bool:
    return (_is_int(v) or isinstance(v, (float, np.floating))) and math.isfinite(float(v))


def _short(v: Any, n: int = 60) -> str:
    s = repr(v)
    return s if len(s) <= n else s[: n - 3] + "..."


_DIGESTS: dict[tuple[str, int, int], str] = {}


def file_digest(path: Path) -> str:
    """First 16 hex digits of the SHA-256 of a file (cached by path, size, mtime)."""
    st = path.stat()
    k = (str(path), st.st_size, st.st_mtime_ns)
    if k not in _DIGESTS:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                h.update(chunk)
        _DIGESTS[k] = h.hexdigest()[:16]
    return _DIGESTS[k]


# --------------------------------------------------------------------------- seeds
def parse_seeds(value: Any, where: str = "seeds") -> tuple[int, ...]:
    """Seeds from an int count, a list, ``"a:b"`` / ``"a,b,c"`` or ``{start, count}``.

    >>> parse_seeds(3), parse_seeds([5, 1]), parse_seeds("2:5"), parse_seeds("7,8")
    ((0, 1, 2), (5, 1), (2, 3, 4), (7, 8))
    >>> parse_seeds({"start": 10, "count": 2})
    (10, 11)
    >>> parse_seeds(-1)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: seeds: a seed count must be >= 1, got -1
    """
    def bad(msg: str) -> ConfigError:
        return ConfigError(f"{where}: {msg}")

    if _is_int(value):
        if value < 1:
            raise bad(f"a seed count must be >= 1, got {value}")
        return tuple(range(int(value)))
    if isinstance(value, str):
        text = value.strip()
        try:
            if ":" in text:
                a, b = (int(t) for t in text.split(":"))
                seeds = tuple(range(a, b))
            else:
                seeds = tuple(int(t) for t in text.split(",") if t.strip())
        except ValueError:
            raise bad(f"expected 'A:B', 'A,B,C' or a count, got {value!r}") from None
        if not seeds:
            raise bad(f"{value!r} holds no seed")
        if min(seeds) < 0:
            raise bad(f"seeds must be >= 0, got {value!r}")
        return seeds
    if isinstance(value, Mapping):
        unknown = set(value) - {"start", "count"}
        if unknown or "count" not in value:
            raise bad(f"expected {{start: A, count: N}}, got {_short(dict(value))}")
        start, count = value.get("start", 0), value["count"]
        if not _is_int(start) or start < 0:
            raise bad(f"start must be an integer >= 0, got {start!r}")
        if not _is_int(count) or count < 1:
            raise bad(f"count must be an integer >= 1, got {count!r}")
        return tuple(range(int(start), int(start) + int(count)))
    if isinstance(value, (list, tuple)):
        if not value:
            raise bad("the seed list is empty")
        for i, s in enumerate(value):
            if not _is_int(s) or s < 0:
                raise ConfigError(f"{where}[{i}]: a seed must be an integer >= 0, got {s!r}")
        if len(set(value)) != len(value):
            raise bad("the seed list repeats a seed")
        return tuple(int(s) for s in value)
    raise bad(f"expected a count, a list of integers, 'A:B' or {{start, count}}, got {value!r}")


# --------------------------------------------------------------------------- entries
@dataclass(frozen=True)
class Limits:
    """Per-run limits (become a :class:`pathfuse.Budget`)."""

    time_limit_s: float | None = None
    max_iterations: int | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"time_limit_s": self.time_limit_s, "max_iterations": self.max_iterations}

    def budget(self) -> Budget:
        return Budget(max_iterations=self.max_iterations, time_limit_s=self.time_limit_s)


def _parse_limits(value: Any, where: str, base: Limits | None = None) -> Limits:
    base = base or Limits()
    if value is None:
        return base
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: expected a mapping {{time_limit_s, max_iterations}}, "
                          f"got {_short(value)}")
    for k in value:
        if k not in _LIMIT_KEYS:
            raise ConfigError(f"{where}.{k}: unknown limit; use one of {', '.join(_LIMIT_KEYS)}")
    t = value.get("time_limit_s", base.time_limit_s)
    m = value.get("max_iterations", base.max_iterations)
    if t is not None and (not _is_num(t) or float(t) <= 0):
        raise ConfigError(f"{where}.time_limit_s: must be a number > 0, got {t!r}")
    if m is not None and (not _is_int(m) or m < 1):
        raise ConfigError(f"{where}.max_iterations: must be an integer >= 1, got {m!r}")
    return Limits(None if t is None else float(t), None if m is None else int(m))


@dataclass(frozen=True)
class PlannerEntry:
    """One ``planners[i]`` entry: a registry name, fixed params and swept axes.

    ``kinds`` are the run kinds it applies to: ``static`` when the name is in
    :mod:`pathfuse.planners.registry`, ``dynamic`` when it is an online planner
    of :mod:`pathfuse.world` (and the experiment has such maps).
    """

    index: int
    name: str
    label: str | None
    params: tuple[tuple[str, tuple[Any, ...]], ...]
    """(key, values) in file order; a fixed parameter has one value."""
    limits: Limits
    kinds: tuple[str, ...] = ("static",)
    fields_by_kind: dict[str, tuple[str, ...]] = field(default_factory=dict)
    defaults_by_kind: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def swept(self) -> tuple[str, ...]:
        return tuple(k for k, vals in self.params if len(vals) > 1)

    def combinations(self) -> list[dict[str, Any]]:
        """Every parameter combination (explicit values only), first key outermost."""
        keys = [k for k, _ in self.params]
        return [dict(zip(keys, combo, strict=True)) for combo in
                itertools.product(*(vals for _, vals in self.params))]

    def config_name(self, combo: Mapping[str, Any]) -> str:
        """plannerConfigs.name: the label, or ``name(k=v,...)`` over the swept keys."""
        base = self.label or self.name
        sw = self.swept
        if not sw:
            return base
        inner = ",".join(f"{k}={_fmt_value(combo[k])}" for k in sw)
        return f"{base}({inner})"


def _fmt_value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return canonical_json(v) if not isinstance(v, str) else v


def _coerce_param(value: Any, default: Any, annotation: Any = None) -> Any:
    """Match YAML scalars to the parameter's type (1 -> 1.0 for a float parameter)."""
    is_float = isinstance(default, float) or (
        default is None and "float" in str(annotation) and "int" not in str(annotation))
    if is_float and _is_int(value):
        return float(value)
    if isinstance(default, tuple) and isinstance(value, list):
        return tuple(value)
    return value


@dataclass(frozen=True)
class MapEntry:
    """One ``maps[i]`` entry (a static map with its queries, or a dynamic scenario)."""

    index: int
    name: str
    kind: str  # "static" or "dynamic"
    spec: dict[str, Any] | None  # the map spec as written (static)
    family: str | None
    seeds: tuple[int, ...]
    robot_radius_m: float
    queries: tuple[dict[str, Any], ...] = ()
    random_queries: dict[str, Any] | None = None
    scen: str | None = None
    lines: Any = None
    dynamic: Any = None
    pair_keys: bool = False
    """The query came from the entry's own start/goal keys."""

    @property
    def seeded_map(self) -> bool:
        """True when every seed draws a different map."""
        if self.family not in GENERATED_FAMILIES or self.spec is None:
            return False
        inner = self.spec.get(self.family)
        return not ((isinstance(inner, Mapping) and "seed" in inner) or _is_int(inner))

    def map_spec_for(self, seed: int) -> dict[str, Any]:
        """The map spec of this entry for ``seed`` (seed injected for generated maps)."""
        assert self.spec is not None
        spec = json.loads(canonical_json(self.spec))
        if self.seeded_map:
            inner = spec.get(self.family) or {}
            inner["seed"] = int(seed)
            spec[self.family] = inner
        return spec


@dataclass(frozen=True)
class RunSpec:
    """One run of the sweep, as the runner hands it to a worker.

    ``key`` identifies the run in the store; ``payload`` is the canonical JSON
    it hashes (the run's full parameters, stored in ``runs.params``).
    """

    key: str
    problem_key: str
    index: int
    kind: str
    group: str
    map_index: int
    planner_index: int
    config: str
    planner: str
    params: dict[str, Any]
    full_params: dict[str, Any]
    seed: int
    query: dict[str, Any]
    query_index: int
    map_key: str
    map_spec: dict[str, Any] | None
    limits: dict[str, Any]
    robot_radius_m: float
    reference: dict[str, Any] | None
    payload: str
    settings: str = "{}"
    """plannerConfigs.settings: canonical JSON of the config's parameters (no run seed)."""


# --------------------------------------------------------------------------- experiment
@dataclass(frozen=True)
class Experiment:
    """A validated experiment file.  :meth:`expand` gives its runs."""

    path: Path
    name: str
    description: str
    text: str
    seeds: tuple[int, ...]
    limits: Limits
    robot_radius_m: float
    reference: dict[str, Any] | None
    store_paths: bool
    imports: tuple[str, ...]
    maps: tuple[MapEntry, ...]
    planners: tuple[PlannerEntry, ...]

    @property
    def base_dir(self) -> Path:
        return self.path.parent

    def resolve(self, rel: str) -> Path:
        """A path of the file resolved against the experiment's folder."""
        p = Path(os.path.expanduser(rel))
        return p if p.is_absolute() else (self.base_dir / p)

    def import_paths(self) -> list[str]:
        """``imports`` with .py paths made absolute (module names kept)."""
        out = []
        for imp in self.imports:
            out.append(str(self.resolve(imp).resolve()) if imp.endswith(".py") else imp)
        return out

    def expand(self) -> list[RunSpec]:
        """The full, deterministic run list (see the module docstring for the order).

        Raises :class:`ConfigError` when the maps or scenario files cannot be
        read (naming ``maps[i]``) or two entries would produce the same run.
        """
        runs: list[RunSpec] = []
        seen: dict[str, tuple[int, int]] = {}
        combos = [(p, p.combinations()) for p in self.planners]
        for entry in self.maps:
            applicable = [(p, c) for p, c in combos if entry.kind in p.kinds]
            for seed in entry.seeds:
                map_portable, map_load, map_key = self._map_identity(entry, seed)
                for qi, query in enumerate(self._queries(entry, seed)):
                    problem = {"v": KEY_VERSION, "group": entry.name, "kind": entry.kind,
                               "map": map_portable, "query": query,
                               "robot_radius_m": entry.robot_radius_m}
                    problem_key = run_key(problem)[:24]
                    for pe, pcombos in applicable:
                        defaults = pe.defaults_by_kind[entry.kind]
                        for combo in pcombos:
                            params = dict(combo)
                            settings = canonical_json({**defaults, **combo})
                            if "seed" in pe.fields_by_kind[entry.kind] and "seed" not in params:
                                params["seed"] = int(seed)
                            full = {**defaults, **params}
                            limits = pe.limits.as_dict()
                            reference = self.reference if entry.kind == "static" else None
                            payload = canonical_json({
                                **problem, "planner": pe.name, "params": full,
                                "seed": int(seed), "limits": limits, "reference": reference,
                            })
                            key = hashlib.sha256(payload.encode("ascii")).hexdigest()
                            if key in seen:
                                m0, p0 = seen[key]
                                raise ConfigError(
                                    f"{self.path}: planners[{pe.index}] on maps[{entry.index}] "
                                    f"repeats the runs of planners[{p0}] on maps[{m0}] "
                                    "(same planner, parameters, map, query and seed)")
                            seen[key] = (entry.index, pe.index)
                            runs.append(RunSpec(
                                key=key, problem_key=problem_key, index=len(runs),
                                kind=entry.kind, group=entry.name, map_index=entry.index,
                                planner_index=pe.index, config=pe.config_name(combo),
                                planner=pe.name, params=params, full_params=full,
                                seed=int(seed), query=query, query_index=qi,
                                map_key=map_key, map_spec=map_load, limits=limits,
                                robot_radius_m=entry.robot_radius_m, reference=reference,
                                payload=payload, settings=settings))
        return runs

    # -- map identity ------------------------------------------------------
    def _map_identity(self, entry: MapEntry, seed: int) -> tuple[Any, Any, str]:
        """(portable spec for the key, loadable spec, cache key) of entry's map for seed."""
        if entry.kind == "dynamic":
            dyn = entry.dynamic
            if isinstance(dyn, str):
                p = self.resolve(dyn)
                portable: dict[str, Any] = {"dynamic": dyn, "sha256": file_digest(p)}
                load: dict[str, Any] = {"dynamic": str(p.resolve())}
            elif "generate" in dyn and dyn.get("family_seed") is not None:
                # scenario number `seed` of one family: the episode keeps the scenario's seed
                portable = {"dynamic": {"generate": dyn["generate"],
                                        "family_seed": int(dyn["family_seed"]),
                                        "index": int(seed)}}
                load = portable
            elif "generate" in dyn:  # a generated family: one scenario per seed
                portable = {"dynamic": {"generate": dyn["generate"], "seed": int(seed)}}
                load = portable
            else:
                portable = {"dynamic": dyn}
                load = {"dynamic": dyn, "base_dir": str(self.base_dir.resolve())}
            return portable, load, run_key(portable)[:24]
        spec = entry.map_spec_for(seed)
        portable = dict(spec)
        load = dict(spec)
        if entry.family in FILE_FAMILIES:
            rel = _file_of(spec, entry.family)
            p = self.resolve(rel)
            portable["sha256"] = file_digest(p)
            load = _with_file(spec, entry.family, str(p.resolve()))
        return portable, load, run_key(portable)[:24]

    # -- queries -------------------------------------------------------------
    def _queries(self, entry: MapEntry, seed: int) -> list[dict[str, Any]]:
        if entry.kind == "dynamic":
            return [{}]
        if entry.scen is not None:
            return list(self._scen_queries(entry))
        if entry.random_queries is not None:
            rq = entry.random_queries
            return [{"random": i, "min_distance_m": rq["min_distance_m"]}
                    for i in range(rq["count"])]
        return [dict(q) for q in entry.queries]

    def _scen_queries(self, entry: MapEntry) -> list[dict[str, Any]]:
        from pathfuse.io.scenario import read_scen

        where = f"{self.path}: maps[{entry.index}]"
        assert entry.scen is not None and entry.spec is not None
        _, map_load, map_key = self._map_identity(entry, entry.seeds[0])
        scen_path = self.resolve(entry.scen)
        k = (map_key, str(scen_path.resolve()), file_digest(scen_path),
             canonical_json(entry.lines))
        cache = _SCEN_CACHE
        if k in cache:
            return cache[k]
        grid = _load_for_expand(self, entry, where)
        try:
            probs = read_scen(self.resolve(entry.scen), grid)
        except PathfuseError as exc:
            raise ConfigError(f"{where}.scen: {exc}") from None
        chosen = _select_lines(probs, entry.lines, f"{where}.lines")
        digest = file_digest(self.resolve(entry.scen))
        out = [{"scen": entry.scen, "scen_sha256": digest, "line": p.line,
                "start": [float(p.start[0]), float(p.start[1])],
                "goal": [float(p.goal[0]), float(p.goal[1])],
                "optimal_length": float(p.optimal_length)} for p in chosen]
        cache[k] = out
        return out


_SCEN_CACHE: dict[tuple[str, ...], list[dict[str, Any]]] = {}


def _check_lines_form(sel: Any, where: str) -> None:
    ok = (_is_int(sel) and sel >= 1) or (isinstance(sel, list) and sel
                                          and all(_is_int(x) for x in sel))
    if isinstance(sel, Mapping):
        keys = set(sel)
        ok = keys == {"limit"} or keys == {"every"} or ("sample" in keys
                                                         and keys <= {"sample", "seed"})
        if ok:
            _select_lines([], sel, where)  # checks the numbers
    if not ok:
        raise ConfigError(f"{where}: expected N, a list of line numbers, {{limit: N}}, "
                          f"{{sample: N, seed: S}} or {{every: K}}, got {_short(sel)}")


def _file_of(spec: Mapping[str, Any], family: str) -> str:
    return str(spec[family])


def _with_file(spec: Mapping[str, Any], family: str, path: str) -> dict[str, Any]:
    out = dict(spec)
    out[family] = path
    return out


def _select_lines(probs: list[Any], sel: Any, where: str) -> list[Any]:
    """Pick scen problems: None (all), N (first N), [line, ...], {limit|sample|every}."""
    if sel is None:
        return probs
    if _is_int(sel):
        if sel < 1:
            raise ConfigError(f"{where}: must be >= 1, got {sel}")
        return probs[: int(sel)]
    if isinstance(sel, list):
        by_line = {p.line: p for p in probs}
        out = []
        for i, ln in enumerate(sel):
            if not _is_int(ln) or ln not in by_line:
                raise ConfigError(f"{where}[{i}]: no problem on line {ln!r} of the scen file "
                                  f"(lines {probs[0].line}..{probs[-1].line})" if probs else
                                  f"{where}[{i}]: the scen file holds no problem")
            out.append(by_line[int(ln)])
        return out
    if isinstance(sel, Mapping):
        keys = set(sel)
        if keys <= {"limit"} and keys:
            return _select_lines(probs, sel["limit"], f"{where}.limit")
        if "sample" in keys and keys <= {"sample", "seed"}:
            n, s = sel["sample"], sel.get("seed", 0)
            if not _is_int(n) or n < 1:
                raise ConfigError(f"{where}.sample: must be an integer >= 1, got {n!r}")
            if not _is_int(s) or s < 0:
                raise ConfigError(f"{where}.seed: must be an integer >= 0, got {s!r}")
            if n >= len(probs):
                return probs
            idx = np.sort(np.random.default_rng(int(s)).choice(len(probs), int(n),
                                                               replace=False))
            return [probs[i] for i in idx]
        if keys == {"every"}:
            k = sel["every"]
            if not _is_int(k) or k < 1:
                raise ConfigError(f"{where}.every: must be an integer >= 1, got {k!r}")
            return probs[:: int(k)]
    raise ConfigError(f"{where}: expected N, a list of line numbers, {{limit: N}}, "
                      f"{{sample: N, seed: S}} or {{every: K}}, got {_short(sel)}")


# --------------------------------------------------------------------------- map loading
def load_map(spec: Mapping[str, Any], base_dir: str | os.PathLike[str] = ".") -> Any:
    """Load a map spec with :func:`pathfuse.io.map_from_spec` (paths against ``base_dir``).

    >>> g = load_map({"rows": ["..", "#."]})
    >>> g.shape
    (2, 2)
    """
    from pathfuse.io import map_from_spec

    return map_from_spec(dict(spec), base_dir)


def load_dynamic(spec: Mapping[str, Any]) -> Any:
    """The :class:`~pathfuse.world.Scenario` of a loadable dynamic spec.

    ``{"dynamic": FILE}``, ``{"dynamic": {inline scenario}, "base_dir": DIR}``,
    ``{"dynamic": {"generate": {...}, "seed": S}}`` (scenario 0 of the family
    :func:`pathfuse.world.generate.generate_scenarios` draws with seed ``S``) or
    ``{"dynamic": {"generate": {...}, "family_seed": F, "index": I}}`` (scenario
    ``I`` of the family with seed ``F``).
    """
    from pathfuse.world import load_scenario

    dyn = spec["dynamic"]
    if isinstance(dyn, Mapping) and "generate" in dyn:
        from pathfuse.world.generate import generate_scenarios

        if "family_seed" in dyn:
            return generate_scenarios(1, seed=int(dyn["family_seed"]), first=int(dyn["index"]),
                                      **dict(dyn["generate"]))[0]
        return generate_scenarios(1, seed=int(dyn["seed"]), **dict(dyn["generate"]))[0]
    if isinstance(dyn, Mapping) and spec.get("base_dir"):
        d = json.loads(canonical_json(dyn))
        m = d.get("map")
        if isinstance(m, Mapping):  # relative map files: against the experiment's folder
            for fam in FILE_FAMILIES:
                if isinstance(m.get(fam), str) and not Path(m[fam]).is_absolute():
                    m[fam] = str(Path(spec["base_dir"]) / m[fam])
        return load_scenario(d)
    return load_scenario(dyn)


def _load_for_expand(exp: Experiment, entry: MapEntry, where: str) -> Any:
    spec = entry.map_spec_for(entry.seeds[0])
    try:
        return load_map(spec, exp.base_dir)
    except PathfuseError as exc:
        raise ConfigError(f"{where}.map: {exc}") from None
    except (TypeError, ValueError, OSError) as exc:
        raise ConfigError(f"{where}.map: cannot load {_short(entry.spec)}: {exc}") from None


# --------------------------------------------------------------------------- parsing
def load_experiment(path: str | os.PathLike[str], seeds: Any = None,
                    check_maps: bool = True) -> Experiment:
    """Read and validate an experiment file.

    Parameters
    ----------
    path : path-like
        The YAML file.
    seeds : optional
        Overrides every ``seeds`` of the file (same forms as :func:`parse_seeds`).
    check_maps : bool
        Load each static map once (first seed) so that a bad map fails now.

    Raises
    ------
    ConfigError
        One line: ``FILE: key.path: what is wrong``.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{p}: no such experiment file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{p}: cannot read experiment file ({exc})") from None
    return parse_experiment(text, p, seeds=seeds, check_maps=check_maps)


def parse_experiment(text: str, path: str | os.PathLike[str] = "experiment.yaml",
                     seeds: Any = None, check_maps: bool = True) -> Experiment:
    """Validate experiment YAML ``text`` (``path`` names it and anchors relative paths)."""
    path = Path(path)
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"{path}: {where}invalid YAML: {problem}") from None
    try:
        return _parse(doc, path, text, seeds, check_maps)
    except ConfigError as exc:
        msg = str(exc)
        if not msg.startswith(str(path)):
            msg = f"{path}: {msg}"
        raise ConfigError(msg) from None


def experiment_from_dict(doc: Mapping[str, Any], path: str | os.PathLike[str],
                         check_maps: bool = True) -> Experiment:
    """Validate an experiment given as a dict (the presets ``pathfuse paper`` and
    ``pathfuse dynamic`` build theirs this way); ``path`` names it and anchors relative
    paths, and its YAML is kept as the experiment's text."""
    path = Path(path)
    text = yaml.safe_dump(_plain(dict(doc)), sort_keys=False)
    try:
        return _parse(dict(doc), path, text, None, check_maps)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def _parse(doc: Any, path: Path, text: str, seeds_override: Any,
           check_maps: bool) -> Experiment:
    if not isinstance(doc, Mapping):
        raise ConfigError(f"the file must hold a mapping with maps and planners, "
                          f"got {type(doc).__name__}")
    for k in doc:
        if k not in _TOP_KEYS:
            raise ConfigError(f"{k}: unknown key; expected one of {', '.join(_TOP_KEYS)}")
    name = doc.get("name", path.stem)
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"name: must be a non-empty string, got {name!r}")
    desc = doc.get("description", "") or ""
    if not isinstance(desc, str):
        raise ConfigError(f"description: must be a string, got {_short(desc)}")
    if seeds_override is not None:
        top_seeds = parse_seeds(seeds_override, "seeds (override)")
    else:
        top_seeds = parse_seeds(doc.get("seeds", 1), "seeds")
    limits = _parse_limits(doc.get("limits"), "limits")
    radius = _radius(doc.get("robot_radius_m", 0.0), "robot_radius_m")
    store_paths = doc.get("store_paths", False)
    if not isinstance(store_paths, bool):
        raise ConfigError(f"store_paths: must be true or false, got {store_paths!r}")
    imports = doc.get("imports", []) or []
    if isinstance(imports, str):
        imports = [imports]
    if not isinstance(imports, list) or not all(isinstance(i, str) and i for i in imports):
        raise ConfigError(f"imports: must be a list of module names or .py files, "
                          f"got {_short(imports)}")
    exp_dir = path.parent
    for i, imp in enumerate(imports):
        if imp.endswith(".py"):
            ip = Path(imp) if Path(imp).is_absolute() else exp_dir / imp
            if not ip.is_file():
                raise ConfigError(f"imports[{i}]: no such file {ip}")
    _do_imports(imports, exp_dir)

    if "reference" in doc:
        reference = _parse_reference(doc["reference"])
    else:  # default: A* (when this build has it)
        from pathfuse.planners.registry import planner_names

        reference = _parse_reference("astar" if "astar" in planner_names() else None)

    raw_maps = doc.get("maps")
    if not isinstance(raw_maps, list) or not raw_maps:
        raise ConfigError("maps: must be a non-empty list of maps")
    maps = []
    names: dict[str, int] = {}
    for i, v in enumerate(raw_maps):
        entry = _parse_map(i, v, top_seeds, radius, exp_dir,
                           seeds_override is not None)
        if entry.name in names:
            raise ConfigError(f"maps[{i}].name: {entry.name!r} is already the name of "
                              f"maps[{names[entry.name]}]")
        names[entry.name] = i
        maps.append(entry)
    kinds = tuple(k for k in ("static", "dynamic") if any(m.kind == k for m in maps))
    raw_planners = doc.get("planners")
    if not isinstance(raw_planners, list) or not raw_planners:
        raise ConfigError("planners: must be a non-empty list of planners")
    planners = tuple(_parse_planner(i, v, limits, kinds) for i, v in enumerate(raw_planners))
    for m in maps:
        if not any(m.kind in p.kinds for p in planners):
            raise ConfigError(f"maps[{m.index}]: no planner of this experiment runs "
                              f"{m.kind} maps (" + ("planners that run online: "
                              + ", ".join(_registry("dynamic").names()) if m.kind == "dynamic"
                              else "planners: " + ", ".join(_registry("static").names()))
                              + ")")
    exp = Experiment(path=path, name=name.strip(), description=desc, text=text,
                     seeds=top_seeds, limits=limits, robot_radius_m=radius,
                     reference=reference, store_paths=store_paths,
                     imports=tuple(imports), maps=tuple(maps), planners=planners)
    if check_maps:
        for entry in exp.maps:
            if entry.kind == "static" and entry.scen is None:
                grid = _load_for_expand(exp, entry, f"maps[{entry.index}]")
                _check_queries(entry, grid)
            elif entry.kind == "dynamic":
                _, load, _ = exp._map_identity(entry, entry.seeds[0])
                try:
                    load_dynamic(load)
                except PathfuseError as exc:
                    raise ConfigError(f"maps[{entry.index}].dynamic: {exc}") from None
    return exp


def _do_imports(imports: Sequence[str], base_dir: Path) -> None:
    """Import plug-in modules (they register planners) in this process."""
    from pathfuse.bench.execute import ensure_imports

    paths = [str((base_dir / i).resolve()) if i.endswith(".py") and not Path(i).is_absolute()
             else i for i in imports]
    try:
        ensure_imports(paths)
    except Exception as exc:  # noqa: BLE001 - any import failure is a config error
        raise ConfigError(f"imports: cannot import: {type(exc).__name__}: {exc}") from None


def _radius(v: Any, where: str) -> float:
    if not _is_num(v) or float(v) < 0:
        raise ConfigError(f"{where}: must be a number >= 0 (metres), got {v!r}")
    return float(v)


def _parse_reference(v: Any) -> dict[str, Any] | None:
    if v is None or v is False:
        return None
    from pathfuse.planners.registry import get_planner, make_params

    if isinstance(v, str):
        v = {"planner": v}
    if not isinstance(v, Mapping) or "planner" not in v or set(v) - {"planner", "params"}:
        raise ConfigError(f"reference: expected a planner name or {{planner, params}}, "
                          f"got {_short(v)}")
    try:
        spec = get_planner(v["planner"])
        make_params(spec, v.get("params") or {})
    except ConfigError as exc:
        raise ConfigError(f"reference: {exc}") from None
    return {"planner": spec.name, "params": _plain(dict(v.get("params") or {}))}


class _Registry:
    """The planners of one run kind: every planner for static maps, the planners that run
    online (tick by tick) for dynamic entries.  One registry serves both."""

    def __init__(self, kind: str) -> None:
        self.kind = kind

    def names(self) -> list[str]:
        from pathfuse.planners.registry import REGISTRY, planner_names

        names = planner_names()
        return names if self.kind == "static" else [n for n in names if REGISTRY[n].online]

    def get(self, name: Any) -> Any:
        from pathfuse.planners.registry import get_planner

        spec = get_planner(name)
        if self.kind == "dynamic" and not spec.online:
            raise ConfigError(f"planner {spec.name!r} only plans offline; it cannot run on a "
                              "dynamic entry")
        return spec

    def make(self, spec: Any, params: Mapping[str, Any]) -> Any:
        from pathfuse.planners.registry import make_params

        return make_params(spec, dict(params), key="params")


_REGISTRIES: dict[str, _Registry] = {}


def _registry(kind: str) -> _Registry:
    if kind not in _REGISTRIES:
        _REGISTRIES[kind] = _Registry(kind)
    return _REGISTRIES[kind]


def _parse_planner(i: int, v: Any, top_limits: Limits,
                   kinds: Sequence[str] = ("static",)) -> PlannerEntry:
    where = f"planners[{i}]"
    if isinstance(v, str):
        v = {"name": v}
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}: expected a planner name or a mapping with name/params, "
                          f"got {_short(v)}")
    for k in v:
        if k not in _PLANNER_KEYS:
            raise ConfigError(f"{where}.{k}: unknown key; expected one of "
                              f"{', '.join(_PLANNER_KEYS)}")
    if "name" not in v:
        raise ConfigError(f"{where}.name: missing (the planner's registry name)")
    name = v["name"]
    if "kinds" in v:
        want = v["kinds"]
        want = [want] if isinstance(want, str) else want
        if not isinstance(want, list) or not want or \
                not set(want) <= {"static", "dynamic"}:
            raise ConfigError(f"{where}.kinds: expected a list of static / dynamic, "
                              f"got {_short(v['kinds'])}")
        kinds = [k for k in kinds if k in want]
    specs: dict[str, Any] = {}
    for kind in kinds:
        reg = _registry(kind)
        if isinstance(name, str) and name in reg.names():
            specs[kind] = reg.get(name)
        elif isinstance(name, str):
            try:  # an older name (alias) of a planner of this kind
                specs[kind] = reg.get(name)
            except ConfigError:
                pass
    if not specs:
        if len(kinds) == 1 or not kinds:
            try:
                _registry(kinds[0] if kinds else "static").get(name)
            except ConfigError as exc:
                raise ConfigError(f"{where}.name: {exc}") from None
        choices = "; ".join(f"{k}: {', '.join(_registry(k).names())}" for k in kinds)
        raise ConfigError(f"{where}.name: unknown planner {name!r} (choose from {choices})")
    label = v.get("label")
    if label is not None and (not isinstance(label, str) or not label.strip()):
        raise ConfigError(f"{where}.label: must be a non-empty string, got {label!r}")
    raw = v.get("params") or {}
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{where}.params: expected a mapping of parameter: value or "
                          f"[values], got {_short(raw)}")
    fields_by_kind = {k: tuple(f.name for f in dataclasses.fields(sp.params_cls))
                      for k, sp in specs.items()}
    types: dict[str, Any] = {}
    raw_defaults: dict[str, Any] = {}
    for sp in specs.values():
        types.update({f.name: f.type for f in dataclasses.fields(sp.params_cls)})
        raw_defaults.update(sp.defaults())
    params: list[tuple[str, tuple[Any, ...]]] = []
    for k, val in raw.items():
        kw = f"{where}.params.{k}"
        for kind, sp in specs.items():
            if k not in fields_by_kind[kind]:
                what = "online planner" if kind == "dynamic" else "planner"
                raise ConfigError(f"{kw}: {what} {sp.name!r} has no such parameter; its "
                                  f"parameters are: {', '.join(sorted(fields_by_kind[kind]))}")
        values = list(val) if isinstance(val, list) else [val]
        if not values:
            raise ConfigError(f"{kw}: the list of values is empty")
        vals = tuple(_coerce_param(x, raw_defaults.get(k), types.get(k)) for x in values)
        for j, x in enumerate(vals):
            for kind, sp in specs.items():
                try:
                    _registry(kind).make(sp, {k: x})
                except ConfigError as exc:
                    idx = f"[{j}]" if isinstance(val, list) else ""
                    raise ConfigError(f"{kw}{idx}: {_strip_planner(str(exc))}") from None
        if len(set(map(canonical_json, vals))) != len(vals):
            raise ConfigError(f"{kw}: the list of values repeats a value")
        params.append((str(k), tuple(_plain(list(vals)))))
    entry = PlannerEntry(
        index=i, name=name, label=label.strip() if label else None, params=tuple(params),
        limits=_parse_limits(v.get("limits"), f"{where}.limits", top_limits),
        kinds=tuple(specs), fields_by_kind=fields_by_kind,
        defaults_by_kind={k: _plain(sp.defaults()) for k, sp in specs.items()})
    for combo in entry.combinations():  # cross-parameter checks of the dataclass
        for kind, sp in specs.items():
            try:
                _registry(kind).make(sp, {k: _coerce_param(x, raw_defaults.get(k),
                                                           types.get(k))
                                          for k, x in combo.items()})
            except ConfigError as exc:
                raise ConfigError(f"{where}.params: {_strip_planner(str(exc))} "
                                  f"(combination {canonical_json(combo)})") from None
    return entry


def _strip_planner(msg: str) -> str:
    """``params.r1_m: must be ...`` -> ``must be ...`` (the caller names the key)."""
    if msg.startswith("params.") and ": " in msg:
        return msg.split(": ", 1)[1]
    return msg


def _parse_map(i: int, v: Any, top_seeds: tuple[int, ...], top_radius: float,
               exp_dir: Path, seeds_overridden: bool) -> MapEntry:
    where = f"maps[{i}]"
    if isinstance(v, str):
        v = {"map": v}
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}: expected a mapping with map (or dynamic) and queries, "
                          f"got {_short(v)}")
    for k in v:
        if k not in _MAP_KEYS:
            raise ConfigError(f"{where}.{k}: unknown key; expected one of {', '.join(_MAP_KEYS)}")
    seeds = top_seeds if seeds_overridden or "seeds" not in v else \
        parse_seeds(v["seeds"], f"{where}.seeds")
    radius = _radius(v.get("robot_radius_m", top_radius), f"{where}.robot_radius_m")
    if "dynamic" in v:
        extra = set(v) - {"name", "dynamic", "seeds", "robot_radius_m"}
        if extra:
            raise ConfigError(f"{where}.{sorted(extra)[0]}: not used with dynamic "
                              "(the scenario holds the map and the queries)")
        dyn = v["dynamic"]
        if isinstance(dyn, str):
            dp = Path(dyn) if Path(dyn).is_absolute() else exp_dir / dyn
            if not dp.is_file():
                raise ConfigError(f"{where}.dynamic: no such scenario file {dp}")
            default_name = Path(dyn).stem
        elif isinstance(dyn, Mapping):
            dyn = _plain(dict(dyn))
            if "generate" in dyn:
                _check_generate(dyn, f"{where}.dynamic")
            default_name = f"dynamic-{i}"
        else:
            raise ConfigError(f"{where}.dynamic: expected a scenario file or a mapping, "
                              f"got {_short(dyn)}")
        name = _entry_name(v, where, default_name)
        return MapEntry(index=i, name=name, kind="dynamic", spec=None, family=None,
                        seeds=seeds, robot_radius_m=radius, dynamic=dyn)
    if "map" not in v:
        raise ConfigError(f"{where}.map: missing (a map spec such as paper, "
                          "{movingai: FILE}, {ros: FILE.yaml}; or use dynamic)")
    spec, family = _parse_map_spec(v["map"], f"{where}.map", exp_dir)
    default_name = family if family in GENERATED_FAMILIES else (
        Path(_file_of(spec, family)).stem if family in FILE_FAMILIES else f"map-{i}")
    name = _entry_name(v, where, default_name)
    given = [k for k in ("queries", "scen") if k in v] + (
        ["start/goal"] if ("start" in v or "goal" in v) else [])
    if len(given) > 1:
        raise ConfigError(f"{where}: give only one of start/goal, queries and scen "
                          f"(got {', '.join(given)})")
    if "lines" in v and "scen" not in v:
        raise ConfigError(f"{where}.lines: only used with scen")
    queries: list[dict[str, Any]] = []
    random_q = None
    scen = None
    if "scen" in v:
        scen = v["scen"]
        if not isinstance(scen, str):
            raise ConfigError(f"{where}.scen: expected a .scen file path, got {_short(scen)}")
        sp = Path(scen) if Path(scen).is_absolute() else exp_dir / scen
        if not sp.is_file():
            raise ConfigError(f"{where}.scen: no such file {sp}")
        if family != "movingai":
            raise ConfigError(f"{where}.scen: scen files go with MovingAI maps "
                              f"({{movingai: FILE}}), not {family!r}")
        if "lines" in v:  # the form now; the line numbers once the file is read
            _check_lines_form(v["lines"], f"{where}.lines")
    elif "start" in v or "goal" in v:
        queries.append({"start": _point(v.get("start"), f"{where}.start"),
                        "goal": _point(v.get("goal"), f"{where}.goal")})
    elif "queries" in v:
        q = v["queries"]
        if isinstance(q, Mapping):
            if set(q) - {"random", "min_distance_m"} or "random" not in q:
                raise ConfigError(f"{where}.queries: expected a list of {{start, goal}} or "
                                  f"{{random: N, min_distance_m: D}}, got {_short(dict(q))}")
            n = q["random"]
            if not _is_int(n) or n < 1:
                raise ConfigError(f"{where}.queries.random: must be an integer >= 1, got {n!r}")
            d = q.get("min_distance_m", 0.0)
            if not _is_num(d) or float(d) < 0:
                raise ConfigError(f"{where}.queries.min_distance_m: must be a number >= 0, "
                                  f"got {d!r}")
            random_q = {"count": int(n), "min_distance_m": float(d)}
        elif isinstance(q, list) and q:
            for j, item in enumerate(q):
                qw = f"{where}.queries[{j}]"
                if isinstance(item, Mapping):
                    if set(item) - {"start", "goal"}:
                        raise ConfigError(f"{qw}: expected {{start: [x, y], goal: [x, y]}}, "
                                          f"got {_short(dict(item))}")
                    s, g = item.get("start"), item.get("goal")
                    queries.append({"start": _point(s, f"{qw}.start"),
                                    "goal": _point(g, f"{qw}.goal")})
                elif isinstance(item, list) and len(item) == 2:
                    queries.append({"start": _point(item[0], f"{qw}[0]"),
                                    "goal": _point(item[1], f"{qw}[1]")})
                else:
                    raise ConfigError(f"{qw}: expected {{start: [x, y], goal: [x, y]}} or "
                                      f"[[x, y], [x, y]], got {_short(item)}")
        else:
            raise ConfigError(f"{where}.queries: expected a non-empty list of {{start, goal}} "
                              f"or {{random: N}}, got {_short(q)}")
    elif family == "paper":
        from pathfuse.generate import PAPER_GOAL, PAPER_START

        queries.append({"start": [float(c) for c in PAPER_START],
                        "goal": [float(c) for c in PAPER_GOAL]})
    else:
        raise ConfigError(f"{where}: needs start/goal, queries or scen (only the paper map "
                          "has default start and goal)")
    return MapEntry(index=i, name=name, kind="static", spec=spec, family=family,
                    seeds=seeds, robot_radius_m=radius, queries=tuple(queries),
                    random_queries=random_q, scen=scen, lines=v.get("lines"),
                    pair_keys="start" in v or "goal" in v)


def _check_generate(dyn: Mapping[str, Any], where: str) -> None:
    """``{generate: {...}}`` holds arguments of ``generate_scenarios`` (pathfuse.world)."""
    import inspect

    from pathfuse.world.generate import generate_scenarios

    if not set(dyn) <= {"generate", "family_seed"} or "generate" not in dyn \
            or not isinstance(dyn["generate"], Mapping):
        raise ConfigError(f"{where}: expected {{generate: {{moving: K, speed_range: [lo, hi], "
                          f"...}}}} (and optionally family_seed: S), got {_short(dict(dyn))}")
    fs = dyn.get("family_seed")
    if fs is not None and (not _is_int(fs) or fs < 0):
        raise ConfigError(f"{where}.family_seed: must be an integer >= 0, got {_short(fs)}")
    allowed = [p for p in inspect.signature(generate_scenarios).parameters
               if p not in ("n_scenarios", "seed", "first")]
    for k in dyn["generate"]:
        if k not in allowed:
            raise ConfigError(f"{where}.generate.{k}: unknown argument; expected one of "
                              f"{', '.join(allowed)} (the run's seed is the family seed, "
                              "or with family_seed the scenario's index)")


def _entry_name(v: Mapping[str, Any], where: str, default: str) -> str:
    name = v.get("name", default)
    if not isinstance(name, str) or not name.strip() or "/" in name:
        raise ConfigError(f"{where}.name: must be a non-empty string without '/', "
                          f"got {name!r}")
    return name.strip()


def _parse_map_spec(m: Any, where: str, exp_dir: Path) -> tuple[dict[str, Any], str]:
    if isinstance(m, str):
        low = m.lower()
        if m in GENERATED_FAMILIES:
            m = {m: {}}
        elif low.endswith(".map"):
            m = {"movingai": m}
        elif low.endswith((".yaml", ".yml")):
            m = {"ros": m}
        else:
            raise ConfigError(f"{where}: {m!r} is not a map family (paper, random) nor a "
                              ".map / .yaml file; use a mapping such as {image: FILE, "
                              "resolution: 0.05}")
    if not isinstance(m, Mapping):
        raise ConfigError(f"{where}: expected a map spec mapping, got {_short(m)}")
    fams = [f for f in ALL_FAMILIES if f in m]
    if len(fams) != 1:
        raise ConfigError(f"{where}: name exactly one map family of {', '.join(ALL_FAMILIES)}"
                          f"; got keys {', '.join(map(str, m)) or '(none)'}")
    family = fams[0]
    spec = _plain(dict(m))
    if family in GENERATED_FAMILIES:
        inner = spec[family]
        if inner is None:
            spec[family] = {}
        elif family == "paper" and _is_int(inner) and inner >= 0:
            spec[family] = {"seed": int(inner)}
        elif not isinstance(inner, Mapping):
            raise ConfigError(f"{where}.{family}: expected a mapping of generator arguments, "
                              f"got {_short(inner)}")
        if "seed" in spec[family] and (not _is_int(spec[family]["seed"])
                                       or spec[family]["seed"] < 0):
            raise ConfigError(f"{where}.{family}.seed: must be an integer >= 0, "
                              f"got {spec[family]['seed']!r}")
    elif family in FILE_FAMILIES:
        rel = spec[family]
        if not isinstance(rel, str) or not rel.strip():
            raise ConfigError(f"{where}.{family}: missing file name")
        p = Path(os.path.expanduser(rel))
        p = p if p.is_absolute() else exp_dir / p
        if not p.is_file():
            raise ConfigError(f"{where}.{family}: no such file {p}")
    return spec, family


def _point(v: Any, where: str) -> list[float]:
    if v is None:
        raise ConfigError(f"{where}: missing (an [x, y] point in metres)")
    if not isinstance(v, (list, tuple)) or len(v) != 2 or not all(_is_num(c) for c in v):
        raise ConfigError(f"{where}: expected [x, y] (two finite numbers, metres), "
                          f"got {_short(v)}")
    return [float(v[0]), float(v[1])]


def _check_queries(entry: MapEntry, grid: Any) -> None:
    """Explicit points must lie on the map (blocked points are a run status, not an error)."""
    for j, q in enumerate(entry.queries):
        for what in ("start", "goal"):
            p = np.asarray(q[what], dtype=float)
            if not bool(grid.in_bounds(p)[0]):
                x0, y0, x1, y1 = grid.bounds
                w = f"maps[{entry.index}].{what}" if entry.pair_keys or (
                    entry.family == "paper" and not entry.queries[1:]) \
                    else f"maps[{entry.index}].queries[{j}].{what}"
                raise ConfigError(f"{w}: ({p[0]:g}, {p[1]:g}) lies outside map "
                                  f"{entry.name!r} [{x0:g}, {x1:g}) x [{y0:g}, {y1:g})")


def iter_groups(runs: Iterable[RunSpec]) -> Iterable[list[RunSpec]]:
    """Consecutive runs that share a map instance (same ``map_key`` and kind)."""
    cur: list[RunSpec] = []
    for r in runs:
        if cur and (r.map_key != cur[0].map_key or r.kind != cur[0].kind
                    or r.group != cur[0].group):
            yield cur
            cur = []
        cur.append(r)
    if cur:
        yield cur
