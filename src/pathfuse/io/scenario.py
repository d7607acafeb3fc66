"""Read MovingAI ``.scen`` scenario files (benchmark queries with optimal lengths).

Format: a first line ``version 1`` (``version 1.0`` in old files), then one
problem per line with the tab-separated columns::

    bucket  map  map_width  map_height  start_x  start_y  goal_x  goal_y  optimal_length

Coordinates are MovingAI cells (``y = 0`` at the top).  :func:`read_scen`
converts them to the pathfuse frame of the map they are read against: cells
``(row, col) = (H - 1 - y, x)`` and world points at the cell centres; the
optimal length is multiplied by the map's resolution so that it is in metres.
Blank lines are skipped.

Examples
--------
>>> import tempfile, pathlib
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["...", "...", "..."], resolution=0.5)
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d) / "tiny.scen"
...     _ = p.write_text("version 1\\n0\\ttiny.map\\t3\\t3\\t0\\t0\\t2\\t2\\t2.82842712\\n")
...     probs = read_scen(p, g)
>>> q = probs[0]
>>> q.line, q.start_cell, q.goal_cell, q.start, q.goal
(2, (2, 0), (0, 2), (0.25, 1.25), (1.25, 0.25))
>>> round(q.optimal_length, 6)
1.414214
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from pathfuse.grid import GridMap
from pathfuse.limits import read_capped
from pathfuse.result import MapFormatError
from pathfuse.validate import short as _shown

__all__ = ["ScenProblem", "read_scen", "scen_map_name"]


@dataclass(frozen=True)
class ScenProblem:
    """One benchmark query of a ``.scen`` file, in the frame of a :class:`GridMap`.

    Attributes
    ----------
    line : int
        1-based line number in the file.
    bucket : int
        The file's difficulty bucket.
    map_name : str
        The map column as written in the file.
    map_width, map_height : int
        Map size in cells as written in the file.
    start, goal : (float, float)
        World coordinates (metres) of the centres of the start and goal cells.
    start_cell, goal_cell : (int, int)
        ``(row, col)`` cells in the pathfuse convention (row 0 at the bottom).
    optimal_length : float
        The file's optimal length times the map resolution (metres).
    """

    line: int
    bucket: int
    map_name: str
    map_width: int
    map_height: int
    start: tuple[float, float]
    goal: tuple[float, float]
    start_cell: tuple[int, int]
    goal_cell: tuple[int, int]
    optimal_length: float


def _lines(path: Path) -> list[str]:
    try:
        data = read_capped(path, "the scenario file")
    except FileNotFoundError:
        from pathfuse.datasets import missing_hint
        raise MapFormatError(f"{path}: no such scenario file (the MovingAI benchmarks: "
                             f"{missing_hint('movingai')})") from None
    except IsADirectoryError:
        raise MapFormatError(f"{path}: is a directory, not a scenario file") from None
    except OSError as exc:
        raise MapFormatError(f"{path}: cannot read scenario file ({exc.strerror})") from None
    text = data.decode("utf-8", errors="replace")
    return [ln.rstrip("\r") for ln in text.split("\n")]


def _split(line: str) -> list[str]:
    return line.split("\t") if "\t" in line else line.split()


def _check_version(path: Path, lines: list[str]) -> None:
    if not lines or not "".join(lines).strip():
        raise MapFormatError(f"{path}, line 1: scenario file is empty")
    parts = lines[0].split()
    if len(parts) != 2 or parts[0] != "version" or parts[1] not in ("1", "1.0"):
        hint = ""
        if parts[:1] == ["type"] or path.suffix.lower() == ".map":
            hint = " (this is a MovingAI map (.map), not a scenario file: give the .map first)"
        raise MapFormatError(
            f"{path}, line 1: must be 'version 1' or 'version 1.0', "
            f"got {_shown(lines[0][:60])}{hint}"
        )


def scen_map_name(path: str | os.PathLike[str]) -> str:
    """The map column of the first problem of a scenario file (to find the map it needs).

    Raises :class:`MapFormatError` when the file has no problem line.
    """
    path = Path(path)
    lines = _lines(path)
    _check_version(path, lines)
    for k, line in enumerate(lines[1:], start=2):
        if line.strip():
            cols = _split(line.strip())
            if len(cols) < 2:
                raise MapFormatError(f"{path}, line {k}: no map column in {_shown(line[:60])}")
            return cols[1]
    raise MapFormatError(f"{path}: scenario file holds no problem line")


def read_scen(path: str | os.PathLike[str], grid: GridMap) -> list[ScenProblem]:
    """Read every problem of a ``.scen`` file against the map ``grid``.

    Parameters
    ----------
    path : str or path-like
        The scenario file.
    grid : GridMap
        The map the scenario was made for (usually from
        :func:`pathfuse.io.movingai.read_movingai`); it gives the frame in
        which ``start``/``goal`` are expressed and the metres per cell.

    Returns
    -------
    list of ScenProblem
        In file order.

    Raises
    ------
    MapFormatError
        Missing or empty file, a bad version line, a line without 9 columns,
        a non-numeric field, a map size that differs from ``grid``'s, or a
        start or goal outside the map.  The message names the file and line.
    """
    path = Path(path)
    lines = _lines(path)
    _check_version(path, lines)
    h, w = grid.height, grid.width
    res = grid.resolution
    out: list[ScenProblem] = []
    for lineno, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        cols = _split(line)
        if len(cols) != 9:
            raise MapFormatError(
                f"{path}, line {lineno}: must have 9 columns "
                f"(bucket map W H sx sy gx gy optimal), got {len(cols)}"
            )
        names = ("bucket", "map", "map width", "map height", "start x", "start y",
                 "goal x", "goal y")
        ints: list[int] = []
        for k in (0, 2, 3, 4, 5, 6, 7):
            try:
                ints.append(int(cols[k]))
            except ValueError:
                raise MapFormatError(
                    f"{path}, line {lineno}: {names[k]} must be an integer, got {_shown(cols[k])}"
                ) from None
        bucket, mw, mh, sx, sy, gx, gy = ints
        try:
            opt = float(cols[8])
        except ValueError:
            opt = math.nan
        if not math.isfinite(opt) or opt < 0:
            raise MapFormatError(
                f"{path}, line {lineno}: optimal length must be a finite number >= 0, "
                f"got {_shown(cols[8])}"
            )
        if (mw, mh) != (w, h):
            raise MapFormatError(
                f"{path}, line {lineno}: scenario map size {mw}x{mh} (WxH) differs from "
                f"map {_shown(grid.name)} size {w}x{h}"
            )
        for what, x, y in (("start", sx, sy), ("goal", gx, gy)):
            if not (0 <= x < w and 0 <= y < h):
                raise MapFormatError(
                    f"{path}, line {lineno}: {what} ({x}, {y}) is outside the "
                    f"{w}x{h} map"
                )
        s_cell = (h - 1 - sy, sx)
        g_cell = (h - 1 - gy, gx)
        ox, oy = grid.origin
        out.append(
            ScenProblem(
                line=lineno,
                bucket=bucket,
                map_name=cols[1],
                map_width=mw,
                map_height=mh,
                start=(ox + (sx + 0.5) * res, oy + (s_cell[0] + 0.5) * res),
                goal=(ox + (gx + 0.5) * res, oy + (g_cell[0] + 0.5) * res),
                start_cell=s_cell,
                goal_cell=g_cell,
                optimal_length=opt * res,
            )
        )
    if not out:
        raise MapFormatError(f"{path}: scenario file holds no problem line (only its header)")
    return out
