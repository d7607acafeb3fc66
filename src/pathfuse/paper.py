"""Reproduction of the paper's experiment (Section IV, Tables I and II, Fig. 3).

The paper ran its five planners once, on one random 15 m map.  :func:`run_paper`
runs them on ``n_seeds`` seeded paper-setup maps (15 m x 15 m, 1 m cells,
start (1, 1), goal (11, 11), 50 random obstacle cells, K_att 40, K_rep 5,
rho_0 2 m) and keeps every run, failures included; :func:`write_paper_outputs`
writes the tables (one map, and statistics over all maps), the Fig. 3
comparison and a box plot of R_length.

Failures are never dropped: a planner that fails on a map counts against its
success rate, and R_length / R_time statistics are over the maps where *both*
fusion and the reference succeeded, with that count printed beside them.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.api import plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import evaluate, r_ratio
from pathfuse.result import ConfigError
from pathfuse.stats import markdown_table as _md
from pathfuse.stats import mean_ci, wilson_ci
from pathfuse.stats import write_csv as _write_csv

__all__ = [
    "PAPER_PLANNERS",
    "PAPER_LABELS",
    "PaperConfig",
    "PaperRun",
    "run_paper",
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
            raise ConfigError(f"n_seeds must be a positive integer, got {self.n_seeds!r}")
        if "fusion" not in self.planners:
            raise ConfigError("planners must include 'fusion' (R_length is relative to it)")

    def planner_params(self, name: str) -> dict[str, Any]:
        base: dict[str, Any] = {}
        if name in _APF_PLANNERS:
            base = {"k_att": self.k_att, "k_rep": self.k_rep, "rho0_m": self.rho0_m,
                    "step_m": self.step_m}
        base.update(self.params.get(name, {}))
        return base


@dataclass
class PaperRun:
    """All records of a reproduction: one dict per (seed, planner)."""

    config: PaperConfig
    records: list[dict[str, Any]]
    wall_s: float
    results: dict[tuple[int, str], Any] = field(default_factory=dict, repr=False)

    def by_planner(self, name: str) -> list[dict[str, Any]]:
        return [r for r in self.records if r["planner"] == name]

    def seeds(self) -> list[int]:
        return sorted({r["seed"] for r in self.records})


def run_paper(
    config: PaperConfig | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> PaperRun:
    """Run every planner of ``config`` on every seeded paper map.

    Each record holds: seed, planner, status, success, collision_free,
    length_m, time_s (planning wall clock, A* included where used, numba
    compilation excluded), min_clearance_m, smoothness_rad, steps,
    expansions, iterations.  ``progress(done, total)`` is called per map.
    """
    cfg = config or PaperConfig()
    seeds = range(cfg.first_seed, cfg.first_seed + cfg.n_seeds)
    records: list[dict[str, Any]] = []
    keep: dict[tuple[int, str], Any] = {}
    t0 = time.perf_counter()
    for i, seed in enumerate(seeds):
        grid = paper_map(seed)
        for name in cfg.planners:
            res = plan(grid, PAPER_START, PAPER_GOAL, planner=name, **cfg.planner_params(name))
            m = evaluate(grid, res)
            records.append({
                "seed": seed,
                "planner": name,
                "status": res.status.name,
                "success": bool(res.success),
                "collision_free": bool(m["collision_free"]),
                "length_m": float(res.length),
                "time_s": float(res.time_s),
                "min_clearance_m": float(m["min_clearance_m"]),
                "smoothness_rad": float(m["smoothness_rad"]),
                "steps": int(m["steps"]),
                "expansions": int(res.expansions),
                "iterations": int(res.iterations),
            })
            if seed == cfg.figure_seed:
                keep[(seed, name)] = res
        if progress is not None:
            progress(i + 1, cfg.n_seeds)
    return PaperRun(cfg, records, time.perf_counter() - t0, keep)


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


def summary_rows(run: PaperRun) -> list[dict[str, Any]]:
    """Per-planner statistics over all maps (the rows of the statistics tables)."""
    rows = []
    for name in run.config.planners:
        recs = run.by_planner(name)
        n = len(recs)
        ok = [r for r in recs if r["success"]]
        cf = sum(r["success"] and r["collision_free"] for r in recs)
        lengths = [r["length_m"] for r in ok]
        times = [r["time_s"] for r in recs]
        sr = wilson_ci(len(ok), n)
        lm = mean_ci(lengths)
        tm = mean_ci(times)
        row: dict[str, Any] = {
            "planner": name,
            "maps": n,
            "successes": len(ok),
            "success_rate": sr[0], "success_ci_low": sr[1], "success_ci_high": sr[2],
            "collision_free_successes": cf,
            "failures": ", ".join(
                f"{s}:{sum(r['status'] == s for r in recs)}"
                for s in sorted({r["status"] for r in recs if not r["success"]})
            ),
            "length_mean_m": lm[0], "length_ci_low_m": lm[1], "length_ci_high_m": lm[2],
            "length_median_m": float(np.median(lengths)) if lengths else math.nan,
            "time_mean_s": tm[0], "time_ci_low_s": tm[1], "time_ci_high_s": tm[2],
            "time_median_s": float(np.median(times)) if times else math.nan,
        }
        for key, label in (("length_m", "r_length"), ("time_s", "r_time")):
            if name == "fusion":
                row.update({f"{label}_mean": math.nan, f"{label}_ci_low": math.nan,
                            f"{label}_ci_high": math.nan, f"{label}_median": math.nan,
                            f"{label}_pairs": 0, f"{label}_fusion_shorter": 0})
                continue
            vals = _paired(run, name, key)
            m = mean_ci(vals)
            row.update({
                f"{label}_mean": m[0], f"{label}_ci_low": m[1], f"{label}_ci_high": m[2],
                f"{label}_median": float(np.median(vals)) if vals.size else math.nan,
                f"{label}_pairs": int(vals.size),
                f"{label}_fusion_shorter": int((vals < 0).sum()),
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
        "that use it; numba compilation excluded by a warm-up call before timing).\n"
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
    _write_csv(files["runs_csv"], run.records)
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

    plot_fig3(run, files["fig3_png"])
    plot_r_length(run, {k: _paired(run, k, "length_m") for k in run.config.planners
                        if k != "fusion"}, files["r_length_png"])
    return files
