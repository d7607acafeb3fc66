"""Small maps written as text rows inside a YAML file (or a dict).

::

    rows:
      - "....."
      - ".##.."
      - "....."
    resolution: 1.0      # optional, metres per cell (default 1.0)
    origin: [0, 0]       # optional, lower-left corner in metres (default [0, 0])
    name: corridor       # optional

The *first* row is the *top* of the map (the bottom row is pathfuse row 0),
so the text looks like the map.  ``.`` is free, ``#`` and ``@`` are blocked;
any other character is an error naming its row and column.  ``rows`` may
also be one multi-line string (a YAML ``|`` block); blank lines and the
whitespace around each line are then dropped.

Examples
--------
>>> g = read_rows_yaml({"rows": ["..#", "..."], "resolution": 0.5})
>>> g.shape, bool(g.occupied[1, 2]), g.resolution
((2, 3), True, 0.5)
>>> read_rows_yaml({"rows": "..\\n#.\\n"}).occupied.astype(int).tolist()
[[1, 0], [0, 0]]
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.io.ros import load_yaml_mapping
from pathfuse.result import ConfigError, MapError, MapFormatError
from pathfuse.validate import short as _shown

__all__ = ["read_rows_yaml", "ROWS_KEYS", "FREE_CHAR", "BLOCKED_CHARS"]

FREE_CHAR = "."
BLOCKED_CHARS = "#@"
ROWS_KEYS = ("rows", "resolution", "origin", "name")
"""Keys an inline rows map may have."""


def _parse_rows(where: str, rows: object) -> list[str]:
    if isinstance(rows, str) and rows.strip() and "\n" not in rows.strip():
        raise MapFormatError(
            f"{where}: 'rows' must be a list of strings (or a multi-line '|' block), got the "
            f"single string {_shown(rows)}; write rows: [{_shown(rows)}] for a one-row map"
        )
    if isinstance(rows, str):
        lines = [ln.strip() for ln in rows.splitlines()]
        lines = [ln for ln in lines if ln]
    elif isinstance(rows, (list, tuple)):
        lines = []
        for i, r in enumerate(rows):
            if not isinstance(r, str):
                raise MapFormatError(
                    f"{where}: 'rows' entry {i + 1} (from the top) must be a string of "
                    f"'.', '#' and '@', got {_shown(r)} (quote rows in YAML)"
                )
            lines.append(r)
    else:
        raise MapFormatError(
            f"{where}: 'rows' must be a list of strings or one multi-line string, got"
            f" {_shown(rows)}"
        )
    if not lines:
        raise MapFormatError(f"{where}: 'rows' holds no row")
    width = len(lines[0])
    if width == 0:
        raise MapFormatError(f"{where}: row 1 (from the top) is empty")
    for i, line in enumerate(lines):
        if len(line) != width:
            raise MapFormatError(
                f"{where}: ragged rows: row {i + 1} (from the top) has {len(line)} "
                f"characters, row 1 has {width}"
            )
        for j, ch in enumerate(line):
            if ch != FREE_CHAR and ch not in BLOCKED_CHARS:
                raise MapFormatError(
                    f"{where}: row {i + 1} (from the top), column {j + 1}: invalid character "
                    f"{_shown(ch)} (use '.' for free, '#' or '@' for blocked)"
                )
    return lines


def read_rows_yaml(
    source: str | os.PathLike[str] | dict[str, Any],
    *,
    resolution: float | None = None,
    origin: tuple[float, float] | None = None,
    name: str | None = None,
) -> GridMap:
    """Build a map from text rows given in a YAML file or an already parsed dict.

    Parameters
    ----------
    source : str, path-like or dict
        A YAML file path, or a mapping with ``rows`` and optionally
        ``resolution``, ``origin`` and ``name``.
    resolution, origin, name : optional
        Values for keys the source does not give.  Giving one the source
        also gives is a :class:`ConfigError` (two values, which one?).

    Raises
    ------
    MapFormatError
        Missing file, YAML syntax error, missing ``rows``, an unknown key, a
        row that is not a string, ragged rows, an invalid character (row and
        column are 1-based, counted from the top-left), a bad resolution or
        origin.  Messages name the file (``<dict>`` for a dict).
    ConfigError
        An argument that the source also gives.
    """
    if isinstance(source, dict):
        doc = source
        where = "<dict>"
        default_name = "rows"
    else:
        path = Path(source)
        doc = load_yaml_mapping(path, "rows map YAML")
        where = str(path)
        default_name = path.stem
    for key in doc:
        if key not in ROWS_KEYS:
            raise MapFormatError(
                f"{where}: unknown key"
                f" {_shown(key)} in a rows map (allowed: {', '.join(ROWS_KEYS)})"
            )
    if "rows" not in doc:
        raise MapFormatError(f"{where}: missing key 'rows'")
    for key, arg in (("resolution", resolution), ("origin", origin), ("name", name)):
        if arg is not None and key in doc:
            raise ConfigError(f"{where}: {key} is given both by the map ({_shown(doc[key])}) and "
                              f"by the caller ({_shown(arg)})")
    lines = _parse_rows(where, doc["rows"])

    res_v = doc.get("resolution", resolution if resolution is not None else 1.0)
    if isinstance(res_v, bool):
        raise MapFormatError(f"{where}: key 'resolution' must be a number, got {_shown(res_v)}")
    try:
        res = float(res_v)
    except (TypeError, ValueError):
        raise MapFormatError(f"{where}: key 'resolution' must be a number, got {_shown(res_v)}") \
            from None
    if not math.isfinite(res) or res <= 0:
        raise MapFormatError(f"{where}: key 'resolution' must be a finite number > 0, "
                             f"got {_shown(res_v)}")
    org_v = doc.get("origin", origin if origin is not None else (0.0, 0.0))
    try:
        if isinstance(org_v, (str, bytes)) or len(org_v) != 2:
            raise TypeError
        ox, oy = (float(v) for v in org_v)
    except (TypeError, ValueError):
        raise MapFormatError(f"{where}: key 'origin' must be [x, y] in metres, got"
                             f" {_shown(org_v)}") \
            from None
    if not (math.isfinite(ox) and math.isfinite(oy)):
        raise MapFormatError(f"{where}: key 'origin' must be finite, got {_shown(org_v)}")
    label = doc.get("name", name if name is not None else default_name)
    arr = np.array([[ch in BLOCKED_CHARS for ch in ln] for ln in lines], dtype=bool)[::-1]
    try:
        return GridMap(arr, resolution=res, origin=(ox, oy), name=str(label),
                       meta={"source": where, "format": "rows"})
    except MapError as exc:  # pragma: no cover - inputs validated above
        raise MapFormatError(f"{where}: {exc}") from None
