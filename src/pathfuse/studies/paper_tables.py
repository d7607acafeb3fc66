"""Statistics and tables of the paper reproduction (:mod:`pathfuse.studies.paper`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.bench.summary import group_stats, median, value_stats
from pathfuse.generate import PAPER_GOAL, PAPER_START
from pathfuse.metrics import r_ratio
from pathfuse.stats import counted
from pathfuse.stats import markdown_table as _md
from pathfuse.stats import write_csv as _write_csv
from pathfuse.studies.paper_config import PAPER_LABELS, PAPER_PLANNERS, PAPER_TABLE, PaperRun

__all__ = ["summary_rows", "write_paper_outputs"]


# --------------------------------------------------------------------------- statistics
def _paired(run: PaperRun, fusion: str, ref: str, key: str) -> np.ndarray:
    """R = (fusion - ref) / ref on the seeds where both succeeded."""
    fus = {r["seed"]: r for r in run.by_planner(fusion)}
    out = []
    for r in run.by_planner(ref):
        f = fus.get(r["seed"])
        if f and f["success"] and r["success"] and r[key] > 0:
            out.append(r_ratio(f[key], r[key]))
    return np.asarray(out, dtype=float)


def excess(run: PaperRun, column: str) -> np.ndarray:
    """``(L - L_shortest) / L_shortest`` of ``column`` on the maps where both succeeded
    (empty without a ``shortest`` column)."""
    low = {r["seed"]: r for r in run.by_planner("shortest")}
    out = []
    for r in run.by_planner(column):
        s = low.get(r["seed"])
        if s and s["success"] and r["success"] and s["length_m"] > 0:
            out.append(r_ratio(r["length_m"], s["length_m"]))
    return np.asarray(out, dtype=float)


def _as_run(r: dict[str, Any]) -> dict[str, Any]:
    """A record in the form :func:`~pathfuse.bench.summary.group_stats` reads."""
    return {"id": r["id"], "solved": r["success"], "status_name": r["status"],
            "collision_free": r["collision_free"], "collisions": 0,
            "solution_length": r["length_m"] if r["success"] else None, "time": r["time_s"],
            "time_to_goal": None}


def summary_rows(run: PaperRun, variant: str | None = None) -> list[dict[str, Any]]:
    """Per-column statistics over all maps: the rows of each variant's tables.

    One row per (variant, column) of :meth:`PaperConfig.table_columns`, in
    table order (only ``variant``'s when given).  R_length and R_time pair the
    column with the fusion of the same variant; ``excess_*`` pairs it with
    ``shortest``.
    """
    cfg = run.config
    rows = []
    for v in cfg.variants if variant is None else (variant,):
        fusion = cfg.column("fusion", v)
        fus = {r["seed"]: r for r in run.by_planner(fusion)}
        for col in cfg.table_columns(v):
            recs = run.by_planner(col)
            rl: dict[int, float] = {}
            if col != fusion:
                for r in recs:
                    f = fus.get(r["seed"])
                    if f and f["success"] and r["success"] and r["length_m"] > 0:
                        rl[r["id"]] = r_ratio(f["length_m"], r["length_m"])
            g = group_stats([_as_run(r) for r in recs], rl)
            row: dict[str, Any] = {
                "variant": v,
                "planner": col,
                "is_fusion": col == fusion,
                "maps": g["runs"],
                "successes": g["solved"],
                "success_rate": g["success_rate"], "success_ci_low": g["success_ci_low"],
                "success_ci_high": g["success_ci_high"],
                "collision_free_successes": g["collision_free"],
                "failures": g["failures"].replace("; ", ", "),
                "length_mean_m": g["length_mean_m"], "length_ci_low_m": g["length_ci_low_m"],
                "length_ci_high_m": g["length_ci_high_m"],
                "length_median_m": g["length_median_m"],
                "time_mean_s": g["time_mean_s"], "time_ci_low_s": g["time_ci_low_s"],
                "time_ci_high_s": g["time_ci_high_s"], "time_median_s": g["time_median_s"],
            }
            for key, label in (("length_m", "r_length"), ("time_s", "r_time")):
                vals = [] if col == fusion else list(_paired(run, fusion, col, key))
                st = value_stats(vals, label)
                row.update({
                    f"{label}_mean": st[f"{label}_mean"], f"{label}_ci_low": st[f"{label}_ci_low"],
                    f"{label}_ci_high": st[f"{label}_ci_high"],
                    f"{label}_median": median(vals),
                    f"{label}_pairs": len(vals),
                    f"{label}_fusion_shorter": int(sum(x < 0 for x in vals)),
                })
            ex = [] if col == "shortest" else list(excess(run, col))
            st = value_stats(ex, "excess")
            row.update({"excess_mean": st["excess_mean"], "excess_ci_low": st["excess_ci_low"],
                        "excess_ci_high": st["excess_ci_high"],
                        "excess_median": st["excess_median"], "excess_pairs": len(ex)})
            rows.append(row)
    return rows


# --------------------------------------------------------------------------- tables
def _pct(v: float) -> str:
    return "n/a" if not np.isfinite(v) else f"{100 * v:+.2f}%"


def _one_map_tables(run: PaperRun) -> tuple[str, list[list[str]]]:
    cfg = run.config
    seed = cfg.figure_seed
    v = cfg.variants[0]
    names = cfg.table_columns(v)
    fusion = cfg.column("fusion", v)
    recs = {r["planner"]: r for r in run.records if r["seed"] == seed}
    fus = recs.get(fusion)
    head = [""] + [cfg.label(n) for n in names]

    def cell_len(n: str) -> str:
        r = recs[n]
        if r["success"]:
            return f"{r['length_m']:.4f} (m)"
        return f"{r['status']} ({r['length_m']:.4f} m partial)"

    def r_of(n: str, key: str) -> str:
        if n == fusion:
            return "-"
        r = recs[n]
        if not (r["success"] and fus and fus["success"]):
            return "n/a (a planner failed)"
        return _pct(r_ratio(fus[key], r[key]))

    def ex_of(n: str) -> str:
        low = recs.get("shortest")
        r = recs[n]
        if n == "shortest" or low is None:
            return "-"
        if not (r["success"] and low["success"]):
            return "n/a (a planner failed)"
        return _pct(r_ratio(r["length_m"], low["length_m"]))

    t1 = [head, ["Path length"] + [cell_len(n) for n in names],
          ["R_length"] + [r_of(n, "length_m") for n in names]]
    if "shortest" in names:
        t1.append(["Excess over the shortest path"] + [ex_of(n) for n in names])
    t2 = [head, ["Processing time"] + [f"{recs[n]['time_s'] * 1e3:.3f} (ms)" for n in names],
          ["R_time"] + [r_of(n, "time_s") for n in names]]
    md = (
        f"### Table I (one map, seed {seed}, {v} variant): path length\n\n{_md(t1)}\n\n"
        f"### Table II (one map, seed {seed}, {v} variant): processing time\n\n{_md(t2)}\n"
    )
    csv_rows = [["table", "row"] + list(names)]
    for tname, t in (("I", t1), ("II", t2)):
        for row in t[1:]:
            csv_rows.append([tname] + row)
    return md, csv_rows


_VARIANT_TEXT = {
    "pathfuse": "pathfuse variant: the planners with pathfuse's defaults (escape, progress rule, "
                "safe step, stall test)",
    "paper": "paper variant: apf, ref6, ref7 and fusion as printed (eq. 8 ahead = paper-x, no "
             "escape, the full step along the force - a step touching an obstacle is a "
             "COLLISION - and no stall test)",
}


def _stats_tables(run: PaperRun, rows: list[dict[str, Any]], variant: str) -> str:
    cfg = run.config
    names = cfg.table_columns(variant)
    by = {r["planner"]: r for r in rows if r["variant"] == variant}
    n = cfg.n_seeds
    head = [""] + [cfg.label(k) for k in names]

    def ci(r, a, lo, hi, scale=1.0, fmt="{:.4f}"):
        if not np.isfinite(r[a]):
            return "n/a"
        lo_s, hi_s = fmt.format(r[lo] * scale), fmt.format(r[hi] * scale)
        return f"{fmt.format(r[a] * scale)} [{lo_s}, {hi_s}]"

    def rr(r, label):
        if r["is_fusion"]:
            return "-"
        if r[f"{label}_pairs"] == 0:
            return "n/a"
        return (f"{_pct(r[f'{label}_mean'])} [{_pct(r[f'{label}_ci_low'])}, "
                f"{_pct(r[f'{label}_ci_high'])}] (n={r[f'{label}_pairs']})")

    def ex(r):
        if r["planner"] == "shortest" or r["excess_pairs"] == 0:
            return "-"
        return (f"{_pct(r['excess_mean'])} [{_pct(r['excess_ci_low'])}, "
                f"{_pct(r['excess_ci_high'])}] (n={r['excess_pairs']})")

    t1 = [
        head,
        ["Success rate [95% CI]"] + [
            f"{by[k]['successes']}/{by[k]['maps']} = {100 * by[k]['success_rate']:.1f}% "
            f"[{100 * by[k]['success_ci_low']:.1f}, {100 * by[k]['success_ci_high']:.1f}]"
            for k in names],
        ["Failures by status"] + [by[k]["failures"] or "none" for k in names],
        ["Path length mean [95% CI] (m)"] + [
            ci(by[k], "length_mean_m", "length_ci_low_m", "length_ci_high_m") for k in names],
        ["Path length median (m)"] + [
            "n/a" if not by[k]["successes"] else f"{by[k]['length_median_m']:.4f}"
            for k in names],
        ["R_length mean [95% CI]"] + [rr(by[k], "r_length") for k in names],
        ["R_length median"] + [
            "-" if by[k]["is_fusion"] else _pct(by[k]["r_length_median"]) for k in names],
        ["Maps where fusion is shorter"] + [
            "-" if by[k]["is_fusion"]
            else f"{by[k]['r_length_fusion_shorter']}/{by[k]['r_length_pairs']}"
            for k in names],
    ]
    if "shortest" in names:
        t1 += [
            ["Excess over the shortest path mean [95% CI]"] + [ex(by[k]) for k in names],
            ["Excess over the shortest path median"] + [
                "-" if k == "shortest" or by[k]["excess_pairs"] == 0
                else _pct(by[k]["excess_median"]) for k in names],
        ]
    t2 = [
        head,
        ["Time mean [95% CI] (ms)"] + [
            ci(by[k], "time_mean_s", "time_ci_low_s", "time_ci_high_s", 1e3, "{:.3f}")
            for k in names],
        ["Time median (ms)"] + [f"{1e3 * by[k]['time_median_s']:.3f}" for k in names],
        ["R_time mean [95% CI]"] + [rr(by[k], "r_time") for k in names],
        ["R_time median"] + [
            "-" if by[k]["is_fusion"] else _pct(by[k]["r_time_median"]) for k in names],
    ]
    return (
        f"### Table I over {counted(n, 'map')} (seeds {cfg.first_seed}.."
        f"{cfg.first_seed + n - 1}), {variant} variant: path length\n\n"
        f"{_VARIANT_TEXT.get(variant, variant)}.\n\n{_md(t1)}\n\n"
        "Length statistics are over each planner's successful runs; R_length pairs only maps "
        "where both fusion and the reference succeeded (n = number of such maps). "
        "R < 0 means the fusion path is shorter (paper eq. 10). The excess over the shortest "
        "path, (L - L_shortest) / L_shortest, pairs each planner with the true shortest path "
        "on the maps where both succeeded.\n\n"
        f"### Table II over {counted(n, 'map')}, {variant} variant: processing time\n\n"
        f"{_md(t2)}\n\n"
        "Times are wall-clock planning times in this process (A* included for the planners "
        "that use it; numba compilation excluded by a warm-up call before timing).  The "
        "interval of a mean time is a 95% percentile bootstrap (2000 resamples, seed 0), which "
        "stays above zero; the other intervals are Student-t (Wilson for rates).\n"
    )


def write_paper_outputs(run: PaperRun, out_dir: str | Path) -> dict[str, Path]:
    """Write tables (Markdown + CSV), Fig. 3 and the R_length box plot into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cfg = run.config
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
    rule = "with corner cutting" if cfg.corner_cutting else "without corner cutting"
    stats = "\n".join(_stats_tables(run, rows, v) for v in cfg.variants)
    text = (
        "# Reproduction of Ju, Luo and Yan, Tables I and II\n\n"
        f"{counted(cfg.n_seeds, 'paper-setup map')} (15 m x 15 m, 1 m cells, start {PAPER_START}, "
        f"goal {PAPER_GOAL}, 50 random obstacle cells), K_att {cfg.k_att:g}, "
        f"K_rep {cfg.k_rep:g}, rho_0 {cfg.rho0_m:g} m, "
        f"one step of {cfg.step_m:g} m for every stepping planner, the A* reference {rule}; "
        f"{counted(len(run.records), 'run')} in {run.wall_s:.2f} s "
        f"({len(run.records) / max(run.wall_s, 1e-9):.0f} runs/s).\n\n"
        f"## The paper's values (one unpublished map)\n\n{paper_md}\n\n"
        f"## One map\n\n{one_md}\n## All maps\n\n{stats}"
    )
    files["tables_md"].write_text(text)
    from pathfuse.viz.paper import plot_fig3, plot_r_length

    seed = cfg.figure_seed
    v = cfg.variants[0]
    fusion = cfg.column("fusion", v)
    shown = {name: run.results[(seed, cfg.column(name, v))]
             for name in (*cfg.planners, *cfg.references)
             if (seed, cfg.column(name, v)) in run.results}
    plot_fig3(shown, seed, PAPER_LABELS, files["fig3_png"])
    plot_r_length({k: _paired(run, fusion, k, "length_m") for k in cfg.table_columns(v)
                   if k != fusion}, cfg.n_seeds, PAPER_LABELS, files["r_length_png"])
    return files
