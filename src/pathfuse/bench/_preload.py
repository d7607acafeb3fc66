"""Imported once by the worker pool's fork server, before it forks any worker.

It imports the planners and metrics and compiles (or loads from numba's
cache) their kernels, so every worker forked afterwards starts warm: a pool
starts in milliseconds instead of re-loading numba code in each process.
Failures are ignored here; a worker that needs a planner imports it itself.
"""

from __future__ import annotations


def _warm() -> None:
    try:
        from pathfuse import api
        from pathfuse.planners.registry import REGISTRY, planner_names

        planner_names()
        for name, spec in list(REGISTRY.items()):
            if spec.warmup is not None and name not in api._WARM:
                spec.warmup()
                api._WARM.add(name)
    except Exception:  # noqa: BLE001 - best effort only
        pass
    try:
        from pathfuse.metrics_kernels import warmup as warmup_metrics

        warmup_metrics()
    except Exception:  # noqa: BLE001
        pass
    try:  # the dynamic world's kernels (online planners, geometry, moving discs)
        from pathfuse.world.geometry import warmup_geometry
        from pathfuse.world.obstacles import warmup_obstacles
        from pathfuse.world.online import warmup_online

        warmup_online()
        warmup_geometry()
        warmup_obstacles()
    except Exception:  # noqa: BLE001
        pass


_warm()
