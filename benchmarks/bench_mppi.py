"""Time per tick of ``mppi`` against ``dwa``, in the same run (python benchmarks/bench_mppi.py).

Both controllers drive the same episodes with :func:`pathfuse.simulate`: the
BARN worlds shipped with the tests (``tests/data/barn``, or ``--barn DIR``)
with the diff-drive Jackal-sized disc at 1 and 2 m/s, and the example
scenarios (moving discs) with a diff-drive and a holonomic robot.  For each
controller it reports the median and 90th percentile of the wall time of one
decision (``Episode.plan_times_s``: the controller's command through the
safety shield), the process CPU time per simulated tick (decision, world and
bookkeeping; what a decision costs at most when a shared machine stretches
wall times), and the ratio of the medians mppi / dwa.  numba compilation is
kept out by one warm-up episode per controller and robot.  The load average
is printed at the start and the end.

With ``--json PATH`` it also writes the figures, the machine and the load
(``benchmarks/run_all.py`` writes the speed page's ``mppi`` block from them).

Usage::

    python benchmarks/bench_mppi.py [--barn DIR] [--worlds 0,17,20,43] [--params '{}'] [--json F]
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

import pathfuse
from pathfuse.world import load_scenario

ROOT = Path(__file__).resolve().parents[1]


def episodes(barn: str, worlds: str) -> list[tuple[str, dict, dict]]:
    """(label, scenario, robot overrides) of every episode."""
    from pathfuse.studies.barn import BarnConfig, _scenario, find_worlds, jackal_robot

    out: list[tuple[str, dict, dict]] = []
    for speed in (1.0, 2.0):
        robot = dict(jackal_robot("diff-drive"), max_speed=speed)
        cfg = BarnConfig(barn, resolution=0.05, robot=robot)
        for w in find_worlds(barn, worlds):
            out.append((f"barn {speed:g} m/s", _scenario(cfg, w, "0" * 16), {}))
    for f in sorted(glob.glob(str(ROOT / "examples" / "scenarios" / "*.yaml"))):
        sc = load_scenario(f)
        for model in ("diff-drive", "holonomic"):
            rb = {"model": model, "radius": sc.robot.radius_m, "max_speed": sc.robot.max_speed_mps,
                  "sensing_radius": sc.robot.sensing_radius_m}
            out.append((f"examples {model}", f, rb))
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--barn", default=str(ROOT / "tests" / "data" / "barn"))
    ap.add_argument("--worlds", default=None, help="BARN worlds (default: all in --barn)")
    ap.add_argument("--params", default="{}", help="mppi parameters, as JSON")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    load0 = round(os.getloadavg()[0], 2)
    eps = episodes(args.barn, args.worlds)
    planners = {"mppi": {"name": "mppi", "params": json.loads(args.params)}, "dwa": "dwa"}
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.2f} at start; {len(eps)} episodes per controller")
    # warm-up: every kernel compiled (or loaded) before any clock starts
    for p in planners.values():
        for model in ("diff-drive", "holonomic"):
            pathfuse.simulate(eps[-1][1], planner=p, robot=dict(eps[-1][2], model=model))
    rows: dict[tuple[str, str], np.ndarray] = {}
    cpu: dict[tuple[str, str], float] = {}
    outcome: dict[tuple[str, str], list[str]] = {}
    for name, p in planners.items():
        for label, sc, rb in eps:
            c0 = time.process_time()
            ep = pathfuse.simulate(sc, planner=p, robot=rb or None)
            key = (name, label)
            rows[key] = np.concatenate([rows.get(key, np.zeros(0)), ep.plan_times_s])
            cpu[key] = cpu.get(key, 0.0) + time.process_time() - c0
            outcome.setdefault(key, []).append(ep.status.name.lower())
    print(f"{'controller':10s} {'episodes':20s} {'ticks':>6s} {'median ms':>10s} "
          f"{'p90 ms':>8s} {'CPU ms/tick':>12s}  outcomes")
    labels = list(dict.fromkeys(lb for lb, _, _ in eps))
    for label in labels:
        for name in planners:
            t = rows[(name, label)]
            oc = outcome[(name, label)]
            summary = ", ".join(f"{s} {oc.count(s)}" for s in sorted(set(oc)))
            print(f"{name:10s} {label:20s} {t.size:6d} {1e3 * np.median(t):10.2f} "
                  f"{1e3 * np.percentile(t, 90):8.2f} {1e3 * cpu[(name, label)] / t.size:12.2f}"
                  f"  {summary}")
    allm = np.concatenate([rows[("mppi", lb)] for lb in labels])
    alld = np.concatenate([rows[("dwa", lb)] for lb in labels])
    print(f"all episodes: mppi median {1e3 * np.median(allm):.2f} ms, dwa "
          f"{1e3 * np.median(alld):.2f} ms per tick; mppi / dwa = "
          f"{np.median(allm) / np.median(alld):.2f}")
    load1 = round(os.getloadavg()[0], 2)
    print(f"load average {load1:.2f} at the end")
    res = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(), "load": load0,
                       "python": platform.python_version()},
           "load_end": load1, "params": json.loads(args.params),
           "episodes_per_controller": len(eps),
           "rows": [{"controller": name, "episodes": label,
                     "runs": len(outcome[(name, label)]), "ticks": int(rows[(name, label)].size),
                     "median_ms": 1e3 * float(np.median(rows[(name, label)])),
                     "p90_ms": 1e3 * float(np.percentile(rows[(name, label)], 90)),
                     "cpu_ms_per_tick": 1e3 * cpu[(name, label)] / rows[(name, label)].size,
                     "outcomes": {s: outcome[(name, label)].count(s)
                                  for s in sorted(set(outcome[(name, label)]))}}
                    for label in labels for name in planners],
           "all": {name: 1e3 * float(np.median(np.concatenate(
               [rows[(name, lb)] for lb in labels]))) for name in planners}}
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)
    return res


if __name__ == "__main__":
    main()
