"""One entry point for every map source: :func:`load_map` (a name or a file) and
:func:`map_from_spec` (the ``map:`` section of a scenario or experiment file).

=====================  ===========================================================
source                 read by
=====================  ===========================================================
``"paper"``            :func:`pathfuse.generate.paper_map` (``seed`` or 0)
``*.map``              :func:`~pathfuse.io.movingai.read_movingai`
``*.yaml``/``*.yml``   :func:`~pathfuse.io.ros.read_ros_map` if it has ``image``,
                       :func:`~pathfuse.io.inline.read_rows_yaml` if it has ``rows``
``*.png`` ``*.pgm``    :func:`~pathfuse.io.image.read_image` (``resolution`` needed)
``*.jpg`` ``*.jpeg``
``*.bmp``
``*.npy``              :func:`~pathfuse.io.image.read_npy` (``resolution`` needed)
``*.world`` ``*.sdf``  :func:`~pathfuse.io.gazebo.read_gazebo_world` (Gazebo SDF,
(``.gz`` too)          plain or gzipped; ``resolution`` default 0.05 m)
=====================  ===========================================================

Examples
--------
>>> load_map("paper", seed=2).shape
(15, 15)
>>> g = map_from_spec({"rows": ["..#", "..."], "resolution": 0.5})
>>> g.shape, g.resolution
((2, 3), 0.5)
>>> map_from_spec({"random": {"size": [6, 4], "obstacles": 5, "seed": 1}}).shape
(4, 6)
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pathfuse.generate import paper_map, random_map
from pathfuse.grid import GridMap
from pathfuse.io.gazebo import GAZEBO_SUFFIXES, is_gazebo_path, read_gazebo_world
from pathfuse.io.image import IMAGE_SUFFIXES, read_image, read_npy
from pathfuse.io.inline import read_rows_yaml
from pathfuse.io.movingai import read_movingai
from pathfuse.io.ros import UNKNOWN_POLICIES, _read_ros_doc, load_yaml_mapping
from pathfuse.result import ConfigError, MapError, MapFormatError
from pathfuse.validate import short as _shown

__all__ = ["load_map", "map_from_spec", "SUPPORTED_SUFFIXES", "SPEC_SOURCES"]

SUPPORTED_SUFFIXES = (".map", ".yaml", ".yml", *IMAGE_SUFFIXES, ".npy", *GAZEBO_SUFFIXES)
"""File name endings :func:`load_map` reads."""

SPEC_SOURCES = ("random", "paper", "movingai", "ros", "image", "npy", "rows", "gazebo")
"""The source keys of a map spec; exactly one must be present."""

_SPEC_EXTRA = {
    "random": ("name",),
    "paper": (),
    "movingai": ("resolution", "origin", "name"),
    "ros": ("unknown", "name"),
    "image": ("resolution", "origin", "threshold", "negate", "name"),
    "npy": ("resolution", "origin", "name"),
    "rows": ("resolution", "origin", "name"),
    "gazebo": ("resolution", "bounds", "margin", "name"),
}
_RANDOM_KEYS = ("size", "resolution", "obstacles", "density", "seed", "origin",
                "keep_free", "connect")


def _check_unknown(unknown: str) -> None:
    if unknown not in UNKNOWN_POLICIES:
        raise ConfigError(f"unknown must be 'occupied' or 'free', got {_shown(unknown)}")


def load_map(
    spec: str | os.PathLike[str] | GridMap,
    *,
    resolution: float | None = None,
    origin: tuple[float, float] | None = None,
    seed: int | None = None,
    unknown: str = "occupied",
    bounds: tuple[float, float, float, float] | None = None,
) -> GridMap:
    """Load a map from a name or a file, choosing the reader by the file's ending.

    Parameters
    ----------
    spec : str, path-like or GridMap
        ``"paper"`` or a file path (see the module table).  A
        :class:`GridMap` is returned unchanged.
    resolution : float, optional
        Metres per cell.  Required for images and ``.npy``; optional for
        ``.map`` (default 1.0) and rows YAML (when the file has none);
        refused for ROS YAML and ``"paper"``, which fix their own.
    origin : (float, float), optional
        Lower-left corner in metres, with the same rules as ``resolution``
        (default ``(0, 0)``).
    seed : int, optional
        Seed of the generated ``"paper"`` map (default 0); ignored for files.
    unknown : {"occupied", "free"}
        What unknown cells of a ROS map become (see :mod:`pathfuse.io.ros`).
    bounds : (x_min, y_min, x_max, y_max), optional
        Extent of a Gazebo world's grid in metres (default: its obstacles
        grown by 1 m); refused for other sources.

    Raises
    ------
    MapFormatError
        Missing file (the message names the path), unknown file ending (the
        message lists the supported ones), a YAML with neither ``image`` nor
        ``rows``, or any reader's error.
    ConfigError
        ``resolution``/``origin`` given for a source that fixes its own.
    MapError
        Missing ``resolution`` for an image or ``.npy``.
    """
    _check_unknown(unknown)
    if isinstance(spec, GridMap):
        return spec
    if isinstance(spec, str) and spec.strip().lower() == "paper":
        if resolution is not None or origin is not None:
            raise ConfigError("the paper map has a fixed resolution (1 m) and origin (-0.5, -0.5)")
        return paper_map(0 if seed is None else seed)
    if not isinstance(spec, (str, os.PathLike)):
        raise ConfigError(f"a map is 'paper' or a file path, got {_shown(spec)}")
    path = Path(os.path.expanduser(os.fspath(spec)))
    suffix = path.suffix.lower()
    if is_gazebo_path(path):
        if origin is not None:
            raise ConfigError(f"{path}: a Gazebo world's grid is placed by bounds=(x_min, "
                              f"y_min, x_max, y_max), not origin={origin!r}")
        return read_gazebo_world(path, 0.05 if resolution is None else resolution,
                                 bounds=bounds)
    if bounds is not None:
        raise ConfigError(f"{path}: bounds= applies to Gazebo worlds only")
    if suffix not in SUPPORTED_SUFFIXES:
        raise MapFormatError(
            f"{path}: unsupported map file type {_shown(suffix or '(no extension)')}; "
            f"supported: 'paper', {', '.join(SUPPORTED_SUFFIXES)}"
        )
    if not path.exists():
        hint = ""
        if suffix == ".map":
            from pathfuse.datasets import missing_hint

            hint = f" (the MovingAI benchmarks: {missing_hint('movingai')})"
        raise MapFormatError(f"map file not found: {path}{hint}")
    if path.is_dir():
        raise MapFormatError(f"map path is a directory, not a file: {path}")
    if suffix == ".map":
        return read_movingai(
            path,
            resolution=1.0 if resolution is None else resolution,
            origin=(0.0, 0.0) if origin is None else origin,
        )
    if suffix in (".yaml", ".yml"):
        doc = load_yaml_mapping(path, "map YAML")
        if "image" in doc:
            for key, val in (("resolution", resolution), ("origin", origin)):
                if val is not None:
                    raise ConfigError(
                        f"{path}: a ROS map sets its own {key}; do not pass {key}={_shown(val)}"
                    )
            return _read_ros_doc(path, doc, unknown, None)
        if "rows" in doc:
            return read_rows_yaml(path, resolution=resolution, origin=origin)
        raise MapFormatError(
            f"{path}: a map YAML needs an 'image' key (ROS map_server map) or a 'rows' key "
            f"(inline map); found keys {sorted(map(str, doc))}"
        )
    if suffix == ".npy":
        return read_npy(path, resolution, (0.0, 0.0) if origin is None else origin)
    return read_image(path, resolution, (0.0, 0.0) if origin is None else origin)


def _resolve(base_dir: Path, value: object, key: str) -> Path:
    if not isinstance(value, (str, os.PathLike)) or not os.fspath(value).strip():
        raise ConfigError(f"map spec key '{key}' must be a file path, got {_shown(value)}")
    p = Path(os.path.expanduser(os.fspath(value)))
    return p if p.is_absolute() else base_dir / p


def _random_from_spec(value: object, name: str | None) -> GridMap:
    if not isinstance(value, Mapping):
        raise ConfigError(
            f"map spec key 'random' must be a mapping (size, resolution, obstacles | density, "
            f"seed, ...), got {_shown(value)}"
        )
    for key in value:
        if key not in _RANDOM_KEYS:
            raise ConfigError(
                f"unknown key 'random.{key}' in map spec (allowed: {', '.join(_RANDOM_KEYS)})"
            )
    if "size" not in value:
        raise ConfigError("map spec 'random' needs 'size' ([width, height] in metres)")
    kwargs: dict[str, Any] = {"size_m": value["size"]}
    for key, arg in (("resolution", "resolution"), ("obstacles", "obstacles"),
                     ("density", "density"), ("seed", "seed"), ("origin", "origin"),
                     ("keep_free", "keep_free"), ("connect", "connect")):
        if key in value:
            kwargs[arg] = value[key]
    if name is not None:
        kwargs["name"] = name
    try:
        return random_map(**kwargs)
    except ConfigError as exc:
        raise ConfigError(f"map spec 'random': {exc}") from None
    except MapError as exc:
        raise MapError(f"map spec 'random': {exc}") from None


def map_from_spec(spec: Mapping[str, Any] | str, base_dir: str | os.PathLike[str] = ".") -> GridMap:
    """Build a map from the ``map`` section of a scenario or experiment file.

    Exactly one source key, with its companions::

        {random: {size: [15, 15], resolution: 1.0, obstacles: 50, seed: 7}}
                 # or density: 0.2 instead of obstacles; also origin,
                 # keep_free: [[x, y], ...], connect: [[[x, y], [x, y]], ...]
        {paper: {seed: 3}}            # or paper: 3, or paper: null (seed 0)
        {movingai: FILE.map, resolution: 1.0, origin: [0, 0]}
        {ros: FILE.yaml, unknown: occupied}
        {image: FILE.png, resolution: 0.05, origin: [0, 0], threshold: 0.5, negate: false}
        {npy: FILE.npy, resolution: 0.1, origin: [0, 0]}
        {rows: ["....", ".##."], resolution: 1.0, origin: [0, 0]}
        {gazebo: FILE.world.gz, resolution: 0.05, bounds: [x0, y0, x1, y1], margin: 1.0}

    Every source also takes ``name`` except ``paper``.  A string spec is
    passed to :func:`load_map` (relative paths against ``base_dir``).

    Parameters
    ----------
    spec : mapping or str
        The map section.
    base_dir : str or path-like
        Folder that relative file paths are taken from (normally the folder
        of the scenario file).

    Raises
    ------
    ConfigError
        No or several source keys, an unknown key (the message names it),
        a missing required key, a value of the wrong kind.
    MapFormatError, MapError
        From the readers and generators (missing files, bad contents).
    """
    base = Path(base_dir)
    if isinstance(spec, (str, os.PathLike)):
        s = os.fspath(spec)
        if s.strip().lower() == "paper":
            return paper_map(0)
        return load_map(_resolve(base, s, "map"))
    if not isinstance(spec, Mapping):
        raise ConfigError(f"a map spec must be a mapping or a file name, got {_shown(spec)}")
    sources = [k for k in SPEC_SOURCES if k in spec]
    if len(sources) != 1:
        what = "no" if not sources else f"several ({', '.join(sources)})"
        raise ConfigError(
            f"a map spec needs exactly one of {', '.join(SPEC_SOURCES)}; it has {what}"
        )
    src = sources[0]
    allowed = _SPEC_EXTRA[src]
    for key in spec:
        if key != src and key not in allowed:
            raise ConfigError(
                f"unknown key {_shown(key)} in a '{src}' map spec (allowed with '{src}': "
                f"{', '.join(allowed) if allowed else 'nothing else'})"
            )
    value = spec[src]
    name = spec.get("name")
    if name is not None and not isinstance(name, str):
        raise ConfigError(f"map spec key 'name' must be a string, got {_shown(name)}")

    if src == "random":
        return _random_from_spec(value, name)
    if src == "paper":
        if value is None:
            seed = 0
        elif isinstance(value, Mapping):
            for key in value:
                if key != "seed":
                    raise ConfigError(f"unknown key 'paper.{key}' in map spec (allowed: seed)")
            seed = value.get("seed", 0)
        else:
            seed = value
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(f"map spec 'paper' seed must be a non-negative integer, got"
                              f" {_shown(seed)}")
        return paper_map(seed)
    if src == "rows":
        doc = {"rows": value}
        for key in ("resolution", "origin", "name"):
            if key in spec:
                doc[key] = spec[key]
        return read_rows_yaml(doc)

    path = _resolve(base, value, src)
    if src == "gazebo":
        return read_gazebo_world(path, spec.get("resolution", 0.05), bounds=spec.get("bounds"),
                                 margin_m=spec.get("margin", 1.0), name=name)
    if src == "movingai":
        return read_movingai(path, resolution=spec.get("resolution", 1.0),
                             origin=spec.get("origin", (0.0, 0.0)), name=name)
    if src == "ros":
        unknown = spec.get("unknown", "occupied")
        _check_unknown(unknown)
        doc = load_yaml_mapping(path, "ROS map YAML")
        return _read_ros_doc(path, doc, unknown, name)
    if "resolution" not in spec:
        raise ConfigError(f"an '{src}' map spec needs 'resolution' (metres per cell)")
    if src == "npy":
        return read_npy(path, spec["resolution"], spec.get("origin", (0.0, 0.0)), name=name)
    negate = spec.get("negate", False)
    if not isinstance(negate, bool):
        raise ConfigError(f"map spec key 'negate' must be true or false, got {_shown(negate)}")
    return read_image(path, spec["resolution"], spec.get("origin", (0.0, 0.0)),
                      threshold=spec.get("threshold", 0.5), negate=negate, name=name)
