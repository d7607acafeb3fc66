"""The occupancy grid every planner reads.

Convention (the one of ROS ``nav_msgs/OccupancyGrid``)::

    y ^
      |  row H-1  +---+---+---+
      |     ...   |   |   |   |
      |  row 1    +---+---+---+
      |  row 0    | . | # | . |      occupied[row, col]
      |           +---+---+---+
      |         origin
      +-----------------------------> x
                  col 0  1   2

* ``occupied[row, col]`` is a boolean array; row 0 is the *bottom* row.
* Column index grows with x, row index with y.
* ``origin`` (metres) is the lower-left corner of cell (0, 0); ``resolution``
  is the side of a cell in metres.  The centre of cell (r, c) is
  ``origin + ((c + 0.5) * resolution, (r + 0.5) * resolution)``.

MovingAI maps and images are stored top row first; their readers flip them so
that this convention holds for every map in pathfuse.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, cast

import numpy as np

from pathfuse.limits import MAX_EXTENT_M
from pathfuse.result import MapError
from pathfuse.validate import short as _shown

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["GridMap", "label_regions"]

#: Up to this many cells :func:`label_regions` labels in Python (no scipy.ndimage import).
SMALL_LABELS = 1 << 12


def _scipy_loaded() -> bool:
    """Whether scipy.ndimage is imported already (:func:`label_regions` then needs no
    import)."""
    return "scipy.ndimage" in sys.modules


def label_regions(free: np.ndarray, eight: bool = False) -> np.ndarray:
    """The labels of ``scipy.ndimage.label(free)`` (4-connected; ``eight``: 8-connected),
    as an int32 array: 0 on blocked cells, regions numbered in the order of their first
    cell in row-major order.

    On a small map (at most :data:`SMALL_LABELS` cells, the paper's 15 x 15) a flood fill
    in Python computes them, which spares a first plan the import of scipy.ndimage (a
    quarter of a CPU second); scipy on a larger one, and on any once it is imported (a
    replan around moving discs labels a map per replan: about 1 ms in Python on a
    40 x 48 map, 0.05 ms in scipy).

    >>> label_regions(np.array([[True, False, True], [False, True, True]])).tolist()
    [[1, 0, 2], [0, 2, 2]]
    >>> label_regions(np.array([[True, False], [False, True]]), eight=True).tolist()
    [[1, 0], [0, 1]]
    """
    free = np.asarray(free, dtype=bool)
    if free.size > SMALL_LABELS or _scipy_loaded():
        from scipy import ndimage

        labels, _ = ndimage.label(free, structure=np.ones((3, 3), bool) if eight else None)
        return np.asarray(labels, dtype=np.int32)
    h, w = free.shape
    ok = free.ravel().tolist()
    lab = [0] * len(ok)
    moves = [(-1, 0), (1, 0), (0, -1), (0, 1)]
    if eight:
        moves += [(-1, -1), (-1, 1), (1, -1), (1, 1)]
    n = 0
    for s in range(len(ok)):
        if not ok[s] or lab[s]:
            continue
        n += 1
        lab[s] = n
        todo = [s]
        while todo:
            r, c = divmod(todo.pop(), w)
            for dr, dc in moves:
                rr, cc = r + dr, c + dc
                q = rr * w + cc
                if 0 <= rr < h and 0 <= cc < w and ok[q] and not lab[q]:
                    lab[q] = n
                    todo.append(q)
    return np.array(lab, dtype=np.int32).reshape(h, w)

_KERNEL_MAX = 24
"""Inflation kernels wider than this many cells each side use the distance transform."""


def _as_points(xy: object, what: str = "point") -> np.ndarray:
    """(2,) or (N, 2) array-like -> float (N, 2); raises MapError on bad shape."""
    p = np.asarray(xy, dtype=np.float64)
    if p.ndim == 1:
        p = p.reshape(1, -1)
    if p.ndim != 2 or p.shape[1] != 2:
        shape = np.shape(cast("ArrayLike", xy))  # np.asarray accepted it above
        raise MapError(f"{what} must have shape (2,) or (N, 2), got {shape}")
    return p


def _locked(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a`` (which the caller no longer writes) that cannot be made
    writeable again.

    numpy lets the owner of a buffer turn writing back on (``setflags(write=True)``),
    and an unpickled array is writeable; a view of a read-only buffer can never be.
    The searchers, inflations and labels cached per map rely on the map not changing.
    """
    buf = a if a.base is None else a.copy()
    buf.setflags(write=False)
    return buf.view()


@dataclass(frozen=True, eq=False)
class GridMap:
    """A 2-D occupancy grid with a metric frame.

    Parameters
    ----------
    occupied : array_like of bool, shape (H, W)
        ``True`` where a cell is blocked.  Row 0 is the bottom row.
    resolution : float
        Cell side in metres (> 0).
    origin : (float, float)
        World coordinates (metres) of the lower-left corner of cell (0, 0).
    name : str
        A label used in reports and figures.

    Examples
    --------
    >>> g = GridMap.from_rows(["..#", "...", "#.."], resolution=0.5)
    >>> g.shape
    (3, 3)
    >>> bool(g.occupied[0, 0])  # the bottom-left cell is the last text row
    True
    >>> g.cell_to_world([[0, 1]]).tolist()
    [[0.75, 0.25]]
    >>> g.world_to_cell([0.75, 0.25]).tolist()
    [[0, 1]]
    """

    occupied: np.ndarray
    resolution: float = 1.0
    origin: tuple[float, float] = (0.0, 0.0)
    name: str = "grid"
    meta: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupied)
        if occ.ndim != 2:
            raise MapError(f"occupancy must be a 2-D array, got shape {occ.shape}")
        if occ.size == 0:
            raise MapError(f"map {_shown(self.name)} is empty (shape {occ.shape})")
        if occ.dtype != np.bool_:
            if not np.issubdtype(occ.dtype, np.number):
                raise MapError(f"occupancy must be boolean or numeric, got dtype {occ.dtype}")
            occ = occ != 0
        occ = _locked(np.ascontiguousarray(occ, dtype=np.bool_).copy())
        object.__setattr__(self, "occupied", occ)
        try:
            res = float(self.resolution)
        except (TypeError, ValueError):
            raise MapError(f"resolution must be a number, got {_shown(self.resolution)}") from None
        if not np.isfinite(res) or res <= 0:
            raise MapError(f"resolution must be a finite number > 0, got {_shown(self.resolution)}")
        object.__setattr__(self, "resolution", res)
        try:
            ox, oy = (float(v) for v in self.origin)
        except (TypeError, ValueError):
            raise MapError(f"origin must be two numbers (x, y), got"
                           f" {_shown(self.origin)}") from None
        if not (np.isfinite(ox) and np.isfinite(oy)):
            raise MapError(f"origin must be finite, got {_shown(self.origin)}")
        h, w = occ.shape
        far = max(abs(ox), abs(oy), abs(ox + w * res), abs(oy + h * res))
        if not far <= MAX_EXTENT_M:
            raise MapError(
                f"the map reaches {far:.3g} m from the world origin (resolution {res:g} m, "
                f"origin ({ox:g}, {oy:g}), {h} x {w} cells); pathfuse works within "
                f"{MAX_EXTENT_M:g} m (MAX_EXTENT_M)")
        object.__setattr__(self, "origin", (ox, oy))

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_rows(
        cls,
        rows: list[str],
        resolution: float = 1.0,
        origin: tuple[float, float] = (0.0, 0.0),
        name: str = "rows",
        blocked: str = "#@",
    ) -> GridMap:
        """Build a map from text rows, the *first* row being the *top* of the map.

        ``blocked`` characters are obstacles, every other character is free.
        """
        if isinstance(rows, (str, bytes)) or not isinstance(rows, (list, tuple)):
            raise MapError(f"rows must be a list of strings, got {_shown(rows)}")
        if not rows:
            raise MapError("rows must hold at least one row")
        for i, r in enumerate(rows):
            if not isinstance(r, str):
                raise MapError(f"rows[{i}] must be a string, got {_shown(r)}")
        widths = {len(r) for r in rows}
        if len(widths) != 1:
            raise MapError(f"rows must all have the same length, got lengths {sorted(widths)}")
        arr = np.array([[ch in blocked for ch in r] for r in rows], dtype=bool)
        return cls(arr[::-1], resolution=resolution, origin=origin, name=name)

    def with_occupied(self, occupied: np.ndarray, name: str | None = None) -> GridMap:
        """A copy with another occupancy array of the same shape and frame."""
        occupied = np.asarray(occupied, dtype=bool)
        if occupied.shape != self.shape:
            raise MapError(f"occupancy shape {occupied.shape} != map shape {self.shape}")
        return GridMap(occupied, self.resolution, self.origin, name or self.name, dict(self.meta))

    # ------------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) = (height, width) in cells."""
        return self.occupied.shape  # type: ignore[return-value]

    @property
    def height(self) -> int:
        return int(self.occupied.shape[0])

    @property
    def width(self) -> int:
        return int(self.occupied.shape[1])

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) of the map in metres."""
        ox, oy = self.origin
        return (ox, oy, ox + self.width * self.resolution, oy + self.height * self.resolution)

    @property
    def free_count(self) -> int:
        return int(self.occupied.size - np.count_nonzero(self.occupied))

    def world_to_cell(self, xy: object) -> np.ndarray:
        """(N, 2) int array of ``[row, col]`` for world points ``[x, y]``.

        Points outside the map give indices outside ``[0, H) x [0, W)``; use
        :meth:`in_bounds` to test.  Non-finite points raise :class:`MapError`.
        """
        p = _as_points(xy)
        if not np.all(np.isfinite(p)):
            bad = p[~np.isfinite(p).all(axis=1)][0].tolist()
            raise MapError(f"coordinates must be finite, got {bad}")
        col = np.floor((p[:, 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((p[:, 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return np.stack([row, col], axis=1)

    def cell_to_world(self, cells: object) -> np.ndarray:
        """(N, 2) float array of cell-centre ``[x, y]`` for ``[row, col]`` cells."""
        c = np.asarray(cells, dtype=np.float64)
        if c.ndim == 1:
            c = c.reshape(1, -1)
        x = self.origin[0] + (c[:, 1] + 0.5) * self.resolution
        y = self.origin[1] + (c[:, 0] + 0.5) * self.resolution
        return np.stack([x, y], axis=1)

    def cells_in_bounds(self, cells: object) -> np.ndarray:
        c = np.asarray(cells).reshape(-1, 2)
        return (c[:, 0] >= 0) & (c[:, 0] < self.height) & (c[:, 1] >= 0) & (c[:, 1] < self.width)

    def in_bounds(self, xy: object) -> np.ndarray:
        """Boolean array: which world points lie inside the map."""
        p = _as_points(xy)
        ok = np.isfinite(p).all(axis=1)
        out = np.zeros(p.shape[0], dtype=bool)
        if ok.any():
            out[ok] = self.cells_in_bounds(self.world_to_cell(p[ok]))
        return out

    def is_free(self, xy: object) -> np.ndarray:
        """Boolean array: which world points lie in a free cell (out of map -> False)."""
        p = _as_points(xy)
        out = self.in_bounds(p)
        if out.any():
            rc = self.world_to_cell(p[out])
            out[out] = ~self.occupied[rc[:, 0], rc[:, 1]]
        return out

    # ------------------------------------------------------------------ derived maps
    def inflate(self, radius_m: float) -> GridMap:
        """Grow obstacles by a disc robot's radius.

        A cell becomes occupied when its centre lies closer than ``radius_m``
        to an occupied cell (the cell taken as a square, not as its centre),
        so a disc of that radius centred on any free cell centre touches no
        obstacle.  ``radius_m = 0`` returns an equal map.  The grown map is
        cached per radius, so planners that inflate on every query (and the
        A* buffers kept per map) are not rebuilt each time.

        >>> g = GridMap.from_rows([".....", ".....", "..#..", ".....", "....."])
        >>> int(g.inflate(0.4).occupied.sum()), int(g.inflate(0.6).occupied.sum())
        (1, 5)
        """
        r = float(radius_m)
        if not np.isfinite(r) or r < 0:
            raise MapError(f"inflation radius must be a finite number >= 0, got {_shown(radius_m)}")
        cache = self._inflated
        if r not in cache:
            if len(cache) >= 8:
                cache.pop(next(iter(cache)))
            cache[r] = self._inflate(r)
        return cache[r]

    @cached_property
    def _inflated(self) -> dict[object, GridMap]:
        return {}

    def cspace(self, radius_m: float) -> GridMap:
        """The free space of a disc robot's centre: obstacles *and the map's edge* grown.

        A cell is blocked when its centre is closer than ``radius_m`` to an
        occupied square or to the map's outside.  An 8-connected path through
        the free cell centres without corner cutting keeps a disc of that
        radius clear of every occupied square and inside the map along its
        whole length (checked exhaustively over cell offsets and radii in the
        tests).  ``radius_m = 0`` returns the map itself.  Cached per radius.

        >>> g = GridMap.from_rows([".....", ".....", "....."], resolution=0.5)
        >>> g.cspace(0.3).occupied.astype(int).tolist()    # edge cells are 0.25 m in
        [[1, 1, 1, 1, 1], [1, 0, 0, 0, 1], [1, 1, 1, 1, 1]]
        """
        r = float(radius_m)
        if not math.isfinite(r) or r < 0:
            raise MapError(f"robot radius must be a finite number >= 0, got {_shown(radius_m)}")
        if r == 0:
            return self
        key = ("cspace", r)
        cache = self._inflated
        if key not in cache:
            if len(cache) >= 8:
                cache.pop(next(iter(cache)))
            if r > min(self.shape) * self.resolution / 2:
                # every cell centre is closer than r to the map's edge: nothing is free (and
                # no padding as wide as the radius is allocated)
                cache[key] = self.with_occupied(np.ones_like(self.occupied),
                                                name=f"{self.name}+r{r:g}")
                return cache[key]  # type: ignore[return-value]
            k = int(math.ceil(r / self.resolution + 0.5)) + 1
            padded = np.pad(self.occupied, k, constant_values=True)
            res = self.resolution
            big = GridMap(padded, res, (self.origin[0] - k * res, self.origin[1] - k * res))
            occ = big._inflate(r).occupied[k:-k, k:-k]
            cache[key] = self.with_occupied(occ, name=f"{self.name}+r{r:g}")
        return cache[key]  # type: ignore[return-value]

    def _inflate(self, r: float) -> GridMap:
        if r == 0 or not self.occupied.any():
            return self.with_occupied(self.occupied.copy())
        h, w = self.shape
        if r > math.hypot(h, w) * self.resolution:
            # farther than the map's diagonal: every cell is within r of every obstacle
            return self.with_occupied(np.ones_like(self.occupied), name=f"{self.name}+r{r:g}")
        # distance from a cell centre to the nearest point of an occupied square
        # = distance to the square's centre shrunk by half a cell on each axis.
        k = int(np.ceil(r / self.resolution + 0.5))
        if k > _KERNEL_MAX:
            grown = self._inflate_far(r)
        else:
            d = np.arange(-k, k + 1, dtype=np.float64)
            dx = np.maximum(np.abs(d)[None, :] - 0.5, 0.0)
            dy = np.maximum(np.abs(d)[:, None] - 0.5, 0.0)
            footprint = np.hypot(dx, dy) * self.resolution < r
            from scipy import ndimage

            grown = ndimage.binary_dilation(self.occupied, structure=footprint)
        return self.with_occupied(grown | self.occupied, name=f"{self.name}+r{r:g}")

    def _inflate_far(self, r: float) -> np.ndarray:
        """Inflation by a radius wider than the dilation kernel allows, in time and memory
        linear in the map (not in the radius): the nearest point of a square to a cell
        centre is one of its corners or edge midpoints, all on the half-cell lattice, so
        one exact distance transform of that lattice finds it."""
        from scipy import ndimage

        h, w = self.shape
        lat = np.zeros((2 * h + 1, 2 * w + 1), dtype=bool)
        rr, cc = np.nonzero(self.occupied)
        for di in (0, 1, 2):
            for dj in (0, 1, 2):
                if di != 1 or dj != 1:
                    lat[2 * rr + di, 2 * cc + dj] = True
        idx = ndimage.distance_transform_edt(~lat, return_distances=False, return_indices=True)
        ci = np.arange(1, 2 * h, 2)[:, None]
        cj = np.arange(1, 2 * w, 2)[None, :]
        # the same formula as the kernel's: half-cell offsets, hypot, times the resolution
        dy = np.abs(idx[0][1::2, 1::2] - ci) * 0.5
        dx = np.abs(idx[1][1::2, 1::2] - cj) * 0.5
        return np.hypot(dx, dy) * self.resolution < r

    @cached_property
    def distance_field(self) -> np.ndarray:
        """Euclidean distance (metres) from each cell centre to the nearest occupied cell centre.

        Occupied cells hold 0.  A map with no obstacle holds ``inf``
        everywhere.  Computed once (scipy.ndimage.distance_transform_edt) and
        cached.
        """
        from scipy import ndimage

        if not self.occupied.any():
            df = np.full(self.shape, np.inf)
        else:
            df = ndimage.distance_transform_edt(~self.occupied) * self.resolution
        return _locked(df)

    @cached_property
    def components(self) -> np.ndarray:
        """Label of the connected free region of each cell (0 for occupied).

        4-connectivity, which equals 8-connectivity without corner cutting.
        """
        return _locked(label_regions(~self.occupied))

    def __setstate__(self, state: dict) -> None:
        """Unpickled (a study's worker, Dask): the arrays are read-only again."""
        self.__dict__.update({k: _locked(v) if isinstance(v, np.ndarray) else v
                              for k, v in state.items()})

    def __repr__(self) -> str:
        return (
            f"GridMap(name={self.name!r}, shape={self.shape}, resolution={self.resolution:g}, "
            f"origin={self.origin}, free={self.free_count})"
        )
