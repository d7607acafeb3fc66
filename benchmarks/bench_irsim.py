"""What the IR-SIM adapter costs per IR-SIM step (issue 18: at most 2 ms for fusion).

Runs every shipped people world (``examples/irsim``, seed 0) with each planner
(default: ``fusion`` at its defaults) through
:class:`pathfuse.integrations.irsim.IrsimController`, after one untimed warm-up
episode per planner (numba compiles or loads its kernels there), and times at
every step, wall clock and process CPU time:

* ``act``: the whole :meth:`IrsimController.act` (sensing the walkers, the
  planner's command through the shield, converting the action);
* ``adapter``: ``act`` less the planner's command: what the adapter itself adds;
* ``command``: the planner's command (:meth:`Controller.command`), for scale;
* ``env.step``: IR-SIM's own step, for scale.

Medians, 95th percentiles and maxima over every step of every world, the load
average before and after, and the machine.  Timings are never asserted in tests;
this script is where they are measured.

Usage::

    python benchmarks/bench_irsim.py [--planners fusion,dwa] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from pathfuse.integrations.irsim import IrsimController, make_env
from pathfuse.integrations.irsim_run import perturb_env, read_world_spec

WORLDS = Path(__file__).resolve().parents[1] / "examples" / "irsim"


def episode(world: Path, planner: str, seed: int = 0) -> dict[str, list[float]]:
    """One episode; per-step wall and CPU times (s) of each part."""
    spec = read_world_spec(world)
    env = make_env(world, seed=seed)
    perturb_env(env, seed, spec.position_m, spec.speed_frac, (env.robot.id,))
    ctrl = IrsimController(env, planner)
    out: dict[str, list[float]] = {k: [] for k in ("act", "adapter", "command", "step",
                                                   "act_cpu", "step_cpu")}
    n = int(round(spec.time_limit_s / float(env._world.step_time)))
    for _ in range(n):
        c0, w0 = time.process_time(), time.perf_counter()
        a = ctrl.act(env)
        w1, c1 = time.perf_counter(), time.process_time()
        env.step(a)
        w2, c2 = time.perf_counter(), time.process_time()
        out["act"].append(w1 - w0)
        out["adapter"].append((w1 - w0) - ctrl.command_times_s[-1])
        out["command"].append(ctrl.command_times_s[-1])
        out["step"].append(w2 - w1)
        out["act_cpu"].append(c1 - c0)
        out["step_cpu"].append(c2 - c1)
        if env.robot.collision or env.robot.arrive or ctrl.failure is not None:
            break
    return out


def _cell(seconds: list[float]) -> str:
    v = 1e3 * np.asarray(seconds)
    return f"{np.median(v):.3f} / {np.percentile(v, 95):.3f} / {v.max():.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--planners", default="fusion")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    worlds = sorted(WORLDS.glob("*.yaml"))
    load0 = os.getloadavg()
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, {platform.processor() or '?'}"
          f", Python {platform.python_version()}; load average before "
          f"{load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}")
    print(f"{len(worlds)} worlds (examples/irsim, seed 0), {a.repeat} repeats; ms per IR-SIM "
          "step: median / p95 / max\n")
    print("| planner | steps | act (wall) | act (CPU) | adapter (wall) | planner command (wall)"
          " | IR-SIM env.step (wall) | env.step (CPU) |")
    print("|---|---|---|---|---|---|---|---|")
    for planner in [p.strip() for p in a.planners.split(",") if p.strip()]:
        episode(worlds[0], planner)  # warm-up: compiles or loads the kernels, not timed
        acc: dict[str, list[float]] = {}
        for _ in range(a.repeat):
            for w in worlds:
                for k, v in episode(w, planner).items():
                    acc.setdefault(k, []).extend(v)

        cells = {k: _cell(v) for k, v in acc.items()}
        print(f"| {planner} | {len(acc['act'])} | {cells['act']} | {cells['act_cpu']} | "
              f"{cells['adapter']} | {cells['command']} | {cells['step']} | "
              f"{cells['step_cpu']} |")
    load1 = os.getloadavg()
    print(f"\nload average after {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")


if __name__ == "__main__":
    main()
