"""Whether a planner's numba kernels are already in numba's on-disk cache.

Used only to print a notice before a first, slow compile; any doubt (a
numba version whose internals differ) counts as "cached", so the notice is
never wrong by being noisy.
"""

from __future__ import annotations

import hashlib
import os
from typing import Any

__all__ = ["cold_kernels", "is_cached"]


def is_cached(dispatcher: Any, online: bool | None = None) -> bool:
    """True when ``dispatcher`` (an ``@njit(cache=True)`` function) has an index on disk
    (and, for a kernel made by a factory, an entry of its own in it).

    The field loops (:mod:`pathfuse.field.kernels`) have two kinds of signature, a
    static plan's (``None`` for the discs) and an online one's: with ``online`` given,
    the index must hold one of that kind.
    """
    try:
        cache_file = dispatcher._cache._cache_file
        index = cache_file._index_path
    except AttributeError:
        return True
    if not os.path.exists(index):
        return False
    closure = getattr(getattr(dispatcher, "py_func", None), "__closure__", None)
    if online is None and closure is None:
        return True
    try:
        from numba import types

        keys = list(cache_file._load_index())
        if closure is not None:  # kernels made by one factory share an index: numba's key
            # tells them apart by a hash of the closure's variables
            from numba.core.serialize import dumps

            cvars = hashlib.sha256(dumps(tuple(c.cell_contents for c in closure)))
            keys = [key for key in keys if key[2][1] == cvars.hexdigest()]
        if online is None:
            return bool(keys)
        return any(online != any(isinstance(t, types.NoneType) for t in key[0])
                   for key in keys)
    except Exception:  # noqa: BLE001 - numba's internals differ: count it as cached
        return True


def cold_kernels(spec: Any, params: Any = None, diff_drive: bool = False,
                 online: bool = False) -> list[str]:
    """Names of the kernels ``spec`` (a PlannerSpec) runs with ``params`` (its global
    planner's and its controller's, online with ``online``, with ``diff_drive`` those of
    a diff-drive robot too) that numba must still compile."""
    from pathfuse.field.kernels import field_loop, fusion_loop

    kernels: list[Any] = []
    gname = spec.global_planner_of(params)
    if gname is not None:
        from pathfuse.planners.globals.builtin import global_kernels

        # the A* kernel of the heuristic the plan runs, as warm() compiles it
        kernels.extend(global_kernels(gname, getattr(params, "heuristic", None)))
    if spec.controller is not None:
        kernels.extend(spec.controller.kernels())
        if diff_drive:
            kernels.extend(spec.controller.diff_drive_kernels())
    online = online or diff_drive
    return [getattr(k, "__name__", str(k)) for k in kernels
            if not is_cached(k, online if k is field_loop or k is fusion_loop else None)]
