"""Hashes of plans, episodes and collision answers, to show a refactoring changed no result.

Every case is hashed on its own (the bytes of its path or trajectory, its status and its
counts), so two runs compare case by case::

    python benchmarks/costmap_hashes.py --out before.json
    ... change the code ...
    python benchmarks/costmap_hashes.py --out after.json --compare before.json

Cases (issue 17, item 1: the collision checks moved onto the Costmap):

* ``plan``: the paper's five planners (astar, apf, ref6, ref7, fusion) and the any-angle
  global planners (thetastar, lazy-thetastar, astar-smooth, shortest) on the eight paper
  maps, three random maps and a MovingAI maze, for a point, a disc (0.3 m) and a
  diff-drive robot; the paper variant (the field planners as printed), a safety margin
  (``clearance_m``) and the boundary repulsion on the paper maps;
* ``episode``: fusion, apf, dwa, mppi and astar (Regulated Pure Pursuit when diff-drive)
  among four moving discs on generated scenarios, holonomic and diff-drive, and the
  example scenarios;
* ``check``: the scenario and generator checks (a disc at a point, a patrol leg) on
  random points, generated scenario families (both placements), the discs' bouncing
  trajectories, and the field forces and progress rule called from Python (the
  playground's layers, ``force_at``).

Nothing here is timed or asserted by the tests.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(os.environ.get("PATHFUSE_ROOT", Path(__file__).resolve().parents[1]))
MAZE = Path("/work/shared/data/movingai/maze-32-32-2.map")
FIELD = ("apf", "ref6", "ref7", "fusion")


def _h(*parts: Any) -> str:
    d = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            d.update(str(p.shape).encode())
            d.update(np.ascontiguousarray(p).tobytes())
        else:
            d.update(repr(p).encode())
    return d.hexdigest()[:16]


def _maps() -> list[tuple[str, Any, tuple[float, float], tuple[float, float]]]:
    from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map, random_map
    from pathfuse.io.movingai import read_movingai

    out = [(f"paper{s}", paper_map(s), PAPER_START, PAPER_GOAL) for s in range(8)]
    for s in (1, 2, 3):
        g = random_map((15.0, 15.0), 1.0, obstacles=60, seed=100 + s,
                       keep_free=[(1.0, 1.0), (13.5, 12.5)],
                       connect=[((1.0, 1.0), (13.5, 12.5))])
        out.append((f"random{s}", g, (1.0, 1.0), (13.5, 12.5)))
    if MAZE.exists():
        out.append(("maze", read_movingai(MAZE), (15.5, 2.5), (1.5, 27.5)))
    return out


def plan_cases(quick: bool) -> dict[str, str]:
    from pathfuse import plan
    from pathfuse.robot import RobotModel

    out: dict[str, str] = {}
    robots: list[tuple[str, dict[str, Any]]] = [
        ("point", {"robot_radius_m": 0.0}), ("disc", {"robot_radius_m": 0.3}),
        ("dd", {"robot": RobotModel(kind="diff-drive", radius_m=0.3)})]
    planners = ("astar", "apf", "ref6", "ref7", "fusion", "thetastar", "lazy-thetastar",
                "astar-smooth", "shortest")
    for mname, g, start, goal in _maps():
        paper = mname.startswith("paper")
        for rname, kw in robots:
            for p in planners:
                if mname == "maze" and p in ("apf", "ref6", "ref7") and rname != "point":
                    continue
                variants: list[tuple[str, dict[str, Any], dict[str, Any]]] = [("", {}, {})]
                if paper and not quick and rname != "dd":
                    if p in FIELD:
                        v = {"safe_step": False, "stall_exit": False}
                        if p == "fusion":
                            v.update(ahead="paper-x", escape=False)
                        variants.append(("paper", v, {}))
                        variants.append(("boundary", {"static_repulsion": "boundary"}, {}))
                    if p in ("astar", "fusion", "thetastar") and rname == "disc":
                        variants.append(("margin", {}, {"clearance_m": 0.3}))
                for vname, params, extra in variants:
                    r = plan(g, start, goal, p, **kw, **extra, **params)
                    key = f"plan/{mname}/{rname}/{p}" + (f"/{vname}" if vname else "")
                    out[key] = _h(r.status.name, r.path, r.length, r.expansions,
                                  r.iterations)
    return out


def episode_cases(quick: bool) -> dict[str, str]:
    from pathfuse.robot import RobotModel
    from pathfuse.world import simulate
    from pathfuse.world.generate import generate_scenarios

    out: dict[str, str] = {}
    n = 2 if quick else 5
    scs = generate_scenarios(n, moving=4, speed_range=(0.3, 0.8), seed=11, time_limit=40.0)
    robots = [("holo", None), ("dd", RobotModel(kind="diff-drive", radius_m=0.3))]
    for i, sc in enumerate(scs):
        for rname, rb in robots:
            for p in ("fusion", "apf", "dwa", "mppi", "astar"):
                if quick and p in ("mppi", "apf"):
                    continue
                ep = simulate(sc, planner=p, seed=i, robot=rb)
                out[f"episode/gen{i}/{rname}/{p}"] = _h(
                    ep.status.name, ep.positions, ep.velocities, ep.headings, ep.commands,
                    ep.obstacle_positions, ep.n_ticks, ep.min_static_clearance_m)
    for f in sorted((ROOT / "examples" / "scenarios").glob("*.yaml")):
        if quick:
            break
        for p in ("fusion", "dwa"):
            ep = simulate(str(f), planner=p)
            out[f"episode/{f.stem}/{p}"] = _h(ep.status.name, ep.positions, ep.headings,
                                              ep.obstacle_positions, ep.n_ticks)
    return out


def check_cases() -> dict[str, str]:
    from pathfuse.planners.controllers.apf import APFParams
    from pathfuse.planners.controllers.apf import force_at as apf_force_at
    from pathfuse.planners.controllers.fusion import FusionParams
    from pathfuse.planners.controllers.fusion import force_at as fusion_force_at
    from pathfuse.problem import Problem
    from pathfuse.web.layers import attractors, potential_field
    from pathfuse.world import generate as wgen
    from pathfuse.world import scenario as wsc
    from pathfuse.world.generate import generate_scenarios
    from pathfuse.world.obstacles import LinearObstacle, RandomWalkObstacle

    out: dict[str, str] = {}
    rng = np.random.default_rng(5)
    for mname, g, start, goal in _maps():
        x0, y0, x1, y1 = g.bounds
        pts = np.column_stack([rng.uniform(x0 - 0.5, x1 + 0.5, 400),
                               rng.uniform(y0 - 0.5, y1 + 0.5, 400)])
        radii = rng.uniform(0.0, 0.8, 400)
        a = [wsc._disc_clear(g, (float(p[0]), float(p[1])), float(r))
             for p, r in zip(pts, radii, strict=True)]
        b = [wgen._disc_ok(g, p, float(r)) for p, r in zip(pts, radii, strict=True)]
        c = [wgen._leg_ok(g, pts[i], pts[i - 1] * 0.1 + pts[i] * 0.9, float(radii[i]))
             for i in range(len(pts))]
        out[f"check/{mname}/scene"] = _h(a, b, c)
        trajs = []
        for i in range(20):
            p = (float(pts[i, 0]), float(pts[i, 1]))
            trajs.extend(LinearObstacle(p, (float(rng.normal()), float(rng.normal())),
                                        float(radii[i] * 0.5)).trajectory(g, 0.1, 200))
            trajs.extend(RandomWalkObstacle(p, 0.6, seed=i, radius=float(radii[i] * 0.5))
                         .trajectory(g, 0.1, 200))
        out[f"check/{mname}/bounce"] = _h(*trajs)
        fa = apf_force_at(g, pts[:50], goal, APFParams())
        fb = apf_force_at(g, pts[:50], goal, APFParams(static_repulsion="boundary"))
        pb = Problem.create(g, start, goal, 0.0)
        wp = np.linspace(start, goal, 30)
        ff = [fusion_force_at(g, tuple(p), goal, wp, FusionParams(), k) for k, p in
              enumerate(pts[:29])]
        att = attractors(pb, wp + 0.01, wp, 2.0)
        out[f"check/{mname}/forces"] = _h(fa, fb, np.array(ff), att)
        if mname in ("paper0", "random1"):
            pf = potential_field(g, goal, 40.0, 5.0, 2.0)
            out[f"check/{mname}/potential"] = _h(json.dumps(pf, sort_keys=True, default=str))
    for placement in ("route", "uniform"):
        for moving in (2, 6):
            scs = generate_scenarios(6, moving=moving, seed=3, placement=placement)
            out[f"check/generate/{placement}/{moving}"] = _h(
                json.dumps([s.to_dict() for s in scs], sort_keys=True, default=str))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--compare", help="an earlier --out to compare with")
    ap.add_argument("--quick", action="store_true", help="fewer cases (a smoke run)")
    ap.add_argument("--only", choices=("plan", "episode", "check"), action="append")
    a = ap.parse_args()
    t0 = time.perf_counter()
    cases: dict[str, str] = {}
    only = a.only or ["plan", "episode", "check"]
    if "check" in only:
        cases.update(check_cases())
    if "plan" in only:
        cases.update(plan_cases(a.quick))
    if "episode" in only:
        cases.update(episode_cases(a.quick))
    Path(a.out).write_text(json.dumps(cases, indent=1, sort_keys=True) + "\n")
    total = _h(json.dumps(cases, sort_keys=True))
    print(f"{len(cases)} cases, digest {total}, {time.perf_counter() - t0:.0f} s")
    if a.compare:
        old = json.loads(Path(a.compare).read_text())
        diff = sorted(k for k in set(old) | set(cases) if old.get(k) != cases.get(k))
        for k in diff[:40]:
            print(f"DIFFERS {k}: {old.get(k)} -> {cases.get(k)}")
        print(f"{len(diff)} of {len(set(old) | set(cases))} cases differ")
        return 1 if diff else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
