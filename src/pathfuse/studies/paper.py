"""Reproduction of the paper's experiment (Section IV, Tables I and II, Fig. 3): a preset study.

The paper ran its five planners once, on one random 15 m map.  :func:`run_paper`
builds an experiment of the study engine (:mod:`pathfuse.bench`) that runs
them on ``n_seeds`` seeded paper-setup maps (15 m x 15 m, 1 m cells, start
(1, 1), goal (11, 11), 50 random obstacle cells, K_att 40, K_rep 5, rho_0 2 m),
runs it into a result store (resumable: the same command finishes an
interrupted run) and reads every run back, failures included;
:func:`write_paper_outputs` writes the tables (one map, and statistics over
all maps), the Fig. 3 comparison and a box plot of R_length.

Failures are never dropped: a planner that fails on a map counts against its
success rate, and R_length / R_time statistics are over the maps where *both*
fusion and the reference succeeded, with that count printed beside them.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.bench.summary import group_stats, median, value_stats
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import r_ratio
from pathfuse.result import ConfigError
from pathfuse.stats import markdown_table as _md
from pathfuse.stats import mean_ci, wilson_ci
from pathfuse.stats import write_csv as _write_csv

__all__ = [
    "PAPER_PLANNERS",
    "PAPER_LABELS",
    "PaperConfig",
    "PaperRun",
    "paper_experiment",
    "run_paper",
    "summary_rows",
    "write_paper_outputs",
    "mean_ci",
    "wilson_ci",
]

#: Column order of the paper's tables (the fusion planner last, as in Table I).
PAPER_PLANNERS = ("astar", "apf", "ref6", "ref7", "fusion")
PAPER_LABELS = {
    "astar": "A-star",
    "apf": "Artificial potential field method",
    "ref6": "Reference method [6]",
    "ref7": "Reference method [7]",
    "fusion": "Fusion algorithm",
}
#: Table I/II values printed in the paper (one map, MATLAB on an i7-8750H).
PAPER_TABLE = {
    "length_m": {"astar": 14.7279, "apf": 15.0897, "ref6": 15.8056, "ref7": 15.8767,
                 "fusion": 14.2182},
    "time_s": {"astar": 2.1280, "apf": 0.7380, "ref6": 2.6650, "ref7": 2.3910, "fusion": 3.3180},
}
_APF_PLANNERS = {"apf", "fusion", "ref6", "ref7"}


@dataclass(frozen=True)
class PaperConfig:
    """Settings of the reproduction.

    Attributes
    ----------
    n_seeds : int
        Number of maps (seeds ``first_seed .. first_seed + n_seeds - 1``).
    first_seed : int
        Seed of the first map.
    figure_seed : int
        The map drawn in Fig. 3 and reported in the one-map tables.
    planners : tuple of str
        Registry names; ``fusion`` must be among them for R_length / R_time.
    k_att, k_rep, rho0_m : float
        The paper's potential-field constants, given to every APF-based planner.
    step_m : float
        One step length (metres) for all four stepping planners (apf, ref6,
        ref7, fusion), so that their lengths and times compare like for like.
        The planners' own defaults differ (fusion steps 0.5 cells by default,
        the others 0.1); 0.1 m is the finer, more faithful choice.
    params : dict
        Extra per-planner parameters, ``{name: {key: value}}``.
    """

    n_seeds: int = 100
    first_seed: int = 0
    figure_seed: int = 0
    planners: tuple[str, ...] = PAPER_PLANNERS
    k_att: float = 40.0
    k_rep: float = 5.0
    rho0_m: float = 2.0
    step_m: float = 0.1
    params: dict[str, dict[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.n_seeds, int) or self.n_seeds < 1:
            raise ConfigError(f"n_seeds: must be a positive integer, got {self.n_seeds!r}")
        if "fusion" not in self.planners:
            raise ConfigError("planners: must include 'fusion' (R_length is relative to it)")

    def planner_params(self, name: str) -> dict[str, Any]:
        base: dict[str, Any] = {}
        if name in _APF_PLANNERS:
            base = {"k_att": self.k_att, "k_rep": self.k_rep, "rho0_m": self.rho0_m,
                    "step_m": self.step_m}
        base.update(self.params.get(name, {}))
        return base


@dataclass
class PaperRun:
    """All records of a reproduction: one dict per (seed, planner), seed-major."""

    config: PaperConfig
    records: list[dict[str, Any]]
    wall_s: float
    results: dict[tuple[int, str], Any] = field(default_factory=dict, repr=False)
    summary: Any = None
    """The :class:`~pathfuse.bench.runner.SweepSummary` of the engine run."""

    def by_planner(self, name: str) -> list[dict[str, Any]]:
        return [r for r in self.records if r["planner"] == name]

    def seeds(self) -> list[int]:
        return sorted({r["seed"] for r in self.records})


def paper_experiment(config: PaperConfig | None = None, base_dir: str | os.PathLike[str] = "."
                     ) -> Any:
    """The experiment of the study engine that the reproduction runs.

    One map entry (the paper's map family, a fresh map per seed, the paper's
    start and goal), every planner of ``config`` with the paper's constants
    and one common step, no R_length reference (the reproduction pairs each
    planner with the fusion itself), no limits beyond each planner's own
    finite defaults.
    """
    from pathfuse.bench.experiment import experiment_from_dict

    cfg = config or PaperConfig()
    doc = {
        "name": "paper",
        "description": "Ju, Luo and Yan, Sec. IV: five planners on seeded 15 m paper maps",
        "seeds": {"start": cfg.first_seed, "count": cfg.n_seeds},
        "reference": None,
        "maps": [{"name": "paper", "map": "paper"}],
        "planners": [{"name": n, "params": cfg.planner_params(n)} if cfg.planner_params(n)
                     else n for n in cfg.planners],
    }
    return experiment_from_dict(doc, Path(base_dir) / "paper.yaml", check_maps=False)


def run_paper(
    config: PaperConfig | None = None,
    progress: bool | None = False,
    workers: int | None = 1,
    db_path: str | os.PathLike[str] | None = None,
    stream: Any = None,
) -> PaperRun:
    """Run every planner of ``config`` on every seeded paper map with the study engine.

    Each record holds: seed, planner, status, success, collision_free,
    length_m (the partial path's on failure), time_s (planning wall clock, A*
    included where used, numba compilation excluded), min_clearance_m,
    smoothness_rad, steps, expansions, iterations.  ``db_path`` keeps the
    runs (default: an in-memory store); runs already stored there are not
    run again.  ``workers`` > 1 runs a process pool (the engine's).
    """
    from pathfuse.bench.runner import run_experiment
    from pathfuse.bench.store import ResultStore

    cfg = config or PaperConfig()
    exp = paper_experiment(cfg)
    specs = exp.expand()
    store = ResultStore(":memory:" if db_path is None else db_path)
    try:
        summary = run_experiment(exp, store, workers=workers, progress=progress,
                                 stream=stream, label="paper")
        stored = store.rows_by_key([r.key for r in specs])
    finally:
        store.close()
    order = {name: i for i, name in enumerate(cfg.planners)}
    records = [_record(r.seed, r.planner, stored[r.key]) for r in
               sorted(specs, key=lambda r: (r.seed, order[r.planner]))]
    return PaperRun(cfg, records, summary.wall_s, _figure_plans(cfg), summary)


def _record(seed: int, planner: str, row: dict[str, Any]) -> dict[str, Any]:
    solved = bool(row["solved"])
    length = row["solution_length"] if solved else row["path_length"]
    clear = row["solution_clearance"]
    return {
        "seed": seed,
        "planner": planner,
        "status": row["status_name"],
        "success": solved,
        "collision_free": bool(row["collision_free"]),
        "length_m": float(length or 0.0),
        "time_s": float(row["time"] or 0.0),
        "min_clearance_m": math.inf if clear is None else float(clear),
        "smoothness_rad": float(row["solution_smoothness"] or 0.0),
        "steps": int(row["steps"] or 0),
        "expansions": int(row["expansions"] or 0),
        "iterations": int(row["iterations"] or 0),
        "id": int(row["id"]),
    }


def _figure_plans(cfg: PaperConfig) -> dict[tuple[int, str], Any]:
    """The plans of the figure's map, planned again here for Fig. 3 (deterministic)."""
    from pathfuse.api import plan


    grid = paper_map(cfg.figure_seed)
    return {(cfg.figure_seed, name): plan(grid, PAPER_START, PAPER_GOAL, planner=name,
                                          **cfg.planner_params(name))
            for name in cfg.planners}


# --------------------------------------------------------------------------- statistics
def _paired(run: PaperRun, ref: str, key: str) -> np.ndarray:
    """R = (fusion - ref) / ref on the seeds where both succeeded."""
    fus = {r["seed"]: r for r in run.by_planner("fusion")}
    out = []
    for r in run.by_planner(ref):
        f = fus.get(r["seed"])
        if f and f["success"] and r["success"] and r[key] > 0:
            out.append(r_ratio(f[key], r[key]))
    return np.asarray(out, dtype=float)


def _as_run(r: dict[str, Any]) -> dict[str, Any]:
    """A record in the form :func:`~pathfuse.bench.summary.group_stats` reads."""
    return {"id": r["id"], "solved": r["success"], "status_name": r["status"],
            "collision_free": r["collision_free"], "collisions": 0,
            "solution_length": r["length_m"] if r["success"] else None, "time": r["time_s"],
            "time_to_goal": None}


def summary_rows(run: PaperRun) -> list[dict[str, Any]]:
    """Per-planner statistics over all maps (the rows of the statistics tables)."""
    fus = {r["seed"]: r for r in run.by_planner("fusion")}
    rows = []
    for name in run.config.planners:
        recs = run.by_planner(name)
        rl: dict[int, float] = {}
        if name != "fusion":
            for r in recs:
                f = fus.get(r["seed"])
                if f and f["success"] and r["success"] and r["length_m"] > 0:
                    rl[r["id"]] = r_ratio(f["length_m"], r["length_m"])
        g = group_stats([_as_run(r) for r in recs], rl)
        row: dict[str, Any] = {
            "planner": name,
            "maps": g["runs"],
            "successes": g["solved"],
            "success_rate": g["success_rate"], "success_ci_low": g["success_ci_low"],
            "success_ci_high": g["success_ci_high"],
            "collision_free_successes": g["collision_free"],
            "failures": g["failures"].replace("; ", ", "),
            "length_mean_m": g["length_mean_m"], "length_ci_low_m": g["length_ci_low_m"],
            "length_ci_high_m": g["length_ci_high_m"], "length_median_m": g["length_median_m"],
            "time_mean_s": g["time_mean_s"], "time_ci_low_s": g["time_ci_low_s"],
            "time_ci_high_s": g["time_ci_high_s"], "time_median_s": g["time_median_s"],
        }
        for key, label in (("length_m", "r_length"), ("time_s", "r_time")):
            vals = [] if name == "fusion" else list(_paired(run, name, key))
            v = value_stats(vals, label)
            row.update({
                f"{label}_mean": v[f"{label}_mean"], f"{label}_ci_low": v[f"{label}_ci_low"],
                f"{label}_ci_high": v[f"{label}_ci_high"],
                f"{label}_median": median(vals),
                f"{label}_pairs": len(vals),
                f"{label}_fusion_shorter": int(sum(x < 0 for x in vals)),
            })
        rows.append(row)
    return rows


# --------------------------------------------------------------------------- tables
def _pct(v: float) -> str:
    return "n/a" if not np.isfinite(v) else f"{100 * v:+.2f}%"


def _one_map_tables(run: PaperRun) -> tuple[str, list[list[str]]]:
    seed = run.config.figure_seed
    names = run.config.planners
    recs = {r["planner"]: r for r in run.records if r["seed"] == seed}
    fus = recs.get("fusion")
    head = [""] + [PAPER_LABELS.get(n, n) for n in names]

    def cell_len(n: str) -> str:
        r = recs[n]
        if r["success"]:
            return f"{r['length_m']:.4f} (m)"
        return f"{r['status']} ({r['length_m']:.4f} m partial)"

    def r_of(n: str, key: str) -> str:
        if n == "fusion":
            return "-"
        r = recs[n]
        if not (r["success"] and fus and fus["success"]):
            return "n/a (a planner failed)"
        return _pct(r_ratio(fus[key], r[key]))

    t1 = [head, ["Path length"] + [cell_len(n) for n in names],
          ["R_length"] + [r_of(n, "length_m") for n in names]]
    t2 = [head, ["Processing time"] + [f"{recs[n]['time_s'] * 1e3:.3f} (ms)" for n in names],
          ["R_time"] + [r_of(n, "time_s") for n in names]]
    md = (
        f"### Table I (one map, seed {seed}): path length\n\n{_md(t1)}\n\n"
        f"### Table II (one map, seed {seed}): processing time\n\n{_md(t2)}\n"
    )
    csv_rows = [["table", "row"] + [n for n in names]]
    for tname, t in (("I", t1), ("II", t2)):
        for row in t[1:]:
            csv_rows.append([tname] + row)
    return md, csv_rows


def _stats_tables(run: PaperRun, rows: list[dict[str, Any]]) -> str:
    names = run.config.planners
    by = {r["planner"]: r for r in rows}
    n = run.config.n_seeds
    head = [""] + [PAPER_LABELS.get(k, k) for k in names]

    def ci(r, a, lo, hi, scale=1.0, fmt="{:.4f}"):
        if not np.isfinite(r[a]):
            return "n/a"
        lo_s, hi_s = fmt.format(r[lo] * scale), fmt.format(r[hi] * scale)
        return f"{fmt.format(r[a] * scale)} [{lo_s}, {hi_s}]"

    def rr(r, label):
        if r["planner"] == "fusion":
            return "-"
        if r[f"{label}_pairs"] == 0:
            return "n/a"
        return (f"{_pct(r[f'{label}_mean'])} [{_pct(r[f'{label}_ci_low'])}, "
                f"{_pct(r[f'{label}_ci_high'])}] (n={r[f'{label}_pairs']})")

    t1 = [
        head,
        ["Success rate [95% CI]"] + [
            f"{by[k]['successes']}/{by[k]['maps']} = {100 * by[k]['success_rate']:.1f}% "
            f"[{100 * by[k]['success_ci_low']:.1f}, {100 * by[k]['success_ci_high']:.1f}]"
            for k in names],
        ["Failures by status"] + [by[k]["failures"] or "none" for k in names],
        ["Path length mean [95% CI] (m)"] + [
            ci(by[k], "length_mean_m", "length_ci_low_m", "length_ci_high_m") for k in names],
        ["Path length median (m)"] + [f"{by[k]['length_median_m']:.4f}" for k in names],
        ["R_length mean [95% CI]"] + [rr(by[k], "r_length") for k in names],
        ["R_length median"] + [
            "-" if k == "fusion" else _pct(by[k]["r_length_median"]) for k in names],
        ["Maps where fusion is shorter"] + [
            "-" if k == "fusion"
            else f"{by[k]['r_length_fusion_shorter']}/{by[k]['r_length_pairs']}"
            for k in names],
    ]
    t2 = [
        head,
        ["Time mean [95% CI] (ms)"] + [
            ci(by[k], "time_mean_s", "time_ci_low_s", "time_ci_high_s", 1e3, "{:.3f}")
            for k in names],
        ["Time median (ms)"] + [f"{1e3 * by[k]['time_median_s']:.3f}" for k in names],
        ["R_time mean [95% CI]"] + [rr(by[k], "r_time") for k in names],
        ["R_time median"] + [
            "-" if k == "fusion" else _pct(by[k]["r_time_median"]) for k in names],
    ]
    return (
        f"### Table I over {n} maps (seeds {run.config.first_seed}.."
        f"{run.config.first_seed + n - 1}): path length\n\n{_md(t1)}\n\n"
        "Length statistics are over each planner's successful runs; R_length pairs only maps "
        "where both fusion and the reference succeeded (n = number of such maps). "
        "R < 0 means the fusion path is shorter (paper eq. 10).\n\n"
        f"### Table II over {n} maps: processing time\n\n{_md(t2)}\n\n"
        "Times are wall-clock planning times in this process (A* included for the planners "
        "that use it; numba compilation excluded by a warm-up call before timing).  The "
        "interval of a mean time is a 95% percentile bootstrap (2000 resamples, seed 0), which "
        "stays above zero; the other intervals are Student-t (Wilson for rates).\n"
    )


def write_paper_outputs(run: PaperRun, out_dir: str | Path) -> dict[str, Path]:
    """Write tables (Markdown + CSV), Fig. 3 and the R_length box plot into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = summary_rows(run)
    one_md, one_csv = _one_map_tables(run)
    files = {
        "runs_csv": out / "runs.csv",
        "summary_csv": out / "summary.csv",
        "one_map_csv": out / "tables_one_map.csv",
        "tables_md": out / "tables.md",
        "fig3_png": out / "fig3_paths.png",
        "r_length_png": out / "r_length_boxplot.png",
    }
    _write_csv(files["runs_csv"], [{k: v for k, v in r.items() if k != "id"}
                                   for r in run.records])
    _write_csv(files["summary_csv"], rows)
    _write_csv(files["one_map_csv"], one_csv)
    paper_md = _md([
        [""] + [PAPER_LABELS[k] for k in PAPER_PLANNERS],
        ["Path length (paper)"] + [f"{PAPER_TABLE['length_m'][k]:.4f} (m)" for k in PAPER_PLANNERS],
        ["Processing time (paper, MATLAB)"] + [f"{PAPER_TABLE['time_s'][k]:.4f} (s)"
                                               for k in PAPER_PLANNERS],
    ])
    text = (
        "# Reproduction of Ju, Luo and Yan, Tables I and II\n\n"
        f"{run.config.n_seeds} paper-setup maps (15 m x 15 m, 1 m cells, start {PAPER_START}, "
        f"goal {PAPER_GOAL}, 50 random obstacle cells), K_att {run.config.k_att:g}, "
        f"K_rep {run.config.k_rep:g}, rho_0 {run.config.rho0_m:g} m, "
        f"one step of {run.config.step_m:g} m for every stepping planner; "
        f"{len(run.records)} runs in {run.wall_s:.2f} s "
        f"({len(run.records) / max(run.wall_s, 1e-9):.0f} runs/s).\n\n"
        f"## The paper's values (one unpublished map)\n\n{paper_md}\n\n"
        f"## One map\n\n{one_md}\n## All maps\n\n{_stats_tables(run, rows)}"
    )
    files["tables_md"].write_text(text)
    from pathfuse.viz.paper import plot_fig3, plot_r_length

    seed = run.config.figure_seed
    plot_fig3({name: res for (sd, name), res in run.results.items() if sd == seed}, seed,
              PAPER_LABELS, files["fig3_png"])
    plot_r_length({k: _paired(run, k, "length_m") for k in run.config.planners
                   if k != "fusion"}, run.config.n_seeds, PAPER_LABELS, files["r_length_png"])
    return files
