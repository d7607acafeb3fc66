"""The ``irsim`` run kind of an experiment: map entries that are IR-SIM world files.

An entry ``{name: N, irsim: FILE}`` or ``{name: N, irsim: {world: FILE,
resolution_m: R, time_limit_s: T}}`` (optionally ``seeds``) runs every planner
of the kind through the world with :func:`pathfuse.integrations.irsim_run.run_irsim_episode`
(``pathfuse[irsim]``), one episode per seed; the file's path is relative to the
experiment file and its SHA-256 is part of every run key.  The planners of the
kind are pathfuse's online planners and IR-SIM's own robot
(:data:`pathfuse.integrations.irsim_run.RVO_BASELINE`), which its executor runs
itself (:data:`pathfuse.bench.execute.EXTERNAL_PLANNERS`).

Everything is imported on first use, so reading an experiment without such an
entry never imports IR-SIM.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pathfuse.bench.keys import _is_num, _short, parse_seeds
from pathfuse.bench.spec import MapEntry
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.validate import short as _shown

__all__ = ["parse_irsim_entry", "external_names", "external_spec", "IRSIM_KEYS"]

IRSIM_KEYS = ("world", "resolution_m", "time_limit_s")
"""The keys of an ``irsim:`` mapping."""


def external_names(kind: str) -> list[str]:
    """The planner names a run kind adds to pathfuse's registry (``irsim``: IR-SIM's RVO
    robot)."""
    if kind != "irsim":
        return []
    from pathfuse.integrations.irsim_run import RVO_BASELINE

    return [RVO_BASELINE]


def external_spec(kind: str, name: Any) -> Any:
    """The (unregistered) planner spec of an external planner of ``kind``, or None."""
    if name not in external_names(kind):
        return None
    from pathfuse.integrations.irsim_run import baseline_spec

    return baseline_spec()


def parse_irsim_entry(i: int, v: Mapping[str, Any], top_seeds: tuple[int, ...],
                      top_radius: float, exp_dir: Path, seeds_overridden: bool) -> MapEntry:
    """``maps[i]`` with an ``irsim:`` key (the arguments of the parser's ``_parse_map``).

    Raises
    ------
    ConfigError
        An unknown key, no such world file, a file IR-SIM's settings block of which is bad,
        a bad resolution or time limit (the message names ``maps[i]`` and the key).
    """
    where = f"maps[{i}]"
    extra = set(v) - {"name", "irsim", "seeds"}
    if extra:
        raise ConfigError(f"{where}.{sorted(extra)[0]}: not used with irsim "
                          "(the world file holds the map, the robot and its goal)")
    seeds = top_seeds if seeds_overridden or "seeds" not in v else \
        parse_seeds(v["seeds"], f"{where}.seeds")
    w = v["irsim"]
    if isinstance(w, str):
        w = {"world": w}
    if not isinstance(w, Mapping) or not isinstance(w.get("world"), str) \
            or set(w) - set(IRSIM_KEYS):
        raise ConfigError(f"{where}.irsim: must be an IR-SIM world file or {{world: FILE, "
                          f"resolution_m: R, time_limit_s: T}}, got {_short(w)}")
    wp = Path(os.path.expanduser(w["world"]))
    wp = wp if wp.is_absolute() else exp_dir / wp
    if not wp.is_file():
        raise ConfigError(f"{where}.irsim: no such IR-SIM world file {wp}")
    from pathfuse.integrations.irsim_run import read_world_spec

    try:
        read_world_spec(wp)
    except PathfuseError as exc:
        raise ConfigError(f"{where}.irsim: {exc}") from None
    spec: dict[str, Any] = {"world": w["world"]}
    for key, default, unit in (("resolution_m", 0.05, "metres"), ("time_limit_s", None,
                                                                   "seconds")):
        val = w.get(key, default)
        if val is None:
            continue
        if not _is_num(val) or float(val) <= 0:
            raise ConfigError(f"{where}.irsim.{key}: must be a number > 0 ({unit}), "
                              f"got {_shown(val)}")
        spec[key] = float(val)
    name = v.get("name", Path(w["world"]).stem)
    if not isinstance(name, str) or not name.strip() or "/" in name:
        raise ConfigError(f"{where}.name: must be a non-empty string without '/', "
                          f"got {_shown(name)}")
    return MapEntry(index=i, name=name.strip(), kind="irsim", spec=None, family=None,
                    seeds=seeds, robot_radius_m=float(top_radius), dynamic=spec)
