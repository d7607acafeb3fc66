"""Imported once by the worker pool's fork server, before it forks any worker.

It imports pathfuse's planners and metrics, so every worker forked afterwards
starts with them imported.  Kernels are compiled (or loaded from numba's
cache) by each worker for the planners its runs use, and only those.
Failures are ignored here; a worker that needs a module imports it itself.
"""

from __future__ import annotations


def _warm() -> None:
    try:
        import pathfuse.api  # noqa: F401
        import pathfuse.metrics  # noqa: F401
    except Exception:  # noqa: BLE001 - best effort only
        pass


_warm()
