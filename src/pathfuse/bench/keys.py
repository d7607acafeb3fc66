"""Identities of a sweep: canonical JSON, run keys, seeds, limits and map families.

The run key of a run is the SHA-256 of the canonical JSON of its full
parameters; the result store skips runs whose key it holds, which is what
makes a sweep resumable (:mod:`pathfuse.bench.experiment`).
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.limits import MAX_SEED, check_count
from pathfuse.result import Budget, ConfigError
from pathfuse.validate import short as _shown

KEY_VERSION = 1
"""Bumped only if the meaning of a run key changes (it never silently does)."""

GENERATED_FAMILIES = ("paper", "random")
"""Map families drawn from a seed; without an explicit seed they take the run's."""
FILE_FAMILIES = ("movingai", "ros", "image", "npy", "gazebo")
"""Map families read from a file (path relative to the experiment file)."""
INLINE_FAMILIES = ("rows",)
"""Maps written inline in the experiment."""
ALL_FAMILIES = GENERATED_FAMILIES + FILE_FAMILIES + INLINE_FAMILIES

_TOP_KEYS = ("name", "description", "seeds", "limits", "robot_radius_m", "reference",
             "store_paths", "imports", "maps", "planners")
_MAP_KEYS = ("name", "map", "start", "goal", "queries", "scen", "lines", "seeds",
             "robot_radius_m", "dynamic", "irsim")
_PLANNER_KEYS = ("name", "label", "params", "limits", "kinds")
_LIMIT_KEYS = ("time_limit_s", "max_iterations")


# --------------------------------------------------------------------------- helpers
def canonical_json(obj: Any) -> str:
    """Canonical JSON: sorted keys, no spaces, shortest float repr, no NaN.

    >>> canonical_json({"b": 1.0, "a": [1, (2, 3)], "c": np.float64(0.1)})
    '{"a":[1,[2,3]],"b":1.0,"c":0.1}'
    """
    return json.dumps(_plain(obj), sort_keys=True, separators=(",", ":"), allow_nan=False,
                      ensure_ascii=True)


def _plain(obj: Any) -> Any:
    """Convert numpy scalars/arrays, tuples and paths into plain JSON types."""
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj)
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return _plain(dataclasses.asdict(obj))
    if isinstance(obj, enum.Enum):
        return str(obj.name)
    return obj


def run_key(payload: Mapping[str, Any]) -> str:
    """SHA-256 hex digest of the canonical JSON of ``payload``.

    >>> run_key({"b": 2, "a": 1}) == run_key({"a": 1, "b": 2})
    True
    >>> len(run_key({"a": 1}))
    64
    """
    return hashlib.sha256(canonical_json(payload).encode("ascii")).hexdigest()


def _is_int(v: Any) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def _is_num(v: Any) -> bool:
    return (_is_int(v) or isinstance(v, (float, np.floating))) and math.isfinite(float(v))


def _short(v: Any, n: int = 60) -> str:
    s = repr(v)
    return s if len(s) <= n else s[: n - 3] + "..."


_DIGESTS: dict[tuple[str, int, int], str] = {}


def file_digest(path: Path) -> str:
    """First 16 hex digits of the SHA-256 of a file (cached by path, size, mtime)."""
    st = path.stat()
    k = (str(path), st.st_size, st.st_mtime_ns)
    if k not in _DIGESTS:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                h.update(chunk)
        _DIGESTS[k] = h.hexdigest()[:16]
    return _DIGESTS[k]


# --------------------------------------------------------------------------- seeds
def parse_seeds(value: Any, where: str = "seeds") -> tuple[int, ...]:
    """Seeds from an int count, a list, ``"a:b"`` / ``"a,b,c"`` or ``{start, count}``.

    >>> parse_seeds(3), parse_seeds([5, 1]), parse_seeds("2:5"), parse_seeds("7,8")
    ((0, 1, 2), (5, 1), (2, 3, 4), (7, 8))
    >>> parse_seeds({"start": 10, "count": 2})
    (10, 11)
    >>> parse_seeds(-1)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: seeds: a seed count must be >= 1, got -1
    """
    def bad(msg: str) -> ConfigError:
        return ConfigError(f"{where}: {msg}")

    def counted(start: int, count: int) -> tuple[int, ...]:
        if start < 0 or start > MAX_SEED:
            raise bad(f"seeds must be integers in [0, 2**63), got {_shown(start)}")
        check_count(count, "MAX_RUNS", f"{where}: a seed count")
        if start + count - 1 > MAX_SEED:
            raise bad(f"seeds must be integers in [0, 2**63), got up to {start + count - 1}")
        return tuple(range(start, start + count))

    if _is_int(value):
        if value < 1:
            raise bad(f"a seed count must be >= 1, got {value}")
        return counted(0, int(value))
    if isinstance(value, str):
        text = value.strip()
        if len(text) > 100_000:
            raise bad(f"a seed text of {len(text)} characters is too long; use 'A:B' or a count")
        try:
            if ":" in text:
                a, b = (int(t) for t in text.split(":"))
            else:
                seeds = tuple(int(t) for t in text.split(",") if t.strip())
        except ValueError:
            raise bad(f"must be 'A:B', 'A,B,C' or a count, got {_shown(value)}") from None
        if ":" in text:
            if b <= a:
                raise bad(f"{_shown(value)} holds no seed")
            return counted(a, b - a)
        if not seeds:
            raise bad(f"{_shown(value)} holds no seed")
        if min(seeds) < 0 or max(seeds) > MAX_SEED:
            raise bad(f"seeds must be integers in [0, 2**63), got {_shown(value)}")
        return seeds
    if isinstance(value, Mapping):
        unknown = set(value) - {"start", "count"}
        if unknown or "count" not in value:
            raise bad(f"must be {{start: A, count: N}}, got {_short(dict(value))}")
        start, count = value.get("start", 0), value["count"]
        if not _is_int(start) or start < 0:
            raise bad(f"start must be an integer >= 0, got {_shown(start)}")
        if not _is_int(count) or count < 1:
            raise bad(f"count must be an integer >= 1, got {_shown(count)}")
        return counted(int(start), int(count))
    if isinstance(value, (list, tuple)):
        if not value:
            raise bad("the seed list is empty")
        check_count(len(value), "MAX_RUNS", f"{where}: a seed list")
        for i, s in enumerate(value):
            if not _is_int(s) or s < 0 or s > MAX_SEED:
                raise ConfigError(f"{where}[{i}]: a seed must be an integer in [0, 2**63), "
                                  f"got {_shown(s)}")
        if len(set(value)) != len(value):
            raise bad("the seed list repeats a seed")
        return tuple(int(s) for s in value)
    raise bad(f"must be a count, a list of integers, 'A:B' or {{start, count}}, "
              f"got {_shown(value)}")


# --------------------------------------------------------------------------- entries
@dataclass(frozen=True)
class Limits:
    """Per-run limits (become a :class:`pathfuse.Budget`)."""

    time_limit_s: float | None = None
    max_iterations: int | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"time_limit_s": self.time_limit_s, "max_iterations": self.max_iterations}

    def budget(self) -> Budget:
        return Budget(max_iterations=self.max_iterations, time_limit_s=self.time_limit_s)


def _parse_limits(value: Any, where: str, base: Limits | None = None) -> Limits:
    base = base or Limits()
    if value is None:
        return base
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: must be a mapping {{time_limit_s, max_iterations}}, "
                          f"got {_short(value)}")
    for k in value:
        if k not in _LIMIT_KEYS:
            raise ConfigError(f"{where}.{k}: unknown limit; use one of {', '.join(_LIMIT_KEYS)}")
    t = value.get("time_limit_s", base.time_limit_s)
    m = value.get("max_iterations", base.max_iterations)
    if t is not None and (not _is_num(t) or float(t) <= 0):
        raise ConfigError(f"{where}.time_limit_s: must be a number > 0, got {_shown(t)}")
    if m is not None and (not _is_int(m) or m < 1):
        raise ConfigError(f"{where}.max_iterations: must be an integer >= 1, got {_shown(m)}")
    return Limits(None if t is None else float(t), None if m is None else int(m))


def check_generate(dyn: Mapping[str, Any], where: str) -> None:
    """``{generate: {...}}`` holds arguments of ``generate_scenarios`` (pathfuse.world)."""
    import inspect

    from pathfuse.world.generate import generate_scenarios

    if not set(dyn) <= {"generate", "family_seed"} or "generate" not in dyn \
            or not isinstance(dyn["generate"], Mapping):
        raise ConfigError(f"{where}: must be {{generate: {{moving: K, speed_range: [lo, hi], "
                          f"...}}}} (and optionally family_seed: S), got {_short(dict(dyn))}")
    fs = dyn.get("family_seed")
    if fs is not None and (not _is_int(fs) or fs < 0):
        raise ConfigError(f"{where}.family_seed: must be an integer >= 0, got {_short(fs)}")
    allowed = [p for p in inspect.signature(generate_scenarios).parameters
               if p not in ("n_scenarios", "seed", "first")]
    for k in dyn["generate"]:
        if k not in allowed:
            raise ConfigError(f"{where}.generate.{k}: unknown argument (allowed:  "
                              f"{', '.join(allowed)}; the run's seed is the family seed, "
                              "or with family_seed the scenario's index)")
