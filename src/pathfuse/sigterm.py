"""SIGTERM ends a command like Ctrl-C (:class:`Terminated`, a ``KeyboardInterrupt``).

Its own small module, so that every command installs the handler without importing
:mod:`pathfuse.bench` (the sweep engine: experiment files, the store, the runner);
:mod:`pathfuse.bench.lifeline` re-exports both names.
"""

from __future__ import annotations

import threading

__all__ = ["Terminated", "terminate_like_ctrl_c"]


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C's ``KeyboardInterrupt`` so it ends a sweep the same way:
    what finished is stored, the workers are stopped, the same command resumes."""

    signame = "SIGTERM"


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated()


def terminate_like_ctrl_c() -> None:
    """Make SIGTERM raise :class:`Terminated` in the main thread (the command line does)."""
    import signal

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _raise_terminated)
