"""Tables of a BARN study (:mod:`pathfuse.studies.barn`): per planner, next to the published DWA.

:func:`summary_rows` gives, per planner, the episodes, the success, collision
and timeout counts and rates with 95 % Wilson intervals, the mean metric over
every episode (failures count 0) with a 95 % Student-t interval, and the mean
time over the successful episodes with its interval.  Beside them: the
collisions split into the robot's fault (it was moving, or hit the static map)
and hits while it stood still (:func:`fault_stats`; on BARN's static worlds
every collision is the robot's), the 5th and 50th percentiles of the minimum
static clearance over the successful episodes (:func:`percentile_stats`), and
how often the safety shield replaced a command (:func:`shield_stats`).  Rows
stored before these values existed summarise too: their cells read n/a.
:func:`markdown_report` lays them out with the challenge's published DWA
baseline as a reference line:
that baseline was measured in Gazebo with a real navigation stack (laser
scans, costmaps, physics), so it is a landmark, not a like-for-like comparison.

Examples
--------
>>> recs = [{"world": 0, "planner": "fusion", "status": "success", "time_s": 6.0,
...          "metric": 0.5}, {"world": 1, "planner": "fusion", "status": "collision",
...          "time_s": 2.0, "metric": 0.0}]
>>> r = summary_rows(recs, ["fusion"])[0]
>>> r["episodes"], r["success"], r["collision"], r["metric_mean"], r["time_mean_s"]
(2, 1, 1, 0.25, 6.0)
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.result import Status
from pathfuse.stats import counted, markdown_table, mean_ci, wilson_ci, write_csv

__all__ = ["summary_rows", "markdown_report", "text_table", "write_barn_outputs",
           "OUTCOMES", "PERCENTILES", "fault_stats", "percentile_stats", "shield_stats",
           "fault_cell", "percentile_cell", "shield_cell", "social_stats", "SOCIAL_GAP_M"]

#: The challenge's outcomes, as stored in an episode's ``status``: the lowercase values
#: of :class:`~pathfuse.result.Status`.
OUTCOMES = tuple(s.value for s in (Status.SUCCESS, Status.COLLISION, Status.TIMEOUT))
PERCENTILES = (5, 50)
"""The percentiles of the minimum clearances reported (over successful episodes)."""


def fault_stats(flags: Sequence[bool | None], n: int) -> dict[str, Any]:
    """The collisions of ``n`` episodes split by fault (``flags``: each collision's
    ``collision_at_fault``): ``collision_at_fault`` and ``collision_standing`` with
    their rates over the ``n`` episodes and 95 % Wilson intervals, and
    ``collision_fault_unknown`` (collisions stored without the value).  With any
    unknown the split is unknown: counts None, rates NaN.

    >>> r = fault_stats([True, True, False], 10)
    >>> r["collision_at_fault"], r["collision_standing"], r["collision_standing_rate"]
    (2, 1, 0.1)
    >>> fault_stats([True, None], 4)["collision_at_fault"] is None
    True
    """
    unknown = sum(f is None for f in flags)
    out: dict[str, Any] = {}
    for key, want in (("collision_at_fault", True), ("collision_standing", False)):
        if unknown:
            out.update({key: None, f"{key}_rate": math.nan, f"{key}_ci_low": math.nan,
                        f"{key}_ci_high": math.nan})
            continue
        k = sum(f is want for f in flags)
        p, lo, hi = wilson_ci(k, n)
        out.update({key: k, f"{key}_rate": p, f"{key}_ci_low": lo, f"{key}_ci_high": hi})
    out["collision_fault_unknown"] = unknown
    return out


def percentile_stats(values: Sequence[float | None], prefix: str,
                     unit: str = "_m") -> dict[str, Any]:
    """``prefix_n`` (the finite values) and ``prefix_p5{unit}``, ``prefix_p50{unit}``
    (:data:`PERCENTILES`; numpy's linear interpolation between order statistics; NaN
    without a finite value).

    >>> percentile_stats([0.0, None, 1.0, math.inf], "gap")
    {'gap_n': 2, 'gap_p5_m': 0.05, 'gap_p50_m': 0.5}
    """
    v = [float(x) for x in values if x is not None and math.isfinite(float(x))]
    out: dict[str, Any] = {f"{prefix}_n": len(v)}
    for q in PERCENTILES:
        out[f"{prefix}_p{q}{unit}"] = float(np.percentile(v, q)) if v else math.nan
    return out


SOCIAL_GAP_M = 0.3
"""A *social success* (issue 18's measure) reaches the goal and never comes closer than
this to any moving disc (the least gap between the robot's and the disc's edges)."""


def social_stats(ok: Sequence[Mapping[str, Any]], n: int) -> dict[str, Any]:
    """The social successes among the successful records ``ok`` of ``n`` episodes: count,
    rate and 95 % Wilson interval (an episode without discs has an infinite gap).

    >>> social_stats([{"min_obstacle_distance_m": 0.5}, {"min_obstacle_distance_m": 0.1}],
    ...              4)["social"]
    1
    """
    c = sum(1 for r in ok if float(r["min_obstacle_distance_m"]) >= SOCIAL_GAP_M)
    p, lo, hi = wilson_ci(c, n)
    return {"social": c, "social_rate": p, "social_ci_low": lo, "social_ci_high": hi}


def shield_stats(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The safety shield's counts summed over ``records`` (``shield_<name>``, None when
    no record has them), ``shield_commands`` (their total) and ``shield_replaced_rate``
    (the share of commands it did not pass as asked; NaN without counts).

    >>> shield_stats([{"shield_asked": 3, "shield_nearest": 1}])["shield_replaced_rate"]
    0.25
    """
    from pathfuse.shield import CODE_NAMES

    keys = [f"shield_{c}" for c in CODE_NAMES]
    have = [r for r in records if any(r.get(k) is not None for k in keys)]
    out: dict[str, Any] = {k: (sum(int(r.get(k) or 0) for r in have) if have else None)
                           for k in keys}
    total = sum(out[k] or 0 for k in keys)
    out["shield_commands"] = total if have else None
    replaced = total - (out["shield_asked"] or 0)
    out["shield_replaced_rate"] = replaced / total if total else math.nan
    return out


def summary_rows(records: Sequence[Mapping[str, Any]],
                 planners: Sequence[str]) -> list[dict[str, Any]]:
    """One row per planner (see the module docstring)."""
    rows = []
    for name in planners:
        recs = [r for r in records if r["planner"] == name]
        n = len(recs)
        row: dict[str, Any] = {"planner": name, "episodes": n}
        for o in OUTCOMES:
            k = sum(r["status"] == o for r in recs)
            p, lo, hi = wilson_ci(k, n)
            row.update({o: k, f"{o}_rate": p, f"{o}_ci_low": lo, f"{o}_ci_high": hi})
        # Student-t intervals, clipped to the values the quantity can take (metric 0..0.5,
        # time >= 0): a skewed sample of mostly zeros can put the bare interval below 0
        m, lo, hi = mean_ci([float(r["metric"]) for r in recs])
        row.update({"metric_mean": m, "metric_ci_low": _clip(lo, 0.0, 0.5),
                    "metric_ci_high": _clip(hi, 0.0, 0.5)})
        t, tlo, thi = mean_ci([float(r["time_s"]) for r in recs if r["status"] == "success"])
        row.update({"time_mean_s": t, "time_ci_low_s": _clip(tlo, 0.0, math.inf),
                    "time_ci_high_s": thi})
        detail: dict[str, int] = {}
        for r in recs:
            s = str(r.get("pathfuse_status", ""))
            if r["status"] == "timeout" and s and s != "TIMEOUT":
                detail[s] = detail.get(s, 0) + 1
        row["timeout_detail"] = ", ".join(f"{k} {v}" for k, v in sorted(detail.items()))
        row.update(fault_stats([r.get("collision_at_fault") for r in recs
                                if r["status"] == "collision"], n))
        row.update(percentile_stats([r.get("min_static_clearance_m") for r in recs
                                     if r["status"] == "success"], "min_static_clearance"))
        row.update(shield_stats(recs))
        rows.append(row)
    return rows


def _clip(v: float, lo: float, hi: float) -> float:
    return v if math.isnan(v) else min(max(v, lo), hi)


def _rate(r: Mapping[str, Any], key: str) -> str:
    if not r["episodes"]:
        return "n/a"
    return (f"{r[key]}/{r['episodes']} = {100 * r[f'{key}_rate']:.1f}% "
            f"[{100 * r[f'{key}_ci_low']:.1f}, {100 * r[f'{key}_ci_high']:.1f}]")


def _mean(r: Mapping[str, Any], key: str, unit: str = "", fmt: str = "{:.4f}") -> str:
    m = r[f"{key}_mean{unit}"]
    if not math.isfinite(m):
        return "n/a"
    lo, hi = r[f"{key}_ci_low{unit}"], r[f"{key}_ci_high{unit}"]
    return f"{fmt.format(m)} [{fmt.format(lo)}, {fmt.format(hi)}]"


def fault_cell(r: Mapping[str, Any]) -> str:
    """``"at fault / standing"`` counts of a summary row, n/a when unknown."""
    a, b = r.get("collision_at_fault"), r.get("collision_standing")
    return "n/a" if a is None or b is None else f"{a} / {b}"


def percentile_cell(r: Mapping[str, Any], prefix: str, unit: str = "_m",
                    fmt: str = "{:.3g}") -> str:
    """``"p5 / p50"`` of a summary row (3 significant digits: a clearance of a few
    micrometres stays visible), n/a without values."""
    vals = [r.get(f"{prefix}_p{q}{unit}") for q in PERCENTILES]
    if any(v is None or not math.isfinite(v) for v in vals):
        return "n/a"
    return " / ".join(fmt.format(v) for v in vals)


def shield_cell(r: Mapping[str, Any]) -> str:
    """The share of commands the shield replaced, n/a without counts."""
    p = r.get("shield_replaced_rate")
    return "n/a" if p is None or not math.isfinite(p) else f"{100 * p:.1f}%"


def _table(rows: Sequence[Mapping[str, Any]], baseline: Mapping[str, Any] | None
           ) -> list[list[str]]:
    head = ["planner", "success [95% CI]", "collision", "robot at fault / hit standing",
            "timeout", "mean metric [95% CI]", "mean time (s), successes [95% CI]",
            "min static clearance (m), successes: p5 / p50", "shield: commands replaced"]
    table = [head]
    for r in rows:
        to = _rate(r, "timeout")
        if r.get("timeout_detail"):
            to += f" (of which {r['timeout_detail']})"
        table.append([r["planner"], _rate(r, "success"), _rate(r, "collision"),
                      fault_cell(r), to, _mean(r, "metric"), _mean(r, "time", "_s", "{:.2f}"),
                      percentile_cell(r, "min_static_clearance"), shield_cell(r)])
    if baseline:
        table.append([f"*{baseline['planner']}*", f"*{100 * baseline['success']:.1f}%*",
                      f"*{100 * baseline['collision']:.1f}%*", "n/a",
                      f"*{100 * baseline['timeout']:.1f}%*", f"*{baseline['metric']:.4f}*",
                      f"*{baseline['time_s']:.2f}*", "n/a", "n/a"])
    return table


def markdown_report(run: Any, rows: Sequence[Mapping[str, Any]] | None = None,
                    figures: Mapping[str, str] | None = None) -> str:
    """The study as Markdown: the setup, the table with the DWA reference line, notes, and
    ``figures`` (caption -> image file, relative to the report) below them."""
    from pathfuse.studies.barn import (
        BARN_GOAL,
        BARN_GOAL_TOLERANCE_M,
        BARN_START,
        BARN_TIME_LIMIT_S,
        DWA_BASELINE,
    )

    cfg = run.config
    rows = summary_rows(run.records, cfg.planners) if rows is None else rows
    robot = ", ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                      for k, v in cfg.robot.items())
    idx = [w.index for w in run.worlds]
    return (
        "# BARN: the challenge's protocol on its Gazebo worlds\n\n"
        f"{counted(len(idx), 'world')} ({_span(idx)}) from {cfg.directory}, rasterised at "
        f"{cfg.resolution:g} m; start {BARN_START}, goal {BARN_GOAL} (reached within "
        f"{BARN_GOAL_TOLERANCE_M:g} m), {BARN_TIME_LIMIT_S:g} s limit; robot: {robot}; "
        f"dt {cfg.dt:g} s.  {counted(len(run.records), 'episode')} in {run.wall_s:.1f} s "
        f"with {counted(run.workers, 'worker')}.\n\n"
        f"{markdown_table(_table(rows, DWA_BASELINE))}\n\n"
        "Rates carry 95% Wilson intervals and means 95% Student-t intervals (clipped to "
        "the values the quantity can take).  The metric "
        "is the challenge's (success x optimal_time / clip(time, 2 optimal_time, 8 "
        "optimal_time), at most 0.5) averaged over every episode, failures counting 0; the "
        "mean time is over the successful episodes only.  A timeout is every episode that "
        "neither reached the goal nor collided: the planner's own give-ups (no path, "
        "stalled) are listed beside it.  A collision is the robot's fault when it was "
        "moving during the colliding tick (any collision with the static map is); \"hit "
        "standing\" counts moving discs that walked into it standing still (BARN's worlds "
        "have none, so every collision here is the robot's).  The minimum static "
        "clearance is each successful episode's least gap between the robot disc and the "
        "map (exact over every tick, capped at 2 m), given as its 5th and 50th "
        "percentiles over those episodes; \"shield: commands replaced\" is the share of "
        "commands the safety shield did not pass as asked (a nearby safe command, the "
        "emergency stop, or a disc evasion).  n/a: no such episode, or episodes stored "
        "before the value existed.\n\n"
        f"*{DWA_BASELINE['planner']}*: {DWA_BASELINE['note']}.  pathfuse simulates a disc "
        "robot with exact continuous collision checks against the occupied cells, perfect "
        "localisation and the map known in advance, so its rates are not those a Gazebo "
        "run would give.\n"
        + "".join(f"\n![{cap}]({f})\n\n*{cap}*\n" for cap, f in (figures or {}).items())
    )


def _span(idx: Sequence[int]) -> str:
    if not idx:
        return "none"
    if list(idx) == list(range(idx[0], idx[0] + len(idx))):
        return f"indices {idx[0]}-{idx[-1]}"
    return f"indices {idx[0]}..{idx[-1]}, {len(idx)} of them"


def text_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """The planner table as aligned plain text (what the command prints)."""
    from pathfuse.studies.barn import DWA_BASELINE

    table = [[c.strip("*") for c in row] for row in _table(rows, DWA_BASELINE)]
    widths = [max(len(r[i]) for r in table) for i in range(len(table[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
                     for r in table)


def write_barn_outputs(run: Any, out_dir: str | Path) -> dict[str, Path]:
    """Write ``barn.md``, ``summary.csv``, ``episodes.csv`` (no trajectories), the figure of
    the planners (``barn_planners.png``: :func:`~pathfuse.viz.barn.plot_barn_planners`)
    and, when the run kept one world's paths (``run.figure_world``), that world's
    trajectories (``barn_world_N.png``: :func:`~pathfuse.viz.barn.plot_barn_world`) into
    ``out_dir``; return their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = summary_rows(run.records, run.config.planners)
    files = {"report_md": out / "barn.md", "summary_csv": out / "summary.csv",
             "episodes_csv": out / "episodes.csv"}
    figures = _write_figures(run, rows, out)
    files["report_md"].write_text(markdown_report(
        run, rows, {cap: f.name for cap, f in figures.values()}), encoding="utf-8")
    write_csv(files["summary_csv"], [{k: ("" if isinstance(v, float) and math.isnan(v) else v)
                                      for k, v in r.items()} for r in rows])
    write_csv(files["episodes_csv"], [{k: ("" if v is None else v) for k, v in r.items()
                                       if k != "trajectory"} for r in run.records])
    files.update({k: f for k, (_, f) in figures.items()})
    return files


def _write_figures(run: Any, rows: Sequence[Mapping[str, Any]], out: Path
                   ) -> dict[str, tuple[str, Path]]:
    """The figures of :func:`write_barn_outputs`: ``{key: (caption, file)}``."""
    from pathfuse.studies.barn import (
        BARN_BOUNDS,
        BARN_GOAL,
        BARN_GOAL_TOLERANCE_M,
        BARN_START,
        DWA_BASELINE,
    )
    from pathfuse.viz.barn import plot_barn_planners, plot_barn_world

    cfg = run.config
    n_worlds = len(run.worlds)
    figs: dict[str, tuple[str, Path]] = {}
    cap = (f"Outcomes and mean metric by planner over {n_worlds} world"
           f"{'s' if n_worlds != 1 else ''}")
    figs["planners_png"] = (cap, out / "barn_planners.png")
    plot_barn_planners(rows, figs["planners_png"][1], baseline=DWA_BASELINE, title=cap)
    w = next((w for w in run.worlds if w.index == getattr(run, "figure_world", None)), None)
    if w is None:
        return figs
    from pathfuse.io.gazebo import read_gazebo_world

    recs = {r["planner"]: r for r in run.records if r["world"] == w.index}
    tracks = [{"planner": name, "status": recs[name]["status"], "time_s": recs[name]["time_s"],
               "positions": run.paths[name]} for name in cfg.planners
              if name in recs and name in run.paths]
    if not tracks:
        return figs
    cap = f"The trajectories on world {w.index}, one panel per planner"
    figs["world_png"] = (cap, out / f"barn_world_{w.index}.png")
    grid = read_gazebo_world(w.world, cfg.resolution, bounds=BARN_BOUNDS)
    plot_barn_world(grid, tracks, figs["world_png"][1], start=BARN_START, goal=BARN_GOAL,
                    goal_tolerance_m=BARN_GOAL_TOLERANCE_M,
                    robot_radius_m=cfg.robot_radius_m, title=cap)
    return figs


def json_lines(records: Sequence[Mapping[str, Any]]) -> str:
    """One JSON object per episode, one per line."""
    return "".join(json.dumps(dict(r), allow_nan=False) + "\n" for r in records)
