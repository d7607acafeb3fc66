"""Why ref7 fails offline on the BARN worlds: the method or a defect?  (issue 11)

The issue measured ``plan()`` with ref7 at 0/25 BARN worlds at every resolution.
This script repeats that measurement and then takes the failure apart:

1. success of every stepping planner with ``plan()`` at 0.05, 0.1 and 0.15 m,
   robot radius 0.22 m (the issue's setting);
2. where ref7 stops: the distance from the stall point to the sub-goal it was
   heading for, and the attraction and repulsion there (they cancel: a force
   equilibrium of eq. 5 + eq. 6, not a stuck loop);
3. ref7 with a sub-goal tolerance up to 1 m (a more forgiving reading of
   "from sub-base to sub-base"), shorter and longer segments, a smaller rho_0;
4. ref7's own sub-goals with ref6's Ge-Cui repulsion (which vanishes at the
   target): if the plain repulsion is the cause, this succeeds.

Usage: ``python benchmarks/barn_ref7.py [--barn ../shared/data/barn] [--worlds 25]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import pathfuse
from pathfuse.costmap import costmap_for
from pathfuse.field.forces import att_force_xy
from pathfuse.field.repulsion import grid_repulsion
from pathfuse.io.gazebo import read_gazebo_world
from pathfuse.planners.controllers import refs
from pathfuse.studies.barn import BARN_BOUNDS, BARN_GOAL, BARN_START, find_worlds

RADIUS = 0.22


def _grids(barn: Path, n: int, res: float) -> list[pathfuse.GridMap]:
    worlds = find_worlds(barn)[:n]
    return [read_gazebo_world(w.world, res, bounds=BARN_BOUNDS) for w in worlds]


def _ok(grids: list[pathfuse.GridMap], planner: str, **kw: object) -> tuple[int, list[float]]:
    ok, gaps = 0, []
    for g in grids:
        r = pathfuse.plan(g, BARN_START, BARN_GOAL, planner, robot_radius_m=RADIUS, **kw)
        ok += bool(r.success)
        if not r.success and "subgoals" in r.info:
            subs = r.info["subgoals"]
            k = min(int(r.info["subgoals_reached"]), len(subs) - 1)
            gaps.append(float(np.hypot(*(r.path[-1] - subs[k]))))
    return ok, gaps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--barn", default=str(Path(__file__).parents[1] / ".." / ".." / "shared"
                                           / "data" / "barn"))
    ap.add_argument("--worlds", type=int, default=25)
    a = ap.parse_args()
    barn = Path(a.barn)
    t0 = time.perf_counter()
    print(f"# plan() on the first {a.worlds} BARN worlds, robot radius {RADIUS} m\n")
    print("| resolution | astar | fusion | apf | ref6 | ref7 |")
    print("|---|---|---|---|---|---|")
    for res in (0.05, 0.1, 0.15):
        grids = _grids(barn, a.worlds, res)
        cells = [f"{_ok(grids, p)[0]}/{len(grids)}"
                 for p in ("astar", "fusion", "apf", "ref6", "ref7")]
        print(f"| {res:g} m | " + " | ".join(cells) + " |")

    grids = _grids(barn, a.worlds, 0.05)
    g = grids[0]
    r = pathfuse.plan(g, BARN_START, BARN_GOAL, "ref7", robot_radius_m=RADIUS)
    sub = r.info["subgoals"][int(r.info["subgoals_reached"])]
    x, y = r.path[-1]
    rx, ry = grid_repulsion(x, y, costmap_for(g, 0.0, lattice=False), 5.0, 2.0, 2.0)
    ax, ay = att_force_xy(x, y, sub[0], sub[1], 40.0)
    print(f"\n{g.name} at 0.05 m: ref7 {r.status.name} at ({x:.3f}, {y:.3f}), "
          f"{np.hypot(x - sub[0], y - sub[1]):.3f} m before its sub-goal "
          f"({sub[0]:.3f}, {sub[1]:.3f}); attraction ({ax:.2f}, {ay:.2f}), repulsion "
          f"({rx:.2f}, {ry:.2f}): sum ({ax + rx:.2f}, {ay + ry:.2f})")
    print(f"  the last moves: {np.round(r.path[-4:], 4).tolist()}")

    print("\n| ref7 variant (0.05 m) | success | median distance to the sub-goal at the stall |")
    print("|---|---|---|")
    variants: list[tuple[str, dict[str, object]]] = [
        ("defaults (ends passed within 1/4 cell)", {}),
        *[(f"subgoal_tolerance_m={t}", {"subgoal_tolerance_m": t}) for t in (0.1, 0.3, 0.6,
                                                                            1.0)],
        *[(f"segment_length_m={s}", {"segment_length_m": s}) for s in (1.0, 6.0)],
        ("rho0_m=0.5", {"rho0_m": 0.5}),
        ("k_rep=0.5", {"k_rep": 0.5}),
    ]
    for label, kw in variants:
        ok, gaps = _ok(grids, "ref7", **kw)
        med = f"{np.median(gaps):.2f} m" if gaps else "-"
        print(f"| {label} | {ok}/{len(grids)} | {med} |")

    original = refs.Ref6Controller.make_subgoals

    def ref7_ends(self: refs.Ref6Controller) -> np.ndarray:
        path = self.plan.waypoints
        subs = path[refs.segment_ends(path, 3.0)].copy()
        subs[-1] = self.problem.goal
        return subs

    refs.Ref6Controller.make_subgoals = ref7_ends  # type: ignore[method-assign]
    try:
        ok, _ = _ok(grids, "ref6", subgoal_tolerance_m=0.0125)
    finally:
        refs.Ref6Controller.make_subgoals = original  # type: ignore[method-assign]
    print(f"| ref7's segment ends with ref6's Ge-Cui repulsion | {ok}/{len(grids)} | - |")
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
