"""Ticks per second of every online controller, against real time (python benchmarks/...).

What a user runs: :func:`pathfuse.simulate` on the shipped example scenarios
and on generated scenarios of the dynamic benchmark (4 moving discs), with a
holonomic and with a diff-drive robot.  For each planner it reports the
median wall time of one control decision (``Episode.plan_times_s``: the
controller's ``act`` plus, on a diff-drive robot, the shared conversion to
``(v, omega)``), the decisions per second, the real-time factor (decisions
per second x ``dt``: how many times faster than the robot's clock), the
whole simulation's ticks per second (world stepping and bookkeeping
included), the process CPU time per simulated tick (decision, world and
bookkeeping: what the decision costs at most when the machine is loaded and
wall times stretch) and CPU over wall time.  numba compilation
is kept out by one warm-up episode per planner and model.

With ``--json PATH`` it also writes the figures, the machine and the load
(``benchmarks/run_all.py`` writes the speed page's ``controllers`` block from
them).

Usage::

    python benchmarks/bench_controllers.py [--scenarios 10] [--planners dwa,fusion] [--json F]
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import platform
import time
from typing import Any

import numpy as np

import pathfuse
from pathfuse.planners.registry import get_planner, planner_names
from pathfuse.world import load_scenario
from pathfuse.world.generate import generate_scenarios

ROOT = os.path.join(os.path.dirname(__file__), "..")


def scenarios(n: int) -> list:
    files = sorted(glob.glob(os.path.join(ROOT, "examples", "scenarios", "*.yaml")))
    out = [load_scenario(f) for f in files]
    out += generate_scenarios(n, moving=4, speed_range=(0.3, 0.8), seed=0)
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", type=int, default=10, help="generated scenarios (4 discs)")
    ap.add_argument("--planners", default="", help="comma-separated (default: all online)")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    import numba

    res: dict[str, Any] = {
        "machine": {"machine": platform.machine(), "cores": os.cpu_count(),
                    "load": round(os.getloadavg()[0], 2), "python": platform.python_version(),
                    "numba": numba.__version__},
        "scenarios": {"shipped": 0, "generated": args.scenarios, "moving": 4}, "rows": []}
    names = [n for n in (args.planners.split(",") if args.planners else planner_names())
             if get_planner(n).online]
    scs = scenarios(args.scenarios)
    res["scenarios"]["shipped"] = len(scs) - args.scenarios
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.2f} at start; {len(scs)} scenarios")
    print(f"{'planner':13s} {'robot':10s} {'decision µs (median)':>21s} {'decisions/s':>12s} "
          f"{'x real time':>12s} {'sim ticks/s':>12s} {'CPU µs/tick':>12s} {'CPU/wall':>9s}")
    rows = {}
    for model in ("holonomic", "diff-drive"):
        for name in names:
            def run(sc, name=name, model=model):
                rb = {"model": model, "radius": sc.robot.radius_m,
                      "sensing_radius": sc.robot.sensing_radius_m,
                      "max_speed": sc.robot.max_speed_mps}
                return pathfuse.simulate(sc, planner=name, robot=rb)

            run(scs[0])  # warm-up: numba compilation stays out
            per_tick = []
            ticks = 0
            dts = []
            w0, c0 = time.perf_counter(), time.process_time()
            for sc in scs:
                ep = run(sc)
                per_tick.append(ep.plan_times_s)
                ticks += ep.n_ticks
                dts.append(sc.dt)
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            pt = np.concatenate(per_tick)
            med = float(np.median(pt))
            dt = float(np.median(dts))
            rows[(name, model)] = med
            res["rows"].append({
                "planner": name, "robot": model, "decision_us": 1e6 * med,
                "decisions_per_s": 1.0 / med, "x_real_time": dt / med,
                "ticks_per_wall_s": ticks / wall, "cpu_us_per_tick": 1e6 * cpu / ticks,
                "ticks_per_cpu_s": ticks / cpu, "cpu_over_wall": cpu / wall, "ticks": ticks,
                "dt_s": dt})
            print(f"{name:13s} {model:10s} {1e6 * med:21.1f} {1.0 / med:12.0f} "
                  f"{dt / med:12.0f} {ticks / wall:12.0f} {1e6 * cpu / ticks:12.1f} "
                  f"{cpu / wall:9.2f}", flush=True)
    res["load_end"] = round(os.getloadavg()[0], 2)
    print(f"load average {res['load_end']:.2f} at the end")
    if "dwa" in names:
        print("\nhow many times a dwa decision costs another controller's (same robot):")
        for model in ("holonomic", "diff-drive"):
            ref = rows[("dwa", model)]
            print(f"  {model}: " + ", ".join(f"{n} {ref / rows[(n, model)]:.0f}x"
                                            for n in names if n != "dwa"))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)
    return res


if __name__ == "__main__":
    main()
