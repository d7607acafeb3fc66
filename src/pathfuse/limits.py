"""The sizes pathfuse refuses to allocate, in one place; an environment variable raises each.

Everything a user types (a file, an option, a parameter) is checked against
these limits *before* memory is allocated or a loop starts, so no input can
exhaust the machine.  Each limit has a default and an environment variable
that raises (or lowers) it::

    PATHFUSE_MAX_CELLS=200000000 pathfuse plan --map huge.yaml ...

=========================  ===============  =====================================================
limit                      default          what it bounds
=========================  ===============  =====================================================
``MAX_CELLS``              67,108,864       cells of one map (8192 x 8192): readers, generators,
                                            inflation (a map of that size takes about 0.5-1.5 GB
                                            while planning)
``MAX_RUNS``               2,000,000        runs of one experiment (seeds x queries x parameter
                                            combinations), and seeds of one ``seeds:`` value
``MAX_TICKS``              1,000,000        ticks of one episode times the bodies that move
                                            (``time_limit / dt x (1 + discs)``)
``MAX_STEPS``              10,000,000       moves of one offline plan of a stepping planner
                                            (its path keeps every move)
``MAX_FILE_BYTES``         268,435,456      bytes read from one map or image file (256 MiB)
``MAX_YAML_BYTES``         16,777,216       bytes of one YAML file (16 MiB)
``MAX_YAML_NODES``         1,000,000        YAML nodes of one file *with aliases expanded*
                                            (stops "billion laughs" alias bombs)
``MAX_YAML_DEPTH``         100              nesting depth of YAML collections
=========================  ===============  =====================================================

Two fixed bounds: a seed is an integer in ``[0, 2**63)`` (:data:`MAX_SEED`,
SQLite's integer range), and a map lies within ``1e12`` m of the world origin
(:data:`MAX_EXTENT_M`).

Examples
--------
>>> limit("MAX_YAML_DEPTH")
100
>>> check_count(10, "MAX_RUNS", "seeds")
10
>>> check_count(10**9, "MAX_RUNS", "seeds")        # doctest: +ELLIPSIS
Traceback (most recent call last):
...
pathfuse.limits.LimitError: seeds: 1000000000 is above the limit of 2000000 (MAX_RUNS; ...)
"""

from __future__ import annotations

import os
from pathlib import Path

from pathfuse.result import ConfigError, PathfuseError

__all__ = [
    "LimitError",
    "DEFAULTS",
    "MAX_SEED",
    "MAX_EXTENT_M",
    "limit",
    "env_name",
    "check_count",
    "check_cells",
    "read_capped",
]

DEFAULTS: dict[str, int] = {
    "MAX_CELLS": 8192 * 8192,
    "MAX_RUNS": 2_000_000,
    "MAX_TICKS": 1_000_000,
    "MAX_STEPS": 10_000_000,
    "MAX_FILE_BYTES": 256 * 1024 * 1024,
    "MAX_YAML_BYTES": 16 * 1024 * 1024,
    "MAX_YAML_NODES": 1_000_000,
    "MAX_YAML_DEPTH": 100,
}
"""Default value of every limit (see the module docstring)."""

MAX_EXTENT_M = 1e12
"""Every map lies within this many metres of the world origin (so that squared distances
stay finite): a ROS ``resolution: 1e308`` is refused, not planned on."""

MAX_SEED = 2**63 - 1
"""The largest seed: seeds are stored as SQLite (signed 64-bit) integers."""


class LimitError(ConfigError):
    """An input asks for more than a limit of :mod:`pathfuse.limits` allows.

    The message names the input, the limit and the environment variable that raises it.
    """


def env_name(name: str) -> str:
    """The environment variable that overrides limit ``name``: ``PATHFUSE_MAX_CELLS``."""
    return f"PATHFUSE_{name}"


def limit(name: str) -> int:
    """The current value of limit ``name`` (its environment variable, else the default).

    An environment variable that is not a positive integer is a :class:`ConfigError`.
    """
    default = DEFAULTS[name]
    raw = os.environ.get(env_name(name))
    if raw is None or not raw.strip():
        return default
    try:
        value = int(raw.strip().replace("_", ""))
    except ValueError:
        value = 0
    if value < 1:
        raise ConfigError(f"{env_name(name)}: must be an integer >= 1, got {raw[:40]!r}")
    return value


def _how(name: str) -> str:
    return f"{name}; set the environment variable {env_name(name)} to raise it"


def check_count(n: int, name: str, what: str, error: type[PathfuseError] = LimitError) -> int:
    """``n`` when it is at most limit ``name``; else a :class:`LimitError` naming ``what``."""
    cap = limit(name)
    if n > cap:
        raise error(f"{what}: {n} is above the limit of {cap} ({_how(name)})")
    return n


def check_cells(height: int, width: int, what: str,
                error: type[PathfuseError] = LimitError) -> None:
    """Refuse a ``height x width`` map above ``MAX_CELLS`` before it is allocated."""
    cap = limit("MAX_CELLS")
    n = int(height) * int(width)
    if n > cap:
        raise error(f"{what}: a map of {int(height)} x {int(width)} = {n} cells is above the "
                    f"limit of {cap} cells ({_how('MAX_CELLS')})")


def read_capped(path: str | os.PathLike[str], what: str, name: str = "MAX_FILE_BYTES",
                error: type[PathfuseError] = LimitError) -> bytes:
    """The bytes of ``path``, reading at most limit ``name`` of them.

    A longer file (or an endless one, such as a pipe) is refused after
    reading one byte more than the limit, so it never fills memory; a device
    (a link to ``/dev/zero``) is refused unread.  ``OSError`` propagates for
    the caller to word.
    """
    import stat

    cap = limit(name)
    with open(Path(path), "rb") as fh:
        mode = os.fstat(fh.fileno()).st_mode
        if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
            raise error(f"{path}: {what} is a device, not a file")
        data = fh.read(cap + 1)
    if len(data) > cap:
        raise error(f"{path}: {what} is larger than the limit of {cap} bytes "
                    f"({_how(name)})")
    return data
