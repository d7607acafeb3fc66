"""A validated experiment and its deterministic run list (:class:`Experiment`, :class:`RunSpec`).

Built by :mod:`pathfuse.bench.parse`; see :mod:`pathfuse.bench.experiment` for the file format.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.bench.keys import (
    FILE_FAMILIES,
    GENERATED_FAMILIES,
    KEY_VERSION,
    Limits,
    _is_int,
    _plain,
    _short,
    canonical_json,
    file_digest,
    run_key,
)
from pathfuse.limits import check_count
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.validate import short as _shown


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
    kind: str  # "static", "dynamic" or "irsim"
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


def _dumps(plain: Any) -> str:
    """:func:`canonical_json` of a value already made of JSON types."""
    return json.dumps(plain, sort_keys=True, separators=(",", ":"), allow_nan=False,
                      ensure_ascii=True)


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
        cached = self.__dict__.get("_runs")
        if cached is not None:
            return list(cached)
        runs: list[RunSpec] = []
        seen: dict[str, tuple[int, int]] = {}
        # the parts of a payload are made plain (JSON types) once, not once per run: the
        # payload's JSON is the same as canonical_json of the whole (tested)
        combos = [(p, [_plain(c) for c in p.combinations()]) for p in self.planners]
        settings_of: dict[tuple[int, str, int], str] = {}
        plain_defaults = {(p.index, k): _plain(d) for p in self.planners
                          for k, d in p.defaults_by_kind.items()}
        plain_limits = {p.index: _plain(p.limits.as_dict()) for p in self.planners}
        total = 0
        for entry in self.maps:  # count first: refuse a run list above MAX_RUNS unbuilt
            per_query = sum(len(c) for p, c in combos if entry.kind in p.kinds)
            total += len(entry.seeds) * len(self._queries(entry, entry.seeds[0])) * per_query
        check_count(total, "MAX_RUNS", f"{self.path}: the experiment's runs")
        for entry in self.maps:
            applicable = [(p, c) for p, c in combos if entry.kind in p.kinds]
            reference = _plain(self.reference if entry.kind == "static" else None)
            for seed in entry.seeds:
                map_portable, map_load, map_key = self._map_identity(entry, seed)
                for qi, query in enumerate(self._queries(entry, seed)):
                    problem = _plain({"v": KEY_VERSION, "group": entry.name,
                                      "kind": entry.kind, "map": map_portable, "query": query,
                                      "robot_radius_m": entry.robot_radius_m})
                    problem_key = run_key(problem)[:24]
                    for pe, pcombos in applicable:
                        defaults = plain_defaults[(pe.index, entry.kind)]
                        limits = plain_limits[pe.index]
                        takes_seed = "seed" in pe.fields_by_kind[entry.kind]
                        for ci, combo in enumerate(pcombos):
                            params = dict(combo)
                            sk = (pe.index, entry.kind, ci)
                            if sk not in settings_of:
                                settings_of[sk] = canonical_json({**defaults, **combo})
                            settings = settings_of[sk]
                            if takes_seed and "seed" not in params:
                                params["seed"] = int(seed)
                            full = {**defaults, **params}
                            payload = _dumps({
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
        object.__setattr__(self, "_runs", tuple(runs))  # the same list on every call
        return runs

    # -- map identity ------------------------------------------------------
    def _map_identity(self, entry: MapEntry, seed: int) -> tuple[Any, Any, str]:
        """(portable spec for the key, loadable spec, cache key) of entry's map for seed."""
        if entry.kind == "irsim":  # an IR-SIM world file: its contents are its identity
            w = entry.dynamic
            p = self.resolve(w["world"])
            portable_w: dict[str, Any] = {"irsim": {**w, "sha256": file_digest(p)}}
            load_w: dict[str, Any] = {"irsim": {**w, "world": str(p.resolve())}}
            return portable_w, load_w, run_key(portable_w)[:24]
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
        if entry.kind in ("dynamic", "irsim"):
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
        raise ConfigError(f"{where}: must be N, a list of line numbers, {{limit: N}}, "
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
                raise ConfigError(f"{where}[{i}]: no problem on line {_shown(ln)} of the scen file "
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
                raise ConfigError(f"{where}.sample: must be an integer >= 1, got {_shown(n)}")
            if not _is_int(s) or s < 0:
                raise ConfigError(f"{where}.seed: must be an integer >= 0, got {_shown(s)}")
            if n >= len(probs):
                return probs
            idx = np.sort(np.random.default_rng(int(s)).choice(len(probs), int(n),
                                                               replace=False))
            return [probs[i] for i in idx]
        if keys == {"every"}:
            k = sel["every"]
            if not _is_int(k) or k < 1:
                raise ConfigError(f"{where}.every: must be an integer >= 1, got {_shown(k)}")
            return probs[:: int(k)]
    raise ConfigError(f"{where}: must be N, a list of line numbers, {{limit: N}}, "
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


def _yaml_map_spec(rel: str, where: str, exp_dir: Path) -> dict[str, Any]:
    """The map spec of a ``.yaml`` file named by its path, read as :func:`pathfuse.io.load_map`
    reads it: a ROS map_server map (``{ros: FILE}``) when the file has ``image``, an
    inline-rows map when it has ``rows`` (its ``rows``, ``resolution`` and ``origin``
    inlined, named by its ``name`` or the file's stem, so the run key follows its
    contents).  A missing file stays ``{ros: FILE}`` (the caller names it).

    Raises
    ------
    ConfigError
        A file that is not a YAML mapping, a rows map that does not read (ragged rows,
        an unknown key, ...), or neither ``image`` nor ``rows``; the message names
        ``where`` and the file.
    """
    from pathfuse.io.inline import read_rows_yaml
    from pathfuse.io.ros import load_yaml_mapping

    p = Path(os.path.expanduser(rel))
    p = p if p.is_absolute() else exp_dir / p
    if not p.is_file():
        return {"ros": rel}
    try:
        doc = load_yaml_mapping(p, "map YAML")
        if "image" in doc:
            return {"ros": rel}
        if "rows" not in doc:
            raise ConfigError(f"{p}: a map YAML needs an 'image' key (ROS map_server map) or "
                              f"a 'rows' key (inline map); found keys {sorted(map(str, doc))}")
        read_rows_yaml(p)  # the checks load_map makes, naming the file
    except PathfuseError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    spec: dict[str, Any] = {"rows": doc["rows"],
                            **{k: doc[k] for k in ("resolution", "origin") if k in doc}}
    spec["name"] = doc["name"] if isinstance(doc.get("name"), str) else p.stem
    return spec


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
        if isinstance(m, dict):  # relative map files: against the experiment's folder
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

