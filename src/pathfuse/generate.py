"""Seeded random occupancy grids, including the paper's 15 m x 15 m test map.

The paper (Ju, Luo and Yan, Sec. IV) draws "a map with a length and width of
15 meters", start ``[1, 1]``, goal ``[11, 11]`` and "50 obstacles randomly
added".  :func:`paper_map` reproduces that setup with 1 m cells and the origin
at ``(-0.5, -0.5)``, so that *integer world coordinates are cell centres*:
the start and goal are the centres of cells ``(row, col) = (1, 1)`` and
``(11, 11)``, and every cell centre has integer coordinates, as in the paper's
figures.  On an *empty* 15 x 15 map the 8-connected A* length from (1, 1) to
(11, 11) is ten diagonal steps, ``10 * sqrt(2) = 14.1421`` m.  The paper's
Table I A* length, 14.7279 m, is ``9 * sqrt(2) + 2``: the next lattice length,
one diagonal step replaced by a horizontal and a vertical one.  Without
corner cutting this happens when an obstacle cell *touches* the diagonal
(for example cell (row 6, col 5)); a cell *on* the diagonal costs more
(``8 * sqrt(2) + 4 = 15.3137``).  Both are lengths of paths through cell
centres in this frame, which is why we chose it.  (Uniform random obstacles
rarely give the paper's length: over seeds 0-999 the no-corner-cut A* length
is 14.1421 once and 14.7279 six times; the median is about 17.07.)

Every generator takes a ``seed`` and uses :func:`numpy.random.default_rng`;
the same arguments give the same map.  Obstacles are distinct cells, so the
obstacle count is exact.

Examples
--------
>>> g = paper_map(seed=3)
>>> g.shape, g.resolution, g.origin, int(g.occupied.sum())
((15, 15), 1.0, (-0.5, -0.5), 50)
>>> bool(g.is_free([PAPER_START, PAPER_GOAL]).all())
True
>>> bool((paper_map(seed=3).occupied == g.occupied).all())
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pathfuse.grid import GridMap, label_regions
from pathfuse.limits import check_cells
from pathfuse.result import ConfigError, MapError
from pathfuse.validate import short as _shown

__all__ = [
    "paper_map",
    "random_map",
    "shapes_map",
    "PAPER_START",
    "PAPER_GOAL",
    "PAPER_SIZE_M",
    "PAPER_OBSTACLES",
    "PAPER_RESOLUTION",
    "PAPER_ORIGIN",
]

PAPER_START: tuple[float, float] = (1.0, 1.0)
"""Start point of the paper's experiment (metres, a cell centre of :func:`paper_map`)."""
PAPER_GOAL: tuple[float, float] = (11.0, 11.0)
"""Goal point of the paper's experiment (metres, a cell centre of :func:`paper_map`)."""
PAPER_SIZE_M: float = 15.0
"""Side of the paper's square map in metres."""
PAPER_OBSTACLES: int = 50
"""Number of random obstacle cells in the paper's map."""
PAPER_RESOLUTION: float = 1.0
"""Cell side of :func:`paper_map` in metres."""
PAPER_ORIGIN: tuple[float, float] = (-0.5, -0.5)
"""Lower-left corner of :func:`paper_map`: puts cell centres on integer coordinates."""

_DEFAULT_MAX_ATTEMPTS = 1000


def _cells_of(size: float, resolution: float, axis: str) -> int:
    n = size / resolution
    if not math.isfinite(n):
        raise MapError(f"map {axis} size {size:g} m at {resolution:g} m cells is not a finite "
                       "number of cells")
    k = int(round(n))
    if k < 1 or abs(n - k) > 1e-6 * max(1.0, n):
        raise MapError(
            f"map {axis} size {size:g} m is not a positive whole number of "
            f"{resolution:g} m cells ({n:g} cells)"
        )
    return k


def _point_cell(grid_shape: tuple[int, int], origin: tuple[float, float], resolution: float,
                p: object, what: str) -> tuple[int, int]:
    try:
        # any iterable of two numbers; a TypeError is reported below
        x, y = (float(v) for v in p)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise MapError(f"{what} must be an (x, y) pair of numbers, got {_shown(p)}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise MapError(f"{what} must be finite, got {_shown(p)}")
    col = math.floor((x - origin[0]) / resolution)
    row = math.floor((y - origin[1]) / resolution)
    h, w = grid_shape
    if not (0 <= row < h and 0 <= col < w):
        raise MapError(f"{what} {(x, y)} lies outside the map")
    return row, col


def random_map(
    size_m: float | Sequence[float] = (15.0, 15.0),
    resolution: float = 1.0,
    obstacles: int | None = None,
    density: float | None = None,
    seed: int = 0,
    keep_free: Sequence[Sequence[float]] = (),
    connect: Sequence[tuple[Sequence[float], Sequence[float]]] = (),
    origin: tuple[float, float] = (0.0, 0.0),
    name: str | None = None,
    max_attempts: int = _DEFAULT_MAX_ATTEMPTS,
) -> GridMap:
    """A map with an exact number of randomly placed obstacle cells.

    Parameters
    ----------
    size_m : float or (float, float)
        Map size ``(width_x, height_y)`` in metres (one number: a square).
        Each side must be a whole number of cells.
    resolution : float
        Cell side in metres.
    obstacles : int, optional
        Number of obstacle cells (distinct cells, so the count is exact).
    density : float, optional
        Fraction of *all* cells that are obstacles, in ``[0, 1]``; the count
        is ``density * rows * cols`` rounded half up.  Give exactly one of
        ``obstacles`` and ``density``.
    seed : int
        Seed of :func:`numpy.random.default_rng`.  Same arguments -> same map.
    keep_free : sequence of (x, y)
        World points whose cells never receive an obstacle.
    connect : sequence of ((x, y), (x, y))
        Pairs of world points that must lie in the same free region
        (4-connectivity, which equals 8-connectivity without corner
        cutting).  Their cells are kept free too.
    origin : (float, float)
        Lower-left corner of the map in metres.
    name : str, optional
        Map name; defaults to ``random-<W>x<H>-n<count>-s<seed>``.
    max_attempts : int
        When ``connect`` fails, the obstacles are drawn again from the same
        generator (so the result stays deterministic); after this many draws
        a :class:`MapError` is raised.

    Returns
    -------
    GridMap
        ``meta`` holds ``generator``, ``seed``, ``obstacles`` (the count)
        and ``attempts`` (draws used).

    Raises
    ------
    ConfigError
        Both or neither of ``obstacles``/``density``, a negative count, a
        density outside ``[0, 1]``, a seed that is not an integer.
    MapError
        A size that is not a whole number of cells, a point outside the map,
        more obstacles than cells that may hold one, or no connected draw
        within ``max_attempts``.

    Examples
    --------
    >>> g = random_map((4.0, 2.0), resolution=0.5, obstacles=5, seed=1)
    >>> g.shape, int(g.occupied.sum())
    ((4, 8), 5)
    >>> random_map(3.0, density=0.5, seed=0).free_count
    4
    """
    if (obstacles is None) == (density is None):
        raise ConfigError("give exactly one of obstacles (a count) and density (a fraction)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"seed must be a non-negative integer, got {_shown(seed)}")
    if isinstance(max_attempts, bool) or not isinstance(max_attempts, (int, np.integer)) \
            or max_attempts < 1:
        raise ConfigError(f"max_attempts must be a positive integer, got {_shown(max_attempts)}")
    try:
        res = float(resolution)
    except (TypeError, ValueError):
        raise MapError(f"resolution must be a number, got {_shown(resolution)}") from None
    if not math.isfinite(res) or res <= 0:
        raise MapError(f"resolution must be a finite number > 0, got {_shown(resolution)}")
    try:
        sizes = np.broadcast_to(np.asarray(size_m, dtype=np.float64), (2,))
    except (TypeError, ValueError):
        raise MapError(f"size_m must be a number or (width, height) in metres, got"
                       f" {_shown(size_m)}") \
            from None
    if not np.all(np.isfinite(sizes)) or np.any(sizes <= 0):
        raise MapError(f"size_m must be finite and > 0, got {_shown(size_m)}")
    width = _cells_of(float(sizes[0]), res, "width")
    height = _cells_of(float(sizes[1]), res, "height")
    try:
        ox, oy = (float(v) for v in origin)
    except (TypeError, ValueError):
        raise MapError(f"origin must be two numbers (x, y), got {_shown(origin)}") from None
    n_cells = width * height
    check_cells(height, width, f"random map {float(sizes[0]):g} m x {float(sizes[1]):g} m "
                f"at {res:g} m")

    if obstacles is not None:
        if isinstance(obstacles, bool) or not isinstance(obstacles, (int, np.integer)) \
                or obstacles < 0:
            raise ConfigError(f"obstacles must be a non-negative integer, got {_shown(obstacles)}")
        count = int(obstacles)
    else:
        try:
            d = float(density)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ConfigError(f"density must be a number in [0, 1], got"
                              f" {_shown(density)}") from None
        if not (0.0 <= d <= 1.0):
            raise ConfigError(f"density must be in [0, 1], got {_shown(density)}")
        count = int(math.floor(d * n_cells + 0.5))

    shape = (height, width)
    kept: set[tuple[int, int]] = set()
    for p in keep_free:
        kept.add(_point_cell(shape, (ox, oy), res, p, "keep_free point"))
    pairs: list[tuple[tuple[int, int], tuple[int, int]]] = []
    for pair in connect:
        try:
            a, b = pair
        except (TypeError, ValueError):
            raise MapError(f"connect entries must be pairs of points, got {_shown(pair)}") from None
        ca = _point_cell(shape, (ox, oy), res, a, "connect point")
        cb = _point_cell(shape, (ox, oy), res, b, "connect point")
        kept.update((ca, cb))
        pairs.append((ca, cb))

    kept_flat = np.array(sorted(r * width + c for r, c in kept), dtype=np.int64)
    candidates = np.setdiff1d(np.arange(n_cells, dtype=np.int64), kept_flat)
    if count > candidates.size:
        raise MapError(
            f"cannot place {count} obstacles: the {height}x{width} map has only "
            f"{candidates.size} cells that may hold one ({len(kept)} kept free)"
        )
    if pairs and count == candidates.size and count > 0:
        # every candidate blocked: one deterministic outcome, check it once
        max_attempts = 1

    rng = np.random.default_rng(int(seed))
    label = name if name is not None else f"random-{width}x{height}-n{count}-s{int(seed)}"
    for attempt in range(1, int(max_attempts) + 1):
        chosen = rng.choice(candidates, size=count, replace=False)
        occ: np.ndarray = np.zeros(n_cells, dtype=bool)
        occ[chosen] = True
        occ = occ.reshape(shape)
        if pairs:
            labels = label_regions(~occ)  # 4-connected: 8-connected without corner cutting
            if any(labels[a] != labels[b] for a, b in pairs):
                continue
        meta = {"generator": "random_map", "seed": int(seed), "obstacles": count,
                "attempts": attempt}
        return GridMap(occ, resolution=res, origin=(ox, oy), name=label, meta=meta)
    raise MapError(
        f"no draw of {count} obstacles on the {height}x{width} map keeps the points "
        f"{[(a, b) for a, b in pairs]} (row, col) connected after {max_attempts} attempts "
        f"(seed {seed})"
    )


def paper_map(seed: int = 0) -> GridMap:
    """The paper's experiment map: 15 m x 15 m, 1 m cells, 50 random obstacle cells.

    The origin is ``(-0.5, -0.5)`` so that integer world coordinates are
    cell centres; :data:`PAPER_START` ``(1, 1)`` and :data:`PAPER_GOAL`
    ``(11, 11)`` are the centres of cells ``(1, 1)`` and ``(11, 11)``.  They
    are kept free and connected (no-corner-cut 8-connectivity, which equals
    4-connectivity); a draw that disconnects them is replaced by the next
    draw of the same generator, so the map depends only on ``seed``.

    On an empty map the A* length from start to goal is ``10 * sqrt(2) =
    14.1421`` m; the paper's Table I A* length ``14.7279 = 9 * sqrt(2) + 2``
    is the next possible lattice length (one diagonal step replaced by a
    horizontal and a vertical one), reached without corner cutting when an
    obstacle cell touches the straight diagonal.

    Parameters
    ----------
    seed : int
        Seed of :func:`numpy.random.default_rng`.

    Examples
    --------
    >>> g = paper_map(0)
    >>> g.name, g.bounds
    ('paper-0', (-0.5, -0.5, 14.5, 14.5))
    >>> g.world_to_cell([PAPER_START, PAPER_GOAL]).tolist()
    [[1, 1], [11, 11]]
    """
    g = random_map(
        size_m=(PAPER_SIZE_M, PAPER_SIZE_M),
        resolution=PAPER_RESOLUTION,
        obstacles=PAPER_OBSTACLES,
        seed=seed,
        keep_free=(PAPER_START, PAPER_GOAL),
        connect=((PAPER_START, PAPER_GOAL),),
        origin=PAPER_ORIGIN,
        name=f"paper-{seed}",
    )
    g.meta.update({"generator": "paper_map", "start": PAPER_START, "goal": PAPER_GOAL})
    return g


def shapes_map(seed: int = 0, resolution: float = 0.1, size_m: Sequence[float] = (12.0, 12.0),
               discs: int = 12, boxes: int = 6, radius_range_m: Sequence[float] = (0.3, 0.8),
               box_side_range_m: Sequence[float] = (0.4, 1.6),
               keep_free: Sequence[Sequence[float]] = ((1.0, 1.0), (11.0, 11.0)),
               keep_free_radius_m: float = 1.2) -> GridMap:
    """A map of random discs and axis-aligned boxes, drawn in continuous space, then
    rasterised at ``resolution``: a cell is occupied when its centre lies inside a shape.

    The shapes depend on ``seed`` only, not on the resolution, so the same world can be
    rasterised at several resolutions (the resolution-independence study of the
    potential-field repulsion).  No shape comes within ``keep_free_radius_m`` of the
    ``keep_free`` points.  The origin is ``(0, 0)``.

    >>> a, b = shapes_map(3, 0.1), shapes_map(3, 0.05)
    >>> a.shape, b.shape, bool(abs(a.occupied.mean() - b.occupied.mean()) < 0.005)
    ((120, 120), (240, 240), True)
    """
    rng = np.random.default_rng([int(seed), 7919])
    w_m, h_m = (float(v) for v in size_m)
    shapes: list[tuple[str, float, float, float, float]] = []
    r_lo, r_hi = (float(v) for v in radius_range_m)
    b_lo, b_hi = (float(v) for v in box_side_range_m)
    free = np.asarray(keep_free, dtype=np.float64).reshape(-1, 2)
    while len(shapes) < discs + boxes:
        kind = "disc" if len(shapes) < discs else "box"
        cx, cy = rng.uniform(0, w_m), rng.uniform(0, h_m)
        if kind == "disc":
            r = rng.uniform(r_lo, r_hi)
            ext = r
            shape = ("disc", cx, cy, r, r)
        else:
            hw, hh = rng.uniform(b_lo, b_hi) / 2, rng.uniform(b_lo, b_hi) / 2
            ext = math.hypot(hw, hh)
            shape = ("box", cx, cy, hw, hh)
        if free.size and np.min(np.hypot(free[:, 0] - cx, free[:, 1] - cy)) < \
                ext + keep_free_radius_m:
            continue
        shapes.append(shape)
    nx, ny = _cells_of(w_m, resolution, "width"), _cells_of(h_m, resolution, "height")
    xs = (np.arange(nx) + 0.5) * resolution
    ys = (np.arange(ny) + 0.5) * resolution
    X, Y = np.meshgrid(xs, ys)
    occ = np.zeros((ny, nx), dtype=bool)
    for kind, cx, cy, a, b in shapes:
        if kind == "disc":
            occ |= (X - cx) ** 2 + (Y - cy) ** 2 <= a * a
        else:
            occ |= (np.abs(X - cx) <= a) & (np.abs(Y - cy) <= b)
    return GridMap(occ, resolution=resolution, origin=(0.0, 0.0),
                   name=f"shapes-{seed}@{resolution:g}")
