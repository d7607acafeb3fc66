"""Stepping-loop speed of the APF and fusion planners, and fusion vs A* planning time.

Measured as ratios within one run (nothing here is asserted by the tests):

1. Paper maps (15 m x 15 m, 1 m cells, 50 obstacles, start (1,1), goal (11,11)):
   per seed, the planning time ``time_s`` of A* and of fusion (which includes
   its A*), each the minimum of ``--repeat`` alternating runs; reports the
   median over seeds of fusion / A* (the paper reports 1.56 in MATLAB; a
   faster A* raises this ratio, as fusion's stepping is most of its time), and
   the same ratio for the wall time of whole ``plan()`` calls (query checks and
   result building included).
2. Steps per second of the APF and fusion stepping loops (force steps divided
   by the time spent inside the stepping driver, numba dispatch included) on
   the paper maps and on a 1024 x 1024 map of the same obstacle density, for
   queries of the same shape (goal 10 cells up and right of the start), plus
   one long fusion run across the big map.  Targets: >= 1e6 steps/s, and the
   big-map rate >= half the paper-map rate.

Usage::

    python benchmarks/bench_stepping.py [--seeds 200] [--big 1024] [--queries 300] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

from pathfuse import plan
from pathfuse.generate import PAPER_GOAL, PAPER_OBSTACLES, PAPER_START, paper_map, random_map
from pathfuse.planners.registry import get_planner
from pathfuse.planners.run import warm


def _rate(results) -> tuple[float, int, float]:
    steps = sum(r.iterations for r in results)
    t = sum(r.info["step_time_s"] for r in results)
    return (steps / t if t > 0 else float("nan")), steps, t


def _queries(grid, n, rng, offset=10):
    free = np.argwhere(~grid.occupied)
    out = []
    while len(out) < n:
        r, c = free[rng.integers(len(free))]
        rr, cc = r + offset, c + offset
        if rr < grid.height and cc < grid.width and not grid.occupied[rr, cc]:
            if grid.components[r, c] == grid.components[rr, cc]:
                out.append((grid.cell_to_world([r, c])[0], grid.cell_to_world([rr, cc])[0]))
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=200, help="paper maps (seeds 0..N-1)")
    ap.add_argument("--big", type=int, default=1024, help="side of the big map, cells")
    ap.add_argument("--queries", type=int, default=300, help="queries on the big map")
    ap.add_argument("--repeat", type=int, default=5, help="timing repeats (min is kept)")
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args(argv)
    load0 = round(os.getloadavg()[0], 2)

    for name in ("astar", "apf", "fusion"):
        warm(get_planner(name))  # compile (or load) the kernels before any clock starts

    # ---- 1. paper maps: fusion vs A*, and stepping rates.  A* and fusion are timed
    # alternately on the same map (min of --repeat runs each), so that load on the
    # machine hits both alike.
    ratios, t_astar, t_fusion, wall_ratios = [], [], [], []
    apf_runs, fus_runs = [], []
    for s in range(args.seeds):
        g = paper_map(s)
        ta = tf = wa = wf = float("inf")
        fr = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            a = plan(g, PAPER_START, PAPER_GOAL, planner="astar")
            t1 = time.perf_counter()
            f = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
            t2 = time.perf_counter()
            ta, tf = min(ta, a.time_s), min(tf, f.time_s)
            wa, wf = min(wa, t1 - t0), min(wf, t2 - t1)
            fr.append(f)
        t_astar.append(ta)
        t_fusion.append(tf)
        ratios.append(tf / ta)
        wall_ratios.append(wf / wa)
        fus_runs.append(min(fr, key=lambda r: r.info.get("step_time_s", 0)))
        ar = [plan(g, PAPER_START, PAPER_GOAL, planner="apf") for _ in range(args.repeat)]
        apf_runs.append(min(ar, key=lambda r: r.info["step_time_s"]))
    fus_ok = sum(r.success for r in fus_runs)
    apf_small, apf_small_n, _ = _rate(apf_runs)
    fus_small, fus_small_n, _ = _rate([r for r in fus_runs if "step_time_s" in r.info])

    # ---- 2. big map, same density and query shape
    density = PAPER_OBSTACLES / 225
    t0 = time.perf_counter()
    big = random_map(size_m=float(args.big), resolution=1.0, density=density, seed=1,
                     origin=(-0.5, -0.5), name=f"big-{args.big}")
    t_gen = time.perf_counter() - t0
    rng = np.random.default_rng(7)
    qs = _queries(big, args.queries, rng)
    apf_big_runs, fus_big_runs = [], []
    for s, e in qs:
        apf_big_runs.append(min((plan(big, s, e, planner="apf") for _ in range(args.repeat)),
                                key=lambda r: r.info["step_time_s"]))
        fr = [plan(big, s, e, planner="fusion") for _ in range(args.repeat)]
        fr = [r for r in fr if "step_time_s" in r.info]
        if fr:
            fus_big_runs.append(min(fr, key=lambda r: r.info["step_time_s"]))
    apf_big, apf_big_n, _ = _rate(apf_big_runs)
    fus_big, fus_big_n, _ = _rate(fus_big_runs)

    # one long fusion run across the big map
    far = big.cell_to_world([[10, 10], [args.big - 11, args.big - 11]])
    long_run = None
    if big.components[10, 10] and big.components[10, 10] == big.components[-11, -11]:
        long_run = plan(big, far[0], far[1], planner="fusion")

    out = {
        "machine": {"machine": platform.machine(), "cores": os.cpu_count(), "load": load0,
                    "python": platform.python_version()},
        "load_end": round(os.getloadavg()[0], 2),
        "paper_seeds": args.seeds,
        "fusion_success": fus_ok,
        "astar_time_median_s": statistics.median(t_astar),
        "fusion_time_median_s": statistics.median(t_fusion),
        "fusion_over_astar_median": statistics.median(ratios),
        "fusion_over_astar_p90": float(np.percentile(ratios, 90)),
        "fusion_over_astar_wall_median": statistics.median(wall_ratios),
        "apf_steps_per_s_paper": apf_small,
        "fusion_steps_per_s_paper": fus_small,
        "apf_steps_per_s_big": apf_big,
        "fusion_steps_per_s_big": fus_big,
        "apf_big_over_paper": apf_big / apf_small,
        "fusion_big_over_paper": fus_big / fus_small,
        "steps": {"apf_paper": apf_small_n, "fusion_paper": fus_small_n, "apf_big": apf_big_n,
                  "fusion_big": fus_big_n},
        "big_map": {"side": args.big, "generate_s": t_gen, "queries": len(qs)},
    }
    if long_run is not None:
        out["long_fusion"] = {
            "status": long_run.status.name,
            "length_m": long_run.length,
            "astar_length_m": long_run.info.get("astar_length"),
            "steps": long_run.iterations,
            "steps_per_s": long_run.info.get("steps_per_s"),
            "astar_time_s": long_run.info.get("astar_time_s"),
            "time_s": long_run.time_s,
        }

    print(f"paper maps: {args.seeds} seeds, fusion success {fus_ok}/{args.seeds}")
    print(f"  A* median {out['astar_time_median_s'] * 1e6:9.1f} us   "
          f"fusion median {out['fusion_time_median_s'] * 1e6:9.1f} us")
    print(f"  fusion / A* time_s: median {out['fusion_over_astar_median']:.2f}  "
          f"p90 {out['fusion_over_astar_p90']:.2f}   (the paper: 1.56 in MATLAB)")
    print(f"  fusion / A* wall time of the whole plan() call: median "
          f"{out['fusion_over_astar_wall_median']:.2f}")
    print("steps per second (stepping driver, dispatch included):")
    print(f"  {'':8s} {'paper 15x15':>14s} {f'{args.big}x{args.big}':>14s} {'big/paper':>10s}")
    print(f"  {'apf':8s} {apf_small:14.3e} {apf_big:14.3e} {apf_big / apf_small:10.2f}")
    print(f"  {'fusion':8s} {fus_small:14.3e} {fus_big:14.3e} {fus_big / fus_small:10.2f}")
    print("  (targets: >= 1e6 steps/s; big/paper >= 0.5)")
    if long_run is not None:
        lr = out["long_fusion"]
        print(f"long fusion run across the big map: {lr['status']}, {lr['steps']} steps, "
              f"{lr['steps_per_s']:.3e} steps/s, A* {lr['astar_time_s']:.3f} s, "
              f"length {lr['length_m']:.1f} m vs A* {lr['astar_length_m']:.1f} m")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
