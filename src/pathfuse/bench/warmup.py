"""Compile, once and before the clock starts, the kernels a sweep will run.

numba compiles a kernel on its first call and keeps it in its on-disk cache
(``cache=True``).  A sweep's client calls :func:`warm_kernels` before it
starts its workers: on a cold cache it compiles the planners' kernels, the
metrics' and (for dynamic runs) the world's once, and the workers then load
them from the cache instead of each compiling them again.  The caller is told
first (``notify``) when anything is not cached, so a first run is never a
silent wait.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

__all__ = ["cold_kernels_of", "warm_kernels"]


def _metric_kernels() -> list:
    from pathfuse import metrics_kernels as mk

    return [mk.evaluate_kernel, mk.segment_clearances_kernel, mk.geometry_kernel,
            mk.shape_kernel, mk.build_pyramid]


def _world_kernels() -> list:
    from pathfuse import costmap, shield, sweep
    from pathfuse.world import obstacles

    return [obstacles._bounce_trajectory, costmap.point_distance, costmap.segment_distance,
            sweep.disc_sweep_gaps, sweep.segment_static_distance, shield.shield_unicycle,
            shield.shield_holonomic]


def cold_kernels_of(planners: Iterable[str], metrics: bool = True,
                    world: bool = False) -> list[str]:
    """What must still be compiled: planner names, then ``metrics`` and ``world``."""
    from pathfuse.planners.kernel_cache import cold_kernels, is_cached
    from pathfuse.planners.registry import get_planner

    out = [n for n in dict.fromkeys(planners)
           if cold_kernels(get_planner(n), diff_drive=world, online=world)]
    if metrics and not all(is_cached(k) for k in _metric_kernels()):
        out.append("the metrics")
    if world and not all(is_cached(k) for k in _world_kernels()):
        out.append("the moving-obstacle world")
    return out


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def warm_kernels(planners: Iterable[str], metrics: bool = True, world: bool = False,
                 notify: Callable[[str], None] | None = None) -> list[str]:
    """Compile (or load) the kernels of ``planners`` (and the metrics, the world).

    ``notify`` is called once, with a one-line message, when something is not
    in numba's cache yet.  Returns what was cold.
    """
    from pathfuse.planners.registry import get_planner
    from pathfuse.planners.run import warm

    names = list(dict.fromkeys(planners))
    cold = cold_kernels_of(names, metrics, world)
    if cold and notify is not None:
        notify(f"compiling the kernels of {_and(cold)} (first run only; cached afterwards)")
    for n in names:  # a world's robot may be a diff-drive one
        warm(get_planner(n), diff_drive=world, online=world)
    if metrics:
        from pathfuse.metrics_kernels import warmup

        warmup()
    if world:
        from pathfuse.geometry import point_segment_distance
        from pathfuse.shield import warmup_shield
        from pathfuse.sweep import warmup_segments
        from pathfuse.world.obstacles import warmup_obstacles

        warmup_segments()
        point_segment_distance(1.0, 1.0, 0.0, 0.0, 2.0, 0.0)  # World's goal test
        warmup_obstacles()
        warmup_shield()
    return cold
