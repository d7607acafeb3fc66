"""The execution backends of a sweep: in this process, a local process pool, a Dask cluster.

Runs travel in batches of groups (runs that share a map instance); workers
return result rows and never touch the store; the client's sink writes them.
A worker that dies takes its batch down with it: the batches in flight are
re-run one run at a time in a fresh single-worker pool, so only the run that
kills its worker is stored as an ``ERROR``.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing as mp
import os
import signal
import sys
import time
from collections import deque
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from pathfuse.bench.execute import execute_batch, execute_run
from pathfuse.bench.experiment import (
    Experiment,
    RunSpec,
    iter_groups,
)
from pathfuse.bench.plugins import ensure_imports
from pathfuse.result import PathfuseError


class Sink(Protocol):
    """Where a backend hands the finished rows (the runner's store writer)."""

    def write(self, rows: Sequence[dict[str, Any]]) -> None: ...


CRASH_TEXT = ("WorkerCrashed: the worker process died while running this run "
              "(segfault, os._exit, out of memory or killed)")


# --------------------------------------------------------------------------- batching
def make_batches(runs: Sequence[RunSpec], workers: int,
                 batch_size: int | None = None) -> list[list[list[RunSpec]]]:
    """Pack runs into batches of at most ``batch_size`` runs; a batch is a list of groups
    (consecutive runs on the same map instance), so a worker loads each map once.

    The default size gives each worker about eight batches, capped at 64 runs.
    """
    if not runs:
        return []
    if batch_size is None:
        batch_size = max(1, min(64, math.ceil(len(runs) / (max(1, workers) * 8))))
    batches: list[list[list[RunSpec]]] = []
    cur: list[list[RunSpec]] = []
    n = 0
    for group in iter_groups(runs):
        for i in range(0, len(group), batch_size):
            chunk = group[i:i + batch_size]
            if n + len(chunk) > batch_size and cur:
                batches.append(cur)
                cur, n = [], 0
            cur.append(chunk)
            n += len(chunk)
    if cur:
        batches.append(cur)
    return batches


def _run_payload(r: RunSpec) -> dict[str, Any]:
    return {"key": r.key, "planner": r.planner, "params": r.params, "seed": r.seed,
            "query": r.query, "limits": r.limits, "robot_radius_m": r.robot_radius_m,
            "reference": r.reference}


def _group_payload(exp: Experiment, chunk: Sequence[RunSpec],
                   grids: dict[str, Any] | None = None) -> dict[str, Any]:
    r0 = chunk[0]
    g: dict[str, Any] = {"kind": r0.kind, "map_key": r0.map_key, "map_spec": r0.map_spec,
                         "base_dir": str(exp.base_dir.resolve()),
                         "runs": [_run_payload(r) for r in chunk]}
    if grids and r0.map_key in grids:
        g["grid"] = grids[r0.map_key]
    return g


def _batch_payload(exp: Experiment, batch: Sequence[Sequence[RunSpec]],
                   grids: dict[str, Any] | None = None) -> dict[str, Any]:
    return {"imports": exp.import_paths(), "store_paths": exp.store_paths,
            "groups": [_group_payload(exp, c, grids) for c in batch]}



def _crash_row(run: RunSpec) -> dict[str, Any]:
    return {"run_key": run.key, "status_name": "ERROR", "solved": False, "error": CRASH_TEXT}


def _exception_rows(batch: Sequence[Sequence[RunSpec]], exc: BaseException) -> list[dict]:
    text = f"{type(exc).__name__}: {exc}".strip()
    return [{"run_key": r.key, "status_name": "ERROR", "solved": False, "error": text}
            for chunk in batch for r in chunk]


# --------------------------------------------------------------------------- backends
SERIAL_FLUSH_S = 0.25
"""In-process runs are committed in small batches, at least this often (seconds): a kill
loses at most the runs of the last quarter second, which the same command runs again."""


def _run_serial(exp: Experiment, todo: Sequence[RunSpec], sink: Sink) -> None:
    pending: list[dict[str, Any]] = []
    last = time.perf_counter()
    try:
        for group in iter_groups(todo):
            gp = _group_payload(exp, group)
            for r in group:
                pending.append(execute_run(gp, _run_payload(r), store_paths=exp.store_paths))
                now = time.perf_counter()
                if len(pending) >= 256 or now - last >= SERIAL_FLUSH_S:
                    sink.write(pending)
                    pending, last = [], now
    finally:  # Ctrl-C: what finished is stored
        if pending:
            sink.write(pending)


def _worker_init(imports: Sequence[str], client_pid: int | None = None) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the client handles Ctrl-C and SIGTERM;
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # it stops the workers itself
    if client_pid is not None:  # die with the client, even after kill -9
        from pathfuse.bench.lifeline import watch_client

        watch_client(client_pid)
    ensure_imports(imports)


def _mp_context() -> Any:
    methods = mp.get_all_start_methods()
    if "forkserver" in methods:
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["pathfuse", "pathfuse.bench.execute",
                                    "pathfuse.bench._preload"])
        return ctx
    return mp.get_context("spawn")


def _ping() -> int:
    return os.getpid()


@contextlib.contextmanager
def _main_without_file() -> Any:
    """Hide ``__main__.__file__`` when it is no file (``python - < script``, REPL tools).

    Fork-server and spawn workers re-import the main script by its path; a
    main read from stdin has none, and every worker would die at start.  The
    workers run only pathfuse code, so they do not need the main module.
    """
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    hide = path is not None and getattr(main, "__spec__", None) is None and \
        not os.path.isfile(path)
    if hide:
        del main.__file__  # type: ignore[union-attr]
    try:
        yield
    finally:
        if hide:
            main.__file__ = path  # type: ignore[union-attr]


class WorkersCannotStart(PathfuseError):
    """The worker processes die before running anything (an import error, a bad plug-in)."""


class _Pool:
    """A process pool whose workers are started (and checked) before it is used."""

    def __init__(self, workers: int, imports: Sequence[str]) -> None:
        self.ex = ProcessPoolExecutor(max_workers=workers, mp_context=_mp_context(),
                                      initializer=_worker_init,
                                      initargs=(list(imports), os.getpid()))
        try:
            pings = [self.ex.submit(_ping) for _ in range(workers)]
            for f in pings:
                f.result(timeout=300)
        except BaseException as exc:  # Ctrl-C/SIGTERM while starting: stop the workers
            self.kill()
            if not isinstance(exc, BrokenProcessPool):
                raise
            raise WorkersCannotStart(
                "the worker processes die as they start (see the errors above); run with "
                "workers=1 to see the problem in this process") from None

    def submit(self, payload: dict[str, Any]) -> Future:
        try:
            return self.ex.submit(execute_batch, payload)
        except (BrokenProcessPool, RuntimeError) as exc:  # broke since the last check
            f: Future = Future()
            f.set_exception(BrokenProcessPool(str(exc)))
            return f

    def kill(self) -> None:
        procs = list(getattr(self.ex, "_processes", {}).values())
        self.ex.shutdown(wait=False, cancel_futures=True)
        for p in procs:  # only the workers this pool started (they ignore SIGTERM)
            if p.is_alive():
                p.kill()
        for p in procs:
            p.join(timeout=5)


def _run_pool(exp: Experiment, todo: Sequence[RunSpec], sink: Sink, workers: int,
              batch_size: int | None) -> None:
    imports = exp.import_paths()
    pending = deque(make_batches(todo, workers, batch_size))
    pool = _Pool(workers, imports)
    in_flight: dict[Future, list[list[RunSpec]]] = {}
    try:
        while pending or in_flight:
            while pending and len(in_flight) < 2 * workers:
                b = pending.popleft()
                in_flight[pool.submit(_batch_payload(exp, b))] = b
            done, _ = wait(list(in_flight), return_when=FIRST_COMPLETED)
            broken: list[list[list[RunSpec]]] = []
            for f in done:
                b = in_flight.pop(f)
                try:
                    rows = f.result()
                except BrokenProcessPool:
                    broken.append(b)
                    continue
                except Exception as exc:  # noqa: BLE001 - e.g. an unpicklable result
                    rows = _exception_rows(b, exc)
                sink.write(rows)
            if broken:
                # every other batch in flight fails with the pool; keep those that finished
                rest = list(in_flight.items())
                in_flight.clear()
                wait([f for f, _ in rest], timeout=30)
                for f, b in rest:
                    try:
                        sink.write(f.result(timeout=0))
                    except Exception:  # noqa: BLE001 - broken or cancelled
                        broken.append(b)
                pool.kill()
                _isolate(exp, [r for b in broken for c in b for r in c], sink, imports)
                pool = _Pool(workers, imports)
    finally:
        pool.kill()


def _isolate(exp: Experiment, runs: Sequence[RunSpec], sink: Sink,
             imports: Sequence[str]) -> None:
    """Re-run suspects one by one in a single-worker pool to find the run that crashes."""
    pool = _Pool(1, imports)
    try:
        for r in runs:
            fut = pool.submit(_batch_payload(exp, [[r]]))
            try:
                rows = fut.result()
            except BrokenProcessPool:
                rows = [_crash_row(r)]
                pool.kill()
                pool = _Pool(1, imports)
            except Exception as exc:  # noqa: BLE001
                rows = _exception_rows([[r]], exc)
            sink.write(rows)
    finally:
        pool.kill()
