"""Whether a planner's numba kernels are already in numba's on-disk cache.

Used only to print a notice before a first, slow compile; any doubt (a
numba version whose internals differ) counts as "cached", so the notice is
never wrong by being noisy.
"""

from __future__ import annotations

import os
from typing import Any

__all__ = ["cold_kernels", "is_cached"]


def is_cached(dispatcher: Any) -> bool:
    """True when ``dispatcher`` (an ``@njit(cache=True)`` function) has an index on disk."""
    try:
        index = dispatcher._cache._cache_file._index_path
    except AttributeError:
        return True
    return os.path.exists(index)


def cold_kernels(spec: Any, params: Any = None, diff_drive: bool = False) -> list[str]:
    """Names of the kernels ``spec`` (a PlannerSpec) runs with ``params`` (its global
    planner's and its controller's, with ``diff_drive`` those of a diff-drive robot too)
    that numba must still compile."""
    kernels: list[Any] = []
    gname = spec.global_planner_of(params)
    if gname is not None:
        from pathfuse.planners.globals.builtin import global_kernels

        kernels.extend(global_kernels(gname))
    if spec.controller is not None:
        kernels.extend(spec.controller.kernels())
        if diff_drive:
            kernels.extend(spec.controller.diff_drive_kernels())
    return [getattr(k, "__name__", str(k)) for k in kernels if not is_cached(k)]
