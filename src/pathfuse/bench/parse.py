"""Reading and checking an experiment file or dict into a :class:`~pathfuse.bench.spec.Experiment`.

Every error is one line naming the file and the key; see
:mod:`pathfuse.bench.experiment` for the format.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from pathfuse.bench.keys import (
    _MAP_KEYS,
    _PLANNER_KEYS,
    _TOP_KEYS,
    ALL_FAMILIES,
    FILE_FAMILIES,
    GENERATED_FAMILIES,
    Limits,
    _is_int,
    _is_num,
    _parse_limits,
    _plain,
    _short,
    canonical_json,
    check_generate,
    parse_seeds,
)
from pathfuse.bench.kind_irsim import external_names, external_spec, parse_irsim_entry
from pathfuse.bench.spec import (
    Experiment,
    MapEntry,
    PlannerEntry,
    _check_lines_form,
    _coerce_param,
    _file_of,
    _load_for_expand,
    _yaml_map_spec,
    load_dynamic,
)
from pathfuse.limits import check_count
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.validate import mapping, point
from pathfuse.validate import short as _shown


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
    from pathfuse.limits import read_capped

    p = Path(path)
    try:
        data = read_capped(p, "the experiment file", "MAX_YAML_BYTES")
    except FileNotFoundError:
        raise ConfigError(f"{p}: no such experiment file") from None
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read experiment file ({exc.strerror or exc})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not a UTF-8 text file ({exc.reason} at byte {exc.start})") \
            from None
    return parse_experiment(text, p, seeds=seeds, check_maps=check_maps)


def parse_experiment(text: str, path: str | os.PathLike[str] = "experiment.yaml",
                     seeds: Any = None, check_maps: bool = True) -> Experiment:
    """Validate experiment YAML ``text`` (``path`` names it and anchors relative paths)."""
    from pathfuse.safeyaml import load_yaml

    path = Path(path)
    doc = load_yaml(text, str(path), ConfigError)
    try:
        return _parse(doc, path, text, seeds, check_maps)
    except ConfigError as exc:
        msg = str(exc)
        if not msg.startswith(str(path)):
            msg = f"{path}: {msg}"
        raise type(exc)(msg) from None


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
    mapping(doc, "", _TOP_KEYS)
    name = doc.get("name", path.stem)
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"name: must be a non-empty string, got {_shown(name)}")
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
        raise ConfigError(f"store_paths: must be true or false, got {_shown(store_paths)}")
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
        entry = (parse_irsim_entry if isinstance(v, Mapping) and "irsim" in v else _parse_map)(
            i, v, top_seeds, radius, exp_dir, seeds_override is not None)
        if entry.name in names:
            raise ConfigError(f"maps[{i}].name: {_shown(entry.name)} is already the name of "
                              f"maps[{names[entry.name]}]")
        names[entry.name] = i
        maps.append(entry)
    kinds = tuple(k for k in ("static", "dynamic", "irsim") if any(m.kind == k for m in maps))
    raw_planners = doc.get("planners")
    if not isinstance(raw_planners, list) or not raw_planners:
        raise ConfigError("planners: must be a non-empty list of planners")
    planners = tuple(_parse_planner(i, v, limits, kinds) for i, v in enumerate(raw_planners))
    for m in maps:
        if not any(m.kind in p.kinds for p in planners):
            raise ConfigError(f"maps[{m.index}]: no planner of this experiment runs "
                              f"{m.kind} maps (" + ("planners that run online: "
                              + ", ".join(_registry(m.kind).names()) if m.kind != "static"
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
    from pathfuse.bench.plugins import ensure_imports

    paths = [str((base_dir / i).resolve()) if i.endswith(".py") and not Path(i).is_absolute()
             else i for i in imports]
    try:
        ensure_imports(paths)
    except Exception as exc:  # noqa: BLE001 - any import failure is a config error
        raise ConfigError(f"imports: cannot import: {type(exc).__name__}: {exc}") from None


def _radius(v: Any, where: str) -> float:
    if not _is_num(v) or float(v) < 0:
        raise ConfigError(f"{where}: must be a number >= 0 (metres), got {_shown(v)}")
    return float(v)


def _parse_reference(v: Any) -> dict[str, Any] | None:
    if v is None or v is False:
        return None
    from pathfuse.planners.registry import get_planner, make_params

    if isinstance(v, str):
        v = {"planner": v}
    if not isinstance(v, Mapping) or "planner" not in v or set(v) - {"planner", "params"}:
        raise ConfigError(f"reference: must be a planner name or {{planner, params}}, "
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
        return names if self.kind == "static" else \
            [n for n in names if REGISTRY[n].online] + external_names(self.kind)

    def get(self, name: Any) -> Any:
        from pathfuse.planners.registry import get_planner

        spec = external_spec(self.kind, name) or get_planner(name)
        if self.kind == "dynamic" and not spec.online:
            raise ConfigError(f"planner {_shown(spec.name)} only plans offline; it cannot run on a "
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
        raise ConfigError(f"{where}: must be a planner name or a mapping with name/params, "
                          f"got {_short(v)}")
    mapping(v, where, _PLANNER_KEYS)
    if "name" not in v:
        raise ConfigError(f"{where}.name: missing (the planner's registry name)")
    name = v["name"]
    if "kinds" in v:
        want = v["kinds"]
        want = [want] if isinstance(want, str) else want
        if not isinstance(want, list) or not want or \
                not set(want) <= {"static", "dynamic", "irsim"}:
            raise ConfigError(f"{where}.kinds: must be a list of static / dynamic / irsim, "
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
        raise ConfigError(f"{where}.name: unknown planner {_shown(name)} (choose from {choices})")
    label = v.get("label")
    if label is not None and (not isinstance(label, str) or not label.strip()):
        raise ConfigError(f"{where}.label: must be a non-empty string, got {_shown(label)}")
    raw = v.get("params") or {}
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{where}.params: must be a mapping of parameter: value or "
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
                raise ConfigError(f"{kw}: {what} {_shown(sp.name)} has no such parameter; its "
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
    n_combos = 1
    for _, vals in params:
        n_combos *= len(vals)
    if n_combos > 1:
        grid = " x ".join(str(len(vals)) for _, vals in params if len(vals) > 1)
        check_count(n_combos, "MAX_RUNS", f"{where}.params: the parameter grid ({grid})")
    entry = PlannerEntry(
        index=i, name=name, label=label.strip() if label else None, params=tuple(params),
        limits=_parse_limits(v.get("limits"), f"{where}.limits", top_limits),
        kinds=tuple(specs), fields_by_kind=fields_by_kind,
        defaults_by_kind={k: _plain(sp.key_defaults()) for k, sp in specs.items()})
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


def _dynamic_entry(i: int, v: Mapping[str, Any], where: str, seeds: tuple[int, ...],
                   radius: float, exp_dir: Path) -> MapEntry:
    """A ``dynamic:`` map entry (a scenario file, or a mapping such as ``generate:``)."""
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
            check_generate(dyn, f"{where}.dynamic")
        default_name = f"dynamic-{i}"
    else:
        raise ConfigError(f"{where}.dynamic: must be a scenario file or a mapping, "
                          f"got {_short(dyn)}")
    name = _entry_name(v, where, default_name)
    return MapEntry(index=i, name=name, kind="dynamic", spec=None, family=None,
                    seeds=seeds, robot_radius_m=radius, dynamic=dyn)


def _queries(q: Any, where: str) -> tuple[list[dict[str, Any]], dict[str, Any] | None]:
    """``(queries, random_queries)`` of a map entry's ``queries:`` (a list of
    ``{start, goal}`` or ``[[x, y], [x, y]]``, or ``{random: N, min_distance_m: D}``)."""
    queries: list[dict[str, Any]] = []
    if isinstance(q, Mapping):
        if set(q) - {"random", "min_distance_m"} or "random" not in q:
            raise ConfigError(f"{where}.queries: must be a list of {{start, goal}} or "
                              f"{{random: N, min_distance_m: D}}, got {_short(dict(q))}")
        n = q["random"]
        if not _is_int(n) or n < 1:
            raise ConfigError(f"{where}.queries.random: must be an integer >= 1, got"
                              f" {_shown(n)}")
        check_count(int(n), "MAX_RUNS", f"{where}.queries.random")
        d = q.get("min_distance_m", 0.0)
        if not _is_num(d) or float(d) < 0:
            raise ConfigError(f"{where}.queries.min_distance_m: must be a number >= 0, "
                              f"got {_shown(d)}")
        return queries, {"count": int(n), "min_distance_m": float(d)}
    if not (isinstance(q, list) and q):
        raise ConfigError(f"{where}.queries: must be a non-empty list of {{start, goal}} "
                          f"or {{random: N}}, got {_short(q)}")
    for j, item in enumerate(q):
        qw = f"{where}.queries[{j}]"
        if isinstance(item, Mapping):
            if set(item) - {"start", "goal"}:
                raise ConfigError(f"{qw}: must be {{start: [x, y], goal: [x, y]}}, "
                                  f"got {_short(dict(item))}")
            s, g = item.get("start"), item.get("goal")
            queries.append({"start": _point(s, f"{qw}.start"),
                            "goal": _point(g, f"{qw}.goal")})
        elif isinstance(item, list) and len(item) == 2:
            queries.append({"start": _point(item[0], f"{qw}[0]"),
                            "goal": _point(item[1], f"{qw}[1]")})
        else:
            raise ConfigError(f"{qw}: must be {{start: [x, y], goal: [x, y]}} or "
                              f"[[x, y], [x, y]], got {_short(item)}")
    return queries, None


def _parse_map(i: int, v: Any, top_seeds: tuple[int, ...], top_radius: float,
               exp_dir: Path, seeds_overridden: bool) -> MapEntry:
    where = f"maps[{i}]"
    if isinstance(v, str):
        v = {"map": v}
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}: must be a mapping with map (or dynamic) and queries, "
                          f"got {_short(v)}")
    mapping(v, where, _MAP_KEYS)
    seeds = top_seeds if seeds_overridden or "seeds" not in v else \
        parse_seeds(v["seeds"], f"{where}.seeds")
    radius = _radius(v.get("robot_radius_m", top_radius), f"{where}.robot_radius_m")
    if "dynamic" in v:
        return _dynamic_entry(i, v, where, seeds, radius, exp_dir)
    if "map" not in v:
        raise ConfigError(f"{where}.map: missing (a map spec such as paper, "
                          "{movingai: FILE}, {ros: FILE.yaml}; or use dynamic)")
    spec, family = _parse_map_spec(v["map"], f"{where}.map", exp_dir)
    default_name = family if family in GENERATED_FAMILIES else (
        Path(_file_of(spec, family)).stem if family in FILE_FAMILIES else
        Path(v["map"]).stem if isinstance(v["map"], str) else f"map-{i}")
    name = _entry_name(v, where, default_name)
    given = [k for k in ("queries", "scen") if k in v] + (
        ["start/goal"] if ("start" in v or "goal" in v) else [])
    if len(given) > 1:
        raise ConfigError(f"{where}: give only one of start/goal, queries and scen "
                          f"(got {', '.join(given)})")
    if "lines" in v and "scen" not in v:
        raise ConfigError(f"{where}.lines: only used with scen")
    queries: list[dict[str, Any]] = []
    random_q: dict[str, Any] | None = None
    scen = None
    if "scen" in v:
        scen = v["scen"]
        if not isinstance(scen, str):
            raise ConfigError(f"{where}.scen: must be a .scen file path, got {_short(scen)}")
        sp = Path(scen) if Path(scen).is_absolute() else exp_dir / scen
        if not sp.is_file():
            from pathfuse.datasets import missing_hint
            raise ConfigError(f"{where}.scen: no such file {sp} ({missing_hint('movingai')})")
        if family != "movingai":
            raise ConfigError(f"{where}.scen: scen files go with MovingAI maps "
                              f"({{movingai: FILE}}), not {_shown(family)}")
        if "lines" in v:  # the form now; the line numbers once the file is read
            _check_lines_form(v["lines"], f"{where}.lines")
    elif "start" in v or "goal" in v:
        queries.append({"start": _point(v.get("start"), f"{where}.start"),
                        "goal": _point(v.get("goal"), f"{where}.goal")})
    elif "queries" in v:
        queries, random_q = _queries(v["queries"], where)
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


def _entry_name(v: Mapping[str, Any], where: str, default: str) -> str:
    name = v.get("name", default)
    if not isinstance(name, str) or not name.strip() or "/" in name:
        raise ConfigError(f"{where}.name: must be a non-empty string without '/', "
                          f"got {_shown(name)}")
    return name.strip()


def _parse_map_spec(m: Any, where: str, exp_dir: Path) -> tuple[dict[str, Any], str]:
    if isinstance(m, str):
        low = m.lower()
        if m in GENERATED_FAMILIES:
            m = {m: {}}
        elif low.endswith(".map"):
            m = {"movingai": m}
        elif low.endswith((".yaml", ".yml")):
            m = _yaml_map_spec(m, where, exp_dir)
        else:
            raise ConfigError(f"{where}: {_shown(m)} is not a map family (paper, random) nor a "
                              ".map / .yaml file; use a mapping such as {image: FILE, "
                              "resolution: 0.05}")
    if not isinstance(m, Mapping):
        raise ConfigError(f"{where}: must be a map spec mapping, got {_short(m)}")
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
            raise ConfigError(f"{where}.{family}: must be a mapping of generator arguments, "
                              f"got {_short(inner)}")
        if "seed" in spec[family] and (not _is_int(spec[family]["seed"])
                                       or spec[family]["seed"] < 0):
            raise ConfigError(f"{where}.{family}.seed: must be an integer >= 0, "
                              f"got {_shown(spec[family]['seed'])}")
    elif family in FILE_FAMILIES:
        rel = spec[family]
        if not isinstance(rel, str) or not rel.strip():
            raise ConfigError(f"{where}.{family}: missing file name")
        p = Path(os.path.expanduser(rel))
        p = p if p.is_absolute() else exp_dir / p
        if not p.is_file():
            from pathfuse.datasets import missing_hint
            hint = f" ({missing_hint('movingai')})" if family == "movingai" else ""
            raise ConfigError(f"{where}.{family}: no such file {p}{hint}")
    return spec, family


def _point(v: Any, where: str) -> list[float]:
    if v is None:
        raise ConfigError(f"{where}: missing (an [x, y] point in metres)")
    return list(point(v, where))


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
                                  f"{_shown(entry.name)} [{x0:g}, {x1:g}) x [{y0:g}, {y1:g})")


