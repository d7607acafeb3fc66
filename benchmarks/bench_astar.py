"""Grid A* speed: pathfuse vs scipy.sparse.csgraph, tcod and networkx on MovingAI problems.

All tools answer the *same* randomly sampled scenario lines of each map (seeded),
one query at a time, interleaved query by query so that machine noise hits them
alike.  Reported: median milliseconds per query, the ratio to pathfuse (same
corner rule), and the largest relative deviation of each tool's path length
from the scenario's optimal length (every path's length is recomputed from its
cells, and every path is checked to be 8-connected, obstacle-free and, under the
no-corner-cutting rule, free of cut corners).

What is and is not timed
------------------------
* pathfuse: :func:`pathfuse.plan` (query checks, search, world-coordinate path).
  numba compilation and the per-map buffers are made by a warm-up query before
  timing (excluded); every later query reuses the map's buffers.
* scipy: ``dijkstra(G, indices=start, return_predecessors=True)`` plus the walk
  back along the predecessors.  scipy has no A* and no single-target stop, so
  this is a full single-source search.  Building the CSR graph is excluded.
* tcod (libtcod): integer edge costs (straight 100000, diagonal 141421, the
  closest a user gets to sqrt(2) with int32 distances on these maps).
  - no corner cutting: ``tcod.path.CustomGraph`` with the 4 straight edges and
    4 diagonal edges whose ``condition`` array marks the cells where both
    orthogonal neighbours are free, ``set_heuristic`` (octile-like), then per
    query the faster of a new ``Pathfinder`` and a reused one after ``clear()``.
    The graph build is excluded.
  - corner cutting allowed (what ``SimpleGraph``, ``path2d`` and the old
    ``AStar`` do; they cannot forbid it): ``tcod.path.path2d`` (one call per
    query, nothing to exclude) and the old float ``tcod.path.AStar(cost,
    diagonal=sqrt(2))``, which stops when the goal is first *reached*, not
    expanded, so its paths need not be optimal (the length column shows it).
* networkx: ``astar_path`` with a euclidean heuristic on the same CSR graph
  (``from_scipy_sparse_array``; build excluded), on ``--nx-queries`` queries only.

Usage::

    python benchmarks/bench_astar.py [--maps maze512-4-6 64room_005 Boston_0_1024]
        [--queries 60] [--seed 0] [--nx-queries 3] [--data DIR] [--json out.json]

``--json`` writes ``{"machine", "load_end", "queries", "seed", "rows"}`` (a row per map,
tool and corner rule), what ``benchmarks/run_all.py`` renders into docs/speed.md.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import scipy.sparse
from scipy.sparse.csgraph import dijkstra

import pathfuse
from pathfuse.io.movingai import read_movingai
from pathfuse.io.scenario import read_scen

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "movingai"
DEFAULT_MAPS = ["maze512-4-6", "64room_005", "Boston_0_1024"]
SQRT2 = math.sqrt(2.0)
TCOD_STRAIGHT, TCOD_DIAGONAL = 100_000, 141_421

# (dr, dc) of the 8 moves
MOVES = [(0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1)]


def build_csr(occ: np.ndarray, corner_cutting: bool) -> scipy.sparse.csr_matrix:
    """Directed 8-connected grid graph (node = row * W + col), vectorised."""
    h, w = occ.shape
    free = ~occ
    pad = np.zeros((h + 2, w + 2), dtype=bool)
    pad[1:-1, 1:-1] = free
    idx = np.arange(h * w).reshape(h, w)
    src, dst, cost = [], [], []
    for dr, dc in MOVES:
        ok = free & pad[1 + dr:1 + dr + h, 1 + dc:1 + dc + w]
        if dr and dc and not corner_cutting:
            ok &= pad[1 + dr:1 + dr + h, 1:1 + w] & pad[1:1 + h, 1 + dc:1 + dc + w]
        r, c = np.nonzero(ok)
        src.append(idx[r, c])
        dst.append(idx[r + dr, c + dc])
        cost.append(np.full(len(r), SQRT2 if dr and dc else 1.0))
    return scipy.sparse.csr_matrix(
        (np.concatenate(cost), (np.concatenate(src), np.concatenate(dst))), shape=(h * w, h * w)
    )


def cells_length(cells: np.ndarray) -> float:
    d = np.abs(np.diff(np.asarray(cells), axis=0))
    diag = int(np.count_nonzero((d == 1).all(axis=1)))
    return (len(d) - diag) + diag * SQRT2


def check_cells(occ: np.ndarray, cells: np.ndarray, s, g, corner_cutting: bool) -> str:
    """'' if the path is valid, else what is wrong."""
    cells = np.asarray(cells)
    if len(cells) == 0:
        return "no path"
    if tuple(cells[0]) != tuple(s) or tuple(cells[-1]) != tuple(g):
        return "wrong ends"
    if occ[cells[:, 0], cells[:, 1]].any():
        return "enters an obstacle"
    d = np.diff(cells, axis=0)
    if len(d) and (np.abs(d).max(axis=1) != 1).any():
        return "not 8-connected"
    if not corner_cutting:
        diag = (d != 0).all(axis=1)
        r, c = cells[:-1][diag].T
        dr, dc = d[diag].T
        if (occ[r + dr, c] | occ[r, c + dc]).any():
            return "cuts a corner"
    return ""


# ----------------------------------------------------------------------------- tools
def tool_pathfuse(grid, heuristic: str, corner_cutting: bool) -> Callable:
    def run(p):
        r = pathfuse.plan(grid, p.start, p.goal, heuristic=heuristic, corner_cutting=corner_cutting)
        return r.info.get("cells", np.zeros((0, 2), dtype=int))

    return run


def tool_scipy(graph, w: int) -> Callable:
    def run(p):
        s = p.start_cell[0] * w + p.start_cell[1]
        t = p.goal_cell[0] * w + p.goal_cell[1]
        _, pred = dijkstra(graph, indices=s, return_predecessors=True)
        if pred[t] < 0 and t != s:
            return np.zeros((0, 2), dtype=int)
        out = [t]
        while out[-1] != s:
            out.append(pred[out[-1]])
        nodes = np.array(out[::-1])
        return np.stack([nodes // w, nodes % w], axis=1)

    return run


def tcod_custom_graph(occ: np.ndarray):
    import tcod.path

    h, w = occ.shape
    free = ~occ
    pad = np.zeros((h + 2, w + 2), dtype=bool)
    pad[1:-1, 1:-1] = free
    cost = free.astype(np.int8)
    graph = tcod.path.CustomGraph((h, w))
    straight = [[0, TCOD_STRAIGHT, 0], [TCOD_STRAIGHT, 0, TCOD_STRAIGHT], [0, TCOD_STRAIGHT, 0]]
    graph.add_edges(edge_map=straight, cost=cost)
    for dr in (-1, 1):
        for dc in (-1, 1):
            both = free & pad[1 + dr:1 + dr + h, 1:1 + w] & pad[1:1 + h, 1 + dc:1 + dc + w]
            graph.add_edge((dr, dc), TCOD_DIAGONAL, cost=cost, condition=both.astype(np.int8))
    graph.set_heuristic(cardinal=TCOD_STRAIGHT, diagonal=TCOD_DIAGONAL)
    return graph


def tool_tcod_new(graph) -> Callable:
    import tcod.path

    def run(p):
        pf = tcod.path.Pathfinder(graph)
        pf.add_root(p.start_cell)
        return pf.path_to(p.goal_cell)

    return run


def tool_tcod_reuse(graph) -> Callable:
    import tcod.path

    pf = tcod.path.Pathfinder(graph)

    def run(p):
        pf.clear()
        pf.add_root(p.start_cell)
        return pf.path_to(p.goal_cell)

    return run


def tool_tcod_path2d(occ: np.ndarray) -> Callable:
    import tcod.path

    cost = (~occ).astype(np.int32)

    def run(p):
        return tcod.path.path2d(
            cost, start_points=[p.start_cell], end_points=[p.goal_cell],
            cardinal=TCOD_STRAIGHT, diagonal=TCOD_DIAGONAL,
        )

    return run


def tool_tcod_old_astar(occ: np.ndarray) -> Callable:
    import tcod.path

    astar = tcod.path.AStar((~occ).astype(np.int8), diagonal=SQRT2)

    def run(p):
        # with a numpy cost array, AStar takes (i, j) indices of that array
        path = astar.get_path(*p.start_cell, *p.goal_cell)
        if not path:
            return np.zeros((0, 2), dtype=int)
        return np.array([p.start_cell, *path])

    return run


def tool_networkx(graph, w: int) -> Callable:
    import networkx as nx

    G = nx.from_scipy_sparse_array(graph, create_using=nx.DiGraph)

    def h(a, b):
        return math.hypot(a // w - b // w, a % w - b % w)

    def run(p):
        s = p.start_cell[0] * w + p.start_cell[1]
        t = p.goal_cell[0] * w + p.goal_cell[1]
        nodes = np.array(nx.astar_path(G, s, t, heuristic=h, weight="weight"))
        return np.stack([nodes // w, nodes % w], axis=1)

    return run


# ----------------------------------------------------------------------------- driver
def bench_map(name: str, data: Path, n_queries: int, seed: int, nx_queries: int) -> list[dict]:
    grid = read_movingai(data / f"{name}.map")
    probs = read_scen(data / f"{name}.map.scen", grid)
    rng = np.random.default_rng(seed)
    sample = [probs[i] for i in rng.choice(len(probs), size=min(n_queries, len(probs)),
                                           replace=False)]
    occ = grid.occupied
    h, w = occ.shape
    lo = min(p.optimal_length for p in sample)
    hi = max(p.optimal_length for p in sample)
    print(f"\n== {name}: {h}x{w}, {grid.free_count} free cells, {len(sample)} of {len(probs)} "
          f"scen problems (seed {seed}), optimal lengths {lo:.0f}..{hi:.0f} cells", flush=True)
    t = time.perf_counter()
    g_nocut = build_csr(occ, corner_cutting=False)
    g_cut = build_csr(occ, corner_cutting=True)
    tc_graph = tcod_custom_graph(occ)
    print(f"   graph builds (excluded from timings): {time.perf_counter() - t:.2f} s", flush=True)

    # (label, corner_cutting, runner, every query?)
    tools: list[tuple[str, bool, Callable, bool]] = [
        ("pathfuse euclidean", False, tool_pathfuse(grid, "euclidean", False), True),
        ("pathfuse octile", False, tool_pathfuse(grid, "octile", False), True),
        ("scipy dijkstra", False, tool_scipy(g_nocut, w), True),
        ("tcod CustomGraph, new Pathfinder", False, tool_tcod_new(tc_graph), True),
        ("tcod CustomGraph, reused Pathfinder", False, tool_tcod_reuse(tc_graph), True),
        ("networkx astar_path", False, None, False),
        ("pathfuse euclidean", True, tool_pathfuse(grid, "euclidean", True), True),
        ("pathfuse octile", True, tool_pathfuse(grid, "octile", True), True),
        ("scipy dijkstra", True, tool_scipy(g_cut, w), True),
        ("tcod path2d", True, tool_tcod_path2d(occ), True),
        ("tcod old AStar (float)", True, tool_tcod_old_astar(occ), True),
    ]
    if nx_queries > 0:
        t = time.perf_counter()
        tools[5] = ("networkx astar_path", False, tool_networkx(g_nocut, w), False)
        print(f"   networkx graph build (excluded): {time.perf_counter() - t:.2f} s", flush=True)
    else:
        tools.pop(5)

    # warm-up: numba compile / per-map buffers / first-call costs, excluded
    for _, _, run, _ in tools:
        run(sample[0])
    times: dict[int, list[float]] = {i: [] for i in range(len(tools))}
    lengths: dict[int, dict[int, float]] = {i: {} for i in range(len(tools))}
    bad: dict[int, str] = {}
    for q, p in enumerate(sample):
        for i, (_, cut, run, every) in enumerate(tools):
            if not every and q >= nx_queries:
                continue
            t0 = time.perf_counter()
            cells = run(p)
            times[i].append(time.perf_counter() - t0)
            problem = check_cells(occ, cells, p.start_cell, p.goal_cell, cut)
            if problem:
                bad.setdefault(i, f"line {p.line}: {problem}")
            else:
                lengths[i][q] = cells_length(cells)

    def index(label: str, cut: bool) -> int:
        return next(i for i, t in enumerate(tools) if t[0] == label and t[1] == cut)

    rows = []
    for i, (label, cut, _, _) in enumerate(tools):
        med = statistics.median(times[i])
        if cut:  # reference: pathfuse (checked against an independent Dijkstra in the tests)
            ref = lengths[index("pathfuse euclidean", True)]
        else:  # reference: the scenario's optimal length
            ref = {q: p.optimal_length for q, p in enumerate(sample)}
        dev = max((abs(v - ref[q]) / max(ref[q], 1.0) for q, v in lengths[i].items()), default=0.0)
        rows.append({
            "map": name,
            "tool": label,
            "rule": "corner cutting" if cut else "no corner cutting",
            "queries": len(times[i]),
            "median_ms": med * 1e3,
            "mean_ms": statistics.fmean(times[i]) * 1e3,
            "ratio_vs_pathfuse_euclidean": med / statistics.median(
                times[index("pathfuse euclidean", cut)]),
            "ratio_vs_pathfuse_octile": med / statistics.median(
                times[index("pathfuse octile", cut)]),
            "max_rel_length_dev": dev,
            "invalid": bad.get(i, ""),
        })
    return rows


def print_table(rows: list[dict]) -> None:
    head = (f"{'map':<14} {'rule':<7} {'tool':<36} {'n':>4} {'median ms':>10} "
            f"{'x pf-eucl':>9} {'x pf-oct':>9} {'len dev':>9}  notes")
    print("\n" + head + "\n" + "-" * len(head))
    for r in rows:
        rule = "cut" if r["rule"] == "corner cutting" else "no-cut"
        print(f"{r['map']:<14} {rule:<7} {r['tool']:<36} {r['queries']:>4} {r['median_ms']:>10.3f} "
              f"{r['ratio_vs_pathfuse_euclidean']:>9.2f} {r['ratio_vs_pathfuse_octile']:>9.2f} "
              f"{r['max_rel_length_dev']:>9.1e}  {r['invalid']}")
    print("\nx pf-eucl / x pf-oct: the tool's median time divided by pathfuse's (euclidean /\n"
          "octile heuristic) under the same corner rule; > 1 means pathfuse is faster.\n"
          "len dev: max |length - reference| / reference over the queries; reference = the scen\n"
          "optimal length (no-cut rule) or pathfuse's length (cut rule; pathfuse is checked\n"
          "against an independent Dijkstra in tests/test_astar.py).  Timings exclude numba\n"
          "compilation, per-map buffers and every graph build (warm-up query first).")


def main(argv: list[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", nargs="+", default=DEFAULT_MAPS, help="map names in --data")
    ap.add_argument("--queries", type=int, default=60, help="scen problems sampled per map")
    ap.add_argument("--seed", type=int, default=0, help="sampling seed")
    ap.add_argument("--nx-queries", type=int, default=3,
                    help="queries given to networkx (slow); 0 skips it")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="MovingAI folder")
    ap.add_argument("--json", type=Path, help="also write the rows to this JSON file")
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        sys.exit(f"MovingAI data folder not found: {args.data} (use --data)")
    try:
        import tcod  # noqa: F401
    except ImportError:
        sys.exit("tcod is not installed: pip install 'pathfuse[bench]'")
    import os
    import platform

    load0 = round(os.getloadavg()[0], 2)
    print(f"pathfuse {pathfuse.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
          f"tcod {__import__('tcod').__version__}, networkx {__import__('networkx').__version__}; "
          f"{platform.machine()}, {os.cpu_count()} cores, load average {load0}")
    rows = []
    for name in args.maps:
        rows += bench_map(name, args.data, args.queries, args.seed, args.nx_queries)
    print_table(rows)
    if args.json:
        out = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(), "load": load0,
                           "python": platform.python_version()},
               "load_end": round(os.getloadavg()[0], 2), "queries": args.queries,
               "seed": args.seed, "rows": rows}
        args.json.write_text(json.dumps(out, indent=1))
    return rows


if __name__ == "__main__":
    main()
