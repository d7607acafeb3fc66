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


def cold_kernels(spec: Any) -> list[str]:
    """Names of the kernels ``spec`` (a PlannerSpec) runs that numba must still compile."""
    kernels: list[Any] = []
    if spec.uses_astar:
        from pathfuse.search.kernel import _astar_kernel

        kernels.append(_astar_kernel)
    if spec.controller is not None:
        kernels.extend(spec.controller.kernels())
    return [getattr(k, "__name__", str(k)) for k in kernels if not is_cached(k)]
