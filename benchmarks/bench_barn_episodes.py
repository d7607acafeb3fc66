"""CPU time of BARN episodes, this code against another copy of pathfuse (old vs new).

Each round runs every planner on every world once in a fresh process, alternating the
two source trees (old, new, old, new, ...; the numba caches warm, one episode first to
load them), and records the CPU time of each planner's episodes and a hash of every
episode's outcome (status, ticks, path length, least clearances, shield counts and the
trajectory bit for bit: positions, headings, commands).  It prints the median CPU per
planner for both, their ratio, and whether the episodes are the same.

    python benchmarks/bench_barn_episodes.py --old /tmp/pathfuse-main/src \\
        --barn ../shared/data/barn --planners apf,ref7,mppi --worlds 0,121,280 --rounds 3

The machine is often shared: the load average is printed at the start and the end, and
only CPU time (``time.process_time``) is compared.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

_CHILD = r"""
import hashlib, json, sys, time
import numpy as np
from pathfuse.studies.barn import BarnConfig, find_worlds, _scenario
from pathfuse.world.scenario import load_scenario
from pathfuse.world import simulate
barn, planners, worlds = sys.argv[1], sys.argv[2].split(","), sys.argv[3]
cfg = BarnConfig(barn, planners=tuple(planners))
scs = [(w.index, load_scenario(_scenario(cfg, w, "x"))) for w in find_worlds(barn, worlds)]
for p in planners:  # load the kernels (numba's cache) before any clock
    simulate(scs[0][1], planner=p, seed=0)
out = {}
for p in planners:
    cpu, h, ticks = 0.0, hashlib.sha256(), 0
    for i, sc in scs:
        c = time.process_time()
        ep = simulate(sc, planner=p, seed=0)
        cpu += time.process_time() - c
        ticks += ep.n_ticks
        h.update(repr((i, ep.status.name, ep.n_ticks, ep.path_length_m, ep.min_distance_m,
                       ep.min_static_clearance_m, ep.time_to_goal_s, ep.message,
                       sorted(ep.shield_counts.items()))).encode())
        for a in (ep.positions, ep.headings, ep.commands):
            h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    out[p] = {"cpu_s": cpu, "ticks": ticks, "hash": h.hexdigest()[:16]}
print(json.dumps(out))
"""


def _run(src: str, args: argparse.Namespace) -> dict:
    env = dict(os.environ, PYTHONPATH=src)
    r = subprocess.run([sys.executable, "-c", _CHILD, args.barn, args.planners, args.worlds],
                       env=env, capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", required=True, help="the other copy's src folder")
    ap.add_argument("--new", default=str(Path(__file__).resolve().parents[1] / "src"),
                    help="this copy's src folder (default)")
    ap.add_argument("--barn", default="../shared/data/barn")
    ap.add_argument("--planners", default="apf,ref7,mppi,fusion")
    ap.add_argument("--worlds", default="0,121,280")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(f"load average at the start: {os.getloadavg()}")
    res: dict[str, list[dict]] = {"old": [], "new": []}
    for k in range(args.rounds):
        for which in ("old", "new") if k % 2 == 0 else ("new", "old"):
            res[which].append(_run(getattr(args, which), args))
    print(f"load average at the end: {os.getloadavg()}")
    print(f"{'planner':<16}{'ticks':>7}{'old ms/tick':>13}{'new ms/tick':>13}{'new/old':>9}"
          "  same episodes")
    for p in args.planners.split(","):
        ticks = res["new"][0][p]["ticks"]
        old = statistics.median(r[p]["cpu_s"] for r in res["old"]) / ticks * 1e3
        new = statistics.median(r[p]["cpu_s"] for r in res["new"]) / ticks * 1e3
        same = len({r[p]["hash"] for r in res["old"] + res["new"]}) == 1
        print(f"{p:<16}{ticks:>7}{old:>13.3f}{new:>13.3f}{new / old:>9.3f}  {same}")
    digest = hashlib.sha256(json.dumps(res, sort_keys=True).encode()).hexdigest()[:8]
    print(f"(per-round CPU in {digest}: " + json.dumps(
        {w: [{p: round(r[p]["cpu_s"], 3) for p in r} for r in rs] for w, rs in res.items()})
          + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main())
