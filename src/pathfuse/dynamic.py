"""The dynamic benchmark: online planners among moving obstacles.

The paper's claim is that A* alone cannot handle dynamic obstacles while the
A*-APF fusion can.  :func:`run_dynamic` measures it: for every number of
moving discs ``K`` in ``config.moving`` it draws the same ``n_seeds``
scenarios with :func:`pathfuse.world.generate.generate_scenarios` (paper map
family, start (1, 1), goal (11, 11), discs aimed across the robot's route,
deterministic in ``config.seed``; scenario ``i`` sits on the same map for
every ``K``) and runs every online planner through each of them with
:func:`pathfuse.world.simulate`.  Nothing is dropped: every episode is a row
of the per-episode CSV, whatever its status.

:func:`summary_rows` reduces them per (``K``, planner): the counts of each
status (they add up to the number of episodes), the success / collision /
timeout / local-minimum / no-path rates with 95 % Wilson intervals, and path
length and time to goal over the successful episodes (mean with a 95 %
Student-t interval, median).  :func:`write_dynamic_outputs` writes them as
Markdown and CSV with a plot of the success rate against ``K``.

Examples
--------
>>> cfg = DynamicConfig(n_seeds=2, moving=(0, 1), planners=("fusion", "astar"))
>>> run = run_dynamic(cfg)
>>> len(run.records)                       # 2 disc counts x 2 scenarios x 2 planners
8
>>> [(r["moving"], r["planner"], r["episodes"]) for r in summary_rows(run)][:2]
[(0, 'fusion', 2), (0, 'astar', 2)]
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.result import ConfigError, PathfuseError
from pathfuse.stats import markdown_table, mean_ci, wilson_ci, write_csv

__all__ = [
    "DynamicConfig",
    "DynamicRun",
    "OUTCOMES",
    "run_dynamic",
    "summary_rows",
    "success_pivot",
    "paired_rows",
    "markdown_report",
    "write_dynamic_outputs",
]

#: Episode statuses in table order (``EpisodeStatus`` names).
OUTCOMES = ("SUCCESS", "COLLISION", "TIMEOUT", "LOCAL_MINIMUM", "NO_PATH")
_OUTCOME_KEYS = {"SUCCESS": "reached", "COLLISION": "collision", "TIMEOUT": "timeout",
                 "LOCAL_MINIMUM": "local_minimum", "NO_PATH": "no_path"}
_OUTCOME_LABELS = {"SUCCESS": "success", "COLLISION": "collision", "TIMEOUT": "timeout",
                   "LOCAL_MINIMUM": "local min", "NO_PATH": "no path"}


def _is_int(v: Any) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, np.integer))


@dataclass(frozen=True)
class DynamicConfig:
    """What to run.

    Attributes
    ----------
    n_seeds : int
        Scenarios per number of moving discs.
    moving : tuple of int
        Numbers of moving discs (each >= 0; duplicates are dropped, order kept).
    speed_range : (float, float)
        Disc speeds are drawn uniformly from it (m/s, ``0 < low <= high``).
    planners : tuple of str
        Online planner names; empty = every registered online planner.
    seed : int
        Master seed of :func:`~pathfuse.world.generate.generate_scenarios`.
    params : mapping
        Per-planner parameter overrides, ``{name: {key: value}}``.

    Examples
    --------
    >>> DynamicConfig(moving=(4, 0, 4)).moving
    (4, 0)
    >>> DynamicConfig(speed_range=(0.8, 0.3))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: speed_range: expected (low, high) with 0 < low <= high ...
    """

    n_seeds: int = 50
    moving: tuple[int, ...] = (0, 2, 4, 8)
    speed_range: tuple[float, float] = (0.3, 0.8)
    planners: tuple[str, ...] = ()
    seed: int = 0
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from pathfuse.planners.registry import REGISTRY, get_planner, make_params, planner_names

        def online_planner_names() -> list[str]:
            return [n for n in planner_names() if REGISTRY[n].online]

        def get_online_planner(name: str) -> Any:
            return get_planner(name)

        def make_online_params(spec: Any, params: Any, key: str) -> Any:
            return make_params(spec, params, key=key)

        if not _is_int(self.n_seeds) or self.n_seeds < 1:
            raise ConfigError(f"n_seeds: expected a positive integer, got {self.n_seeds!r}")
        if not _is_int(self.seed) or self.seed < 0:
            raise ConfigError(f"seed: expected an integer >= 0, got {self.seed!r}")
        try:
            moving = tuple(self.moving)
        except TypeError:
            raise ConfigError(f"moving: expected a list of integers >= 0, "
                              f"got {self.moving!r}") from None
        if not moving or not all(_is_int(k) and k >= 0 for k in moving):
            raise ConfigError(f"moving: expected a list of integers >= 0, got {self.moving!r}")
        object.__setattr__(self, "moving", tuple(dict.fromkeys(int(k) for k in moving)))
        try:
            lo, hi = (float(v) for v in self.speed_range)
            ok = math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ConfigError(f"speed_range: expected (low, high) with 0 < low <= high m/s, "
                              f"got {self.speed_range!r}")
        object.__setattr__(self, "speed_range", (lo, hi))
        if isinstance(self.planners, str):
            raise ConfigError(f"planners: expected a list of names, got {self.planners!r}")
        canonical = []
        for n in tuple(self.planners) or tuple(online_planner_names()):
            try:
                canonical.append(get_online_planner(n).name)  # older names -> the planner's
            except ConfigError as exc:
                raise ConfigError(f"planners: {exc}") from None
        names = tuple(dict.fromkeys(canonical))
        object.__setattr__(self, "planners", names)
        if not isinstance(self.params, Mapping):
            raise ConfigError(f"params: expected {{planner: {{key: value}}}}, "
                              f"got {self.params!r}")
        for n, p in self.params.items():
            if n not in names:
                raise ConfigError(f"params.{n}: not among the planners run "
                                  f"({', '.join(names)})")
            if not isinstance(p, Mapping):
                raise ConfigError(f"params.{n}: expected a mapping of parameters, got {p!r}")
            make_online_params(get_online_planner(n), p, key=f"params.{n}")

    def choice(self, name: str) -> dict[str, Any]:
        """The ``planner`` argument of :func:`pathfuse.simulate` for ``name``."""
        return {"name": name, "params": dict(self.params.get(name, {}))}

    @property
    def n_episodes(self) -> int:
        return self.n_seeds * len(self.moving) * len(self.planners)


@dataclass
class DynamicRun:
    """Every episode of a benchmark: one record (dict) per (moving, scenario, planner)."""

    config: DynamicConfig
    records: list[dict[str, Any]]
    wall_s: float
    workers: int = 1

    @property
    def episodes_per_s(self) -> float:
        return len(self.records) / max(self.wall_s, 1e-9)


def _record(moving: int, index: int, sc: Any, ep: Any, wall_s: float) -> dict[str, Any]:
    return {
        "moving": int(moving),
        "index": int(index),
        "scenario": sc.name,
        "map": sc.grid.name,
        "planner": ep.planner,
        "status": ep.status.name,
        "reached": bool(ep.reached),
        "path_length_m": float(ep.path_length_m),
        "time_to_goal_s": None if ep.time_to_goal_s is None else float(ep.time_to_goal_s),
        "sim_time_s": float(ep.times[-1]),
        "n_ticks": int(ep.n_ticks),
        "min_distance_m": float(ep.min_distance_m),
        "min_obstacle_distance_m": float(ep.min_obstacle_distance_m),
        "min_static_clearance_m": float(ep.min_static_clearance_m),
        "collision_with": "" if ep.collision_with is None else str(ep.collision_with),
        "mean_plan_time_s": float(ep.mean_plan_time_s),
        "max_plan_time_s": float(ep.plan_times_s.max()) if ep.plan_times_s.size else 0.0,
        "setup_time_s": float(ep.setup_time_s),
        "wall_s": float(wall_s),
        "message": ep.message,
    }


def _run_task(task: tuple[int, int, Any, tuple[str, ...], dict[str, Any]]
              ) -> list[dict[str, Any]]:
    """One scenario through every planner (what a worker process runs)."""
    from pathfuse.world import simulate

    moving, index, sc, planners, choices = task
    out = []
    for name in planners:
        t0 = time.perf_counter()
        ep = simulate(sc, planner=choices[name])
        out.append(_record(moving, index, sc, ep, time.perf_counter() - t0))
    return out


def _worker_init() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business


def _run_pool(tasks: list[Any], workers: int
              ) -> Iterator[tuple[tuple[int, int], list[dict[str, Any]]]]:
    """Yield ``((moving, index), records)`` as worker processes finish scenarios."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    if "forkserver" in mp.get_all_start_methods():
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["pathfuse.dynamic", "pathfuse.world"])
    else:  # pragma: no cover - Windows
        ctx = mp.get_context("spawn")
    from pathfuse.bench.runner import _main_without_file

    with _main_without_file():
        ex = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_init)
        try:
            futs = {ex.submit(_run_task, t): (t[0], t[1]) for t in tasks}
            for f in as_completed(futs):
                yield futs[f], f.result()
        except BrokenProcessPool as exc:
            raise PathfuseError(f"a worker process died ({exc}); run with workers=1 to see "
                                "the problem in this process") from None
        finally:
            ex.shutdown(wait=True, cancel_futures=True)


def run_dynamic(
    config: DynamicConfig | None = None,
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
) -> DynamicRun:
    """Run the benchmark.

    Parameters
    ----------
    config : DynamicConfig, optional
        Default ``DynamicConfig()``.
    progress : callable, optional
        ``progress(done, total)`` after every scenario (``done`` episodes).
    workers : int
        Processes; 1 runs in this process.  The records (timings aside) do
        not depend on it, and come back in the same order: by ``moving`` as
        configured, then scenario index, then planner.

    Returns
    -------
    DynamicRun
    """
    from pathfuse.world.generate import generate_scenarios

    cfg = config or DynamicConfig()
    if not _is_int(workers) or workers < 1:
        raise ConfigError(f"workers: expected a positive integer, got {workers!r}")
    choices = {n: cfg.choice(n) for n in cfg.planners}
    t0 = time.perf_counter()
    tasks = []
    for k in cfg.moving:
        scs = generate_scenarios(cfg.n_seeds, moving=k, speed_range=cfg.speed_range,
                                 seed=cfg.seed, name=f"dyn-k{k}")
        tasks += [(k, i, sc, cfg.planners, choices) for i, sc in enumerate(scs)]
    total = cfg.n_episodes
    results: dict[tuple[int, int], list[dict[str, Any]]] = {}
    done = 0
    if workers == 1 or len(tasks) <= 1:
        for task in tasks:
            results[(task[0], task[1])] = _run_task(task)
            done += len(cfg.planners)
            if progress is not None:
                progress(done, total)
    else:
        for key, recs in _run_pool(tasks, min(workers, len(tasks))):
            results[key] = recs
            done += len(cfg.planners)
            if progress is not None:
                progress(done, total)
    records = [r for t in tasks for r in results[(t[0], t[1])]]
    return DynamicRun(cfg, records, time.perf_counter() - t0, workers=int(workers))


# --------------------------------------------------------------------------- statistics
def summary_rows(run: DynamicRun) -> list[dict[str, Any]]:
    """One row per (moving, planner): status counts and rates with 95 % Wilson intervals,
    path length and time to goal over the successful episodes (mean, 95 % CI, median),
    and the mean planning time per tick."""
    rows = []
    for k in run.config.moving:
        for name in run.config.planners:
            recs = [r for r in run.records if r["moving"] == k and r["planner"] == name]
            n = len(recs)
            row: dict[str, Any] = {"moving": k, "planner": name, "episodes": n}
            for st in OUTCOMES:
                row[_OUTCOME_KEYS[st]] = sum(r["status"] == st for r in recs)
            for st in OUTCOMES:
                key = _OUTCOME_KEYS[st]
                p, lo, hi = wilson_ci(row[key], n)
                row.update({f"{key}_rate": p, f"{key}_ci_low": lo, f"{key}_ci_high": hi})
            ok = [r for r in recs if r["status"] == "SUCCESS"]
            for col, label, unit in (("path_length_m", "path_length", "m"),
                                     ("time_to_goal_s", "time_to_goal", "s")):
                vals = [float(r[col]) for r in ok]
                m, lo, hi = mean_ci(vals)
                row.update({f"{label}_mean_{unit}": m, f"{label}_ci_low_{unit}": lo,
                            f"{label}_ci_high_{unit}": hi,
                            f"{label}_median_{unit}": float(np.median(vals)) if vals
                            else math.nan})
            row["mean_plan_time_us"] = 1e6 * float(np.mean([r["mean_plan_time_s"]
                                                           for r in recs])) if recs else math.nan
            rows.append(row)
    return rows


def paired_rows(run: DynamicRun, reference: str = "fusion") -> list[dict[str, Any]]:
    """Paired success comparison of ``reference`` against every other planner.

    Every planner runs the same scenarios, so per number of discs the
    scenarios split into both reached / only ``reference`` reached / only the
    other reached / neither.  ``p_value`` is the exact two-sided McNemar test
    on the discordant pairs (binomial, p = 1/2): small when one planner wins
    the scenarios they disagree on more often than chance would.  Empty when
    ``reference`` was not run.

    >>> cfg = DynamicConfig(n_seeds=2, moving=(1,), planners=("fusion", "astar"))
    >>> [sorted(r)[:4] for r in paired_rows(run_dynamic(cfg))]
    [['both', 'moving', 'neither', 'only_other']]
    """
    from scipy.stats import binomtest

    cfg = run.config
    if reference not in cfg.planners:
        return []
    ok = {(r["moving"], r["index"], r["planner"]): r["status"] == "SUCCESS"
          for r in run.records}
    rows = []
    for k in cfg.moving:
        for name in cfg.planners:
            if name == reference:
                continue
            c = {"both": 0, "only_reference": 0, "only_other": 0, "neither": 0}
            for i in range(cfg.n_seeds):
                a, b = ok[(k, i, reference)], ok[(k, i, name)]
                c["both" if a and b else "only_reference" if a else "only_other" if b
                  else "neither"] += 1
            d = c["only_reference"] + c["only_other"]
            p = 1.0 if d == 0 else float(binomtest(c["only_reference"], d, 0.5).pvalue)
            rows.append({"moving": k, "reference": reference, "other": name, **c,
                         "p_value": p})
    return rows


def success_pivot(rows: Sequence[Mapping[str, Any]], key: str = "reached") -> list[list[str]]:
    """A planner x moving table of ``key`` rates (``"reached"``, ``"collision"``, ...)."""
    moving: list[int] = []
    planners: list[str] = []
    for r in rows:
        if r["moving"] not in moving:
            moving.append(r["moving"])
        if r["planner"] not in planners:
            planners.append(r["planner"])
    by = {(r["moving"], r["planner"]): r for r in rows}
    table = [["planner"] + [f"{k} discs" for k in moving]]
    for name in planners:
        cells = []
        for k in moving:
            r = by.get((k, name))
            cells.append("-" if r is None else _rate_cell(r, key, short=True))
        table.append([name] + cells)
    return table


def _rate_cell(r: Mapping[str, Any], key: str, short: bool = False) -> str:
    n, c = r["episodes"], r[key]
    p, lo, hi = r[f"{key}_rate"], r[f"{key}_ci_low"], r[f"{key}_ci_high"]
    if not n:
        return "n/a"
    if short:
        return f"{100 * p:.0f}% [{100 * lo:.0f}, {100 * hi:.0f}]"
    return f"{c}/{n} = {100 * p:.0f}% [{100 * lo:.0f}, {100 * hi:.0f}]"


def _stat_cell(r: Mapping[str, Any], label: str, unit: str, fmt: str = "{:.2f}") -> str:
    m = r[f"{label}_mean_{unit}"]
    if not np.isfinite(m):
        return "n/a"
    lo, hi = r[f"{label}_ci_low_{unit}"], r[f"{label}_ci_high_{unit}"]
    return f"{fmt.format(m)} [{fmt.format(lo)}, {fmt.format(hi)}]"


def _median_cell(r: Mapping[str, Any], label: str, unit: str) -> str:
    v = r[f"{label}_median_{unit}"]
    return "n/a" if not np.isfinite(v) else f"{v:.2f}"


def markdown_report(run: DynamicRun, rows: Sequence[Mapping[str, Any]] | None = None) -> str:
    """The benchmark as Markdown: setup, a success-rate pivot and the full table."""
    rows = summary_rows(run) if rows is None else rows
    cfg = run.config
    lo, hi = cfg.speed_range
    head = ["discs", "planner", "success [95% CI]", "collision", "timeout", "local min",
            "no path", "path length (m) mean [95% CI]", "median", "time to goal (s) mean "
            "[95% CI]", "median", "plan time/tick (µs)"]
    table = [head]
    for r in rows:
        table.append([
            str(r["moving"]), r["planner"], _rate_cell(r, "reached"),
            _rate_cell(r, "collision"), _rate_cell(r, "timeout"),
            _rate_cell(r, "local_minimum"), _rate_cell(r, "no_path"),
            _stat_cell(r, "path_length", "m"), _median_cell(r, "path_length", "m"),
            _stat_cell(r, "time_to_goal", "s"), _median_cell(r, "time_to_goal", "s"),
            "n/a" if not np.isfinite(r["mean_plan_time_us"]) else f"{r['mean_plan_time_us']:.0f}",
        ])
    params = "; ".join(f"{n}: {dict(p)}" for n, p in cfg.params.items() if p) or "defaults"
    return (
        "# Dynamic benchmark: online planners among moving obstacles\n\n"
        f"{cfg.n_seeds} generated scenarios per number of moving discs "
        f"({', '.join(map(str, cfg.moving))}), seed {cfg.seed}: paper map family "
        "(15 m x 15 m, 50 random cells, a new map per scenario, the same maps for every "
        "disc count), start (1, 1), goal (11, 11), robot radius 0.2 m at 1 m/s with 3 m "
        f"sensing, discs of radius 0.2-0.4 m at {lo:g}-{hi:g} m/s aimed across the route, "
        "dt 0.1 s, time limit 60 s.  Planner parameters: "
        f"{params}.\n\n"
        f"{len(run.records)} episodes in {run.wall_s:.2f} s "
        f"({run.episodes_per_s:.1f} episodes/s, {run.workers} worker"
        f"{'s' if run.workers != 1 else ''}).\n\n"
        "## Success rate [95% Wilson CI]\n\n"
        f"{markdown_table(success_pivot(rows))}\n\n"
        "## Collision rate [95% Wilson CI]\n\n"
        f"{markdown_table(success_pivot(rows, 'collision'))}\n\n"
        f"{_paired_md(run)}"
        "## All outcomes\n\n"
        f"{markdown_table(table)}\n\n"
        "Counts per row add up to the episodes run (nothing dropped); rates carry 95% Wilson "
        "score intervals.  Path length and time to goal are over each planner's successful "
        "episodes only (so planners are compared on different subsets), with a 95% Student-t "
        "interval of the mean.  Plan time is the wall-clock time of the planner's per-tick "
        "decision, averaged over ticks and then over episodes.\n"
    )


def _paired_md(run: DynamicRun) -> str:
    rows = paired_rows(run)
    if not rows:
        return ""
    table = [["discs", "fusion vs", "both reached", "only fusion", "only the other",
              "neither", "McNemar p (exact)"]]
    for r in rows:
        table.append([str(r["moving"]), r["other"], str(r["both"]), str(r["only_reference"]),
                      str(r["only_other"]), str(r["neither"]), f"{r['p_value']:.2g}"])
    return (
        "## Fusion against each planner, scenario by scenario\n\n"
        "Every planner ran the same scenarios; \"only fusion\" counts the scenarios the fusion "
        "reached and the other did not.  The p-value is the exact two-sided McNemar test on "
        "those discordant scenarios (no correction for the many comparisons).\n\n"
        f"{markdown_table(table)}\n\n")


def _csv_value(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, float) and math.isnan(v):
        return ""
    return v


def write_dynamic_outputs(run: DynamicRun, out_dir: str | Path) -> dict[str, Path]:
    """Write ``dynamic.md``, ``summary.csv``, ``episodes.csv``, ``paired.csv`` (when the
    fusion was run: :func:`paired_rows`) and ``success_vs_moving.png``.

    Empty CSV cells are missing values (no successful episode, no time to goal).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = summary_rows(run)
    files = {
        "report_md": out / "dynamic.md",
        "summary_csv": out / "summary.csv",
        "episodes_csv": out / "episodes.csv",
        "success_png": out / "success_vs_moving.png",
    }
    files["report_md"].write_text(markdown_report(run, rows), encoding="utf-8")
    write_csv(files["summary_csv"], [{k: _csv_value(v) for k, v in r.items()} for r in rows])
    write_csv(files["episodes_csv"],
              [{k: _csv_value(v) for k, v in r.items()} for r in run.records])
    paired = paired_rows(run)
    if paired:
        files["paired_csv"] = out / "paired.csv"
        write_csv(files["paired_csv"], paired)
    from pathfuse.viz.animate import plot_success_vs_moving

    cfg = run.config
    plot_success_vs_moving(
        rows, files["success_png"],
        title=f"{cfg.n_seeds} scenarios per point, discs at {cfg.speed_range[0]:g}-"
              f"{cfg.speed_range[1]:g} m/s (seed {cfg.seed})")
    return files
