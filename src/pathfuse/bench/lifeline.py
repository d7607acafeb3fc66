"""Worker processes die with the sweep that started them.

A pool worker is a child of multiprocessing's fork server, not of the sweep's
client process, so the kernel does not tell it when the client dies (``kill
-9``, an out-of-memory kill, a crash).  Left alone it would wait forever for
work, and keep the fork server and the resource tracker alive with it.
:func:`watch_client` starts a daemon thread in the worker that waits for the
client to end and then ends the worker:

* on Linux (>= 5.3) through a pidfd of the client, which becomes readable the
  moment the client exits (a zombie counts as exited, and a recycled pid
  cannot fool it);
* elsewhere by polling the client's pid every ``poll_s`` seconds.

A worker busy in a numba kernel holds the GIL, so it ends when its current
kernel returns (a run's kernels are bounded by the run's budget).  When every
worker has gone, the fork server and the resource tracker see their pipes
close and exit on their own.
"""

from __future__ import annotations

import os
import threading
import time

from pathfuse.sigterm import Terminated, terminate_like_ctrl_c

__all__ = ["watch_client", "client_alive", "Terminated", "terminate_like_ctrl_c"]

EXIT_ORPHANED = 75
"""Exit status of a worker whose client died."""


def client_alive(pid: int) -> bool:
    """True while process ``pid`` runs (a zombie is dead here)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - someone else's process took the pid
        return False
    try:  # Linux: a killed client that its parent has not reaped yet is a zombie
        with open(f"/proc/{pid}/stat", "rb") as fh:
            state = fh.read().rsplit(b")", 1)[1].split()[0]
        return state not in (b"Z", b"X")
    except (OSError, IndexError):
        return True


def _wait_pidfd(pid: int) -> bool:
    """Block until ``pid`` exits; False when pidfds are unavailable."""
    import select

    open_pidfd = getattr(os, "pidfd_open", None)
    if open_pidfd is None:
        return False
    try:
        fd = open_pidfd(pid)
    except ProcessLookupError:
        return True  # already gone
    except OSError:  # an old kernel, a sandbox
        return False
    try:
        select.select([fd], [], [])
    finally:
        os.close(fd)
    return True


def _watch(pid: int, poll_s: float) -> None:
    if not _wait_pidfd(pid):
        while client_alive(pid):
            time.sleep(poll_s)
    os._exit(EXIT_ORPHANED)


def watch_client(pid: int, poll_s: float = 0.5) -> threading.Thread:
    """End this process (``os._exit``) as soon as process ``pid`` has ended.

    Call it in a worker's initializer with the client's pid; the returned
    daemon thread does the waiting.
    """
    if not client_alive(pid):
        os._exit(EXIT_ORPHANED)
    t = threading.Thread(target=_watch, args=(pid, poll_s), name="pathfuse-lifeline",
                         daemon=True)
    t.start()
    return t
