"""The worker processes of ``pathfuse serve``: every computation runs in one, so a request
past its time is stopped at once by killing its process.

A thread cannot be stopped (a numba kernel holds on to it until it returns), a process
can: :class:`WorkerPool` keeps up to ``size`` worker processes, forked from the server
process (so they have its planners, plug-ins registered at run time included, and the
kernels it has compiled), and gives each job to an idle one.  When a job passes its
deadline the pool sends SIGKILL to its worker: the CPU it used stops that instant, the
request is answered 503 and a fresh worker is forked for the next job.

* **Queue.**  At most ``size`` jobs run at once; up to ``max_queue`` more wait for a
  worker, each until its own deadline.  Past that the answer is :class:`PoolBusy` at once
  (the app answers 503 with ``Retry-After``).
* **Slow jobs step aside.**  A job still running after ``slow_after_s`` has its worker's
  nice value raised to 10, so the short requests that arrive meanwhile get the CPU
  first; that worker is replaced after its job (a process cannot lower its nice value
  again).
* **Deadlines hold without the server.**  Each job carries its deadline to the worker,
  which arms ``SIGALRM`` (default action: terminate) a little past it: a worker whose
  server died still stops.  An idle worker whose server died exits when its socket
  closes.
* **Shutdown.**  :meth:`WorkerPool.stop_now` (safe in a signal handler) kills every
  worker; the jobs in flight end with :class:`WorkerLost` at once.

A worker talks to the server over a socket pair with length-prefixed pickles: the job
``(kind, args, alarm_s)``; any number of ``("ask", request)`` whose replies the server's
``answer`` function gives (the app's map store uses it for uploads); then ``("done",
result)`` or ``("crash", message, traceback)``.

Forking a process that runs threads needs care; the fork is made while holding numba's
compiler lock (so no kernel is half compiled in the child), and the child resets what
it shares with the server: signal handlers and wake-up fd, the sockets and pipes it
inherited (listening socket and client connections included), ``sys.stdout`` and
``sys.stderr``.  The app's ``setup`` hook resets its own locks.
"""

from __future__ import annotations

import math
import os
import pickle
import signal
import socket
import stat
import struct
import sys
import threading
import time
import traceback
import warnings
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NoReturn

import anyio

__all__ = ["WorkerPool", "PoolBusy", "JobTimeout", "WorkerLost", "JobCrashed"]

RunJob = Callable[[str, Any], Any]
"""In a worker: ``run_job(kind, args) -> result`` (picklable)."""
Answer = Callable[[Any], Any]
"""In the server: the reply to a worker's ``ask(request)``."""
Setup = Callable[[Callable[[Any], Any]], None]
"""In a new worker, once: ``setup(ask)``, ``ask(request) -> reply`` asks the server."""

_HEADER = struct.Struct("!Q")


class PoolBusy(Exception):
    """Every worker is busy and the queue is full (or the request's deadline passed while
    it waited); ``retry_after`` is a whole number of seconds to wait."""

    def __init__(self, message: str, retry_after: int) -> None:
        super().__init__(message)
        self.retry_after = retry_after


class JobTimeout(Exception):
    """The job passed its deadline; its worker was killed."""


class WorkerLost(Exception):
    """The worker died before answering (the server is stopping, or the system killed it)."""


class JobCrashed(Exception):
    """The job raised in its worker: ``message`` (``Type: text``) and ``trace``."""

    def __init__(self, message: str, trace: str) -> None:
        super().__init__(message)
        self.message = message
        self.trace = trace


# --------------------------------------------------------------------------- wire
def _send(sock: socket.socket, obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    sock.sendall(_HEADER.pack(len(data)) + data)


def _recv_exact(sock: socket.socket, n: int) -> bytes:
    buf = bytearray(n)
    view = memoryview(buf)
    got = 0
    while got < n:
        k = sock.recv_into(view[got:], n - got)
        if k == 0:
            raise EOFError("the other end closed")
        got += k
    return bytes(buf)


def _recv(sock: socket.socket) -> Any:
    (n,) = _HEADER.unpack(_recv_exact(sock, _HEADER.size))
    return pickle.loads(_recv_exact(sock, n))


_wait_readable: Callable[[Any], Any] = getattr(anyio, "wait_readable", None) or \
    anyio.wait_socket_readable  # anyio < 4.7


# --------------------------------------------------------------------------- the child
def _close_inherited(keep: int) -> None:
    """Close the sockets and pipes a forked child inherited (the server's listening socket,
    its client connections, its event loop's wake-up pipes), except ``keep`` and stdio."""
    fds: list[int] = []
    for folder in ("/proc/self/fd", "/dev/fd"):  # Linux, macOS
        try:
            fds = [int(x) for x in os.listdir(folder)]
            break
        except (OSError, ValueError):
            continue
    for fd in fds:
        if fd <= 2 or fd == keep:
            continue
        try:
            mode = os.fstat(fd).st_mode
            if stat.S_ISSOCK(mode) or stat.S_ISFIFO(mode):
                os.close(fd)
        except OSError:
            pass


def _child_setup(keep_fd: int) -> None:
    try:
        signal.set_wakeup_fd(-1)
    except (ValueError, OSError):
        pass
    for sig in (signal.SIGTERM, signal.SIGALRM, signal.SIGHUP, signal.SIGUSR1,
                signal.SIGUSR2, signal.SIGCHLD):
        signal.signal(sig, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the server stops its workers
    _close_inherited(keep_fd)
    # fresh streams: the server's may have been locked by another thread at the fork
    sys.stdout = open(1, "w", closefd=False, buffering=1)  # noqa: SIM115
    sys.stderr = open(2, "w", closefd=False, buffering=1)  # noqa: SIM115


def _child_main(sock: socket.socket, run_job: RunJob, setup: list[Setup]) -> NoReturn:
    """The worker's loop; never returns (``os._exit``: no atexit handler of the server)."""
    try:
        _child_setup(sock.fileno())

        def ask(request: Any) -> Any:
            _send(sock, ("ask", request))
            return _recv(sock)

        for fn in setup:
            fn(ask)
        while True:
            try:
                kind, args, alarm_s = _recv(sock)
            except (EOFError, OSError):
                break
            signal.setitimer(signal.ITIMER_REAL, max(float(alarm_s), 0.001))
            try:
                reply: tuple[Any, ...] = ("done", run_job(kind, args))
            except BaseException as exc:  # noqa: BLE001 - a bug: tell the server, keep going
                reply = ("crash", f"{type(exc).__name__}: {exc}", traceback.format_exc())
            signal.setitimer(signal.ITIMER_REAL, 0)
            try:
                _send(sock, reply)
            except OSError:
                break
    finally:
        os._exit(0)


def _event_loop() -> object:
    """The running asyncio loop (None under another backend)."""
    import asyncio

    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _fork_guard() -> Any:
    """numba's compiler lock when numba is loaded (no kernel is half compiled at the fork)."""
    mod = sys.modules.get("numba.core.compiler_lock")
    return getattr(mod, "global_compiler_lock", None)


# --------------------------------------------------------------------------- the pool
@dataclass
class _Worker:
    pid: int
    sock: socket.socket
    generation: int
    niced: bool = False
    started: float = 0.0
    deadline: float = 0.0  # of the job it runs; 0 when idle


def _kill_all(workers: dict[int, _Worker]) -> None:
    for w in list(workers.values()):
        try:
            os.kill(w.pid, signal.SIGKILL)
        except OSError:
            pass
        try:
            os.waitpid(w.pid, 0)
        except OSError:
            pass


def _reap(pid: int) -> None:
    try:
        os.waitpid(pid, 0)
    except OSError:
        pass


@dataclass
class _Counters:
    """What the pool did (for tests and ``/api/status``)."""

    jobs: int = 0
    timeouts: int = 0
    cancelled: int = 0
    busy: int = 0
    forks: int = 0
    lost: int = 0
    extra: dict[str, int] = field(default_factory=dict)


class WorkerPool:
    """Worker processes that run jobs under deadlines (see the module docstring).

    Parameters
    ----------
    run_job : callable
        ``run_job(kind, args) -> result``, called in a worker.
    answer : callable
        ``answer(request) -> reply``, called in the server for a worker's ``ask``.
    size : int
        Workers, hence jobs running at once.
    max_queue : int
        Jobs that may wait for a worker; one more is refused at once.
    slow_after_s : float
        A job running longer has its worker's nice value raised to 10.
    setup : list of callable
        ``setup(ask)`` called in each new worker (e.g. to reset locks).
    """

    def __init__(self, run_job: RunJob, answer: Answer, *, size: int = 3, max_queue: int = 32,
                 slow_after_s: float = 0.5, setup: list[Setup] | None = None) -> None:
        self.size = max(1, int(size))
        self.max_queue = max(0, int(max_queue))
        self.slow_after_s = float(slow_after_s)
        self.alarm_margin_s = 1.0
        self._run_job = run_job
        self._answer = answer
        self._setup = list(setup or [])
        self._lock = threading.Lock()
        self._idle: list[_Worker] = []
        self._all: dict[int, _Worker] = {}
        self._generation = 0
        self._closing = False
        self._sem: anyio.Semaphore | None = None
        self._fork_limiter: anyio.CapacityLimiter | None = None
        self._loop: object = None
        self.counters = _Counters()
        self._finalizer = weakref.finalize(self, _kill_all, self._all)
        if os.name != "posix":  # pragma: no cover - pathfuse serve needs fork
            raise OSError("the worker pool needs os.fork (Linux or macOS)")

    # ------------------------------------------------------------------ state
    def pids(self) -> list[int]:
        """Process ids of the live workers."""
        return list(self._all)

    def busy_pids(self) -> list[int]:
        """Process ids of the workers running a job."""
        return [w.pid for w in list(self._all.values()) if w.deadline]

    def renew(self) -> None:
        """Replace every worker by a fresh fork as soon as it is idle (after the server
        compiled kernels or registered planners that the workers should have)."""
        self._generation += 1

    def retry_after(self) -> int:
        """Seconds until a worker frees up at the latest: the nearest deadline of a running
        job (at least 1)."""
        now = time.monotonic()
        ends = [w.deadline - now for w in list(self._all.values()) if w.deadline]
        return max(1, math.ceil(min(ends))) if ends else 1

    def waiting(self) -> int:
        """Jobs waiting for a worker."""
        return 0 if self._sem is None else self._sem.statistics().tasks_waiting

    # ------------------------------------------------------------------ running a job
    async def run(self, kind: str, args: Any, deadline: float) -> Any:
        """Run ``run_job(kind, args)`` in a worker and return its result.

        ``deadline`` is a :func:`time.monotonic` time covering the wait for a worker too.

        Raises
        ------
        PoolBusy
            The queue is full, or the deadline passed before a worker was free.
        JobTimeout
            The job passed the deadline (its worker was killed).
        WorkerLost
            The worker died (the server is stopping).
        JobCrashed
            The job raised (its message and traceback).
        """
        if self._closing:
            raise WorkerLost("the server is shutting down")
        loop = _event_loop()
        if self._sem is None or loop is not self._loop:  # first use, or a new event loop
            self._sem = anyio.Semaphore(self.size)
            self._fork_limiter = anyio.CapacityLimiter(1)
            self._loop = loop
        sem = self._sem
        if sem.value == 0 and sem.statistics().tasks_waiting >= self.max_queue:
            self.counters.busy += 1
            n, q = self.size, self.max_queue
            raise PoolBusy(f"the server is busy: {n} request{'s' if n != 1 else ''} "
                           f"{'are' if n != 1 else 'is'} computing and {q} more "
                           f"{'are' if q != 1 else 'is'} waiting", self.retry_after())
        try:
            with anyio.fail_after(max(0.0, deadline - time.monotonic())):
                await sem.acquire()
        except TimeoutError:
            self.counters.busy += 1
            raise PoolBusy("the server is busy: no worker was free within this request's "
                           "time", self.retry_after()) from None
        try:
            if self._closing:
                raise WorkerLost("the server is shutting down")
            for attempt in (0, 1):
                w = await self._checkout(deadline)
                try:
                    _send(w.sock, (kind, args, deadline - time.monotonic() +
                                   self.alarm_margin_s))
                except OSError:  # it died while idle: the job did not start
                    self._retire(w)
                    self.counters.lost += 1
                    if attempt or self._closing:
                        raise WorkerLost("a worker process died") from None
                    continue
                return await self._talk(w, deadline)
            raise AssertionError("unreachable")  # pragma: no cover
        finally:
            sem.release()

    async def _checkout(self, deadline: float) -> _Worker:
        """An idle worker of the current generation, forked if there is none (a fork may wait
        for numba's compiler lock: past the deadline the request gives up, the fork goes on
        and leaves its worker idle)."""
        while True:
            with self._lock:
                while self._idle:
                    w = self._idle.pop()
                    if w.generation == self._generation and not w.niced:
                        return w
                    self._retire_locked(w)
            if self._closing:
                raise WorkerLost("the server is shutting down")
            try:
                with anyio.fail_after(max(0.0, deadline - time.monotonic())):
                    await anyio.to_thread.run_sync(self._fork, limiter=self._fork_limiter,
                                                   abandon_on_cancel=True)
            except TimeoutError:
                self.counters.busy += 1
                raise PoolBusy("the server is busy: no worker was ready within this "
                               "request's time", self.retry_after()) from None

    async def _talk(self, w: _Worker, deadline: float) -> Any:
        w.started = time.monotonic()
        w.deadline = deadline
        self.counters.jobs += 1
        done = False
        try:
            while True:
                msg = await self._next(w, deadline)
                if msg[0] == "ask":
                    _send(w.sock, self._answer(msg[1]))
                    continue
                done = True
                if msg[0] == "crash":
                    raise JobCrashed(msg[1], msg[2])
                return msg[1]
        except (OSError, EOFError):
            self.counters.lost += 1
            why = "the server is shutting down" if self._closing else \
                "the system stopped it, out of memory perhaps"
            raise WorkerLost(f"the worker process stopped before answering ({why})") from None
        except anyio.get_cancelled_exc_class():
            self.counters.cancelled += 1
            raise
        finally:
            w.deadline = 0.0
            if done and not w.niced and w.generation == self._generation and \
                    not self._closing:
                with self._lock:
                    if len(self._all) <= self.size:
                        self._idle.append(w)
                    else:
                        self._retire_locked(w)
            else:
                self._retire(w)

    async def _next(self, w: _Worker, deadline: float) -> Any:
        """The worker's next message, waiting at most until ``deadline``."""
        while True:
            now = time.monotonic()
            if now >= deadline:
                self.counters.timeouts += 1
                raise JobTimeout("past the deadline")
            wait = deadline - now
            if not w.niced:
                wait = min(wait, max(0.0, w.started + self.slow_after_s - now))
            readable = False
            with anyio.move_on_after(wait):
                await _wait_readable(w.sock)
                readable = True
            if readable:
                return _recv(w.sock)
            if not w.niced and time.monotonic() >= w.started + self.slow_after_s:
                try:
                    os.setpriority(os.PRIO_PROCESS, w.pid, 10)
                except OSError:
                    pass
                w.niced = True

    # ------------------------------------------------------------------ processes
    def _fork(self) -> None:
        """Fork a worker into the idle list (runs in a thread: the fork waits for numba's
        compiler lock)."""
        parent, child = socket.socketpair()
        lock = _fork_guard()
        if lock is not None:
            lock.acquire()
        try:
            with warnings.catch_warnings():  # Python >= 3.12 warns on fork with threads
                warnings.simplefilter("ignore", DeprecationWarning)
                pid = os.fork()
        except OSError:
            parent.close()
            child.close()
            raise
        finally:
            if lock is not None:
                lock.release()
        if pid == 0:  # pragma: no cover - the child (os._exit: coverage cannot see it)
            parent.close()
            _child_main(child, self._run_job, self._setup)
        child.close()
        w = _Worker(pid, parent, self._generation)
        with self._lock:
            self._all[pid] = w
            self._idle.append(w)
        self.counters.forks += 1
        if self._closing:
            self.stop_now()

    def _retire_locked(self, w: _Worker) -> None:
        self._all.pop(w.pid, None)
        try:
            os.kill(w.pid, signal.SIGKILL)
        except OSError:
            pass
        try:
            w.sock.close()
        except OSError:
            pass
        threading.Thread(target=_reap, args=(w.pid,), daemon=True,
                         name=f"pathfuse-reap-{w.pid}").start()

    def _retire(self, w: _Worker) -> None:
        with self._lock:
            self._retire_locked(w)

    def stop_now(self) -> None:
        """Refuse new jobs and SIGKILL every worker (no lock taken: safe in a signal
        handler); the jobs in flight end with :class:`WorkerLost`."""
        self._closing = True
        for w in list(self._all.values()):
            try:
                os.kill(w.pid, signal.SIGKILL)
            except OSError:
                pass

    def close(self) -> None:
        """:meth:`stop_now` and wait for the workers to be gone; the pool forks new workers
        if it is used again (a server started anew)."""
        self.stop_now()
        with self._lock:
            workers = list(self._all.values())
            self._all.clear()
            self._idle.clear()
        for w in workers:
            try:
                w.sock.close()
            except OSError:
                pass
            _reap(w.pid)
        self._closing = False
