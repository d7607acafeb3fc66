"""Python side of the stepping planners: defaults, validation, the chunked driver.

:func:`drive` calls a numba batch loop (:func:`~pathfuse.field.stepper.apf_run`,
:func:`~pathfuse.field.stepper.fusion_run` or any loop with the same calling
convention ``run(buf, n, n_stop) -> (n, code)``) in chunks of steps, grows the
path buffer, enforces the iteration cap and checks the wall-clock limit
between chunks, and maps the loop's code to a :class:`~pathfuse.result.Status`.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["....", "....", "...."])
>>> s = resolve_stepping(g, step_m=None, goal_tolerance_m=None, stall_distance_m=None,
...                      robot_radius_m=0.0, max_iterations=None)
>>> s.step_m, s.goal_tolerance_m, s.stall_distance_m, s.max_steps
(0.1, 0.1, 0.25, 1700)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from pathfuse.field.stepper import (
    CODE_BLOCKED,
    CODE_GOAL,
    CODE_GOAL_SNAP,
    CODE_RUNNING,
    CODE_STALLED,
    MARGIN_FRAC,
)
from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, Status

__all__ = [
    "STEP_FRAC",
    "STALL_FRAC",
    "Stepping",
    "resolve_stepping",
    "drive",
    "outcome",
    "DriveOutcome",
    "check_positive",
    "check_nonneg",
    "check_int",
    "check_stepping_params",
]

#: Default step, as a fraction of the map resolution (see :func:`resolve_stepping`).
STEP_FRAC = 0.1
#: Default stall distance, in steps.
STALL_FRAC = 2.5
#: Default step cap: this many times (width + height) / step, plus 1000.
CAP_FACTOR = 10.0
#: Steps per call of the numba loop between wall-clock checks.
CHUNK = 8192


def _num(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return v


def check_positive(name: str, value: Any, optional: bool = False) -> None:
    """ConfigError naming ``name`` unless ``value`` is a finite number > 0 (or None if optional).

    >>> check_positive("k_att", -1.0)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: k_att must be > 0, got -1.0
    """
    if optional and value is None:
        return
    if _num(name, value) <= 0:
        raise ConfigError(f"{name} must be > 0, got {value!r}")


def check_nonneg(name: str, value: Any) -> None:
    """ConfigError naming ``name`` unless ``value`` is a finite number >= 0."""
    if _num(name, value) < 0:
        raise ConfigError(f"{name} must be >= 0, got {value!r}")


def check_int(name: str, value: Any, minimum: int) -> None:
    """ConfigError naming ``name`` unless ``value`` is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ConfigError(f"{name} must be an integer >= {minimum}, got {value!r}")


def check_stepping_params(p: Any) -> None:
    """Check the parameters every stepping planner shares (APF, fusion, ref6, ref7).

    ``p`` has ``k_att``, ``k_rep``, ``rho0_m``, ``step_m``, ``goal_tolerance_m``,
    ``robot_radius_m``, ``stall_steps`` and ``stall_distance_m``; a bad one is a
    :class:`ConfigError` naming it.
    """
    check_positive("k_att", p.k_att)
    check_nonneg("k_rep", p.k_rep)
    check_positive("rho0_m", p.rho0_m)
    check_positive("step_m", p.step_m, optional=True)
    check_positive("goal_tolerance_m", p.goal_tolerance_m, optional=True)
    check_nonneg("robot_radius_m", p.robot_radius_m)
    check_int("stall_steps", p.stall_steps, 1)
    check_positive("stall_distance_m", p.stall_distance_m, optional=True)


@dataclass(frozen=True)
class Stepping:
    """Resolved stepping settings (metres) for one query."""

    step_m: float
    goal_tolerance_m: float
    stall_distance_m: float
    clear_m: float
    max_steps: int


def resolve_stepping(
    grid: GridMap,
    step_m: float | None,
    goal_tolerance_m: float | None,
    stall_distance_m: float | None,
    robot_radius_m: float,
    max_iterations: int | None,
) -> Stepping:
    """Fill in the defaults that depend on the map.

    * ``step_m``: ``STEP_FRAC * resolution`` (0.1 m on 1 m cells);
    * ``goal_tolerance_m``: one step;
    * ``stall_distance_m``: ``STALL_FRAC`` steps;
    * ``clear_m``: ``robot_radius_m`` plus a margin of ``MARGIN_FRAC`` cells;
    * ``max_steps``: ``max_iterations`` if given, else
      ``CAP_FACTOR * (width + height) * resolution / step + 1000``.
    """
    res = grid.resolution
    step = float(step_m) if step_m is not None else STEP_FRAC * res
    tol = float(goal_tolerance_m) if goal_tolerance_m is not None else step
    stall = float(stall_distance_m) if stall_distance_m is not None else STALL_FRAC * step
    if max_iterations is not None:
        cap = int(max_iterations)
    else:
        cap = int(math.ceil(CAP_FACTOR * (grid.width + grid.height) * res / step)) + 1000
    return Stepping(step, tol, stall, float(robot_radius_m) + MARGIN_FRAC * res, cap)


class DriveOutcome(NamedTuple):
    """What :func:`drive` returns."""

    path: np.ndarray
    status: Status
    steps: int
    code: int
    step_time_s: float


def drive(
    run: Callable[[np.ndarray, int, int, int], tuple[int, int, int]],
    start: np.ndarray,
    max_steps: int,
    deadline: float | None,
    chunk: int = CHUNK,
) -> DriveOutcome:
    """Run a batch loop in chunks until it ends, the step cap, or the deadline.

    Parameters
    ----------
    run : callable
        ``run(buf, n, n_stop, max_steps) -> (n, code, steps)`` as
        :func:`~pathfuse.field.stepper.apf_run` (the map and settings bound).
    start : ndarray, shape (2,)
        First path point.
    max_steps : int
        Cap on force steps; reaching it gives ``MAX_ITERATIONS``.
    deadline : float or None
        ``time.perf_counter()`` value after which the plan ends with ``TIMEOUT``
        (checked between chunks of ``chunk`` steps).

    Returns
    -------
    DriveOutcome
        The path (a copy, trimmed), the status, the number of force steps
        (the final move onto the goal excluded) and the time spent stepping.
    """
    t0 = time.perf_counter()
    cap = min(max_steps, 1024) + 2
    buf = np.empty((cap, 2), dtype=np.float64)
    buf[0] = start
    n = 1
    total = 0
    while True:
        n, code, steps = run(buf, n, cap - 1, min(chunk, max_steps - total))
        total += steps
        if code != CODE_RUNNING or total >= max_steps:
            break
        if deadline is not None and time.perf_counter() > deadline:
            break
        if n >= cap - 1:
            nb = np.empty((2 * cap, 2), dtype=np.float64)
            nb[:n] = buf[:n]
            buf, cap = nb, 2 * cap
    return outcome(buf[:n].copy(), code, total, max_steps, time.perf_counter() - t0)


def outcome(path: np.ndarray, code: int, steps: int, max_steps: int,
            step_time_s: float) -> DriveOutcome:
    """The :class:`DriveOutcome` of a finished batch loop (status from its code)."""
    if code == CODE_GOAL or code == CODE_GOAL_SNAP:
        status = Status.SUCCESS
    elif code == CODE_STALLED or code == CODE_BLOCKED:
        status = Status.LOCAL_MINIMUM
    elif steps >= max_steps:
        status = Status.MAX_ITERATIONS
    else:
        status = Status.TIMEOUT
    return DriveOutcome(path, status, steps, code, step_time_s)


def failure_message(out: DriveOutcome, goal: np.ndarray, stepping: Stepping,
                    stall_steps: int) -> str:
    """A human sentence for a non-success outcome."""
    x, y = out.path[-1]
    dist = math.hypot(x - goal[0], y - goal[1])
    where = f"at ({x:.3f}, {y:.3f}), {dist:.3f} m from the goal"
    if out.code == CODE_BLOCKED:
        return f"blocked {where}: no collision-free move along the force"
    if out.code == CODE_STALLED:
        return (f"local minimum {where}: moved less than {stepping.stall_distance_m:g} m "
                f"over the last {stall_steps} steps")
    if out.status is Status.MAX_ITERATIONS:
        return f"step cap of {stepping.max_steps} steps reached {where}"
    return f"time limit reached after {out.steps} steps, {where}"
