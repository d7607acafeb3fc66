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

Variants (``PaperConfig.variants``):

``"pathfuse"``
    The planners with pathfuse's defaults (the escape, the ``progress`` rule
    of "ahead", the safe step that slides along walls, the stall test).
``"paper"``
    The four stepping planners as printed (:data:`PAPER_VARIANT`): eq. 8
    (``ahead="paper-x"``), no escape, the full step along the force (a step
    that touches an obstacle is a ``COLLISION``, counted) and no stall test
    (the loop stops only at the goal or the move cap).  A* is the same in
    both.

Every variant's table also holds the any-angle references
(``PaperConfig.references``: A* with line-of-sight smoothing, Theta*) and
``shortest``, the true shortest path, against which every planner's *excess*
``(L - L_shortest) / L_shortest`` is given (paired by map).  With
``corner_cutting=True`` the A* column cuts corners (as the paper's A* very
likely did: its 14.7279 m is 9 sqrt(2) + 2, the corner-cutting length).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.stats import mean_ci, wilson_ci
from pathfuse.studies.paper_config import (
    PAPER_LABELS,
    PAPER_PLANNERS,
    PAPER_TABLE,
    PAPER_VARIANT,
    REFERENCES,
    VARIANTS,
    PaperConfig,
    PaperRun,
)
from pathfuse.studies.paper_tables import summary_rows, write_paper_outputs

__all__ = [
    "PAPER_PLANNERS",
    "PAPER_LABELS",
    "PAPER_TABLE",
    "PAPER_VARIANT",
    "REFERENCES",
    "VARIANTS",
    "PaperConfig",
    "PaperRun",
    "paper_experiment",
    "run_paper",
    "summary_rows",
    "write_paper_outputs",
    "mean_ci",
    "wilson_ci",
]

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
        "planners": [_entry(cfg, col, name, v) for col, name, v in cfg.columns()],
    }
    return experiment_from_dict(doc, Path(base_dir) / "paper.yaml", check_maps=False)


def _entry(cfg: PaperConfig, col: str, name: str, variant: str) -> Any:
    params = cfg.planner_params(name, variant)
    if col == name and not params:
        return name
    entry: dict[str, Any] = {"name": name, "params": params}
    if col != name:
        entry["label"] = col
    return entry


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
    order = {col: i for i, (col, _, _) in enumerate(cfg.columns())}
    records = [_record(r.seed, r.config, stored[r.key]) for r in
               sorted(specs, key=lambda r: (r.seed, order[r.config]))]
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
    v = cfg.variants[0]
    return {(cfg.figure_seed, cfg.column(name, v)):
            plan(grid, PAPER_START, PAPER_GOAL, planner=name, **cfg.planner_params(name, v))
            for name in (*cfg.planners, *cfg.references)}
