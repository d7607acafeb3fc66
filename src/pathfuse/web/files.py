"""Map files in the web app: measured before they are read, and uploads read safely.

:func:`check_file_cells` refuses a map file whose grid would pass ``Limits.max_cells``,
reading only what tells its size (a header, a rows YAML's rows, a Gazebo world's shapes,
parsed but not rasterised); :func:`check_scenario_cells` does the same for the map of a
scenario file of the catalog.  :func:`read_upload` reads uploaded files: they are written
to a fresh temporary folder under names the server chooses and read with
:func:`pathfuse.load_map` once their sizes, zip members, unpacked sizes and cell counts
have been checked; a decompression bomb (an image whose header claims more pixels than
Pillow accepts) is a 413 like any map over the limit.
"""

from __future__ import annotations

import io
import math
import os
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pathfuse.grid import GridMap
from pathfuse.result import MapFormatError, PathfuseError
from pathfuse.web.limits import ApiError, Limits, _cells_ok

__all__ = ["check_file_cells", "check_scenario_cells", "check_spec_cells", "read_upload"]


def check_spec_cells(spec: Mapping[str, Any], limits: Limits, where: str) -> None:
    """Refuse a generated map (``random``, ``rows``) above ``limits.max_cells``."""
    rnd = spec.get("random")
    if isinstance(rnd, Mapping):
        size, res = rnd.get("size"), rnd.get("resolution", 1.0)
        try:
            w = math.ceil(float(size[0]) / float(res))  # type: ignore[index]
            h = math.ceil(float(size[1]) / float(res))  # type: ignore[index]
        except (TypeError, ValueError, IndexError, ZeroDivisionError, OverflowError):
            return  # map_from_spec names the bad value
        if w > 0 and h > 0:
            _cells_ok(w, h, limits, f"{where}.random")
    rows = spec.get("rows")
    if isinstance(rows, list) and rows:
        width = max((len(r) for r in rows if isinstance(r, str)), default=0)
        _cells_ok(width, len(rows), limits, f"{where}.rows")


_FILE_SOURCES = ("movingai", "ros", "image", "npy", "gazebo")


def check_scenario_cells(path: Path, limits: Limits, name: str | None = None) -> None:
    """Refuse a scenario file (of the catalog) whose map would be larger than the cell limit,
    before the map is read: its map spec's file is measured as :func:`check_file_cells`
    does, a generated map by its size."""
    from pathfuse.safeyaml import read_yaml

    label = name or path.name
    try:
        doc = read_yaml(path, "scenario")
    except PathfuseError:
        return  # load_scenario names the problem
    m = doc.get("map") if isinstance(doc, Mapping) else None

    def file_of(value: Any) -> Path | None:
        if not isinstance(value, str) or not value.strip():
            return None
        p = Path(os.path.expanduser(value.strip()))
        return p if p.is_absolute() else path.parent / p

    if isinstance(m, str) and m.strip().lower() != "paper":
        f = file_of(m)
        if f is not None and f.is_file():
            check_file_cells(f, limits, name=f"{label}: map")
    elif isinstance(m, Mapping):
        for key in _FILE_SOURCES:
            f = file_of(m.get(key))
            if f is not None and f.is_file():
                check_file_cells(f, limits, m.get("resolution"), f"{label}: map",
                                 m.get("bounds"), m.get("margin", 1.0))
        check_spec_cells(m, limits, f"{label}: map")



_IMAGE = (".png", ".pgm", ".jpg", ".jpeg", ".bmp")


def _check_header(path: Path, limits: Limits, name: str | None = None) -> None:
    """Refuse a file whose header announces more cells than the limit (nothing decoded)."""
    suffix = path.suffix.lower()
    name = name or path.name
    if suffix in _IMAGE:
        import warnings

        from PIL import Image, UnidentifiedImageError

        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", Image.DecompressionBombWarning)
                with Image.open(path) as im:
                    w, h = im.size
        except Image.DecompressionBombError:
            raise ApiError(413, f"{name}: the image's header claims more pixels than this "
                                f"server's limit of {limits.max_cells} cells") from None
        except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
            raise MapFormatError(f"{name}: not a readable image ({exc})") from None
        _cells_ok(w, h, limits, name)
    elif suffix == ".npy":
        shape = _npy_shape(path, name)
        if len(shape) == 2:
            _cells_ok(shape[1], shape[0], limits, name)
        elif math.prod(shape) > limits.max_cells:
            raise ApiError(413, f"{name}: an array of shape {shape} is more than this "
                                f"server's limit of {limits.max_cells} cells")
    elif suffix == ".map":
        try:
            with path.open("rb") as f:
                head = f.read(256).decode("ascii", "replace").split()
        except OSError as exc:
            raise MapFormatError(f"{name}: cannot read ({exc.strerror})") from None
        dims = {}
        for key in ("height", "width"):
            if key in head:
                i = head.index(key)
                if i + 1 < len(head) and head[i + 1].isdigit():
                    dims[key] = int(head[i + 1])
        if len(dims) == 2:
            _cells_ok(dims["width"], dims["height"], limits, name)


def _npy_shape(path: Path, name: str) -> tuple[int, ...]:
    """The shape a ``.npy`` file's header announces (the array is not read)."""
    from numpy.lib import format as npformat

    try:
        with path.open("rb") as f:
            version = npformat.read_magic(f)
            if version == (1, 0):
                shape, _, _ = npformat.read_array_header_1_0(f)
            elif version == (2, 0):
                shape, _, _ = npformat.read_array_header_2_0(f)
            else:
                raise ValueError(f"unsupported .npy version {version}")
    except (OSError, ValueError, SyntaxError) as exc:
        raise MapFormatError(f"{name}: not a readable .npy array ({exc})") from None
    return tuple(int(s) for s in shape)


def _check_yaml_cells(path: Path, limits: Limits, name: str) -> None:
    """A rows YAML's rows, or a ROS YAML's image header, against the cell limit."""
    from pathfuse.io.ros import load_yaml_mapping

    try:
        doc = load_yaml_mapping(path)
    except PathfuseError:
        return  # load_map names the problem
    rows = doc.get("rows")
    if isinstance(rows, list):
        width = max((len(r) for r in rows if isinstance(r, str)), default=0)
        _cells_ok(width, len(rows), limits, name)
        return
    image = doc.get("image")
    if isinstance(image, str) and image.strip():
        img = Path(os.path.expanduser(image.strip()))
        img = img if img.is_absolute() else path.parent / img
        if img.is_file() and img.suffix.lower() in _IMAGE:
            _check_header(img, limits, f"{name}: image")


def _check_world_cells(path: Path, limits: Limits, resolution: Any, name: str,
                       bounds: Any = None, margin: Any = 1.0) -> None:
    """A Gazebo world's grid size from its shapes (parsed, not rasterised) against the limit."""
    from pathfuse.io.gazebo import _check_bounds, _check_number, _grid_frame, world_footprints

    res = _check_number(resolution, "resolution", gt=0)
    b = _check_bounds(bounds)
    m = _check_number(margin, "margin", ge=0)
    shapes = world_footprints(path)
    if not shapes.footprints:
        return  # read_gazebo_world names the problem
    _, (h, w) = _grid_frame(shapes.footprints, res, b, m, path)
    _cells_ok(w, h, limits, name)


def check_file_cells(path: Path, limits: Limits, resolution: float | None = None,
                     name: str | None = None, bounds: Any = None, margin: Any = 1.0) -> None:
    """Refuse a map file whose grid would have more than ``limits.max_cells`` cells, reading
    only what tells its size: an image's, a ``.npy``'s or a ``.map``'s header, a rows YAML's
    rows, a ROS YAML's image header, a Gazebo world's shapes (``resolution``, ``bounds``
    and ``margin`` as :func:`pathfuse.io.gazebo.read_gazebo_world` takes them; a world's
    default resolution is 0.05 m).

    Raises
    ------
    ApiError
        413 with the size and the limit.
    """
    from pathfuse.io.gazebo import is_gazebo_path

    label = name or path.name
    if is_gazebo_path(path):
        _check_world_cells(path, limits, 0.05 if resolution is None else resolution, label,
                           bounds, margin)
    elif path.suffix.lower() in (".yaml", ".yml"):
        _check_yaml_cells(path, limits, label)
    else:
        _check_header(path, limits, label)


def _check_gzip_size(path: Path, limit: int, name: str) -> None:
    """Refuse a gzipped upload that unpacks to more than ``limit`` bytes (read in chunks)."""
    import gzip

    total = 0
    try:
        with gzip.open(path, "rb") as f:
            while chunk := f.read(1 << 20):
                total += len(chunk)
                if total > limit:
                    raise ApiError(413, f"{name}: unpacks to more than {limit} bytes, this "
                                        "server's limit")
    except (OSError, EOFError):
        return  # not gzip after all, or corrupt: the reader names it


def _safe_name(name: str, index: int) -> str:
    """A file name to write an upload under: the base name's letters, digits and ``._-``."""
    base = os.path.basename(str(name).replace("\\", "/")) or f"upload{index}"
    keep = "".join(ch if ch.isalnum() or ch in "._-" else "_" for ch in base)[:100]
    keep = keep.lstrip(".") or f"upload{index}"
    return keep


def _unzip(data: bytes, folder: Path, limits: Limits, zip_name: str) -> list[Path]:
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
        raise MapFormatError(f"{zip_name}: not a valid zip file") from None
    members = [m for m in zf.infolist() if not m.is_dir()]
    if len(members) > 16:
        raise ApiError(413, f"{zip_name}: {len(members)} files; a map zip holds at most 16")
    total = sum(m.file_size for m in members)
    if total > limits.max_upload_bytes * 4:
        raise ApiError(413, f"{zip_name}: unpacks to {total} bytes, more than this server's "
                            f"limit of {limits.max_upload_bytes * 4}")
    out = []
    for i, m in enumerate(members):
        name = _safe_name(m.filename, i)
        if name.startswith("__MACOSX") or m.filename.startswith("__MACOSX/"):
            continue
        target = folder / name
        with zf.open(m) as src:
            blob = src.read(m.file_size + 1)
        if len(blob) > m.file_size:
            raise MapFormatError(f"{zip_name}: {m.filename}: size does not match the zip's "
                                 "directory")
        target.write_bytes(blob)
        out.append(target)
    return out


def _pick_map_file(paths: list[Path]) -> Path:
    """The map among uploaded files: a YAML (ROS or rows) first, else the one map file."""
    from pathfuse.io.load import SUPPORTED_SUFFIXES

    yamls = [p for p in paths if p.suffix.lower() in (".yaml", ".yml")]
    if len(yamls) > 1:
        raise MapFormatError("several YAML files uploaded; upload one map at a time "
                             f"({', '.join(p.name for p in yamls)})")
    if yamls:
        return yamls[0]
    maps = [p for p in paths if p.suffix.lower() in SUPPORTED_SUFFIXES]
    if len(maps) != 1:
        names = ", ".join(p.name for p in paths) or "nothing"
        raise MapFormatError(
            f"expected one map file ({', '.join(SUPPORTED_SUFFIXES)}, or a ROS .yaml with its "
            f"image, or a .zip of them), got {names}")
    return maps[0]


def _check_ros_image(yaml_path: Path, folder: Path) -> None:
    """A ROS YAML's ``image`` must be one of the uploaded files (never a server path)."""
    import yaml

    try:
        doc = yaml.safe_load(yaml_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return  # load_map names the problem
    if not isinstance(doc, Mapping) or "image" not in doc:
        return
    img = doc.get("image")
    if not isinstance(img, str):
        return
    target = (folder / img).resolve()
    if target.parent != folder.resolve() or not target.is_file():
        raise MapFormatError(
            f"{yaml_path.name}: image {img!r} was not uploaded with it; upload the YAML and "
            "its image together (two files, or one .zip)")


def read_upload(files: list[tuple[str, bytes]], limits: Limits,
                resolution: float | None = None) -> GridMap:
    """Read uploaded files (name, content) into a map with :func:`pathfuse.load_map`.

    One map file, a ROS YAML with its image, or a ``.zip`` of them.  Images and
    ``.npy`` need ``resolution``.  Sizes and cell counts are checked first.
    """
    if not files:
        raise MapFormatError("no file uploaded")
    if len(files) > 4:
        raise ApiError(400, f"{len(files)} files uploaded; a map is at most a YAML and its "
                            "image (or one .zip)")
    with tempfile.TemporaryDirectory(prefix="pathfuse-upload-") as tmp:
        folder = Path(tmp)
        try:
            grid, name = _read_files(files, folder, limits, resolution)
        except ApiError:
            raise
        except PathfuseError as exc:
            # the temporary folder is the server's business: name the files as uploaded
            raise type(exc)(str(exc).replace(str(folder) + os.sep, "")
                            .replace(str(folder), "")) from None
        except (ValueError, OSError, MemoryError) as exc:
            msg = str(exc).replace(str(folder) + os.sep, "").replace(str(folder), "")
            raise MapFormatError(f"cannot read this map ({msg})") from None
    _cells_ok(grid.width, grid.height, limits, name)
    return grid


def _read_files(files: list[tuple[str, bytes]], folder: Path, limits: Limits,
                resolution: float | None) -> tuple[GridMap, str]:
    from pathfuse.io import load_map

    paths: list[Path] = []
    for i, (name, data) in enumerate(files):
        safe = _safe_name(name, i)
        if safe.lower().endswith(".zip"):
            paths += _unzip(data, folder, limits, safe)
        else:
            target = folder / safe
            target.write_bytes(data)
            paths.append(target)
    path = _pick_map_file(paths)
    for p in paths:
        if p.name.lower().endswith(".gz"):
            _check_gzip_size(p, limits.max_upload_bytes * 4, p.name)
    if path.suffix.lower() in (".yaml", ".yml"):
        _check_ros_image(path, folder)
    for p in paths:
        if p != path:
            _check_header(p, limits)
    check_file_cells(path, limits, resolution)
    kwargs: dict[str, Any] = {}
    if resolution is not None and path.suffix.lower() not in (".yaml", ".yml"):
        kwargs["resolution"] = resolution
    return load_map(path, **kwargs), path.name
