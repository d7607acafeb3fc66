"""The summary statistics of a group of stored runs: one function for every study.

``pathfuse report`` (per map entry and planner configuration), ``pathfuse
paper`` (per planner over the seeded maps) and ``pathfuse dynamic`` (per
number of discs and planner) all reduce their runs with :func:`group_stats`;
they differ only in how they group and lay out the rows.

A *run* here is a dict with the columns of the result store
(:mod:`pathfuse.bench.store`): ``solved``, ``status_name``,
``collision_free``, ``collisions``, ``solution_length``, ``time``,
``time_to_goal`` (and ``id`` when paired values are given).  Failures are
counted, never dropped: rates are over every run of the group, errors
included; lengths and times to goal are over the solved runs (so two planners
are compared on different subsets; paired values compare them on the same
problems).  Means come with 95 % intervals: Student-t for lengths and
R_length, a seeded percentile bootstrap for planning times and times to goal
(skewed, positive values whose t interval can go below zero).

Examples
--------
>>> runs = [{"id": 1, "solved": True, "status_name": "SUCCESS", "collision_free": True,
...          "collisions": 0, "solution_length": 3.0, "time": 0.01, "time_to_goal": None},
...         {"id": 2, "solved": False, "status_name": "LOCAL_MINIMUM", "collision_free": True,
...          "collisions": 0, "solution_length": None, "time": 0.02, "time_to_goal": None}]
>>> s = group_stats(runs, statuses=("SUCCESS", "LOCAL_MINIMUM"))
>>> s["solved"], s["failures"], s["success_rate"], s["local_minimum"], s["length_mean_m"]
(1, 'LOCAL_MINIMUM:1', 0.5, 1, 3.0)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pathfuse.stats import bootstrap_mean_ci, mean_ci, wilson_ci

__all__ = ["group_stats", "value_stats", "rate_stats", "median"]


def median(values: Sequence[float]) -> float:
    """The median, NaN for no value."""
    return float(np.median(values)) if len(values) else math.nan


def rate_stats(k: int, n: int, prefix: str) -> dict[str, float]:
    """``prefix_rate``, ``prefix_ci_low``, ``prefix_ci_high``: k of n with a 95 % Wilson interval.

    >>> rate_stats(0, 4, "collision")["collision_ci_low"]
    0.0
    """
    p, lo, hi = wilson_ci(k, n)
    return {f"{prefix}_rate": p, f"{prefix}_ci_low": lo, f"{prefix}_ci_high": hi}


def value_stats(values: Sequence[float], prefix: str, unit: str = "",
                ci: str = "t") -> dict[str, Any]:
    """``prefix_n``, ``prefix_mean{unit}``, ``prefix_ci_low{unit}``, ``prefix_ci_high{unit}`` and
    ``prefix_median{unit}``: the mean with its 95 % interval, and the median.

    ``ci="t"``: Student-t (lengths, R_length); ``ci="bootstrap"``: percentile bootstrap,
    2000 resamples, seed 0 (times: skewed and positive, their interval stays above zero).

    >>> value_stats([1.0, 3.0], "length", "_m")["length_median_m"]
    2.0
    """
    m, lo, hi = bootstrap_mean_ci(values) if ci == "bootstrap" else mean_ci(values)
    return {f"{prefix}_n": len(values), f"{prefix}_mean{unit}": m,
            f"{prefix}_ci_low{unit}": lo, f"{prefix}_ci_high{unit}": hi,
            f"{prefix}_median{unit}": median(values)}


def group_stats(runs: Sequence[Mapping[str, Any]], rl: Mapping[int, float] | None = None,
                statuses: Sequence[str] = ()) -> dict[str, Any]:
    """The summary of one group of runs (see the module docstring).

    ``rl`` maps run ids to a paired value (R_length against a reference, on
    the same problem and seed); ``statuses`` adds, for each status name, its
    count (key: the lower-case name) and its rate with a Wilson interval.
    """
    n = len(runs)
    solved = [r for r in runs if r["solved"]]
    errors = sum(r["status_name"] == "ERROR" for r in runs)
    failed: dict[str, int] = {}
    for r in runs:
        if not r["solved"]:
            s = r["status_name"] or "UNKNOWN"
            failed[s] = failed.get(s, 0) + 1
    checked = [r for r in solved if r.get("collision_free") is not None]
    cf = sum(bool(r["collision_free"]) for r in checked)
    coll = sum(1 for r in runs if (r.get("collisions") or 0) > 0)
    lengths = [float(r["solution_length"]) for r in solved if r["solution_length"] is not None]
    times = [float(r["time"]) for r in runs
             if r["status_name"] != "ERROR" and r["time"] is not None]
    ttg = [float(r["time_to_goal"]) for r in solved if r.get("time_to_goal") is not None]
    rl = rl or {}
    rv = [rl[r["id"]] for r in runs if r.get("id") in rl]
    out: dict[str, Any] = {
        "runs": n, "solved": len(solved), "not_solved": n - len(solved) - errors,
        "errors": errors,
        "failures": "; ".join(f"{k}:{v}" for k, v in sorted(failed.items())),
        **rate_stats(len(solved), n, "success"),
        "collision_checked": len(checked), "collision_free": cf,
        **rate_stats(cf, len(checked), "collision_free"),
        "collision_runs": coll, **rate_stats(coll, n, "collision"),
        **value_stats(lengths, "length", "_m"),
        **value_stats(times, "time", "_s", ci="bootstrap"),
        **value_stats(ttg, "time_to_goal", "_s", ci="bootstrap"),
        **{k.replace("r_length_n", "r_length_pairs"): v
           for k, v in value_stats(rv, "r_length").items()},
        "r_length_shorter": sum(v < 0 for v in rv),
    }
    for st in statuses:
        k = sum(r["status_name"] == st for r in runs)
        out[st.lower()] = k
        out.update(rate_stats(k, n, st.lower()))
    return out
