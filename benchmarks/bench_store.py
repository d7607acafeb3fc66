"""Time of the result store's writes on a realistic sweep (measured, not asserted).

Runs the sweep once (``--seeds``, default 100: the 3600 runs of the fusion
sweep) and records every batch of rows the runner hands to
``ResultStore.insert_runs``; then writes those same batches, each in its own
transaction as the runner does, into a fresh database ``--repeat`` times and
prints the median and range of the total write time.  ``--baseline`` names
another store module (e.g. the schema-1 store from git history) timed on the
same rows, alternating with the current one::

    git show 71f9583:src/pathfuse/bench/store.py > /tmp/store_v1.py
    python benchmarks/bench_store.py --baseline /tmp/store_v1.py
    python benchmarks/bench_store.py --baseline /tmp/store_v1.py --baseline-without-progress \
        --experiment experiments/dynamic-benchmark.yaml --seeds 5

Only the store is timed: the runs themselves, the registry rows (experiments and
configurations) and the opening of the database are not.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

REPO = Path(__file__).resolve().parents[1]


def capture(experiment: str, seeds: int, workers: int, folder: Path
            ) -> list[list[dict[str, Any]]]:
    """Run the sweep and return the row batches the runner stored (ids as written)."""
    from pathfuse.bench import run_bench
    from pathfuse.bench import store as st

    batches: list[list[dict[str, Any]]] = []
    orig = st.ResultStore.insert_runs

    def record(self: Any, rows: Any) -> int:
        batches.append([dict(r) for r in rows])
        return int(orig(self, rows))

    st.ResultStore.insert_runs = record  # type: ignore[method-assign]
    try:
        run_bench(experiment, folder / "capture.db", seeds=seeds, workers=workers,
                  progress=False)
    finally:
        st.ResultStore.insert_runs = orig  # type: ignore[method-assign]
    return batches


def load_module(path: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location("baseline_store", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def write_once(mod: ModuleType, batches: list[list[dict[str, Any]]], db: Path) -> float:
    """Seconds to write every batch into a fresh store of module ``mod``."""
    with mod.ResultStore(db) as store:
        eids: dict[Any, int] = {}
        pids: dict[Any, int] = {}
        for rows in batches:  # the registry rows first, untimed (the runner does the same)
            for r in rows:
                eids.setdefault(r["experimentid"], store.ensure_experiment(
                    "bench", f"entry{r['experimentid']}", str(r.get("kind") or "static")))
                pids.setdefault(r["plannerid"], store.ensure_planner_config(
                    f"cfg{r['plannerid']}", str(r.get("planner") or "x"), "{}"))
        ready = [[{**r, "experimentid": eids[r["experimentid"]],
                   "plannerid": pids[r["plannerid"]]} for r in rows] for rows in batches]
        t0 = time.perf_counter()
        for rows in ready:
            store.insert_runs(rows)
        return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--experiment",
                    default=str(REPO / "experiments" / "fusion-sweep-r1-r2-step.yaml"))
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--workers", type=int, default=2,
                    help="workers of the captured sweep (they set the batch sizes; default 2)")
    ap.add_argument("--baseline", help="path of another store module to time on the same rows")
    ap.add_argument("--baseline-without-progress", action="store_true",
                    help="give the baseline the rows without their progress samples (as the "
                         "schema-1 runner made them)")
    args = ap.parse_args(argv)
    from pathfuse.bench import store as current

    mods: dict[str, ModuleType] = {"current": current}
    if args.baseline:
        mods["baseline"] = load_module(args.baseline)
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        batches = capture(args.experiment, args.seeds, args.workers, folder)
        n = sum(len(b) for b in batches)
        rows = {k: batches for k in mods}
        if args.baseline_without_progress:
            rows["baseline"] = [[{k: v for k, v in r.items() if k != "progress"} for r in b]
                                for b in batches]
        times: dict[str, list[float]] = {k: [] for k in mods}
        for i in range(args.repeat):
            for name, mod in mods.items():
                times[name].append(write_once(mod, rows[name], folder / f"{name}{i}.db"))
    load = os.getloadavg()
    samples = sum(len(r.get("progress") or ()) for b in batches for r in b)
    print(f"{n} runs in {len(batches)} batches, {samples} progress samples "
          f"({Path(args.experiment).name}, seeds {args.seeds}, {args.workers} workers); "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    for name, ts in times.items():
        print(f"  {name:8s} median {statistics.median(ts) * 1e3:7.1f} ms "
              f"(min {min(ts) * 1e3:.1f}, max {max(ts) * 1e3:.1f}, {len(ts)} repeats), "
              f"{statistics.median(ts) / n * 1e6:.1f} us per run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
