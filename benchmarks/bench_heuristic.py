"""The ``astar`` planner's heuristic: Euclidean (the paper's eq. 2) against octile.

Both heuristics are admissible and consistent on the 8-connected grid, so both give
optimal paths of the same length; octile is the exact distance on an empty grid, so
A* expands fewer cells.  For every scen line of the shipped MovingAI maps (and the
paper's maps between the paper's start and goal) this plans with :func:`pathfuse.plan`
under each heuristic, interleaved query by query, and reports:

* the largest difference of the two lengths (0 up to float rounding: the same
  optimum) and how many paths are not the same cells (ties broken otherwise);
* the median of the per-query ratios of expansions and of times (``time_s``, the
  search itself; CPU time of the whole ``plan()`` call; wall time of it).

Usage::

    python benchmarks/bench_heuristic.py [--data tests/data/movingai] [--paper 50]
        [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import pathfuse
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map


def _once(grid: Any, s: Any, g: Any, h: str) -> tuple[Any, float, float]:
    c0, w0 = time.process_time(), time.perf_counter()
    r = pathfuse.plan(grid, s, g, heuristic=h)
    return r, time.process_time() - c0, time.perf_counter() - w0


def compare(grid: Any, queries: list[tuple[Any, Any]]) -> dict[str, Any]:
    for h in ("euclidean", "octile"):  # compile and build the map's buffers untimed
        pathfuse.plan(grid, queries[0][0], queries[0][1], heuristic=h)
    dl, differ, n = 0.0, 0, 0
    ratios: dict[str, list[float]] = {"expansions": [], "search": [], "cpu": [], "wall": []}
    for s, g in queries:
        re, ce, we = _once(grid, s, g, "euclidean")
        ro, co, wo = _once(grid, s, g, "octile")
        if not re.success:
            assert not ro.success
            continue
        n += 1
        dl = max(dl, abs(re.length - ro.length))
        differ += int(not np.array_equal(re.info["cells"], ro.info["cells"]))
        if ro.expansions:
            ratios["expansions"].append(re.expansions / ro.expansions)
        ratios["search"].append(re.time_s / max(ro.time_s, 1e-9))
        ratios["cpu"].append(ce / max(co, 1e-9))
        ratios["wall"].append(we / max(wo, 1e-9))
    return {"queries": n, "max_length_difference": dl, "different_paths": differ,
            **{f"euclidean_over_octile_{k}": statistics.median(v) if v else None
               for k, v in ratios.items()}}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("tests/data/movingai"))
    ap.add_argument("--paper", type=int, default=50, help="paper maps (seeds 0..N-1)")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    out: dict[str, Any] = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(),
                                       "load_start": round(os.getloadavg()[0], 2),
                                       "python": platform.python_version()}, "maps": {}}
    for mp in sorted(args.data.glob("*.map")):
        grid = pathfuse.read_movingai(mp)
        qs = []
        for scen in sorted(args.data.glob(mp.stem + "*.scen")):
            qs += [(p.start, p.goal) for p in pathfuse.read_scen(scen, grid)]
        if qs:
            out["maps"][mp.stem] = compare(grid, qs)
    paper = [(paper_map(seed), PAPER_START, PAPER_GOAL) for seed in range(args.paper)]
    rows = [compare(g, [(s, e)]) for g, s, e in paper]
    out["maps"]["paper"] = {
        "queries": sum(r["queries"] for r in rows),
        "max_length_difference": max(r["max_length_difference"] for r in rows),
        "different_paths": sum(r["different_paths"] for r in rows)}
    out["machine"]["load_end"] = round(os.getloadavg()[0], 2)
    print(f"# bench_heuristic: {platform.machine()}, {os.cpu_count()} CPUs, load "
          f"{out['machine']['load_start']} -> {out['machine']['load_end']}")
    print(f"{'map':<22} {'queries':>7} {'max dL':>9} {'diff paths':>10} {'exp E/O':>8} "
          f"{'search E/O':>10} {'cpu E/O':>8} {'wall E/O':>8}")
    def f(r: dict[str, Any], k: str) -> str:
        v = r.get(k)
        return "-" if v is None else f"{v:.2f}"

    for name, r in out["maps"].items():
        print(f"{name:<22} {r['queries']:>7} {r['max_length_difference']:>9.2g} "
              f"{r['different_paths']:>10} {f(r, 'euclidean_over_octile_expansions'):>8} "
              f"{f(r, 'euclidean_over_octile_search'):>10} {f(r, 'euclidean_over_octile_cpu'):>8} "
              f"{f(r, 'euclidean_over_octile_wall'):>8}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
