"""Planners among people in IR-SIM worlds (a preset study: ``pathfuse irsim``).

Every planner (pathfuse's online planners through
:class:`~pathfuse.integrations.irsim.IrsimController`, and IR-SIM's own robot
driven by its RVO behaviour, :data:`~pathfuse.integrations.irsim_run.RVO_BASELINE`)
runs every IR-SIM world file for seeds ``0 .. n_seeds - 1`` (each seed perturbs
the walkers' starts and speeds: :func:`~pathfuse.integrations.irsim_run.perturb_env`),
as one experiment of the study engine (its worker pool, result store, resume and
progress bar; the run kind ``irsim``).  Nothing is dropped: every episode is a
row of ``episodes.csv``, whatever its status.

:func:`summary_rows` reduces them per planner (over every world) and per
(world, planner): episodes, successes (rate with a 95 % Wilson interval),
episodes IR-SIM ended in a collision and those of them the robot drove into,
the median of each episode's minimum gap to the people, the mean time within
0.45 m of a person, the median time to goal over the successes and the median
path irregularity (definitions: :mod:`pathfuse.world.social`).

Examples
--------
>>> import os
>>> from pathfuse.integrations.irsim_run import example_worlds_dir
>>> world = os.path.join(example_worlds_dir(), "doorway.yaml")
>>> run = run_irsim_study(IrsimConfig((world,), planners=("astar", "irsim-rvo"), n_seeds=1,
...                                   time_limit_s=2.0))
>>> [(r["world"], r["planner"], r["status"]) for r in run.records]
[('doorway', 'astar', 'TIMEOUT'), ('doorway', 'irsim-rvo', 'TIMEOUT')]
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

from pathfuse.result import ConfigError
from pathfuse.stats import counted
from pathfuse.validate import short as _shown

__all__ = ["IrsimConfig", "IrsimRun", "irsim_experiment", "run_irsim_study",
           "summary_rows", "text_table", "markdown_report", "write_irsim_outputs",
           "find_world_files", "DEFAULT_SEEDS", "write_gifs"]

DEFAULT_SEEDS = 8
"""Seeds per world by default."""


def find_world_files(paths: Sequence[str | os.PathLike[str]]) -> tuple[str, ...]:
    """World files named by ``paths``: files, and the ``*.yaml`` files of folders (sorted).

    Raises
    ------
    ConfigError
        A path that does not exist, or a folder without a ``.yaml`` file.
    """
    out: list[str] = []
    for p in paths:
        q = Path(os.path.expanduser(os.fspath(p)))
        if q.is_dir():
            found = sorted(str(f) for f in q.iterdir()
                           if f.suffix in (".yaml", ".yml") and f.is_file())
            if not found:
                raise ConfigError(f"{q}: no IR-SIM world file (*.yaml) in this folder")
            out.extend(found)
        elif q.is_file():
            out.append(str(q))
        else:
            raise ConfigError(f"{q}: no such IR-SIM world file or folder")
    return tuple(dict.fromkeys(os.path.abspath(f) for f in out))


@dataclass(frozen=True)
class IrsimConfig:
    """What ``pathfuse irsim`` runs.

    Attributes
    ----------
    worlds : tuple of str
        IR-SIM world files (each with a ``custom: pathfuse:`` block or defaults).
    planners : tuple of str
        Online planners of pathfuse and ``irsim-rvo``; empty: every online planner and
        ``irsim-rvo``.
    n_seeds : int
        Seeds per world (0 .. n_seeds - 1).
    resolution_m : float
        Cell side of the rasterised static obstacles (m).
    params : mapping
        Per-planner parameter overrides ``{name: {key: value}}``.
    time_limit_s : float or None
        Overrides every world's time limit.
    """

    worlds: tuple[str, ...]
    planners: tuple[str, ...] = ()
    n_seeds: int = DEFAULT_SEEDS
    resolution_m: float = 0.05
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    time_limit_s: float | None = None

    def __post_init__(self) -> None:
        from pathfuse.integrations.irsim_run import RVO_BASELINE, read_world_spec
        from pathfuse.planners.registry import REGISTRY, get_planner, make_params, planner_names

        if isinstance(self.worlds, str) or not self.worlds:
            raise ConfigError(f"worlds: must be a list of IR-SIM world files, got "
                              f"{_shown(self.worlds)}")
        worlds = find_world_files(self.worlds)
        for w in worlds:
            read_world_spec(w)
        object.__setattr__(self, "worlds", worlds)
        stems = [Path(w).stem for w in worlds]
        dup = {s for s in stems if stems.count(s) > 1}
        if dup:
            raise ConfigError(f"worlds: two world files are named {sorted(dup)[0]!r} (the name "
                              "identifies a world in the tables)")
        n = self.n_seeds
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ConfigError(f"n_seeds: must be a positive integer, got {_shown(n)}")
        r = self.resolution_m
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not math.isfinite(r) \
                or r <= 0:
            raise ConfigError(f"resolution_m: must be a number > 0, got {_shown(r)}")
        t = self.time_limit_s
        if t is not None and (isinstance(t, bool) or not isinstance(t, (int, float))
                              or not math.isfinite(t) or t <= 0):
            raise ConfigError(f"time_limit_s: must be a number > 0, got {_shown(t)}")
        if isinstance(self.planners, str):
            raise ConfigError(f"planners: must be a list of names, got {_shown(self.planners)}")
        names = []
        for p in tuple(self.planners) or (*[p for p in planner_names() if REGISTRY[p].online],
                                           RVO_BASELINE):
            if p == RVO_BASELINE:
                names.append(p)
                continue
            try:
                spec = get_planner(p)
            except ConfigError as exc:
                raise ConfigError(f"planners: {exc} (or {RVO_BASELINE}, IR-SIM's RVO "
                                  "robot)") from None
            if not spec.online:
                raise ConfigError(f"planners: {spec.name!r} only plans offline")
            names.append(spec.name)
        object.__setattr__(self, "planners", tuple(dict.fromkeys(names)))
        if not isinstance(self.params, Mapping):
            raise ConfigError(f"params: must be {{planner: {{key: value}}}}, got "
                              f"{_shown(self.params)}")
        for name, ps in self.params.items():
            if name not in self.planners:
                raise ConfigError(f"params.{name}: not among the planners run "
                                  f"({', '.join(self.planners)})")
            if name == RVO_BASELINE and ps:
                raise ConfigError(f"params.{name}: IR-SIM's RVO robot takes no parameters")
            if name != RVO_BASELINE:
                make_params(get_planner(name), ps, key=f"params.{name}")
        object.__setattr__(self, "params", {k: dict(v) for k, v in self.params.items()})

    @property
    def n_episodes(self) -> int:
        return len(self.worlds) * len(self.planners) * self.n_seeds


@dataclass
class IrsimRun:
    """Every episode of a study: one record (dict) per (world, seed, planner), in that
    order (worlds as configured)."""

    config: IrsimConfig
    records: list[dict[str, Any]]
    wall_s: float
    workers: int = 1


# --------------------------------------------------------------------------- engine
def irsim_experiment(cfg: IrsimConfig) -> Any:
    """The study engine's experiment: one ``irsim`` map entry per world (named by its file's
    stem), every planner, seeds ``0 .. n_seeds - 1``."""
    from pathfuse.bench.experiment import experiment_from_dict

    maps = []
    for w in cfg.worlds:
        spec: dict[str, Any] = {"world": w, "resolution_m": float(cfg.resolution_m)}
        if cfg.time_limit_s is not None:
            spec["time_limit_s"] = float(cfg.time_limit_s)
        maps.append({"name": Path(w).stem, "irsim": spec})
    doc = {
        "name": "irsim",
        "description": "planners among people in IR-SIM worlds",
        "seeds": cfg.n_seeds,
        "maps": maps,
        "planners": [{"name": n, "params": dict(cfg.params.get(n, {})), "kinds": ["irsim"]}
                     if cfg.params.get(n) else {"name": n, "kinds": ["irsim"]}
                     for n in cfg.planners],
    }
    return experiment_from_dict(doc, Path(cfg.worlds[0]).parent / "irsim.yaml",
                                check_maps=False)


def _record(row: Mapping[str, Any]) -> dict[str, Any]:
    m = json.loads(row["metrics"] or "{}")
    t = json.loads(row["timing"] or "{}")
    gap = m.get("min_gap_m")
    return {
        "world": m.get("world", row.get("map_name", "")),
        "kind": m.get("kind", ""),
        "planner": row["planner"],
        "seed": int(row["seed"]),
        "status": row["status_name"],
        "reached": bool(row["solved"]),
        "collision": bool(m.get("collision", False)),
        "collision_with": m.get("collision_with") or "",
        "collision_at_fault": m.get("collision_at_fault"),
        "min_gap_m": math.inf if gap is None and m.get("people") == 0 else
        (math.nan if gap is None else float(gap)),
        "time_within_m_s": float(m.get("time_within_m_s", math.nan)),
        "at_fault_contacts": m.get("at_fault_contacts"),
        "contacts": m.get("contacts"),
        "path_irregularity_rad_per_m": float(m.get("path_irregularity_rad_per_m", math.nan)),
        "time_to_goal_s": m.get("time_to_goal_s"),
        "sim_time_s": float(m.get("sim_time_s", 0.0)),
        "path_length_m": float(m.get("path_length_m", 0.0)),
        "unperturbed": m.get("unperturbed"),
        "median_act_time_ms": 1e3 * float(t.get("median_act_time_s", 0.0)),
        "median_command_time_ms": 1e3 * float(t.get("median_command_time_s", 0.0)),
        "wall_s": float(row.get("wall_time") or 0.0),
        "message": row.get("message") or "",
    }


def run_irsim_study(config: IrsimConfig, *, workers: int | None = 1,
                    db_path: str | os.PathLike[str] | None = None,
                    progress: bool | None = False, stream: Any = None) -> IrsimRun:
    """Run (or resume, with ``db_path``) the study with the study engine.

    ``workers``: processes of the engine's pool (1: in this process; None: every CPU);
    the records do not depend on it.  Episodes already in ``db_path`` are not run again.
    """
    from pathfuse.bench.runner import run_experiment
    from pathfuse.bench.store import ResultStore

    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ConfigError(f"workers: must be a positive integer, got {_shown(workers)}")
    exp = irsim_experiment(config)
    specs = exp.expand()
    store = ResultStore(":memory:" if db_path is None else db_path)
    try:
        summary = run_experiment(exp, store, workers=workers, progress=progress, stream=stream,
                                 label="irsim", unit="episodes")
        stored = store.rows_by_key([r.key for r in specs])
    finally:
        store.close()
    rank = {Path(w).stem: i for i, w in enumerate(config.worlds)}
    order = {n: i for i, n in enumerate(config.planners)}
    ordered = sorted(specs, key=lambda r: (rank[r.group], r.seed, order[r.planner]))
    records = []
    for r in ordered:
        row = dict(stored[r.key])
        if row.get("status_name") == "ERROR":  # counted, never dropped
            rec = {"world": r.group, "kind": "", "planner": r.planner, "seed": r.seed,
                   "status": "ERROR", "reached": False, "collision": False,
                   "collision_with": "", "collision_at_fault": None, "min_gap_m": math.nan,
                   "time_within_m_s": math.nan, "at_fault_contacts": None, "contacts": None,
                   "path_irregularity_rad_per_m": math.nan, "time_to_goal_s": None,
                   "sim_time_s": 0.0, "path_length_m": 0.0, "unperturbed": None,
                   "median_act_time_ms": 0.0, "median_command_time_ms": 0.0,
                   "wall_s": float(row.get("wall_time") or 0.0),
                   "message": str(row.get("error") or "")}
        else:
            rec = _record(row)
            rec["world"] = r.group
        records.append(rec)
    return IrsimRun(config, records, summary.wall_s, summary.workers)


# --------------------------------------------------------------------------- statistics
def _median(vals: Sequence[float]) -> float:
    v = [x for x in vals if x is not None and not math.isnan(x)]
    return float(np.median(v)) if v else math.nan


def _stats(rs: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    from pathfuse.stats import wilson_ci

    n = len(rs)
    ok = sum(r["reached"] for r in rs)
    rate, lo, hi = wilson_ci(ok, n) if n else (math.nan, math.nan, math.nan)
    coll = sum(r["collision"] for r in rs)
    fault = sum(1 for r in rs if r["collision"] and r["collision_at_fault"])
    return {
        "episodes": n, "successes": ok, "success": rate, "success_lo": lo, "success_hi": hi,
        "collisions": coll, "at_fault_collisions": fault,
        "errors": sum(r["status"] == "ERROR" for r in rs),
        "timeouts": sum(r["status"] == "TIMEOUT" for r in rs),
        "median_min_gap_m": _median([r["min_gap_m"] for r in rs]),
        "mean_time_within_s": float(np.nanmean([r["time_within_m_s"] for r in rs]))
        if n and not all(math.isnan(r["time_within_m_s"]) for r in rs) else math.nan,
        "median_time_to_goal_s": _median([r["time_to_goal_s"] for r in rs if r["reached"]]),
        "median_path_irregularity_rad_per_m":
            _median([r["path_irregularity_rad_per_m"] for r in rs]),
        "median_act_time_ms": _median([r["median_act_time_ms"] for r in rs
                                       if r["median_act_time_ms"] > 0]),
    }


def summary_rows(records: Sequence[Mapping[str, Any]],
                 planners: Sequence[str]) -> list[dict[str, Any]]:
    """Per planner over every world (``world`` = ``"all"``), then per (world, planner); the
    counts of each row add up to its episodes (nothing dropped)."""
    worlds = list(dict.fromkeys(r["world"] for r in records))
    out = []
    for p in planners:
        rs = [r for r in records if r["planner"] == p]
        out.append({"world": "all", "planner": p, **_stats(rs)})
    for w in worlds:
        for p in planners:
            rs = [r for r in records if r["planner"] == p and r["world"] == w]
            if rs:
                out.append({"world": w, "planner": p, **_stats(rs)})
    return out


def _cell(v: float, fmt: str = "{:.2f}") -> str:
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v)


_HEAD = ["world", "planner", "success [95% CI]", "IR-SIM collisions (at fault)",
         "median min gap (m)", "time within 0.45 m (s, mean)", "median time to goal (s)",
         "path irregularity (rad/m, median)"]


def _table(rows: Sequence[Mapping[str, Any]]) -> list[list[str]]:
    table = [list(_HEAD)]
    for r in rows:
        succ = (f"{r['successes']}/{r['episodes']} {100 * r['success']:.0f}% "
                f"[{100 * r['success_lo']:.0f}, {100 * r['success_hi']:.0f}]"
                if r["episodes"] else "n/a")
        table.append([r["world"], r["planner"], succ,
                      f"{r['collisions']} ({r['at_fault_collisions']})",
                      _cell(r["median_min_gap_m"], "{:.3f}"),
                      _cell(r["mean_time_within_s"]), _cell(r["median_time_to_goal_s"], "{:.1f}"),
                      _cell(r["median_path_irregularity_rad_per_m"])])
    return table


def text_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """The summary as aligned text (what ``pathfuse irsim`` prints)."""
    table = _table(rows)
    widths = [max(len(r[i]) for r in table) for i in range(len(table[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
                     for r in table)


def markdown_report(run: IrsimRun, rows: Sequence[Mapping[str, Any]] | None = None) -> str:
    """``irsim.md``: what was run, the table, and the metrics' definitions."""
    from pathfuse.integrations.irsim_run import read_world_spec
    from pathfuse.stats import markdown_table

    cfg = run.config
    rows = summary_rows(run.records, cfg.planners) if rows is None else rows
    specs = [read_world_spec(w) for w in cfg.worlds]
    worlds = "\n".join(f"- `{s.name}` ({s.kind}): {s.description or 'no description'}; "
                       f"time limit {s.time_limit_s:g} s, seeds jitter the walkers' starts by "
                       f"up to {s.position_m:g} m and their speeds by up to "
                       f"{100 * s.speed_frac:g} %" for s in specs)
    errors = sum(r["status"] == "ERROR" for r in run.records)
    return (
        "# Planners among people in IR-SIM\n\n"
        f"{counted(len(run.records), 'episode')} ({counted(len(cfg.planners), 'planner')} x "
        f"{counted(len(cfg.worlds), 'world')} x {counted(cfg.n_seeds, 'seed')}) in "
        f"{run.wall_s:.1f} s ({counted(run.workers, 'worker')}); {errors} ended in an error.  "
        "Static obstacles "
        f"rasterised at {cfg.resolution_m:g} m.  `irsim-rvo` is IR-SIM's own robot driven by "
        "its RVO behaviour.\n\n"
        f"{worlds}\n\n"
        f"{markdown_table(_table(rows))}\n\n"
        "Success: IR-SIM says the robot arrived (within its goal threshold) before any "
        "collision and before the time limit.  IR-SIM collisions: episodes IR-SIM ended in a "
        "collision (its own geometry check); at fault: the robot moved faster than 0.01 m/s "
        "in the step that ended in it, or hit a static obstacle.  The minimum gap is each "
        "episode's least distance between the robot's disc and a person's at the steps "
        "(negative: overlap), its median over every episode of the row; time within 0.45 m: "
        "seconds with a person closer than 0.45 m (surface to surface), mean per episode; "
        "path irregularity: the robot's total turning per metre driven "
        "(pathfuse.world.social).  Nothing is dropped: every episode is a row of "
        "episodes.csv.\n")


def write_irsim_outputs(run: IrsimRun, out_dir: str | os.PathLike[str]) -> dict[str, Path]:
    """Write ``irsim.md``, ``summary.csv`` and ``episodes.csv`` into ``out_dir``."""
    from pathfuse.stats import write_csv

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = summary_rows(run.records, run.config.planners)

    def plain(v: Any) -> Any:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return ""
        return v

    files = {"report_md": out / "irsim.md", "summary_csv": out / "summary.csv",
             "episodes_csv": out / "episodes.csv"}
    files["report_md"].write_text(markdown_report(run, rows), encoding="utf-8")
    write_csv(files["summary_csv"], [{k: plain(v) for k, v in r.items()} for r in rows])
    write_csv(files["episodes_csv"], [{k: plain(v) for k, v in r.items()} for r in run.records])
    return files


def write_gifs(config: IrsimConfig, out_dir: str | os.PathLike[str], seed: int = 0
               ) -> list[Path]:
    """One GIF per (world, planner) of seed ``seed`` in ``out_dir/gifs`` (the episode run
    again: it is the same episode, see :mod:`pathfuse.integrations.irsim_run`; a planner
    with a ``seed`` parameter gets the run's seed, as the study engine gives it)."""
    from pathfuse.integrations.irsim_run import run_irsim_episode
    from pathfuse.viz.animate import animate_episode

    folder = Path(out_dir) / "gifs"
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    from pathfuse.integrations.irsim_run import RVO_BASELINE
    from pathfuse.planners.registry import get_planner

    for w in config.worlds:
        for p in config.planners:
            params = dict(config.params.get(p) or {})
            if p != RVO_BASELINE and "seed" in get_planner(p).defaults():
                params.setdefault("seed", seed)  # as the study engine gives it (mppi)
            ep = run_irsim_episode(w, p, seed, params or None,
                                   resolution_m=config.resolution_m,
                                   time_limit_s=config.time_limit_s)
            f = folder / f"{Path(w).stem}_{p}_seed{seed}.gif"
            animate_episode(ep, f, title=f"{Path(w).stem}: {p} (seed {seed}): "
                                         f"{ep.status.name.lower()}")
            out.append(f)
    return out
