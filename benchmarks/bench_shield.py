"""What the safety shield costs per command, against the check it replaced.

The shield (:mod:`pathfuse.shield`) runs once per tick for every online
controller.  This replays the states of real BARN episodes (the four worlds
of ``tests/data/barn``, the diff-drive Jackal-sized disc at 2 m/s, ``dwa``
driving, the shield on) and times, on each state:

* ``shield (asked)``: :func:`~pathfuse.shield.shield_unicycle` on the command
  the robot really applied (what almost every tick costs: the command passes),
  called as ``Controller.command`` calls it, with the window's sample counts
  ``NV, NW`` given (an omitted default argument sends every call through
  numba's slow dispatch);
* ``shield (adversarial)``: the same on full speed at a random yaw rate, so the
  window search runs whenever that command has no clear stop;
* ``straight-stop check``: the previous conversion's admissibility test of one
  command (:func:`pathfuse.planners.drive.admissible`, a straight stop), the
  peer the shield replaced;
* ``dwa decision``: one ``dwa`` control decision (``Episode.plan_times_s``), for
  scale.

Medians, 95th percentiles and maxima over all states, with the process CPU
time beside the wall time, the load average and the machine.  numba compiles
in a warm-up first (not timed).

With ``--json PATH`` it also writes the figures, the machine and the load
(``benchmarks/run_all.py`` writes the speed page's ``shield`` block from them).

Usage::

    python benchmarks/bench_shield.py [--repeat 5] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from pathfuse.costmap import NO_DISCS, costmap_for
from pathfuse.planners.drive import admissible
from pathfuse.shield import CODE_NAMES, NV, NW, shield_unicycle, warmup_shield
from pathfuse.studies.barn import BarnConfig, _scenario, find_worlds, jackal_robot
from pathfuse.world import load_scenario, simulate

BARN = Path(__file__).resolve().parents[1] / "tests" / "data" / "barn"


def states() -> tuple[list[tuple], list[float]]:
    """(scenario grid, pose, last command, applied command) of every tick, and the dwa
    decision times."""
    cfg = BarnConfig(str(BARN), resolution=0.05, robot=jackal_robot("diff-drive"))
    out = []
    decide = []
    for w in find_worlds(BARN, None):
        sc = load_scenario(_scenario(cfg, w, "0" * 16))
        ep = simulate(sc, planner="dwa")
        decide.extend(ep.plan_times_s[1:].tolist())
        for t in range(ep.n_ticks):
            prev = ep.commands[t - 1] if t else np.zeros(2)
            out.append((sc, ep.positions[t], float(ep.headings[t]), prev, ep.commands[t]))
    return out, decide


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="timings per state (the least kept)")
    ap.add_argument("--json", help="write the figures to this file")
    a = ap.parse_args(argv)
    load0 = round(os.getloadavg()[0], 2)
    warmup_shield()
    data, decide = states()
    rng = np.random.default_rng(0)
    rows: dict[str, list[float]] = {"shield (asked)": [], "shield (adversarial)": [],
                                    "straight-stop check": []}
    codes = np.zeros(5, dtype=np.int64)
    c0 = time.process_time()
    w0 = time.perf_counter()
    for sc, p, th, prev, cmd in data:
        g = sc.grid
        rb = sc.robot
        cm = costmap_for(g, rb.radius_m)
        clear = cm.clear_m
        lim = (rb.min_speed_mps, rb.max_speed_mps, rb.max_accel_mps2, rb.max_yaw_rate_radps,
               rb.max_yaw_accel_radps2)
        adv = (rb.max_speed_mps, float(rng.uniform(-1, 1)) * rb.max_yaw_rate_radps)
        for name, (v, w) in (("shield (asked)", cmd), ("shield (adversarial)", adv)):
            best = np.inf
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                out = shield_unicycle(cm, float(p[0]), float(p[1]), th,
                                      float(prev[0]), float(prev[1]), float(v), float(w),
                                      float(sc.dt), *lim, NO_DISCS, 0.0, NV, NW)
                best = min(best, time.perf_counter() - t0)
            rows[name].append(best)
            if name == "shield (adversarial)":
                codes[out[2]] += 1
        v, w = float(cmd[0]), float(cmd[1])
        best = np.inf
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            admissible(cm, float(p[0]), float(p[1]), th, v, w, float(sc.dt),
                       v * v / (2.0 * rb.max_accel_mps2), clear)
            best = min(best, time.perf_counter() - t0)
        rows["straight-stop check"].append(best)
    cpu = time.process_time() - c0
    wall = time.perf_counter() - w0
    rows["dwa decision"] = decide
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, {platform.python_version()}; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"{len(data)} states of 4 BARN episodes (dwa, diff-drive 0.333 m, 2 m/s); "
          f"timing loop {wall:.1f} s wall, {cpu:.1f} s CPU")
    ref = float(np.median(rows["straight-stop check"]))
    print(f"{'':24s} {'median µs':>10s} {'p95 µs':>9s} {'max µs':>9s} {'median / straight':>18s}")
    for name, vals in rows.items():
        x = np.asarray(vals) * 1e6
        print(f"{name:24s} {np.median(x):10.1f} {np.percentile(x, 95):9.1f} {x.max():9.1f} "
              f"{np.median(x) / (ref * 1e6):18.1f}")
    print("adversarial commands: " + ", ".join(f"{n} {codes[i]}"
                                               for i, n in enumerate(CODE_NAMES)))
    res = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(), "load": load0,
                       "python": platform.python_version()},
           "load_end": round(os.getloadavg()[0], 2), "states": len(data), "repeat": a.repeat,
           "rows": {name: {"median_us": float(np.median(np.asarray(v) * 1e6)),
                           "p95_us": float(np.percentile(np.asarray(v) * 1e6, 95)),
                           "max_us": float(np.max(np.asarray(v) * 1e6))}
                    for name, v in rows.items()},
           "adversarial_codes": {n: int(codes[i]) for i, n in enumerate(CODE_NAMES)}}
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=2)
    return res


if __name__ == "__main__":
    main()
