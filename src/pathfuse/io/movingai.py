"""Read and write MovingAI ``.map`` grid benchmark files.

The format (N. Sturtevant, "Benchmarks for Grid-Based Pathfinding", 2012)::

    type octile
    height H
    width W
    map
    <H rows of W characters, the first row being the TOP of the map>

``.``, ``G`` and ``S`` (swamp, passable at normal cost) are free; ``@``,
``O``, ``T`` (trees) and ``W`` (water) are blocked.  Lines may end in CRLF.

MovingAI cell ``(x, y)`` has ``y = 0`` at the *top*; pathfuse row 0 is the
*bottom* (see :mod:`pathfuse.grid`), so MovingAI ``(x, y)`` is pathfuse
``(row, col) = (H - 1 - y, x)``.  :func:`movingai_to_cell` does the conversion.

Examples
--------
>>> import tempfile, pathlib
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["..@", "...", "@.."])
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "tiny.map"
...     write_movingai(g, p)
...     print(p.read_text())
...     h = read_movingai(p, resolution=0.5)
type octile
height 3
width 3
map
..@
...
@..
<BLANKLINE>
>>> bool((h.occupied == g.occupied).all()), h.resolution, h.name
(True, 0.5, 'tiny')
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pathfuse.grid import GridMap
from pathfuse.limits import check_cells, read_capped
from pathfuse.result import MapError, MapFormatError
from pathfuse.validate import short as _shown

__all__ = [
    "read_movingai",
    "write_movingai",
    "movingai_to_cell",
    "cell_to_movingai",
    "FREE_CHARS",
    "BLOCKED_CHARS",
]

FREE_CHARS = ".GS"
"""Characters of passable cells."""
BLOCKED_CHARS = "@OTW"
"""Characters of blocked cells."""

# byte -> 0 free, 1 blocked, 2 not a map character
_LUT = np.full(256, 2, dtype=np.uint8)
for _ch in FREE_CHARS:
    _LUT[ord(_ch)] = 0
for _ch in BLOCKED_CHARS:
    _LUT[ord(_ch)] = 1


def movingai_to_cell(x: int, y: int, height: int) -> tuple[int, int]:
    """Pathfuse ``(row, col)`` of MovingAI cell ``(x, y)`` on a map ``height`` rows tall.

    >>> movingai_to_cell(3, 0, 10)
    (9, 3)
    """
    return (int(height) - 1 - int(y), int(x))


def cell_to_movingai(row: int, col: int, height: int) -> tuple[int, int]:
    """MovingAI ``(x, y)`` of pathfuse cell ``(row, col)``; inverse of :func:`movingai_to_cell`.

    >>> cell_to_movingai(9, 3, 10)
    (3, 0)
    """
    return (int(col), int(height) - 1 - int(row))


def _read_lines(path: Path) -> list[bytes]:
    try:
        data = read_capped(path, "the map file")
    except FileNotFoundError:
        from pathfuse.datasets import missing_hint
        raise MapFormatError(f"{path}: no such map file (the MovingAI benchmarks: "
                             f"{missing_hint('movingai')})") from None
    except IsADirectoryError:
        raise MapFormatError(f"{path}: is a directory, not a map file") from None
    except OSError as exc:
        raise MapFormatError(f"{path}: cannot read map file ({exc.strerror})") from None
    if not data.strip():
        raise MapFormatError(f"{path}: file is empty")
    lines = data.split(b"\n")
    return [ln[:-1] if ln.endswith(b"\r") else ln for ln in lines]


def _header_int(path: Path, lineno: int, key: str, text: bytes) -> int:
    parts = text.split()
    if len(parts) != 2 or parts[0].decode("ascii", "replace").lower() != key:
        raise MapFormatError(
            f"{path}, line {lineno}: must be '{key} <integer>', "
            f"got {_shown(text.decode('ascii', 'replace'))}"
        )
    raw = parts[1].decode("ascii", "replace")
    try:
        value = int(raw)
    except ValueError:
        raise MapFormatError(
            f"{path}, line {lineno}: {key} must be an integer, got {_shown(raw)}"
        ) from None
    if value <= 0:
        raise MapFormatError(f"{path}, line {lineno}: {key} must be > 0, got {value}")
    return value


def read_movingai(
    path: str | os.PathLike[str],
    resolution: float = 1.0,
    origin: tuple[float, float] = (0.0, 0.0),
    name: str | None = None,
) -> GridMap:
    """Read a MovingAI ``.map`` file into a :class:`~pathfuse.grid.GridMap`.

    Parameters
    ----------
    path : str or path-like
        The ``.map`` file.
    resolution : float
        Cell side in metres given to the map (the format has no units).
    origin : (float, float)
        World position (metres) of the lower-left corner of the map.
    name : str, optional
        Map name; defaults to the file name without ``.map``.

    Returns
    -------
    GridMap
        Rows flipped so that row 0 is the bottom row; ``meta`` holds
        ``{"source": str(path), "format": "movingai"}``.

    Raises
    ------
    MapFormatError
        Missing or empty file, bad header, non-positive size, a row of the
        wrong width, a character that is not a map character, or a file with
        fewer rows than its header says.  The message names the file, the
        line (1-based) and, for a bad character, its column.
    """
    path = Path(path)
    lines = _read_lines(path)
    # header: "type octile", "height H", "width W", "map" (height/width in either order)
    i = 0
    while i < len(lines) and not lines[i].strip():
        i += 1
    first = lines[i].split() if i < len(lines) else []
    if len(first) != 2 or first[0].lower() != b"type":
        hint = ""
        if first[:1] == [b"version"] or path.suffix.lower() == ".scen":
            hint = " (this is a MovingAI scenario file (.scen), not a map: give the .map first)"
        raise MapFormatError(
            f"{path}, line {i + 1}: must be the header 'type octile', "
            f"got {_shown(lines[i].decode('ascii', 'replace'))}{hint}"
        )
    if first[1].lower() != b"octile":
        raise MapFormatError(
            f"{path}, line {i + 1}: unsupported map type "
            f"{_shown(first[1].decode('ascii', 'replace'))} (only 'octile' is supported)"
        )
    sizes: dict[str, int] = {}
    for _ in range(2):
        i += 1
        if i >= len(lines) or not any(ln.strip() for ln in lines[i:]):
            raise MapFormatError(
                f"{path}, line {i + 1}: file ends inside the header (expected height and width)"
            )
        key = lines[i].split()[:1]
        key_s = key[0].decode("ascii", "replace").lower() if key else ""
        if key_s not in ("height", "width") or key_s in sizes:
            want = " or ".join(k for k in ("height", "width") if k not in sizes)
            raise MapFormatError(
                f"{path}, line {i + 1}: must be '{want} <integer>', "
                f"got {_shown(lines[i].decode('ascii', 'replace'))}"
            )
        sizes[key_s] = _header_int(path, i + 1, key_s, lines[i])
    i += 1
    if i >= len(lines) or not any(ln.strip() for ln in lines[i:]):
        raise MapFormatError(f"{path}, line {i + 1}: file ends inside the header (expected 'map')")
    if lines[i].strip().lower() != b"map":
        got = lines[i].decode("ascii", "replace")
        raise MapFormatError(f"{path}, line {i + 1}: must be 'map', got {_shown(got)}")
    height, width = sizes["height"], sizes["width"]
    check_cells(height, width, f"{path}: header")
    first_row = i + 1
    rows = lines[first_row:first_row + height]
    # a final newline leaves one empty string at the end: ignore trailing blank lines
    trailing = lines[first_row + height:]
    if len(rows) < height or (len(rows) == height and not rows[-1] and not trailing):
        n_rows = sum(1 for r in rows if r)
        raise MapFormatError(
            f"{path}, line {first_row + n_rows + 1}: file is truncated: header says "
            f"height {height}, found {n_rows} map rows"
        )
    for k, extra in enumerate(trailing):
        if extra.strip():
            raise MapFormatError(
                f"{path}, line {first_row + height + k + 1}: unexpected content after the "
                f"{height} map rows: {_shown(extra[:40].decode('ascii', 'replace'))}"
            )
    grid = np.empty((height, width), dtype=np.bool_)
    for r, row in enumerate(rows):
        lineno = first_row + r + 1
        if len(row) != width:
            raise MapFormatError(
                f"{path}, line {lineno}: map row {r} has {len(row)} characters, "
                f"header says width {width}"
            )
        codes = _LUT[np.frombuffer(row, dtype=np.uint8)]
        bad = np.flatnonzero(codes == 2)
        if bad.size:
            col = int(bad[0])
            ch = row[col:col + 1].decode("latin-1")
            raise MapFormatError(
                f"{path}, line {lineno}, column {col + 1}: unknown map character {_shown(ch)} "
                f"(free: {_shown(FREE_CHARS)}, blocked: {_shown(BLOCKED_CHARS)})"
            )
        grid[r] = codes == 1
    try:
        return GridMap(
            grid[::-1],
            resolution=resolution,
            origin=origin,
            name=name if name is not None else path.name.removesuffix(".map"),
            meta={"source": str(path), "format": "movingai"},
        )
    except MapFormatError:
        raise
    except MapError as exc:
        raise MapError(f"{path}: {exc}") from None


def write_movingai(grid: GridMap, path: str | os.PathLike[str]) -> None:
    """Write ``grid`` as a MovingAI ``.map`` file (``@`` blocked, ``.`` free, LF endings).

    The top row of the map is written first, so :func:`read_movingai` gives
    back an equal occupancy array.  Resolution and origin are not stored.
    """
    occ = np.asarray(grid.occupied, dtype=bool)
    h, w = occ.shape
    chars = np.where(occ[::-1], ord("@"), ord(".")).astype(np.uint8)
    body = b"\n".join(bytes(row) for row in chars)
    text = f"type octile\nheight {h}\nwidth {w}\nmap\n".encode("ascii") + body + b"\n"
    try:
        Path(path).write_bytes(text)
    except OSError as exc:
        raise MapFormatError(f"{path}: cannot write the map file ({exc.strerror or exc})") \
            from None
