"""Reports of a study database: tables per planner configuration, box plots, sweeps.

:func:`write_report` reads a study written by :func:`pathfuse.bench.run_bench`
(``pathfuse bench``) and writes, into one folder:

``report.md`` / ``report.html``
    Every table and figure on one page (the HTML is self-contained: inline
    CSS, the figures embedded as base64 and linked to their PNG files).
``summary.csv``
    One row per (scope, planner configuration); ``scope`` is a map entry
    (OMPL experiment, e.g. ``"paper"``) or ``all`` / ``all static`` /
    ``all dynamic`` (every entry of a run kind pooled).
``parameters.csv``
    For every swept parameter of a planner: one row per (scope, value),
    pooling the configurations that share that value.
``length_<entry>.png``, ``time_<entry>.png``, ``r_length_<entry>.png``
    Box plots per planner configuration of each map entry.
``param_<planner>_<name>.png``
    A swept parameter against the success rate (95 % Wilson bars) and the
    mean path length (95 % t bars).

Statistics (every row):

* ``runs`` counts every stored run; ``solved + not_solved + errors = runs``.
  Runs that raised (``ERROR``) are counted separately and never dropped:
  they count as not solved in the success rate.
* success rate = solved / runs, with a 95 % Wilson score interval.
* collision-free rate = solved runs whose path is collision-free / solved
  runs whose path was checked (Wilson interval); collision rate = runs with
  a collision / runs (dynamic worlds: the episode ended in a collision).
* path length, time to goal: over solved runs (mean, 95 % Student-t
  interval, median); planning time: over every run that did not raise.
* R_length = (L - L_ref) / L_ref (the paper's eq.), over the runs where the
  run *and* its reference solved the same problem (``problem_key`` + ``seed``);
  ``r_length_pairs`` says how many.  By default the reference is the one the
  experiment file named (the stored ``runs.R_length``: the reference
  planner, or the optimum of a MovingAI scen line); ``reference=`` picks a
  planner or planner configuration of the study instead.
* excess over the shortest path = (L - L_shortest) / L_shortest, when the
  study ran the ``shortest`` planner: each solved run paired with
  ``shortest``'s solved run on the same problem and seed (``excess_pairs``;
  :func:`~pathfuse.bench.study.excess_values`).

Runs appended to the study from OMPL's benchmark logs (``ompl_benchmark_statistics -a``)
are reported too: of kind ``ompl``, each OMPL experiment a scope ``"<name> [OMPL x.y.z]"``,
their failures by OMPL's status text (an approximate solution is not solved, as in OMPL's
``solved`` column).

A swept parameter is one that takes more than one value among the
configurations of a planner (per run kind), read from the configurations'
full parameters (``plannerConfigs.settings``, the run's ``params`` without
its seed).

Examples
--------
>>> import pathlib, tempfile
>>> from pathfuse.bench import run_bench
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = (d / "exp.yaml").write_text('''
... seeds: 3
... maps:
...   - name: room
...     map: {rows: ["......", ".##...", "......"]}
...     start: [0.5, 0.5]
...     goal: [5.5, 2.5]
... planners:
...   - name: astar
...     params: {heuristic: [euclidean, octile]}
... ''')
>>> _ = run_bench(d / "exp.yaml", d / "study.db", workers=1, progress=False)
>>> study = load_study(d / "study.db")
>>> len(study.runs), swept_parameters(study)
(6, {('static', 'astar'): ['heuristic']})
>>> rows = summary_rows(study)
>>> [(r["scope"], r["config"], r["runs"], r["solved"], r["r_length_mean"]) for r in rows]
... # doctest: +NORMALIZE_WHITESPACE
[('room', 'astar(heuristic=euclidean)', 3, 3, 0.0),
 ('room', 'astar(heuristic=octile)', 3, 3, 0.0),
 ('all', 'astar(heuristic=euclidean)', 3, 3, 0.0),
 ('all', 'astar(heuristic=octile)', 3, 3, 0.0)]
>>> files = write_report(d / "study.db", d / "out")
>>> sorted(p.name for p in files.values())[:4]
['length_room.png', 'param_astar_heuristic.png', 'parameters.csv', 'r_length_room.png']
"""

from __future__ import annotations

import base64
import html
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.bench.study import (
    ConfigInfo,
    ExperimentInfo,
    Study,
    _reference_label,
    _scope_names,
    _scopes,
    _sort_values,
    load_study,
    parameter_rows,
    r_length_values,
    resolve_reference,
    summary_rows,
    swept_parameters,
)
from pathfuse.result import ConfigError
from pathfuse.stats import markdown_table, write_csv

__all__ = [
    "ConfigInfo",
    "ExperimentInfo",
    "Study",
    "load_study",
    "swept_parameters",
    "resolve_reference",
    "r_length_values",
    "summary_rows",
    "parameter_rows",
    "write_report",
    "build_report",
    "StudyReport",
]

# --------------------------------------------------------------------------- formatting
def _pct_ci(row: Mapping[str, Any], key: str, count: str, n: str) -> str:
    if not row[n]:
        return "n/a"
    return (f"{row[count]}/{row[n]} = {100 * row[key + '_rate']:.1f}% "
            f"[{100 * row[key + '_ci_low']:.1f}, {100 * row[key + '_ci_high']:.1f}]")


def _decimals(v: float, digits: int = 3, most: int = 4) -> int:
    """Decimals that show ``v`` with ``digits`` significant digits (at most ``most``)."""
    if not np.isfinite(v) or v == 0:
        return 2
    return int(min(most, max(0, digits - 1 - math.floor(math.log10(abs(v))))))


def _num_ci(row: Mapping[str, Any], base: str, unit: str = "", scale: float = 1.0,
            fmt: str | None = None) -> tuple[str, str]:
    """``"mean [low, high]"`` and the median, all with the decimals of the mean (``fmt``
    fixes them; default 3 significant digits of the mean)."""
    m = row[f"{base}_mean{unit}"]
    if not np.isfinite(m):
        return "n/a", "n/a"
    f = fmt or f"{{:.{_decimals(m * scale)}f}}"
    lo, hi = row[f"{base}_ci_low{unit}"] * scale, row[f"{base}_ci_high{unit}"] * scale
    return (f"{f.format(m * scale)} [{f.format(lo)}, {f.format(hi)}]",
            _num(row[f"{base}_median{unit}"], scale, f))


def _num(v: float, scale: float = 1.0, fmt: str = "{:.3f}") -> str:
    return "n/a" if not np.isfinite(v) else fmt.format(v * scale)


def _r_cell(row: Mapping[str, Any]) -> str:
    if not row["r_length_pairs"]:
        return "n/a"
    m, lo, hi = row["r_length_mean"], row["r_length_ci_low"], row["r_length_ci_high"]
    return f"{100 * m:+.2f}% [{100 * lo:+.2f}, {100 * hi:+.2f}]"


def _table(rows: Sequence[Mapping[str, Any]], first: Sequence[tuple[str, str]],
           dynamic: bool) -> list[list[list[str]]]:
    """Three tables of at most nine columns (a window's width): outcomes, lengths and
    times, R_length (and the excess over the shortest path, when the study has one).

    Lengths in m with 3 decimals, times with 3 significant digits (mean, interval and
    median of a row alike), rates in % with 1 decimal, R_length and the excess with 2.
    """
    key = [h for h, _ in first]
    out_head = key + ["runs", "success [95% CI]", "errors", "not solved by status",
                      "collision-free (solved)"] + (["collisions [95% CI]"] if dynamic else [])
    num_head = key + ["length (m) mean [95% CI]", "median", "time (ms) mean [95% CI]",
                      "median"] + (["time to goal (s) mean [95% CI]", "median"] if dynamic
                                   else [])
    r_head = key + ["R_length mean [95% CI]", "median", "shorter / pairs"]
    excess = any(r.get("excess_pairs") for r in rows)
    if excess:
        r_head += ["excess over the shortest path mean [95% CI]", "median", "pairs"]
    outcomes, numbers, ratios = [out_head], [num_head], [r_head]
    for r in rows:
        k = [str(r[c]) for _, c in first]
        outcomes.append(k + [
            str(r["runs"]), _pct_ci(r, "success", "solved", "runs"), str(r["errors"]),
            r["failures"] or "-",
            _pct_ci(r, "collision_free", "collision_free", "collision_checked")]
            + ([_pct_ci(r, "collision", "collision_runs", "runs")] if dynamic else []))
        numbers.append(k + [*_num_ci(r, "length", "_m", fmt="{:.3f}"),
                            *_num_ci(r, "time", "_s", 1e3)]
                       + (list(_num_ci(r, "time_to_goal", "_s")) if dynamic else []))
        pairs = r["r_length_pairs"]
        line = k + [_r_cell(r), f"{100 * r['r_length_median']:+.2f}%" if pairs else "n/a",
                    f"{r['r_length_shorter']}/{pairs}" if pairs else "n/a"]
        if excess:
            n = r.get("excess_pairs", 0)
            line += ["n/a" if not n else
                     f"{100 * r['excess_mean']:+.2f}% [{100 * r['excess_ci_low']:+.2f}, "
                     f"{100 * r['excess_ci_high']:+.2f}]",
                     "n/a" if not n else f"{100 * r['excess_median']:+.2f}%", str(n)]
        ratios.append(line)
    return [outcomes, numbers, ratios]


def _slug(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-.")
    return s or "x"


def _csv_value(v: Any) -> Any:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    return v


# --------------------------------------------------------------------------- the report
@dataclass
class _Section:
    title: str
    text: str = ""
    tables: list[list[list[str]]] = field(default_factory=list)
    images: list[tuple[str, str]] = field(default_factory=list)  # (file name, caption)
    level: int = 2


_NOTES = (
    "runs counts every stored run (solved + not solved + errors). Runs that raised "
    "(ERROR) are never dropped: they count as not solved. Success rate: solved / runs "
    "with a 95% Wilson score interval. Collision-free: solved runs whose path is "
    "collision-free / solved runs that were checked. Length (and time to goal) over solved "
    "runs; planning time over every run that did not raise. Means come with a 95% "
    "interval: Student-t for length and R_length; for planning time and time to goal, "
    "which are positive and skewed, a percentile bootstrap (2000 resamples, seed 0), whose "
    "ends are means of resampled runs and so never go below zero. Numbers: lengths in m "
    "with 3 decimals, times with 3 significant digits, rates in %. "
    "R_length = (L - L_ref) / L_ref over the runs where the run and its "
    "reference both solved the same problem (problem_key + seed); pairs = how many; "
    "shorter = pairs where the configuration's path is shorter than the reference's. "
    "R_length < 0: shorter than the reference. When the study ran the planner shortest (the "
    "true shortest path among the occupied squares), the excess over the shortest path = "
    "(L - L_shortest) / L_shortest pairs every solved run with shortest's on the same "
    "problem and seed."
)


def write_report(db_path: str | Path, out_dir: str | Path, reference: str | None = None,
                 params: Sequence[str] | None = None, *, dpi: int = 110,
                 embed_images: bool = True) -> dict[str, Path]:
    """Write the report of a study database into ``out_dir`` (created if needed).

    Parameters
    ----------
    db_path : path-like
        The study database of ``pathfuse bench``.
    out_dir : path-like
        Output folder.
    reference : str, optional
        R_length reference: a planner configuration name, or a planner with
        one configuration per run kind (default: the experiment's own
        reference, stored with each run).
    params : sequence of str, optional
        Parameters to plot against success rate and length (default: every
        swept parameter).
    dpi : int
        Resolution of the PNG figures.
    embed_images : bool
        Embed the figures in ``report.html`` as base64 (they are linked to
        the PNG files either way).

    Returns
    -------
    dict
        Name -> path of every file written (``report_md``, ``report_html``,
        ``summary_csv``, ``parameters_csv``, and one entry per figure).

    Raises
    ------
    ConfigError
        A bad database, reference or parameter name (one line).
    """
    return build_report(db_path, reference, params).write(out_dir, dpi=dpi,
                                                          embed_images=embed_images)


@dataclass
class StudyReport:
    """The numbers of a report (:func:`build_report`); :meth:`write` writes the files.

    ``rows`` are :func:`summary_rows`, ``parameter_rows`` :func:`parameter_rows`,
    ``r_length`` the run id -> R_length pairs, ``swept`` the plotted parameters.
    """

    study: Study
    reference: str | None
    reference_label: str
    r_length: dict[int, float]
    swept: dict[tuple[str, str], list[str]]
    rows: list[dict[str, Any]]
    parameter_rows: list[dict[str, Any]]

    def write(self, out_dir: str | Path, *, dpi: int = 110,
              embed_images: bool = True) -> dict[str, Path]:
        """Write the files (see :func:`write_report`)."""
        return _write(self, Path(out_dir), dpi, embed_images)


def build_report(db_path: str | Path, reference: str | None = None,
                 params: Sequence[str] | None = None) -> StudyReport:
    """Read a study and compute every table of its report (arguments as
    :func:`write_report`)."""
    study = load_study(db_path)
    rl = r_length_values(study, reference)
    swept = swept_parameters(study, params)
    return StudyReport(study, reference, _reference_label(study, reference), rl, swept,
                       summary_rows(study, reference, rl),
                       parameter_rows(study, swept, reference, rl))


def _write(rep: StudyReport, out: Path, dpi: int, embed_images: bool) -> dict[str, Path]:
    study, ref_label, swept = rep.study, rep.reference_label, rep.swept
    rows, prows = rep.rows, rep.parameter_rows
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{out}: cannot create the output folder ({exc.strerror})") from None
    files: dict[str, Path] = {
        "report_md": out / "report.md",
        "report_html": out / "report.html",
        "summary_csv": out / "summary.csv",
        "parameters_csv": out / "parameters.csv",
    }
    write_csv(files["summary_csv"], [{k: _csv_value(v) for k, v in r.items()} for r in rows])
    if prows:
        write_csv(files["parameters_csv"],
                  [{k: _csv_value(v) for k, v in r.items()} for r in prows])
    else:
        files["parameters_csv"].write_text(
            "scope,kind,planner,parameter,value,configs,runs\n", encoding="utf-8")

    sections = _map_sections(rep, out, dpi, files) + _parameter_sections(rep, out, dpi, files)

    head = _header(study, ref_label, swept)
    files["report_md"].write_text(_markdown(head, sections), encoding="utf-8")
    files["report_html"].write_text(_html(study, head, sections, out, embed_images),
                                    encoding="utf-8")
    return files


def _map_sections(rep: StudyReport, out: Path, dpi: int,
                  files: dict[str, Path]) -> list[_Section]:
    """A section per map entry (its table and box plots, added to ``files``), then one per
    kind with several entries, pooled."""
    study, rl, ref_label = rep.study, rep.r_length, rep.reference_label
    rows = rep.rows
    from pathfuse.viz import report as viz

    sections: list[_Section] = []
    names = _scope_names(study)
    used_slugs: set[str] = set()
    exp_ids = sorted({r["experimentid"] for r in study.runs})
    for eid in exp_ids:
        scope = names[eid]
        runs = [r for r in study.runs if r["experimentid"] == eid]
        kind = runs[0]["kind"]
        srows = [r for r in rows if r["scope"] == scope]
        slug = _slug(scope)
        if slug in used_slugs:
            slug = f"{slug}-{eid}"
        used_slugs.add(slug)
        cids = sorted({r["plannerid"] for r in runs})
        labels = [study.configs[c].name for c in cids]

        def values(key: str, cids: list[int] = cids, runs: list[dict[str, Any]] = runs,
                   scale: float = 1.0) -> list[np.ndarray]:
            return [np.array([scale * float(r[key]) for r in runs if r["plannerid"] == c
                              and r[key] is not None and r["status_name"] != "ERROR"
                              and (key == "time" or r["solved"])], dtype=float)
                    for c in cids]

        sec = _Section(f"{scope} ({kind}, {len(runs)} runs)",
                       text=f"Map entry `{study.experiments[eid].name}`.")
        sec.tables = _table(srows, [("configuration", "config")], kind == "dynamic")
        name = f"length_{slug}.png"
        viz.plot_boxes(labels, values("solution_length"), out / name,
                       xlabel="path length [m] (solved runs)", title=f"{scope}: path length",
                       dpi=dpi)
        files[f"length_{slug}"] = out / name
        sec.images.append((name, "Path length per configuration (solved runs)"))
        name = f"time_{slug}.png"
        viz.plot_boxes(labels, values("time", scale=1e3), out / name,
                       xlabel="planning time [ms]", title=f"{scope}: planning time", dpi=dpi,
                       log=True)
        files[f"time_{slug}"] = out / name
        sec.images.append((name, "Planning time per configuration (every run that did not "
                                 "raise)"))
        if kind == "dynamic":
            name = f"time_to_goal_{slug}.png"
            viz.plot_boxes(labels, values("time_to_goal"), out / name,
                           xlabel="time to goal [s] (reached)",
                           title=f"{scope}: time to goal", dpi=dpi)
            files[f"time_to_goal_{slug}"] = out / name
            sec.images.append((name, "Simulated time to goal (episodes that reached it)"))
        rvals = [np.array([100 * rl[r["id"]] for r in runs
                           if r["plannerid"] == c and r["id"] in rl]) for c in cids]
        if any(v.size for v in rvals):
            name = f"r_length_{slug}.png"
            viz.plot_boxes(labels, rvals, out / name,
                           xlabel="R_length = (L - L_ref) / L_ref [%]",
                           title=f"{scope}: R_length against {ref_label}", dpi=dpi, zero=True)
            files[f"r_length_{slug}"] = out / name
            sec.images.append((name, f"R_length against {ref_label} (paired runs)"))
        sections.append(sec)
    for scope, kind, _, pooled in _scopes(study):
        if not pooled:
            continue
        n_exp = len({r["experimentid"] for r in study.runs if r["kind"] == kind})
        if n_exp < 2:
            continue
        srows = [r for r in rows if r["scope"] == scope]
        sec = _Section(f"{scope}: every {kind} map entry pooled ({n_exp} entries)")
        sec.tables = _table(srows, [("configuration", "config")], kind == "dynamic")
        runs = [r for r in study.runs if r["kind"] == kind]
        cids = sorted({r["plannerid"] for r in runs})
        rvals = [np.array([100 * rl[r["id"]] for r in runs
                           if r["plannerid"] == c and r["id"] in rl]) for c in cids]
        if any(v.size for v in rvals):
            name = f"r_length_{_slug(scope)}_pooled.png"
            viz.plot_boxes([study.configs[c].name for c in cids], rvals, out / name,
                           xlabel="R_length = (L - L_ref) / L_ref [%]",
                           title=f"{scope}: R_length against {ref_label}", dpi=dpi, zero=True)
            files[f"r_length_{_slug(scope)}_pooled"] = out / name
            sec.images.append((name, f"R_length against {ref_label}, every entry pooled"))
        sections.append(sec)
    return sections


def _parameter_sections(rep: StudyReport, out: Path, dpi: int,
                        files: dict[str, Path]) -> list[_Section]:
    """The swept parameters: a section and a plot per parameter."""
    study = rep.study
    prows, swept = rep.parameter_rows, rep.swept
    from pathfuse.viz import report as viz

    sections: list[_Section] = []
    if prows:
        sections.append(_Section(
            "Swept parameters",
            text="For every parameter that takes several values among the configurations of "
                 "a planner (or the parameters chosen with --param): the configurations "
                 "sharing a value pooled over the other swept parameters, per map entry "
                 "(and every entry of a kind pooled when there are several).  The pooled "
                 "configurations ran on the same maps, so their runs are not independent and "
                 "the intervals are narrower than they should be; for a paired comparison "
                 "pick one configuration as --reference (R_length then pairs every run with "
                 "that configuration's run on the same problem and seed)."))
    for (kind, planner), plist in swept.items():
        n_exp = len({r["experimentid"] for r in study.runs if r["kind"] == kind})
        for p in plist:
            pr = [r for r in prows if r["kind"] == kind and r["planner"] == planner
                  and r["parameter"] == p]
            if not pr:
                continue
            tag = f"{planner}_{p}" if len(study.kinds) == 1 else f"{kind}_{planner}_{p}"
            name = f"param_{_slug(tag)}.png"
            exp_scopes = list(dict.fromkeys(r["scope"] for r in pr if not r["pooled"]))
            lines = {}
            for s in exp_scopes or [r["scope"] for r in pr[:1]]:
                lines[s] = [r for r in pr if r["scope"] == s]
            cfg_vals = [study.configs[c].params[p] for c in study.config_ids(kind)
                        if study.configs[c].planner == planner and p in study.configs[c].params]
            _, numeric = _sort_values(cfg_vals)
            viz.plot_parameter(p, lines, out / name, numeric=numeric,
                               title=f"{planner} ({kind}): {p}", dpi=dpi)
            files[f"param_{_slug(tag)}"] = out / name
            sec = _Section(f"{planner} ({kind}): parameter {p}", level=3,
                           text=f"Every configuration of {planner} with the same value of "
                                f"{p} pooled (over the other swept parameters).")
            shown = [r for r in pr if not r["pooled"] or n_exp > 1]
            sec.tables = _table(shown, [("scope", "scope"), (p, "value"),
                                       ("configs", "configs")], kind == "dynamic")
            sec.images.append((name, f"{p} against success rate (95% Wilson) and mean length "
                                     "(95% t)"))
            sections.append(sec)
    return sections


def _header(study: Study, ref_label: str, swept: Mapping[tuple[str, str], Sequence[str]]
            ) -> list[str]:
    n = len(study.runs)
    solved = sum(r["solved"] for r in study.runs)
    errors = sum(r["status_name"] == "ERROR" for r in study.runs)
    studies = sorted({e.name.rsplit("/", 1)[0] for e in study.experiments.values()
                      if "/" in e.name})
    lines = [
        f"Study database `{study.path}`"
        + (f" (experiment{'s' if len(studies) > 1 else ''}: {', '.join(studies)})"
           if studies else "") + ".",
        f"{n} runs: {solved} solved, {n - solved - errors} not solved, {errors} errors; "
        f"{_plural(len({r['experimentid'] for r in study.runs}), 'map entry', 'map entries')}, "
        f"{_plural(len(study.config_ids()), 'planner configuration')}.",
        f"R_length reference: {ref_label}.",
    ]
    if swept:
        lines.append("Swept parameters: " + "; ".join(
            f"{pl} ({k}): {', '.join(ps)}" for (k, pl), ps in swept.items()) + ".")
    if study.sessions:
        s0, s1 = study.sessions[0], study.sessions[-1]
        hosts = sorted({s["host"] for s in study.sessions if s["host"]})
        vers = sorted({s["pathfuse_version"] for s in study.sessions if s["pathfuse_version"]})
        lines.append(f"{len(study.sessions)} bench session(s) from {s0['started_at']} to "
                     f"{s1['finished_at'] or s1['started_at']} (last: {s1['state']}) on "
                     f"{', '.join(hosts) or '?'}, pathfuse {', '.join(vers) or '?'}.")
    return lines


def _plural(n: int, one: str, many: str | None = None) -> str:
    return f"{n} {one if n == 1 else (many or one + 's')}"


def _markdown(head: Sequence[str], sections: Sequence[_Section]) -> str:
    out = ["# pathfuse study report", "", *[f"{h}  " for h in head], "", _NOTES, ""]
    for s in sections:
        out += ["#" * s.level + " " + s.title, ""]
        if s.text:
            out += [s.text, ""]
        for t in s.tables:
            out += [markdown_table(t), ""]
        for name, cap in s.images:
            out += [f"![{cap}]({name})", ""]
    return "\n".join(out)


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em;
color:#222;max-width:110em}
h1{font-size:1.6em}h2{font-size:1.3em;margin-top:2em;border-bottom:1px solid #ccc}
h3{font-size:1.1em;margin-top:1.5em}
table{border-collapse:collapse;font-size:0.82em;margin:0.8em 0;display:block;overflow-x:auto}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right;white-space:nowrap}
th{background:#f0f0f0;position:sticky;top:0}
td:first-child,th:first-child{text-align:left}
tr:nth-child(even) td{background:#fafafa}
figure{display:inline-block;margin:0.5em 1em 0.5em 0;vertical-align:top}
figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:0.8em;color:#555}
.notes{font-size:0.85em;color:#444;max-width:60em}
"""


def _html(study: Study, head: Sequence[str], sections: Sequence[_Section], out: Path,
          embed: bool) -> str:
    e = html.escape

    def md_inline(text: str) -> str:
        return re.sub(r"`([^`]*)`", r"<code>\1</code>", e(text))

    parts = ["<!DOCTYPE html>", "<html lang='en'><head><meta charset='utf-8'>",
             f"<title>pathfuse report: {e(study.path.name)}</title>",
             f"<style>{_CSS}</style></head><body>",
             "<h1>pathfuse study report</h1>"]
    parts += [f"<p>{md_inline(h)}</p>" for h in head]
    parts.append(f"<p class='notes'>{e(_NOTES)}</p>")
    toc = [f"<li><a href='#s{i}'>{e(s.title)}</a></li>" for i, s in enumerate(sections)]
    parts.append("<ul>" + "".join(toc) + "</ul>")
    for i, s in enumerate(sections):
        parts.append(f"<h{s.level} id='s{i}'>{e(s.title)}</h{s.level}>")
        if s.text:
            parts.append(f"<p>{md_inline(s.text)}</p>")
        for t in s.tables:
            rows = ["<tr>" + "".join(f"<th>{e(c)}</th>" for c in t[0]) + "</tr>"]
            rows += ["<tr>" + "".join(f"<td>{e(str(c))}</td>" for c in r) + "</tr>"
                     for r in t[1:]]
            parts.append("<table>" + "".join(rows) + "</table>")
        for name, cap in s.images:
            if embed:
                data = base64.b64encode((out / name).read_bytes()).decode("ascii")
                src = f"data:image/png;base64,{data}"
            else:
                src = e(name)
            parts.append(f"<figure><a href='{e(name)}'><img src='{src}' alt='{e(cap)}' "
                         f"title='{e(name)}'></a><figcaption>{e(cap)} "
                         f"(<a href='{e(name)}'>{e(name)}</a>)</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)

