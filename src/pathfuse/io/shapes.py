"""Exact rasterisation of 2-D footprints (discs and convex polygons) into an occupancy grid.

The rule, for every shape and every cell: **a cell is occupied when the shape's
interior overlaps the cell's square by more than** :data:`OVERLAP_EPS_M`
(1e-9 m).  A shape that only touches a cell's edge or corner leaves it free,
and a cell that a shape overlaps by any positive amount is occupied, however
small the overlap.  So the occupied cells are exactly the cells a robot's
centre could not be sure to find free of the shape, with no sampling.

* A disc of radius ``r`` at ``c`` overlaps a square when the distance from
  ``c`` to the (closed) square is below ``r - eps``.
* A convex polygon overlaps a square when their projections overlap by more
  than ``eps`` on every separating axis: the x and y axes and each edge's
  normal (the separating axis theorem; for two convex sets it is exact).

Examples
--------
>>> occ = np.zeros((3, 3), dtype=bool)
>>> add_disc(occ, (1.5, 1.5), 0.5, origin=(0.0, 0.0), resolution=1.0)  # touches 4 edges
>>> occ.astype(int).tolist()
[[0, 0, 0], [0, 1, 0], [0, 0, 0]]
>>> add_disc(occ, (1.5, 1.5), 0.6, origin=(0.0, 0.0), resolution=1.0)  # overlaps them
>>> occ.astype(int).tolist()
[[0, 1, 0], [1, 1, 1], [0, 1, 0]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["OVERLAP_EPS_M", "Footprint", "add_disc", "add_polygon", "convex_hull",
           "rasterise"]

OVERLAP_EPS_M = 1e-9
"""Overlap (m) below which a shape is taken to touch a cell, not to overlap it."""


@dataclass(frozen=True)
class Footprint:
    """The 2-D footprint of one collision shape.

    Attributes
    ----------
    kind : {"disc", "polygon"}
    center : (float, float)
        Disc centre (polygon: the mean of its vertices).
    radius : float
        Disc radius (0 for a polygon).
    vertices : (K, 2) float array
        Polygon vertices, counter-clockwise, convex (empty for a disc).
    source : str
        Where the shape comes from (``model/link/collision``, with the file line).
    """

    kind: str
    center: tuple[float, float]
    radius: float = 0.0
    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    source: str = ""

    def bbox(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) of the footprint."""
        if self.kind == "disc":
            cx, cy = self.center
            r = self.radius
            return (cx - r, cy - r, cx + r, cy + r)
        v = self.vertices
        return (float(v[:, 0].min()), float(v[:, 1].min()), float(v[:, 0].max()),
                float(v[:, 1].max()))

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """Signed distance from points (N, 2) to the footprint (negative inside)."""
        p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        if self.kind == "disc":
            return np.hypot(p[:, 0] - self.center[0], p[:, 1] - self.center[1]) - self.radius
        return _polygon_signed_distance(p, self.vertices)


def _polygon_signed_distance(p: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Signed distance from points to a convex counter-clockwise polygon."""
    a = v
    b = np.roll(v, -1, axis=0)
    ab = b - a  # (K, 2)
    ap = p[:, None, :] - a[None, :, :]  # (N, K, 2)
    den = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
    t = np.clip(np.sum(ap * ab[None], axis=2) / den[None], 0.0, 1.0)
    closest = a[None] + t[..., None] * ab[None]
    d = np.hypot(*(p[:, None, :] - closest).transpose(2, 0, 1)).min(axis=1)
    cross = ab[None, :, 0] * ap[..., 1] - ab[None, :, 1] * ap[..., 0]
    inside = np.all(cross >= 0.0, axis=1)
    return np.where(inside, -d, d)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull (Andrew's monotone chain) of points (N, 2).

    >>> convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]])).tolist()
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    """
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points, dtype=np.float64)})
    if len(pts) <= 2:
        return np.array(pts, dtype=np.float64).reshape(-1, 2)

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 1e-15:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 1e-15:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1], dtype=np.float64)


def _cell_window(occ: np.ndarray, bbox: tuple[float, float, float, float],
                 origin: tuple[float, float], resolution: float
                 ) -> tuple[int, int, int, int] | None:
    """Rows r0..r1 and cols c0..c1 (exclusive ends) whose squares meet ``bbox``."""
    h, w = occ.shape
    x0, y0, x1, y1 = bbox
    ox, oy = origin
    c0 = max(0, math.floor((x0 - ox) / resolution) - 1)
    c1 = min(w, math.floor((x1 - ox) / resolution) + 2)
    r0 = max(0, math.floor((y0 - oy) / resolution) - 1)
    r1 = min(h, math.floor((y1 - oy) / resolution) + 2)
    if c0 >= c1 or r0 >= r1:
        return None
    return r0, r1, c0, c1


def add_disc(occ: np.ndarray, center: tuple[float, float], radius: float,
             origin: tuple[float, float], resolution: float) -> None:
    """Mark in ``occ`` (H, W, row 0 at the bottom) every cell the disc overlaps."""
    cx, cy = float(center[0]), float(center[1])
    if radius <= OVERLAP_EPS_M:
        return
    win = _cell_window(occ, (cx - radius, cy - radius, cx + radius, cy + radius), origin,
                       resolution)
    if win is None:
        return
    r0, r1, c0, c1 = win
    ox, oy = origin
    xs0 = ox + np.arange(c0, c1) * resolution
    ys0 = oy + np.arange(r0, r1) * resolution
    dx = np.maximum(np.maximum(xs0 - cx, cx - (xs0 + resolution)), 0.0)
    dy = np.maximum(np.maximum(ys0 - cy, cy - (ys0 + resolution)), 0.0)
    hit = dx[None, :] ** 2 + dy[:, None] ** 2 < (radius - OVERLAP_EPS_M) ** 2
    occ[r0:r1, c0:c1] |= hit


def add_polygon(occ: np.ndarray, vertices: np.ndarray, origin: tuple[float, float],
                resolution: float) -> None:
    """Mark in ``occ`` every cell the convex polygon (K, 2, counter-clockwise) overlaps."""
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    if v.shape[0] < 3:
        return
    bbox = (float(v[:, 0].min()), float(v[:, 1].min()), float(v[:, 0].max()),
            float(v[:, 1].max()))
    win = _cell_window(occ, bbox, origin, resolution)
    if win is None:
        return
    r0, r1, c0, c1 = win
    ox, oy = origin
    xs0 = ox + np.arange(c0, c1) * resolution
    ys0 = oy + np.arange(r0, r1) * resolution
    eps = OVERLAP_EPS_M
    # the x and y axes
    ox_ok = (np.minimum(xs0 + resolution, bbox[2]) - np.maximum(xs0, bbox[0])) > eps
    oy_ok = (np.minimum(ys0 + resolution, bbox[3]) - np.maximum(ys0, bbox[1])) > eps
    hit = oy_ok[:, None] & ox_ok[None, :]
    if not hit.any():
        return
    cxs = xs0 + 0.5 * resolution
    cys = ys0 + 0.5 * resolution
    edges = np.roll(v, -1, axis=0) - v
    for ex, ey in edges:
        n = math.hypot(ex, ey)
        if n == 0.0:
            continue
        nx, ny = ey / n, -ex / n  # an edge normal (either sense works for the test)
        proj = v[:, 0] * nx + v[:, 1] * ny
        pmin, pmax = float(proj.min()), float(proj.max())
        half = 0.5 * resolution * (abs(nx) + abs(ny))
        cproj = cxs[None, :] * nx + cys[:, None] * ny
        hit &= (np.minimum(cproj + half, pmax) - np.maximum(cproj - half, pmin)) > eps
    occ[r0:r1, c0:c1] |= hit


def rasterise(footprints: list[Footprint], shape: tuple[int, int],
              origin: tuple[float, float], resolution: float) -> np.ndarray:
    """A boolean (H, W) grid with every cell some footprint overlaps (see the module rule)."""
    occ = np.zeros(shape, dtype=bool)
    for fp in footprints:
        if fp.kind == "disc":
            add_disc(occ, fp.center, fp.radius, origin, resolution)
        else:
            add_polygon(occ, fp.vertices, origin, resolution)
    return occ
