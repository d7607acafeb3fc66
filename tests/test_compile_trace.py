"""benchmarks/compile_trace.py: on an empty numba cache it lists what a command compiles,
each function's CPU time split into type inference, numba's lowering, LLVM's own work and
the rest, and the parts add up to the totals it prints (nothing about speed is asserted)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_trace_of_a_cold_astar_plan(tmp_path):
    # compiled: on an empty cache a plan on the paper map runs its kernels interpreted
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PATHFUSE_KERNELS": "compiled"}
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "compile_trace.py"), "plan",
                          "--map", "paper", "--planner", "astar"], capture_output=True,
                         text=True, env=env, check=True, timeout=600).stdout
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.split() == [
        "CPU", "s", "typing", "lowering", "llvm", "other", "function"])
    rows = {}
    for line in lines[head + 1:]:
        if not re.match(r"^\s+\d", line):
            break
        *nums, name = line.split(None, 5)
        rows[name] = [float(x) for x in nums]
    names = set(rows)
    assert "pathfuse.search.kernel._make_kernel.<locals>.kernel" in names
    assert "pathfuse.search.kernel._trace" in names
    assert not any("fusion" in n or "field" in n for n in names)  # only what astar runs
    for name, (total, *parts) in rows.items():
        assert abs(total - sum(parts)) <= 0.011, (name, total, parts)  # rounding of 4 parts
    everything = rows.pop("(all)")
    for k in range(5):
        assert abs(everything[k] - sum(r[k] for r in rows.values())) <= 0.01 * (len(rows) + 1)
    assert everything[3] > 0.0  # LLVM ran: its passes and machine code are measured
    summary = next(line for line in lines if line.startswith("numba's own set-up"))
    compiled = float(re.search(r"compiling ([\d.]+) s \((\d+) functions\)", summary)[1])
    assert abs(compiled - everything[0]) <= 0.011
    assert re.search(r"cache: 0 loaded \(\), \d+ missed", out)
