"""Read and write ROS ``map_server`` maps (a YAML file naming a PGM/PNG image).

The YAML keys are those of ROS 1 ``map_server`` and ROS 2 ``nav2_map_server``::

    image: map.pgm            # relative to the YAML file's folder, or absolute
    resolution: 0.05          # metres per pixel
    origin: [-10.0, -10.0, 0.0]   # x, y of the lower-left pixel's corner, yaw
    negate: 0
    occupied_thresh: 0.65
    free_thresh: 0.196
    mode: trinary             # optional: trinary (default), scale or raw

``image``, ``resolution``, ``origin``, ``negate``, ``occupied_thresh`` and
``free_thresh`` are required, as in ``map_server``; other keys are kept in
``meta["yaml"]`` and otherwise ignored.

Pixel -> occupancy value (as map_server computes it)
----------------------------------------------------
``shade`` is the pixel's brightness in ``[0, 1]``: the mean of its R, G, B
channels divided by 255 (a grey pixel: its value / 255).  In *trinary* mode
an alpha channel, if the image has one, is averaged in with the colour
channels (map_server does this "to preserve existing behaviour").
``p = 1 - shade`` (``p = shade`` if ``negate``) is the occupancy probability.

* ``trinary``: 100 if ``p > occupied_thresh``, 0 if ``p < free_thresh``,
  else -1 (unknown).
* ``scale``: -1 if the pixel is not fully opaque; else 100 / 0 as in
  trinary, and in between ``rint((p - free_thresh) / (occupied_thresh -
  free_thresh) * 100)``.
* ``raw``: the value is ``round(mean of R, G, B)`` itself when it lies in
  0..100, else -1; ``negate`` is not applied (as in nav2).

These ROS values (int8, -1..100) are kept in ``meta["occupancy"]``.

ROS values -> a boolean grid (pathfuse's choice)
------------------------------------------------
A :class:`~pathfuse.grid.GridMap` only has free and occupied cells.  Value
100 is *occupied*, value 0 is *free*; every other cell - ROS unknown (-1)
and, in ``scale``/``raw`` mode, the in-between values 1..99 - is *not known
to be free or occupied*.  Those cells are marked in ``meta["unknown"]`` and
become occupied (``unknown="occupied"``, the default, the safe choice for a
robot) or free (``unknown="free"``, an optimistic planner).  Anyone who wants
another cut of the scale values can threshold ``meta["occupancy"]``.

Orientation and frame
---------------------
Image row 0 is the *top* of the map; it becomes pathfuse row ``H - 1``, so
pathfuse row 0 is the bottom image row (this is what map_server does when it
fills ``nav_msgs/OccupancyGrid``).  ``origin[:2]`` becomes
``GridMap.origin``.  A non-zero yaw ``origin[2]`` is *not* applied: the grid
stays axis-aligned in the map's own frame, the yaw is kept in
``meta["yaw"]`` and a :class:`UserWarning` is issued (many ROS tools ignore
the yaw too).

Examples
--------
>>> import tempfile, pathlib
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["..#", "...", "#.."], resolution=0.05, origin=(-1.0, 2.5))
>>> with tempfile.TemporaryDirectory() as d:
...     y = write_ros_map(g, pathlib.Path(d) / "tiny.yaml")
...     print(y.read_text(), end="")
...     h = read_ros_map(y)
image: tiny.pgm
mode: trinary
resolution: 0.05
origin: [-1.0, 2.5, 0.0]
negate: 0
occupied_thresh: 0.65
free_thresh: 0.196
>>> bool((h.occupied == g.occupied).all()), h.resolution, h.origin
(True, 0.05, (-1.0, 2.5))
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.io.image import load_pixels
from pathfuse.result import ConfigError, MapError, MapFormatError
from pathfuse.validate import short as _shown

__all__ = ["read_ros_map", "write_ros_map", "occupancy_values", "ROS_MODES", "UNKNOWN_POLICIES"]

ROS_MODES = ("trinary", "scale", "raw")
"""The ``mode`` values map_server accepts."""
UNKNOWN_POLICIES = ("occupied", "free")
"""What cells that are neither certainly free nor certainly occupied become."""

_REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")

# pixel values written by write_ros_map (the ones ROS map_saver writes)
_PIX_OCCUPIED = 0
_PIX_FREE = 254
_PIX_UNKNOWN = 205
_WRITE_OCCUPIED_THRESH = 0.65
_WRITE_FREE_THRESH = 0.196


def load_yaml_mapping(path: Path, what: str = "map YAML") -> dict[str, Any]:
    """Parse a YAML file that must hold a mapping; every failure is a :class:`MapFormatError`
    (or a :class:`~pathfuse.limits.LimitError` for a file beyond the limits of
    :mod:`pathfuse.safeyaml`)."""
    from pathfuse.safeyaml import read_yaml_mapping

    return read_yaml_mapping(path, what, MapFormatError)


def _number(path: Path, key: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise MapFormatError(f"{path}: key '{key}' must be a number, got {_shown(value)}")
    try:
        x = float(value)
    except ValueError:
        raise MapFormatError(f"{path}: key '{key}' must be a number, got {_shown(value)}") from None
    if not math.isfinite(x):
        raise MapFormatError(f"{path}: key '{key}' must be finite, got {_shown(value)}")
    return x


def _parse_yaml(path: Path, doc: dict[str, Any]) -> dict[str, Any]:
    """Validated map_server parameters from a parsed YAML mapping."""
    for key in _REQUIRED:
        if key not in doc:
            raise MapFormatError(
                f"{path}: missing key '{key}' (a ROS map YAML needs {', '.join(_REQUIRED)})"
            )
    image = doc["image"]
    if not isinstance(image, str) or not image.strip():
        raise MapFormatError(f"{path}: key 'image' must be a non-empty file name, got"
                             f" {_shown(image)}")
    image_path = Path(os.path.expanduser(image.strip()))
    if not image_path.is_absolute():
        image_path = path.parent / image_path

    res = _number(path, "resolution", doc["resolution"])
    if res <= 0:
        raise MapFormatError(f"{path}: key 'resolution' must be > 0, got"
                             f" {_shown(doc['resolution'])}")

    origin = doc["origin"]
    if not isinstance(origin, (list, tuple)) or len(origin) != 3:
        raise MapFormatError(
            f"{path}: key 'origin' must be a list [x, y, yaw] of 3 numbers, got {_shown(origin)}"
        )
    ox, oy, yaw = (_number(path, "origin", v) for v in origin)

    occ_t = _number(path, "occupied_thresh", doc["occupied_thresh"])
    free_t = _number(path, "free_thresh", doc["free_thresh"])
    for key, v in (("occupied_thresh", occ_t), ("free_thresh", free_t)):
        if not 0.0 <= v <= 1.0:
            raise MapFormatError(f"{path}: key '{key}' must be in [0, 1], got {_shown(doc[key])}")
    if free_t >= occ_t:
        raise MapFormatError(
            f"{path}: key 'free_thresh' ({_shown(doc['free_thresh'])}) must be smaller than "
            f"'occupied_thresh' ({_shown(doc['occupied_thresh'])})"
        )

    neg = doc["negate"]
    if isinstance(neg, bool):
        negate = neg
    elif isinstance(neg, int):
        negate = neg != 0
    elif isinstance(neg, str) and neg.strip().lstrip("+-").isdigit():
        negate = int(neg) != 0
    else:
        raise MapFormatError(f"{path}: key 'negate' must be 0/1 or true/false, got {_shown(neg)}")

    mode = doc.get("mode", "trinary")
    if mode not in ROS_MODES:
        raise MapFormatError(
            f"{path}: key 'mode' must be one of {', '.join(ROS_MODES)}, got {_shown(mode)}"
        )
    return {
        "image": image_path,
        "resolution": res,
        "origin": (ox, oy),
        "yaw": yaw,
        "occupied_thresh": occ_t,
        "free_thresh": free_t,
        "negate": negate,
        "mode": mode,
    }


def occupancy_values(
    grey: np.ndarray,
    alpha: np.ndarray | None,
    mode: str,
    negate: bool,
    occupied_thresh: float,
    free_thresh: float,
) -> np.ndarray:
    """ROS occupancy values (int8: -1 unknown, 0..100) of pixels, as map_server computes them.

    ``grey`` is the mean of the colour channels (0..255), ``alpha`` the
    alpha channel (0..255, 255 opaque) or ``None``.  Row order is left as
    given.

    >>> occupancy_values(np.array([[0.0, 128.0, 254.0]]), None, "trinary", False, 0.65, 0.196)
    array([[100,  -1,   0]], dtype=int8)
    >>> occupancy_values(np.array([[0.0, 128.0, 254.0]]), None, "scale", False, 0.65, 0.196)
    array([[100,  67,   0]], dtype=int8)
    >>> occupancy_values(np.array([[0.0, 50.0, 255.0]]), None, "raw", True, 0.65, 0.196)
    array([[ 0, 50, -1]], dtype=int8)
    """
    out = np.full(grey.shape, -1, dtype=np.int8)
    if mode == "raw":
        v = np.floor(grey / 255.0 * 255.0 + 0.5)
        ok = (v >= 0) & (v <= 100)
        out[ok] = v[ok].astype(np.int8)
        return out
    if mode == "trinary" and alpha is not None:
        shade = (grey * 3.0 + alpha) / 4.0 / 255.0
    else:
        shade = grey / 255.0
    p = shade if negate else 1.0 - shade
    occ = p > occupied_thresh
    free = p < free_thresh
    out[occ] = 100
    out[free] = 0
    if mode == "scale":
        mid = ~occ & ~free
        out[mid] = np.rint(
            (p[mid] - free_thresh) / (occupied_thresh - free_thresh) * 100.0
        ).astype(np.int8)
        if alpha is not None:
            out[alpha != 255.0] = -1
    elif mode != "trinary":
        raise ConfigError(f"mode must be one of {', '.join(ROS_MODES)}, got {_shown(mode)}")
    return out


def read_ros_map(
    yaml_path: str | os.PathLike[str],
    unknown: str = "occupied",
    name: str | None = None,
) -> GridMap:
    """Read a ROS ``map_server`` map (YAML + PGM/PNG image) into a :class:`GridMap`.

    Parameters
    ----------
    yaml_path : str or path-like
        The map's YAML file.
    unknown : {"occupied", "free"}
        What cells that are not certainly free or occupied become (ROS
        unknown, and in-between values of ``scale``/``raw`` maps).  The
        default ``"occupied"`` never lets a planner through unexplored space.
    name : str, optional
        Defaults to the YAML file name without its extension.

    Returns
    -------
    GridMap
        Row 0 is the *bottom* image row.  ``meta`` holds ``source`` (the
        YAML path), ``format`` ("ros"), ``image`` (the image path), ``mode``,
        ``negate``, ``occupied_thresh``, ``free_thresh``, ``yaw``, ``yaml``
        (the whole parsed YAML), ``unknown`` (bool mask of the cells that
        were neither 0 nor 100), ``unknown_policy`` and ``occupancy`` (int8
        ROS values, -1..100), both masks in pathfuse row order.

    Raises
    ------
    MapFormatError
        Missing YAML, YAML syntax error, missing key, bad value (non-numeric
        or non-positive resolution, origin not 3 numbers, thresholds outside
        ``[0, 1]`` or ``free_thresh >= occupied_thresh``, unknown mode, bad
        negate), image file missing (the message names the path looked
        for) or corrupt.  Every message names the YAML file.
    ConfigError
        ``unknown`` is not "occupied" or "free".
    """
    if unknown not in UNKNOWN_POLICIES:
        raise ConfigError(f"unknown must be 'occupied' or 'free', got {_shown(unknown)}")
    path = Path(yaml_path)
    doc = load_yaml_mapping(path, "ROS map YAML")
    return _read_ros_doc(path, doc, unknown, name)


def _read_ros_doc(path: Path, doc: dict[str, Any], unknown: str, name: str | None) -> GridMap:
    prm = _parse_yaml(path, doc)
    image_path: Path = prm["image"]
    if not image_path.exists():
        raise MapFormatError(
            f"{path}: image file named by key 'image' ({_shown(doc['image'])}) not found; "
            f"looked for {image_path}"
        )
    grey, alpha = load_pixels(image_path, context=f"{path}: key 'image': ")
    values = occupancy_values(
        grey, alpha, prm["mode"], prm["negate"], prm["occupied_thresh"], prm["free_thresh"]
    )[::-1]
    values = np.ascontiguousarray(values)
    certain_occ = values == 100
    unknown_mask = (values != 100) & (values != 0)
    occupied = certain_occ | unknown_mask if unknown == "occupied" else certain_occ
    if prm["yaw"] != 0.0:
        warnings.warn(
            f"{path}: origin yaw {prm['yaw']:g} rad is not applied; the grid is axis-aligned "
            "in the map frame (yaw kept in meta['yaw'])",
            UserWarning,
            stacklevel=3,
        )
    values.setflags(write=False)
    unknown_mask.setflags(write=False)
    meta = {
        "source": str(path),
        "format": "ros",
        "image": str(image_path),
        "mode": prm["mode"],
        "negate": prm["negate"],
        "occupied_thresh": prm["occupied_thresh"],
        "free_thresh": prm["free_thresh"],
        "yaw": prm["yaw"],
        "yaml": dict(doc),
        "unknown": unknown_mask,
        "unknown_policy": unknown,
        "occupancy": values,
    }
    try:
        return GridMap(
            occupied,
            resolution=prm["resolution"],
            origin=prm["origin"],
            name=name if name is not None else path.stem,
            meta=meta,
        )
    except MapFormatError:
        raise
    except MapError as exc:
        raise MapFormatError(f"{path}: {exc}") from None


def _write_pgm(path: Path, pixels: np.ndarray, resolution: float) -> None:
    h, w = pixels.shape
    header = f"P5\n# CREATOR: pathfuse write_ros_map {resolution:.3f} m/pix\n{w} {h}\n255\n"
    path.write_bytes(header.encode("ascii") + np.ascontiguousarray(pixels, np.uint8).tobytes())


def write_ros_map(
    grid: GridMap,
    yaml_path: str | os.PathLike[str],
    image_name: str | None = None,
    *,
    keep_unknown: bool = False,
) -> Path:
    """Write ``grid`` as a trinary ROS map: an 8-bit PGM (or PNG) image and its YAML.

    Pixels are 0 (occupied) and 254 (free), as ROS ``map_saver`` writes them;
    the YAML says ``occupied_thresh: 0.65`` and ``free_thresh: 0.196``, so
    :func:`read_ros_map` gives back an equal grid (same occupancy,
    resolution and origin).  The top image row is the top map row.

    Parameters
    ----------
    grid : GridMap
        The map.  ``grid.meta["yaw"]`` (if any) is written as the origin yaw.
    yaml_path : str or path-like
        Where to write the YAML.  The image goes in the same folder.
    image_name : str, optional
        Image file name, relative to the YAML's folder; defaults to the YAML
        name with ``.pgm``.  A ``.png`` name writes a PNG.
    keep_unknown : bool
        If true and ``grid.meta["unknown"]`` is a mask of the grid's shape,
        those cells are written as 205 (ROS unknown); reading back with the
        same ``unknown`` policy then gives the same grid.

    Returns
    -------
    Path
        The YAML file written.
    """
    ypath = Path(yaml_path)
    if image_name is None:
        image_name = ypath.with_suffix(".pgm").name
    ipath = ypath.parent / image_name
    suffix = ipath.suffix.lower()
    if suffix not in (".pgm", ".png"):
        raise MapError(f"image_name must end in .pgm or .png, got {_shown(image_name)}")
    occ = np.asarray(grid.occupied, dtype=bool)
    pixels = np.where(occ, _PIX_OCCUPIED, _PIX_FREE).astype(np.uint8)
    if keep_unknown:
        mask = grid.meta.get("unknown")
        if mask is not None and np.shape(mask) == occ.shape:
            pixels[np.asarray(mask, dtype=bool)] = _PIX_UNKNOWN
    pixels = pixels[::-1]
    yaw = grid.meta.get("yaw", 0.0)
    try:
        yaw = float(yaw)
    except (TypeError, ValueError):
        yaw = 0.0
    if not math.isfinite(yaw):
        yaw = 0.0
    if suffix == ".pgm":
        _write_pgm(ipath, pixels, grid.resolution)
    else:
        from PIL import Image

        Image.fromarray(pixels).save(ipath)
    doc = {
        "image": image_name,
        "mode": "trinary",
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin[0]), float(grid.origin[1]), yaw],
        "negate": 0,
        "occupied_thresh": _WRITE_OCCUPIED_THRESH,
        "free_thresh": _WRITE_FREE_THRESH,
    }
    import yaml

    ypath.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
    return ypath
