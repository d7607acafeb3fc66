"""Exact grid search speed on MovingAI maps: pathfuse's A* and jump point search against
scipy's Dijkstra and pyastar2d (C++), on the hardest queries and on mixed ones.

Queries
-------
* ``hard``: the ``--hard`` scenario lines of each map with the longest optimal length.
* ``mixed``: ``--mixed`` scenario lines drawn at random (seeded).

Tools (every one answers every query, in rotating order query by query, over
``--rounds`` rounds, so that machine noise hits them alike)
---------------------------------------------------------------------------
* ``astar``: :func:`pathfuse.plan` with its defaults (planner ``astar``, the
  Euclidean heuristic): query checks, search, world-coordinate path.
* ``astar-octile``: the same with ``heuristic="octile"``.
* ``search-octile``: the A* searcher alone (``get_searcher(grid).search_checked``,
  octile), the level at which jump point search is timed.
* ``jps``: jump point search (:mod:`pathfuse.search.jps`) through its searcher,
  the full cell path included.
* ``scipy``: ``scipy.sparse.csgraph.dijkstra(G, indices=start)`` and the walk back
  along its predecessors; scipy has no A* and no early exit, so this is a full
  single-source search.  Building the CSR graph is excluded.
* ``pyastar2d``: its C++ A* (``pyastar2d.astar.astar`` on weights flattened
  once; the Python wrapper's per-call ``min`` and ``flatten`` over the whole
  map are left out, which favours it).  It solves an easier problem than the
  others: corners may be cut, a diagonal costs 1 and its heuristic is
  Chebyshev's, so its paths are not shortest under the MovingAI rules (the
  ``len/opt`` column measures them under those rules).  The targets of issue 21
  are judged against this entry point.
* ``pyastar2d-public``: the same search through the function a pyastar2d user
  calls, ``pyastar2d.astar_path(weights, start, goal, allow_diagonal=True)``
  on the (H, W) float32 weights made once: each call checks ``weights.min()``
  and flattens the grid (a copy) before the C++ search.

Every pathfuse length is checked against the scenario's optimum (relative
1e-6) and every JPS path's straight and diagonal move counts against A*'s.
numba compilation and the per-map buffers and component labels are made by a
warm-up query on each map before timing, and are not in any figure.

Reported: the median CPU time (``time.process_time``) and wall time per query
of each tool, and per-query paired ratios (the median of ``other / astar``
over the queries of a set).  The machine (architecture, cores, load average at
the start and the end) is printed first: the machines are shared.

``--big N`` adds a map of N x N cells (Boston_0_1024 scaled up by N / 1024,
each cell becoming a square block) and times A* (both heuristics) and JPS on
its ``--big-queries`` longest scaled scenario lines: expansions per second of
CPU time, and the one-off cost of a new map (the searcher's buffers and the
component labels), which is paid by the first query and excluded above.

Usage::

    python benchmarks/bench_search.py [--data DIR] [--maps ...] [--hard 5] [--mixed 30]
        [--rounds 3] [--seed 0] [--big 4096] [--big-queries 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_astar import build_csr  # noqa: E402 - the same graph as the A* benchmark

import pathfuse  # noqa: E402
from pathfuse.grid import GridMap  # noqa: E402
from pathfuse.io.movingai import read_movingai  # noqa: E402
from pathfuse.io.scenario import read_scen  # noqa: E402
from pathfuse.search.astar import AStarSearcher, get_searcher  # noqa: E402
from pathfuse.search.jps import JPSSearcher, get_jps_searcher  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "movingai"
DEFAULT_MAPS = ["Boston_0_1024", "maze512-4-6", "64room_005", "den520d", "Boston_0_256",
                "maze-32-32-2"]
TOOLS = ["astar", "astar-octile", "search-octile", "jps", "scipy", "pyastar2d",
         "pyastar2d-public"]
SQRT2 = math.sqrt(2.0)


def machine() -> dict[str, Any]:
    """What the figures were measured on."""
    import numba

    return {"machine": platform.machine(), "cores": os.cpu_count(),
            "load": round(os.getloadavg()[0], 2), "python": platform.python_version(),
            "numpy": np.__version__, "numba": numba.__version__}


def moves(cells: np.ndarray) -> tuple[int, int]:
    d = np.abs(np.diff(np.asarray(cells), axis=0)).sum(axis=1)
    return int((d == 1).sum()), int((d == 2).sum())


def cell_path_length(cells: np.ndarray) -> float:
    a, b = moves(cells)
    return a + b * SQRT2


def scen_file(data: Path, name: str) -> Path:
    for cand in (data / f"{name}.map.scen", data / f"{name}-random-1.scen"):
        if cand.is_file():
            return cand
    raise SystemExit(f"no scenario file for {name} in {data}")


def make_tools(g: GridMap) -> dict[str, Callable[[Any], float]]:
    """One callable per tool: a scenario problem in, the path length (cells) out."""
    res = g.resolution
    origin = (float(g.origin[0]), float(g.origin[1]), float(res))
    search = get_searcher(g)
    jps = get_jps_searcher(g)
    csr = build_csr(g.occupied, corner_cutting=False)
    h, w = g.shape
    weights = np.where(g.occupied, np.inf, 1.0).astype(np.float32).ravel()
    tools: dict[str, Callable[[Any], float]] = {
        "astar": lambda p: pathfuse.plan(g, p.start, p.goal).length / res,
        "astar-octile": lambda p: pathfuse.plan(g, p.start, p.goal,
                                                heuristic="octile").length / res,
        "search-octile": lambda p: search.search_checked(p.start_cell, p.goal_cell, "octile",
                                                         None, None, origin).cost,
        "jps": lambda p: jps.search_checked(p.start_cell, p.goal_cell, "octile", None, None,
                                            origin).cost,
    }

    def scipy_dijkstra(p: Any) -> float:
        from scipy.sparse.csgraph import dijkstra

        src = p.start_cell[0] * w + p.start_cell[1]
        dist, pred = dijkstra(csr, indices=src, return_predecessors=True)
        node = p.goal_cell[0] * w + p.goal_cell[1]
        out = float(dist[node])
        while node != src and node >= 0:
            node = pred[node]
        return out

    tools["scipy"] = scipy_dijkstra
    try:
        import pyastar2d
        import pyastar2d.astar as pa

        def pyastar(p: Any) -> float:
            path = pa.astar(weights, h, w, p.start_cell[0] * w + p.start_cell[1],
                            p.goal_cell[0] * w + p.goal_cell[1], True, 0)
            return cell_path_length(path)

        grid2d = weights.reshape(h, w)  # what a pyastar2d user passes: (H, W) float32

        def pyastar_public(p: Any) -> float:
            path = pyastar2d.astar_path(grid2d, p.start_cell, p.goal_cell, allow_diagonal=True)
            return cell_path_length(path)

        tools["pyastar2d"] = pyastar
        tools["pyastar2d-public"] = pyastar_public
    except ImportError:
        pass
    return tools


def timed(fn: Callable[[], Any]) -> tuple[float, float, Any]:
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - c0, out


def run_set(g: GridMap, probs: list, tools: dict[str, Callable[[Any], float]],
            rounds: int) -> dict[str, Any]:
    """Every tool on every problem, rotating the order; medians and paired ratios."""
    names = list(tools)
    wall: dict[str, list[list[float]]] = {n: [[] for _ in probs] for n in names}
    cpu: dict[str, list[list[float]]] = {n: [[] for _ in probs] for n in names}
    lengths: dict[str, list[float]] = {n: [0.0] * len(probs) for n in names}
    k = 0
    for _ in range(rounds):
        for i, p in enumerate(probs):
            order = names[k % len(names):] + names[:k % len(names)]
            k += 1
            for n in order:
                tw, tc, length = timed(lambda n=n, p=p: tools[n](p))
                wall[n][i].append(tw)
                cpu[n][i].append(tc)
                lengths[n][i] = length
    res = g.resolution
    for n in ("astar", "astar-octile", "search-octile", "jps", "scipy"):
        for p, length in zip(probs, lengths[n], strict=True):
            opt = p.optimal_length / res
            if abs(length - opt) > 1e-6 * max(1.0, opt):
                raise SystemExit(f"{n}: length {length} != optimum {opt} ({p.line})")
    if "pyastar2d-public" in lengths:  # one C++ search behind both entry points
        assert lengths["pyastar2d-public"] == lengths["pyastar2d"]
    out: dict[str, Any] = {"queries": len(probs), "tools": {}}
    base_c = [statistics.median(v) for v in cpu["astar"]]
    base_w = [statistics.median(v) for v in wall["astar"]]
    for n in names:
        per_c = [statistics.median(v) for v in cpu[n]]
        per_w = [statistics.median(v) for v in wall[n]]
        entry = {"cpu_ms": 1e3 * statistics.median(per_c),
                 "wall_ms": 1e3 * statistics.median(per_w),
                 "cpu_ratio": statistics.median(c / max(b, 1e-9)
                                                for c, b in zip(per_c, base_c, strict=True)),
                 "wall_ratio": statistics.median(c / max(b, 1e-9)
                                                 for c, b in zip(per_w, base_w, strict=True))}
        if n.startswith("pyastar2d"):
            entry["len_over_opt"] = [min(r), max(r)] if (r := [
                length / (p.optimal_length / res) for p, length in zip(probs, lengths[n],
                                                                        strict=True)
                if p.optimal_length > 0]) else [1.0, 1.0]
        out["tools"][n] = entry
    c = {n: [statistics.median(v) for v in cpu[n]] for n in names}
    out["jps_vs_search_octile"] = statistics.median(
        a / max(b, 1e-9) for a, b in zip(c["search-octile"], c["jps"], strict=True))
    out["jps_vs_astar"] = statistics.median(
        a / max(b, 1e-9) for a, b in zip(c["astar"], c["jps"], strict=True))
    return out


def per_map(data: Path, name: str, hard: int, mixed: int, seed: int,
            rounds: int) -> dict[str, Any]:
    g = read_movingai(data / f"{name}.map")
    probs = [p for p in read_scen(scen_file(data, name), g) if p.optimal_length > 0]
    longest = sorted(probs, key=lambda p: (-p.optimal_length, p.line))[:hard]
    rng = np.random.default_rng(seed)
    pick = [probs[i] for i in sorted(rng.choice(len(probs), min(mixed, len(probs)),
                                                replace=False))]
    tools = make_tools(g)
    for fn in tools.values():  # compilation, buffers and labels: before any clock
        fn(pick[0])
    a, j = (get_searcher(g).search(longest[0].start_cell, longest[0].goal_cell, "octile"),
            get_jps_searcher(g).search(longest[0].start_cell, longest[0].goal_cell))
    assert moves(a.cells) == moves(j.cells)
    return {"shape": list(g.shape), "hard": run_set(g, longest, tools, rounds),
            "mixed": run_set(g, pick, tools, rounds)}


def big(data: Path, side: int, nq: int) -> dict[str, Any]:
    """A side x side map (Boston_0_1024 scaled up): expansions per CPU second, one-off
    costs of a new map."""
    src = read_movingai(data / "Boston_0_1024.map")
    k = side // src.shape[0]
    occ = np.kron(src.occupied, np.ones((k, k), dtype=bool))
    probs = sorted(read_scen(scen_file(data, "Boston_0_1024"), src),
                   key=lambda p: (-p.optimal_length, p.line))[:nq]
    queries = [((p.start_cell[0] * k, p.start_cell[1] * k),
                (p.goal_cell[0] * k, p.goal_cell[1] * k)) for p in probs]
    out: dict[str, Any] = {"side": side, "queries": nq}
    g = GridMap(occ)
    _, t_lab, _ = timed(lambda: g.components)
    _, t_buf, searcher = timed(lambda: AStarSearcher(g.occupied, labels=g.components))
    _, t_jbuf, jps = timed(lambda: JPSSearcher(g.occupied, labels=g.components))
    out["labels_cpu_s"], out["astar_buffers_cpu_s"], out["jps_buffers_cpu_s"] = \
        t_lab, t_buf, t_jbuf
    for tag, fn in (("astar-euclidean", lambda a, b: searcher.search(a, b, "euclidean")),
                    ("astar-octile", lambda a, b: searcher.search(a, b, "octile")),
                    ("jps", lambda a, b: jps.search(a, b))):
        fn(*queries[0])  # the pages of the buffers this search touches: first touch
        cpu, wall, exp = [], [], 0
        for a, b in queries:
            tw, tc, r = timed(lambda a=a, b=b, fn=fn: fn(a, b))
            cpu.append(tc)
            wall.append(tw)
            exp += r.expansions
        out[tag] = {"cpu_ms": 1e3 * statistics.median(cpu),
                    "wall_ms": 1e3 * statistics.median(wall),
                    "mexp_per_cpu_s": exp / sum(cpu) / 1e6, "expansions": exp // nq}
    return out


def report(res: dict[str, Any]) -> None:
    m = res["machine"]
    print(f"machine: {m['machine']}, {m['cores']} cores, load average {m['load']} at the "
          f"start, {res['load_end']} at the end; python {m['python']}, numpy {m['numpy']}, "
          f"numba {m['numba']}")
    for name, r in res["maps"].items():
        for part in ("hard", "mixed"):
            s = r[part]
            print(f"\n{name} {r['shape'][0]}x{r['shape'][1]}, {part} ({s['queries']} queries): "
                  f"median ms CPU / wall, and CPU ratio to astar (paired median)")
            for n, t in s["tools"].items():
                extra = (f"  len/opt {t['len_over_opt'][0]:.2f}-{t['len_over_opt'][1]:.2f}"
                         if "len_over_opt" in t else "")
                print(f"  {n:<14} {t['cpu_ms']:9.3f} {t['wall_ms']:9.3f}  "
                      f"x{t['cpu_ratio']:.2f}{extra}")
            print(f"  jps: {s['jps_vs_search_octile']:.2f}x faster than the octile A* "
                  f"searcher, {s['jps_vs_astar']:.2f}x than plan() with the defaults")
    if "big" in res:
        b = res["big"]
        print(f"\n{b['side']}x{b['side']} (Boston_0_1024 scaled up), {b['queries']} longest "
              f"queries: labels {b['labels_cpu_s']:.2f} s, A* buffers "
              f"{b['astar_buffers_cpu_s']:.2f} s, JPS buffers {b['jps_buffers_cpu_s']:.2f} s "
              f"CPU (once per map)")
        for tag in ("astar-euclidean", "astar-octile", "jps"):
            t = b[tag]
            print(f"  {tag:<16} {t['cpu_ms']:9.1f} ms CPU {t['wall_ms']:9.1f} ms wall, "
                  f"{t['expansions']} expansions, {t['mexp_per_cpu_s']:.1f} M/s CPU")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--maps", nargs="+", default=DEFAULT_MAPS)
    ap.add_argument("--hard", type=int, default=5)
    ap.add_argument("--mixed", type=int, default=30)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--big", type=int, default=4096, help="side of the big map (0: none)")
    ap.add_argument("--big-queries", type=int, default=3)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        sys.exit(f"no MovingAI data in {args.data} (pass --data)")
    res: dict[str, Any] = {"machine": machine(), "maps": {}}
    for name in args.maps:
        res["maps"][name] = per_map(args.data, name, args.hard, args.mixed, args.seed,
                                    args.rounds)
    if args.big:
        res["big"] = big(args.data, args.big, args.big_queries)
    res["load_end"] = round(os.getloadavg()[0], 2)
    report(res)
    if args.json:
        args.json.write_text(json.dumps(res, indent=1) + "\n")
    return res


if __name__ == "__main__":
    main()
