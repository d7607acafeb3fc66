"""A study database read back: its runs, planner configurations and map entries, and the
per-group statistics of ``pathfuse report`` (:func:`summary_rows`, :func:`parameter_rows`).

See :mod:`pathfuse.bench.report` for what the report shows.
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pathfuse.bench.summary import group_stats, value_stats
from pathfuse.result import ConfigError

_RUN_FIELDS = ("id", "experimentid", "plannerid", "kind", "planner", "seed", "problem_key",
               "solved", "status_name", "solution_length", "time", "collision_free",
               "collisions", "time_to_goal", "R_length", "reference_source", "params")


@dataclass(frozen=True)
class ConfigInfo:
    """One planner configuration (``plannerConfigs`` row) as the report names it.

    ``name`` is the stored name, made unique within a run kind by appending
    ``#id`` when two configurations share it; ``params`` are its full
    parameters.
    """

    id: int
    name: str
    planner: str
    kind: str
    params: Mapping[str, Any]


@dataclass(frozen=True)
class ExperimentInfo:
    """One map entry (OMPL experiment) of the study: ``name`` is ``"study/entry"``."""

    id: int
    name: str
    entry: str
    kind: str


@dataclass
class Study:
    """The runs of a study database, read once.

    ``runs`` are dicts of the columns in ``_RUN_FIELDS`` (``solved`` and
    ``collision_free`` as bool or None), in ``runs.id`` order.
    """

    path: Path
    runs: list[dict[str, Any]]
    configs: dict[int, ConfigInfo]
    experiments: dict[int, ExperimentInfo]
    sessions: list[dict[str, Any]] = field(default_factory=list)

    @property
    def kinds(self) -> list[str]:
        """Run kinds present, in order of first appearance."""
        return list(dict.fromkeys(r["kind"] for r in self.runs))

    def config_ids(self, kind: str | None = None) -> list[int]:
        """Configuration ids that have runs (of ``kind``), in id order."""
        ids = {r["plannerid"] for r in self.runs if kind is None or r["kind"] == kind}
        return sorted(ids)


# --------------------------------------------------------------------------- loading
def _connect(path: Path) -> sqlite3.Connection:
    from pathfuse.bench.dbcheck import check_study_file
    from pathfuse.bench.migrate import open_current

    check_study_file(path, write=False)  # a folder, not SQLite, foreign, damaged
    try:
        conn = open_current(str(path))  # an older schema: migrated in memory, file untouched
        conn.row_factory = sqlite3.Row
        tables = {r[0] for r in conn.execute(
            "SELECT name FROM sqlite_master WHERE type IN ('table', 'view')")}
    except sqlite3.Error as exc:
        raise ConfigError(f"{path}: cannot read the database ({exc})") from None
    need = {"runs", "experiments", "plannerConfigs", "enums", "pathfuse_meta", "pathfuse_runs",
            "pathfuse_experiments", "pathfuse_configs", "pathfuse_results"}
    if not need <= tables:
        conn.close()
        missing = ", ".join(sorted(need - tables))
        raise ConfigError(f"{path}: not a pathfuse study database (no table {missing}; "
                          "write one with pathfuse bench)")
    return conn


def _select_runs(conn: sqlite3.Connection) -> list[sqlite3.Row]:
    """The columns of ``_RUN_FIELDS`` of every run (NULL for a property no run reported)."""
    have = {r[1] for r in conn.execute("PRAGMA table_info(pathfuse_results)")}
    cols = ", ".join(f'"{c}"' if c in have else f'NULL AS "{c}"' for c in _RUN_FIELDS)
    return conn.execute(f"SELECT {cols}, run_key, status, status_text FROM pathfuse_results "
                        "ORDER BY id").fetchall()


def _run_dict(r: sqlite3.Row) -> dict[str, Any]:
    """One run for the report.  A run appended from an OMPL log (no pathfuse row) is of
    kind ``ompl``, its status OMPL's text, its planner its configuration."""
    d = {c: r[c] for c in _RUN_FIELDS}
    d["solved"] = bool(d["solved"])  # OMPL's solved: an exact solution, as pathfuse's
    d["collision_free"] = _opt_bool(d["collision_free"])
    if r["run_key"] is None:
        d["kind"] = "ompl"
        d["status_name"] = r["status_text"] or f"OMPL status {r['status']}"
    d["kind"] = d["kind"] or "static"
    return d


def _json(text: Any) -> Any:
    try:
        return json.loads(text) if isinstance(text, str) else None
    except ValueError:
        return None


def _opt_bool(v: Any) -> bool | None:
    return None if v is None else bool(v)


def load_study(db_path: str | Path) -> Study:
    """Read a study database (read-only).

    Raises
    ------
    ConfigError
        One line naming the file: missing, a folder, not SQLite, not written
        by pathfuse, unreadable, or without any run.
    """
    path = Path(db_path)
    conn = _connect(path)
    try:
        rows = _select_runs(conn)
        exps = conn.execute("SELECT e.id, e.name, e.version, p.entry, p.kind "
                            "FROM experiments e LEFT JOIN pathfuse_experiments p "
                            "ON p.experimentid = e.id ORDER BY e.id").fetchall()
        cfgs = conn.execute("SELECT c.id, c.name, p.planner, c.settings "
                            "FROM plannerConfigs c LEFT JOIN pathfuse_configs p "
                            "ON p.plannerid = c.id ORDER BY c.id").fetchall()
        try:
            sessions = [dict(r) for r in conn.execute(
                "SELECT study, experiment_file, started_at, finished_at, state, host, "
                "pathfuse_version, workers, scheduler, planned, skipped, ran, errors "
                "FROM pathfuse_sessions ORDER BY id")]
        except sqlite3.Error:
            sessions = []
    except sqlite3.Error as exc:
        raise ConfigError(f"{path}: cannot read the database ({exc})") from None
    finally:
        conn.close()
    if not rows:
        raise ConfigError(f"{path}: the study holds no runs yet "
                          "(run 'pathfuse bench EXPERIMENT.yaml --db "
                          f"{path}' first)")
    runs = [_run_dict(r) for r in rows]
    experiments = {}
    for e in exps:
        name = e["name"] or f"experiment {e['id']}"
        if e["kind"] is None:  # appended from an OMPL log: named apart from pathfuse's entries
            experiments[int(e["id"])] = ExperimentInfo(int(e["id"]), name,
                                                       f"{name} [{e['version']}]", "ompl")
            continue
        entry = e["entry"] or name.rsplit("/", 1)[-1]
        experiments[int(e["id"])] = ExperimentInfo(int(e["id"]), name, entry, e["kind"])
    kind_of: dict[int, str] = {}
    first_params: dict[int, Any] = {}
    for d in runs:
        kind_of.setdefault(d["plannerid"], d["kind"])
        first_params.setdefault(d["plannerid"], d["params"])
    configs: dict[int, ConfigInfo] = {}
    for c in cfgs:
        cid = int(c["id"])
        if cid not in kind_of:
            continue
        params = _json(c["settings"])
        if not isinstance(params, dict):  # fall back to the run's parameters (minus seed)
            p = _json(first_params[cid])
            params = dict(p.get("params") or {}) if isinstance(p, dict) else {}
            params.pop("seed", None)
        configs[cid] = ConfigInfo(cid, c["name"], c["planner"] or c["name"], kind_of[cid],
                                  params)
    # names unique within a kind
    for kind in set(kind_of.values()):
        same: dict[str, list[int]] = {}
        for cid, c in configs.items():
            if c.kind == kind:
                same.setdefault(c.name, []).append(cid)
        for name, ids in same.items():
            if len(ids) > 1:
                for cid in ids:
                    c = configs[cid]
                    configs[cid] = ConfigInfo(cid, f"{name}#{cid}", c.planner, c.kind, c.params)
    for d in runs:
        if d["plannerid"] not in configs:  # a run without its config row: keep it anyway
            configs[d["plannerid"]] = ConfigInfo(d["plannerid"], f"config#{d['plannerid']}",
                                                 d["planner"] or "?", d["kind"], {})
        if d["experimentid"] not in experiments:
            experiments[d["experimentid"]] = ExperimentInfo(
                d["experimentid"], f"experiment {d['experimentid']}",
                f"experiment-{d['experimentid']}", d["kind"])
    return Study(path, runs, configs, experiments, sessions)


# --------------------------------------------------------------------------- parameters
def _value_key(v: Any) -> str:
    return json.dumps(v, sort_keys=True)


def swept_parameters(study: Study, names: Sequence[str] | None = None
                     ) -> dict[tuple[str, str], list[str]]:
    """``{(kind, planner): [parameter, ...]}`` of the parameters to plot.

    Without ``names``: every parameter that takes more than one value among
    the configurations of a planner (of one run kind).  With ``names``: those
    parameters, for every planner that has them (:class:`ConfigError` naming
    the parameters the study has when one is unknown).
    """
    by: dict[tuple[str, str], list[ConfigInfo]] = {}
    for kind in study.kinds:  # a configuration can run on static and dynamic entries alike
        for cid in study.config_ids(kind):
            c = study.configs[cid]
            by.setdefault((kind, c.planner), []).append(c)
    out: dict[tuple[str, str], list[str]] = {}
    if names:
        known = sorted({k for cs in by.values() for c in cs for k in c.params})
        for n in names:
            if n not in known:
                raise ConfigError(f"--param {n}: no planner of the study has this parameter "
                                  f"(parameters: {', '.join(known) or 'none'})")
        for key, cs in by.items():
            have = [n for n in dict.fromkeys(names) if any(n in c.params for c in cs)]
            if have:
                out[key] = have
        return out
    for key, cs in by.items():
        keys = list(dict.fromkeys(k for c in cs for k in c.params))
        sw = [k for k in keys
              if len({_value_key(c.params.get(k)) for c in cs}) > 1]
        if sw:
            out[key] = sw
    return out


# --------------------------------------------------------------------------- R_length
def resolve_reference(study: Study, name: str) -> dict[str, int]:
    """``{kind: config id}`` of the reference ``name`` (a config name, or a planner that
    has exactly one configuration in that run kind).  :class:`ConfigError` if none or
    ambiguous."""
    out: dict[str, int] = {}
    for kind in study.kinds:
        ids = study.config_ids(kind)
        exact = [i for i in ids if study.configs[i].name == name]
        if not exact:
            exact = [i for i in ids if study.configs[i].planner == name]
            if len(exact) > 1:
                names = ", ".join(study.configs[i].name for i in exact)
                raise ConfigError(f"--reference {name}: planner {name} has {len(exact)} "
                                  f"configurations ({names}); name one of them")
        if len(exact) == 1:
            out[kind] = exact[0]
    if not out:
        avail = ", ".join(dict.fromkeys(study.configs[i].name for i in study.config_ids()))
        raise ConfigError(f"--reference {name}: no such planner or configuration in "
                          f"{study.path} (configurations: {avail})")
    return out


def r_length_values(study: Study, reference: str | None = None) -> dict[int, float]:
    """``{run id: R_length}`` for every run paired with a solved reference.

    ``reference=None``: the stored ``runs.R_length`` (the experiment's own
    reference) of solved runs.  Otherwise each solved run of a kind is paired
    with the reference configuration's solved run on the same ``problem_key``
    and ``seed``: R = (L - L_ref) / L_ref.
    """
    out: dict[int, float] = {}
    if reference is None:
        for r in study.runs:
            v = r["R_length"]
            if r["solved"] and v is not None and math.isfinite(v):
                out[r["id"]] = float(v)
        return out
    ref_ids = resolve_reference(study, reference)
    ref_len: dict[tuple[str, str, int], float] = {}
    for r in study.runs:
        if ref_ids.get(r["kind"]) == r["plannerid"] and r["solved"] \
                and r["solution_length"] is not None and r["solution_length"] > 0:
            ref_len[(r["kind"], r["problem_key"], r["seed"])] = float(r["solution_length"])
    for r in study.runs:
        if not r["solved"] or r["solution_length"] is None:
            continue
        lr = ref_len.get((r["kind"], r["problem_key"], r["seed"]))
        if lr is not None:
            out[r["id"]] = (float(r["solution_length"]) - lr) / lr
    return out


def excess_values(study: Study) -> dict[int, float]:
    """``{run id: (L - L_shortest) / L_shortest}``: each solved run paired with the solved run
    of the ``shortest`` planner on the same ``problem_key`` and ``seed`` (empty when the
    study has no ``shortest`` run)."""
    low: dict[tuple[str, str, int], float] = {}
    for r in study.runs:
        if study.configs[r["plannerid"]].planner == "shortest" and r["solved"] \
                and r["solution_length"] is not None and r["solution_length"] > 0:
            low[(r["kind"], r["problem_key"], r["seed"])] = float(r["solution_length"])
    out: dict[int, float] = {}
    if not low:
        return out
    for r in study.runs:
        if not r["solved"] or r["solution_length"] is None \
                or study.configs[r["plannerid"]].planner == "shortest":
            continue
        ls = low.get((r["kind"], r["problem_key"], r["seed"]))
        if ls is not None:
            out[r["id"]] = (float(r["solution_length"]) - ls) / ls
    return out


def _reference_label(study: Study, reference: str | None) -> str:
    if reference is not None:
        ids = resolve_reference(study, reference)
        return ", ".join(f"{study.configs[i].name} ({k})" for k, i in ids.items())
    srcs = sorted({r["reference_source"] for r in study.runs if r["reference_source"]})
    if not srcs:
        return "none"
    return ", ".join("the scen file's optimum" if s == "scen" else s for s in srcs) + \
        " (the experiment's reference)"


# --------------------------------------------------------------------------- statistics
def _group_stats(runs: Sequence[Mapping[str, Any]], rl: Mapping[int, float]) -> dict[str, Any]:
    return group_stats(runs, rl)


def _scopes(study: Study) -> list[tuple[str, str, list[dict[str, Any]], bool]]:
    """(scope, kind, runs, pooled): each map entry, then each kind pooled."""
    out = []
    names = _scope_names(study)
    for eid in sorted(names):
        rs = [r for r in study.runs if r["experimentid"] == eid]
        out.append((names[eid], rs[0]["kind"], rs, False))
    kinds = study.kinds
    for kind in kinds:
        rs = [r for r in study.runs if r["kind"] == kind]
        out.append(("all" if len(kinds) == 1 else f"all {kind}", kind, rs, True))
    return out


def _scope_names(study: Study) -> dict[int, str]:
    """Experiment id -> scope name (the entry, or the full name where entries repeat)."""
    ids = sorted({r["experimentid"] for r in study.runs})
    entries = [study.experiments[i].entry for i in ids]
    return {i: (study.experiments[i].entry if entries.count(study.experiments[i].entry) == 1
                else study.experiments[i].name) for i in ids}


def summary_rows(study: Study, reference: str | None = None,
                 rl: Mapping[int, float] | None = None) -> list[dict[str, Any]]:
    """One row per (scope, planner configuration): see the module docstring.

    ``scope`` is a map entry (``pooled`` False), then ``all`` (or ``all static`` / ``all
    dynamic`` when the study has both kinds) pooling every entry of the kind.
    ``param.<name>`` columns hold the configuration's value of every swept
    parameter (empty where the planner has no such parameter).
    """
    if rl is None:
        rl = r_length_values(study, reference)
    ex = excess_values(study)
    swept = sorted({p for ps in swept_parameters(study).values() for p in ps})
    rows = []
    for scope, kind, runs, pooled in _scopes(study):
        by: dict[int, list[dict[str, Any]]] = {}
        for r in runs:
            by.setdefault(r["plannerid"], []).append(r)
        for cid in sorted(by):
            c = study.configs[cid]
            row: dict[str, Any] = {"scope": scope, "pooled": pooled, "kind": kind,
                                   "planner": c.planner, "config": c.name}
            for p in swept:
                row[f"param.{p}"] = _param_text(c.params[p]) if p in c.params else ""
            row.update(_group_stats(by[cid], rl))
            vals = [ex[r["id"]] for r in by[cid] if r["id"] in ex]
            st = value_stats(vals, "excess")
            row.update({"excess_pairs": len(vals), "excess_mean": st["excess_mean"],
                        "excess_ci_low": st["excess_ci_low"],
                        "excess_ci_high": st["excess_ci_high"],
                        "excess_median": st["excess_median"]})
            rows.append(row)
    return rows


def _param_text(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, str):
        return v
    return json.dumps(v)


def _sort_values(values: Iterable[Any]) -> tuple[list[Any], bool]:
    """Distinct values sorted; True when all are numbers (a numeric axis)."""
    uniq = list({_value_key(v): v for v in values}.values())
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in uniq)
    if numeric:
        return sorted(uniq), True
    return sorted(uniq, key=_value_key), False


def parameter_rows(study: Study, swept: Mapping[tuple[str, str], Sequence[str]] | None = None,
                   reference: str | None = None, rl: Mapping[int, float] | None = None
                   ) -> list[dict[str, Any]]:
    """For each (kind, planner, parameter) of ``swept`` (default: auto-detected), one row
    per (scope, value) pooling every configuration of the planner with that value."""
    if swept is None:
        swept = swept_parameters(study)
    if rl is None:
        rl = r_length_values(study, reference)
    rows = []
    for (kind, planner), params in swept.items():
        cfg = {cid: study.configs[cid] for cid in study.config_ids(kind)
               if study.configs[cid].planner == planner}
        for p in params:
            values, _ = _sort_values(c.params[p] for c in cfg.values() if p in c.params)
            for scope, skind, runs, pooled in _scopes(study):
                if skind != kind:
                    continue
                for v in values:
                    ids = {cid for cid, c in cfg.items()
                           if p in c.params and _value_key(c.params[p]) == _value_key(v)}
                    sel = [r for r in runs if r["plannerid"] in ids]
                    if not sel:
                        continue
                    rows.append({"scope": scope, "pooled": pooled, "kind": kind,
                                 "planner": planner,
                                 "parameter": p, "value": _param_text(v),
                                 "configs": len({r["plannerid"] for r in sel}),
                                 **_group_stats(sel, rl)})
    return rows


