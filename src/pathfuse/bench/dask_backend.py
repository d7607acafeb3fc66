"""The Dask backend of a sweep: the same batches on an existing ``distributed`` cluster.

Workers only compute; the client (this process) writes the store.  What can
go wrong with a cluster is not a run's failure, so it is never stored as one:

* **The scheduler is lost** (killed, the network is down): Dask cancels every
  future with reason ``scheduler-connection-lost``.  The sweep stops at once
  with :class:`ClusterLost`; the runs that finished are stored, the others
  stay missing, so the same command resumes them.
* **Every worker is gone** (the scheduler is alive but has no worker): the
  sweep says so in one line (``notice``) after ``NO_WORKER_NOTICE_S``, keeps
  waiting for a worker to join for ``worker_wait_s`` seconds in all, then
  stops with :class:`ClusterLost`.
* **A run kills its worker** (Dask's ``KilledWorker``): its batch is re-run
  one run per task, and only the run that kills its worker is stored as an
  ``ERROR``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import CancelledError
from typing import Any, Protocol

from pathfuse.bench.execute import execute_batch
from pathfuse.bench.experiment import FILE_FAMILIES, Experiment, RunSpec, load_dynamic, load_map
from pathfuse.bench.pool import _batch_payload, _crash_row, _exception_rows, make_batches
from pathfuse.result import ConfigError, PathfuseError

__all__ = ["ClusterLost", "run_dask", "connect_dask", "NO_WORKER_NOTICE_S",
           "DEFAULT_WORKER_WAIT_S"]

NO_WORKER_NOTICE_S = 5.0
"""Seconds without any worker before the sweep says so."""

DEFAULT_WORKER_WAIT_S = 60.0
"""Seconds without any worker before the sweep gives up (``--worker-wait``)."""

_CHECK_EVERY_S = 1.0


class ClusterLost(PathfuseError):
    """The Dask cluster went away during a sweep; the unfinished runs stay missing.

    ``summary`` (set by the runner) tells what was stored before.
    """

    summary: Any = None


class DaskSink(Protocol):
    def write(self, rows: Sequence[dict[str, Any]]) -> None: ...

    def notice(self, text: str) -> None: ...


def connect_dask(scheduler: Any) -> tuple[Any, bool]:
    """A ``distributed.Client`` for ``scheduler`` (an address or a client) and whether it is
    ours to close; :class:`ConfigError` in one line when it cannot connect."""
    try:
        import distributed  # type: ignore[import-not-found]
    except ImportError:
        raise ConfigError("scheduler: Dask distributed is not installed; install it with "
                          "pip install 'pathfuse[dask]'") from None
    if isinstance(scheduler, distributed.Client):
        return scheduler, False
    if not isinstance(scheduler, str) or "://" not in scheduler:
        raise ConfigError(f"scheduler: must be an address like tcp://HOST:8786, "
                          f"got {scheduler!r}")
    _probe(scheduler)
    try:
        return distributed.Client(scheduler, timeout="20s", set_as_default=False), True
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"scheduler: cannot connect to {scheduler} ({exc})") from None


def _probe(address: str, timeout_s: float = 5.0) -> None:
    """Fail fast when nothing listens at a ``tcp://HOST:PORT`` address."""
    import socket
    from urllib.parse import urlsplit

    u = urlsplit(address)
    if u.scheme != "tcp" or u.port is None:
        return
    try:
        with socket.create_connection((u.hostname or "127.0.0.1", u.port), timeout=timeout_s):
            pass
    except OSError as exc:
        raise ConfigError(f"scheduler: cannot connect to {address} ({exc.strerror or exc}); "
                          "is 'dask scheduler' running there?") from None


def _address(client: Any) -> str:
    try:
        return str(client.scheduler.address)
    except AttributeError:  # pragma: no cover
        return "the Dask scheduler"


def _lost(client: Any) -> ClusterLost:
    # one wording, whichever sign of the loss came first (a cancelled future, the client
    # reconnecting, a failed call): which one wins is a matter of timing
    return ClusterLost(f"lost the Dask scheduler at {_address(client)}; the runs that "
                       "finished are stored, run the same command again to finish the rest")


class _Watch:
    """Counts the cluster's workers while the sweep waits; gives up when none come back."""

    def __init__(self, client: Any, sink: DaskSink, worker_wait_s: float) -> None:
        self.client, self.sink, self.wait_s = client, sink, worker_wait_s
        self.last_check = 0.0
        self.none_since: float | None = None
        self.told = False

    def workers(self) -> int:
        if getattr(self.client, "status", "running") != "running":
            raise _lost(self.client)
        try:
            info = self.client.scheduler_info()
        except (OSError, TimeoutError):
            raise _lost(self.client) from None
        return len(info.get("workers", {}))

    def check(self) -> None:
        now = time.monotonic()
        if now - self.last_check < _CHECK_EVERY_S:
            return
        self.last_check = now
        if self.workers():
            if self.told:
                self.sink.notice(f"a worker joined the Dask cluster at {_address(self.client)}"
                                 "; the sweep goes on")
            self.none_since, self.told = None, False
            return
        if self.none_since is None:
            self.none_since = now
        idle = now - self.none_since
        if idle >= self.wait_s:
            raise ClusterLost(
                f"every worker of the Dask cluster at {_address(self.client)} is gone (none "
                f"for {idle:.0f} s); the runs that finished are stored, start workers and run "
                "the same command again to finish the rest")
        if idle >= min(NO_WORKER_NOTICE_S, self.wait_s / 2) and not self.told:
            self.told = True
            self.sink.notice(
                f"no worker is connected to the Dask scheduler at {_address(self.client)}; "
                f"waiting up to {self.wait_s:.0f} s for one (Ctrl-C stops, stored runs are "
                "kept)")


def _result(f: Any, watch: _Watch) -> Any:
    """``f.result()``, checking the cluster while it waits: a finished task whose worker dies
    before its result is fetched is queued again, and with no worker left a plain
    ``result()`` would wait forever."""
    while True:
        try:
            return f.result(timeout=_CHECK_EVERY_S)
        except TimeoutError:
            watch.check()


def _drain(client: Any, futures: Sequence[Any], watch: _Watch, handle: Any) -> None:
    """Hand each future to ``handle`` as it completes, checking the cluster while waiting."""
    from distributed import as_completed  # type: ignore[import-not-found]

    ac = as_completed(futures, loop=client.loop)
    while not ac.is_empty():
        if ac.has_ready():
            for f in ac.next_batch(block=False):
                if f.status == "cancelled":
                    raise _lost(client)
                handle(f)
        else:
            watch.check()
            time.sleep(0.02)


def run_dask(exp: Experiment, todo: Sequence[RunSpec], sink: DaskSink, scheduler: Any,
             batch_size: int | None, worker_wait_s: float = DEFAULT_WORKER_WAIT_S) -> int:
    """Run ``todo`` on the cluster; returns its thread count.  :class:`ClusterLost` if it
    goes away (nothing is stored for the runs that did not finish)."""
    from distributed.scheduler import KilledWorker  # type: ignore[import-not-found]

    client, own = connect_dask(scheduler)
    futures: list[Any] = []
    watch = _Watch(client, sink, worker_wait_s)
    try:
        nworkers = max(1, sum(w.get("nthreads", 1) for w in
                              client.scheduler_info().get("workers", {}).values()))
        for imp in exp.import_paths():
            if imp.endswith(".py"):
                client.upload_file(imp)
        # maps read from files are loaded here once and shipped; generated maps are
        # made on the workers from their spec
        grids: dict[str, Any] = {}
        for r in todo:
            if r.map_key in grids or not r.map_spec:
                continue
            if r.kind == "static" and any(f in r.map_spec for f in FILE_FAMILIES):
                grids[r.map_key] = client.scatter(load_map(r.map_spec, exp.base_dir),
                                                  broadcast=False, hash=True)
            elif r.kind == "dynamic" and isinstance(r.map_spec.get("dynamic"), str):
                grids[r.map_key] = client.scatter(load_dynamic(r.map_spec),
                                                  broadcast=False, hash=True)
        index: dict[Any, list[list[RunSpec]]] = {}
        for b in make_batches(todo, nworkers, batch_size):
            f = client.submit(execute_batch, _batch_payload(exp, b, grids), pure=False)
            index[f] = b
            futures.append(f)
        singles: list[RunSpec] = []

        def batch_done(f: Any) -> None:
            b = index.pop(f)
            try:
                sink.write(_result(f, watch))
            except KilledWorker:
                singles.extend(r for c in b for r in c)
            except CancelledError:
                raise
            except Exception as exc:  # noqa: BLE001 - stored as the runs' error
                sink.write(_exception_rows(b, exc))

        _drain(client, list(futures), watch, batch_done)
        # batches that killed workers: one run per task, so only the culprit fails
        if singles:
            single_index: dict[Any, RunSpec] = {}
            fs = []
            for r in singles:
                f = client.submit(execute_batch, _batch_payload(exp, [[r]], grids),
                                  pure=False)
                single_index[f] = r
                fs.append(f)
            futures.extend(fs)

            def single_done(f: Any) -> None:
                r = single_index.pop(f)
                try:
                    sink.write(_result(f, watch))
                except KilledWorker:
                    sink.write([_crash_row(r)])
                except CancelledError:
                    raise
                except Exception as exc:  # noqa: BLE001
                    sink.write(_exception_rows([[r]], exc))

            _drain(client, fs, watch, single_done)
        return nworkers
    except CancelledError:  # a future cancelled between the check and its result
        raise _lost(client) from None
    finally:
        try:
            client.cancel(futures)
        except Exception:  # noqa: BLE001 - the cluster may be gone
            pass
        if own:
            try:
                client.close(timeout=5)
            except Exception:  # noqa: BLE001 - the scheduler is gone
                pass
