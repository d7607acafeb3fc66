"""The glue around the A* kernel: what pathfuse.plan() costs beyond the search itself.

For every MovingAI map with a scenario file (the small ones included), on the
same seeded sample of scenario lines, each tool answering the whole sample in
a row (as a user's loop would), the tools alternating over ``--rounds``
rounds so that machine noise hits them alike:

* ``plan``: :func:`pathfuse.plan` as a user calls it (query checks, global
  planner, result with the world-coordinate path);
* ``kernel``: the searcher alone, ``get_searcher(grid).search(start_cell,
  goal_cell)`` - the A* kernel and its buffers, no query checks, no result;
* ``scipy``: ``scipy.sparse.csgraph.dijkstra(G, indices=start)`` plus the walk
  back along the predecessors (the CSR graph build is excluded; scipy has no
  A* and no early exit).

It prints the median microseconds per query, ``plan / kernel`` (the glue's
share; 1.0 = none) and ``scipy / plan``, and a tiny query (two neighbouring
cells of Boston_0_1024: the start and the goal are expanded) that exposes the
fixed cost of a call.
numba compilation and the per-map buffers are made by a warm-up query before
any timing.  Wall time and CPU time (``time.process_time``) are both printed,
with the load average and the core count: the machines are shared.

Usage::

    python benchmarks/bench_plan.py [--data DIR] [--queries 100] [--seed 0] [--repeat 2000]
        [--rounds 5] [--json out.json]
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

import numpy as np
from scipy.sparse.csgraph import dijkstra

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_astar import build_csr  # noqa: E402 - the same graph as the A* benchmark

import pathfuse  # noqa: E402
from pathfuse.io.movingai import read_movingai  # noqa: E402
from pathfuse.io.scenario import read_scen  # noqa: E402
from pathfuse.search.astar import get_searcher  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "movingai"


def timed(fn) -> tuple[float, float]:
    w0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w0, time.process_time() - c0


def tiny(data: Path, repeat: int) -> dict:
    g = read_movingai(data / "Boston_0_1024.map")
    free = np.argwhere(~g.occupied)
    r, c = (int(v) for v in free[len(free) // 2])
    nb = next((r + dr, c + dc) for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0))
              if not g.occupied[r + dr, c + dc])
    s = tuple(float(v) for v in g.cell_to_world([[r, c]])[0])
    e = tuple(float(v) for v in g.cell_to_world([nb])[0])
    searcher = get_searcher(g)
    pathfuse.plan(g, s, e)
    plan_w, plan_c, kern_w, kern_c = [], [], [], []
    for _ in range(repeat):
        w, cpu = timed(lambda: pathfuse.plan(g, s, e))
        plan_w.append(w)
        plan_c.append(cpu)
        w, cpu = timed(lambda: searcher.search((r, c), nb))
        kern_w.append(w)
        kern_c.append(cpu)
    pw, kw = statistics.median(plan_w), statistics.median(kern_w)
    exp = searcher.search((r, c), nb).expansions
    print(f"tiny query on Boston_0_1024 ({repeat} calls, {exp} expansions): plan() "
          f"{1e6 * pw:.1f} us (CPU {1e6 * statistics.median(plan_c):.1f}), kernel "
          f"{1e6 * kw:.1f} us (CPU {1e6 * statistics.median(kern_c):.1f}); fixed overhead "
          f"of plan() {1e6 * (pw - kw):.1f} us")
    return {"calls": repeat, "expansions": exp, "plan_us": 1e6 * pw, "kernel_us": 1e6 * kw,
            "plan_cpu_us": 1e6 * statistics.median(plan_c),
            "kernel_cpu_us": 1e6 * statistics.median(kern_c)}


def per_map(data: Path, queries: int, seed: int, rounds: int) -> dict:
    print(f"\n{'map':<32} {'n':>4} {'plan us':>10} {'kernel us':>10} {'plan/kernel':>11} "
          f"{'scipy us':>10} {'scipy/plan':>10}")
    out = {}
    for scen in sorted(data.glob("*.scen")):
        name = scen.name.split(".map")[0].split("-random-")[0]
        mp = data / f"{name}.map"
        if not mp.is_file():
            continue
        g = read_movingai(mp)
        probs = read_scen(scen, g)
        rng = np.random.default_rng(seed)
        pick = [probs[i] for i in sorted(rng.choice(len(probs), min(queries, len(probs)),
                                                    replace=False))]
        searcher = get_searcher(g)
        csr = build_csr(g.occupied, corner_cutting=False)
        w = g.width
        pathfuse.plan(g, pick[0].start, pick[0].goal)  # buffers, compilation

        def sp(p, csr=csr, w=w) -> None:
            src = p.start_cell[0] * w + p.start_cell[1]
            _, pred = dijkstra(csr, indices=src, return_predecessors=True)
            node = p.goal_cell[0] * w + p.goal_cell[1]
            while node != src and node >= 0:
                node = pred[node]

        tools = (lambda p, g=g: pathfuse.plan(g, p.start, p.goal),
                 lambda p, s=searcher: s.search(p.start_cell, p.goal_cell), sp)
        times: list[list[float]] = [[], [], []]
        for _ in range(rounds):  # each tool answers the whole sample in a row, as a user's
            for k, tool in enumerate(tools):  # loop would; the rounds alternate the tools
                for p in pick:
                    times[k].append(timed(lambda p=p, tool=tool: tool(p))[0])
        tp, tk, ts = times
        mp_, mk, ms = (statistics.median(v) for v in (tp, tk, ts))
        print(f"{name:<32} {len(pick):>4} {1e6 * mp_:>10.1f} {1e6 * mk:>10.1f} "
              f"{mp_ / mk:>11.2f} {1e6 * ms:>10.1f} {ms / mp_:>10.1f}")
        out[name] = {"queries": len(pick), "plan_us": 1e6 * mp_, "kernel_us": 1e6 * mk,
                     "scipy_us": 1e6 * ms}
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--queries", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--json", type=Path, help="write the numbers to this file")
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        sys.exit(f"no MovingAI data in {args.data} (pass --data)")
    load0 = round(os.getloadavg()[0], 2)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
          f"{load0:.2f}; python {platform.python_version()}; "
          f"pathfuse from {Path(pathfuse.__file__).parent}")
    res = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(), "load": load0,
                       "python": platform.python_version()},
           "tiny": tiny(args.data, args.repeat),
           "maps": per_map(args.data, args.queries, args.seed, args.rounds)}
    res["load_end"] = round(os.getloadavg()[0], 2)
    print(f"\nload average at the end: {res['load_end']:.2f}")
    if args.json:
        args.json.write_text(json.dumps(res, indent=1) + "\n")
    return res


if __name__ == "__main__":
    main()
