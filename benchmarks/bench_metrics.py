"""Speed of ``pathfuse.metrics.evaluate``: numba kernels vs the previous k-d tree code and shapely.

Cases
-----
1. Paper maps (15 m x 15 m, 1 m cells, 50 obstacles; seeds 0..N-1): the
   paths of the planners astar, apf, fusion, ref6 and ref7 from
   ``PAPER_START`` to ``PAPER_GOAL`` (failed plans keep their partial path).
2. Large cases: a MovingAI map (default ``Boston_0_1024.map``), the
   scenario problem whose optimal length is closest to ``--big-length``,
   planned with ``--big-planner`` (ref6 makes 0.1 m steps: a few thousand
   points; skipped if the map file is missing); and a synthetic open room,
   1024 x 1024 with walls on the border only and a 3000-point circle around
   the centre, 411 m from the nearest wall (the worst case for a search that
   grows windows around each segment).  Fewer, longer timing samples.

Tools, all timed on the same cases, interleaved repeat by repeat (their
order rotating) so that machine noise hits them alike
---------------------------------------------------------------------
* ``new``: :func:`pathfuse.metrics.evaluate` (numba kernels, compiled before
  any timing; the per-map occupancy pyramid is built by a warm-up call and
  cached, its build time printed for the large maps).
* ``old``: the previous implementation, a k-d tree over the occupied cell
  centres with candidate lists handled in Python, copied below verbatim as
  the BASELINE (its per-map tree is built by the warm-up call and cached, as
  in the library, so tree building is *not* timed: this favours the baseline).
* ``new_clr``: :func:`pathfuse.metrics.min_clearance` alone, the like-for-like
  partner of shapely.
* ``shapely``: ``LineString(path).distance(union)``, the union of the
  occupied squares as boxes built once per map outside the timed loop (on
  the large map from horizontal runs of occupied cells, the same region,
  because a union of 250 000 single-cell boxes takes ~20 s to build).  It
  gives the clearance only (no length, bounds or collision flags); the
  union's build time on the paper maps is printed apart.  Skipped
  if shapely is not installed (``pip install shapely``, or the ``bench`` extra).

Reported per tool: the median over cases of each case's median time per
call (wall and CPU, ``time.process_time``), and the median over cases of the
per-case ratios.  Checked, not timed: ``new`` and ``old`` give equal dicts
on every case (floats equal to 1e-12 relative; the count of bit-identical
cases is printed) and equal per-segment clearances; shapely's clearance agrees
to 1e-9.

Usage::

    python benchmarks/bench_metrics.py [--seeds 50] [--repeat 7] [--no-big] [--json out.json]
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
import weakref
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

import pathfuse
from pathfuse import metrics
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.grid import GridMap
from pathfuse.metrics_kernels import warmup as warmup_metrics
from pathfuse.result import PlanResult, Status

try:
    import shapely
    from shapely.geometry import LineString, Point
except ImportError:  # pragma: no cover - optional
    shapely = None

PLANNERS = ("astar", "apf", "fusion", "ref6", "ref7")
BIG_MAP = "/work/shared/data/movingai/Boston_0_1024.map"


# =====================================================================================
# BASELINE: the previous implementation of pathfuse.metrics (k-d tree candidates),
# copied verbatim from src/pathfuse/metrics.py at commit 984fa04.  Timed as "old".
# =====================================================================================
_TREES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _old_tree(grid: GridMap):
    if grid in _TREES:
        return _TREES[grid]
    cells = np.argwhere(grid.occupied)
    if cells.shape[0] == 0:
        entry = None
    else:
        centres = grid.cell_to_world(cells)
        entry = (cKDTree(centres), centres)
    _TREES[grid] = entry
    return entry


def _old_point_box_dist(px, py, x0, y0, x1, y1):
    dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - py, py - y1), 0.0)
    return np.hypot(dx, dy)


def _old_point_seg_dist(px, py, ax, ay, bx, by):
    vx, vy = bx - ax, by - ay
    l2 = vx * vx + vy * vy
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(l2 > 0, ((px - ax) * vx + (py - ay) * vy) / np.where(l2 > 0, l2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(px - (ax + t * vx), py - (ay + t * vy))


def _old_seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1):
    t0 = np.zeros(np.broadcast(ax, x0).shape)
    t1 = np.ones_like(t0)
    ok = np.ones(t0.shape, dtype=bool)
    for a, b, lo, hi in ((ax, bx, x0, x1), (ay, by, y0, y1)):
        d = b - a
        flat = d == 0
        ok &= ~(flat & ((a < lo) | (a > hi)))
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            dd = np.where(flat, 1.0, d)
            ta = (lo - a) / dd
            tb = (hi - a) / dd
        tmin = np.where(flat, -np.inf, np.minimum(ta, tb))
        tmax = np.where(flat, np.inf, np.maximum(ta, tb))
        t0 = np.maximum(t0, tmin)
        t1 = np.minimum(t1, tmax)
    return ok & (t0 <= t1)


def _old_seg_box_dist(ax, ay, bx, by, x0, y0, x1, y1):
    d = np.minimum(_old_point_box_dist(ax, ay, x0, y0, x1, y1),
                   _old_point_box_dist(bx, by, x0, y0, x1, y1))
    for cx, cy in ((x0, y0), (x1, y0), (x0, y1), (x1, y1)):
        d = np.minimum(d, _old_point_seg_dist(cx, cy, ax, ay, bx, by))
    return np.where(_old_seg_hits_box(ax, ay, bx, by, x0, y0, x1, y1), 0.0, d)


def _old_group_min(values, groups, n):
    out = np.full(n, np.inf)
    np.minimum.at(out, groups, values)
    return out


def _old_candidates(tree, centres_q, radii):
    lists = tree.query_ball_point(centres_q, r=radii)
    lens = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
    if lens.sum() == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    idx = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists if len(x)])
    owner = np.repeat(np.arange(len(lists)), lens)
    return owner, idx


def _old_point_clearances(grid, p, tree, centres):
    h = grid.resolution / 2
    near, _ = tree.query(p)
    owner, idx = _old_candidates(tree, p, near + h * math.sqrt(2) + 1e-9 * grid.resolution)
    c = centres[idx]
    d = _old_point_box_dist(p[owner, 0], p[owner, 1], c[:, 0] - h, c[:, 1] - h, c[:, 0] + h,
                            c[:, 1] + h)
    return _old_group_min(d, owner, p.shape[0])


def old_segment_clearances(grid, path):
    p = metrics._path(path)
    if p.shape[0] == 0:
        return np.zeros(0)
    entry = _old_tree(grid)
    n = max(p.shape[0] - 1, 1)
    if entry is None:
        return np.full(n, np.inf)
    tree, centres = entry
    dp = _old_point_clearances(grid, p, tree, centres)
    if p.shape[0] == 1:
        return dp
    a, b = p[:-1], p[1:]
    upper = np.minimum(dp[:-1], dp[1:])
    mid = 0.5 * (a + b)
    half = 0.5 * np.hypot(*(b - a).T)
    h = grid.resolution / 2
    radii = upper + half + h * math.sqrt(2) + 1e-9 * grid.resolution
    owner, idx = _old_candidates(tree, mid, radii)
    c = centres[idx]
    d = _old_seg_box_dist(a[owner, 0], a[owner, 1], b[owner, 0], b[owner, 1], c[:, 0] - h,
                          c[:, 1] - h, c[:, 0] + h, c[:, 1] + h)
    return np.minimum(_old_group_min(d, owner, n), upper)


def old_min_clearance(grid, path):
    d = old_segment_clearances(grid, path)
    return float(d.min()) if d.size else math.inf


def old_collision_free(grid, path, robot_radius_m=0.0):
    r = float(robot_radius_m)
    p = metrics._path(path)
    if p.shape[0] == 0:
        return True
    if not metrics.in_bounds(grid, p):
        return False
    c = old_min_clearance(grid, p)
    return c > 0.0 if r == 0.0 else c >= r


def old_evaluate(grid, result, robot_radius_m=0.0):
    p = metrics._path(result.path)
    return {
        "planner": result.planner,
        "status": result.status.name,
        "success": bool(result.success),
        "time_s": float(result.time_s),
        "iterations": int(result.iterations),
        "expansions": int(result.expansions),
        "length_m": metrics.path_length(p),
        "steps": metrics.n_steps(p),
        "smoothness_rad": metrics.smoothness(p),
        "min_clearance_m": old_min_clearance(grid, p),
        "in_bounds": metrics.in_bounds(grid, p) if p.shape[0] else True,
        "collision_free": old_collision_free(grid, p, robot_radius_m),
    }
# ================================ end of BASELINE ====================================


def _union(grid: GridMap, runs: bool):
    """The occupied squares as one shapely geometry (single boxes, or row runs of them)."""
    ox, oy = grid.origin
    res = grid.resolution
    if runs:
        x0, x1, rows = [], [], []
        for r in range(grid.height):
            v = np.diff(np.concatenate([[0], grid.occupied[r].astype(np.int8), [0]]))
            s, e = np.flatnonzero(v == 1), np.flatnonzero(v == -1)
            x0.append(s)
            x1.append(e)
            rows.append(np.full(len(s), r))
        c0, c1, r = np.concatenate(x0), np.concatenate(x1), np.concatenate(rows)
    else:
        cells = np.argwhere(grid.occupied)
        r, c0 = cells[:, 0], cells[:, 1]
        c1 = c0 + 1
    boxes = shapely.box(ox + c0 * res, oy + r * res, ox + c1 * res, oy + (r + 1) * res)
    return shapely.union_all(boxes)


def _shapely_fn(path: np.ndarray, union):
    geom = LineString(path) if len(path) > 1 else Point(path[0])
    return lambda: geom.distance(union)


def _same(a: dict, b: dict) -> tuple[bool, bool]:
    """(equal to float rounding, bit-identical) for two metric dicts."""
    if a.keys() != b.keys():
        return False, False
    close = all(
        (x == y) or (isinstance(x, float) and isinstance(y, float)
                     and math.isclose(x, y, rel_tol=1e-12, abs_tol=0.0))
        for x, y in ((a[k], b[k]) for k in a)
    )
    exact = all(x == y and type(x) is type(y) for x, y in ((a[k], b[k]) for k in a))
    return close, exact


def _time_case(fns: dict[str, Any], repeat: int, target_s: float) -> dict[str, tuple[float, float]]:
    """Median (wall, cpu) seconds per call of each function, interleaved repeat by repeat."""
    inner = {}
    for name, fn in fns.items():  # calls per sample: about target_s of work
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        inner[name] = max(1, min(10_000, int(target_s / max(dt, 1e-7))))
    wall: dict[str, list[float]] = {k: [] for k in fns}
    cpu: dict[str, list[float]] = {k: [] for k in fns}
    names = list(fns)
    for rep in range(repeat):
        for name in names[rep % len(names):] + names[:rep % len(names)]:
            fn, k = fns[name], inner[name]
            w0, c0 = time.perf_counter(), time.process_time()
            for _ in range(k):
                fn()
            w1, c1 = time.perf_counter(), time.process_time()
            wall[name].append((w1 - w0) / k)
            cpu[name].append((c1 - c0) / k)
    return {k: (statistics.median(wall[k]), statistics.median(cpu[k])) for k in fns}


def _check(grid: GridMap, res: PlanResult, where: str, counts: dict[str, int]) -> None:
    new, old = metrics.evaluate(grid, res), old_evaluate(grid, res)
    close, exact = _same(new, old)
    assert close, f"{where}: new and old evaluate differ:\n new {new}\n old {old}"
    sn, so = metrics.segment_clearances(grid, res.path), old_segment_clearances(grid, res.path)
    assert sn.shape == so.shape and np.allclose(sn, so, rtol=1e-12, atol=0.0), where
    counts["cases"] += 1
    counts["identical"] += bool(exact and np.array_equal(sn, so))


def _fns(grid: GridMap, res: PlanResult, union) -> dict[str, Any]:
    fns = {
        "new": lambda: metrics.evaluate(grid, res),
        "old": lambda: old_evaluate(grid, res),
        "new_clr": lambda: metrics.min_clearance(grid, res.path),
    }
    if union is not None and len(res.path):
        fns["shapely"] = _shapely_fn(np.asarray(res.path, dtype=float), union)
    return fns


def _summary(rows: list[dict], label: str) -> dict:
    out: dict[str, Any] = {"label": label, "cases": len(rows)}
    for tool in ("new", "old", "new_clr", "shapely"):
        have = [r for r in rows if tool in r]
        if have:
            out[tool] = {"wall_ms": statistics.median(r[tool][0] for r in have) * 1e3,
                         "cpu_ms": statistics.median(r[tool][1] for r in have) * 1e3,
                         "cases": len(have)}
    out["old/new"] = statistics.median(r["old"][0] / r["new"][0] for r in rows)
    sh = [r for r in rows if "shapely" in r]
    if sh:
        out["shapely/new_clr"] = statistics.median(r["shapely"][0] / r["new_clr"][0] for r in sh)
        out["shapely/new"] = statistics.median(r["shapely"][0] / r["new"][0] for r in sh)
    return out


def _print_summary(s: dict) -> None:
    parts = []
    for tool in ("new", "old", "new_clr", "shapely"):
        if tool in s:
            parts.append(f"{tool} {s[tool]['wall_ms']:.4g} ms (cpu {s[tool]['cpu_ms']:.4g})")
    ratios = f"old/new {s['old/new']:6.1f}x"
    if "shapely/new_clr" in s:
        ratios += (f"  shapely/new_clr {s['shapely/new_clr']:5.1f}x"
                   f"  shapely/new {s['shapely/new']:5.1f}x")
    print(f"  {s['label']:<8} n={s['cases']:<4} " + " | ".join(parts))
    print(f"  {'':<8} {'':<6} {ratios}")


def _large_case(desc: str, label: str, grid: GridMap, res: PlanResult, args, counts) -> dict:
    """Time one large case; the per-map structures are built (and timed) once beforehand."""
    t0 = time.perf_counter()
    metrics._pyramid(grid)  # the new code's per-map pyramid, cached like the old tree
    t_pyr = time.perf_counter() - t0
    t0 = time.perf_counter()
    _old_tree(grid)
    t_tree = time.perf_counter() - t0
    _check(grid, res, label, counts)
    union, t_union = None, float("nan")
    if shapely:
        t0 = time.perf_counter()
        union = _union(grid, runs=True)
        t_union = time.perf_counter() - t0
    fns = _fns(grid, res, union)
    if "shapely" in fns:
        d_sh, d_new = fns["shapely"](), metrics.min_clearance(grid, res.path)
        assert math.isclose(d_sh, d_new, rel_tol=1e-9, abs_tol=1e-9), (label, d_sh, d_new)
    row = _time_case(fns, max(3, args.repeat // 2), 4 * args.sample_ms / 1e3)
    out = _summary([row], label)
    out.update(desc=desc, map=grid.name, shape=list(grid.shape), points=len(res.path),
               min_clearance_m=metrics.min_clearance(grid, res.path),
               build_ms={"pyramid": t_pyr * 1e3, "old_tree": t_tree * 1e3,
                         "shapely_union": t_union * 1e3})
    print(f"\n{label}: {grid.name} {grid.shape[0]}x{grid.shape[1]}, "
          f"{int(grid.occupied.sum())} occupied cells; {desc}; {len(res.path)} points, "
          f"clearance {out['min_clearance_m']:.6f} m")
    print(f"  built once per map, untimed: new pyramid {t_pyr * 1e3:.1f} ms, old k-d tree "
          f"{t_tree * 1e3:.1f} ms" + (f", shapely union {t_union:.2f} s" if shapely else ""))
    _print_summary(out)
    return out


def _load() -> str:
    la = os.getloadavg()
    return f"{la[0]:.2f} {la[1]:.2f} {la[2]:.2f}"


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50, help="paper maps (seeds 0..N-1)")
    ap.add_argument("--repeat", type=int, default=7, help="timing samples per case (median kept)")
    ap.add_argument("--sample-ms", type=float, default=2.0,
                    help="work per timing sample, ms (calls are repeated to reach it)")
    ap.add_argument("--big-map", default=BIG_MAP, help="MovingAI map of the large case")
    ap.add_argument("--big-length", type=float, default=400.0,
                    help="pick the scenario problem with the optimal length closest to this")
    ap.add_argument("--big-planner", default="ref6", help="planner of the large case")
    ap.add_argument("--no-big", action="store_true", help="skip the large case")
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args(argv)

    ncpu = os.cpu_count()
    try:
        avail = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        avail = ncpu
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, pathfuse "
          f"{pathfuse.__version__ if hasattr(pathfuse, '__version__') else '?'}, shapely "
          f"{shapely.__version__ if shapely else 'NOT INSTALLED (pip install shapely): skipped'}")
    print(f"cores: {ncpu} (usable {avail}); load average at start: {_load()}")
    load0 = os.getloadavg()[0]

    warmup_metrics()  # numba compile / cache load, kept out of the timings
    sample_s = args.sample_ms / 1e3
    counts = {"cases": 0, "identical": 0}
    rows: list[dict] = []
    t_unions: list[float] = []
    t_start = time.perf_counter()
    for seed in range(args.seeds):
        grid = paper_map(seed)
        union = None
        if shapely:
            t0 = time.perf_counter()
            union = _union(grid, runs=False)
            t_unions.append(time.perf_counter() - t0)
        for name in PLANNERS:
            res = pathfuse.plan(grid, PAPER_START, PAPER_GOAL, planner=name)
            _check(grid, res, f"seed {seed} {name}", counts)  # also warms every tool
            fns = _fns(grid, res, union)
            if "shapely" in fns:
                d_sh, d_new = fns["shapely"](), metrics.min_clearance(grid, res.path)
                assert math.isclose(d_sh, d_new, rel_tol=1e-9, abs_tol=1e-9), (seed, name)
            row = _time_case(fns, args.repeat, sample_s)
            row.update(planner=name, seed=seed, points=len(res.path))
            rows.append(row)
    print(f"\npaper maps: {args.seeds} seeds x {len(PLANNERS)} planners; median over cases of "
          f"the per-case median time per call ({args.repeat} samples of ~{args.sample_ms:g} ms)")
    print(f"  points per path: median {statistics.median(r['points'] for r in rows):.0f}, "
          f"max {max(r['points'] for r in rows)}")
    summaries = [_summary(rows, "all")]
    for name in PLANNERS:
        summaries.append(_summary([r for r in rows if r["planner"] == name], name))
    for s in summaries:
        _print_summary(s)
    if t_unions:
        print(f"  shapely's union of a paper map's 50 squares (untimed above) takes "
              f"{statistics.median(t_unions) * 1e3:.3f} ms (median), once per map")
    print(f"  paper maps took {time.perf_counter() - t_start:.1f} s; load average now {_load()}")

    large = []
    if not args.no_big:
        path = Path(args.big_map)
        if not path.exists():
            print(f"\nlarge case skipped: {path} not found")
        else:
            grid = pathfuse.load_map(str(path))
            probs = pathfuse.read_scen(Path(str(path) + ".scen"), grid)
            prob = min(probs, key=lambda p: abs(p.optimal_length - args.big_length))
            res = pathfuse.plan(grid, prob.start, prob.goal, planner=args.big_planner)
            large.append(_large_case(
                f"{path.name}, scen line {prob.line} (optimal {prob.optimal_length:.1f} m), "
                f"{args.big_planner}: {res.status.name}", "large", grid, res, args, counts))
        # an open room: the clearance is hundreds of cells, the worst case of a search
        # that grows windows around each segment
        occ = np.zeros((1024, 1024), dtype=bool)
        occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
        grid = GridMap(occ, name="open1024")
        t = np.linspace(0.0, 2 * np.pi, 3000)
        circle = np.c_[512 + 100 * np.cos(t), 512 + 100 * np.sin(t)]
        res = PlanResult(Status.SUCCESS, circle, planner="circle")
        large.append(_large_case("synthetic open room (walls on the border only), "
                                 "circle of radius 100 m round the centre", "open",
                                 grid, res, args, counts))

    print(f"\nchecks: new == old evaluate() and segment_clearances() on all {counts['cases']} "
          f"cases ({counts['identical']} bit for bit); shapely clearance agrees to 1e-9")
    print(f"load average at end: {_load()}")
    out = {"machine": {"machine": platform.machine(), "cores": ncpu,
                       "load": round(load0, 2), "python": platform.python_version()},
           "load_end": round(os.getloadavg()[0], 2), "seeds": args.seeds,
           "cores": ncpu, "usable_cores": avail, "paper": summaries, "large": large,
           "shapely_union_ms": statistics.median(t_unions) * 1e3 if t_unions else None,
           "checks": counts, "loadavg_end": os.getloadavg()}
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main()
