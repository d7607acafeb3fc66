"""Where a small map's ``plan()`` spends its time in ``bench_search.py``'s rotation, layer by
layer (issue 21).

Each layer is timed in the ``astar`` slot of ``bench_search.py``'s rotation of tools (its
``make_tools``: the same six tools in the same order, ``astar`` replaced by the layer), so
that it finds the caches as ``plan()`` finds them there: right after pyastar2d, itself
after scipy's Dijkstra.  Layers, outermost first:

* ``plan``: :func:`pathfuse.plan` with its defaults (where the code has it, through
  ``run.quick_plan``, without a ``Problem``);
* ``create+solve``: ``Problem.create`` then ``run.solve`` (no registry look-up);
* ``solve(pre)``: ``run.solve`` on a problem made beforehand;
* ``lane(pre)``: the lane ``run._astar_as_planned`` on a problem made beforehand;
* ``search_checked``: the map's A* searcher (``SearchResult`` included);
* ``kernel``: the euclidean kernel's compiled entry alone (it traces the path when the
  code has the trace in the kernel; an older code's separate trace is left out), with the
  buffers as the code passes them (packed by dtype, or one array each);
* ``noop``: an empty call (the timer's own cost).

Queries: the hardest (``--hard`` longest scenario lines) and mixed ones (``--mixed``
lines drawn with ``--seed``), as in ``bench_search.py``.  Printed (one JSON line, also
appended to ``--out``): per layer the median CPU time per query (µs, medians over the
rounds, then over the queries) and the median per-query ratio of pyastar2d's time to the
layer's, plus the load average.  ``PYTHONPATH`` picks the code: run it alternately on two
checkouts to compare them.

Usage::

    python benchmarks/plan_layers.py [--map maze-32-32-2] [--reps 3] [--out layers.jsonl]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_search as bs  # noqa: E402 - the same tools and queries

import pathfuse  # noqa: E402
from pathfuse.io.movingai import read_movingai  # noqa: E402
from pathfuse.io.scenario import read_scen  # noqa: E402
from pathfuse.planners.registry import get_planner, make_params  # noqa: E402
from pathfuse.planners.run import _astar_as_planned, solve  # noqa: E402
from pathfuse.problem import Problem  # noqa: E402
from pathfuse.search import astar as A  # noqa: E402


def layers(g: Any) -> dict[str, Any]:
    """One callable per layer: a scenario problem in."""
    spec = get_planner("astar")
    cfg = make_params(spec, None)
    origin = (float(g.origin[0]), float(g.origin[1]), float(g.resolution))
    s = A.get_searcher(g)
    made: dict[int, Problem] = {}

    def problem(p: Any) -> Problem:
        q = made.get(id(p))
        if q is None:
            q = made[id(p)] = Problem.create(g, p.start, p.goal, 0.0, None, 0.0, None)
        return q

    def kernel(p: Any) -> int:
        (sr, sc), (gr, gc) = p.start_cell, p.goal_cell
        wp = s._wp
        s._gen += 2
        start = (sr + 1) * wp + sc + 1
        goal = (gr + 1) * wp + gc + 1
        args: tuple[Any, ...]
        if hasattr(s, "_u64"):  # the buffers packed by dtype
            args = (s._cell, s._f8, s._u64, s._i32, s._meta, s._gen, start, goal, wp, False,
                    s.free_count, start, 0.0, 0.0, 1.0)
        else:
            args = (s._cell, s._g, s._qkey, s._qnode, s._qnext, s._heads, s._bits, s._skey,
                    s._snode, s._meta, s._cq, s._cf, s._gen, start, goal, wp, False,
                    s.free_count)
            if s._meta.size >= 6:  # the kernel that traces the path itself
                args += (start, 0.0, 0.0, 1.0)
        return int(A._KERNEL_ENTRY["euclidean"](*args)[1])

    return {
        "plan": lambda p: pathfuse.plan(g, p.start, p.goal),
        "create+solve": lambda p: solve(spec, Problem.create(g, p.start, p.goal, 0.0, None,
                                                             0.0, None), cfg),
        "solve(pre)": lambda p: solve(spec, problem(p), cfg),
        "lane(pre)": lambda p: _astar_as_planned(spec, problem(p), cfg),
        "search_checked": lambda p: s.search_checked(p.start_cell, p.goal_cell, "euclidean",
                                                     None, None, origin),
        "kernel": kernel,
        "noop": lambda p: None,
    }


def measure(probs: list, tools: dict[str, Any], lays: dict[str, Any],
            reps: int) -> dict[str, Any]:
    names = list(tools)
    cpu = {lay: {n: [[] for _ in probs] for n in names} for lay in lays}
    k = 0
    for _ in range(reps):
        for lay, fn in lays.items():
            for i, p in enumerate(probs):
                order = names[k % len(names):] + names[:k % len(names)]
                k += 1
                for n in order:
                    f = fn if n == "astar" else tools[n]
                    c0 = time.process_time()
                    f(p)
                    cpu[lay][n][i].append(time.process_time() - c0)
    out: dict[str, Any] = {}
    for lay in lays:
        a = [statistics.median(v) for v in cpu[lay]["astar"]]
        pa = [statistics.median(v) for v in cpu[lay]["pyastar2d"]]
        out[lay] = (round(1e6 * statistics.median(a), 2),
                    round(statistics.median(y / max(x, 1e-9) for x, y in zip(a, pa,
                                                                           strict=True)), 3))
    first = next(iter(lays))
    out["pyastar2d"] = round(1e6 * statistics.median(
        statistics.median(v) for v in cpu[first]["pyastar2d"]), 2)
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=bs.DEFAULT_DATA)
    ap.add_argument("--map", default="maze-32-32-2")
    ap.add_argument("--hard", type=int, default=5)
    ap.add_argument("--mixed", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--out", type=Path, help="append the JSON line to this file")
    args = ap.parse_args(argv)
    g = read_movingai(args.data / f"{args.map}.map")
    probs = [p for p in read_scen(bs.scen_file(args.data, args.map), g) if p.optimal_length > 0]
    longest = sorted(probs, key=lambda p: (-p.optimal_length, p.line))[:args.hard]
    rng = np.random.default_rng(args.seed)
    pick = [probs[i] for i in sorted(rng.choice(len(probs), min(args.mixed, len(probs)),
                                                replace=False))]
    tools = bs.make_tools(g)
    if "pyastar2d" not in tools:
        sys.exit("pyastar2d is not installed")
    lays = layers(g)
    for p in pick[:2]:  # compilation, buffers and labels: before any clock
        for fn in list(tools.values()) + list(lays.values()):
            fn(p)
    res: dict[str, Any] = {"map": args.map, "code": os.environ.get("PYTHONPATH", ""),
                           "load0": os.getloadavg()[0]}
    res["hard"] = measure(longest, tools, lays, args.reps)
    res["mixed"] = measure(pick, tools, lays, args.reps)
    res["load1"] = os.getloadavg()[0]
    line = json.dumps(res)
    print(line)
    if args.out:
        with args.out.open("a") as f:
            f.write(line + "\n")
    return res


if __name__ == "__main__":
    main()
