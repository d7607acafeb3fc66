"""Maps for the web app: what a request may name, uploads, and the JSON form of a grid.

A request never names a file on the server's disk.  A map in a request is one of:

=================================================  =========================================
``"paper"`` (with ``"seed"`` beside it)            the paper's seeded 15 m map
``{"paper": {"seed": 5}}``                         the same
``{"random": {...}}``, ``{"rows": [...], ...}``    a map spec as in scenario files, without
                                                   the file-based sources
``{"blank": {"size": [W, H], "resolution": r}}``   an empty map of W x H cells
``{"grid": {"width", "height", "bits", ...}}``     an edited grid sent back by the page
``{"id": "ID"}`` or ``"ID"``                       a map of the server's catalog (the maps
                                                   of examples/ and tests/data, ``--maps``
                                                   folders) or an upload, by its id
=================================================  =========================================

Catalog ids are keys of a table built when the server starts; an id that is
not in the table is a 404, whatever it looks like.  Uploads are written to a
fresh temporary folder under the names the server chooses and read with
:func:`pathfuse.load_map`, after size and cell-count checks that read only
the files' headers.
"""

from __future__ import annotations

import base64
import hashlib
import io
import math
import os
import tempfile
import threading
import zipfile
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, MapFormatError, PathfuseError

__all__ = [
    "Limits",
    "ApiError",
    "MapEntry",
    "MapStore",
    "grid_to_json",
    "grid_from_bits",
    "read_upload",
]


class ApiError(PathfuseError):
    """A request the server refuses, with its HTTP status."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Limits:
    """What one request may ask for (``pathfuse serve`` options set them).

    Attributes
    ----------
    max_cells : int
        Cells of any map (uploaded, generated, blank or sent back edited).
    max_upload_bytes : int
        Size of an upload request (every file together).
    max_body_bytes : int
        Size of a JSON request body.
    time_budget_s : float
        Wall time of one request's computation; planners get it as their
        ``Budget.time_limit_s``.
    max_ticks : int
        Ticks of one simulated episode.
    max_discs : int
        Moving discs of one scenario.
    grace_s : float
        How long past ``time_budget_s`` the server waits for a computation
        before it answers 503 (a planner stops at its budget, but the
        metrics and layers around it take a little longer).
    """

    max_cells: int = 2048 * 2048
    max_upload_bytes: int = 32 * 1024 * 1024
    max_body_bytes: int = 16 * 1024 * 1024
    time_budget_s: float = 20.0
    max_ticks: int = 20000
    max_discs: int = 64
    grace_s: float = 5.0


# --------------------------------------------------------------------------- JSON form
def grid_to_json(grid: GridMap, map_id: str | None = None) -> dict[str, Any]:
    """The page's form of a grid: size, frame and the occupancy packed 8 cells a byte.

    ``bits`` is base64 of ``numpy.packbits`` of ``occupied`` in row-major order,
    row 0 (the bottom row) first.

    >>> g = GridMap.from_rows(["#..", "..."])
    >>> d = grid_to_json(g)
    >>> d["width"], d["height"], grid_from_bits(d).occupied.tolist() == g.occupied.tolist()
    (3, 2, True)
    """
    occ = np.ascontiguousarray(grid.occupied)
    return {
        "id": map_id,
        "name": grid.name,
        "width": int(grid.width),
        "height": int(grid.height),
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin[0]), float(grid.origin[1])],
        "bits": base64.b64encode(np.packbits(occ.ravel()).tobytes()).decode("ascii"),
    }


def pack_mask(mask: np.ndarray) -> str:
    """base64 of ``numpy.packbits`` of a bool array, row-major (as ``bits`` above)."""
    return base64.b64encode(np.packbits(np.ascontiguousarray(mask).ravel()).tobytes()
                            ).decode("ascii")


def _cells_ok(w: int, h: int, limits: Limits, what: str) -> None:
    if w * h > limits.max_cells:
        raise ApiError(413, f"{what}: {w} x {h} = {w * h} cells is more than this server's "
                            f"limit of {limits.max_cells} cells")


def _int_field(d: Mapping[str, Any], key: str, where: str) -> int:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ConfigError(f"{where}.{key}: must be an integer >= 1, got {v!r}")
    return v


def grid_from_bits(d: Mapping[str, Any], limits: Limits | None = None,
                   where: str = "map.grid") -> GridMap:
    """The :class:`GridMap` of a ``grid_to_json`` dict (checked before anything is allocated)."""
    from pathfuse import validate

    if not isinstance(d, Mapping):
        raise ConfigError(f"{where}: must be a mapping with width, height, bits, got "
                          f"{validate.short(d)}")
    validate.mapping(d, where, ("id", "name", "width", "height", "resolution", "origin",
                                "bits"))
    w, h = _int_field(d, "width", where), _int_field(d, "height", where)
    _cells_ok(w, h, limits or Limits(), where)
    res = validate.number(d.get("resolution", 1.0), f"{where}.resolution", gt=0)
    origin = validate.point(d.get("origin", [0.0, 0.0]), f"{where}.origin")
    bits = d.get("bits")
    if not isinstance(bits, str):
        raise ConfigError(f"{where}.bits: must be a base64 string, got {validate.short(bits)}")
    need = (w * h + 7) // 8
    if len(bits) > 4 * ((need + 2) // 3) + 8:
        raise ConfigError(f"{where}.bits: longer than {w} x {h} cells need")
    try:
        raw = base64.b64decode(bits, validate=True)
    except ValueError:
        raise ConfigError(f"{where}.bits: not valid base64") from None
    if len(raw) != need:
        raise ConfigError(f"{where}.bits: must hold {need} bytes for {w} x {h} cells, "
                          f"got {len(raw)}")
    occ = np.unpackbits(np.frombuffer(raw, dtype=np.uint8), count=w * h).astype(bool)
    name = d.get("name") or "edited"
    return GridMap(occ.reshape(h, w), res, origin, name=str(name)[:80])


# --------------------------------------------------------------------------- store
@dataclass
class MapEntry:
    """A map the server can hand out by id."""

    id: str
    name: str
    kind: str  # "catalog" or "upload"
    path: Path | None = None  # catalog files only (chosen by the server, never by a request)
    grid: GridMap | None = None
    spec: Any = None  # a self-contained map spec (paper/random/rows) when there is one
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None
    info: dict[str, Any] = field(default_factory=dict)


_MAP_SPEC_KEYS = ("paper", "random", "rows")


class MapStore:
    """The catalog (files found when the server starts) and the uploads (kept in memory).

    Thread-safe; uploads and edited grids are kept in bounded LRU tables.
    """

    def __init__(self, folders: list[tuple[str, Path]] | None = None,
                 limits: Limits | None = None, max_uploads: int = 32) -> None:
        self.limits = limits or Limits()
        self._lock = threading.Lock()
        self._catalog: dict[str, MapEntry] = {}
        self._uploads: OrderedDict[str, MapEntry] = OrderedDict()
        self._grids: OrderedDict[str, GridMap] = OrderedDict()
        self._max_uploads = max_uploads
        self.scenarios: dict[str, Path] = {}
        for label, folder in folders or []:
            self._scan(label, Path(folder))

    # ------------------------------------------------------------------ catalog
    def _scan(self, label: str, folder: Path) -> None:
        """Add the maps and the scenario files (those that load) under ``folder``, with ids
        ``label/relative/path``."""
        from pathfuse.io.load import SUPPORTED_SUFFIXES

        if not folder.is_dir():
            return
        root = folder.resolve()
        for p in sorted(root.rglob("*")):
            if not p.is_file() or any(part.startswith(".") for part in p.parts):
                continue
            rel = f"{label}/{p.relative_to(root).as_posix()}"
            suffix = p.suffix.lower()
            if suffix in (".yaml", ".yml"):
                kind = _yaml_kind(p)
                if kind == "scenario" and _loads(p):
                    self.scenarios[rel] = p
                elif kind == "map":
                    self._catalog[rel] = MapEntry(rel, p.name, "catalog", p)
            elif suffix == ".map" or (suffix in SUPPORTED_SUFFIXES and suffix not in
                                      (".png", ".pgm", ".jpg", ".jpeg", ".bmp", ".npy")):
                # images and .npy need a resolution: upload them instead
                self._catalog[rel] = MapEntry(rel, p.name, "catalog", p)

    def catalog(self) -> list[dict[str, Any]]:
        """Every catalog map and scenario: id, name, kind."""
        out = [{"id": "paper", "name": "paper (seeded 15 m map)", "kind": "generated"}]
        out += [{"id": e.id, "name": e.name, "kind": "file"} for e in self._catalog.values()]
        return out

    def get(self, map_id: str) -> MapEntry:
        """The entry of ``map_id`` with its grid loaded; :class:`ApiError` 404 otherwise."""
        with self._lock:
            e = self._uploads.get(map_id)
            if e is not None:
                self._uploads.move_to_end(map_id)
                return e
            e = self._catalog.get(map_id)
        if e is None:
            raise ApiError(404, f"map: no map with id {_short(map_id)} on this server "
                                "(GET /api/maps lists them)")
        if e.grid is None:
            from pathfuse.io import load_map

            assert e.path is not None
            e.grid = load_map(e.path)
        return e

    def add_upload(self, grid: GridMap, name: str, spec: Any = None) -> MapEntry:
        """Keep an uploaded (or generated) grid; returns its entry with a fresh id."""
        digest = hashlib.sha1(grid.occupied.tobytes()).hexdigest()[:10]
        map_id = f"upload-{digest}-{os.urandom(3).hex()}"
        e = MapEntry(map_id, name, "upload", grid=grid, spec=spec)
        with self._lock:
            self._uploads[map_id] = e
            while len(self._uploads) > self._max_uploads:
                self._uploads.popitem(last=False)
        return e

    # ------------------------------------------------------------------ requests
    def resolve(self, spec: Any, seed: Any = None, where: str = "map") -> tuple[GridMap, Any]:
        """The grid of a request's map, and a self-contained spec of it (or None).

        See the module docstring for what ``spec`` may be.
        """
        from pathfuse import validate
        from pathfuse.generate import paper_map

        if isinstance(spec, str):
            if spec.strip().lower() == "paper":
                s = 0 if seed is None else validate.integer(seed, "seed", ge=0)
                return paper_map(s), {"paper": {"seed": s}}
            e = self.get(spec)
            return e.grid, e.spec  # type: ignore[return-value]
        if not isinstance(spec, Mapping):
            raise ConfigError(f"{where}: must be 'paper', a map id or a map spec mapping, got "
                              f"{validate.short(spec)}")
        if "id" in spec:
            validate.mapping(spec, where, ("id",))
            e = self.get(validate.text(spec["id"], f"{where}.id"))
            return e.grid, e.spec  # type: ignore[return-value]
        if "grid" in spec:
            validate.mapping(spec, where, ("grid",))
            return self._edited(spec["grid"], f"{where}.grid"), None
        if "blank" in spec:
            validate.mapping(spec, where, ("blank",))
            return self._blank(spec["blank"], f"{where}.blank"), None
        files = [k for k in spec if k not in _MAP_SPEC_KEYS and k in
                 ("movingai", "ros", "image", "npy")]
        if files:
            raise ApiError(400, f"{where}.{files[0]}: the server reads no file a request "
                                "names; upload the map (POST /api/maps) and use its id")
        self._check_spec_size(spec, where)
        from pathfuse.io import map_from_spec

        try:
            grid = map_from_spec(spec)
        except PathfuseError as exc:
            raise type(exc)(f"{where}: {exc}") from None
        return grid, dict(spec)

    def _check_spec_size(self, spec: Mapping[str, Any], where: str) -> None:
        """Refuse a generated map above the cell limit before generating it."""
        rnd = spec.get("random")
        if isinstance(rnd, Mapping):
            size, res = rnd.get("size"), rnd.get("resolution", 1.0)
            try:
                w = math.ceil(float(size[0]) / float(res))  # type: ignore[index]
                h = math.ceil(float(size[1]) / float(res))  # type: ignore[index]
            except (TypeError, ValueError, IndexError, ZeroDivisionError, OverflowError):
                return  # map_from_spec names the bad value
            if w > 0 and h > 0:
                _cells_ok(w, h, self.limits, f"{where}.random")
        rows = spec.get("rows")
        if isinstance(rows, list) and rows and isinstance(rows[0], str):
            _cells_ok(len(rows[0]), len(rows), self.limits, f"{where}.rows")

    def _blank(self, d: Any, where: str) -> GridMap:
        from pathfuse import validate

        validate.mapping(d, where, ("size", "resolution", "origin", "name"))
        size = d.get("size")
        if not isinstance(size, (list, tuple)) or len(size) != 2:
            raise ConfigError(f"{where}.size: must be [width, height] in cells, got "
                              f"{validate.short(size)}")
        w = validate.integer(size[0], f"{where}.size[0]", ge=1)
        h = validate.integer(size[1], f"{where}.size[1]", ge=1)
        _cells_ok(w, h, self.limits, where)
        res = validate.number(d.get("resolution", 1.0), f"{where}.resolution", gt=0)
        origin = validate.point(d.get("origin", [0.0, 0.0]), f"{where}.origin")
        return GridMap(np.zeros((h, w), dtype=bool), res, origin,
                       name=str(d.get("name") or f"blank-{w}x{h}"))

    def _edited(self, d: Any, where: str) -> GridMap:
        """An edited grid; the same content again gives the same GridMap (its A* buffers,
        c-space and distance field are reused)."""
        if isinstance(d, Mapping) and isinstance(d.get("bits"), str):
            key = hashlib.sha1(repr((d.get("width"), d.get("height"), d.get("resolution"),
                                     d.get("origin"), d.get("name"), d["bits"])).encode()
                               ).hexdigest()
            with self._lock:
                g = self._grids.get(key)
                if g is not None:
                    self._grids.move_to_end(key)
                    return g
        else:
            key = ""
        g = grid_from_bits(d, self.limits, where)
        if key:
            with self._lock:
                self._grids[key] = g
                while len(self._grids) > 8:
                    self._grids.popitem(last=False)
        return g


def _short(v: Any) -> str:
    from pathfuse.validate import short

    return short(v)


def _loads(p: Path) -> bool:
    """Whether a scenario file loads (the catalog lists only those)."""
    from pathfuse.world.scenario import load_scenario

    try:
        load_scenario(p)
    except (PathfuseError, OSError, ValueError):
        return False
    return True


def _yaml_kind(p: Path) -> str:
    """``"scenario"``, ``"map"`` or ``""`` from a YAML file's top-level keys."""
    import yaml

    try:
        if p.stat().st_size > 4 * 1024 * 1024:
            return ""
        doc = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return ""
    if not isinstance(doc, Mapping):
        return ""
    if "start" in doc and "goal" in doc and "map" in doc:
        return "scenario"
    if "image" in doc or "rows" in doc:
        return "map"
    return ""


# --------------------------------------------------------------------------- uploads
_IMAGE = (".png", ".pgm", ".jpg", ".jpeg", ".bmp")


def _check_header(path: Path, limits: Limits) -> None:
    """Refuse a file whose header announces more cells than the limit (nothing decoded)."""
    suffix = path.suffix.lower()
    name = path.name
    if suffix in _IMAGE:
        from PIL import Image, UnidentifiedImageError

        try:
            with Image.open(path) as im:
                w, h = im.size
        except (UnidentifiedImageError, OSError, ValueError) as exc:
            raise MapFormatError(f"{name}: not a readable image ({exc})") from None
        _cells_ok(w, h, limits, name)
    elif suffix == ".npy":
        try:
            arr = np.load(path, mmap_mode="r", allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise MapFormatError(f"{name}: not a readable .npy array ({exc})") from None
        shape = tuple(int(s) for s in getattr(arr, "shape", ()))
        del arr
        if len(shape) == 2:
            _cells_ok(shape[1], shape[0], limits, name)
    elif suffix == ".map":
        try:
            with path.open("rb") as f:
                head = f.read(256).decode("ascii", "replace").split()
        except OSError as exc:
            raise MapFormatError(f"{name}: cannot read ({exc})") from None
        dims = {}
        for key in ("height", "width"):
            if key in head:
                i = head.index(key)
                if i + 1 < len(head) and head[i + 1].isdigit():
                    dims[key] = int(head[i + 1])
        if len(dims) == 2:
            _cells_ok(dims["width"], dims["height"], limits, name)


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
        _check_header(p, limits)
    if path.suffix.lower() in (".yaml", ".yml"):
        _check_ros_image(path, folder)
    kwargs: dict[str, Any] = {}
    if resolution is not None and path.suffix.lower() not in (".yaml", ".yml"):
        kwargs["resolution"] = resolution
    return load_map(path, **kwargs), path.name
