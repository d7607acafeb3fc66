"""One collision-checking object: the static map, the robot's clearance and a distance layer.

A :class:`Costmap` is what every collision check of the robot layer needs,
in one value built once per problem (as OMPL's state validity checker or
Nav2's costmap): the occupancy, its origin and resolution, the robot's
radius and the clearance it keeps (the radius plus a millionth of a cell,
:data:`pathfuse.geometry.MARGIN_FRAC`), the map's far corner, and the
clearance lower-bound lattice the controllers read (a distance field on the
map's cells split ``s x s``, :func:`clearance_lattice`).

It is a :class:`typing.NamedTuple` of arrays and floats, so numba kernels
take it as **one argument**, read its fields by name, and cache their
machine code on disk (``cache=True``; a jitclass cannot be cached, and a
structref costs the same per call, see ``docs/architecture.md``).  The
checks are numba functions that take it first:

* :func:`point_distance`, :func:`segment_distance`, :func:`arc_distance` -
  the exact distance (a lower bound for the arc, exact at its threshold) from
  a point, a straight move or a unicycle arc to the occupied squares and the
  map's outside (:mod:`pathfuse.sweep` does the geometry);
* :func:`point_clear`, :func:`segment_clear`, :func:`arc_clear` - whether
  that distance is at least ``clear`` (the robot's disc does not touch);
* :func:`field_distance` - the cheap lower bound of the distance to the
  occupied squares read from the lattice, and the exact one to the edge;
* :func:`move_clear` - the planners' move rule
  (:func:`pathfuse.geometry.segment_is_clear`): a straight move keeps ``clear``
  from the occupied squares and stays inside the map, where it may touch the edge
  (it keeps the radius from it, not the margin); the field controllers' steps,
  their progress rule and escapes, and the global planners' snapping use it.

:class:`Discs` holds the moving discs a check is made against (centres,
velocities, speed bounds, radii).

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((10, 10), dtype=np.bool_); occ[:, 6] = True   # a wall at x = 6
>>> cm = make_costmap(occ, 0.3)
>>> round(cm.clear_m, 9), cm.xmax_m, cm.ymax_m
(0.300001, 10.0, 10.0)
>>> float(point_distance(cm, 5.0, 5.0, 2.0))          # one metre to the wall
1.0
>>> bool(segment_clear(cm, 5.0, 5.0, 5.8, 5.0, cm.clear_m))   # 0.2 m short of it: touches
False
>>> bool(arc_clear(cm, 2.0, 5.0, 0.0, 1.0, 0.5, 1.0, cm.clear_m))
True
>>> bool(move_clear(cm, 0.3, 5.0, 0.3, 9.7, cm.clear_m))    # the radius from the edge: a move
True
>>> bool(segment_clear(cm, 0.3, 5.0, 0.3, 9.7, cm.clear_m))  # the exact sweep keeps the margin
False
>>> make_costmap(occ, -1.0)
Traceback (most recent call last):
...
pathfuse.result.ConfigError: radius_m: must be a number >= 0, got -1.0
"""

from __future__ import annotations

import math
import weakref
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from pathfuse.geometry import MARGIN_FRAC, segment_is_clear
from pathfuse.grid import GridMap
from pathfuse.result import ConfigError
from pathfuse.sweep import arc_static_distance, segment_static_distance
from pathfuse.validate import number, point, short

__all__ = [
    "Costmap", "Discs", "make_costmap", "costmap_for", "make_discs", "NO_DISCS",
    "clearance_lattice", "point_distance", "segment_distance", "arc_distance",
    "point_clear", "segment_clear", "arc_clear", "field_distance", "move_clear",
    "warmup_costmap",
]

_MAX_LATTICE_CELLS = 4_000_000
_LATTICES: weakref.WeakKeyDictionary[GridMap, dict[float, tuple[np.ndarray, float]]] = \
    weakref.WeakKeyDictionary()
_COSTMAPS: weakref.WeakKeyDictionary[GridMap, dict[tuple[float, float, bool], Costmap]] = \
    weakref.WeakKeyDictionary()


class Costmap(NamedTuple):
    """The static map and the robot's clearance, as numba kernels take them (one argument).

    Build it with :func:`make_costmap` (which checks its inputs) or
    :func:`costmap_for` (the same, cached per map).

    Attributes
    ----------
    occ : (H, W) bool array, read-only
        ``occ[row, col]``: the cell is occupied (row 0 at the bottom).
    ox_m, oy_m : float
        The map's lower-left corner (metres).
    res_m : float
        The cell side (metres).
    xmax_m, ymax_m : float
        The map's upper-right corner, ``ox_m + W res_m`` and ``oy_m + H res_m``.
    radius_m : float
        The robot's disc radius (the moving discs' gaps are measured from it).
    clear_m : float
        The static clearance the robot keeps: by default the radius plus a
        millionth of a cell (:data:`pathfuse.geometry.MARGIN_FRAC`).
    field : (Hs, Ws) float array, read-only
        The clearance lower bound on a lattice of cells of side ``field_res_m``:
        the distance from each lattice cell's centre to the nearest occupied
        square, less half a lattice cell's diagonal (``inf`` on a free map).
        Built without it (``lattice=False``, for the field loops, which never
        read it): one cell of ``-inf``, a lower bound that proves no clearance.
    field_res_m : float
        The lattice's cell side (the map's cell split ``s x s``, ``s`` from 1 to 8).

    Examples
    --------
    >>> import numpy as np
    >>> cm = make_costmap(np.zeros((4, 6), dtype=np.bool_), 0.2, resolution_m=0.5,
    ...                   origin=(-1.0, 2.0))
    >>> cm.ox_m, cm.oy_m, cm.xmax_m, cm.ymax_m, cm.field.shape, cm.field_res_m
    (-1.0, 2.0, 2.0, 4.0, (4, 6), 0.5)
    """

    occ: np.ndarray
    ox_m: float
    oy_m: float
    res_m: float
    xmax_m: float
    ymax_m: float
    radius_m: float
    clear_m: float
    field: np.ndarray
    field_res_m: float


class Discs(NamedTuple):
    """Moving discs as numba kernels take them (one argument): ``K`` of them.

    Attributes
    ----------
    pos_m : (K, 2) float array
        Centres (metres).
    vel_mps : (K, 2) float array
        Velocities (m/s) as sensed.
    speed_bound_mps : (K,) float array
        How fast each may come (the shield's passive-safety bound: at least
        its sensed speed).
    radius_m : (K,) float array
        Radii (metres).

    Examples
    --------
    >>> d = make_discs([[1.0, 2.0]], [[0.5, 0.0]], [0.3])
    >>> d.pos_m.tolist(), d.speed_bound_mps.tolist(), d.radius_m.tolist()
    ([[1.0, 2.0]], [0.5], [0.3])
    >>> len(NO_DISCS.radius_m)
    0
    """

    pos_m: np.ndarray
    vel_mps: np.ndarray
    speed_bound_mps: np.ndarray
    radius_m: np.ndarray


def _lattice(occ: np.ndarray, res: float, s: int, df1: np.ndarray | None) -> np.ndarray:
    h, w = occ.shape
    r = res / s
    if s == 1 and df1 is not None:
        df = df1
    elif not occ.any():
        df = np.full((h * s, w * s), np.inf)
    else:
        from scipy import ndimage

        fine = np.repeat(np.repeat(occ, s, axis=0), s, axis=1) if s > 1 else occ
        df = ndimage.distance_transform_edt(~fine) * r
    out = np.ascontiguousarray(df - r * math.sqrt(0.5), dtype=np.float64)
    out.setflags(write=False)
    return out


def _split(res: float, shape: tuple[int, int], cell_m: float) -> int:
    h, w = shape
    s = max(1, min(8, int(math.ceil(res / cell_m - 1e-9))))
    while s > 1 and h * w * s * s > _MAX_LATTICE_CELLS:
        s -= 1
    return s


def clearance_lattice(grid: GridMap, cell_m: float) -> tuple[np.ndarray, float]:
    """A clearance lower bound on a lattice of the map's cells split ``s x s`` (``s`` up to
    8, so that a lattice cell is about ``cell_m``, and at most four million of them).

    The distance from each lattice cell centre to the nearest occupied square,
    less half a lattice cell's diagonal (that is :attr:`GridMap.distance_field
    <pathfuse.grid.GridMap.distance_field>` less a cell's half-diagonal when
    ``s = 1``); the distance is 1-Lipschitz, so ``field[c] - |p - c|`` bounds
    it from below at any point ``p``.  Returns ``(field, lattice cell side)``,
    cached per map.

    Examples
    --------
    >>> g = GridMap.from_rows(["...", ".#.", "..."])
    >>> f, r = clearance_lattice(g, 0.5)
    >>> f.shape, r, round(float(f[0, 0]), 4)   # (0.25, 0.25): 1.0607 to the corner (1, 1)
    ((6, 6), 0.5, 1.0607)
    """
    res = float(grid.resolution)
    s = _split(res, grid.shape, cell_m)
    per = _LATTICES.setdefault(grid, {})
    hit = per.get(float(s))
    if hit is not None:
        return hit
    out = (_lattice(grid.occupied, res, s, grid.distance_field if s == 1 else None), res / s)
    per[float(s)] = out
    return out


def make_costmap(occupied: Any, radius_m: float, *, origin: Any = None,
                 resolution_m: Any = None, clear_m: Any = None,
                 field_cell_m: Any = None, lattice: bool = True) -> Costmap:
    """The one constructor of a :class:`Costmap`: checks its inputs, builds the lattice.

    Parameters
    ----------
    occupied : GridMap or (H, W) bool array
        The static map; with a :class:`~pathfuse.grid.GridMap` its origin and
        resolution are used (``origin`` and ``resolution_m`` must then be left out).
    radius_m : float
        The robot's disc radius (>= 0).
    origin : (float, float), optional
        The map's lower-left corner, default ``(0, 0)`` (arrays only).
    resolution_m : float, optional
        The cell side (> 0), default 1 (arrays only).
    clear_m : float, optional
        The static clearance to keep (>= 0), default ``radius_m`` plus
        :data:`~pathfuse.geometry.MARGIN_FRAC` of a cell.
    field_cell_m : float, optional
        The lattice's cell side (> 0) wanted; default: the map's cells.
    lattice : bool
        False: no clearance lattice (no distance transform, no scipy import):
        ``field`` is one cell of ``-inf`` (so :func:`field_distance` proves
        nothing) and ``field_res_m`` the map's cell side.  For kernels that do
        not read it (the field loops of :mod:`pathfuse.field.kernels`).

    Raises
    ------
    pathfuse.result.ConfigError
        Naming the argument and its value.

    Examples
    --------
    >>> import numpy as np
    >>> cm = make_costmap(np.zeros((2, 2), dtype=np.bool_), 0.25, resolution_m=0.1,
    ...                   field_cell_m=0.05)
    >>> cm.field.shape, cm.field_res_m
    ((4, 4), 0.05)
    >>> bare = make_costmap(np.zeros((2, 2), dtype=np.bool_), 0.25, lattice=False)
    >>> bare.field.tolist(), bare.field_res_m
    ([[-inf]], 1.0)
    >>> make_costmap(np.zeros((2, 2), dtype=np.bool_), 0.25, resolution_m=0)
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: resolution_m: must be a number > 0, got 0
    """
    if isinstance(occupied, GridMap):
        if origin is not None or resolution_m is not None:
            raise ConfigError("origin, resolution_m: must be left out with a GridMap (its own "
                              f"are used), got {short(origin)}, {short(resolution_m)}")
        occ = occupied.occupied
        ox, oy = (float(v) for v in occupied.origin)
        res = float(occupied.resolution)
        grid: GridMap | None = occupied
    else:
        occ = occupied
        if not isinstance(occ, np.ndarray) or occ.dtype != np.bool_ or occ.ndim != 2 \
                or occ.size == 0:
            what = (f"{occ.dtype} array of shape {occ.shape}" if isinstance(occ, np.ndarray)
                    else short(occ))
            raise ConfigError(f"occupied: must be a 2-D bool array or a GridMap, got {what}")
        ox, oy = point((0.0, 0.0) if origin is None else origin, "origin")
        res = number(1.0 if resolution_m is None else resolution_m, "resolution_m", gt=0)
        grid = None
    radius = number(radius_m, "radius_m", ge=0)
    clear = (radius + MARGIN_FRAC * res if clear_m is None
             else number(clear_m, "clear_m", ge=0))
    cell = res if field_cell_m is None else number(field_cell_m, "field_cell_m", gt=0)
    if occ.flags.writeable or not occ.flags.c_contiguous:
        occ = np.ascontiguousarray(occ).view()
        occ.setflags(write=False)
    h, w = occ.shape
    if not lattice:
        field, fres = np.full((1, 1), -np.inf), res
        field.setflags(write=False)
    elif grid is not None:
        field, fres = clearance_lattice(grid, cell)
    else:
        s = _split(res, (h, w), cell)
        field, fres = _lattice(occ, res, s, None), res / s
    return Costmap(occ, ox, oy, res, ox + w * res, oy + h * res, radius, clear, field, fres)


def costmap_for(grid: GridMap, radius_m: float, field_cell_m: float | None = None,
                lattice: bool = True) -> Costmap:
    """:func:`make_costmap` of a map, built once per map, radius and lattice (cached).

    Examples
    --------
    >>> g = GridMap.from_rows(["..", ".."])
    >>> costmap_for(g, 0.2) is costmap_for(g, 0.2)
    True
    """
    key = (float(radius_m), -1.0 if field_cell_m is None else float(field_cell_m),
           bool(lattice))
    per = _COSTMAPS.setdefault(grid, {})
    cm = per.get(key)
    if cm is None:
        cm = make_costmap(grid, radius_m, field_cell_m=field_cell_m, lattice=lattice)
        per[key] = cm
    return cm


def _disc_array(value: Any, key: str, shape: tuple[int, ...]) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape or not np.isfinite(a).all():
        raise ConfigError(f"{key}: must be finite numbers of shape {shape}, got "
                          f"{short(value)}")
    return np.ascontiguousarray(a)


def make_discs(pos_m: Any, vel_mps: Any, radius_m: Any, speed_bound_mps: Any = None) -> Discs:
    """Checked :class:`Discs`: ``K`` centres, velocities, radii (>= 0) and speed bounds
    (default: the sensed speeds; never below them).

    Examples
    --------
    >>> make_discs([[0.0, 0.0]], [[3.0, 4.0]], [0.2]).speed_bound_mps.tolist()
    [5.0]
    >>> make_discs([[0.0, 0.0]], [[0.0, 0.0]], [-0.2])
    Traceback (most recent call last):
    ...
    pathfuse.result.ConfigError: radius_m: must be numbers >= 0, got [-0.2]
    """
    p = np.asarray(pos_m, dtype=np.float64).reshape(-1, 2) if np.size(pos_m) == 0 \
        else np.asarray(pos_m, dtype=np.float64)
    k = p.shape[0] if p.ndim == 2 else -1
    p = _disc_array(p, "pos_m", (max(k, 0), 2) if k >= 0 else (0, 2))
    k = p.shape[0]
    v = _disc_array(np.reshape(vel_mps, (-1, 2)) if np.size(vel_mps) == 0 else vel_mps,
                    "vel_mps", (k, 2))
    r = _disc_array(radius_m, "radius_m", (k,))
    if (r < 0).any():
        raise ConfigError(f"radius_m: must be numbers >= 0, got {short(r.tolist())}")
    speed = np.hypot(v[:, 0], v[:, 1])
    if speed_bound_mps is None:
        bound = speed
    else:
        bound = _disc_array(speed_bound_mps, "speed_bound_mps", (k,))
        if (bound < speed).any():
            raise ConfigError("speed_bound_mps: must be at least the sensed speeds "
                              f"{short(speed.tolist())}, got {short(bound.tolist())}")
    return Discs(p, v, bound, r)


NO_DISCS = Discs(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0))
"""No moving disc."""


@njit(cache=True, inline="always")
def point_distance(cm: Costmap, x: float, y: float, cap: float) -> float:
    """``min(cap, distance)`` from ``(x, y)`` to the occupied squares and the map's outside
    (exact; 0 outside the map or on an occupied square)."""
    return segment_static_distance(cm.occ, cm.ox_m, cm.oy_m, cm.res_m, x, y, x, y, cap)


@njit(cache=True, inline="always")
def segment_distance(cm: Costmap, ax: float, ay: float, bx: float, by: float, cap: float,
                     edge_slack: float = 0.0) -> float:
    """``min(cap, distance)`` from the segment ``a-b`` to the occupied squares and the map's
    outside (exact, :func:`pathfuse.sweep.segment_static_distance`; ``edge_slack`` is added
    to the distance to the outside only)."""
    return segment_static_distance(cm.occ, cm.ox_m, cm.oy_m, cm.res_m, ax, ay, bx, by, cap,
                                   edge_slack)


@njit(cache=True, inline="always")
def arc_distance(cm: Costmap, x: float, y: float, th: float, v: float, w: float, dt: float,
                 thr: float, cap: float) -> float:
    """A lower bound (exact to 1e-9 m at ``thr``) of the distance from the unicycle arc of
    ``(v, w)`` over ``dt`` from ``(x, y, th)`` to the occupied squares and the outside
    (:func:`pathfuse.sweep.arc_static_distance`), at most ``cap``."""
    return arc_static_distance(cm.occ, cm.ox_m, cm.oy_m, cm.res_m, x, y, th, v, w, dt, thr,
                               cap)


@njit(cache=True, inline="always")
def point_clear(cm: Costmap, x: float, y: float, clear: float) -> bool:
    """Whether a disc of radius ``clear`` at ``(x, y)`` touches nothing static."""
    return point_distance(cm, x, y, clear) >= clear


@njit(cache=True, inline="always")
def segment_clear(cm: Costmap, ax: float, ay: float, bx: float, by: float,
                  clear: float) -> bool:
    """Whether a disc of radius ``clear`` moving straight from ``a`` to ``b`` touches nothing
    static."""
    return segment_distance(cm, ax, ay, bx, by, clear) >= clear


@njit(cache=True, inline="always")
def arc_clear(cm: Costmap, x: float, y: float, th: float, v: float, w: float, dt: float,
              clear: float) -> bool:
    """Whether a disc of radius ``clear`` on the arc of ``(v, w)`` over ``dt`` touches nothing
    static (never misses a contact)."""
    return arc_distance(cm, x, y, th, v, w, dt, clear, clear) >= clear


@njit(cache=True, inline="always")
def field_distance(cm: Costmap, x: float, y: float) -> tuple[float, float]:
    """Lower bounds of the distances from ``(x, y)`` to the occupied squares (from the
    lattice's nearest cell) and, exact, to the map's outside (negative outside the map):
    ``(squares, edge)``."""
    ox = cm.ox_m
    oy = cm.oy_m
    de = min(x - ox, cm.xmax_m - x, y - oy, cm.ymax_m - y)
    r = cm.field_res_m
    h, w = cm.field.shape
    c = min(max(int(math.floor((x - ox) / r)), 0), w - 1)
    q = min(max(int(math.floor((y - oy) / r)), 0), h - 1)
    d = cm.field[q, c] - math.hypot(x - (ox + (c + 0.5) * r), y - (oy + (q + 0.5) * r))
    return d, de


@njit(cache=True, inline="always")
def move_clear(cm: Costmap, ax: float, ay: float, bx: float, by: float, clear: float) -> bool:
    """Whether the straight move ``a-b`` keeps ``clear`` from every occupied square and stays
    inside the map, at least ``clear`` less :data:`~pathfuse.geometry.MARGIN_FRAC` of a
    cell from its edge (:func:`pathfuse.geometry.segment_is_clear`: the rule of every
    planner's and field controller's move; equal ends test a disc at rest)."""
    return segment_is_clear(ax, ay, bx, by, cm.occ, cm.ox_m, cm.oy_m, cm.res_m, clear)


@njit(cache=True)
def _warm(cm: Costmap) -> float:
    a = point_distance(cm, 0.5, 0.5, 1.0) + segment_distance(cm, 0.5, 0.5, 1.0, 1.0, 1.0)
    b = arc_distance(cm, 0.5, 0.5, 0.0, 1.0, 1.0, 0.1, 0.2, 0.2)
    c = 1.0 if point_clear(cm, 0.5, 0.5, 0.1) and segment_clear(cm, 0.5, 0.5, 1.0, 1.0, 0.1) \
        and arc_clear(cm, 0.5, 0.5, 0.0, 1.0, 1.0, 0.1, 0.1) \
        and move_clear(cm, 0.5, 0.5, 1.0, 1.0, 0.1) else 0.0
    return a + b + c + field_distance(cm, 0.5, 0.5)[0]


def warmup_costmap() -> None:
    """Compile (or load from numba's cache) the checks."""
    _warm(make_costmap(np.zeros((3, 3), dtype=np.bool_), 0.2))
