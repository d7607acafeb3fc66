"""Start-up of the command line: import, ``--help``, and a first plan on a cold numba cache.

Each command runs as its own process; its CPU time is the user + system time
of the finished child (``resource.getrusage(RUSAGE_CHILDREN)``), its wall time
measured around it.  Cold runs point ``NUMBA_CACHE_DIR`` at a new empty folder
each time, so numba compiles every kernel the command runs; a warm run reuses
the folder of the cold run before it.

* ``import``: ``python -c "import pathfuse"``;
* ``help``: ``pathfuse --help``;
* ``numba``: ``import numba`` and a first compilation (of a one-line function): numba's
  own start-up, which every first plan pays;
* ``plan-<planner>``: ``pathfuse plan --map paper --planner <planner>``: ``cold`` on an
  empty cache under the default rule (``PATHFUSE_KERNELS`` unset: a small map's plan runs
  its kernels interpreted, :mod:`pathfuse.tier`), ``compile`` on an empty cache with
  ``PATHFUSE_KERNELS=compiled`` (what compiling the kernels costs), and ``warm`` with the
  kernels in the cache (the folder of the ``compile`` run before it; the default rule then
  runs them compiled).

pathfuse's modules are byte-compiled first (:func:`byte_compile`), as an installed
package's are, so no run pays for compiling Python sources.

Usage::

    python benchmarks/bench_startup.py [--runs 5] [--cold-runs 2]
        [--planners astar fusion] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

PATHFUSE = [sys.executable, "-m", "pathfuse.cli"]
NUMBA_FLOOR = "import numba; numba.njit(lambda a: a + 1)(1)"


def run(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one run of ``cmd``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def byte_compile() -> None:
    """Write the bytecode of every pathfuse module, as ``pip install`` does.

    A source checkout run with ``PYTHONDONTWRITEBYTECODE`` set (or from a read-only
    folder) has none, and then every start-up compiles the sources of the modules it
    imports (about 0.2 s of CPU for a plan): a cost an installed pathfuse does not have.
    The children still honour the variable; they read these files.
    """
    import compileall
    import importlib.util

    spec = importlib.util.find_spec("pathfuse")
    assert spec is not None and spec.submodule_search_locations
    for folder in spec.submodule_search_locations:
        compileall.compile_dir(folder, quiet=1)


def summary(samples: list[tuple[float, float]]) -> dict[str, Any]:
    cpu = [c for c, _ in samples]
    wall = [w for _, w in samples]
    return {"runs": len(samples), "cpu_s": statistics.median(cpu),
            "wall_s": statistics.median(wall), "cpu_min_s": min(cpu), "cpu_max_s": max(cpu)}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="runs of each warm command")
    ap.add_argument("--cold-runs", type=int, default=2, help="runs on an empty numba cache")
    ap.add_argument("--planners", nargs="+", default=["astar", "fusion"])
    ap.add_argument("--json", type=Path, help="write the numbers to this file")
    args = ap.parse_args(argv)
    out: dict[str, Any] = {"machine": {"machine": platform.machine(), "cores": os.cpu_count(),
                                       "load": round(os.getloadavg()[0], 2),
                                       "python": platform.python_version()}}
    byte_compile()
    run([sys.executable, "-c", "import pathfuse"])  # the files in the page cache
    out["import"] = summary([run([sys.executable, "-c", "import pathfuse"])
                             for _ in range(args.runs)])
    out["help"] = summary([run([*PATHFUSE, "--help"]) for _ in range(args.runs)])
    # numba's own start-up, the floor under any first plan: its import and its first
    # compilation (of a one-line function) in a process
    out["numba"] = summary([run([sys.executable, "-c", NUMBA_FLOOR]) for _ in range(args.runs)])
    for planner in args.planners:
        cmd = [*PATHFUSE, "plan", "--map", "paper", "--planner", planner]
        cold, compiled, warm = [], [], []
        base = {k: v for k, v in os.environ.items() if k != "PATHFUSE_KERNELS"}
        for _ in range(args.cold_runs):
            cache = tempfile.mkdtemp(prefix="pathfuse-numba-")
            env = {**base, "NUMBA_CACHE_DIR": cache}
            try:
                cold.append(run(cmd, env))  # interpreted: leaves the cache empty
                compiled.append(run(cmd, {**env, "PATHFUSE_KERNELS": "compiled"}))
                warm.extend(run(cmd, env) for _ in range(max(1, args.runs // args.cold_runs)))
            finally:
                shutil.rmtree(cache, ignore_errors=True)
        out[f"plan-{planner}"] = {"cold": summary(cold), "compile": summary(compiled),
                                  "warm": summary(warm)}
    out["load_end"] = round(os.getloadavg()[0], 2)
    m = out["machine"]
    print(f"machine: {m['machine']}, {m['cores']} cores, load average {m['load']} at the start, "
          f"{out['load_end']} at the end; python {m['python']}")
    for key in ("import", "help", "numba"):
        s = out[key]
        print(f"{key:<14} CPU {s['cpu_s']:.3f} s, wall {s['wall_s']:.3f} s (median of {s['runs']})")
    for planner in args.planners:
        for kind in ("cold", "compile", "warm"):
            s = out[f"plan-{planner}"][kind]
            print(f"plan {planner:<9} {kind:<7}: CPU {s['cpu_s']:.2f} s (min {s['cpu_min_s']:.2f}, "
                  f"max {s['cpu_max_s']:.2f}), wall {s['wall_s']:.2f} s, {s['runs']} runs")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return out


if __name__ == "__main__":
    main()
