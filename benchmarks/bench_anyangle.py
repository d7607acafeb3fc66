"""Any-angle planners against grid A*, and the cost of the true shortest path.

Part 1 (MovingAI maps): the same seeded sample of scenario lines per map is
planned by ``astar``, ``astar-smooth``, ``thetastar`` and ``lazy-thetastar``
through the public :func:`pathfuse.plan`, interleaved query by query so that
machine noise hits them alike.  Reported per planner: median wall and CPU ms
per query, the ratio of its median time to A*'s, and the median and minimum of
its length over A*'s length (A*: no corner cutting, euclidean heuristic, the
default).  Every path is checked collision-free by :mod:`pathfuse.metrics`.

Part 2 (``shortest``): the cost of the visibility-graph shortest path through
:func:`pathfuse.plan` on the paper's maps (``--paper-seeds`` maps, median ms,
against A* on the same maps) and on 512-cell maps (``--big`` maps, a few scen
lines each: time per query, the number of convex corners, expansions), and
each planner's length over the shortest path.

numba compilation is kept out of every timing: each planner plans one query
on each MovingAI map before the clock starts (this also builds A*'s per-map
buffers and the cached corner list of ``shortest``; the corner extraction is
timed separately).  On the paper maps only A*'s per-map buffers are built
before the clock: ``shortest``'s corner extraction is part of its time there.

Usage::

    python benchmarks/bench_anyangle.py [--maps maze512-4-6 64room_005 Boston_0_1024 den312d]
        [--queries 30] [--paper-seeds 300] [--big maze512-4-6 64room_005] [--big-queries 5]
        [--seed 0] [--data DIR] [--part 1|2] [--json out.json]

With ``--json PATH`` it also writes the figures, the machine and the load
(``benchmarks/run_all.py`` writes the speed page's ``anyangle`` block from them).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import pathfuse
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.io.movingai import read_movingai
from pathfuse.io.scenario import read_scen
from pathfuse.metrics import collision_free

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "movingai"
ANY = ("astar", "astar-smooth", "thetastar", "lazy-thetastar")


def timed(name, grid, start, goal):
    w0, c0 = time.perf_counter(), time.process_time()
    r = pathfuse.plan(grid, start, goal, planner=name)
    return r, time.perf_counter() - w0, time.process_time() - c0


def part1(names, data, n_queries, seed):
    out = []
    print("\n## Theta*, Lazy Theta* and smoothed A* against A* (MovingAI scen lines)\n")
    print("| map | planner | wall ms (median) | CPU ms | wall / A* | CPU / A* | length / A* "
          "median | min | collision-free |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in names:
        mp, sc = data / f"{name}.map", data / f"{name}.map.scen"
        if not (mp.exists() and sc.exists()):
            print(f"(skipped {name}: no map or scen file in {data})")
            continue
        grid = read_movingai(mp)
        probs = read_scen(sc, grid)
        rng = np.random.default_rng(seed)
        sample = [probs[i] for i in rng.choice(len(probs), min(n_queries, len(probs)),
                                               replace=False)]
        for pl in ANY:  # warm-up: compilation, per-map buffers
            pathfuse.plan(grid, sample[0].start, sample[0].goal, planner=pl)
        wall = {p: [] for p in ANY}
        cpu = {p: [] for p in ANY}
        ratio = {p: [] for p in ANY}
        free = dict.fromkeys(ANY, 0)
        for p in sample:
            ref = None
            for pl in ANY:
                r, w, c = timed(pl, grid, p.start, p.goal)
                assert r.success, (name, pl, r.message)
                wall[pl].append(w)
                cpu[pl].append(c)
                free[pl] += collision_free(grid, r.path)
                if pl == "astar":
                    ref = r.length
                ratio[pl].append(r.length / ref)
        a = statistics.median(wall["astar"])
        ac = statistics.median(cpu["astar"])
        for pl in ANY:
            m = statistics.median(wall[pl])
            mc = statistics.median(cpu[pl])
            print(f"| {name} | {pl} | {1e3 * m:.2f} | {1e3 * mc:.2f} | {m / a:.2f} | "
                  f"{mc / ac:.2f} | {statistics.median(ratio[pl]):.4f} | {min(ratio[pl]):.4f} "
                  f"| {free[pl]}/{len(sample)} |")
            out.append({"map": name, "planner": pl, "wall_ms": 1e3 * m, "cpu_ms": 1e3 * mc,
                        "cpu_over_astar": mc / ac, "length_over_astar": statistics.median(
                            ratio[pl]), "min_length_over_astar": min(ratio[pl]),
                        "collision_free": free[pl], "queries": len(sample)})
    return out


def part2(big, data, n_paper, n_big, seed):
    out: dict = {"paper_maps": n_paper, "paper": [], "big": []}
    print(f"\n## shortest on {n_paper} paper maps (through plan(), median over maps)\n")
    names = ("astar", "astar-smooth", "thetastar", "shortest")
    g0 = paper_map(0)
    for pl in names:
        pathfuse.plan(g0, PAPER_START, PAPER_GOAL, planner=pl)
    wall = {p: [] for p in names}
    cpu = {p: [] for p in names}
    length = {p: [] for p in names}
    for s in range(n_paper):
        g = paper_map(s)
        # A*'s per-map buffers and connectivity labels (used by astar and astar-smooth) are
        # built before the clock starts, as for the MovingAI maps; shortest's corner list is
        # built in its timed call (it is part of its cost on a new map)
        pathfuse.plan(g, PAPER_START, PAPER_GOAL, planner="astar")
        for pl in names:
            r, w, c = timed(pl, g, PAPER_START, PAPER_GOAL)
            wall[pl].append(w)
            cpu[pl].append(c)
            length[pl].append(r.length)
    low = np.array(length["shortest"])
    print("| planner | wall ms (median) | CPU ms | wall / A* | CPU / A* | excess over shortest "
          "(mean) |")
    print("|---|---|---|---|---|---|")
    a = statistics.median(wall["astar"])
    ac = statistics.median(cpu["astar"])
    for pl in names:
        m = statistics.median(wall[pl])
        mc = statistics.median(cpu[pl])
        ex = float(np.mean(np.array(length[pl]) / low - 1.0))
        print(f"| {pl} | {1e3 * m:.3f} | {1e3 * mc:.3f} | {m / a:.2f} | {mc / ac:.2f} | "
              f"{100 * ex:+.2f} % |")
        out["paper"].append({"planner": pl, "wall_ms": 1e3 * m, "cpu_ms": 1e3 * mc,
                             "cpu_over_astar": mc / ac, "excess_over_shortest": ex})

    print("\n## shortest on 512-cell maps (a few scen lines each)\n")
    print("| map | corners | corner extraction ms | query | shortest s (wall) | CPU s "
          "| expansions | A* ms (wall) | A* CPU ms | length / A* |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    from pathfuse.search.visibility import convex_corners, growth_cells

    for name in big:
        mp, sc = data / f"{name}.map", data / f"{name}.map.scen"
        if not (mp.exists() and sc.exists()):
            print(f"(skipped {name}: no map or scen file in {data})")
            continue
        grid = read_movingai(mp)
        t0 = time.perf_counter()
        xs, _, _ = convex_corners(grid.occupied, growth_cells(0.0, grid.resolution))
        t_corners = time.perf_counter() - t0
        probs = read_scen(sc, grid)
        rng = np.random.default_rng(seed)
        # the longest lines of the file's last bucket: the hardest queries
        idx = sorted(range(len(probs)), key=lambda i: -probs[i].optimal_length)[:50]
        pick = [probs[i] for i in rng.choice(idx, min(n_big, len(idx)), replace=False)]
        pathfuse.plan(grid, pick[0].start, pick[0].goal, planner="astar")
        for q, p in enumerate(pick):
            r, w, c = timed("shortest", grid, p.start, p.goal)
            ra, wa, ca = timed("astar", grid, p.start, p.goal)
            print(f"| {name} | {len(xs)} | {1e3 * t_corners:.1f} | {q} | {w:.3f} | {c:.3f} | "
                  f"{r.expansions} | {1e3 * wa:.1f} | {1e3 * ca:.1f} | "
                  f"{r.length / ra.length:.4f} |")
            out["big"].append({"map": name, "corners": len(xs), "query": q, "cpu_s": c,
                               "expansions": int(r.expansions), "astar_cpu_ms": 1e3 * ca,
                               "length_over_astar": r.length / ra.length})
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", nargs="+",
                    default=["maze512-4-6", "64room_005", "Boston_0_1024", "den312d"])
    ap.add_argument("--queries", type=int, default=30)
    ap.add_argument("--paper-seeds", type=int, default=300)
    ap.add_argument("--big", nargs="+", default=["maze512-4-6", "64room_005"])
    ap.add_argument("--big-queries", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--part", type=int, choices=[1, 2], help="run only part 1 or part 2")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    res: dict = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(),
                             "load": round(os.getloadavg()[0], 2),
                             "python": platform.python_version()}}
    print(f"# bench_anyangle: {platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.2f} at the start; numpy {np.__version__}")
    if args.part != 2:
        res["part1"] = part1(args.maps, args.data, args.queries, args.seed)
    if args.part != 1:
        res["part2"] = part2(args.big, args.data, args.paper_seeds, args.big_queries, args.seed)
    res["load_end"] = round(os.getloadavg()[0], 2)
    print(f"\nload average {res['load_end']:.2f} at the end")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2))
    return res


if __name__ == "__main__":
    main()
