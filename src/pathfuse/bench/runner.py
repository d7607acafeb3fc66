"""Run a sweep: expand the experiment, skip what is stored, execute the rest, store it.

:func:`run_bench` is what ``pathfuse bench`` calls.  Execution backends:

* ``workers=1``: in this process, one run after another, each committed as
  it finishes;
* ``workers=N`` (default: the CPUs this process may use): a local process
  pool; runs travel in batches that share maps, which each worker caches;
* ``scheduler="tcp://HOST:PORT"``: an existing Dask distributed cluster
  (``pip install pathfuse[dask]``); workers only compute, this process (the
  client) writes the store.

The client is the only writer.  A sweep that is interrupted (Ctrl-C,
``kill -9``, a crashed worker, a lost cluster) and started again with the
same command runs only the runs whose keys are not yet stored, and ends with
the same result set as an uninterrupted sweep (wall-clock columns aside).
A worker process that dies (segfault, ``os._exit``, out of memory) takes
its batch down with it; the runner re-runs the batches that were in flight
one run at a time in a fresh single-worker pool, so the run that kills its
worker is stored as an ``ERROR`` ("worker process died") and the others
complete.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from pathfuse.bench.dask_backend import DEFAULT_WORKER_WAIT_S, ClusterLost, run_dask
from pathfuse.bench.experiment import (
    Experiment,
    RunSpec,
    canonical_json,
    load_experiment,
)
from pathfuse.bench.lock import StudyLocked, study_lock
from pathfuse.bench.pool import (
    WorkersCannotStart,
    _main_without_file,
    _run_pool,
    _run_serial,
    make_batches,
)
from pathfuse.bench.progress import ProgressBar, progress_enabled
from pathfuse.bench.store import ResultStore
from pathfuse.bench.warmup import warm_kernels
from pathfuse.result import ConfigError
from pathfuse.stats import counted

__all__ = ["run_bench", "run_experiment", "SweepSummary", "SweepInterrupted", "StudyLocked",
           "ClusterLost",
           "WorkersCannotStart", "make_batches", "default_workers"]

CRASH_TEXT = ("WorkerCrashed: the worker process died while running this run "
              "(segfault, os._exit, out of memory or killed)")


@dataclass
class SweepSummary:
    """What a sweep did.  ``str(summary)`` is a short human report."""

    experiment: str
    db_path: str
    total: int = 0
    skipped: int = 0
    ran: int = 0
    succeeded: int = 0
    failed: int = 0
    errors: int = 0
    crashed: int = 0
    interrupted: bool = False
    wall_s: float = 0.0
    workers: int = 1
    scheduler: str | None = None
    error_samples: list[str] = field(default_factory=list)
    compile_s: float = 0.0
    """Seconds of ``wall_s`` spent compiling (or loading) kernels before the runs started."""
    stored_errors: int = 0
    """Runs skipped because they are stored as ``ERROR`` (``retry_errors`` runs them)."""

    @property
    def runs_per_s(self) -> float:
        return self.ran / self.wall_s if self.wall_s > 0 else 0.0

    @property
    def complete(self) -> bool:
        """True when every run of the experiment is now stored."""
        return self.skipped + self.ran == self.total

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["runs_per_s"] = self.runs_per_s
        d["complete"] = self.complete
        return d

    def __str__(self) -> str:
        where = self.scheduler or counted(self.workers, "worker")
        stored = self.skipped + self.ran
        if self.ran == 0 and self.complete and not self.interrupted:
            errs = (f"; {self.stored_errors} of them raised (ERROR), --retry-errors runs "
                    "them again") if self.stored_errors else ""
            every = (f"all {self.total} runs are" if self.total != 1 else "its one run is")
            return (f"{self.experiment}: nothing to run, {every} already "
                    f"stored in {self.db_path} ('pathfuse report {self.db_path}' summarises "
                    f"{'them' if self.total != 1 else 'it'}){errs}")
        comp = f", {self.compile_s:.1f} s of it compiling kernels" \
            if self.compile_s >= 1.0 else ""
        head = (f"{self.experiment}: {counted(self.ran, 'run')} in {self.wall_s:.1f} s "
                f"({self.runs_per_s:.1f} runs/s, {where}{comp}); {self.skipped} already stored; "
                f"{stored}/{self.total} in {self.db_path}")
        tail = (f"\n  of the {counted(self.ran, 'run')} now: solved {self.succeeded}, not solved "
                f"{self.failed}, errors {self.errors}")
        if self.crashed:
            tail += f" ({self.crashed} crashed their worker)"
        if self.interrupted:
            tail += "\n  interrupted: run the same command again to finish the missing runs"
        for e in self.error_samples:
            tail += f"\n  error: {e}"
        return head + tail


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep; ``.summary`` holds what was stored before it."""

    def __init__(self, summary: SweepSummary, signame: str = "") -> None:
        super().__init__(str(summary))
        self.summary = summary
        self.signame = signame
        """``"SIGTERM"`` when a SIGTERM (made a :class:`~pathfuse.bench.lifeline.Terminated`)
        stopped the sweep, ``""`` for Ctrl-C."""


def default_workers() -> int:
    """CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


# --------------------------------------------------------------------------- the sink
class _Sink:
    """Completes worker rows with what the client knows, and writes them."""

    def __init__(self, store: ResultStore, exp: Experiment, runs: Sequence[RunSpec],
                 summary: SweepSummary, bar: ProgressBar) -> None:
        self.store = store
        self.summary = summary
        self.bar = bar
        self.specs = {r.key: r for r in runs}
        self.exp_ids: dict[str, int] = {}
        self.cfg_ids: dict[tuple[str, str], int] = {}
        per_cfg: dict[tuple[str, str], int] = {}
        for r in runs:
            per_cfg[(r.group, r.config)] = per_cfg.get((r.group, r.config), 0) + 1
        with store.transaction():
            for entry in exp.maps:
                counts = [v for (g, _), v in per_cfg.items() if g == entry.name]
                setup = canonical_json({k: v for k, v in asdict(entry).items()
                                        if k != "index"})
                self.exp_ids[entry.name] = store.ensure_experiment(
                    exp.name, entry.name, entry.kind,
                    timelimit=float(exp.limits.time_limit_s or 0.0),
                    runcount=max(counts) if counts else 0, seed=entry.seeds[0], setup=setup)
            for r in runs:
                k = (r.config, r.settings)
                if k not in self.cfg_ids:
                    self.cfg_ids[k] = store.ensure_planner_config(r.config, r.planner,
                                                                  r.settings)

    def notice(self, text: str) -> None:
        """One line on the progress bar's stream (the cluster lost its workers, ...)."""
        self.bar.notice(text)

    def complete(self, row: dict[str, Any]) -> dict[str, Any]:
        r = self.specs[row["run_key"]]
        out = dict(row)
        out.update({
            "experimentid": self.exp_ids[r.group],
            "plannerid": self.cfg_ids[(r.config, r.settings)],
            "problem_key": r.problem_key, "kind": r.kind, "map_name": r.group,
            "planner": r.planner, "seed": r.seed, "query_index": r.query_index,
            "scen_line": r.query.get("line"), "params": r.payload,
        })
        q = r.query
        if "start" in q and out.get("start_x") is None:
            out["start_x"], out["start_y"] = q["start"]
            out["goal_x"], out["goal_y"] = q["goal"]
        return out

    def write(self, rows: Sequence[dict[str, Any]]) -> None:
        full = [self.complete(row) for row in rows]
        self.store.insert_runs(full)
        errs = 0
        for row in full:
            st = row.get("status_name")
            if st == "ERROR":
                errs += 1
                self.summary.errors += 1
                if str(row.get("error", "")).startswith("WorkerCrashed"):
                    self.summary.crashed += 1
                if len(self.summary.error_samples) < 3:
                    self.summary.error_samples.append(
                        f"{row['map_name']} seed {row['seed']} {row['planner']}: "
                        f"{str(row.get('error'))[:200]}")
            elif row.get("solved"):
                self.summary.succeeded += 1
            else:
                self.summary.failed += 1
        self.summary.ran += len(full)
        self.bar.update(len(full), errors=errs)


# --------------------------------------------------------------------------- entry point
def run_bench(
    experiment_path: str | os.PathLike[str],
    db_path: str | os.PathLike[str],
    seeds: Any = None,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | None = True,
    *,
    retry_errors: bool = False,
    batch_size: int | None = None,
    stream: Any = None,
    on_start: Callable[[int, int], None] | None = None,
    worker_wait_s: float = DEFAULT_WORKER_WAIT_S,
) -> SweepSummary:
    """Run (or resume) the sweep of an experiment file into a result database.

    Parameters
    ----------
    experiment_path : path-like
        The experiment YAML (see :mod:`pathfuse.bench.experiment`).
    db_path : path-like
        The study's SQLite database; created if missing, resumed if not.
    seeds : optional
        Override every seed list of the file: a count, a list, ``"A:B"``.
    workers : int, optional
        Local worker processes (default: all usable CPUs; 1 runs in-process).
    scheduler : str, optional
        ``"tcp://HOST:PORT"`` of a Dask scheduler (or a ``distributed.Client``);
        ``workers`` is then ignored.
    progress : bool or None
        False shows nothing; True or None show the progress display on ``stream``
        (:mod:`pathfuse.bench.progress`: a live bar on a terminal, a few plain lines
        elsewhere) and a notice before kernels are compiled.
    retry_errors : bool
        Run again the runs stored as ``ERROR`` (their rows are replaced).
    batch_size : int, optional
        Runs per task (default: about eight tasks per worker, at most 64).
    stream : file, optional
        Where the progress bar writes (default ``sys.stderr``).
    on_start : callable, optional
        Called with ``(total, to_run)`` once the run list is known.
    worker_wait_s : float
        With ``scheduler``: how long to wait when the cluster has no worker left
        before giving up with :class:`ClusterLost` (it says so after 5 s).

    Returns
    -------
    SweepSummary

    Raises
    ------
    ConfigError
        A bad experiment file, ``workers``, ``scheduler`` or database (one line
        naming the key).
    SweepInterrupted
        Ctrl-C (or SIGTERM, see :mod:`pathfuse.bench.lifeline`); everything finished
        before it is stored.
    ClusterLost
        The Dask scheduler was lost, or no worker was left for ``worker_wait_s``; the
        runs that finished are stored, the others stay missing (the same call resumes).
    StudyLocked
        Another sweep is writing the same database (:mod:`pathfuse.bench.lock`).
    """
    t0 = time.perf_counter()
    _check_counts(workers, batch_size)
    exp = load_experiment(experiment_path, seeds=seeds)
    return run_experiment(exp, db_path, workers, scheduler, progress,
                          retry_errors=retry_errors, batch_size=batch_size, stream=stream,
                          on_start=on_start, started=t0, worker_wait_s=worker_wait_s)


def _check_counts(workers: Any, batch_size: Any) -> None:
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ConfigError(f"workers: must be an integer >= 1, got {workers!r}")
    if batch_size is not None and (isinstance(batch_size, bool)
                                   or not isinstance(batch_size, int) or batch_size < 1):
        raise ConfigError(f"batch_size: must be an integer >= 1, got {batch_size!r}")


def run_experiment(
    exp: Experiment,
    db_path: str | os.PathLike[str] | ResultStore,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool | None = True,
    *,
    retry_errors: bool = False,
    batch_size: int | None = None,
    stream: Any = None,
    on_start: Callable[[int, int], None] | None = None,
    started: float | None = None,
    label: str | None = None,
    worker_wait_s: float = DEFAULT_WORKER_WAIT_S,
    unit: str = "runs",
) -> SweepSummary:
    """Run (or resume) a validated :class:`Experiment` into a result database.

    The engine behind :func:`run_bench` and the presets ``pathfuse paper`` and
    ``pathfuse dynamic``; the arguments are those of :func:`run_bench`
    (``db_path`` may also be an open :class:`ResultStore`, left open; ``label``
    names the progress bar, default the experiment's name; ``unit`` names what it
    counts).
    """
    t0 = time.perf_counter() if started is None else started
    _check_counts(workers, batch_size)
    runs = exp.expand()
    nworkers = default_workers() if workers is None else workers
    if scheduler is not None:
        _connect_check(scheduler)
    own_store = not isinstance(db_path, ResultStore)
    # one sweep at a time per database: a second one is refused before it opens the store
    if not isinstance(db_path, ResultStore) and str(db_path) != ":memory:":
        from pathfuse.bench.dbcheck import check_study_file

        check_study_file(db_path, write=True)  # a folder, damaged, foreign, read-only
    with study_lock(db_path.path if isinstance(db_path, ResultStore) else db_path):
        store = db_path if isinstance(db_path, ResultStore) else ResultStore(db_path,
                                                                             check=False)
        return _run_locked(exp, runs, store, own_store, nworkers, scheduler, progress,
                           retry_errors, batch_size, stream, on_start, t0, label,
                           worker_wait_s, unit)


def _run_locked(exp: Experiment, runs: list[RunSpec], store: ResultStore, own_store: bool,
                nworkers: int, scheduler: Any, progress: bool | None, retry_errors: bool,
                batch_size: int | None, stream: Any,
                on_start: Callable[[int, int], None] | None, t0: float,
                label: str | None, worker_wait_s: float, unit: str) -> SweepSummary:
    experiment_path = exp.path
    summary = SweepSummary(experiment=exp.name, db_path=str(store.path), total=len(runs),
                           workers=nworkers,
                           scheduler=_scheduler_name(scheduler))
    try:
        done = store.done_keys(include_errors=not retry_errors)
        todo = [r for r in runs if r.key not in done]
        summary.skipped = len(runs) - len(todo)
        if not retry_errors and summary.skipped:
            errs = done - store.done_keys(include_errors=False)
            summary.stored_errors = sum(1 for r in runs if r.key in errs)
        if on_start is not None:
            on_start(len(runs), len(todo))
        import hashlib

        session = store.start_session(
            study=exp.name, experiment_file=str(Path(experiment_path)),
            experiment_sha256=hashlib.sha256(exp.text.encode("utf-8")).hexdigest()[:16],
            experiment_text=exp.text, workers=nworkers, scheduler=summary.scheduler,
            planned=len(runs), skipped=summary.skipped)
        enabled = progress_enabled(progress)
        bar = ProgressBar(len(runs), label=label or exp.name, stream=stream, enabled=enabled and
                          bool(todo), initial=summary.skipped, unit=unit)
        sink = _Sink(store, exp, runs, summary, bar)
        state = "failed"
        try:
            if todo and scheduler is None:  # compile once here; workers load from the cache
                tw = time.perf_counter()
                from pathfuse.bench.execute import EXTERNAL_PLANNERS

                warm_kernels([r.planner for r in todo
                              if r.planner not in EXTERNAL_PLANNERS.get(r.kind, ())],
                             metrics=True,
                             world=any(r.kind in ("dynamic", "irsim") for r in todo),
                             notify=bar.notice if enabled else None)
                summary.compile_s = time.perf_counter() - tw
                bar.start()
            if not todo:
                pass
            elif scheduler is not None:
                summary.workers = run_dask(exp, todo, sink, scheduler, batch_size,
                                           worker_wait_s)
            elif nworkers == 1 or len(todo) == 1:
                _run_serial(exp, todo, sink)
            else:
                with _main_without_file():
                    _run_pool(exp, todo, sink, nworkers, batch_size)
            state = "finished"
        except KeyboardInterrupt as exc:
            state = "interrupted"
            summary.interrupted = True
            summary.wall_s = time.perf_counter() - t0
            raise SweepInterrupted(summary, getattr(exc, "signame", "")) from None
        except ClusterLost as exc:
            state = "cluster-lost"
            summary.interrupted = True
            exc.summary = summary
            raise
        finally:
            bar.close()
            summary.wall_s = time.perf_counter() - t0
            try:
                store.update_totals()
                store.end_session(session, state=state, ran=summary.ran,
                                  errors=summary.errors)
            except Exception:  # noqa: BLE001 - never mask the original error
                pass
    finally:
        if own_store:
            store.close()
    return summary


def _scheduler_name(scheduler: Any) -> str | None:
    if scheduler is None or isinstance(scheduler, str):
        return scheduler
    try:
        return str(scheduler.scheduler.address)
    except AttributeError:
        return repr(scheduler)


def _connect_check(scheduler: Any) -> None:
    """Fail early (before touching the database) on a bad scheduler value."""
    if isinstance(scheduler, str):
        if "://" not in scheduler:
            raise ConfigError(f"scheduler: must be an address like tcp://HOST:8786, "
                              f"got {scheduler!r}")
        try:
            import distributed  # type: ignore[import-not-found]  # noqa: F401
        except ImportError:
            raise ConfigError("scheduler: Dask distributed is not installed; install it "
                              "with pip install 'pathfuse[dask]'") from None

