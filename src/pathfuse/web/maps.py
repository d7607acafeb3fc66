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

This table is an allow-list (:data:`REQUEST_SOURCES`): any other key, the
file sources of scenario files (``movingai``, ``ros``, ``image``, ``npy``,
``gazebo``) included, is refused with the same answer whether or not the value
names a file that exists, and nothing is read.

Catalog ids are keys of a table built when the server starts; an id that is
not in the table is a 404, whatever it looks like.  Uploads are read by
:mod:`pathfuse.web.files`.  Every map, of the catalog too, is checked against
``Limits.max_cells`` before its grid is allocated.
"""

from __future__ import annotations

import base64
import hashlib
import os
import threading
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.web.limits import ApiError, Limits, _cells_ok

__all__ = [
    "Limits",
    "ApiError",
    "MapEntry",
    "MapStore",
    "REQUEST_SOURCES",
    "request_source",
    "grid_to_json",
    "grid_from_bits",
]

REQUEST_SOURCES = ("paper", "random", "rows", "blank", "grid", "id")
"""The map sources a request may name (the allow-list); none of them reads a file."""
_COMPANIONS: dict[str, tuple[str, ...]] = {
    "paper": (), "random": ("name",), "rows": ("resolution", "origin", "name"),
    "blank": (), "grid": (), "id": ()}


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

    def portable(self) -> MapEntry:
        """A copy to send to another process: the grid without its caches (c-space,
        distance field, search buffers), which the other process builds when it needs
        them."""
        g = self.grid
        if g is not None:
            g = GridMap(g.occupied, g.resolution, g.origin, name=g.name, meta=dict(g.meta))
        return MapEntry(self.id, self.name, self.kind, None, g, self.spec, self.start,
                        self.goal, dict(self.info))


class MapStore:
    """The catalog (files found when the server starts) and the uploads (kept in memory).

    Thread-safe; uploads and edited grids are kept in bounded LRU tables.  In a worker
    process (:meth:`worker_mode`) the uploads table is a cache: an id it does not hold
    is asked of the server process, and the maps the worker adds are handed back to it
    (:meth:`take_added`, :meth:`adopt`).
    """

    def __init__(self, folders: list[tuple[str, Path]] | None = None,
                 limits: Limits | None = None, max_uploads: int = 32) -> None:
        self.limits = limits or Limits()
        self._lock = threading.Lock()
        self._catalog: dict[str, MapEntry] = {}
        self._uploads: OrderedDict[str, MapEntry] = OrderedDict()
        self._grids: OrderedDict[str, GridMap] = OrderedDict()
        self._max_uploads = max_uploads
        self._fetch: Callable[[str], MapEntry | None] | None = None
        self._added: list[MapEntry] = []
        self.scenarios: dict[str, Path] = {}
        for label, folder in folders or []:
            self._scan(label, Path(folder))

    # ------------------------------------------------------------------ worker processes
    def worker_mode(self, fetch: Callable[[str], MapEntry | None],
                    max_uploads: int = 8) -> None:
        """Make this (forked) copy a worker's: uploads come from ``fetch`` and are cached
        (at most ``max_uploads``); the lock is a new one (the server's may have been held
        by another thread when the process was forked)."""
        self._lock = threading.Lock()
        self._uploads = OrderedDict()
        self._max_uploads = max_uploads
        self._fetch = fetch
        self._added = []

    def take_added(self) -> list[MapEntry]:
        """The maps added since the last call (worker mode), ready to send."""
        out, self._added = [e.portable() for e in self._added], []
        return out

    def adopt(self, entries: list[MapEntry]) -> None:
        """Keep maps a worker added, under the ids the worker gave them."""
        with self._lock:
            for e in entries:
                self._uploads[e.id] = e
                self._uploads.move_to_end(e.id)
            while len(self._uploads) > self._max_uploads:
                self._uploads.popitem(last=False)

    def upload_entry(self, map_id: str) -> MapEntry | None:
        """The upload ``map_id`` ready to send to a worker, or None."""
        with self._lock:
            e = self._uploads.get(map_id)
            if e is not None:
                self._uploads.move_to_end(map_id)
        return None if e is None else e.portable()

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
                if kind == "scenario" and _loads(p, self.limits):
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
        """The entry of ``map_id`` with its grid loaded; :class:`ApiError` 404 otherwise.

        A catalog file is checked against the cell limit before it is read, and its
        messages name it by its id, not by its path on the server.
        """
        with self._lock:
            e = self._uploads.get(map_id)
            if e is not None:
                self._uploads.move_to_end(map_id)
                return e
            e = self._catalog.get(map_id)
        if e is None and self._fetch is not None and map_id.startswith("upload-"):
            e = self._fetch(map_id)
            if e is not None:
                self._keep(e)
                return e
        if e is None:
            raise ApiError(404, f"map: no map with id {_short(map_id)} on this server "
                                "(GET /api/maps lists them)")
        if e.grid is None:
            from pathfuse.io import load_map

            assert e.path is not None
            from pathfuse.web.files import check_file_cells

            try:
                check_file_cells(e.path, self.limits, name=e.id)
                e.grid = load_map(e.path)
            except ApiError as exc:
                raise ApiError(exc.status, _hide(str(exc), e.path, e.id)) from None
            except PathfuseError as exc:
                raise type(exc)(_hide(str(exc), e.path, e.id)) from None
            _cells_ok(e.grid.width, e.grid.height, self.limits, e.id)
        return e

    def _keep(self, e: MapEntry) -> None:
        with self._lock:
            self._uploads[e.id] = e
            while len(self._uploads) > self._max_uploads:
                self._uploads.popitem(last=False)

    def add_upload(self, grid: GridMap, name: str, spec: Any = None) -> MapEntry:
        """Keep an uploaded (or generated) grid; returns its entry with a fresh id."""
        digest = hashlib.sha1(grid.occupied.tobytes()).hexdigest()[:10]
        map_id = f"upload-{digest}-{os.urandom(3).hex()}"
        e = MapEntry(map_id, name, "upload", grid=grid, spec=spec)
        self._keep(e)
        if self._fetch is not None:
            self._added.append(e)
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
        source = request_source(spec, where)
        if source == "id":
            e = self.get(validate.text(spec["id"], f"{where}.id"))
            return e.grid, e.spec  # type: ignore[return-value]
        if source == "grid":
            return self._edited(spec["grid"], f"{where}.grid"), None
        if source == "blank":
            return self._blank(spec["blank"], f"{where}.blank"), None
        self.check_spec_size(spec, where)
        from pathfuse.io import map_from_spec

        try:
            grid = map_from_spec(spec)
        except PathfuseError as exc:
            raise type(exc)(f"{where}: {exc}") from None
        return grid, dict(spec)

    def check_spec_size(self, spec: Mapping[str, Any], where: str) -> None:
        """Refuse a generated map above the cell limit before generating it."""
        from pathfuse.web.files import check_spec_cells

        check_spec_cells(spec, self.limits, where)

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


def request_source(spec: Mapping[str, Any], where: str = "map") -> str:
    """The one source key of a request's map mapping, checked against the allow-list
    :data:`REQUEST_SOURCES` (the value is never shown: the answer is the same whether or
    not a file of that name exists).

    >>> request_source({"rows": ["..."], "resolution": 0.5})
    'rows'
    >>> request_source({"gazebo": "/etc/passwd"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pathfuse.web.limits.ApiError: map.gazebo: the server reads no file a request names; ...
    """
    from pathfuse.io.load import SPEC_SOURCES

    sources = [k for k in spec if k in REQUEST_SOURCES]
    for k in spec:
        if k in REQUEST_SOURCES or (len(sources) == 1 and k in _COMPANIONS[sources[0]]):
            continue
        key = k if isinstance(k, str) else _short(k)
        if k in SPEC_SOURCES:
            raise ApiError(400, f"{where}.{key}: the server reads no file a request names; "
                                "upload the map (POST /api/maps) and use its id")
        allowed = ", ".join(_COMPANIONS[sources[0]]) if len(sources) == 1 else ""
        raise ConfigError(f"{where}.{key}: unknown key (a map is one of "
                          f"{', '.join(REQUEST_SOURCES)}"
                          + (f"; allowed with '{sources[0]}': {allowed})" if allowed else ")"))
    if len(sources) != 1:
        what = "none" if not sources else ", ".join(sources)
        raise ConfigError(f"{where}: needs exactly one of {', '.join(REQUEST_SOURCES)}; "
                          f"it has {what}")
    return sources[0]


def _short(v: Any) -> str:
    from pathfuse.validate import short

    return short(v)


def _hide(message: str, path: Path, label: str) -> str:
    """``message`` with the server's path of a file replaced by its catalog id."""
    for p in (str(path), str(path.resolve())):
        message = message.replace(p, label)
    return message


def _loads(p: Path, limits: Limits) -> bool:
    """Whether a scenario file loads within the cell limit (the catalog lists only those)."""
    from pathfuse.web.files import check_scenario_cells
    from pathfuse.world.scenario import load_scenario

    try:
        check_scenario_cells(p, limits)
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
