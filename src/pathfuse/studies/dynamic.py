"""The dynamic benchmark: planners online among moving obstacles (a preset study).

The paper's claim is that A* alone cannot handle dynamic obstacles while the
A*-APF fusion can.  :func:`run_dynamic` measures it: for every number of
moving discs ``K`` in ``config.moving`` it draws the same ``n_seeds``
scenarios with :func:`pathfuse.world.generate.generate_scenarios` (paper map
family, start (1, 1), goal (11, 11), discs aimed across the robot's route,
deterministic in ``config.seed``; scenario ``i`` sits on the same map for
every ``K``) and runs every planner through each of them with
:func:`pathfuse.world.simulate`, as an experiment of the study engine
(:func:`dynamic_experiment`; the engine's worker pool, result store and
progress bar).  Nothing is dropped: every episode is a row of the
per-episode CSV, whatever its status.

:func:`summary_rows` reduces them per (``K``, planner): the counts of each
status (they add up to the number of episodes), the success / collision /
timeout / local-minimum / no-path rates with 95 % Wilson intervals, the
collisions split into the robot's fault and hits while it stood still, path
length and time to goal over the successful episodes (mean with a 95 %
interval: Student-t for the length, seeded bootstrap for the time; median),
the 5th and 50th percentiles of the minimum static clearance and disc gap
over the successful episodes, and the share of commands the shield replaced.
:func:`write_dynamic_outputs` writes them as
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

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.bench.summary import group_stats, value_stats
from pathfuse.result import ConfigError, Status
from pathfuse.stats import counted, markdown_table, write_csv
from pathfuse.studies.barn_report import (
    SOCIAL_GAP_M,
    fault_cell,
    fault_stats,
    percentile_cell,
    percentile_stats,
    shield_cell,
    shield_stats,
    social_stats,
)
from pathfuse.validate import short as _shown

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

_ORDER = (Status.SUCCESS, Status.COLLISION, Status.TIMEOUT, Status.LOCAL_MINIMUM,
          Status.NO_PATH)
#: Episode statuses in table order (:class:`~pathfuse.result.Status` names); a summary
#: row counts each under its :attr:`~pathfuse.result.Status.key` ("reached", ...).
OUTCOMES = tuple(s.name for s in _ORDER)


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
    robot : mapping
        A scenario ``robot:`` block for every scenario (e.g. ``{"model":
        "diff-drive"}``); empty: the generator's default holonomic robot
        (radius 0.2 m, 1 m/s, 3 m sensing).

    Examples
    --------
    >>> DynamicConfig(moving=(4, 0, 4)).moving
    (4, 0)
    >>> DynamicConfig(speed_range=(0.8, 0.3))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: speed_range: must be (low, high) with 0 < low <= high ...
    """

    n_seeds: int = 50
    moving: tuple[int, ...] = (0, 2, 4, 8)
    speed_range: tuple[float, float] = (0.3, 0.8)
    planners: tuple[str, ...] = ()
    seed: int = 0
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    robot: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from pathfuse.planners.registry import REGISTRY, get_planner, make_params, planner_names

        def online_planner_names() -> list[str]:
            return [n for n in planner_names() if REGISTRY[n].online]

        def get_online_planner(name: str) -> Any:
            return get_planner(name)

        def make_online_params(spec: Any, params: Any, key: str) -> Any:
            return make_params(spec, params, key=key)

        if not _is_int(self.n_seeds) or self.n_seeds < 1:
            raise ConfigError(f"n_seeds: must be a positive integer, got {_shown(self.n_seeds)}")
        if not _is_int(self.seed) or self.seed < 0:
            raise ConfigError(f"seed: must be an integer >= 0, got {_shown(self.seed)}")
        try:
            moving = tuple(self.moving)
        except TypeError:
            raise ConfigError(f"moving: must be a list of integers >= 0, "
                              f"got {_shown(self.moving)}") from None
        if not moving or not all(_is_int(k) and k >= 0 for k in moving):
            raise ConfigError(f"moving: must be a list of integers >= 0, got"
                              f" {_shown(self.moving)}")
        object.__setattr__(self, "moving", tuple(dict.fromkeys(int(k) for k in moving)))
        import inspect

        from pathfuse.world.generate import check_body_ticks, generate_scenarios

        defaults = inspect.signature(generate_scenarios).parameters
        check_body_ticks(defaults["time_limit"].default, defaults["dt"].default,
                         max(self.moving))
        try:
            lo, hi = (float(v) for v in self.speed_range)
            ok = math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ConfigError(f"speed_range: must be (low, high) with 0 < low <= high m/s, "
                              f"got {_shown(self.speed_range)}")
        object.__setattr__(self, "speed_range", (lo, hi))
        if isinstance(self.planners, str):
            raise ConfigError(f"planners: must be a list of names, got {_shown(self.planners)}")
        canonical = []
        for n in tuple(self.planners) or tuple(online_planner_names()):
            try:
                canonical.append(get_online_planner(n).name)  # older names -> the planner's
            except ConfigError as exc:
                raise ConfigError(f"planners: {exc}") from None
        names = tuple(dict.fromkeys(canonical))
        object.__setattr__(self, "planners", names)
        if not isinstance(self.params, Mapping):
            raise ConfigError(f"params: must be {{planner: {{key: value}}}}, "
                              f"got {_shown(self.params)}")
        for n, p in self.params.items():
            if n not in names:
                raise ConfigError(f"params.{n}: not among the planners run "
                                  f"({', '.join(names)})")
            if not isinstance(p, Mapping):
                raise ConfigError(f"params.{n}: must be a mapping of parameters, got {_shown(p)}")
            make_online_params(get_online_planner(n), p, key=f"params.{n}")
        if not isinstance(self.robot, Mapping):
            raise ConfigError(f"robot: must be a robot block {{key: value}}, got {self.robot!r}")
        from pathfuse.robot import RobotModel

        RobotModel.from_dict(dict(self.robot))
        object.__setattr__(self, "robot", dict(self.robot))

    def robot_label(self) -> str:
        """The robot in words, for reports."""
        from pathfuse.robot import RobotModel

        rb = RobotModel.from_dict(dict(self.robot))
        text = (f"robot radius {rb.radius_m:g} m at {rb.max_speed_mps:g} m/s with "
                f"{rb.sensing_radius_m:g} m sensing, {rb.kind}")
        if rb.is_diff_drive:
            text += (f" (acceleration {rb.max_accel_mps2:g} m/s^2, yaw rate "
                     f"{rb.max_yaw_rate_radps:g} rad/s, yaw acceleration "
                     f"{rb.max_yaw_accel_radps2:g} rad/s^2)")
        if rb.clearance_m:
            text += f", safety margin {rb.clearance_m:g} m"
        return text

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


def dynamic_experiment(config: DynamicConfig | None = None,
                       base_dir: str | os.PathLike[str] = ".") -> Any:
    """The experiment of the study engine that the benchmark runs.

    One map entry per number of discs ``K`` (named ``kK``): the family
    :func:`~pathfuse.world.generate.generate_scenarios` draws with the master
    seed ``config.seed``, scenario ``i`` for the run seed ``i`` (the same maps
    for every ``K``); every planner of ``config`` with its parameters.
    """
    from pathfuse.bench.experiment import experiment_from_dict

    cfg = config or DynamicConfig()
    lo, hi = cfg.speed_range
    doc = {
        "name": "dynamic",
        "description": "planners among moving discs on the paper map family",
        "seeds": cfg.n_seeds,
        "maps": [{"name": f"k{k}",
                  "dynamic": {"generate": {"moving": k, "speed_range": [lo, hi],
                                           "name": f"dyn-k{k}",
                                           **({"robot": dict(cfg.robot)} if cfg.robot
                                              else {})},
                              "family_seed": cfg.seed}} for k in cfg.moving],
        "planners": [{"name": n, "params": dict(cfg.params.get(n, {})), "kinds": ["dynamic"]}
                     if cfg.params.get(n) else {"name": n, "kinds": ["dynamic"]}
                     for n in cfg.planners],
    }
    return experiment_from_dict(doc, Path(base_dir) / "dynamic.yaml", check_maps=False)


def _record(moving: int, index: int, row: dict[str, Any]) -> dict[str, Any]:
    """One episode's record, from its stored run (``collision_at_fault`` and the shield
    counts are None where the row predates them)."""
    from pathfuse.world.episode import stored_at_fault, stored_shield_counts

    m = json.loads(row["metrics"] or "{}")
    t = json.loads(row["timing"] or "{}")

    def num(key: str) -> float:
        v = m.get(key)
        return math.inf if v is None else float(v)  # non-finite values are stored as null

    return {
        "moving": int(moving),
        "index": int(index),
        "scenario": m.get("scenario", ""),
        "map": m.get("map", ""),
        "planner": row["planner"],
        "status": row["status_name"],
        "reached": bool(row["solved"]),
        "path_length_m": float(m.get("path_length_m", 0.0)),
        "time_to_goal_s": None if m.get("time_to_goal_s") is None
        else float(m["time_to_goal_s"]),
        "sim_time_s": float(m.get("n_ticks", 0)) * float(m.get("dt", 0.0)),
        "n_ticks": int(m.get("n_ticks", 0)),
        "min_distance_m": num("min_distance_m"),
        "min_obstacle_distance_m": num("min_obstacle_distance_m"),
        "min_static_clearance_m": num("min_static_clearance_m"),
        "collision_with": "" if m.get("collision_with") is None else str(m["collision_with"]),
        "mean_plan_time_s": float(t.get("mean_plan_time_s", 0.0)),
        "max_plan_time_s": float(t.get("max_plan_time_s", 0.0)),
        "setup_time_s": float(t.get("setup_time_s", 0.0)),
        "wall_s": float(row["wall_time"] or 0.0),
        "message": row["message"] or "",
        "collision_at_fault": stored_at_fault(m, row["status_name"]),
        **stored_shield_counts(m),
    }


def run_dynamic(
    config: DynamicConfig | None = None,
    progress: bool | None = False,
    workers: int | None = 1,
    db_path: str | os.PathLike[str] | None = None,
    stream: Any = None,
) -> DynamicRun:
    """Run the benchmark with the study engine.

    Parameters
    ----------
    config : DynamicConfig, optional
        Default ``DynamicConfig()``.
    progress : bool or None
        False (default) shows nothing; True or None show the engine's progress display
        (a live bar on a terminal, a few plain lines elsewhere).
    workers : int or None
        Processes of the engine's pool (1: in this process; None: every CPU).
        The records (timings aside) do not depend on it, and come back in the
        same order: by ``moving`` as configured, then scenario index, then
        planner.
    db_path : path, optional
        Keep the episodes in this result store (default: in memory); episodes
        already stored there are not run again.

    Returns
    -------
    DynamicRun
    """
    from pathfuse.bench.runner import run_experiment
    from pathfuse.bench.store import ResultStore

    cfg = config or DynamicConfig()
    if workers is not None and (not _is_int(workers) or workers < 1):
        raise ConfigError(f"workers: must be a positive integer, got {_shown(workers)}")
    exp = dynamic_experiment(cfg)
    specs = exp.expand()
    store = ResultStore(":memory:" if db_path is None else db_path)
    try:
        summary = run_experiment(exp, store, workers=workers, progress=progress, stream=stream,
                                 label="dynamic", unit="episodes")
        stored = store.rows_by_key([r.key for r in specs])
    finally:
        store.close()
    moving = {f"k{k}": k for k in cfg.moving}
    order = {n: i for i, n in enumerate(cfg.planners)}
    rank = {k: i for i, k in enumerate(cfg.moving)}
    ordered = sorted(specs, key=lambda r: (rank[moving[r.group]], r.seed, order[r.planner]))
    records = [_record(moving[r.group], r.seed, stored[r.key]) for r in ordered]
    return DynamicRun(cfg, records, summary.wall_s, workers=summary.workers)


# --------------------------------------------------------------------------- statistics
def summary_rows(run: DynamicRun) -> list[dict[str, Any]]:
    """One row per (moving, planner): status counts and rates with 95 % Wilson intervals,
    path length and time to goal over the successful episodes (mean, 95 % CI, median),
    and the mean planning time per tick (:func:`~pathfuse.bench.summary.group_stats`);
    then the collisions by fault, the clearance percentiles over the successful episodes
    and the shield's counts (:mod:`pathfuse.studies.barn_report`'s helpers)."""
    rows = []
    for k in run.config.moving:
        for name in run.config.planners:
            recs = [r for r in run.records if r["moving"] == k and r["planner"] == name]
            g = group_stats([{"solved": r["reached"], "status_name": r["status"],
                              "solution_length": None, "time": None, "time_to_goal": None}
                             for r in recs], statuses=OUTCOMES)
            row: dict[str, Any] = {"moving": k, "planner": name, "episodes": g["runs"]}
            for st in _ORDER:
                row[st.key] = g[st.value]
            for st in _ORDER:
                key, low = st.key, st.value
                row.update({f"{key}_rate": g[f"{low}_rate"], f"{key}_ci_low": g[f"{low}_ci_low"],
                            f"{key}_ci_high": g[f"{low}_ci_high"]})
            ok = [r for r in recs if r["status"] == "SUCCESS"]
            row.update(social_stats(ok, len(recs)))
            for col, label, unit, ci in (("path_length_m", "path_length", "_m", "t"),
                                         ("time_to_goal_s", "time_to_goal", "_s", "bootstrap")):
                v = value_stats([float(r[col]) for r in ok], label, unit, ci=ci)
                v.pop(f"{label}_n")
                row.update(v)
            row["mean_plan_time_us"] = 1e6 * float(np.mean([r["mean_plan_time_s"]
                                                           for r in recs])) if recs else math.nan
            row.update(fault_stats([r.get("collision_at_fault") for r in recs
                                    if r["status"] == "COLLISION"], len(recs)))
            for col in ("min_static_clearance", "min_obstacle_distance"):
                row.update(percentile_stats([r.get(f"{col}_m") for r in ok], col))
            row.update(shield_stats(recs))
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
            row = by.get((k, name))
            cells.append("-" if row is None else _rate_cell(row, key, short=True))
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
    head = ["discs", "planner", f"{_ORDER[0].label} [95% CI]",
            *(s.label for s in _ORDER[1:]), "path length (m) mean [95% CI]", "median",
            "time to goal (s) mean [95% CI]", "median", "plan time/tick (µs)",
            "collisions: robot at fault / hit standing", "min static clearance (m) p5 / p50",
            "min disc gap (m) p5 / p50", "shield: commands replaced"]
    table = [head]
    for r in rows:
        table.append([
            str(r["moving"]), r["planner"], *(_rate_cell(r, s.key) for s in _ORDER),
            _stat_cell(r, "path_length", "m"), _median_cell(r, "path_length", "m"),
            _stat_cell(r, "time_to_goal", "s"), _median_cell(r, "time_to_goal", "s"),
            "n/a" if not np.isfinite(r["mean_plan_time_us"]) else f"{r['mean_plan_time_us']:.0f}",
            fault_cell(r), percentile_cell(r, "min_static_clearance"),
            percentile_cell(r, "min_obstacle_distance"), shield_cell(r),
        ])
    fault = success_pivot(rows, "collision_at_fault") \
        if all(r["collision_at_fault"] is not None for r in rows) else None
    params = "; ".join(f"{n}: {dict(p)}" for n, p in cfg.params.items() if p) or "defaults"
    return (
        "# Dynamic benchmark: online planners among moving obstacles\n\n"
        f"{cfg.n_seeds} generated scenarios per number of moving discs "
        f"({', '.join(map(str, cfg.moving))}), seed {cfg.seed}: paper map family "
        "(15 m x 15 m, 50 random cells, a new map per scenario, the same maps for every "
        f"disc count), start (1, 1), goal (11, 11), {cfg.robot_label()}, "
        f"discs of radius 0.2-0.4 m at {lo:g}-{hi:g} m/s aimed across the route, "
        "dt 0.1 s, time limit 60 s.  Planner parameters: "
        f"{params}.\n\n"
        f"{counted(len(run.records), 'episode')} in {run.wall_s:.2f} s "
        f"({run.episodes_per_s:.1f} episodes/s, {counted(run.workers, 'worker')}).\n\n"
        "## Success rate [95% Wilson CI]\n\n"
        f"{markdown_table(success_pivot(rows))}\n\n"
        f"## Social success: reached, never within {SOCIAL_GAP_M:g} m of a disc "
        "[95% Wilson CI]\n\n"
        f"{markdown_table(success_pivot(rows, 'social'))}\n\n"
        "## Collision rate [95% Wilson CI]\n\n"
        f"{markdown_table(success_pivot(rows, 'collision'))}\n\n"
        + ("" if fault is None else
           "## Collisions that were the robot's fault [95% Wilson CI]\n\n"
           "The robot was moving during the colliding tick (or hit the static map); the "
           "rest of the collisions are discs walking into it standing still, which the "
           "safety shield's passive safety allows.\n\n"
           f"{markdown_table(fault)}\n\n") +
        f"{_paired_md(run)}"
        "## All outcomes\n\n"
        f"{markdown_table(table)}\n\n"
        "Counts per row add up to the episodes run (nothing dropped); rates carry 95% Wilson "
        "score intervals.  Path length and time to goal are over each planner's successful "
        "episodes only (so planners are compared on different subsets), with a 95% interval "
        "of the mean: Student-t for the length, a percentile bootstrap (2000 resamples, seed "
        "0) for the time to goal, which stays within the range of the data.  "
        "Plan time is the wall-clock time of the planner's per-tick "
        "decision, averaged over ticks and then over episodes.  The minimum static "
        "clearance and disc gap are each successful episode's least gap between the robot "
        "disc and the map, and the moving discs (exact over every tick), as 5th and 50th "
        "percentiles over those episodes.  \"Shield: commands replaced\" is the share of "
        "commands the safety shield did not pass as asked.  n/a: no such episode (no disc "
        "for the gap), or episodes stored before the value existed.\n"
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
